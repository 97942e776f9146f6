//! `spu paper`'s "Beyond the paper" rows for the paper's next steps (issue #34): reflection
//! rays (section 7) beside Table 5's frame rates, and a moving scene's frames with the BVH
//! refitted on the SPEs (section 9.3); their verdicts; and how a moving scene's job runs in
//! process, writing what `spu render --frames` writes.

use crate::paper_beyond::number;
use crate::paper_data::{self as paper, PAPER_SIZE};
use crate::paper_jobs::{SceneSpec, Want, SHT_ON};
use crate::paper_report::Table;
use crate::paper_tables::{Metric, Moving, RowSpec, Setup, TableSpec};
use crate::render_options::Outputs;
use spu_isa::jit::CodeCache;
use spu_loader::animate::{Animator, FrameStats};
use spu_loader::refit::RebuildPolicy;
use spu_loader::render::RenderConfig;

/// The ids of the section's tables, in the report's order.
pub const TABLES: [&str; 2] = ["beyond_reflections", "beyond_moving"];

/// Label of the reflections rows (one bounce: `--reflect-depth` 1).
const REFLECT: &str = "reflections (ours, depth 1)";

/// Table 5's rows (shading mode by machine), then the same machines with reflections, and
/// their frame rate over the shadows frame's.
pub fn reflections(s: &Setup) -> TableSpec {
    let want = |machine: &paper::Machine, shade: &'static str| Want {
        spes: machine.spes,
        clock_ghz: machine.clock_ghz,
        sht: SHT_ON,
        shade,
        ..Want::default()
    };
    let mut rows = Vec::new();
    for (m, mode) in paper::SHADE_MODES.iter().enumerate() {
        for (k, machine) in paper::MACHINES.iter().enumerate() {
            for scene in &s.scenes {
                rows.push(s.row(
                    format!("{mode}: {}", machine.name),
                    scene,
                    Some(paper::TABLE5_FPS[m][k][paper::col(scene.paper)]),
                    &[want(machine, mode)],
                    Metric::Fps1024,
                ));
            }
        }
    }
    for machine in &paper::MACHINES {
        for scene in &s.scenes {
            rows.push(s.row(
                format!("{REFLECT}: {}", machine.name),
                scene,
                None,
                &[want(machine, "reflect")],
                Metric::Fps1024,
            ));
        }
    }
    for machine in &paper::MACHINES {
        for scene in &s.scenes {
            // the same frame, so the frame rates' ratio is the cycles' ratio
            rows.push(s.row(
                format!("reflections over shadows (x): {}", machine.name),
                scene,
                None,
                &[want(machine, "shadows"), want(machine, "reflect")],
                Metric::Speedup,
            ));
        }
    }
    TableSpec {
        id: TABLES[0],
        title: "Beyond the paper: Table 5 with reflections (section 7)",
        unit: "fps at 1024x1024",
        note: format!("Table 5's runs (SHT {SHT_ON}, 256-line direct-mapped caches), then the same machines with `--shade reflect`: shadows plus one reflected ray per hit on a reflective material (the room's table, the conference's tables, the beetle's paint; docs/reflections.md). The paper has no reflections; its numbers are Table 5's. Fps for a {PAPER_SIZE}x{PAPER_SIZE} frame (scaled by the pixel count at a smaller size); the last rows are the reflections' frame rate over the shadows frame's."),
        rows,
    }
}

/// Frames of each moving scene's run: the scene at rest, then moving.
pub const FRAMES: u32 = 2;

/// SPE counts of the moving scenes' runs.
pub const MOVING_SPES: [usize; 2] = [1, 16];

/// The report scenes that have a moving version (`spu render --frames`), and its name.
const MOVING: [(&str, &str); 2] = [("room", "room-flag"), ("beetle", "beetle-drive")];

/// The moving scene standing in for a report scene (`spu render --frames`), if any.
pub fn moving_scene(scene_id: &str) -> Option<&'static str> {
    MOVING.iter().find(|(s, _)| *s == scene_id).map(|(_, m)| *m)
}

/// The report scene a moving scene moves, if `moving` is one.
pub fn still_scene(moving: &str) -> Option<&'static str> {
    MOVING.iter().find(|(_, m)| *m == moving).map(|(s, _)| *s)
}

