//! `spu ld`'s executables against GNU ld's (spu-elf-ld) on the same GNU-as objects and
//! archive, at `readelf`'s level: the loadable segments (address, size, flags) and the
//! global and weak symbols (value, size, type, binding). Where GNU binutils for spu-elf was
//! not found when the test was built, the test is ignored, saying why (`build.rs` finds GNU
//! as; ld and readelf are beside it).

use spu_asm::archive::{Archive, Member};
use spu_asm::link::{link, resolve_inputs, Input, LinkOptions};
use spu_asm::object::Object;
use std::path::{Path, PathBuf};
use std::process::Command;

#[cfg(has_binutils)]
const GNU_AS: &str = env!("SPU_ELF_AS");
#[cfg(not(has_binutils))]
const GNU_AS: &str = "";

/// A binutils program beside GNU as (`spu-elf-as` -> `spu-elf-ld`).
fn sibling(tool: &str) -> PathBuf {
    let gas = Path::new(GNU_AS);
    let name = gas.file_name().unwrap().to_string_lossy();
    let prefix = name.strip_suffix("as").unwrap_or("spu-elf-");
    gas.with_file_name(format!("{prefix}{tool}"))
}

fn run(program: &Path, args: &[&str], cwd: &Path) -> String {
    let out = Command::new(program)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap_or_else(|e| panic!("{}: {e}", program.display()));
    assert!(
        out.status.success(),
        "{} {args:?}: {}",
        program.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// readelf -lW's LOAD lines as (vaddr, memsz, flags) and -sW's global and weak symbols as
/// (name, value, size, type, binding), sorted.
fn summary(readelf: &Path, elf: &Path) -> (Vec<String>, Vec<String>) {
    let dir = elf.parent().unwrap();
    let path = elf.to_str().unwrap();
    let loads = run(readelf, &["-lW", path], dir)
        .lines()
        .filter(|l| l.trim_start().starts_with("LOAD"))
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            // LOAD offset vaddr paddr filesz memsz flags... align
            let flags = f[6..f.len() - 1].join("");
            format!("{} {} {flags}", f[2], f[5])
        })
        .collect();
    let mut symbols: Vec<String> = run(readelf, &["-sW", path], dir)
        .lines()
        .filter_map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            (f.len() >= 8 && (f[4] == "GLOBAL" || f[4] == "WEAK"))
                .then(|| format!("{} {} {} {} {}", f[7], f[1], f[2], f[3], f[4]))
        })
        .collect();
    symbols.sort();
    (loads, symbols)
}

const MAIN: &str = "\t.text\n\t.global _start\n\t.type _start, @function\n_start:\tbrsl\t$0, square\n\tila\t$4, msg\n\tstop\t0x2000\n\t.size _start, .-_start\n\t.section .rodata\nmsg:\t.string \"hi\"\n";
const SQUARE: &str = "\t.text\n\t.global square\n\t.type square, @function\nsquare:\tmpy\t$3, $3, $3\n\tbi\t$0\n\t.size square, .-square\n\t.weak\tsoft\n\t.type soft, @function\nsoft:\tnop\n\t.size soft, 4\n";
const CUBE: &str = "\t.text\n\t.global cube\n\t.type cube, @function\ncube:\tmpy\t$4, $3, $3\n\tmpy\t$3, $4, $3\n\tbi\t$0\n\t.size cube, .-cube\n";

#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn executables_match_gnu_ld() {
    let (gas, gld, readelf) = (Path::new(GNU_AS), sibling("ld"), sibling("readelf"));
    assert!(
        gld.is_file() && readelf.is_file(),
        "no ld/readelf beside {GNU_AS}"
    );
    let dir = std::env::temp_dir().join(format!("spu-gnu-ld-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut objects = Vec::new();
    for (name, source) in [("main", MAIN), ("square", SQUARE), ("cube", CUBE)] {
        std::fs::write(dir.join(format!("{name}.s")), source).unwrap();
        let o = format!("{name}.o");
        run(gas, &[&format!("{name}.s"), "-o", &o], &dir);
        objects.push((o.clone(), std::fs::read(dir.join(&o)).unwrap()));
    }
    // The library: ours, which GNU ld must read as it reads GNU ar's.
    let members = objects[1..]
        .iter()
        .map(|(n, d)| Member {
            name: n.clone(),
            data: d.clone(),
        })
        .collect();
    std::fs::write(dir.join("libm.a"), Archive::new(members).write()).unwrap();
    run(&gld, &["main.o", "libm.a", "-o", "gnu.elf"], &dir);
    let inputs = vec![
        Input::Object(Object::from_elf("main.o", &objects[0].1).unwrap()),
        Input::Archive(
            "libm.a".into(),
            Archive::read("libm.a", &std::fs::read(dir.join("libm.a")).unwrap()).unwrap(),
        ),
    ];
    let linked = link(&resolve_inputs(inputs).unwrap(), &LinkOptions::default()).unwrap();
    std::fs::write(dir.join("ours.elf"), &linked.elf).unwrap();
    let gnu = summary(&readelf, &dir.join("gnu.elf"));
    let ours = summary(&readelf, &dir.join("ours.elf"));
    assert_eq!(ours.0, gnu.0, "segments");
    assert_eq!(ours.1, gnu.1, "symbols");
}
