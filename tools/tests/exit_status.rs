//! Bad input, runaway programs and failed outputs, run through the built `spu` binary: each
//! case asserts the message and the documented exit status (README, "Exit status"), for
//! each class of failure: what used to abort the host, what used to hang it, and what used
//! to pass silently.

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

struct Outcome {
    status: i32,
    stdout: String,
    stderr: String,
}

fn spu(args: &[&str]) -> Outcome {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap();
    let outcome = Outcome {
        status: out.status.code().expect("exited, not killed by a signal"),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    };
    assert!(
        !outcome.stderr.contains("panicked"),
        "spu {args:?} panicked: {}",
        outcome.stderr
    );
    outcome
}

impl Outcome {
    /// The command failed with `status` and its message says `reason`.
    fn refused(&self, status: i32, reason: &str) {
        assert_eq!(self.status, status, "{}", self.stderr);
        assert!(self.stderr.contains(reason), "{}", self.stderr);
    }
}

/// A fresh directory for one test.
fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-exit-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> String {
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path.to_str().unwrap().to_string()
}

fn program(dir: &Path, name: &str, body: &str) -> String {
    write(
        dir,
        name,
        format!("        .text\n        .global _start\n_start:\n{body}"),
    )
}

/// Files left in `dir` besides the inputs (outputs and temporaries).
fn files_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn run_exits_with_the_programs_exit_code() {
    let d = dir("run-codes");
    for (code, status) in [("0x2000", 0), ("0x2005", 5), ("0x20ff", 255)] {
        let src = program(&d, "exit.s", &format!("        stop {code}\n"));
        let out = spu(&["run", &src]);
        assert_eq!(out.status, status, "stop {code}: {}", out.stderr);
        assert!(out.stdout.starts_with(&format!("stopped: stop {code}")));
        assert_eq!(out.stderr, "", "a program's exit is not an error");
    }
    let src = program(&d, "other.s", "        stop 0x1234\n");
    let out = spu(&["run", &src]);
    out.refused(134, "stop 0x1234 is not an exit (0x2000..0x20ff)");
}

#[test]
fn abnormal_stops_exit_134_with_the_reason() {
    let d = dir("abnormal");
    let illegal = program(&d, "illegal.s", "        .word 0x60000000\n");
    let out = spu(&["run", &illegal]);
    out.refused(
        134,
        "SPU stopped abnormally: illegal instruction 0x60000000 at 0x0",
    );
    let deadlock = program(
        &d,
        "deadlock.s",
        "        rdch $3, $SPU_RdInMbox\n        stop 0x2000\n",
    );
    let out = spu(&["run", &deadlock]);
    out.refused(134, "deadlock at 0x0 on channel SPU_RdInMbox (29)");

    // `spu prof` still prints the profile, then says how the program ended.
    for (file, reason) in [
        (&illegal, "illegal instruction 0x60000000"),
        (&deadlock, "deadlock at 0x0"),
    ] {
        let out = spu(&["prof", file]);
        assert_eq!(out.status, 134, "{file}");
        assert!(out.stdout.contains("Total Cycle count"), "{}", out.stdout);
        assert!(out.stderr.contains(reason), "{}", out.stderr);
    }
    let fine = program(&d, "fine.s", "        stop 0x2003\n");
    assert_eq!(
        spu(&["prof", &fine]).status,
        0,
        "prof: any stop is a normal end"
    );
}