/// Per SPE count: the refit's and the frame's cycles and the frame rate with and without
/// the refit, over [`FRAMES`] frames with shadows.
pub fn moving(s: &Setup) -> TableSpec {
    let metrics = [
        ("refit Mcycles per frame", Moving::RefitMcycles),
        ("trace Mcycles per frame", Moving::TraceMcycles),
        ("refit % of the cycles", Moving::RefitPct),
        ("fps with the refit", Moving::Fps),
        ("fps without the refit", Moving::FpsWithoutRefit),
    ];
    let mut rows = Vec::new();
    for scene in &s.scenes {
        // a scene without a moving version has no rows (the note names those that do)
        let Some(name) = moving_scene(&scene.id) else {
            continue;
        };
        let moving = SceneSpec {
            id: name.into(),
            render_name: name.into(),
            paper: scene.paper,
        };
        let row = |label: String, spes: usize, what: Moving| {
            let want = Want {
                spes,
                sht: SHT_ON,
                shade: "shadows",
                frames: FRAMES,
                ..Want::default()
            };
            RowSpec {
                label,
                scene: scene.clone(),
                paper: None,
                jobs: s.job(&moving, want).map(|job| vec![job]),
                metric: Metric::Moving(what),
            }
        };
        for spes in MOVING_SPES {
            for (name, what) in metrics {
                rows.push(row(format!("{spes} SPEs: {name}"), spes, what));
            }
        }
        rows.push(row(
            "frames rebuilt on the host".into(),
            MOVING_SPES[0],
            Moving::Rebuilt,
        ));
    }
    let ratio = RebuildPolicy::default().ratio;
    TableSpec {
        id: TABLES[1],
        title: "Beyond the paper: moving scenes, the BVH refitted on the SPEs (section 9.3)",
        unit: "",
        note: format!("`spu render --frames {FRAMES} --shade shadows` at the report's frame size (not scaled), 2.4 GHz SPEs, SHT {SHT_ON}: room is room-flag (the room with a waving flag), beetle is beetle-drive (the beetle swerving, its wheels turning), the other scenes have no moving version; frame 0 at rest, then moving. Each frame the SPEs refit the BVH (kernels/refit.s, docs/animation.md), then trace it; cycles are per frame (the slowest SPE's), fps over all frames. The host rebuilds the tree instead where the refit's SAH cost passes {ratio} times the built tree's."),
        rows,
    }
}

/// One verdict per table, from its numbers; a table without numbers says so.
pub fn verdicts(tables: &[Table], scenes: &[String]) -> Vec<String> {
    let find = |id: &str| tables.iter().find(|t| t.id == id);
    let mut out = Vec::new();
    if let Some(t) = find(TABLES[0]) {
        let one = paper::MACHINES[0].name;
        let parts: Vec<String> = scenes
            .iter()
            .filter_map(|s| {
                let ratio = number(t, s, &format!("reflections over shadows (x): {one}"))?;
                let fps = number(t, s, &format!("{REFLECT}: {one}"))?;
                Some(format!("{s} {ratio:.2}x ({fps:.2} fps)"))
            })
            .collect();
        out.push(if parts.is_empty() {
            "Reflections (7): not measured (runs missing).".to_string()
        } else {
            format!(
                "Reflections (7), \"each 8x8 primary packet generates one reflection packet\": one bounce on one 2.4 GHz SPE runs at {} of the shadows frame rate; each reflected ray is traced as a packet of its own, since the traversal takes one origin per packet.",
                parts.join("; ")
            )
        });
    }
    if let Some(t) = find(TABLES[1]) {
        let parts: Vec<String> = scenes
            .iter()
            .filter_map(|s| {
                let name = moving_scene(s)?;
                let (spes, refit, trace) = MOVING_SPES.iter().rev().find_map(|&n| {
                    let m = |what: &str| number(t, s, &format!("{n} SPEs: {what}"));
                    Some((
                        n,
                        m("refit Mcycles per frame")?,
                        m("trace Mcycles per frame")?,
                    ))
                })?;
                Some(format!(
                    "{name} on {spes} SPE{} {:.1}% of a shadows frame's cycles",
                    if spes == 1 { "" } else { "s" },
                    100.0 * refit / trace.max(1e-9)
                ))
            })
            .collect();
        out.push(if parts.is_empty() {
            "Moving scenes (9.3): not measured (runs missing or no moving scene).".to_string()
        } else {
            format!(
                "Moving scenes (9.3), \"an SPE loads a chunk of vertices or BVH nodes, works on the data and stores the results back\": the refit on the SPEs takes {}.",
                parts.join("; ")
            )
        });
    }
    out
}

/// A moving scene's job in this process, as `spu render --frames` writes it: each frame a
/// numbered PNG beside `outputs.image`, and the frames' statistics as one JSON array; the
/// trees are built on `bvh_threads` host threads.
pub fn run_frames(
    config: &RenderConfig,
    frames: u32,
    outputs: &Outputs,
    code: &CodeCache,
    bvh_threads: usize,
) -> Result<(), String> {
    let mut animator = Animator::new(&config.scene, frames, RebuildPolicy::default(), bvh_threads)?;
    let mut stats: Vec<FrameStats> = Vec::new();
    for index in 0..frames {
        let frame = animator
            .next_frame(config, code, &mut |_, _| {})
            .map_err(|e| e.to_string())?;
        let path = crate::cmd_animate::numbered(&outputs.image, index, frames);
        let png = crate::png::encode_rgb(
            &crate::cmd_animate::rgb(&frame.frame.colours),
            config.width,
            config.height,
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
        crate::exit::write_file(&path, &png).map_err(|e| e.message.unwrap_or_default())?;
        stats.push(frame.stats(config.clock_ghz, None));
    }
    if let Some(path) = &outputs.stats {
        let json = serde_json::to_string_pretty(&stats).map_err(|e| e.to_string())?;
        crate::exit::write_file(path, json.as_bytes())
            .map_err(|e| e.message.unwrap_or_default())?;
    }
    Ok(())
}
