//! `spu render`: ray-trace a scene with the SPU kernels on 1 to 64 simulated SPEs, as the
//! paper's PPE would drive them, and report the image, the statistics and the validation
//! against the host reference. The frame itself is the library's
//! ([`spu_loader::render`]); this command parses the options
//! ([`crate::render_options`]), draws the progress bar, writes the outputs and says what
//! happened.

use crate::exit::{self, Error, Status};
pub use crate::render_options::Args;
use crate::render_options::Outputs;
use spu_isa::jit::CodeCache;
use spu_loader::render::{self, Prepared, RenderConfig, Validation};
use spu_loader::runtime::FrameError;
use spu_loader::shading;
use std::path::Path;
use std::process::ExitCode;
use std::time::{Duration, Instant};

pub fn run(args: Args) -> exit::Result<ExitCode> {
    if args.frames.is_some() {
        return crate::cmd_animate::run(&args);
    }
    let (config, outputs) = args.config()?;
    let started = Instant::now();
    // the BVH on --threads too, so that --threads 1 is one thread
    let prepared = render::prepare_on(&config.scene, config.threads)?;
    eprintln!(
        "scene {}: {} triangles, {} BVH nodes, prepared in {:.2} s",
        config.scene,
        prepared.scene.triangles.len(),
        prepared.staged.nodes.len(),
        started.elapsed().as_secs_f64()
    );
    if std::env::var_os(PHASES_VARIABLE).is_some() {
        eprintln!(
            "phases: scene prepared in {:.4} s",
            started.elapsed().as_secs_f64()
        );
    }
    let code = args.compile.cache();
    let status = frame(&prepared, &config, &outputs, &code)?;
    Ok(status.into())
}

/// Renders `config` from `prepared` with the blocks of `code`, and writes and says what
/// `outputs` asks for: the status `spu render` exits with.
pub fn frame(
    prepared: &Prepared,
    config: &RenderConfig,
    outputs: &Outputs,
    code: &CodeCache,
) -> exit::Result<Status> {
    let (width, height) = (config.width, config.height);
    // hidden until the frame has run long enough to be worth one (shows_progress)
    let bar =
        indicatif::ProgressBar::with_draw_target(Some(0), indicatif::ProgressDrawTarget::hidden());
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} tiles {pos}/{len} {wide_bar} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let on_terminal = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let mut shown = false;
    let sim_started = Instant::now();
    let result = render::render_with(prepared, config, code, &mut |taken, tiles| {
        if !shown && shows_progress(outputs.quiet, on_terminal, sim_started.elapsed()) {
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            shown = true;
        }
        bar.set_length(tiles as u64);
        bar.set_position(taken as u64)
    });
    bar.finish_and_clear();
    let result = result.map_err(|e| match e {
        FrameError::Setup(message) => Error::failure(message),
        FrameError::CycleLimit { .. } => Error::new(Status::CycleLimit, e.to_string()),
        FrameError::SpuStopped { .. } => Error::new(Status::AbnormalStop, e.to_string()),
    })?;
    let host_seconds = sim_started.elapsed().as_secs_f64();
    let encode_started = Instant::now();
    let png = encode_png(&outputs.image, &result.colours, width, height)?;
    let encode_seconds = encode_started.elapsed().as_secs_f64();
    let write_started = Instant::now();
    exit::write_file(&outputs.image, &png)?;
    if std::env::var_os(PHASES_VARIABLE).is_some() {
        eprintln!(
            "phases: frame {host_seconds:.4} s, PNG encoding {encode_seconds:.4} s, writing {:.4} s",
            write_started.elapsed().as_secs_f64()
        );
    }
    let validation = if outputs.validate {
        let v = render::validate(prepared, config, &result).map_err(Error::failure)?;
        for message in &v.messages {
            eprintln!("{message}");
        }
        Some(v)
    } else {
        None
    };
    let run = &result.run;
    if !outputs.quiet {
        let seconds = run.frame_cycles as f64 / (config.clock_ghz * 1e9);
        let rays = width as f64 * height as f64;
        let mrays = if seconds > 0.0 {
            rays / seconds / 1e6
        } else {
            0.0
        };
        let instructions: u64 = run.spus.iter().map(|s| s.instructions).sum();
        outln!(
            "{} SPE(s): {} cycles per frame, {mrays:.2} MRays/s at {} GHz; {instructions} instructions simulated in {host_seconds:.1} s ({:.0} M/s); wrote {}",
            config.spes,
            run.frame_cycles,
            config.clock_ghz,
            instructions as f64 / host_seconds / 1e6,
            outputs.image.display()
        );
        if !run.reflect_counters.is_empty() {
            outln!("{}", reflections_summary(run, seconds));
        }
        if run.jit.blocks > 0 {
            outln!(
                "block compiler: {:.1}% ran compiled; {} blocks ({} instructions) compiled in {:.2} s{}",
                100.0 * run.jit.compiled_instructions as f64 / instructions.max(1) as f64,
                run.jit.blocks,
                run.jit.block_instructions,
                run.jit.compile_seconds,
                if code.compiling() == spu_isa::jit::Compiling::Background {
                    " on a thread of its own"
                } else {
                    ""
                }
            );
        }
    }
    if let Some(v) = &validation {
        outln!("{}", validation_summary(v));
    }
    if let Some(path) = &outputs.stats {
        let json = result.stats(config, validation.as_ref()).to_json();
        exit::write_file(path, json.as_bytes())?;
    }
    if outputs.heatmap.is_some() || outputs.trace.is_some() {
        crate::frame_views::write(
            run,
            &result.layout,
            (width, height, config.spes, config.clock_ghz),
            outputs.heatmap.as_deref(),
            outputs.trace.as_deref(),
        )?;
    }
    if let Some(path) = &outputs.profile {
        let text = result.profile_listing().map_err(Error::failure)?;
        exit::write_file(path, text.as_bytes())?;
    }
    Ok(validation_status(validation.as_ref()))
}

