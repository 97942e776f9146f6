//! `spu render --frames N`: a moving scene's frames on the simulated SPEs
//! ([`spu_loader::animate`]: the BVH refitted on the SPEs each frame, or rebuilt on the
//! host), each written as a numbered PNG as soon as it is rendered (`-o out.png` →
//! `out_000.png`, ...), with per-frame statistics (refit and trace cycles, frames per second
//! including the refit), `--validate` against the host reference for every frame, and an
//! animated PNG of them all with `--animation`. Every file is declared before the first
//! frame ([`crate::outputs`]); a frame that fails (a bad keyframe, an SPU stopping) ends
//! the run with the frames before it written whole.

use crate::cmd_render::Args;
use crate::exit::{self, Error, Status};
use spu_loader::animate::{Animator, FrameStats};
use spu_loader::animation::{self, keyframe_path};
use spu_loader::refit::RebuildPolicy;
use spu_loader::render;
use spu_loader::runtime::FrameError;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

/// Frames per second of the `--animation` file.
const ANIMATION_FPS: u16 = 30;

/// `out.png` → `out_007.png` for frame 7 of `frames` (three digits at least, more where the
/// frames need them).
pub fn numbered(path: &Path, frame: u32, frames: u32) -> PathBuf {
    let digits = (frames.saturating_sub(1).to_string().len()).max(3);
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!("{stem}_{frame:0digits$}{ext}"))
}

/// The checks of `--frames` and its files, before any work: the frame count, what a run of
/// frames does not write, PNG names, and no output overwriting a keyframe or another output.
pub fn check_options(args: &Args) -> exit::Result<()> {
    let frames = args.frames.unwrap_or(0);
    animation::check_frames(frames).map_err(Error::input)?;
    for (option, given) in [
        ("--profile", args.profile.is_some()),
        ("--heatmap", args.heatmap.is_some()),
        ("--trace", args.trace.is_some()),
        ("--fill", args.fill),
    ] {
        if given {
            return Err(Error::input(format!(
                "{option} is for a single frame: drop it or --frames"
            )));
        }
    }
    if args.rebuild_ratio.is_nan() || args.rebuild_ratio <= 1.0 {
        return Err(Error::input(format!(
            "--rebuild-ratio {}: must be above 1 (a refitted tree is never cheaper than built)",
            args.rebuild_ratio
        )));
    }
    let is_animation = animation::is_built_in(&args.scene) || animation::is_pattern(&args.scene);
    if !is_animation {
        return Err(Error::input(format!(
            "--frames renders a moving scene: {} or a keyframe pattern such as walk_%03d.obj, \
             not {:?}",
            animation::BUILT_IN.join(", "),
            args.scene
        )));
    }
    let is_png = |path: &Path| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    };
    for (option, path) in std::iter::once(("-o", &args.output))
        .chain(args.animation.as_ref().map(|path| ("--animation", path)))
    {
        if !is_png(path) {
            return Err(Error::input(format!(
                "{option} {}: written as PNG; name it .png",
                path.display()
            )));
        }
    }
    let mut files = crate::outputs::Files::new();
    if animation::is_pattern(&args.scene) {
        for frame in 0..frames {
            let path = keyframe_path(&args.scene, frame).expect("a pattern");
            files.input(format!("keyframe {frame}"), &path);
        }
    }
    let names: Vec<PathBuf> = (0..frames)
        .map(|frame| numbered(&args.output, frame, frames))
        .collect();
    for path in &names {
        files.output("-o", path);
    }
    if let Some(path) = &args.animation {
        files.output("--animation", path);
    }
    if let Some(path) = &args.stats {
        files.output("--stats", path);
    }
    files.check()
}

fn frame_error(e: FrameError) -> Error {
    match e {
        // a keyframe that does not load or fit frame 0 is bad input
        FrameError::Setup(message) => Error::input(message),
        FrameError::CycleLimit { .. } => Error::new(Status::CycleLimit, e.to_string()),
        FrameError::SpuStopped { .. } => Error::new(Status::AbnormalStop, e.to_string()),
    }
}

pub(crate) fn rgb(colours: &[u32]) -> Vec<u8> {
    colours
        .iter()
        .flat_map(|c| {
            let [r, g, b, _] = c.to_be_bytes();
            [r, g, b]
        })
        .collect()
}