#[test]
fn cycle_limits_exit_124() {
    let d = dir("cycles");
    let spin = program(&d, "spin.s", "        br _start\n");
    for command in ["run", "prof"] {
        let out = spu(&[command, &spin, "--max-cycles", "5000"]);
        assert_eq!(out.status, 124, "{command}: {}", out.stderr);
        assert!(out.stderr.contains("cycle limit"), "{}", out.stderr);
    }
    // The stop is exact: timing model on or off, either engine, with a branch miss, a
    // dependency stall or a memoized block in the way (`--max-cycles 10` reported 23).
    let dependent = program(
        &d,
        "dependent.s",
        "        il $3, 1\n        fm $4, $3, $3\n        fm $5, $4, $4\n        fm $6, $5, $5\n        br _start\n",
    );
    for file in [&spin, &dependent] {
        for limit in ["10", "23", "5000"] {
            for engine in ["interp", "jit"] {
                for timing in [&[][..], &["--timing"][..]] {
                    let args = [
                        &[
                            "run",
                            file.as_str(),
                            "--max-cycles",
                            limit,
                            "--engine",
                            engine,
                        ][..],
                        timing,
                    ]
                    .concat();
                    let out = spu(&args);
                    assert_eq!(out.status, 124, "{args:?}: {}", out.stderr);
                    assert!(
                        out.stdout.contains(&format!("\ncycles: {limit}\n")),
                        "{args:?}: {}",
                        out.stdout
                    );
                    let json = spu(&[&args[..], &["--json"]].concat());
                    let report: serde_json::Value = serde_json::from_str(&json.stdout).unwrap();
                    assert_eq!(report["cycles"].to_string(), limit, "{args:?}");
                }
            }
        }
    }
    let out = spu(&["prof", &dependent, "--max-cycles", "23", "--json"]);
    assert_eq!(out.status, 124);
    let prof: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert!(prof["totals"]["cycles"].as_u64().unwrap() <= 23, "{prof}");
}

#[test]
fn render_max_cycles_is_per_spe_and_exact() {
    // Each SPE stops at exactly N, whatever the engine and the 10,000-cycle quanta (N
    // falls inside one, and inside the kernel's spin on the tile counter): the message
    // names the SPEs the limit stopped and the ones that had finished, with their clocks.
    let d = dir("render-cycles");
    let image = d.join("r.png");
    let image = image.to_str().unwrap();
    let render = |spes: &str, limit: &str, engine: &str| {
        spu(&[
            "render",
            "--width",
            "16",
            "--height",
            "16",
            "--spes",
            spes,
            "--max-cycles",
            limit,
            "--engine",
            engine,
            "-o",
            image,
        ])
    };
    for engine in ["interp", "jit"] {
        for (spes, limit, stopped) in [
            ("1", "777", "SPE 0 stopped at cycle 777"),
            ("4", "5000", "SPE 0, 1, 2, 3 stopped at cycle 5000"),
            ("3", "12345", "SPE 0, 1, 2 stopped at cycle 12345"),
            (
                "4",
                "60000",
                "SPE 0 stopped at cycle 60000; SPE 1 had finished at cycle 30561; \
                 SPE 2 had finished at cycle 40561; SPE 3 had finished at cycle 50561",
            ),
        ] {
            let out = render(spes, limit, engine);
            assert_eq!(out.status, 124, "{engine} {spes} {limit}: {}", out.stderr);
            assert!(
                out.stderr.ends_with(&format!(
                    "spu: the frame did not finish within {limit} cycles per SPE: {stopped}\n"
                )),
                "{engine} {spes} {limit}: {}",
                out.stderr
            );
        }
    }
    assert!(!Path::new(image).exists(), "no image of a cut frame");
}

