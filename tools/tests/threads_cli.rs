//! `--threads` at its edges and a render cut by SIGINT: the exact notes on standard error,
//! the exit statuses, and that an interrupted render leaves no file behind.

use std::io::BufRead;
use std::process::{Command, Stdio};

fn dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-threads-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[test]
fn more_threads_than_spes_or_cores_run_and_say_so_once() {
    let d = dir("notes");
    let image = d.join("a.png");
    let threads = (cores() + 1).to_string();
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(["render", "--width", "16", "--height", "16", "--spes", "1"])
        .args(["--threads", &threads, "-o"])
        .arg(&image)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let notes: Vec<&str> = stderr.lines().filter(|l| l.contains("--threads")).collect();
    let c = cores();
    assert_eq!(
        notes,
        [
            format!("spu: --threads {threads}: only 1 SPE to run at once, so 1 host thread runs it"),
            format!("spu: --threads {threads}: more than this host's {c} cores; the results are the same, the run likely slower than with --threads {c}"),
        ]
    );
    assert!(image.is_file());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_render_cut_by_sigint_exits_130_and_leaves_no_file() {
    let d = dir("sigint");
    // long enough (a shaded 1024x1024 beetle takes seconds) to be cut while rendering
    let mut child = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args([
            "render", "--scene", "beetle", "--shade", "shadows", "--spes", "2",
        ])
        .args(["--threads", "2", "-o"])
        .arg(d.join("beetle.png"))
        .arg("--stats")
        .arg(d.join("beetle.json"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    // the scene is prepared (outputs checked writable) once this line is out
    while stderr.read_line(&mut line).unwrap() > 0 && !line.starts_with("scene beetle") {
        line.clear();
    }
    assert!(line.starts_with("scene beetle"), "{line}");
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{rest}");
    assert!(rest.ends_with("spu: interrupted\n"), "{rest}");
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");
    std::fs::remove_dir_all(&d).unwrap();
}