pub fn run(args: &Args) -> exit::Result<ExitCode> {
    let (config, outputs) = args.config()?;
    let frames = args.frames.unwrap_or(1);
    let started = Instant::now();
    let mut animator = Animator::new(
        &config.scene,
        frames,
        RebuildPolicy {
            ratio: args.rebuild_ratio,
        },
        config.threads,
    )?;
    let first = animator.animation.first();
    eprintln!(
        "animation {}: {frames} frames of {} triangles, prepared in {:.2} s",
        config.scene,
        first.triangles.len(),
        started.elapsed().as_secs_f64()
    );
    let code = args.compile.cache();
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(frames as u64),
        indicatif::ProgressDrawTarget::hidden(),
    );
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} frames {pos}/{len} {wide_bar} {elapsed}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
    }
    let mut stats: Vec<FrameStats> = Vec::new();
    let mut images: Vec<Vec<u8>> = Vec::new();
    let mut differing = 0;
    for index in 0..frames {
        let frame = animator
            .next_frame(&config, &code, &mut |_, _| {})
            .map_err(frame_error);
        let frame = match frame {
            Ok(frame) => frame,
            Err(e) => {
                bar.finish_and_clear();
                return Err(e);
            }
        };
        let path = numbered(&outputs.image, index, frames);
        let pixels = rgb(&frame.frame.colours);
        let png = crate::png::encode_rgb(&pixels, config.width, config.height)
            .map_err(|e| Error::output(&path, e))?;
        exit::write_file(&path, &png)?;
        let validation = if outputs.validate {
            let v =
                render::validate(&frame.prepared, &config, &frame.frame).map_err(Error::failure)?;
            if !v.passed() {
                differing += 1;
                for message in &v.messages {
                    bar.suspend(|| eprintln!("frame {index}: {message}"));
                }
            }
            Some(v)
        } else {
            None
        };
        let line = frame.stats(config.clock_ghz, validation.as_ref());
        let refit = if line.rebuilt {
            format!(
                "BVH rebuilt on the host (refit SAH cost {:.2} > {} x {:.2})",
                line.sah_refit, args.rebuild_ratio, line.sah_built
            )
        } else {
            format!(
                "refit {} cycles ({} items)",
                line.refit_cycles, line.refit_items
            )
        };
        let checked = match &validation {
            Some(v) => format!(
                "; {} of {} pixels differ",
                v.mismatches + v.colour_mismatches.unwrap_or(0),
                v.pixels
            ),
            None => String::new(),
        };
        bar.suspend(|| -> exit::Result<()> {
            outln!(
                "frame {index}: {refit}, trace {} cycles, {:.2} fps with the refit ({:.2} without) on {} SPE(s) at {} GHz{checked}; wrote {}",
                line.trace_cycles,
                line.fps,
                line.fps_without_refit,
                config.spes,
                config.clock_ghz,
                path.display()
            );
            Ok(())
        })?;
        stats.push(line);
        if args.animation.is_some() {
            images.push(pixels);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let Some(path) = &args.animation {
        let apng = crate::png::encode_apng(&images, config.width, config.height, ANIMATION_FPS)
            .map_err(|e| Error::output(path, e))?;
        exit::write_file(path, &apng)?;
    }
    if let Some(path) = &outputs.stats {
        let json = serde_json::to_string_pretty(&stats).map_err(|e| Error::output(path, e))?;
        exit::write_file(path, json.as_bytes())?;
    }
    let refit: u64 = stats.iter().map(|s| s.refit_cycles).sum();
    let trace: u64 = stats.iter().map(|s| s.trace_cycles).sum();
    let rebuilds = stats.iter().filter(|s| s.rebuilt).count();
    outln!(
        "{frames} frames: {:.2} fps with the refit, the refit {:.1}% of the cycles; {rebuilds} rebuilt on the host",
        config.clock_ghz * 1e9 * frames as f64 / (refit + trace).max(1) as f64,
        100.0 * refit as f64 / (refit + trace).max(1) as f64
    );
    if outputs.validate {
        outln!("validation: {differing} of {frames} frames differ from the host reference");
    }
    Ok(if differing > 0 {
        Status::Differences
    } else {
        Status::Success
    }
    .into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_are_numbered_beside_the_output() {
        let out = Path::new("dir/out.png");
        assert_eq!(numbered(out, 7, 30), Path::new("dir/out_007.png"));
        assert_eq!(numbered(out, 12, 1200), Path::new("dir/out_0012.png"));
    }
}
