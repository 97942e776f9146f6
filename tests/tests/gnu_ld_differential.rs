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
    let opts = LinkOptions {
        output: Some("gnu.elf".into()),
        ..Default::default()
    };
    let linked = link(&resolve_inputs(inputs).unwrap(), &opts).unwrap();
    std::fs::write(dir.join("ours.elf"), &linked.elf).unwrap();
    let differences = executable_differences(&readelf, &dir.join("gnu.elf"), &dir.join("ours.elf"));
    assert!(differences.is_empty(), "{}", differences.join("\n"));
}

/// An ELF32 big-endian file's section headers as (name, type, flags, addr, size, align,
/// contents) and its entry point: enough to compare two executables without readelf's
/// file offsets.
type Sections = Vec<(String, u32, u32, u32, u32, u32, Vec<u8>)>;

fn elf_sections(data: &[u8]) -> (u32, Sections) {
    let u16_at = |o: usize| u16::from_be_bytes([data[o], data[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_be_bytes(data[o..o + 4].try_into().unwrap());
    let (shoff, shnum, shstrndx) = (u32_at(32) as usize, u16_at(48), u16_at(50));
    let header = |i: usize| {
        let h = shoff + 40 * i;
        (0..10).map(|k| u32_at(h + 4 * k)).collect::<Vec<u32>>()
    };
    let names = header(shstrndx);
    let name = |off: u32| {
        let start = (names[4] + off) as usize;
        let end = data[start..].iter().position(|b| *b == 0).unwrap() + start;
        String::from_utf8_lossy(&data[start..end]).into_owned()
    };
    let sections = (1..shnum)
        .map(|i| {
            let h = header(i);
            let contents = if h[1] == 8 {
                Vec::new()
            } else {
                data[h[4] as usize..(h[4] + h[5]) as usize].to_vec()
            };
            (name(h[0]), h[1], h[2], h[3], h[5], h[8], contents)
        })
        .collect();
    (u32_at(24), sections)
}

/// The differences between GNU ld's executable and ours: entry, sections (name, type,
/// flags, address, size, alignment, contents), loadable segments and symbols.
fn executable_differences(readelf: &Path, gnu: &Path, ours: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let (ge, gs) = elf_sections(&std::fs::read(gnu).unwrap());
    let (oe, os) = elf_sections(&std::fs::read(ours).unwrap());
    if ge != oe {
        out.push(format!("entry {oe:#x}, GNU {ge:#x}"));
    }
    let brief = |s: &Sections| -> Vec<String> {
        s.iter()
            .filter(|x| !matches!(x.1, 2 | 3)) // the symbol and string tables: below
            .map(|x| {
                format!(
                    "{} type {} flags {:#x} at {:#x} size {:#x} align {}",
                    x.0, x.1, x.2, x.3, x.4, x.5
                )
            })
            .collect()
    };
    let (gb, ob) = (brief(&gs), brief(&os));
    if gb != ob {
        out.push(format!("sections {ob:?}, GNU {gb:?}"));
    } else {
        for (g, o) in gs.iter().zip(&os) {
            if g.1 != 2 && g.1 != 3 && g.6 != o.6 {
                let at = g.6.iter().zip(&o.6).position(|(a, b)| a != b).unwrap_or(0);
                out.push(format!("{} contents differ at +{at:#x}", g.0));
            }
        }
    }
    let (g, o) = (summary(readelf, gnu), summary(readelf, ours));
    if g.0 != o.0 {
        out.push(format!("segments {:?}, GNU {:?}", o.0, g.0));
    }
    if g.1 != o.1 {
        out.push(format!("global symbols {:?}, GNU {:?}", o.1, g.1));
    }
    out
}

/// Every project source and generated-corpus file that GNU as assembles and GNU ld links
/// on its own: linked by `spu ld` too, the two executables compared section by section
/// (addresses, sizes, flags, contents), segment by segment and symbol by symbol, and
/// `spu dis` compared with `objdump -d` on both.
#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn single_objects_link_as_gnu_ld() {
    use crate::gnu_differential::{dis_difference, gnu_object, project_sources, write_corpus};
    let (gas, gld, readelf) = (Path::new(GNU_AS), sibling("ld"), sibling("readelf"));
    let objdump = sibling("objdump");
    let tmp = std::env::temp_dir().join(format!("spu-gnu-ld1-{}", std::process::id()));
    let mut files = project_sources();
    files.extend(write_corpus(&tmp.join("corpus")));
    let (mut compared, mut failures) = (0, Vec::new());
    for file in &files {
        let Some(obj) = gnu_object(gas, file, &tmp) else {
            continue;
        };
        let gnu_elf = tmp.join("gnu.elf");
        let _ = std::fs::remove_file(&gnu_elf);
        let gnu_ok = Command::new(&gld)
            .arg(tmp.join("gnu.o"))
            .arg("-o")
            .arg(&gnu_elf)
            .current_dir(&tmp)
            .output()
            .unwrap()
            .status
            .success();
        let opts = LinkOptions {
            output: Some(gnu_elf.display().to_string()),
            ..Default::default()
        };
        let ours = link(&[obj], &opts);
        let name = file.display();
        match (gnu_ok, ours) {
            (false, Err(_)) => continue,
            (false, Ok(_)) => failures.push(format!("{name}: GNU ld refuses what spu ld links")),
            (true, Err(e)) => failures.push(format!("{name}: spu ld refuses: {e:?}")),
            (true, Ok(linked)) => {
                compared += 1;
                let ours_elf = tmp.join("ours.elf");
                std::fs::write(&ours_elf, &linked.elf).unwrap();
                for d in executable_differences(&readelf, &gnu_elf, &ours_elf) {
                    failures.push(format!("{name}: {d}"));
                }
                failures.extend(dis_difference(&objdump, &gnu_elf));
                failures.extend(dis_difference(&objdump, &ours_elf));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!(
        "linked {compared} objects with GNU ld and spu ld, {} differences",
        failures.len()
    );
    assert!(compared > 200, "GNU ld linked only {compared} objects");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
