//! `spu ar` and `spu ld` with libraries, as GNU ar and GNU ld behave: an archive of two
//! objects links only the member the program needs, an archive is searched where it
//! stands on the command line, and the executable's headers and symbols are GNU ld's
//! (R+X and R+W segments, symbol types, sizes and bindings, `_end`, the entry warning).

use std::path::{Path, PathBuf};

fn dir(test: &str) -> PathBuf {
    crate::support::fresh_dir("ld", test)
}

use crate::support::spu_in as spu;

fn ok(args: &[&str], cwd: &Path) -> String {
    let (out, err, code) = spu(args, cwd);
    assert_eq!(code, 0, "spu {args:?}: {err}");
    out
}

/// Assembles `source` into `dir/name.o`.
fn object(d: &Path, name: &str, source: &str) {
    std::fs::write(d.join(format!("{name}.s")), source).unwrap();
    ok(
        &["as", "-c", &format!("{name}.s"), "-o", &format!("{name}.o")],
        d,
    );
}

const MAIN: &str = "\t.text\n\t.global _start\n\t.type _start, @function\n_start:\tbrsl\t$0, square\n\tstop\t0x2000\n\t.size _start, .-_start\n";
const SQUARE: &str = "\t.text\n\t.global square\n\t.type square, @function\nsquare:\tmpy\t$3, $3, $3\n\tbi\t$0\n\t.size square, .-square\n\t.data\n\t.global table\n\t.type table, @object\ntable:\t.long 1, 2, 3, 4\n\t.size table, 16\n";
const CUBE: &str = "\t.text\n\t.global cube\n\t.type cube, @function\ncube:\tmpy\t$4, $3, $3\n\tmpy\t$3, $4, $3\n\tbi\t$0\n\t.size cube, .-cube\n\t.weak\tsoft\nsoft:\tnop\n";

/// An ELF32 big-endian file's field.
fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_be_bytes(b[o..o + 4].try_into().unwrap())
}
fn u16_at(b: &[u8], o: usize) -> u16 {
    u16::from_be_bytes(b[o..o + 2].try_into().unwrap())
}

/// The program headers (type, vaddr, filesz, memsz, flags) and the symbols (name, value,
/// size, info, shndx) of an executable.
#[allow(clippy::type_complexity)]
fn headers(b: &[u8]) -> (Vec<[u32; 5]>, Vec<(String, u32, u32, u8, u16)>) {
    let (phoff, phnum) = (u32_at(b, 28) as usize, u16_at(b, 44) as usize);
    let phdrs = (0..phnum)
        .map(|i| {
            let p = phoff + 32 * i;
            [
                u32_at(b, p),
                u32_at(b, p + 8),
                u32_at(b, p + 16),
                u32_at(b, p + 20),
                u32_at(b, p + 24),
            ]
        })
        .collect();
    let (shoff, shnum) = (u32_at(b, 32) as usize, u16_at(b, 48) as usize);
    let sh = |i: usize, f: usize| u32_at(b, shoff + 40 * i + 4 * f) as usize;
    let mut syms = Vec::new();
    for i in 0..shnum {
        if sh(i, 1) != 2 {
            continue;
        }
        let strtab = sh(sh(i, 6), 4);
        for s in b[sh(i, 4)..sh(i, 4) + sh(i, 5)].chunks(16).skip(1) {
            let n = strtab + u32_at(s, 0) as usize;
            let end = b[n..].iter().position(|&c| c == 0).unwrap();
            let name = String::from_utf8(b[n..n + end].to_vec()).unwrap();
            syms.push((name, u32_at(s, 4), u32_at(s, 8), s[12], u16_at(s, 14)));
        }
    }
    (phdrs, syms)
}

