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

use crate::gnu_differential::dis_difference;

#[cfg(has_binutils)]
const GNU_AS: &str = env!("SPU_ELF_AS");
#[cfg(not(has_binutils))]
const GNU_AS: &str = "";
/// binutils' `ld/testsuite/ld-spu` (its `.s` files are linked by both linkers).
#[cfg(has_ld_spu_testsuite)]
const LD_SPU_TESTSUITE: &str = env!("SPU_LD_TESTSUITE_DIR");
#[cfg(not(has_ld_spu_testsuite))]
const LD_SPU_TESTSUITE: &str = "";

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

/// Objects with commons (merged to the largest size and alignment), data of several
/// alignments, read-only data, bss and a call between them.
const COMMONS_A: &str = "\t.text\n\t.global _start\n_start:\tbrsl\t$0, helper\n\tila\t$3, buf\n\tila\t$4, tab\n\tstop\n\t.comm\tbuf, 64, 16\n\t.comm\tc2, 4, 4\n\t.data\n\t.byte 1\n\t.align 4\ntab:\t.long buf, c2\n\t.section .rodata\n\t.string \"abc\"\n";
const COMMONS_B: &str = "\t.text\n\t.global helper\n\t.type helper, @function\nhelper:\tila\t$5, local\n\tbi\t$0\n\t.size helper, .-helper\n\t.comm\tbuf, 32, 8\n\t.data\n\t.short 7\n\t.section .bss\n\t.align 3\nlocal:\t.space 24\n\t.section .rodata\n\t.align 4\n\t.long 9\n";
/// Code in sections of their own names (`.text.hot`, `.init`, an overlay-named section
/// that the default script places as an orphan).
const SECTIONS: &str = "\t.section .text.hot,\"ax\",@progbits\nhot:\tnop\n\t.section .init,\"ax\",@progbits\n\tlnop\n\t.text\n\t.global _start\n_start:\tbrsl\t$0, hot\n\tstop\n\t.section .ov_a,\"ax\",@progbits\nova:\tbi\t$0\n";

/// A link both ways: sources assembled by GNU as, the first `objects` given as objects
/// and the rest as one archive `libx.a` after them; `args` are GNU ld's options beside
/// `-o gnu.elf`, `opts` spu ld's same options.
struct Case {
    name: &'static str,
    sources: &'static [(&'static str, &'static str)],
    objects: usize,
    args: &'static [&'static str],
    opts: fn() -> LinkOptions,
}

const CASES: &[Case] = &[
    Case {
        name: "an object and a library of two",
        sources: &[("main", MAIN), ("square", SQUARE), ("cube", CUBE)],
        objects: 1,
        args: &[],
        opts: LinkOptions::default,
    },
    Case {
        name: "commons, data and bss of two objects",
        sources: &[("a", COMMONS_A), ("b", COMMONS_B)],
        objects: 2,
        args: &[],
        opts: LinkOptions::default,
    },
    Case {
        name: "-Ttext 0x100 -e square",
        sources: &[("main", MAIN), ("square", SQUARE)],
        objects: 2,
        args: &["-Ttext", "0x100", "-e", "square"],
        opts: || LinkOptions {
            text_addr: 0x100,
            entry: Some("square".into()),
            ..Default::default()
        },
    },
    Case {
        name: "-e 0x8 (an address)",
        sources: &[("main", MAIN), ("square", SQUARE)],
        objects: 2,
        args: &["-e", "0x8"],
        opts: || LinkOptions {
            entry: Some("0x8".into()),
            ..Default::default()
        },
    },
    Case {
        name: "named code sections",
        sources: &[("sections", SECTIONS)],
        objects: 1,
        args: &[],
        opts: LinkOptions::default,
    },
];

