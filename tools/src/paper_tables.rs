//! Every table and figure of the paper as rows: for each, the paper's number, the jobs that
//! measure ours and how to read our number from their statistics. The job list of
//! `spu paper` is exactly the union of the rows' jobs.

use crate::paper_data::{self as paper, Cache, PAPER_SIZE};
use crate::paper_jobs::{Job, SceneSpec, Want, SHT_ON};
use spu_loader::stats::FrameStats;

/// A finished job's statistics.
#[derive(Clone, Debug)]
pub enum Measured {
    Frame(Box<Frame>),
    /// A moving scene's frames, in order (`spu render --frames --stats`).
    Frames(Vec<spu_loader::animate::FrameStats>),
}

/// A still frame's statistics: typed, and as raw JSON for keys other kernels add.
#[derive(Clone, Debug)]
pub struct Frame {
    pub stats: FrameStats,
    pub raw: serde_json::Value,
}

impl Measured {
    fn frame(&self) -> Result<&Frame, String> {
        match self {
            Measured::Frame(f) => Ok(f),
            Measured::Frames(_) => Err("a moving scene's frames, not one frame".into()),
        }
    }

    fn frames(&self) -> Result<&[spu_loader::animate::FrameStats], String> {
        match self {
            Measured::Frames(f) if !f.is_empty() => Ok(f),
            Measured::Frames(_) => Err("no frames".into()),
            Measured::Frame(_) => Err("one frame, not a moving scene's frames".into()),
        }
    }
}

/// How a row's number comes out of its jobs' statistics.
#[derive(Clone, Copy, Debug)]
pub enum Metric {
    BvhHitPct,
    TriangleHitPct,
    TraversalSteps,
    TriangleTests,
    EarlyExitsPct,
    EarlyHitsPct,
    MraysPerSpu,
    /// Frames per second, scaled to a 1024x1024 frame (cycles grow with the pixels).
    Fps1024,
    /// Gain of the second job over the first, in %.
    GainPct,
    /// Frame cycles of the first job over the second's.
    Speedup,
    /// A number under `table4` in the stats (added by the shading kernel).
    Table4(&'static str),
    /// Kilobytes read per frame from a main-memory region under `table6`, scaled to
    /// 1024x1024 (row index of [`paper::TABLE6_KB`]).
    Table6(usize),
    /// Branch-miss stall cycles of every SPU, scaled to a 1024x1024 frame.
    BranchStalls1024,
    /// Cycles per instruction over every SPU.
    Cpi,
    /// Frame cycles (the slowest SPU's), in millions, scaled to a 1024x1024 frame.
    Mcycles1024,
    /// Rays of every kind per second over the frame, in millions.
    Mrays,
    /// Main-memory traffic of the frame in GB/s: bytes read and written over its time.
    MemoryGbs,
    /// A moving scene's figure over its frames.
    Moving(Moving),
}

/// What a row of a moving scene's frames shows.
#[derive(Clone, Copy, Debug)]
pub enum Moving {
    /// Refit cycles per frame (the slowest SPE's), in millions.
    RefitMcycles,
    /// Ray-tracing cycles per frame (the slowest SPE's), in millions.
    TraceMcycles,
    /// The refit's share of all cycles, in %.
    RefitPct,
    /// Frames per second over the frames, refit included.
    Fps,
    /// Frames per second over the frames, refit left out.
    FpsWithoutRefit,
    /// Frames whose BVH the host rebuilt instead.
    Rebuilt,
}

/// One row of a table.
#[derive(Clone, Debug)]
pub struct RowSpec {
    pub label: String,
    pub scene: SceneSpec,
    pub paper: Option<f64>,
    /// The jobs whose statistics give our number, or why there is none.
    pub jobs: Result<Vec<Job>, String>,
    pub metric: Metric,
}

#[derive(Clone, Debug)]
pub struct TableSpec {
    pub id: &'static str,
    pub title: &'static str,
    pub unit: &'static str,
    pub note: String,
    pub rows: Vec<RowSpec>,
}

/// What the tables are built for.
#[derive(Clone, Debug)]
pub struct Setup {
    pub scenes: Vec<SceneSpec>,
    pub size: u32,
    /// Largest SPE count to run (64; smaller only to keep tests short).
    pub max_spes: usize,
}

impl Setup {
    pub(crate) fn job(&self, scene: &SceneSpec, want: Want) -> Result<Job, String> {
        if want.spes > self.max_spes {
            return Err(format!("{} SPEs: above --max-spes", want.spes));
        }
        Ok(Job::new(scene, self.size, want))
    }

