//! `spu ld -T` with overlays, end to end: the project's overlay program
//! (`tests/overlay/`: two overlays in one region, a small overlay manager that DMAs them
//! in from the image in main memory) assembled, linked with its script and run, with
//! exact output and exit status under every engine; and the script errors `spu ld`
//! gives, before it writes anything.

use crate::support::{fresh_dir, spu_in};
use std::path::Path;

fn overlay_dir() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/overlay")
        .display()
        .to_string()
}

/// Assembles and links the overlay program in `dir`: `prog.elf`.
fn build(dir: &Path) {
    let src = overlay_dir();
    for name in ["program", "manager"] {
        let (_, err, code) = spu_in(
            &[
                "as",
                "-c",
                &format!("{src}/{name}.s"),
                "-o",
                &format!("{name}.o"),
            ],
            dir,
        );
        assert_eq!(code, 0, "{err}");
    }
    let script = format!("{src}/overlay.ld");
    let (out, err, code) = spu_in(
        &[
            "ld",
            "-T",
            &script,
            "program.o",
            "manager.o",
            "-o",
            "prog.elf",
        ],
        dir,
    );
    assert_eq!((out.as_str(), err.as_str(), code), ("", "", 0));
}

#[test]
fn the_overlay_program_runs_its_overlays_from_main_memory() {
    let dir = fresh_dir("ld-overlays", "run");
    build(&dir);
    for engine in ["jit", "interp"] {
        let (out, err, code) = spu_in(&["run", "-q", "--engine", engine, "prog.elf"], &dir);
        assert_eq!(
            out,
            "one: loaded from the image in main memory\n\
             two: over one, in the same region\n\
             one: loaded from the image in main memory\n",
            "{engine}: {err}"
        );
        assert_eq!(code, 4, "{engine}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_overlay_executable_has_overlay_segments_and_tables() {
    let dir = fresh_dir("ld-overlays", "layout");
    build(&dir);
    let elf = std::fs::read(dir.join("prog.elf")).unwrap();
    assert_eq!(
        spu_asm::elf_check::layout_errors(&elf),
        Vec::<String>::new()
    );
    // The program headers: the two overlays first, PF_OVERLAY (0x08000000) set, at one
    // address, loaded one after the other.
    let u32_at = |o: usize| u32::from_be_bytes(elf[o..o + 4].try_into().unwrap());
    let (phoff, phnum) = (u32_at(28) as usize, u16::from_be_bytes([elf[44], elf[45]]));
    let phdr = |i: usize| {
        (0..8)
            .map(|k| u32_at(phoff + 32 * i + 4 * k))
            .collect::<Vec<_>>()
    };
    assert_eq!(phnum, 6);
    let (a, b) = (phdr(0), phdr(1));
    assert_eq!((a[0], a[2], a[3], a[6]), (1, 0x1b0, 0x1b0, 0x0800_0005));
    assert_eq!(
        (b[0], b[2], b[3], b[6]),
        (1, 0x1b0, 0x1b0 + a[4], 0x0800_0005)
    );
    // `_ovly_table` (after the non-overlay area's entry, at the start of .data, 0x200
    // here) gives each overlay's address, size, file offset (its segment's) and buffer.
    let data = (0..u16::from_be_bytes([elf[48], elf[49]]) as usize)
        .map(|i| u32_at(32) as usize + 40 * i)
        .find(|&h| u32_at(h + 12) == 0x200)
        .map(|h| u32_at(h + 16) as usize)
        .expect("a section at 0x200");
    let entry = |n: usize| {
        (0..4)
            .map(|k| u32_at(data + 16 * n + 4 * k))
            .collect::<Vec<_>>()
    };
    assert_eq!(entry(0), [0, 1, 0, 0]);
    assert_eq!(entry(1), [0x1b0, a[4], a[1], 1]);
    assert_eq!(entry(2), [0x1b0, b[4], b[1], 1]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn script_errors_name_file_line_and_column_and_write_nothing() {
    let dir = fresh_dir("ld-overlays", "errors");
    let src = overlay_dir();
    let (_, err, code) = spu_in(
        &["as", "-c", &format!("{src}/program.s"), "-o", "program.o"],
        &dir,
    );
    assert_eq!(code, 0, "{err}");
    std::fs::write(
        dir.join("bad.ld"),
        "SECTIONS {\n  .text : { *(.text) }\n  MEMORY\n}\n",
    )
    .unwrap();
    let (out, err, code) = spu_in(&["ld", "-T", "bad.ld", "program.o", "-o", "p.elf"], &dir);
    assert_eq!(
        (out.as_str(), err.as_str(), code),
        (
            "",
            "spu ld: bad.ld:4:1: expected an expression, found `}'\n",
            2
        )
    );
    std::fs::write(
        dir.join("insert.ld"),
        "SECTIONS { .x : { *(.x) } }\nINSERT AFTER .text;\n",
    )
    .unwrap();
    let (_, err, code) = spu_in(&["ld", "-T", "insert.ld", "program.o", "-o", "p.elf"], &dir);
    assert_eq!(
        (err.as_str(), code),
        (
            "spu ld: insert.ld: INSERT into the default script is not supported: give a \
             script with the whole SECTIONS too\n",
            2
        )
    );
    // Overlays without a manager: GNU ld would add its built-in one; spu ld says so.
    std::fs::write(
        dir.join("ovl.ld"),
        "SECTIONS { .text : { *(.text) } OVERLAY : { .ov_one { *(.ov_one) } .ov_two { *(.ov_two) } } }\n",
    )
    .unwrap();
    let (_, err, code) = spu_in(&["ld", "-T", "ovl.ld", "program.o", "-o", "p.elf"], &dir);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no `__ovly_load' is defined"), "{err}");
    assert!(!dir.join("p.elf").exists());
    let _ = std::fs::remove_dir_all(&dir);
}
