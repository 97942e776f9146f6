//! `spu paper`'s "Beyond the paper: its proposals measured": the paper's ISA proposals
//! (several outstanding branch hints, the gather load) and its predictions of faster and
//! wider Cells, as tables of our runs (no paper column: the paper has no numbers for
//! them), figures, and a verdict per prediction written from the measured numbers.

use crate::paper_jobs::{Want, SHT_ON};
use crate::paper_report::Table;
use crate::paper_tables::{Metric, Setup, TableSpec};
use plotters::coord::Shift;
use plotters::prelude::*;
use spu_loader::render::MAX_SPES;
use std::path::Path;

/// The ids of the section's tables, in the report's order.
pub const TABLES: [&str; 3] = ["beyond_extensions", "beyond_clock", "beyond_spes"];

/// The extension settings measured: the real SPU, then each proposal. Gather appears once a
/// kernel variant uses it (one whose defines name `EXT_GATHER`).
pub fn extension_settings() -> Vec<&'static str> {
    let mut settings = vec!["none", "multihint=2", "multihint=4", "multihint=8"];
    let gather_kernel = spu_loader::kernels::KernelVariant::ALL
        .iter()
        .any(|k| k.defines().iter().any(|(name, _)| *name == "EXT_GATHER"));
    if gather_kernel {
        settings.push("gather");
        settings.push("multihint=4,gather");
    }
    settings
}

/// The shading modes of Table 5.
const SHADES: [&str; 3] = ["none", "simple", "shadows"];

/// Per extension setting and shading mode, on one 2.4 GHz SPE with SHT.
pub fn extensions(s: &Setup) -> TableSpec {
    let metrics = [
        ("branch-miss stall cycles", Metric::BranchStalls1024),
        ("CPI", Metric::Cpi),
        ("Mcycles per frame", Metric::Mcycles1024),
        ("MRays/s", Metric::Mrays),
        ("fps", Metric::Fps1024),
    ];
    let mut rows = Vec::new();
    for scene in &s.scenes {
        for shade in SHADES {
            for ext in extension_settings() {
                let want = Want {
                    sht: SHT_ON,
                    shade,
                    ext,
                    ..Want::default()
                };
                for (name, metric) in metrics {
                    rows.push(s.row(
                        format!("{shade}, ext {ext}: {name}"),
                        scene,
                        None,
                        &[want],
                        metric,
                    ));
                }
            }
        }
    }
    TableSpec {
        id: TABLES[0],
        title: "Beyond the paper: its ISA proposals measured (section 9.5)",
        unit: "",
        note: format!("One 2.4 GHz SPE, 256-line direct-mapped caches, SHT {SHT_ON}; stall cycles, cycles and fps scaled to 1024x1024. ext none is the real SPU; multihint=N a branch target buffer of N entries (primary rays run the kernel that hints ahead for it); gather the gather load (docs/extensions.md)."),
        rows,
    }
}

/// Clocks of the clock figure, in GHz.
pub const CLOCKS: [f64; 5] = [2.4, 3.2, 4.0, 5.2, 6.4];

/// MRays/s per SPE against clock, with SHT 1 and SHT 4, at a fixed 100 ns latency.
pub fn clocks(s: &Setup) -> TableSpec {
    let mut rows = Vec::new();
    for scene in &s.scenes {
        for sht in [1, SHT_ON] {
            for clock_ghz in CLOCKS {
                let want = Want {
                    sht,
                    clock_ghz,
                    ..Want::default()
                };
                rows.push(s.row(
                    format!("SHT {sht}, {clock_ghz} GHz"),
                    scene,
                    None,
                    &[want],
                    Metric::MraysPerSpu,
                ));
            }
        }
    }
    TableSpec {
        id: TABLES[1],
        title: "Beyond the paper: MRays/s per SPE against clock (section 9.4)",
        unit: "MRays/s",
        note: "One SPE, primary rays, 256-line direct-mapped caches, DMA latency fixed at 100 ns (240 cycles at 2.4 GHz, 640 at 6.4 GHz), 25.6 GB/s memory.".into(),
        rows,
    }
}

/// SPE counts of the SPE figure.
pub const SPE_COUNTS: [usize; 7] = [1, 2, 4, 8, 16, 32, 64];