    /// The paper's best ray caster: with SHT.
    fn best(&self) -> Want {
        Want {
            sht: SHT_ON,
            ..Want::default()
        }
    }

    pub(crate) fn row(
        &self,
        label: impl Into<String>,
        scene: &SceneSpec,
        paper: Option<f64>,
        wants: &[Want],
        metric: Metric,
    ) -> RowSpec {
        RowSpec {
            label: label.into(),
            scene: scene.clone(),
            paper,
            jobs: wants.iter().map(|w| self.job(scene, *w)).collect(),
            metric,
        }
    }
}

/// Every table of the paper, then Figure 2 as a table of speed-ups.
pub fn tables(setup: &Setup) -> Vec<TableSpec> {
    vec![
        table1(setup),
        table2(setup),
        table3(setup),
        table4(setup),
        table5(setup),
        table6(setup),
        figure2(setup),
        crate::paper_beyond::extensions(setup),
        crate::paper_beyond::clocks(setup),
        crate::paper_beyond::spe_counts(setup),
        crate::paper_next::reflections(setup),
        crate::paper_next::moving(setup),
    ]
}

fn table1(s: &Setup) -> TableSpec {
    let mut rows = Vec::new();
    for (cache, name, metric) in [
        (Cache::Bvh, "BC", Metric::BvhHitPct),
        (Cache::Triangle, "TC", Metric::TriangleHitPct),
    ] {
        for lines in paper::CACHE_SIZES {
            for assoc in [4, 1] {
                for scene in &s.scenes {
                    let want = Want {
                        cache: lines,
                        assoc,
                        ..Want::default()
                    };
                    let kind = if assoc == 4 { "4-way" } else { "DM" };
                    rows.push(s.row(
                        format!("{name} ({lines}) {kind}"),
                        scene,
                        paper::table1(cache, lines, assoc, scene.paper),
                        &[want],
                        metric,
                    ));
                }
            }
        }
    }
    TableSpec {
        id: "table1",
        title: "Table 1: cache hit rates, 4-way vs direct mapped (DM), BVH node cache (BC) and triangle cache (TC)",
        unit: "%",
        note: "One SPE, primary rays, both caches of the size in the row, blocking DMA.".into(),
        rows,
    }
}

fn table2(s: &Setup) -> TableSpec {
    let metrics = [
        Metric::TraversalSteps,
        Metric::TriangleTests,
        Metric::EarlyExitsPct,
        Metric::EarlyHitsPct,
        Metric::MraysPerSpu,
    ];
    let mut rows = Vec::new();
    for ((label, values), metric) in paper::TABLE2.iter().zip(metrics) {
        for scene in &s.scenes {
            rows.push(s.row(
                *label,
                scene,
                Some(values[paper::col(scene.paper)]),
                &[Want::default()],
                metric,
            ));
        }
    }
    TableSpec {
        id: "table2",
        title: "Table 2: per-SPE traversal and intersection figures",
        unit: "",
        note: "One 2.4 GHz SPE, 256-line direct-mapped caches, blocking DMA, no shading. Our traversal steps count node visits (box tests); the pair kernel tests both children of a node in one step.".into(),
        rows,
    }
}

fn table3(s: &Setup) -> TableSpec {
    let without = Want::default();
    let with = Want {
        sht: SHT_ON,
        ..Want::default()
    };
    let mut rows = Vec::new();
    for scene in &s.scenes {
        let c = paper::col(scene.paper);
        rows.push(s.row(
            "without SHT (MRays/s)",
            scene,
            Some(paper::TABLE3_WITHOUT[c]),
            &[without],
            Metric::MraysPerSpu,
        ));
        rows.push(s.row(
            format!("with SHT {SHT_ON} (MRays/s)"),
            scene,
            Some(paper::TABLE3_WITH[c]),
            &[with],
            Metric::MraysPerSpu,
        ));
        rows.push(s.row(
            "speed-up (%)",
            scene,
            Some(paper::TABLE3_SPEEDUP_PCT[c]),
            &[without, with],
            Metric::GainPct,
        ));
    }
    TableSpec {
        id: "table3",
        title: "Table 3: software hyperthreading (SHT) on one SPE",
        unit: "",
        note: "One 2.4 GHz SPE, 256-line direct-mapped caches, no shading.".into(),
        rows,
    }
}

fn table4(s: &Setup) -> TableSpec {
    let keys = [
        "same_triangle_pct",
        "passes_per_packet",
        "vertex_cache_hit_pct",
        "material_cache_hit_pct",
    ];
    let want = Want {
        shade: "simple",
        ..s.best()
    };
    let mut rows = Vec::new();
    for ((label, values), key) in paper::TABLE4.iter().zip(keys) {
        for scene in &s.scenes {
            rows.push(s.row(
                *label,
                scene,
                Some(values[paper::col(scene.paper)]),
                &[want],
                Metric::Table4(key),
            ));
        }
    }
    TableSpec {
        id: "table4",
        title: "Table 4: shading coherence and the vertex and material caches",
        unit: "",
        note: "One 2.4 GHz SPE, simple shading, primary rays.".into(),
        rows,
    }
}

fn table5(s: &Setup) -> TableSpec {
    let mut rows = Vec::new();
    for (m, mode) in paper::SHADE_MODES.iter().enumerate() {
        for (k, machine) in paper::MACHINES.iter().enumerate() {
            for scene in &s.scenes {
                let want = Want {
                    spes: machine.spes,
                    clock_ghz: machine.clock_ghz,
                    shade: mode,
                    ..s.best()
                };
                rows.push(s.row(
                    format!("{mode}: {}", machine.name),
                    scene,
                    Some(paper::TABLE5_FPS[m][k][paper::col(scene.paper)]),
                    &[want],
                    Metric::Fps1024,
                ));
            }
        }
    }
    TableSpec {
        id: "table5",
        title: "Table 5: frames per second by shading mode and machine",
        unit: "fps at 1024x1024",
        note: format!(
            "Ray casting without shading, simple shading, shading with shadows; SHT where built. Our fps are for a {PAPER_SIZE}x{PAPER_SIZE} frame: at a smaller size the frame's cycles are scaled by the pixel count. The paper's PS3 row is its extrapolation; ours is simulated at 3.2 GHz. The paper's baseline, a 2.4 GHz Opteron, ran at {} fps (ERW6, Conference, VW Beetle by mode).",
            paper::TABLE5_X86_FPS
                .iter()
                .zip(paper::SHADE_MODES)
                .map(|(v, m)| format!("{m} {} / {} / {}", v[0], v[1], v[2]))
                .collect::<Vec<_>>()
                .join("; ")
        ),
        rows,
    }
}

fn table6(s: &Setup) -> TableSpec {
    let want = Want {
        shade: "simple",
        ..s.best()
    };
    let mut rows = Vec::new();
    for (i, (label, values)) in paper::TABLE6_KB.iter().enumerate() {
        for scene in &s.scenes {
            rows.push(s.row(
                *label,
                scene,
                Some(values[paper::col(scene.paper)]),
                &[want],
                Metric::Table6(i),
            ));
        }
    }
    TableSpec {
        id: "table6",
        title: "Table 6: main-memory traffic per frame by kind of scene data",
        unit: "KB per 1024x1024 frame",
        note: "Simple shading, 256-line caches. At a smaller size the KB are scaled by the pixel count (an approximation: cache reuse changes with the packet footprint).".into(),
        rows,
    }
}

fn figure2(s: &Setup) -> TableSpec {
    let mut rows = Vec::new();
    for scene in &s.scenes {
        for spes in 1..=s.max_spes.min(16) {
            let one = s.best();
            let many = Want { spes, ..s.best() };
            rows.push(s.row(
                format!("{spes} SPEs"),
                scene,
                paper::figure2_speedup(spes, scene.paper),
                &[one, many],
                Metric::Speedup,
            ));
        }
    }
    TableSpec {
        id: "figure2",
        title: "Figure 2: speed-up over 1 to 16 SPEs (dynamic tile load balancing)",
        unit: "x over 1 SPE",
        note: "2.4 GHz SPEs, 256-line caches, SHT where built, no shading, 64x64-pixel tiles. The paper prints no numbers for Figure 2; its 8- and 16-SPE points are Table 5's Single- and Dual-Cell over one SPE. Ideal is the SPE count.".into(),
        rows,
    }
}

/// Our number for a row from its jobs' statistics (in the row's job order).
pub fn value(metric: Metric, measured: &[&Measured]) -> Result<f64, String> {
    if let Metric::Moving(what) = metric {
        return moving(what, measured.first().ok_or("no job")?.frames()?);
    }
    let measured: Vec<&Frame> = measured
        .iter()
        .map(|m| m.frame())
        .collect::<Result<_, _>>()?;
    let first = measured.first().ok_or("no job")?;
    let t2 = &first.stats.table2;
    let v = match metric {
        // per lookup, where the stats have it (older files: Table 2's figure)
        Metric::BvhHitPct => match &first.stats.caches {
            c if c.bvh_lookups > 0 => c.bvh_hit_pct,
            _ => t2.bvh_cache_hit_pct,
        },
        Metric::TriangleHitPct => match &first.stats.caches {
            c if c.triangle_lookups > 0 => c.triangle_hit_pct,
            _ => t2.triangle_cache_hit_pct,
        },
        Metric::TraversalSteps => t2.traversal_steps_per_packet,
        Metric::TriangleTests => t2.triangle_tests_per_packet,
        Metric::EarlyExitsPct => t2.early_exits_pct,
        Metric::EarlyHitsPct => t2.early_hits_pct,
        Metric::MraysPerSpu => t2.mrays_per_sec_per_spu,
        Metric::Fps1024 => {
            let s = &first.stats;
            if s.frame_cycles == 0 {
                return Err("no cycles".into());
            }
            let scale = s.rays as f64 / (PAPER_SIZE as f64 * PAPER_SIZE as f64);
            s.clock_ghz * 1e9 / s.frame_cycles as f64 * scale
        }
        Metric::GainPct => {
            // the same frame, so the gain in rays per second is the cycles' ratio
            let b = measured.get(1).ok_or("no second job")?;
            if b.stats.frame_cycles == 0 {
                return Err("no cycles".into());
            }
            100.0 * (first.stats.frame_cycles as f64 / b.stats.frame_cycles as f64 - 1.0)
        }
        Metric::Speedup => {
            let b = measured.get(1).ok_or("no second job")?;
            if b.stats.frame_cycles == 0 {
                return Err("no cycles".into());
            }
            first.stats.frame_cycles as f64 / b.stats.frame_cycles as f64
        }
        Metric::Table4(key) => first
            .raw
            .get("table4")
            .and_then(|t| t.get(key))
            .and_then(|v| v.as_f64())
            .ok_or_else(|| format!("the stats have no table4.{key}"))?,
        Metric::Table6(row) => table6_kb(first, row)?,
        Metric::BranchStalls1024 => {
            let totals = first.stats.totals.as_ref().ok_or("no profile totals")?;
            totals.stall.branch as f64 * to_1024(first)
        }
        Metric::Cpi => first
            .stats
            .totals
            .as_ref()
            .and_then(|t| t.cpi)
            .ok_or("no profile totals")?,
        Metric::Mcycles1024 => first.stats.frame_cycles as f64 * to_1024(first) / 1e6,
        Metric::Mrays => first.stats.mrays_per_sec,
        Metric::MemoryGbs => {
            let kb = |key: &str| {
                first
                    .raw
                    .get("table6")
                    .and_then(|t| t.get(key))
                    .and_then(|v| v.as_f64())
            };
            let read = kb("total_read_kb").ok_or("the stats have no table6")?;
            let written = kb("frame_buffer_written_kb").unwrap_or(0.0);
            let seconds = first.stats.frame_cycles as f64 / (first.stats.clock_ghz * 1e9);
            if seconds <= 0.0 {
                return Err("no cycles".into());
            }
            (read + written) * 1024.0 / seconds / 1e9
        }
        Metric::Moving(_) => unreachable!("answered above"),
    };
    Ok(v)
}

/// A moving scene's figure over all its frames.
fn moving(what: Moving, frames: &[spu_loader::animate::FrameStats]) -> Result<f64, String> {
    let n = frames.len() as f64;
    let refit: u64 = frames.iter().map(|f| f.refit_cycles).sum();
    let trace: u64 = frames.iter().map(|f| f.trace_cycles).sum();
    // frames over their seconds: each frame's fps is its clock over its cycles
    let rate = |fps: &dyn Fn(&spu_loader::animate::FrameStats) -> f64| {
        let seconds: f64 = frames.iter().map(|f| 1.0 / fps(f)).sum();
        if seconds.is_finite() && seconds > 0.0 {
            Ok(n / seconds)
        } else {
            Err("no frame rate".to_string())
        }
    };
    Ok(match what {
        Moving::RefitMcycles => refit as f64 / n / 1e6,
        Moving::TraceMcycles => trace as f64 / n / 1e6,
        Moving::RefitPct => 100.0 * refit as f64 / (refit + trace).max(1) as f64,
        Moving::Fps => rate(&|f| f.fps)?,
        Moving::FpsWithoutRefit => rate(&|f| f.fps_without_refit)?,
        Moving::Rebuilt => frames.iter().filter(|f| f.rebuilt).count() as f64,
    })
}

/// The keys of the stats' `table6` object (kilobytes read per frame by main-memory
/// region, counted by the MFCs), in the order of the paper's rows.
const TABLE6_KEYS: [&str; 5] = [
    "bvh_nodes_kb",
    "triangle_records_kb",
    "vertex_data_kb",
    "shader_data_kb",
    "total_read_kb",
];

/// The factor from a frame of `m`'s rays to the paper's 1024x1024 primary rays.
fn to_1024(m: &Frame) -> f64 {
    let primary = m.stats.width as f64 * m.stats.height as f64;
    (PAPER_SIZE as f64 * PAPER_SIZE as f64) / primary.max(1.0)
}

fn table6_kb(m: &Frame, row: usize) -> Result<f64, String> {
    let key = TABLE6_KEYS[row];
    let kb = m
        .raw
        .get("table6")
        .and_then(|t| t.get(key))
        .and_then(|v| v.as_f64())
        .ok_or_else(|| format!("the stats have no table6.{key}"))?;
    let scale = (PAPER_SIZE as f64 * PAPER_SIZE as f64) / m.stats.rays.max(1) as f64;
    Ok(kb * scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stats file of a `size`-square frame on one 2.4 GHz SPE, with extra keys.
    fn measured(size: u32, frame_cycles: u64, mrays: f64, extra: &str) -> Measured {
        let text = format!(
            r#"{{"scene": "room", "width": {size}, "height": {size}, "clock_ghz": 2.4,
            "frame_cycles": {frame_cycles}, "rays": {}, "mrays_per_sec": {mrays},
            "spus": [{{"cycles": {frame_cycles}, "instructions": 1, "tiles": 1}}],
            "table2": {{"traversal_steps_per_packet": 40.5, "pair_steps_per_packet": 20,
              "triangle_tests_per_packet": 1.5, "triangles_culled_per_packet": 0,
              "early_exits_pct": 44, "early_hits_pct": 52, "bvh_cache_hit_pct": 97.5,
              "bvh_cache_hit_per_node_pct": 99, "triangle_cache_hit_pct": 96.25,
              "mrays_per_sec_per_spu": {mrays}}},
            "traversal": null, "intersection": null, "totals": null{extra}}}"#,
            size * size
        );
        Measured::Frame(Box::new(Frame {
            stats: FrameStats::from_json(&text).unwrap(),
            raw: serde_json::from_str(&text).unwrap(),
        }))
    }