#[test]
fn numeric_options_are_checked_before_any_work() {
    let d = dir("options");
    let src = program(&d, "p.s", "        stop 0x2000\n");
    let cases: &[(&[&str], &str)] = &[
        (
            &["render", "--clock", "0"],
            "--clock 0: must be a number of GHz",
        ),
        (&["render", "--clock", "nan"], "--clock NaN: must be"),
        (&["render", "--clock", "inf"], "--clock inf: must be"),
        (
            &["render", "--clock", "1e20"],
            "--clock 100000000000000000000: must be",
        ),
        (&["render", "--spes", "0"], "--spes 0: must be 1 to 64"),
        (&["render", "--spes", "65"], "--spes 65: must be 1 to 64"),
        (&["render", "--width", "0"], "--width 0: must be 1 to 8192"),
        (
            &["render", "--height", "100000"],
            "--height 100000: must be 1 to 8192",
        ),
        (
            &["render", "--threads", "0"],
            "--threads 0: must be at least 1",
        ),
        (
            &["render", "--threads", "1025"],
            "--threads 1025: must be 1 to 1024",
        ),
        (
            &["paper", "--threads", "0", "--list-jobs"],
            "--threads 0: must be at least 1",
        ),
        (
            &["render", "--max-cycles", "0"],
            "--max-cycles 0: must be at least 1",
        ),
        (
            &["render", "--bvh-cache", "200"],
            "'--bvh-cache <BVH_CACHE>': 200 lines: must be a power of two from 128 to 1024",
        ),
        (
            &["render", "--tri-cache", "2048"],
            "'--tri-cache <TRI_CACHE>': 2048 lines: must be a power of two from 128 to 1024",
        ),
        (
            &["render", "--camera=0,0,0,0,0,-1,0,1,0,inf"],
            "--camera: camera: non-finite value",
        ),
        (
            &["render", "--camera=0,0,0,0,0,0,0,1,0,60"],
            "eye and target coincide",
        ),
        (
            &["bench", "--iterations", "0"],
            "--iterations 0: must be 1 to",
        ),
        (
            &["run", &src, "--max-cycles", "0"],
            "--max-cycles 0: must be at least 1",
        ),
        (
            &["run", &src, "--memory", "1000000000000000"],
            "--memory 1000000000000000: must be a multiple of 16 from 16 to 4294967296",
        ),
        (&["prof", &src, "--memory", "0"], "--memory 0: must be"),
        (
            &["run", &src, "--mbox-in", "0x100000000"],
            "does not fit in 32 bits",
        ),
        (
            &["run", &src, "--dump-ls", "0x3fff0:0x100"],
            "--dump-ls 0x3fff0:0x100: outside the local store",
        ),
        (
            &["as", &src, "--format", "hex"],
            "--format hex: expected elf or bin",
        ),
        (
            &["render", "--compile", "sometimes"],
            "unknown way of compiling `sometimes` (inline or background)",
        ),
        (
            &["run", &src, "--compile", "lazily"],
            "unknown way of compiling `lazily`",
        ),
    ];
    for (args, message) in cases {
        let out = spu(args);
        assert_eq!(out.status, 2, "spu {args:?}: {}", out.stderr);
        assert!(
            out.stderr.contains(message),
            "spu {args:?}: expected `{message}` in: {}",
            out.stderr
        );
        assert_eq!(out.stdout, "", "spu {args:?} did work before refusing");
    }
    // clap's own usage errors are 2 as well.
    assert_eq!(spu(&["render", "--clock", "fast"]).status, 2);
    assert_eq!(spu(&["frobnicate"]).status, 2);
}

#[test]
fn outputs_are_checked_up_front_and_never_left_partial() {
    let d = dir("outputs");
    // A JPEG name fails at once, before the scene is even loaded, and writes nothing.
    let jpg = d.join("x.jpg");
    let out = spu(&[
        "render",
        "--scene",
        "nonexistent.obj",
        "-o",
        jpg.to_str().unwrap(),
    ]);
    out.refused(2, "the image is written as PNG; name it .png");
    let out = spu(&["render", "--heatmap", jpg.to_str().unwrap()]);
    out.refused(2, "--heatmap");
    out.refused(2, "x.jpg: the image is written as PNG");
    let missing = d.join("no/such/dir/out.png");
    let out = spu(&["render", "-o", missing.to_str().unwrap()]);
    out.refused(2, "cannot write");
    let out = spu(&["render", "--stats", d.to_str().unwrap()]);
    out.refused(2, "is a directory");

    let src = program(&d, "p.s", "        stop 0x2000\n");
    let out = spu(&["as", &src, "-o", missing.to_str().unwrap()]);
    out.refused(2, "cannot write");
    // A write that fails part-way (a full device) is a failure, status 1.
    if Path::new("/dev/full").exists() {
        let out = spu(&["as", &src, "-o", "/dev/full"]);
        assert_eq!(out.status, 1, "{}", out.stderr);
        assert!(
            out.stderr.contains("/dev/full: No space left"),
            "{}",
            out.stderr
        );
    }
    // Assembler errors: bad input, and no output or temporary file left behind.
    let bad = write(&d, "bad.s", "        frob $1\n");
    let elf = d.join("bad.elf");
    let out = spu(&["as", &bad, "-o", elf.to_str().unwrap()]);
    out.refused(2, "bad.s:1:");
    assert_eq!(files_in(&d), ["bad.s", "p.s"]);
    // Success leaves the output only.
    let good = d.join("p.elf");
    assert_eq!(spu(&["as", &src, "-o", good.to_str().unwrap()]).status, 0);
    assert_eq!(files_in(&d), ["bad.s", "p.elf", "p.s"]);
}