#[test]
fn only_the_needed_member_is_linked() {
    let d = dir("needed");
    object(&d, "main", MAIN);
    object(&d, "square", SQUARE);
    object(&d, "cube", CUBE);
    std::fs::create_dir(d.join("lib")).unwrap();
    ok(&["ar", "rcs", "lib/libmath.a", "cube.o", "square.o"], &d);
    assert_eq!(ok(&["ar", "t", "lib/libmath.a"], &d), "cube.o\nsquare.o\n");
    // The index GNU ar writes: the defined globals and weaks of each member, in order.
    let bytes = std::fs::read(d.join("lib/libmath.a")).unwrap();
    let archive = spu_asm::archive::Archive::read("libmath.a", &bytes).unwrap();
    let index: Vec<(&str, usize)> = archive
        .index
        .iter()
        .map(|(s, m)| (s.as_str(), *m))
        .collect();
    assert_eq!(
        index,
        [("cube", 0), ("soft", 0), ("square", 1), ("table", 1)]
    );

    ok(
        &["ld", "main.o", "-L", "lib", "-lmath", "-o", "prog.elf"],
        &d,
    );
    let elf = std::fs::read(d.join("prog.elf")).unwrap();
    let (phdrs, syms) = headers(&elf);
    let names: Vec<&str> = syms.iter().map(|s| s.0.as_str()).collect();
    assert!(
        names.contains(&"square") && names.contains(&"table"),
        "{names:?}"
    );
    assert!(
        !names.contains(&"cube") && !names.contains(&"soft"),
        "{names:?}"
    );
    // main's text (8 bytes), square's at 8 (8), square's data at 0x80 (GNU ld's data
    // segment starts at ALIGN(0x80)): a code segment R+X and a data segment R+W, and the
    // PT_NOTE of `.note.spu_name` (naming "prog.elf", 32 bytes), as GNU ld writes them.
    assert_eq!(
        phdrs,
        [
            [1, 0, 0x10, 0x10, 5],
            [1, 0x80, 16, 16, 6],
            [4, 0, 32, 0, 4]
        ]
    );
    let sym = |n: &str| syms.iter().find(|s| s.0 == n).unwrap().clone();
    // FUNC (2) and OBJECT (1), GLOBAL (1 << 4), sizes kept; sections 1 .text, 2 .data.
    assert_eq!(sym("square"), ("square".into(), 8, 8, 0x12, 1));
    assert_eq!(sym("table"), ("table".into(), 0x80, 16, 0x11, 2));
    assert_eq!(sym("_start"), ("_start".into(), 0, 8, 0x12, 1));
    // The script's symbols: _edata and __bss_start at the end of .data, _end past it.
    assert_eq!(
        (sym("_edata").1, sym("__bss_start").1, sym("_end").1),
        (0x90, 0x90, 0x90)
    );
    assert!(
        !names.contains(&"end"),
        "end is only PROVIDEd when referenced"
    );
    let run = ok(&["run", "prog.elf"], &d);
    assert!(run.contains("stop 0x2000"), "{run}");

    // Both members when both are needed; the weak definition stays weak (STB_WEAK << 4).
    let both = "\t.text\n\t.global _start\n_start:\tbrsl\t$0, square\n\tbrsl\t$0, cube\n\tbrsl\t$0, soft\n\tstop\t0x2000\n";
    object(&d, "both", both);
    ok(&["ld", "both.o", "lib/libmath.a", "-o", "both.elf"], &d);
    let (_, syms) = headers(&std::fs::read(d.join("both.elf")).unwrap());
    let soft = syms.iter().find(|s| s.0 == "soft").unwrap();
    assert_eq!(soft.3, 0x20, "{soft:?}");
    assert!(syms.iter().any(|s| s.0 == "cube"));
}

#[test]
fn an_archive_is_searched_where_it_stands() {
    let d = dir("order");
    object(&d, "main", MAIN);
    object(&d, "square", SQUARE);
    ok(&["ar", "rcs", "libm.a", "square.o"], &d);
    // Before the object that needs it, the library is passed over: GNU ld's error.
    let (_, err, code) = spu(&["ld", "-L", ".", "-lm", "main.o", "-o", "x.elf"], &d);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("main.o: undefined reference to `square'"),
        "{err}"
    );
    ok(&["ld", "main.o", "-lm", "-L", ".", "-o", "x.elf"], &d);
    let (_, err, code) = spu(&["ld", "main.o", "-lnothere", "-o", "x.elf"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("cannot find -lnothere"), "{err}");
}

#[test]
fn bad_archives_are_reported() {
    let d = dir("bad");
    object(&d, "main", MAIN);
    object(&d, "square", SQUARE);
    ok(&["ar", "rcs", "libm.a", "square.o"], &d);
    let good = std::fs::read(d.join("libm.a")).unwrap();
    std::fs::write(d.join("cut.a"), &good[..good.len() - 10]).unwrap();
    let (_, err, code) = spu(&["ld", "main.o", "cut.a", "-o", "x.elf"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("cut.a: member at offset"), "{err}");
    assert!(err.contains("past the end of the archive"), "{err}");
    let mut bad = good.clone();
    bad[8 + 60..8 + 64].copy_from_slice(&0x4000_0000u32.to_be_bytes());
    std::fs::write(d.join("index.a"), &bad).unwrap();
    let (_, err, code) = spu(&["ld", "main.o", "index.a", "-o", "x.elf"], &d);
    assert_eq!(code, 2);
    assert!(err.contains("index.a: bad symbol index"), "{err}");
    let (_, err, code) = spu(&["ar", "t", "index.a"], &d);
    assert_eq!(code, 2, "{err}");
    let (_, err, code) = spu(&["ar", "x", "libm.a"], &d);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn a_missing_entry_symbol_is_a_warning_as_in_gnu_ld() {
    let d = dir("entry");
    object(&d, "square", SQUARE);
    let (_, err, code) = spu(&["ld", "square.o", "-o", "x.elf"], &d);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        err,
        "spu ld: warning: cannot find entry symbol _start; defaulting to 00000000\n"
    );
    let (_, err, code) = spu(&["ld", "square.o", "-e", "0x4", "-o", "x.elf"], &d);
    assert_eq!((code, err.as_str()), (0, ""));
    assert_eq!(u32_at(&std::fs::read(d.join("x.elf")).unwrap(), 24), 4);
}
