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

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-cli-link-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn write(name: &str, text: &str) -> String {
    let p = scratch(name);
    std::fs::write(&p, text).unwrap();
    p.to_str().unwrap().to_string()
}

/// Runs `spu`; its exit status and standard error.
fn spu_status(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const MAIN_S: &str = "
        .text
        .global _start
_start: il      $3, 10
        brsl    $lr, add3
        ila     $5, counter
        lqa     $6, table
        wrch    $SPU_WrOutMbox, $4
        stop    0x2000
        .data
        .align  4
table:  .long   add3, 7, 0, 0
        .comm   counter, 16, 16
";

const ADD3_S: &str = "
        .text
        .global add3
        .type   add3, @function
add3:   ai      $4, $3, 3
        bi      $lr
        .size   add3, .-add3
";

/// Objects from `spu as -c` linked by `spu ld` give the same executable as assembling
/// both sources at once; the relocations resolve across the objects.
#[test]
fn objects_link_like_assembling_together() {
    let (a, b) = (write("main.s", MAIN_S), write("add3.s", ADD3_S));
    let (ao, bo) = (scratch("main.o"), scratch("add3.o"));
    let (ao, bo) = (ao.to_str().unwrap(), bo.to_str().unwrap());
    spu(&["as", "-c", &a, "-o", ao]);
    spu(&["as", "-c", &b, "-o", bo]);
    // One output name for both: the executable's `.note.spu_name` records it.
    let out = scratch("linked.elf");
    spu(&["ld", ao, bo, "-o", out.to_str().unwrap()]);
    let linked = std::fs::read(&out).unwrap();
    spu(&["as", &a, &b, "-o", out.to_str().unwrap()]);
    assert_eq!(linked, std::fs::read(&out).unwrap());
    let text = spu(&["dis", out.to_str().unwrap()]);
    // brsl at 4 to add3 at 0x18; ila of the common (0x90, after .data at 0x80: GNU ld's
    // data segment starts at ALIGN(0x80)).
    assert!(text.contains("33 00 02 80 \tbrsl\t$0,18 <add3>"), "{text}");
    assert!(
        text.contains("42 00 48 05 \tila\t$5,90 <counter>"),
        "{text}"
    );
    assert!(text.contains("30 80 10 06 \tlqa\t$6,80 <table>"), "{text}");
    let run = spu(&["run", out.to_str().unwrap()]);
    assert!(run.contains("outbound mailbox: 0xd"), "{run}");
}

#[test]
fn link_errors_name_object_and_symbol() {
    let a = write("main2.s", MAIN_S);
    let ao = scratch("main2.o");
    let ao = ao.to_str().unwrap();
    spu(&["as", "-c", &a, "-o", ao]);
    let out = scratch("x.elf");
    let out = out.to_str().unwrap();
    let (code, err) = spu_status(&["ld", ao, "-o", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("main2.o: undefined reference to `add3' (.text+0x4)"),
        "{err}"
    );
    let b = write("add3b.s", ADD3_S);
    let bo = scratch("add3b.o");
    let bo = bo.to_str().unwrap();
    spu(&["as", "-c", &b, "-o", bo]);
    let (code, err) = spu_status(&["ld", ao, bo, bo, "-o", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("multiple definition of `add3'"), "{err}");
    let far = write("far.s", ".text\n.global _start\n_start: ai $3, $3, away\n");
    let faro = scratch("far.o");
    spu(&["as", "-c", &far, "-o", faro.to_str().unwrap()]);
    let away = write(
        "away.s",
        ".data\n.space 0x800\n.global away\naway: .long 0\n",
    );
    let awayo = scratch("away.o");
    spu(&["as", "-c", &away, "-o", awayo.to_str().unwrap()]);
    let (code, err) = spu_status(&[
        "ld",
        faro.to_str().unwrap(),
        awayo.to_str().unwrap(),
        "-o",
        out,
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("far.o: .text+0x0: relocation truncated to fit: R_SPU_ADDR10I")
            && err.contains("against `away'"),
        "{err}"
    );
    let big = write("big.s", ".text\n.space 0x30000\n");
    let bigo = scratch("big.o");
    spu(&["as", "-c", &big, "-o", bigo.to_str().unwrap()]);
    let bigo = bigo.to_str().unwrap();
    let (code, err) = spu_status(&["ld", bigo, bigo, "-o", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("does not fit the 256 KiB local store"),
        "{err}"
    );
    // An object for another machine: a small host executable (a host ELF, or not ELF at
    // all); the test binary itself is the fallback, though a debug build of it can exceed
    // the input size limit.
    let host = ["/bin/sh", "/bin/ls"]
        .iter()
        .map(std::path::PathBuf::from)
        .find(|p| p.is_file())
        .unwrap_or_else(|| std::env::current_exe().unwrap());
    let (code, err) = spu_status(&["ld", host.to_str().unwrap(), "-o", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("not SPU") || err.contains("ELF32 MSB"),
        "{err}"
    );
}

/// A raw image has no symbols: objdump writes branch targets as `0x38`.
#[test]
fn raw_image_targets_print_with_0x() {
    let src = write("raw.s", "il $3,1\n1: ai $3,$3,-1\nbrnz $3,1b\n");
    let bin = scratch("raw.bin");
    spu(&["as", &src, "--format", "bin", "-o", bin.to_str().unwrap()]);
    let text = spu(&["dis", bin.to_str().unwrap()]);
    assert!(text.contains("brnz\t$3,0x4"), "{text}");
}

/// Where a local label, an absolute symbol and a global share an address, objdump names
/// it after the global.
#[test]
fn dis_prefers_the_global_symbol() {
    let src = write(
        "names.s",
        "\t.text\n\t.global main\n\t.set ABS, 4\n.Lx:\nloc:\nmain:\til $3,1\n\tbr main\n",
    );
    let elf = scratch("names.elf");
    spu(&["as", &src, "-o", elf.to_str().unwrap()]);
    let text = spu(&["dis", elf.to_str().unwrap()]);
    assert!(text.contains("00000000 <main>:"), "{text}");
    assert!(text.contains("br\t0 <main>"), "{text}");
}
