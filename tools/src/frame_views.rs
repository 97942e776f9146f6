//! The pictures of one rendered frame that `spu render` draws from the SPUs' event logs:
//! the heat maps (`--heatmap`) and the timeline (`--trace`).

use crate::exit::{self, Error};
use spu_loader::frame::FrameLayout;
use spu_loader::runtime::FrameRun;
use spu_loader::timeline::Timeline;
use std::path::Path;

/// Writes the requested views of a frame rendered with the event log on;
/// `frame` is (width, height, SPEs, clock in GHz).
pub fn write(
    run: &FrameRun,
    layout: &FrameLayout,
    (width, height, spes, clock_ghz): (u32, u32, usize, f64),
    heatmap: Option<&Path>,
    trace: Option<&Path>,
) -> exit::Result<()> {
    let timeline = Timeline::new(run, layout, width, height);
    if let Some(path) = heatmap {
        crate::heatmap::write(path, &timeline).map_err(Error::failure)?;
    }
    if let Some(path) = trace {
        let json = crate::trace::to_json(&crate::trace::trace(&timeline, spes, clock_ghz));
        exit::write_file(path, json.as_bytes())?;
    }
    Ok(())
}
