//! `spu paper`: the report holds every table with numbers and the figures, read back as
//! JSON; `--list-jobs` and `--collect` agree with the in-process run; bad input is named.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn spu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-paper-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn report(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("report.json")).unwrap();
    serde_json::from_str(&text).expect("report.json parses")
}

fn table<'a>(report: &'a serde_json::Value, id: &str) -> &'a serde_json::Value {
    report["tables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["id"] == id)
        .unwrap_or_else(|| panic!("no table {id}"))
}

fn ours(t: &serde_json::Value) -> Vec<f64> {
    t["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| r["ours"].as_f64())
        .collect()
}

/// Removes what depends on the host rather than the simulation: how much ran compiled.
fn drop_host_figures(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(map) => {
            map.retain(|k, _| !k.contains("compiled") && !k.contains("jit"));
            map.values_mut().for_each(drop_host_figures);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(drop_host_figures),
        _ => {}
    }
}

/// The quick report on the built-in scenes (at a smaller size, to keep CI short).
#[test]
fn quick_report_has_every_table_and_the_figure() {
    let dir = temp_dir("quick");
    let out = dir.to_str().unwrap();
    let common = [
        "paper",
        "--quick",
        "--size",
        "128",
        "--max-spes",
        "2",
        "--scenes",
        "room,conference,beetle",
        "--out",
        out,
    ];
    let run = spu(&[&common[..], &["--threads", "2"]].concat());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    // the host's peak memory goes to stderr (Linux), never into the report
    if cfg!(target_os = "linux") {
        let line = err
            .lines()
            .find(|l| l.starts_with("peak memory: "))
            .unwrap_or_else(|| panic!("no peak memory line in {err}"));
        assert!(
            line.contains(" MiB resident on this host (up to 2 runs at once; at most ")
                && line.ends_with(" MiB estimated in flight, budget 1280 MiB)"),
            "{line}"
        );
    }
    let r = report(&dir);
    assert!(!std::fs::read_to_string(dir.join("results.md"))
        .unwrap()
        .contains("peak memory"));
    assert_eq!(r["size"], 128);
    let ids: Vec<&str> = r["tables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["id"].as_str().unwrap())
        .collect();
    assert_eq!(
        ids,
        [
            "table1",
            "table2",
            "table3",
            "table4",
            "table5",
            "table6",
            "figure2",
            "beyond_extensions",
            "beyond_clock",
            "beyond_spes",
            "beyond_reflections",
            "beyond_moving"
        ]
    );
    for t in r["tables"].as_array().unwrap() {
        let rows = t["rows"].as_array().unwrap();
        assert!(!rows.is_empty(), "{}", t["id"]);
        for row in rows {
            // every row has a number of ours or says why not; the ratio follows
            match (row["ours"].as_f64(), row["paper"].as_f64()) {
                (Some(o), Some(p)) => {
                    let ratio = row["ratio"].as_f64().unwrap();
                    assert!((ratio - o / p).abs() < 1e-9, "{row}");
                }
                (None, _) => assert!(row["missing"].is_string(), "{row}"),
                (Some(_), None) => assert!(row["ratio"].is_null(), "{row}"),
            }
        }
    }
    // what the direct-mapped blocking ray caster measures is there for every scene
    for id in ["table1", "table2", "table3", "table5", "figure2"] {
        let t = table(&r, id);
        let n = ours(t).len();
        assert!(n >= 3, "{id}: {n} numbers");
    }
    let t2 = table(&r, "table2");
    assert_eq!(ours(t2).len(), 15, "five rows per scene");
    assert!(ours(t2).iter().all(|v| *v >= 0.0));
    let hit_rates = ours(table(&r, "table1"));
    assert!(hit_rates.iter().all(|v| (0.0..=100.0).contains(v)));
    // Figure 2: one SPE is the baseline, and more SPEs are faster
    let f2 = table(&r, "figure2");
    let room: Vec<f64> = f2["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|row| row["scene"] == "room")
        .map(|row| row["ours"].as_f64().unwrap())
        .collect();
    assert_eq!(room.len(), 2);
    assert_eq!(room[0], 1.0);
    assert!(room[1] > 1.5, "{room:?}");
    assert_eq!(r["jobs"], r["jobs_measured"]);
    assert_eq!(r["missing"].as_array().unwrap().len(), 0);

    let files: Vec<&str> = r["figures"][0]["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_str().unwrap())
        .collect();
    assert_eq!(files, ["figure2.png", "figure2.svg"]);
    let png = std::fs::read(dir.join("figure2.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let svg = std::fs::read_to_string(dir.join("figure2.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("ideal"), "{svg}");
    // "Beyond the paper": its figures, a verdict per prediction from the numbers, and
    // the measured rows (runs above --max-spes say why they are missing)
    let stems: Vec<&str> = r["figures"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["files"][0].as_str().unwrap())
        .collect();
    assert_eq!(
        stems,
        [
            "figure2.png",
            "beyond-hints.png",
            "beyond-clock.png",
            "beyond-spes.png"
        ]
    );
    let verdicts = r["verdicts"].as_array().unwrap();
    assert_eq!(verdicts.len(), 6, "{verdicts:?}");
    assert!(verdicts[0].as_str().unwrap().contains("room"));
    assert!(verdicts[4].as_str().unwrap().starts_with("Reflections (7)"));
    let moving = verdicts[5].as_str().unwrap();
    assert!(moving.contains("room-flag on 1 SPE ") && moving.contains("beetle-drive on 1 SPE "));
    reflections_and_moving_rows(&r);
    let clock = table(&r, "beyond_clock");
    let room_clock: Vec<f64> = clock["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|row| {
            row["scene"] == "room" && row["label"].as_str().unwrap().starts_with("SHT 1,")
        })
        .map(|row| row["ours"].as_f64().unwrap())
        .collect();
    assert_eq!(room_clock.len(), 5);
    assert!(room_clock.windows(2).all(|w| w[1] > w[0]), "{room_clock:?}");
    let spes = table(&r, "beyond_spes");
    let rows = spes["rows"].as_array().unwrap();
    assert!(rows
        .iter()
        .filter(|row| row["label"].as_str().unwrap().starts_with("64 SPEs"))
        .all(|row| row["missing"].as_str().unwrap().contains("--max-spes")));
    // each scene's heat maps, beside the report
    let maps = r["heatmaps"].as_array().unwrap();
    assert_eq!(maps.len(), 3);
    for m in maps {
        for key in ["cycles", "wait"] {
            let png = std::fs::read(dir.join(m[key].as_str().unwrap())).unwrap();
            assert_eq!(&png[1..4], b"PNG", "{m}");
        }
    }
    let md = std::fs::read_to_string(dir.join("report.md")).unwrap();
    let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
    assert!(md.contains("## Heat maps") && html.contains("id=\"heatmaps\""));
    for t in r["tables"].as_array().unwrap() {
        let title = t["title"].as_str().unwrap();
        assert!(md.contains(title), "{title} in report.md");
        assert!(
            html.contains(&title.replace('&', "&amp;")),
            "{title} in report.html"
        );
    }
    // results.md, the tables beside the paper's, comes from the statistics alone: built
    // again from the run's stats files it is the same, byte for byte
    let results = std::fs::read_to_string(dir.join("results.md")).unwrap();
    for t in r["tables"].as_array().unwrap() {
        let title = t["title"].as_str().unwrap();
        assert!(results.contains(&format!("\n## {title}\n")), "{title}");
    }
    assert!(results.contains(
        "| row | ERW6 (paper) | room | Conference (paper) | conference | VW Beetle (paper) | beetle | runs (ours) |"
    ));
    let again = dir.join("again");
    let collected = spu(&[
        &common[..8],
        &["--out", again.to_str().unwrap(), "--collect"],
        &[dir.join("jobs").to_str().unwrap()],
    ]
    .concat());
    assert!(collected.status.success());
    assert_eq!(
        std::fs::read_to_string(again.join("results.md")).unwrap(),
        results
    );
    // a budget smaller than any beetle run: those run alone, the others beside each
    // other on 3 threads, and the report is the same, byte for byte
    let budgeted = dir.join("budgeted");
    let run = spu(&[
        &common[..8],
        &["--out", budgeted.to_str().unwrap()],
        &["--threads", "3", "--memory-budget", "64"],
    ]
    .concat());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(
        err.contains(" runs were estimated larger than --memory-budget 64 MiB and ran alone\n"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(budgeted.join("results.md")).unwrap(),
        results
    );

    // --list-jobs prints one render per job, writing where the run wrote
    let listed = spu(&[&common[..], &["--list-jobs"]].concat());
    assert!(listed.status.success());
    let listed = String::from_utf8(listed.stdout).unwrap();
    let lines: Vec<&str> = listed.lines().collect();
    assert_eq!(Some(lines.len() as u64), r["jobs"].as_u64());
    for line in &lines {
        let stats = line
            .split_whitespace()
            .skip_while(|w| *w != "--stats")
            .nth(1)
            .expect("--stats FILE");
        assert!(Path::new(stats).is_file(), "{stats}");
        assert!(line.contains(" render ") && line.contains("--width 128"));
    }
    // The run's frames shared prepared scenes and compiled blocks; a frame of each scene
    // rendered on its own, as the listed command, gives the same statistics and image.
    let alone = dir.join("alone");
    std::fs::create_dir_all(&alone).unwrap();
    for scene in ["room", "conference", "beetle"] {
        let line = lines
            .iter()
            .find(|l| l.contains(&format!("--scene {scene} ")) && l.contains("--shade shadows"))
            .unwrap_or_else(|| panic!("a {scene} frame with shadows is listed"));
        let mut words: Vec<String> = line.split_whitespace().skip(1).map(String::from).collect();
        // (the run's file, this frame's) for the statistics and the image
        let mut stats = (PathBuf::new(), PathBuf::new());
        let mut image = (PathBuf::new(), PathBuf::new());
        for i in 1..words.len() {
            let file = alone.join(Path::new(&words[i]).file_name().unwrap_or_default());
            let own = file.display().to_string();
            match words[i - 1].as_str() {
                "--stats" => stats = (std::mem::replace(&mut words[i], own).into(), file),
                "-o" | "--output" => image = (std::mem::replace(&mut words[i], own).into(), file),
                "--heatmap" | "--trace" | "--profile" => words[i] = own,
                _ => {}
            }
        }
        let args: Vec<&str> = words.iter().map(String::as_str).collect();
        let run = spu(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        assert_eq!(
            std::fs::read(&image.0).unwrap(),
            std::fs::read(&image.1).unwrap(),
            "{scene}: the image"
        );
        let read = |path: &Path| {
            let mut v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
            drop_host_figures(&mut v);
            v
        };
        assert_eq!(read(&stats.0), read(&stats.1), "{scene}: the statistics");
    }
    // a moving scene's job is listed with its frames, and rendered alone it writes the
    // statistics and frames the run wrote
    let line = lines
        .iter()
        .find(|l| l.contains("--scene room-flag ") && l.contains("--spes 1 "))
        .expect("the moving room's job is listed");
    assert!(line.ends_with(" --frames 2"), "{line}");
    let mut words: Vec<String> = line.split_whitespace().skip(1).map(String::from).collect();
    let (mut stats, mut image) = (PathBuf::new(), PathBuf::new());
    for i in 1..words.len() {
        let own = alone.join(Path::new(&words[i]).file_name().unwrap_or_default());
        match words[i - 1].as_str() {
            "--stats" => stats = std::mem::replace(&mut words[i], own.display().to_string()).into(),
            "-o" => image = std::mem::replace(&mut words[i], own.display().to_string()).into(),
            _ => {}
        }
    }
    let args: Vec<&str> = words.iter().map(String::as_str).collect();
    let run = spu(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mine = alone.join(stats.file_name().unwrap());
    assert_eq!(
        std::fs::read_to_string(&stats).unwrap(),
        std::fs::read_to_string(&mine).unwrap(),
        "room-flag: the frames' statistics"
    );
    for frame in ["_000.png", "_001.png"] {
        let name = |p: &Path| {
            let stem = p.file_stem().unwrap().to_str().unwrap().to_string();
            p.with_file_name(stem + frame)
        };
        let alone_image = alone.join(image.file_name().unwrap());
        assert_eq!(
            std::fs::read(name(&image)).unwrap(),
            std::fs::read(name(&alone_image)).unwrap(),
            "room-flag frame {frame}"
        );
    }
    // ... and makes the jobs folder, so the listed commands run in a fresh --out
    let fresh = dir.join("fresh");
    let listed = spu(&["paper", "--out", fresh.to_str().unwrap(), "--list-jobs"]);
    assert!(listed.status.success());
    assert!(fresh.join("jobs").is_dir());
    let _ = std::fs::remove_dir_all(&dir);
}

/// "Beyond the paper": Table 5 with reflections, and the moving scenes' refit and frame
/// rates, on one SPE (more are above the quick run's --max-spes).
fn reflections_and_moving_rows(r: &serde_json::Value) {
    let number = |t: &serde_json::Value, scene: &str, label: &str| -> Option<f64> {
        let rows = t["rows"].as_array().unwrap();
        let row = rows
            .iter()
            .find(|row| row["scene"] == scene && row["label"] == label)
            .unwrap_or_else(|| panic!("{scene}: row {label}"));
        row["ours"].as_f64()
    };
    let t = table(r, "beyond_reflections");
    // Table 5's rows, numbers and paper's numbers, then the reflections
    let table5 = table(r, "table5");
    for row in table5["rows"].as_array().unwrap() {
        let scene = row["scene"].as_str().unwrap();
        let label = row["label"].as_str().unwrap();
        assert_eq!(number(t, scene, label), row["ours"].as_f64(), "{label}");
    }
    assert_eq!(
        t["rows"].as_array().unwrap().len(),
        table5["rows"].as_array().unwrap().len() / 3 * 5
    );
    let one = "2.4 GHz SPE";
    for scene in ["room", "conference", "beetle"] {
        let reflect = number(t, scene, &format!("reflections (ours, depth 1): {one}")).unwrap();
        let shadows = number(t, scene, &format!("shadows: {one}")).unwrap();
        let ratio = number(t, scene, &format!("reflections over shadows (x): {one}")).unwrap();
        // a reflected ray is traced on top of the shadows frame's work
        assert!(reflect < shadows, "{scene}: {reflect} against {shadows}");
        assert!((ratio - reflect / shadows).abs() < 1e-9, "{scene}");
        let dual = format!(
            "reflections (ours, depth 1): {}",
            "Dual-Cell (16 SPEs, 2.4 GHz)"
        );
        assert_eq!(number(t, scene, &dual), None);
    }
    let t = table(r, "beyond_moving");
    for scene in ["room", "beetle"] {
        let m = |label: &str| number(t, scene, label).unwrap();
        let (refit, trace) = (
            m("1 SPEs: refit Mcycles per frame"),
            m("1 SPEs: trace Mcycles per frame"),
        );
        assert!(refit > 0.0 && trace > 0.0, "{scene}");
        let pct = m("1 SPEs: refit % of the cycles");
        assert!(
            (pct - 100.0 * refit / (refit + trace)).abs() < 1e-6,
            "{scene}"
        );
        let (with, without) = (
            m("1 SPEs: fps with the refit"),
            m("1 SPEs: fps without the refit"),
        );
        // fps over both frames: 2.4 GHz over the mean cycles per frame
        assert!(
            (with - 2400.0 / (refit + trace)).abs() < 1e-6 * with,
            "{scene}"
        );
        assert!((without - 2400.0 / trace).abs() < 1e-6 * without, "{scene}");
        assert_eq!(m("frames rebuilt on the host"), 0.0, "{scene}");
        assert_eq!(number(t, scene, "16 SPEs: fps with the refit"), None);
    }
    // the refit has no data-dependent branch: the same cycles each frame, at any frame size
    // (155,475 on one SPE in docs/animation.md's 1024x1024 run)
    assert_eq!(
        number(t, "room", "1 SPEs: refit Mcycles per frame"),
        Some(0.155475)
    );
    // two SPE counts of five rows and the rebuilds, for the scenes that move
    let rows = t["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2 * 11);
    assert!(!rows.iter().any(|row| row["scene"] == "conference"));
}

#[test]
fn collect_names_missing_and_corrupt_stats_and_reports_the_rest() {
    let dir = temp_dir("collect");
    let out = dir.join("run");
    let small = [
        "paper",
        "--size",
        "64",
        "--max-spes",
        "2",
        "--scenes",
        "room",
    ];
    let run = spu(&[&small[..], &["--out", out.to_str().unwrap()]].concat());
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let full = report(&out);
    let jobs = out.join("jobs");
    let mut stats: Vec<PathBuf> = std::fs::read_dir(&jobs)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    stats.sort();
    assert_eq!(Some(stats.len() as u64), full["jobs"].as_u64());
    std::fs::remove_file(&stats[0]).unwrap();
    std::fs::write(&stats[1], "{\"scene\": \"room\", \"width\": ").unwrap();

    let again = dir.join("again");
    let collected = spu(&[
        &small[..],
        &[
            "--collect",
            jobs.to_str().unwrap(),
            "--out",
            again.to_str().unwrap(),
        ],
    ]
    .concat());
    assert_eq!(
        collected.status.code(),
        Some(2),
        "stats missing from --collect"
    );
    let err = String::from_utf8_lossy(&collected.stderr);
    for gone in &stats[..2] {
        let name = gone.file_name().unwrap().to_str().unwrap();
        assert!(err.contains(name), "{name} in {err}");
    }
    let partial = report(&again);
    assert_eq!(partial["missing"].as_array().unwrap().len(), 2);
    assert_eq!(
        partial["jobs_measured"].as_u64().unwrap() + 2,
        full["jobs"].as_u64().unwrap()
    );
    let md = std::fs::read_to_string(again.join("report.md")).unwrap();
    assert!(md.contains("missing:"), "{md}");
    // the rest is reported as before
    assert_eq!(
        table(&partial, "table2")["rows"],
        table(&full, "table2")["rows"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_scenes_and_output_are_named_before_any_work() {
    let dir = temp_dir("bad");
    let out = spu(&[
        "paper",
        "--scenes",
        "room,teapot",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "bad input");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown scene \"teapot\""), "{err}");

    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let under_file = file.join("report");
    let out = spu(&[
        "paper",
        "--scenes",
        "room",
        "--out",
        under_file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "bad input");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--out"), "{err}");
    assert!(!dir.join("jobs").exists());
    // --list-jobs makes OUT/jobs for the listed renders: one that cannot be made is bad
    // input too, found before anything is listed.
    let out = spu(&[
        "paper",
        "--scenes",
        "room",
        "--list-jobs",
        "--out",
        under_file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2), "bad input");
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.starts_with(&format!(
            "spu: --out: {}: ",
            under_file.join("jobs").display()
        )),
        "{err}"
    );

    let out = spu(&[
        "paper",
        "--collect",
        dir.join("nowhere").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("nowhere"));

    // the memory budget is checked before any work, --list-jobs too
    for (budget, listing) in [("0", false), ("63", true), ("2000000000", false)] {
        let mut args = vec![
            "paper",
            "--scenes",
            "room",
            "--memory-budget",
            budget,
            "--out",
            dir.to_str().unwrap(),
        ];
        if listing {
            args.push("--list-jobs");
        }
        let out = spu(&args);
        assert_eq!(out.status.code(), Some(2), "--memory-budget {budget}");
        assert!(out.stdout.is_empty());
        assert_eq!(
            String::from_utf8_lossy(&out.stderr),
            format!("spu: --memory-budget {budget}: must be 64 to 1073741824 MiB\n")
        );
    }
    let out = spu(&[
        "paper",
        "--memory-budget",
        "lots",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&dir);
}
