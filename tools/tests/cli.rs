//! The `spu` commands on a small program, snapshotted: any change in the profile's cycles,
//! the disassembly or the register dump shows up as a snapshot diff.

use std::path::PathBuf;
use std::process::Command;

const PROGRAM: &str = "
        .text
        .global _start
_start: il      $3, 10
        il      $4, 0
        ilhu    $5, 0x3f80              # 1.0f
loop:   hbrr    .Lback, loop
        ai      $4, $4, 3
        fa      $6, $5, $5
        fma     $7, $6, $6, $5
        ai      $3, $3, -1
        nop
        nop
        nop
        nop
.Lback: brnz    $3, loop
        wrch    $SPU_WrOutMbox, $4
        stop    0x2000
";

fn program_file(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, PROGRAM).unwrap();
    path
}

fn spu(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "spu {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn prof_listing() {
    let src = program_file("prof.s");
    let text = spu(&["prof", src.to_str().unwrap()]);
    let text = text.replace(src.to_str().unwrap(), "prof.s");
    insta::assert_snapshot!(text);
}

#[test]
fn dis_of_an_assembled_elf() {
    let src = program_file("dis.s");
    let elf = src.with_extension("elf");
    spu(&["as", src.to_str().unwrap(), "-o", elf.to_str().unwrap()]);
    let text = spu(&["dis", elf.to_str().unwrap()]).replace(elf.to_str().unwrap(), "dis.elf");
    insta::assert_snapshot!(text);
}

#[test]
fn run_with_timing_reports_cycles() {
    let src = program_file("run.s");
    let text = spu(&["run", src.to_str().unwrap(), "--timing"]);
    insta::assert_snapshot!(text);
}

#[test]
fn assembler_errors_name_the_line_and_column() {
    let dir = std::env::temp_dir().join(format!("spu-cli-err-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.s");
    std::fs::write(&path, "  il $3, 70000\n  frob $1\n  lqd $3, 5000($1)\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args([
            "as",
            path.to_str().unwrap(),
            "-o",
            dir.join("x").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr).replace(path.to_str().unwrap(), "bad.s");
    assert!(err.contains("bad.s:1:"), "{err}");
    assert!(err.contains("bad.s:2:"), "{err}");
    assert!(err.contains("out of range"), "{err}");
    assert!(
        !dir.join("x").exists(),
        "nothing is written when there are errors"
    );
}

/// `spu render --profile` writes the kernel's annotated profile, whose per-label cycles add
/// up to the frame's cycles, and `--stats` the Table 2 figures with per-section CPI.
#[test]
fn render_writes_profile_and_stats() {
    let dir = std::env::temp_dir().join(format!("spu-cli-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (png, prof, stats) = (dir.join("r.png"), dir.join("r.prof"), dir.join("r.json"));
    let out = spu(&[
        "render",
        "--scene",
        "room",
        "--width",
        "64",
        "--height",
        "64",
        "-o",
        png.to_str().unwrap(),
        "--profile",
        prof.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    let cycles: u64 = out
        .split(" cycles per frame")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .expect("cycles in the summary line");
    let prof = std::fs::read_to_string(&prof).unwrap();
    assert!(
        prof.contains("\ntrav:\n") && prof.contains("\nray_loop:\n"),
        "{prof}"
    );
    let total = prof
        .lines()
        .find(|l| l.trim_start().starts_with("Total Cycle count"))
        .and_then(|l| l.split_whitespace().last())
        .and_then(|n| n.parse::<u64>().ok())
        .expect("total cycles");
    assert_eq!(total, cycles);
    let text = std::fs::read_to_string(&stats).unwrap();
    let stats = spu_loader::stats::FrameStats::from_json(&text).expect("stats parse");
    assert_eq!(stats.frame_cycles, cycles);
    assert_eq!((stats.width, stats.height, stats.rays), (64, 64, 4096));
    assert_eq!(stats.spus.len(), 1);
    assert!(stats.table2.traversal_steps_per_packet > 0.0, "{text}");
    assert!(stats.table2.pair_steps_per_packet > 0.0, "{text}");
    assert!(stats.validation.is_none());
    let traversal = stats.traversal.expect("traversal section");
    assert!(traversal.cpi_without_nops >= traversal.cpi, "{text}");
    let totals = stats.totals.expect("timing totals");
    assert_eq!(totals.cycles, cycles);
    // the file is the serialisation of what it holds
    assert_eq!(
        spu_loader::stats::FrameStats::from_json(&text)
            .unwrap()
            .to_json(),
        text
    );
}
