//! `spu render --frames N`: a short animation is rendered, refitted on the SPEs and
//! validated frame by frame; its files are numbered PNGs, an animated PNG and a JSON array;
//! bad counts and bad keyframes are refused before the work (or before their frame), the
//! frames before a bad keyframe staying whole.

use crate::read_png_rgb;
use crate::support::{fresh_dir, spu_in};

const SMALL: [&str; 6] = ["--width", "64", "--height", "64", "--spes", "3"];

#[test]
fn three_frames_of_the_flag_validate_and_refit_on_the_spes() {
    let dir = fresh_dir("animate", "flag");
    let args = [
        &[
            "render",
            "--scene",
            "room-flag",
            "--frames",
            "3",
            "--shade",
            "shadows",
        ][..],
        &SMALL,
        &[
            "--validate",
            "-o",
            "f.png",
            "--animation",
            "all.png",
            "--stats",
            "s.json",
        ],
    ]
    .concat();
    let (out, err, status) = spu_in(&args, &dir);
    assert_eq!(status, 0, "{out}{err}");
    assert!(
        out.contains("validation: 0 of 3 frames differ from the host reference"),
        "{out}"
    );
    let mut images = Vec::new();
    for frame in 0..3 {
        let (w, h, pixels) = read_png_rgb(dir.join(format!("f_00{frame}.png")));
        assert_eq!((w, h), (64, 64));
        assert!(out.contains(&format!("frame {frame}: refit ")), "{out}");
        images.push(pixels);
    }
    assert_ne!(images[0], images[2], "the flag moves");
    // the animation holds the same three frames
    let file = std::fs::File::open(dir.join("all.png")).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    assert_eq!(reader.info().animation_control().unwrap().num_frames, 3);
    let mut bytes = vec![0; reader.output_buffer_size().unwrap()];
    for image in &images {
        let info = reader.next_frame(&mut bytes).unwrap();
        let flat: Vec<u8> = image.iter().flatten().copied().collect();
        assert_eq!(bytes[..info.buffer_size()], flat[..]);
    }
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    let frames = stats.as_array().unwrap();
    assert_eq!(frames.len(), 3);
    for (k, frame) in frames.iter().enumerate() {
        assert_eq!(frame["frame"], k);
        assert_eq!(frame["rebuilt"], false);
        assert_eq!(frame["mismatches"], 0);
        let (refit, trace) = (
            frame["refit_cycles"].as_u64().unwrap(),
            frame["trace_cycles"].as_u64().unwrap(),
        );
        assert!(refit > 0 && trace > refit, "{frame}");
        let fps = frame["fps"].as_f64().unwrap();
        assert!((fps - 2.4e9 / (refit + trace) as f64).abs() < 1e-6 * fps);
        assert_eq!(frame["refit_spes"].as_array().unwrap().len(), 3);
    }
    // the same again: the same cycles (deterministic)
    let (again, _, status) = spu_in(&args, &dir);
    assert_eq!(status, 0);
    assert_eq!(again, out);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_low_rebuild_ratio_rebuilds_on_the_host_and_says_so() {
    let dir = fresh_dir("animate", "rebuild");
    let args = [
        &[
            "render",
            "--scene",
            "room-flag",
            "--frames",
            "8",
            "--rebuild-ratio",
            "1.0001",
        ][..],
        &SMALL,
        &["--validate", "-o", "f.png"],
    ]
    .concat();
    let (out, err, status) = spu_in(&args, &dir);
    assert_eq!(status, 0, "{out}{err}");
    assert!(
        out.contains("BVH rebuilt on the host (refit SAH cost"),
        "{out}"
    );
    assert!(!out.contains(" 0 rebuilt on the host"), "{out}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_counts_and_options_exit_2_before_any_work() {
    let dir = fresh_dir("animate", "counts");
    let cases: [(&[&str], &str); 6] = [
        (
            &["--frames", "0"],
            "--frames 0: an animation has 1 to 18000 frames",
        ),
        (
            &["--frames", "1000000000"],
            "--frames 1000000000: an animation has 1 to 18000 frames",
        ),
        (
            &["--frames", "2", "--scene", "room"],
            "--frames renders a moving scene",
        ),
        (
            &["--frames", "2", "--rebuild-ratio", "0.5"],
            "--rebuild-ratio 0.5",
        ),
        (
            &["--animation", "a.png"],
            "--animation writes the frames of --frames N",
        ),
        (
            &["--frames", "2", "--heatmap", "h.png"],
            "--heatmap is for a single frame",
        ),
    ];
    for (case, message) in cases {
        let scene: &[&str] = if case.contains(&"--scene") {
            &[]
        } else {
            &["--scene", "room-flag"]
        };
        let args = [&["render", "-o", "f.png"][..], scene, &SMALL, case].concat();
        let (_, err, status) = spu_in(&args, &dir);
        assert_eq!(status, 2, "{case:?}: {err}");
        assert!(err.contains(message), "{case:?}: {err}");
    }
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "nothing written"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A triangle strip of `quads` quads with its top row raised by `lift`.
fn keyframe(quads: usize, lift: f32) -> String {
    let mut text = String::new();
    for i in 0..=quads {
        text += &format!("v {i} 0 0\nv {i} {} 0.5\n", 1.0 + lift);
    }
    for i in 0..quads {
        let (a, b) = (2 * i + 1, 2 * i + 2);
        text += &format!("f {a} {} {b}\nf {b} {} {}\n", a + 2, a + 2, b + 2);
    }
    text
}

#[test]
fn keyframes_render_and_a_bad_one_is_refused_at_its_frame() {
    let dir = fresh_dir("animate", "keyframes");
    for frame in 0..3 {
        std::fs::write(
            dir.join(format!("walk_{frame:03}.obj")),
            keyframe(6, 0.1 * frame as f32),
        )
        .unwrap();
    }
    let run = |frames: &str| {
        let args = [
            &["render", "--scene", "walk_%03d.obj", "--frames", frames][..],
            &SMALL,
            &["--validate", "-o", "k.png"],
        ]
        .concat();
        spu_in(&args, &dir)
    };
    let (out, err, status) = run("3");
    assert_eq!(status, 0, "{out}{err}");
    assert!(out.contains("validation: 0 of 3 frames differ"), "{out}");
    // a missing keyframe: the frames before it are written, whole
    for frame in 0..3 {
        std::fs::remove_file(dir.join(format!("k_00{frame}.png"))).unwrap();
    }
    let (_, err, status) = run("4");
    assert_eq!(status, 2, "{err}");
    assert!(err.contains("walk_003.obj"), "{err}");
    for frame in 0..3 {
        let (w, h, _) = read_png_rgb(dir.join(format!("k_00{frame}.png")));
        assert_eq!((w, h), (64, 64));
    }
    assert!(!dir.join("k_003.png").exists());
    // a keyframe of another topology names its file and the first vertex past frame 0's
    std::fs::write(dir.join("walk_002.obj"), keyframe(7, 0.2)).unwrap();
    let (_, err, status) = run("3");
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("walk_002.obj:15: keyframe has 16 vertices, frame 0 has 14"),
        "{err}"
    );
    // a vertex that is not finite names its line
    std::fs::write(
        dir.join("walk_002.obj"),
        keyframe(6, 0.2).replacen("v 0 0 0", "v 0 nan 0", 1),
    )
    .unwrap();
    let (_, err, status) = run("3");
    assert_eq!(status, 2, "{err}");
    assert!(err.contains("walk_002.obj:1:"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
