//! `spu render --shade`, `--light`, `--shadow-early`: bad values are refused before any
//! work with exit status 2; a shaded frame validates hits and colours and says so.

use std::process::Command;

fn spu(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn bad_shading_options_exit_2_before_any_work() {
    let dir = std::env::temp_dir().join(format!("spu-shade-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("x.png");
    let out = out.to_str().unwrap();
    let nine: Vec<String> = (0..9).map(|i| format!("--light=0,{i},0")).collect();
    let cases: Vec<Vec<&str>> = vec![
        vec!["--shade", "phong"],
        vec!["--light", "1,2"],
        vec!["--light", "1,2,nan"],
        vec!["--light", "0,0,0,1,-1,0"],
        vec!["--shadow-early", "maybe"],
        vec!["--vertex-cache", "100"],
        vec!["--material-cache", "512"],
        vec!["--shade", "shadows", "--fill"],
        vec!["--shade", "simple", "--fill"],
        vec!["--shade", "reflect", "--reflect-depth", "0"],
        vec!["--shade", "reflect", "--reflect-depth", "5"],
        vec!["--shade", "reflect", "--reflect-depth", "two"],
        vec!["--shade", "shadows", "--reflect-depth", "2"],
        nine.iter().map(String::as_str).collect(),
    ];
    for case in cases {
        let args = [
            &["render", "--width", "8", "--height", "8", "-o", out][..],
            &case,
        ]
        .concat();
        let run = spu(&args);
        assert_eq!(run.status.code(), Some(2), "{case:?}: {run:?}");
        assert!(
            !std::path::Path::new(out).exists(),
            "{case:?} wrote an image"
        );
    }
    // A light without shading would be ignored: refused, saying what to add.
    let run = spu(&[
        "render", "--width", "8", "--height", "8", "-o", out, "--light", "1,2,3",
    ]);
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    assert_eq!(
        String::from_utf8_lossy(&run.stderr),
        "spu: --light lights a shaded frame, and this one is not shaded: add --shade simple or --shade shadows\n"
    );
    assert!(!std::path::Path::new(out).exists());
    // A depth without reflections is refused saying what it is for.
    let run = spu(&[
        "render",
        "--scene",
        "no-such.obj",
        "-o",
        out,
        "--shade",
        "simple",
        "--reflect-depth",
        "2",
    ]);
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    assert_eq!(
        String::from_utf8_lossy(&run.stderr),
        "spu: --reflect-depth sets the bounces of --shade reflect, and this frame does not reflect\n"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_shaded_frame_validates_hits_and_colours() {
    let dir = std::env::temp_dir().join(format!("spu-shade-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("room.png");
    let run = spu(&[
        "render",
        "--width",
        "64",
        "--height",
        "64",
        "--shade",
        "simple",
        "--light",
        "-0.6,2.7,0.4",
        "--light=2,1,2,0.5,0.4,0.3",
        "--validate",
        "-o",
        png.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{run:?}");
    assert!(
        text.contains(
            "0 of 4096 pixels differ from the host reference in the hit triangle, 0 in colour"
        ),
        "{text}"
    );
    let (_, _, pixels) = crate::read_png_rgb(&png);
    let distinct: std::collections::BTreeSet<[u8; 3]> = pixels.into_iter().collect();
    assert!(
        distinct.len() > 100,
        "a coloured image: {} colours",
        distinct.len()
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_frame_with_shadows_validates() {
    let dir = std::env::temp_dir().join(format!("spu-shadows-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("room.png");
    let stats = dir.join("room.json");
    let run = spu(&[
        "render",
        "--width",
        "64",
        "--height",
        "64",
        "--shade",
        "shadows",
        "--shadow-early",
        "on",
        "--validate",
        "--stats",
        stats.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{run:?}");
    assert!(
        text.contains(
            "0 of 4096 pixels differ from the host reference in the hit triangle, 0 in colour"
        ) && text.contains("grazing an occluder's edge"),
        "{text}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let shadow = json["rays_by_kind"]["shadow"].as_u64().unwrap();
    assert!(shadow > 0 && shadow <= 4096, "{json}");
    assert_eq!(json["rays_by_kind"]["primary"].as_u64(), Some(4096));
    assert!(
        json["validation"]["shadow_edge_pixels"].as_u64().is_some(),
        "{json}"
    );
    assert!(json["fps"].as_f64().unwrap() > 0.0);
    std::fs::remove_dir_all(&dir).ok();
}

/// A reflective frame (the room's polished table) validates every bounce and every colour,
/// and its statistics count the reflected rays and packets the host model casts.
#[test]
fn a_frame_with_reflections_validates_and_counts_its_rays() {
    let dir = std::env::temp_dir().join(format!("spu-reflect-ok-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("room.png");
    let stats = dir.join("room.json");
    let (size, depth) = (96, 2);
    let run = spu(&[
        "render",
        "--width",
        &size.to_string(),
        "--height",
        &size.to_string(),
        "--shade",
        "reflect",
        "--reflect-depth",
        &depth.to_string(),
        "--spes",
        "2",
        "--validate",
        "--stats",
        stats.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{run:?}");
    // the host model's reflection packets of the same frame
    let prepared = spu_loader::render::prepare("room").unwrap();
    let reference = spu_loader::reference::Reference::from_staged(&prepared.staged);
    let camera = &prepared.scene.camera;
    let hits = reference.render(camera, size, size, 2);
    let lights = spu_loader::shading::default_lights(&prepared.scene);
    let frame = spu_loader::reflection::ReflectFrame::render(
        &reference, &hits, camera, size, size, &lights, depth, 2,
    );
    let packets = frame.packets(size, size);
    assert!(packets[0].rays > 100, "{packets:?}");
    assert!(
        text.contains(
            "validation: 0 of 9216 pixels differ from the host reference in the hit triangle, 0 in colour (more than 2 of 255 in a channel)"
        ),
        "{text}"
    );
    assert!(
        text.contains(&format!(
            "; bounce 1: 0 of {} reflected rays differ; bounce 2: 0 of {} reflected rays differ\n",
            packets[0].rays, packets[1].rays
        )),
        "{text}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let bounces = json["reflections"].as_array().unwrap();
    assert_eq!(bounces.len(), depth as usize);
    for (b, model) in bounces.iter().zip(&packets) {
        assert_eq!(b["rays"], model.rays, "{b}");
        assert_eq!(b["hits"], model.hits, "{b}");
        assert_eq!(b["packets"], model.packets, "{b}");
    }
    let reflected: u64 = packets.iter().map(|p| p.rays).sum();
    assert_eq!(json["rays_by_kind"]["reflected"], reflected);
    std::fs::remove_dir_all(&dir).ok();
}