/// A frame shows a progress bar once it has run [`PROGRESS_AFTER`], where standard error is
/// a terminal and the frame is not one of many (`quiet`): a short frame ends before a bar
/// would be read, and a log or a pipe gets no bar's redraws.
fn shows_progress(quiet: bool, stderr_is_terminal: bool, elapsed: Duration) -> bool {
    !quiet && stderr_is_terminal && elapsed >= PROGRESS_AFTER
}

/// How long a frame runs before it shows its progress.
const PROGRESS_AFTER: Duration = Duration::from_secs(1);

/// The line `--validate` prints.
fn validation_summary(v: &Validation) -> String {
    let (n, bad) = (v.pixels, v.mismatches);
    let Some(off) = v.colour_mismatches else {
        return format!("validation: {bad} of {n} pixels differ from the host reference");
    };
    let ties = match v.edge_ties {
        0 => String::new(),
        ties => format!(
            "; {ties} more hit, at the reference's distance, another triangle sharing an edge \
             with the reference's and take that triangle's colour"
        ),
    };
    let edges = match v.shadow_edge_pixels {
        Some(edges) => format!(
            "; {edges} more take the colour of a shadow ray grazing an occluder's edge \
             (within 2^-16 barycentric), which either outcome gives"
        ),
        None => String::new(),
    };
    let bounces: String = v
        .bounce_rays
        .iter()
        .zip(&v.bounce_mismatches)
        .enumerate()
        .map(|(k, (rays, bad))| {
            format!("; bounce {}: {bad} of {rays} reflected rays differ", k + 1)
        })
        .collect();
    format!(
        "validation: {bad} of {n} pixels differ from the host reference in the hit triangle, {off} in colour (more than {} of 255 in a channel){ties}{edges}{bounces}",
        shading::COLOUR_TOLERANCE
    )
}

/// The lines a reflect frame adds: its frame rate, the rays by kind, and per bounce its
/// rays, packets, their active-ray fraction, cache hit rates and DMA bytes.
fn reflections_summary(run: &spu_loader::runtime::FrameRun, seconds: f64) -> String {
    let bounces = spu_loader::stats::BounceStats::from_counters(&run.reflect_counters);
    let reflected: u64 = bounces.iter().map(|b| b.rays).sum();
    let mut text = format!(
        "reflections: {:.2} fps; {} shadow and {reflected} reflected rays",
        if seconds > 0.0 { 1.0 / seconds } else { 0.0 },
        run.shadow_rays
    );
    for b in &bounces {
        text.push_str(&format!(
            "\n  bounce {}: {} rays ({} hit) in {} packets, {:.1}% of their rays active; BVH cache {:.1}% hits, triangle cache {:.1}%; {:.1} KB by DMA",
            b.bounce,
            b.rays,
            b.hits,
            b.packets,
            b.active_ray_percent,
            b.bvh_hit_percent,
            b.triangle_hit_percent,
            b.dma_bytes as f64 / 1024.0
        ));
    }
    text
}

/// `--validate` that found differing pixels (hit triangles, or colours beyond the
/// tolerance) exits 3 (after writing every output).
fn validation_status(validation: Option<&Validation>) -> Status {
    match validation {
        Some(v) if !v.passed() => Status::Differences,
        _ => Status::Success,
    }
}

/// Set (to anything), `spu render` says on standard error how long the frame (staging,
/// simulation, read-back), the PNG's encoding and its writing took: the split of a run's
/// wall time that docs/parallel.md measures, without a profiler.
const PHASES_VARIABLE: &str = "SPU_PHASES";

/// The PNG file of the frame's `colours`, to be written to `path`.
fn encode_png(path: &Path, colours: &[u32], width: u32, height: u32) -> exit::Result<Vec<u8>> {
    let mut rgb = Vec::with_capacity(colours.len() * 3);
    for colour in colours {
        let [r, g, b, _] = colour.to_be_bytes();
        rgb.extend([r, g, b]);
    }
    crate::png::encode_rgb(&rgb, width, height).map_err(|e| Error::output(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bar_shows_after_a_second_on_a_terminal_unless_quiet() {
        let second = Duration::from_secs(1);
        assert!(shows_progress(false, true, second));
        assert!(shows_progress(false, true, 5 * second));
        assert!(!shows_progress(
            false,
            true,
            second - Duration::from_millis(1)
        ));
        assert!(
            !shows_progress(false, false, 5 * second),
            "no terminal: no bar"
        );
        assert!(!shows_progress(true, true, 5 * second), "quiet: no bar");
    }

    #[test]
    fn differing_pixels_make_validation_exit_3() {
        let v = |mismatches, colour_mismatches| Validation {
            pixels: 3,
            mismatches,
            colour_mismatches,
            ..Validation::default()
        };
        assert_eq!(validation_status(Some(&v(0, None))), Status::Success);
        assert_eq!(validation_status(Some(&v(0, Some(0)))), Status::Success);
        assert_eq!(
            validation_status(Some(&v(0, Some(1)))),
            Status::Differences,
            "a colour off is a difference"
        );
        assert_eq!(validation_status(Some(&v(2, None))), Status::Differences);
        assert_eq!(ExitCode::from(Status::Differences), ExitCode::from(3));
        assert_eq!(validation_status(None), Status::Success);
        assert_eq!(
            validation_summary(&v(2, None)),
            "validation: 2 of 3 pixels differ from the host reference"
        );
    }
}
