//! `spu render --heatmap FILE.png`: each pixel coloured by the simulated cycles its packet
//! took, and a second map (FILE-wait.png) by the share of those cycles spent waiting on
//! DMA, each with a colour scale (labels drawn by plotters with the embedded font).

use spu_loader::timeline::Timeline;
use std::path::{Path, PathBuf};

/// Viridis, sampled at five points (perceptually even, readable in grey).
const VIRIDIS: [[f64; 3]; 5] = [
    [68.0, 1.0, 84.0],
    [59.0, 82.0, 139.0],
    [33.0, 145.0, 140.0],
    [94.0, 201.0, 98.0],
    [253.0, 231.0, 37.0],
];

/// The colour of `v` in 0..=1.
pub fn colour(v: f64) -> [u8; 3] {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = v * (VIRIDIS.len() - 1) as f64;
    let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f64;
    let mut out = [0u8; 3];
    for (k, o) in out.iter_mut().enumerate() {
        *o = (VIRIDIS[i][k] + f * (VIRIDIS[i + 1][k] - VIRIDIS[i][k])).round() as u8;
    }
    out
}

/// Width of the colour scale to the right of the image.
const SCALE_WIDTH: u32 = 110;
const NO_PACKET: [u8; 3] = [40, 40, 40];

/// The two maps' paths for `--heatmap path`.
pub fn paths(path: &Path) -> (PathBuf, PathBuf) {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "heatmap".into());
    (
        path.to_path_buf(),
        path.with_file_name(format!("{stem}-wait.png")),
    )
}

/// Writes the cycles map to `path` and the DMA-wait map beside it.
pub fn write(path: &Path, timeline: &Timeline) -> Result<(), String> {
    let (cycles_path, wait_path) = paths(path);
    let cycles = timeline.per_pixel(|p| (p.end - p.start) as f64);
    let wait = timeline.per_pixel(|p| {
        let span = (p.end - p.start).max(1) as f64;
        100.0 * p.wait as f64 / span
    });
    let max = cycles.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    let min = cycles.iter().flatten().fold(max, |a, &b| a.min(b));
    draw(
        &cycles_path,
        timeline,
        &cycles,
        (min, max),
        "cycles per packet",
    )?;
    draw(
        &wait_path,
        timeline,
        &wait,
        // from none to the most any packet waited (at least 1%), so small waits show
        (0.0, wait.iter().flatten().fold(1.0f64, |a, &b| a.max(b))),
        "% waiting on DMA",
    )
}

fn draw(
    path: &Path,
    timeline: &Timeline,
    values: &[Option<f64>],
    (lo, hi): (f64, f64),
    title: &str,
) -> Result<(), String> {
    let (w, h) = (timeline.width, timeline.height);
    let scale_h = h.max(160);
    let full_w = w + SCALE_WIDTH;
    let mut rgb = vec![255u8; (full_w * scale_h * 3) as usize];
    let range = (hi - lo).max(1e-9);
    for y in 0..h {
        for x in 0..w {
            let c = match values[(y * w + x) as usize] {
                Some(v) => colour((v - lo) / range),
                None => NO_PACKET,
            };
            let o = ((y * full_w + x) * 3) as usize;
            rgb[o..o + 3].copy_from_slice(&c);
        }
    }
    // the scale: a bar from hi (top) to lo (bottom), labelled at both ends and the middle
    let (bar_x, bar_w) = (w + 10, 16);
    let (bar_top, bar_bottom) = (20u32, scale_h - 20);
    for y in bar_top..bar_bottom {
        let v = 1.0 - (y - bar_top) as f64 / (bar_bottom - bar_top - 1).max(1) as f64;
        let c = colour(v);
        for x in bar_x..bar_x + bar_w {
            let o = ((y * full_w + x) * 3) as usize;
            rgb[o..o + 3].copy_from_slice(&c);
        }
    }
    label(
        &mut rgb,
        (full_w, scale_h),
        (bar_x, bar_top, bar_bottom, bar_w),
        (lo, hi),
        title,
    )?;
    // Encoded in memory and written whole: a failed write leaves no partial image.
    let png = crate::png::encode_rgb(&rgb, full_w, scale_h)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    crate::exit::write_file(path, &png).map_err(|e| e.message.unwrap_or_default())
}

fn label(
    rgb: &mut [u8],
    size: (u32, u32),
    (bar_x, top, bottom, bar_w): (u32, u32, u32, u32),
    (lo, hi): (f64, f64),
    title: &str,
) -> Result<(), String> {
    use plotters::prelude::*;
    crate::paper_figure::register_font()?;
    let root = BitMapBackend::with_buffer(rgb, size).into_drawing_area();
    let style = TextStyle::from(("sans-serif", 12).into_font()).color(&BLACK);
    let fmt = |v: f64| {
        if v.abs() >= 10_000.0 {
            format!("{:.0}k", v / 1000.0)
        } else {
            format!("{v:.0}")
        }
    };
    let x = (bar_x + bar_w + 4) as i32;
    let mid = (top + bottom) / 2;
    let text = [
        (fmt(hi), top as i32 - 6),
        (fmt((lo + hi) / 2.0), mid as i32 - 6),
        (fmt(lo), bottom as i32 - 8),
    ];
    let draw = |s: &str, y: i32| root.draw_text(s, &style, (x, y)).map_err(|e| e.to_string());
    for (s, y) in &text {
        draw(s, *y)?;
    }
    root.draw_text(title, &style, (bar_x as i32 - 4, 4))
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_runs_from_dark_to_bright() {
        assert_eq!(colour(0.0), [68, 1, 84]);
        assert_eq!(colour(1.0), [253, 231, 37]);
        assert_eq!(colour(f64::NAN), colour(0.0));
        let lum = |c: [u8; 3]| 0.3 * c[0] as f64 + 0.59 * c[1] as f64 + 0.11 * c[2] as f64;
        for i in 0..10 {
            assert!(lum(colour(i as f64 / 10.0)) < lum(colour((i + 1) as f64 / 10.0)));
        }
    }
}