/// Multi-object links against GNU ld's: objects and an archive (ours, which GNU ld must
/// read as it reads GNU ar's), commons, `-Ttext`, `-e`; each executable compared section
/// by section, segment by segment and symbol by symbol, and `spu dis` against
/// `objdump -d` on both.
#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn executables_match_gnu_ld() {
    let (gas, gld, readelf) = (Path::new(GNU_AS), sibling("ld"), sibling("readelf"));
    let objdump = sibling("objdump");
    assert!(
        gld.is_file() && readelf.is_file(),
        "no ld/readelf beside {GNU_AS}"
    );
    let mut failures = Vec::new();
    for (n, case) in CASES.iter().enumerate() {
        let dir = std::env::temp_dir().join(format!("spu-gnu-ld-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut objects = Vec::new();
        for (name, source) in case.sources {
            std::fs::write(dir.join(format!("{name}.s")), source).unwrap();
            let o = format!("{name}.o");
            run(gas, &[&format!("{name}.s"), "-o", &o], &dir);
            objects.push((o.clone(), std::fs::read(dir.join(&o)).unwrap()));
        }
        let mut gnu_args: Vec<String> = objects[..case.objects]
            .iter()
            .map(|o| o.0.clone())
            .collect();
        let mut inputs: Vec<Input> = objects[..case.objects]
            .iter()
            .map(|(n, d)| Input::Object(Object::from_elf(n, d).unwrap()))
            .collect();
        if objects.len() > case.objects {
            let members = objects[case.objects..]
                .iter()
                .map(|(n, d)| Member {
                    name: n.clone(),
                    data: d.clone(),
                })
                .collect();
            let lib = Archive::new(members).write();
            std::fs::write(dir.join("libx.a"), &lib).unwrap();
            gnu_args.push("libx.a".into());
            inputs.push(Input::Archive(
                "libx.a".into(),
                Archive::read("libx.a", &lib).unwrap(),
            ));
        }
        gnu_args.extend(case.args.iter().map(|a| a.to_string()));
        gnu_args.extend(["-o".into(), "gnu.elf".into()]);
        let gnu_args: Vec<&str> = gnu_args.iter().map(|a| a.as_str()).collect();
        run(&gld, &gnu_args, &dir);
        let opts = LinkOptions {
            output: Some("gnu.elf".into()),
            ..(case.opts)()
        };
        let linked = link(&resolve_inputs(inputs).unwrap(), &opts).unwrap();
        std::fs::write(dir.join("ours.elf"), &linked.elf).unwrap();
        let differences =
            executable_differences(&readelf, &dir.join("gnu.elf"), &dir.join("ours.elf"));
        failures.extend(differences.iter().map(|d| format!("{}: {d}", case.name)));
        failures.extend(dis_difference(&objdump, &dir.join("ours.elf")));
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
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

/// The files whose executables are known to differ, and how.
const KNOWN: &[(&str, &str)] = &[];

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
    use crate::gnu_differential::{gnu_object, project_sources, write_corpus};
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
                let differences = executable_differences(&readelf, &gnu_elf, &ours_elf);
                let known = KNOWN.iter().find(|k| file.ends_with(k.0));
                match known {
                    Some(k) if differences.is_empty() => failures.push(format!(
                        "{name}: now links as GNU ld does; take it off KNOWN ({})",
                        k.1
                    )),
                    Some(_) => {}
                    None => failures.extend(differences.iter().map(|d| format!("{name}: {d}"))),
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

/// binutils' own SPU linker test sources (`ld/testsuite/ld-spu/*.s`, overlay, icache,
/// PIC and `_EAR_` ones, installed beside GNU binutils by scripts/build-spu-binutils.sh or named by SPU_LD_TESTSUITE, never kept in
/// the repository), linked without their scripts and options (which spu ld does not
/// take: docs/linker.md): both linkers link each alike, or both refuse it.
#[test]
#[cfg_attr(
    not(all(has_binutils, has_ld_spu_testsuite)),
    ignore = "needs GNU binutils for SPU and binutils' ld/testsuite/ld-spu sources: scripts/build-spu-binutils.sh installs both (or SPU_LD_TESTSUITE=dir)"
)]
fn ld_spu_testsuite_sources_link_as_gnu_ld_without_scripts() {
    let suite = Path::new(LD_SPU_TESTSUITE);
    let (gas, gld, readelf) = (Path::new(GNU_AS), sibling("ld"), sibling("readelf"));
    let tmp = std::env::temp_dir().join(format!("spu-ld-spu-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut sources: Vec<PathBuf> = std::fs::read_dir(suite)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "s"))
        .collect();
    sources.sort();
    let (mut compared, mut failures) = (0, Vec::new());
    for source in &sources {
        let Some(obj) = crate::gnu_differential::gnu_object(gas, source, &tmp) else {
            continue;
        };
        let gnu_elf = tmp.join("gnu.elf");
        let _ = std::fs::remove_file(&gnu_elf);
        let gnu_ok = Command::new(&gld)
            .arg("gnu.o")
            .args(["-o", "gnu.elf"])
            .current_dir(&tmp)
            .output()
            .unwrap()
            .status
            .success();
        let opts = LinkOptions {
            output: Some("gnu.elf".into()),
            ..Default::default()
        };
        let name = source.display();
        match (gnu_ok, link(&[obj], &opts)) {
            (false, Err(_)) => compared += 1,
            (false, Ok(_)) => failures.push(format!("{name}: GNU ld refuses what spu ld links")),
            (true, Err(e)) => failures.push(format!("{name}: spu ld refuses: {e:?}")),
            (true, Ok(linked)) => {
                compared += 1;
                std::fs::write(tmp.join("ours.elf"), &linked.elf).unwrap();
                let d = executable_differences(&readelf, &gnu_elf, &tmp.join("ours.elf"));
                failures.extend(d.iter().map(|d| format!("{name}: {d}")));
            }
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!("{compared} ld-spu sources linked (or refused) alike");
    assert!(
        compared > 0,
        "no ld-spu source in {}",
        suite.to_string_lossy()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// An overlay manager's two entry points, enough for a link: with them defined, GNU ld
/// does not add its built-in manager (which spu ld does not carry), so the two linkers'
/// outputs can be compared byte for byte.
const OVERLAY_MANAGER: &str = "\t.text\n\t.global __ovly_load\n\t.type __ovly_load,@function\n__ovly_load:\tbi $0\n\t.global __ovly_return\n__ovly_return:\tbi $0\n";

/// binutils' overlay tests (`ld-spu` `ovl.s` with `-T ovl1.lnk -T ovl.lnk`, `ovl2.s`
/// with `-T ovl2.lnk -T ovl.lnk`: an `OVERLAY` statement inserted into a script),
/// linked by both linkers with a user overlay manager: the executables must be the same
/// file, byte for byte (stubs, `_ovly_table`, `.toe`, overlay segments and offsets,
/// symbol table).
#[test]
#[cfg_attr(
    not(all(has_binutils, has_ld_spu_testsuite)),
    ignore = "needs GNU binutils for SPU and binutils' ld/testsuite/ld-spu sources: scripts/build-spu-binutils.sh installs both (or SPU_LD_TESTSUITE=dir)"
)]
fn ld_spu_overlay_tests_link_byte_identical() {
    use spu_asm::link_script::{parse, Script};
    let suite = Path::new(LD_SPU_TESTSUITE);
    let (gas, gld) = (Path::new(GNU_AS), sibling("ld"));
    let tmp = std::env::temp_dir().join(format!("spu-ld-ovl-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    std::fs::write(tmp.join("mgr.s"), OVERLAY_MANAGER).unwrap();
    run(gas, &["mgr.s", "-o", "mgr.o"], &tmp);
    let cases = [
        ("ovl", ["ovl1.lnk", "ovl.lnk"]),
        ("ovl2", ["ovl2.lnk", "ovl.lnk"]),
    ];
    let (mut identical, mut failures) = (0, Vec::new());
    for (source, scripts) in cases {
        let s = suite.join(format!("{source}.s"));
        let o = format!("{source}.o");
        run(gas, &[s.to_str().unwrap(), "-o", &o], &tmp);
        let lnk: Vec<String> = scripts
            .iter()
            .map(|l| suite.join(l).display().to_string())
            .collect();
        run(
            &gld,
            &["-T", &lnk[0], "-T", &lnk[1], &o, "mgr.o", "-o", "out.elf"],
            &tmp,
        );
        let gnu = std::fs::read(tmp.join("out.elf")).unwrap();
        let parsed = lnk
            .iter()
            .map(|l| {
                (
                    l.clone(),
                    parse(l, &std::fs::read_to_string(l).unwrap()).unwrap(),
                )
            })
            .collect();
        let objects: Vec<Object> = [o.as_str(), "mgr.o"]
            .iter()
            .map(|n| Object::from_elf(n, &std::fs::read(tmp.join(n)).unwrap()).unwrap())
            .collect();
        let opts = LinkOptions {
            output: Some("out.elf".into()),
            script: Some(Script::combine(parsed).unwrap()),
            ..Default::default()
        };
        let ours = link(&objects, &opts).unwrap().elf;
        if ours == gnu {
            identical += 1;
        } else {
            let at = ours.iter().zip(&gnu).position(|(a, b)| a != b);
            failures.push(format!(
                "{source}: differs from GNU ld's at byte {at:?} (sizes {} and {})",
                ours.len(),
                gnu.len()
            ));
        }
    }
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!(
        "{identical} of {} ld-spu overlay links byte-identical",
        cases.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The project's overlay program (`tests/overlay/`: its script, two overlays in one
/// region, its own overlay manager), assembled by GNU as and linked by both linkers with
/// the script: the same file, byte for byte.
#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn the_overlay_program_links_byte_identical() {
    use spu_asm::link_script::{parse, Script};
    let (gas, gld) = (Path::new(GNU_AS), sibling("ld"));
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("overlay");
    let tmp = std::env::temp_dir().join(format!("spu-ld-ovlprog-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut objects = Vec::new();
    for name in ["program", "manager"] {
        let s = src.join(format!("{name}.s"));
        let o = format!("{name}.o");
        run(gas, &[s.to_str().unwrap(), "-o", &o], &tmp);
        objects.push(Object::from_elf(&o, &std::fs::read(tmp.join(&o)).unwrap()).unwrap());
    }
    let script = src.join("overlay.ld");
    let script = script.to_str().unwrap();
    run(
        &gld,
        &["-T", script, "program.o", "manager.o", "-o", "prog.elf"],
        &tmp,
    );
    let gnu = std::fs::read(tmp.join("prog.elf")).unwrap();
    let text = std::fs::read_to_string(script).unwrap();
    let opts = LinkOptions {
        output: Some("prog.elf".into()),
        script: Some(
            Script::combine(vec![(script.into(), parse(script, &text).unwrap())]).unwrap(),
        ),
        ..Default::default()
    };
    let ours = link(&objects, &opts).unwrap().elf;
    let _ = std::fs::remove_dir_all(&tmp);
    let at = ours.iter().zip(&gnu).position(|(a, b)| a != b);
    assert!(
        ours == gnu,
        "differs from GNU ld's at byte {at:?} (sizes {} and {})",
        ours.len(),
        gnu.len()
    );
}