#[test]
fn bad_scenes_are_refused_with_the_reason() {
    let d = dir("scenes");
    let png = d.join("out.png");
    let png = png.to_str().unwrap();
    let render = |scene: &str| {
        spu(&[
            "render", "--scene", scene, "--width", "8", "--height", "8", "-o", png,
        ])
    };
    // A header that declares four billion vertices fails at once, before any allocation.
    let huge = write(
        &d,
        "huge.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
         property float x\nproperty float y\nproperty float z\nelement face 1\n\
         property list uchar int vertex_indices\nend_header\n0123456789",
    );
    let out = render(&huge);
    out.refused(
        2,
        "header declares 4000000000 'vertex' elements but the 10 body bytes",
    );
    // Infinite vertices: refused naming the line, not rendered black.
    let inf = write(&d, "inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n");
    let out = render(&inf);
    out.refused(2, "inf.obj:2: vertex 1 is not finite (inf, 0, 0)");
    let empty = write(&d, "empty.obj", "v 0 0 0\n");
    let out = render(&empty);
    out.refused(2, "the scene has no triangles");
    let missing = d.join("missing.obj");
    let out = render(missing.to_str().unwrap());
    out.refused(2, "missing.obj: cannot read");
    // MTL errors name the library's line; a comment may hold any bytes; a material the
    // library lacks is a warning naming it, once.
    write(
        &d,
        "m.mtl",
        b"# \xe9t\xe9\nnewmtl red\nKd 1 0 0\nillum two\n",
    );
    let tri = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let scene = write(&d, "m.obj", format!("{tri}usemtl red\nf 1 2 3\n"));
    let out = render(&scene);
    out.refused(
        2,
        &format!(
            "{}:4: material library: illum needs",
            d.join("m.mtl").display()
        ),
    );
    write(&d, "m.mtl", b"# \xe9t\xe9\nnewmtl red\nKd 1 0 0\n");
    let mut obj = format!(
        "# caf\u{1}\n{tri}usemtl red\nf 1 2 3\nusemtl blue\nf 1 3 2\nusemtl blue\nf 2 3 1\n"
    )
    .into_bytes();
    let at = obj.iter().position(|&b| b == 1).unwrap();
    obj[at] = 0xe9;
    let scene = write(&d, "m.obj", obj);
    let out = render(&scene);
    assert_eq!(out.status, 0, "{}", out.stderr);
    let warning = format!(
        "warning: {scene}:8: usemtl blue: no such material in the library; default colour\n"
    );
    assert!(out.stderr.starts_with(&warning), "{}", out.stderr);
    assert_eq!(out.stderr.matches("warning").count(), 1, "{}", out.stderr);
    std::fs::remove_file(png).unwrap();
    assert!(
        !Path::new(png).exists(),
        "no image is written for a refused scene"
    );
}

#[test]
fn malformed_programs_are_bad_input() {
    let d = dir("programs");
    let elf = write(
        &d,
        "trunc.elf",
        b"\x7fELF\x01\x02\x01\0\0\0\0\0\0\0\0\0\0\x02",
    );
    for command in ["run", "prof", "dis"] {
        let out = spu(&[command, &elf]);
        assert_eq!(out.status, 2, "{command}: {}", out.stderr);
        assert!(out.stderr.contains("trunc.elf: "), "{}", out.stderr);
    }
    let big = write(&d, "big.bin", vec![0u8; 300 * 1024]);
    let out = spu(&["run", &big]);
    out.refused(2, "307200 bytes do not fit the 256 KiB local store");
    let out = spu(&["run", d.join("absent.elf").to_str().unwrap()]);
    out.refused(2, "absent.elf: No such file");
}

