//! The multi-SPE runtime: starts N simulated SPUs on a shared main memory, lets them take
//! tiles from the shared counter, and collects the frame buffer and the statistics.
//!
//! (The SPU-driving half waits for the SPU core; until then `render_frame` says so.)

use crate::frame::FrameLayout;
use crate::kernel_abi::KernelStats;
use crate::layout::StagedScene;

/// What one SPU did in a frame.
#[derive(Clone, Debug, Default)]
pub struct SpuReport {
    pub cycles: u64,
    pub instructions: u64,
    pub tiles: u64,
    pub stats: KernelStats,
}

/// The outcome of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameRun {
    pub frame_buffer: Vec<u8>,
    pub frame_cycles: u64,
    pub spus: Vec<SpuReport>,
}

impl FrameRun {
    /// Statistics as JSON for `spu render --stats`.
    pub fn stats_json(
        &self,
        scene: &str,
        width: u32,
        height: u32,
        clock_ghz: f64,
        mrays_per_sec: f64,
        validation: Option<(usize, usize)>,
    ) -> String {
        let spus: Vec<String> = self
            .spus
            .iter()
            .map(|s| {
                format!(
                    "{{\"cycles\": {}, \"instructions\": {}, \"tiles\": {}}}",
                    s.cycles, s.instructions, s.tiles
                )
            })
            .collect();
        let validation = match validation {
            Some((pixels, mismatches)) => {
                format!(
                    ",\n  \"validation\": {{\"pixels\": {pixels}, \"mismatches\": {mismatches}}}"
                )
            }
            None => String::new(),
        };
        format!(
            "{{\n  \"scene\": {scene:?},\n  \"width\": {width},\n  \"height\": {height},\n  \"clock_ghz\": {clock_ghz},\n  \"frame_cycles\": {},\n  \"rays\": {},\n  \"mrays_per_sec\": {mrays_per_sec:.3},\n  \"spus\": [{}]{validation}\n}}\n",
            self.frame_cycles,
            width as u64 * height as u64,
            spus.join(", ")
        )
    }
}

/// Renders one frame with `spes` SPUs on `threads` host threads.
pub fn render_frame(
    _staged: &StagedScene,
    _layout: &FrameLayout,
    _spes: usize,
    _threads: usize,
    _clock_ghz: f64,
    _fill: bool,
    _max_cycles: u64,
) -> Result<FrameRun, String> {
    Err("the SPU core is not available yet: spu render cannot run the kernels".into())
}