/// Frame rate and memory traffic against SPE count, one shared memory interface.
pub fn spe_counts(s: &Setup) -> TableSpec {
    let mut rows = Vec::new();
    for scene in &s.scenes {
        for spes in SPE_COUNTS {
            let want = Want {
                spes,
                sht: SHT_ON,
                shade: "simple",
                ..Want::default()
            };
            for (name, metric) in [("fps", Metric::Fps1024), ("GB/s", Metric::MemoryGbs)] {
                rows.push(s.row(format!("{spes} SPEs: {name}"), scene, None, &[want], metric));
            }
        }
    }
    TableSpec {
        id: TABLES[2],
        title: "Beyond the paper: frame rate against SPE count, one shared memory (section 10)",
        unit: "",
        note: format!("2.4 GHz SPEs, simple shading, SHT {SHT_ON}, 256-line caches; fps scaled to 1024x1024; GB/s is the main-memory traffic the frame's counted regions saw (scene data read, colours written) over its time, against the 25.6 GB/s all SPEs share (docs/memory-model.md). A Cell has 8 SPEs, the paper's dual-Cell blade 16; {} and more are hypothetical Cells.", 2 * 16.min(MAX_SPES)),
        rows,
    }
}

/// A row's number by its label and its scene.
pub(crate) fn number(table: &Table, scene: &str, label: &str) -> Option<f64> {
    table
        .rows
        .iter()
        .find(|r| r.scene == scene && r.label == label)
        .and_then(|r| r.ours)
}

/// One verdict per prediction of the paper, from the numbers in `tables`; a prediction
/// whose runs are missing says so.
pub fn verdicts(tables: &[Table], scenes: &[String]) -> Vec<String> {
    let find = |id: &str| tables.iter().find(|t| t.id == id);
    let mut out = Vec::new();
    if let Some(t) = find(TABLES[0]) {
        let stall = |scene: &str, ext: &str| {
            number(
                t,
                scene,
                &format!("none, ext {ext}: branch-miss stall cycles"),
            )
        };
        let fps = |scene: &str, ext: &str| number(t, scene, &format!("none, ext {ext}: fps"));
        let parts: Vec<String> = scenes
            .iter()
            .filter_map(|s| {
                let (base, four) = (stall(s, "none")?, stall(s, "multihint=4")?);
                let (f0, f4) = (fps(s, "none")?, fps(s, "multihint=4")?);
                Some(format!(
                    "{s} {:.0}% of the stalls, {:+.1}% fps",
                    100.0 * four / base.max(1.0),
                    100.0 * (f4 / f0 - 1.0)
                ))
            })
            .collect();
        out.push(if parts.is_empty() {
            "Several outstanding hints (9.5): not measured (runs missing).".to_string()
        } else {
            let halved = parts.len() == scenes.len()
                && scenes.iter().all(|s| {
                    matches!((stall(s, "none"), stall(s, "multihint=4")), (Some(b), Some(f)) if f <= b / 2.0)
                });
            format!(
                "Several outstanding hints (9.5), \"could significantly reduce the misprediction rate\": with 4 entries a frame of primary rays keeps {} of today's branch-miss stall cycles: {}.",
                if halved { "at most half" } else { "more than half" },
                parts.join("; ")
            )
        });
        let gather = extension_settings().contains(&"gather");
        out.push(if gather {
            let parts: Vec<String> = scenes
                .iter()
                .filter_map(|s| {
                    let c =
                        |ext: &str| number(t, s, &format!("simple, ext {ext}: Mcycles per frame"));
                    Some(format!(
                        "{s} {:.2}x the cycles",
                        c("gather")? / c("none")?.max(1e-9)
                    ))
                })
                .collect();
            format!(
                "The gather load (9.5): simple shading with it takes {}.",
                parts.join("; ")
            )
        } else {
            "The gather load (9.5): no kernel uses it yet, so it is not measured.".to_string()
        });
    }
    if let Some(t) = find(TABLES[1]) {
        let (first, last) = (CLOCKS[0], CLOCKS[CLOCKS.len() - 1]);
        let parts: Vec<String> = scenes
            .iter()
            .filter_map(|s| {
                let m = |sht: u32, c: f64| number(t, s, &format!("SHT {sht}, {c} GHz"));
                let gain = |c: f64| Some(m(SHT_ON, c)? / m(1, c)?.max(1e-9) - 1.0);
                Some(format!(
                    "{s} x{:.2} without SHT, x{:.2} with; SHT gains {:.0}% at {first} GHz, {:.0}% at {last} GHz",
                    m(1, last)? / m(1, first)?.max(1e-9),
                    m(SHT_ON, last)? / m(SHT_ON, first)?.max(1e-9),
                    100.0 * gain(first)?,
                    100.0 * gain(last)?
                ))
            })
            .collect();
        out.push(if parts.is_empty() {
            "Faster SPEs (9.4): not measured (runs missing).".to_string()
        } else {
            format!(
                "Faster SPEs with memory latency fixed in ns (9.4): from {first} to {last} GHz the rays per second grow {}; where SHT's gain grows with the clock, latency is what a faster SPE waits on.",
                parts.join("; ")
            )
        });
    }
    if let Some(t) = find(TABLES[2]) {
        let parts: Vec<String> = scenes
            .iter()
            .filter_map(|s| {
                let fps = |n: usize| number(t, s, &format!("{n} SPEs: fps"));
                let gbs = |n: usize| number(t, s, &format!("{n} SPEs: GB/s"));
                let (one, most) = SPE_COUNTS
                    .iter()
                    .rev()
                    .find_map(|&n| Some((fps(1)?, (n, fps(n)?, gbs(n)?))))?;
                let (n, f, g) = most;
                let bound = if g >= 0.9 * 25.6 {
                    ", bandwidth-bound"
                } else {
                    ""
                };
                Some(format!(
                    "{s} {:.1}x on {n} SPEs ({:.0}% of ideal) using {g:.2} of 25.6 GB/s{bound}",
                    f / one.max(1e-9),
                    100.0 * f / one.max(1e-9) / n as f64
                ))
            })
            .collect();
        out.push(if parts.is_empty() {
            "More SPEs (10): not measured (runs missing).".to_string()
        } else {
            format!(
                "More SPEs sharing one memory (10): {}. A frame below 90% of the bandwidth is not bandwidth-bound: what stops its scaling is tiles per SPE and the shared tile counter.",
                parts.join("; ")
            )
        });
    }
    out
}