#[test]
fn assembler_diagnostics_are_one_line_each_in_gnu_form_with_the_column() {
    // GNU as 2.40 writes `t.s:1: Warning: division by zero`; `spu as` writes the same
    // line with the column and the severity as GCC spells it, one line per report.
    let d = dir("diagnostics");
    let src = write(&d, "t.s", ".long 7/0\n.byte 256\nfoo $1\n");
    let out = spu(&["as", &src, "-o", d.join("t.elf").to_str().unwrap()]);
    assert_eq!(out.status, 2);
    assert_eq!(
        out.stderr,
        format!(
            "{src}:1:7: warning: division by zero\n\
             {src}:2:7: warning: value 0x100 truncated to 0x0\n\
             {src}:3:1: error: Invalid mnemonic 'foo'\n\
             1 error(s); nothing written\n"
        )
    );
    let clean = write(&d, "w.s", ".long 7/0\n");
    let out = spu(&["as", &clean, "-o", d.join("w.elf").to_str().unwrap()]);
    assert_eq!(
        (out.status, out.stderr),
        (0, format!("{clean}:1:7: warning: division by zero\n"))
    );
    let absent = d.join("absent.s");
    let out = spu(&[
        "as",
        absent.to_str().unwrap(),
        "-o",
        d.join("a.elf").to_str().unwrap(),
    ]);
    assert_eq!(out.status, 2);
    assert!(
        out.stderr
            .starts_with(&format!("{}: error: can't read: ", absent.display())),
        "{}",
        out.stderr
    );
}

#[test]
fn timing_reports_statements_it_does_not_time() {
    let d = dir("timing");
    let src = write(
        &d,
        "t.s",
        "        .text\nfoo:    il $3, 1\n        frob $1, $2\n        ai $3, $3, 1\n",
    );
    let out = spu(&["timing", &src]);
    out.refused(
        0,
        "t.s:3:9: warning: `frob` is not an SPU instruction; not timed",
    );
}

#[test]
fn json_outputs_are_well_formed() {
    let d = dir("json");
    let src = program(
        &d,
        "p.s",
        "        il $3, 7\n        wrch $SPU_WrOutMbox, $3\n        stop 0x2007\n",
    );
    let out = spu(&["run", &src, "--json"]);
    assert_eq!(out.status, 7);
    let run: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(run["exit_code"], 7);
    assert_eq!(run["outbound_mailbox"], 7);
    assert_eq!(run["registers"][3][0], 7);
    assert!(
        run["stop"].as_str().unwrap().starts_with("stop 0x2007"),
        "{run}"
    );

    // Local-store dumps go inside the one document; the trace goes to standard error.
    let out = spu(&[
        "run",
        &src,
        "--json",
        "--dump-ls",
        "0:0x10",
        "--dump-ls",
        "8:4",
        "--trace",
    ]);
    assert_eq!(out.status, 7, "{}", out.stderr);
    let run: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(
        run["local_store"],
        serde_json::json!([
            {"address": 0, "bytes": "4080038321a00e030000200700000000"},
            {"address": 8, "bytes": "00002007"},
        ])
    );
    assert_eq!(run["instructions"], 3);
    assert_eq!(
        out.stderr,
        "00000: 40800383  il\t$3,7\t$3 <- 00000007 00000007 00000007 00000007\n\
         00004: 21a00e03  wrch\t$ch28,$3\n\
         00008: 00002007  stop\n"
    );
    // Without --json the same dump is text after the summary.
    let out = spu(&["run", &src, "--dump-ls", "8:4"]);
    assert!(
        out.stdout.ends_with("\n00008: 00 00 20 07\n"),
        "{}",
        out.stdout
    );

    let out = spu(&["prof", &src, "--json"]);
    assert_eq!(out.status, 0);
    let prof: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(prof["totals"]["instructions"], 3);
    assert_eq!(prof["instructions"][0]["text"], "il $3,7");

    // No instructions at all: the CPI is null, and the JSON still parses.
    let empty = write(&d, "empty.s", "        .text\n");
    let out = spu(&["timing", &empty, "--json"]);
    assert_eq!(out.status, 0);
    let timing: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    assert_eq!(timing["instructions"], serde_json::json!([]));
}