    #[test]
    fn our_numbers_come_from_the_right_keys() {
        let a = measured(256, 24_000_000, 30.0, "");
        let b = measured(256, 20_000_000, 36.0, "");
        let c = measured(256, 6_000_000, 120.0, "");
        assert_eq!(value(Metric::BvhHitPct, &[&a]), Ok(97.5));
        assert_eq!(value(Metric::TriangleHitPct, &[&a]), Ok(96.25));
        assert_eq!(value(Metric::TraversalSteps, &[&a]), Ok(40.5));
        // 2.4e9 / 24e6 = 100 fps at 256x256, a sixteenth of that at 1024x1024
        assert!((value(Metric::Fps1024, &[&a]).unwrap() - 100.0 / 16.0).abs() < 1e-9);
        assert!((value(Metric::GainPct, &[&a, &b]).unwrap() - 20.0).abs() < 1e-9);
        assert_eq!(value(Metric::Speedup, &[&a, &c]), Ok(4.0));
        assert!(value(Metric::Table4("same_triangle_pct"), &[&a])
            .unwrap_err()
            .contains("table4"));
        let shaded = measured(
            512,
            1,
            1.0,
            r#", "table4": {"same_triangle_pct": 97.5}, "table6": {"bvh_nodes_kb": 6,
              "triangle_records_kb": 10, "vertex_data_kb": 30, "shader_data_kb": 0.5,
              "total_read_kb": 46.5, "frame_buffer_written_kb": 1024}"#,
        );
        assert_eq!(
            value(Metric::Table4("same_triangle_pct"), &[&shaded]),
            Ok(97.5)
        );
        // kilobytes of a 512x512 frame scale by 4 to 1024x1024
        assert_eq!(value(Metric::Table6(0), &[&shaded]), Ok(24.0));
        assert_eq!(value(Metric::Table6(4), &[&shaded]), Ok(186.0));
        assert!(value(Metric::Speedup, &[&a]).is_err());
        // a still frame is no moving scene's frames, nor the other way round
        assert!(value(Metric::Moving(Moving::Fps), &[&a]).is_err());
        let frame = |refit_cycles: u64, trace_cycles: u64| spu_loader::animate::FrameStats {
            frame: 0,
            refit_cycles,
            trace_cycles,
            fps: 2.4e9 / (refit_cycles + trace_cycles) as f64,
            fps_without_refit: 2.4e9 / trace_cycles as f64,
            rebuilt: refit_cycles == 0,
            sah_refit: 1.0,
            sah_built: 1.0,
            refit_items: 1,
            refit_dma_read: 0,
            refit_dma_written: 0,
            refit_spes: Vec::new(),
            mismatches: None,
        };
        let frames = Measured::Frames(vec![frame(2_000_000, 22_000_000), frame(0, 24_000_000)]);
        assert!(value(Metric::Cpi, &[&frames]).is_err());
        let moving = |what| value(Metric::Moving(what), &[&frames]).unwrap();
        assert_eq!(moving(Moving::RefitMcycles), 1.0);
        assert_eq!(moving(Moving::TraceMcycles), 23.0);
        assert!((moving(Moving::RefitPct) - 100.0 * 2.0 / 48.0).abs() < 1e-9);
        // 2 frames in 48 M cycles at 2.4 GHz; 46 M without the refit
        assert!((moving(Moving::Fps) - 100.0).abs() < 1e-9);
        assert!((moving(Moving::FpsWithoutRefit) - 2.0 * 2400.0 / 46.0).abs() < 1e-9);
        assert_eq!(moving(Moving::Rebuilt), 1.0);
    }
}