/// One curve of a figure.
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

/// The curves of `table` with labels `"{prefix}{x}{suffix}"`: one per scene and prefix.
pub fn curves(table: &Table, prefixes: &[&str], suffix: &str, xs: &[f64]) -> Vec<Curve> {
    let mut scenes: Vec<String> = Vec::new();
    for r in &table.rows {
        if !scenes.contains(&r.scene) {
            scenes.push(r.scene.clone());
        }
    }
    let mut out = Vec::new();
    for scene in &scenes {
        for prefix in prefixes {
            let points: Vec<(f64, f64)> = xs
                .iter()
                .filter_map(|&x| Some((x, number(table, scene, &format!("{prefix}{x}{suffix}"))?)))
                .collect();
            if !points.is_empty() {
                out.push(Curve {
                    label: format!("{scene} {}", prefix.trim_end_matches([',', ' '])),
                    points,
                });
            }
        }
    }
    out
}

/// Axis names and the caption of a figure.
pub struct Axes<'a> {
    pub caption: &'a str,
    pub x: &'a str,
    pub y: &'a str,
}

/// Writes `stem.png` and `stem.svg` into `dir`: `curves` as lines; returns the file names.
pub fn write_figure(
    dir: &Path,
    stem: &str,
    axes: &Axes,
    curves: &[Curve],
) -> Result<Vec<String>, String> {
    const SIZE: (u32, u32) = (800, 600);
    crate::paper_figure::register_font()?;
    let png = format!("{stem}.png");
    let svg = format!("{stem}.svg");
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, axes, curves).map_err(|e| format!("{png}: {e}"))?;
    }
    let path = dir.join(&png);
    let bytes = crate::png::encode_rgb(&rgb, SIZE.0, SIZE.1)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    crate::exit::write_file(&path, &bytes).map_err(|e| e.message.unwrap_or_default())?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, SIZE).into_drawing_area();
        draw(&root, axes, curves).map_err(|e| format!("{svg}: {e}"))?;
    }
    crate::exit::write_file(&dir.join(&svg), text.as_bytes())
        .map_err(|e| e.message.unwrap_or_default())?;
    Ok(vec![png, svg])
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    axes: &Axes,
    curves: &[Curve],
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let points = || curves.iter().flat_map(|c| c.points.iter());
    let x_max = points().map(|p| p.0).fold(1.0, f64::max);
    let x_min = points().map(|p| p.0).fold(x_max, f64::min);
    let y_max = points().map(|p| p.1).fold(1e-3, f64::max);
    let mut chart = ChartBuilder::on(root)
        .caption(axes.caption, ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x_min * 0.95..x_max * 1.05, 0f64..y_max * 1.1)?;
    chart
        .configure_mesh()
        .x_desc(axes.x)
        .y_desc(axes.y)
        .label_style(("sans-serif", 14))
        .draw()?;
    for (i, c) in curves.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(c.points.clone(), colour.stroke_width(2)))?
            .label(c.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(c.points.iter().map(|&p| Circle::new(p, 3, colour.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