/// A reader that goes away (`spu dis x | head`) ends the command quietly with status 1,
/// never a panic.
#[test]
fn a_closed_pipe_ends_quietly() {
    let d = dir("pipe");
    // 256 KiB of code disassembles to far more than a pipe buffers.
    let image = write(&d, "image.bin", vec![0x40u8; 256 * 1024]);
    let spin = program(&d, "spin.s", "        br _start\n");
    let dump = ["run", &spin, "--max-cycles", "10", "--dump-ls", "0:0x40000"];
    for args in [&["dis", "--raw", &image][..], &dump[..]] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_spu"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdout = child.stdout.take().unwrap();
        let mut first = [0u8; 16];
        stdout.read_exact(&mut first).unwrap();
        drop(stdout);
        let mut stderr = String::new();
        child
            .stderr
            .take()
            .unwrap()
            .read_to_string(&mut stderr)
            .unwrap();
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(1), "spu {args:?}: {stderr}");
        assert_eq!(stderr, "", "spu {args:?}");
    }
}

/// A render that validates cleanly exits 0; one whose statistics cannot be written exits 1
/// after writing the image whole.
#[test]
fn render_statuses() {
    let d = dir("render");
    let png = d.join("room.png");
    let png = png.to_str().unwrap();
    let small = ["render", "--width", "16", "--height", "16", "-o", png];
    let out = spu(&[&small[..], &["--validate"]].concat());
    assert_eq!(out.status, 0, "{}", out.stderr);
    assert!(
        out.stdout
            .contains("validation: 0 of 256 pixels differ from the host reference"),
        "{}",
        out.stdout
    );
    if Path::new("/dev/full").exists() {
        std::fs::remove_file(png).unwrap();
        let out = spu(&[&small[..], &["--stats", "/dev/full"]].concat());
        assert_eq!(out.status, 1, "{}", out.stderr);
        assert!(
            out.stderr.contains("/dev/full: No space left"),
            "{}",
            out.stderr
        );
        assert!(image_is_complete(png));
    }
    assert_eq!(files_in(&d), ["room.png"], "no temporary file is left");
}

fn image_is_complete(path: &str) -> bool {
    let bytes = std::fs::read(path).unwrap();
    bytes.starts_with(b"\x89PNG") && bytes.ends_with(b"IEND\xae\x42\x60\x82")
}

/// Found by the `assemble` fuzz target: a macro that defines itself again while expanding
/// ran for ever (before the nesting limit and expansion budget); now bad input, with both
/// reasons named.
#[test]
fn recursive_macro_from_the_fuzzer_is_bad_input() {
    let src = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fuzz_regressions/asm-recursive-macro.s"
    );
    let d = dir("fuzz-asm");
    let out = spu(&["as", src, "-o", d.join("x.elf").to_str().unwrap()]);
    assert_eq!(out.status, 2, "{}", out.stderr);
    assert!(
        // gas's own words since macros nest as deep as gas's max_macro_nest (100).
        out.stderr.contains("macros nested too deeply"),
        "{}",
        out.stderr
    );
    assert!(
        out.stderr.ends_with("error(s); nothing written\n"),
        "{}",
        out.stderr
    );
    assert_eq!(files_in(&d), Vec::<String>::new());
}

