//! `spu render --heatmap` and `--trace`: the pictures cover every packet, the trace is
//! well-formed Trace Event Format JSON with properly nested slices, and logging the events
//! changes neither the cycles nor the image.

use std::process::Command;

fn spu(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn heatmap_and_trace_of_a_small_frame() {
    let dir = std::env::temp_dir().join(format!("spu-views-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let base = [
        "render", "--scene", "room", "--width", "128", "--height", "128", "--spes", "2", "--sht",
        "1",
    ];
    let plain = spu(&[&base[..], &["-o", &p("a.png"), "--stats", &p("a.json")]].concat());
    assert!(plain.status.success());
    let viewed = spu(&[
        &base[..],
        &[
            "-o",
            &p("b.png"),
            "--stats",
            &p("b.json"),
            "--heatmap",
            &p("heat.png"),
            "--trace",
            &p("trace.json"),
        ],
    ]
    .concat());
    assert!(
        viewed.status.success(),
        "{}",
        String::from_utf8_lossy(&viewed.stderr)
    );
    // the event log is only watched: same cycles, same image
    let cycles = |f: &str| {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p(f)).unwrap()).unwrap();
        v["frame_cycles"].as_u64().unwrap()
    };
    assert_eq!(cycles("a.json"), cycles("b.json"));
    assert_eq!(
        std::fs::read(p("a.png")).unwrap(),
        std::fs::read(p("b.png")).unwrap()
    );

    for map in ["heat.png", "heat-wait.png"] {
        let (width, height, pixels) = crate::read_png_rgb(p(map));
        assert_eq!((width, height), (128 + 110, 160), "{map}");
        // every pixel of the frame belongs to a packet (none left in the no-packet grey)
        let grey = [40u8, 40, 40];
        assert!((0..128).all(|y| (0..128).all(|x| pixels[(y * width + x) as usize] != grey)));
    }
    let (width, _, heat) = crate::read_png_rgb(p("heat.png"));
    let distinct: std::collections::BTreeSet<[u8; 3]> = (0..128)
        .flat_map(|y| (0..128).map(move |x| (x, y)))
        .map(|(x, y)| heat[(y * width + x) as usize])
        .collect();
    assert!(distinct.len() > 4, "cycles vary over the frame");

    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("trace.json")).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let of = |cat: &str| -> Vec<&serde_json::Value> {
        events.iter().filter(|e| e["cat"] == cat).collect()
    };
    let (tiles, packets) = (of("tile"), of("packet"));
    assert_eq!(tiles.len(), 4);
    assert_eq!(packets.len(), 256);
    assert!(!of("dma-wait").is_empty());
    for e in events {
        let ph = e["ph"].as_str().unwrap();
        assert!(["X", "C", "M"].contains(&ph), "{e}");
        assert!(e["ts"].as_f64().unwrap() >= 0.0 && e["pid"].is_u64() && e["name"].is_string());
        if ph == "X" {
            assert!(e["dur"].as_f64().unwrap() >= 0.0, "{e}");
        }
    }
    // without SHT each packet lies within its tile's span on the SPU's tile track
    for pk in &packets {
        let (ts, end) = (
            pk["ts"].as_f64().unwrap(),
            pk["ts"].as_f64().unwrap() + pk["dur"].as_f64().unwrap(),
        );
        let tile = pk["name"].as_str().unwrap()[7..].split('.').next().unwrap();
        let t = tiles
            .iter()
            .find(|t| {
                t["name"] == format!("tile {tile}")
                    && t["tid"].as_u64() == pk["tid"].as_u64().map(|s| s + 200)
            })
            .unwrap_or_else(|| panic!("no tile for {pk}"));
        let (a, b) = (
            t["ts"].as_f64().unwrap(),
            t["ts"].as_f64().unwrap() + t["dur"].as_f64().unwrap(),
        );
        assert!(a <= ts + 1e-9 && end <= b + 1e-9, "{pk} in {t}");
    }
    let names: Vec<&str> = events
        .iter()
        .filter(|e| e["ph"] == "M" && e["name"] == "thread_name")
        .map(|e| e["args"]["name"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"SPU 0 packets") && names.contains(&"SPU 1 DMA waits"));
    assert!(events
        .iter()
        .any(|e| e["ph"] == "C" && e["name"] == "memory interface"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unwritable_heatmap_or_trace_is_refused_before_rendering() {
    let out = spu(&[
        "render",
        "--width",
        "64",
        "--height",
        "64",
        "--trace",
        "/nonexistent-dir/t.json",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent-dir/t.json"));
}

/// With software hyperthreading packets complete out of order across tiles: every packet
/// is still found once, and the tile spans of an SPU do not overlap.
#[test]
fn trace_with_packets_in_flight() {
    let dir = std::env::temp_dir().join(format!("spu-views-sht-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let out = spu(&[
        "render",
        "--scene",
        "conference",
        "--width",
        "128",
        "--height",
        "128",
        "--spes",
        "2",
        "--sht",
        "4",
        "-o",
        &p("c.png"),
        "--trace",
        &p("t.json"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p("t.json")).unwrap()).unwrap();
    let events = trace["traceEvents"].as_array().unwrap();
    let mut packets: Vec<&str> = events
        .iter()
        .filter(|e| e["cat"] == "packet")
        .map(|e| e["name"].as_str().unwrap())
        .collect();
    packets.sort();
    packets.dedup();
    assert_eq!(packets.len(), 256);
    for tid in [200, 201] {
        let mut spans: Vec<(f64, f64)> = events
            .iter()
            .filter(|e| e["cat"] == "tile" && e["tid"] == tid)
            .map(|e| {
                let ts = e["ts"].as_f64().unwrap();
                (ts, ts + e["dur"].as_f64().unwrap())
            })
            .collect();
        spans.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert!(!spans.is_empty());
        assert!(
            spans.windows(2).all(|w| w[0].1 <= w[1].0 + 1e-9),
            "{spans:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
