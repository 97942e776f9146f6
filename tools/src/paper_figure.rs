//! Figure 2 of the paper redrawn from our runs: speed-up over 1 to 16 SPEs per scene, with
//! the ideal line and the paper's 8- and 16-SPE points, as PNG and SVG (plotters, with an
//! embedded DejaVu font so that no system font is needed).

use crate::paper_report::Table;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// One scene's curve.
#[derive(Clone, Debug)]
pub struct Series {
    pub scene: String,
    pub ours: Vec<(usize, f64)>,
    pub paper: Vec<(usize, f64)>,
}

/// The curves of the Figure 2 table, one per scene in the table's order.
pub fn series(table: &Table) -> Vec<Series> {
    let mut out: Vec<Series> = Vec::new();
    for row in &table.rows {
        let spes: usize = row
            .label
            .split_whitespace()
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or(0);
        let i = match out.iter().position(|s| s.scene == row.scene) {
            Some(i) => i,
            None => {
                out.push(Series {
                    scene: row.scene.clone(),
                    ours: Vec::new(),
                    paper: Vec::new(),
                });
                out.len() - 1
            }
        };
        if let Some(v) = row.ours {
            out[i].ours.push((spes, v));
        }
        if let Some(v) = row.paper {
            out[i].paper.push((spes, v));
        }
    }
    out
}

/// Gives plotters (whose font table is its own, process-wide) the embedded font; doing it
/// again replaces the entry with the same font.
pub fn register_font() -> Result<(), String> {
    plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
        .map_err(|_| "the embedded font did not load".to_string())
}

const WIDTH: u32 = 800;
const HEIGHT: u32 = 600;

/// Writes `stem.png` and `stem.svg` into `dir`; returns the file names.
pub fn write_figure2(dir: &Path, stem: &str, series: &[Series]) -> Result<Vec<String>, String> {
    register_font()?;
    let png = format!("{stem}.png");
    let svg = format!("{stem}.svg");
    let mut rgb = vec![0u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, series).map_err(|e| format!("{png}: {e}"))?;
    }
    let path = dir.join(&png);
    let bytes = crate::png::encode_rgb(&rgb, WIDTH, HEIGHT)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    write_whole(&path, &bytes)?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, (WIDTH, HEIGHT)).into_drawing_area();
        draw(&root, series).map_err(|e| format!("{svg}: {e}"))?;
    }
    let path = dir.join(&svg);
    write_whole(&path, text.as_bytes())?;
    Ok(vec![png, svg])
}

/// [`crate::exit::write_file`], its message as the figures report it.
fn write_whole(path: &Path, bytes: &[u8]) -> Result<(), String> {
    crate::exit::write_file(path, bytes).map_err(|e| e.message.unwrap_or_default())
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    series: &[Series],
) -> Result<(), Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let max_spes = series
        .iter()
        .flat_map(|s| s.ours.iter().chain(&s.paper).map(|p| p.0))
        .max()
        .unwrap_or(16)
        .max(2);
    let top = series
        .iter()
        .flat_map(|s| s.ours.iter().chain(&s.paper).map(|p| p.1))
        .fold(max_spes as f64, f64::max);
    let mut chart = ChartBuilder::on(root)
        .caption(
            "Speed-up over SPEs (dynamic tile load balancing)",
            ("sans-serif", 22),
        )
        .margin(16)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.5f64..max_spes as f64 + 0.5, 0f64..top * 1.05)?;
    chart
        .configure_mesh()
        .x_desc("SPEs")
        .x_labels(max_spes + 2)
        .x_label_formatter(&|x| format!("{}", x.round() as i64))
        .y_desc("speed-up over 1 SPE")
        .label_style(("sans-serif", 14))
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            (1..=max_spes).map(|n| (n as f64, n as f64)),
            BLACK.stroke_width(1),
        ))?
        .label("ideal")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    for (i, s) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        chart
            .draw_series(LineSeries::new(
                s.ours.iter().map(|&(n, v)| (n as f64, v)),
                colour.stroke_width(2),
            ))?
            .label(format!("{} (ours)", s.scene))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(
            s.ours
                .iter()
                .map(|&(n, v)| Circle::new((n as f64, v), 3, colour.filled())),
        )?;
        if !s.paper.is_empty() {
            chart
                .draw_series(
                    s.paper.iter().map(|&(n, v)| {
                        TriangleMarker::new((n as f64, v), 6, colour.stroke_width(2))
                    }),
                )?
                .label(format!("{} (paper, Table 5)", s.scene))
                .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 6, colour.stroke_width(2)));
        }
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