/// No output overwrites an input or another output of the same command, whatever the
/// spelling, symbolic link or hard link: refused before any work, status 2, naming both,
/// and the files are left as they were.
#[test]
fn no_output_overwrites_a_file_the_input_includes() {
    // `.include`, `.incbin` (found beside the source or through -I) and a scene's `mtllib`
    // are inputs as the named ones are: refused before anything is written, naming both.
    let d = dir("included");
    let at = |name: &str| d.join(name).to_str().unwrap().to_string();
    std::fs::create_dir_all(d.join("lib")).unwrap();
    let inc = write(&d, "inc.s", "        il $3, 1\n");
    let blob = write(&d, "blob.bin", "abcd");
    let deep = write(&d.join("lib"), "deep.s", "        il $4, 2\n");
    let src = program(
        &d,
        "x.s",
        "        .include \"inc.s\"\n        .include \"deep.s\"\n        .incbin \"blob.bin\"\n        stop 0x2000\n",
    );
    let other = program(&d, "y.s", "        stop 0x2000\n");
    let lib = at("lib");
    let words = |w: &[&str]| -> Vec<String> { w.iter().map(|s| s.to_string()).collect() };
    let cases: Vec<(Vec<String>, String)> = vec![
        (
            words(&["as", &src, "-I", &lib, "-o", &inc]),
            format!("-o {inc}: would overwrite {src}'s included file {inc}"),
        ),
        (
            words(&["as", &src, "-I", &lib, "-c", "-o", &blob]),
            format!("-o {blob}: would overwrite {src}'s included file {blob}"),
        ),
        (
            words(&[
                "as",
                &src,
                "-I",
                &lib,
                "-o",
                &at("x.elf"),
                "--listing",
                &deep,
            ]),
            format!(
                "--listing {deep}: would overwrite {src}'s included file {}/deep.s",
                lib
            ),
        ),
        (
            words(&["as", &other, &src, "-I", &lib, "-o", &inc]),
            format!("-o {inc}: would overwrite {src}'s included file {inc}"),
        ),
    ];
    for (args, message) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = spu(&args);
        assert_eq!(out.status, 2, "spu {args:?}: {}", out.stderr);
        assert_eq!(out.stderr, format!("spu: {message}\n"), "spu {args:?}");
    }
    assert_eq!(std::fs::read_to_string(&inc).unwrap(), "        il $3, 1\n");
    assert_eq!(std::fs::read_to_string(&blob).unwrap(), "abcd");
    assert_eq!(
        std::fs::read_to_string(&deep).unwrap(),
        "        il $4, 2\n"
    );
    assert!(!d.join("x.elf").exists(), "nothing written");
    // The same source to a fresh output assembles.
    let out = spu(&["as", &src, "-I", &lib, "-o", &at("x.elf")]);
    assert_eq!((out.status, out.stderr.as_str()), (0, ""));

    let mtl = write(&d, "m.mtl", "newmtl green\nKd 0 1 0\n");
    let scene = write(
        &d,
        "s.obj",
        "mtllib m.mtl # the colours\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl green\nf 1 2 3\n",
    );
    let out = spu(&["render", "--scene", &scene, "--stats", &mtl]);
    assert_eq!(out.status, 2, "{}", out.stderr);
    assert_eq!(
        out.stderr,
        format!("spu: --stats {mtl}: would overwrite the scene's material library {mtl}\n")
    );
    assert_eq!(out.stdout, "");
    assert_eq!(
        std::fs::read_to_string(&mtl).unwrap(),
        "newmtl green\nKd 0 1 0\n"
    );
}

#[test]
fn no_output_overwrites_an_input_or_another_output() {
    let d = dir("clobber");
    let at = |name: &str| d.join(name).to_str().unwrap().to_string();
    let src = program(&d, "c.s", "        stop 0x2000\n");
    let original = std::fs::read(&src).unwrap();
    assert_eq!(
        spu(&["as", &src, "-c", "-o", &at("a.o")]).status,
        0,
        "setup"
    );
    assert_eq!(spu(&["as", &src, "-c", "-o", &at("b.o")]).status, 0);
    let (a_o, b_o) = (at("a.o"), at("b.o"));
    let objects = std::fs::read(&a_o).unwrap();
    let scene = write(&d, "s.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let dotted = format!("{}/./c.s", d.display());
    let words = |w: &[&str]| -> Vec<String> { w.iter().map(|s| s.to_string()).collect() };
    let cases: Vec<(Vec<String>, String)> = vec![
        (
            words(&["as", &src, "-o", &src]),
            format!("-o {src}: would overwrite the input {src}"),
        ),
        (
            words(&["as", &src, "-o", &dotted]),
            format!("-o {dotted}: would overwrite the input {src}"),
        ),
        (
            words(&["as", &src, "--listing", &src]),
            format!("--listing {src}: would overwrite the input {src}"),
        ),
        (
            words(&["as", &src, "-o", &at("x.elf"), "--listing", &at("x.elf")]),
            format!(
                "-o {0} and --listing {0} are the same file: each output needs its own",
                at("x.elf")
            ),
        ),
        (
            words(&["ld", &a_o, &b_o, "-o", &a_o]),
            format!("-o {a_o}: would overwrite the input {a_o}"),
        ),
        (
            words(&["timing", &src, "-o", &src]),
            format!("-o {src}: would overwrite the input {src}"),
        ),
        (
            words(&["sched", &src, "-o", &src]),
            format!("-o {src}: would overwrite the input {src}"),
        ),
        (
            words(&["render", "-o", &at("s.png"), "--stats", &at("s.png")]),
            format!(
                "-o {0} and --stats {0} are the same file: each output needs its own",
                at("s.png")
            ),
        ),
        (
            words(&["render", "--heatmap", &at("X.png"), "-o", &at("X.png")]),
            format!(
                "-o {0} and --heatmap {0} are the same file: each output needs its own",
                at("X.png")
            ),
        ),
        (
            words(&["render", "-o", &at("h.png"), "--heatmap", &at("h.png")]),
            format!(
                "-o {0} and --heatmap {0} are the same file: each output needs its own",
                at("h.png")
            ),
        ),
        (
            words(&[
                "render",
                "-o",
                &at("w.png"),
                "--heatmap",
                &at("r-wait.png"),
                "--stats",
                &at("r-wait-wait.png"),
            ]),
            format!(
                "--heatmap {0} and --stats {0} are the same file: each output needs its own",
                at("r-wait-wait.png")
            ),
        ),
        (
            words(&["render", "--trace", &at("x.json"), "--stats", &at("x.json")]),
            format!(
                "--stats {0} and --trace {0} are the same file: each output needs its own",
                at("x.json")
            ),
        ),
        (
            words(&["render", "--scene", &scene, "--stats", &scene]),
            format!("--stats {scene}: would overwrite the scene {scene}"),
        ),
    ];
    for (args, message) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = spu(&args);
        assert_eq!(out.status, 2, "spu {args:?}: {}", out.stderr);
        assert_eq!(out.stderr, format!("spu: {message}\n"), "spu {args:?}");
        assert_eq!(out.stdout, "", "spu {args:?} did work before refusing");
    }
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink("c.s", d.join("soft.s")).unwrap();
        std::fs::hard_link(&src, d.join("hard.s")).unwrap();
        for link in [at("soft.s"), at("hard.s")] {
            let out = spu(&["as", &src, "-o", &link]);
            assert_eq!(out.status, 2, "{}", out.stderr);
            assert_eq!(
                out.stderr,
                format!("spu: -o {link}: would overwrite the input {src}\n")
            );
        }
        // An output through a link that is no input is written through it, whole.
        std::os::unix::fs::symlink("linked.elf", d.join("link.elf")).unwrap();
        assert_eq!(spu(&["as", &src, "-o", &at("link.elf")]).status, 0);
        assert!(std::fs::symlink_metadata(d.join("link.elf"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert!(std::fs::read(at("linked.elf"))
            .unwrap()
            .starts_with(b"\x7fELF"));
        std::fs::remove_file(at("linked.elf")).unwrap();
        std::fs::remove_file(at("link.elf")).unwrap();
        std::fs::remove_file(at("soft.s")).unwrap();
        std::fs::remove_file(at("hard.s")).unwrap();
    }
    assert_eq!(
        std::fs::read(&src).unwrap(),
        original,
        "the source is intact"
    );
    assert_eq!(
        std::fs::read(&a_o).unwrap(),
        objects,
        "the object is intact"
    );
    assert_eq!(
        files_in(&d),
        ["a.o", "b.o", "c.s", "s.obj"],
        "nothing else written"
    );
}
