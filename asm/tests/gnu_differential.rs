//! Objects from `spu as -c` against GNU as's (spu-elf-as), section by section and
//! relocation by relocation, on the `.s` tests of `tests/asm/` that assemble. Skips,
//! saying why, where GNU binutils for spu-elf is not installed
//! (`scripts/build-spu-binutils.sh` builds it; set SPU_BINUTILS to its prefix).

use spu_asm::object::Object;
use spu_asm::{assemble_object_file, Options, RelocTarget};
use std::path::{Path, PathBuf};

fn gnu_as() -> Option<PathBuf> {
    let mut dirs: Vec<PathBuf> = Vec::new();
    if let Ok(p) = std::env::var("SPU_BINUTILS") {
        dirs.push(Path::new(&p).join("bin"));
    }
    if let Ok(h) = std::env::var("HOME") {
        dirs.push(Path::new(&h).join(".local/spu-binutils/bin"));
    }
    if let Ok(path) = std::env::var("PATH") {
        dirs.extend(std::env::split_paths(&path));
    }
    dirs.into_iter()
        .map(|d| d.join("spu-elf-as"))
        .find(|p| p.is_file())
}

/// A relocation as comparable text: offset, type, what it names, addend.
fn relocs(obj: &Object, section: usize) -> Vec<String> {
    let mut v: Vec<String> = obj.sections[section]
        .relocs
        .iter()
        .map(|r| {
            let target = match &r.target {
                RelocTarget::Section(s) => obj.sections[*s].name.clone(),
                RelocTarget::Symbol(n) => n.clone(),
            };
            format!("{:#x} {} {target}{:+}", r.offset, r.kind, r.addend)
        })
        .collect();
    v.sort();
    v
}

#[test]
fn objects_match_gnu_as() {
    let Some(gas) = gnu_as() else {
        eprintln!("skipped: spu-elf-as not found (scripts/build-spu-binutils.sh builds it)");
        return;
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/asm");
    let tmp = std::env::temp_dir().join(format!("spu-gnu-diff-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut failures = Vec::new();
    let mut compared = 0;
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "s"))
        .collect();
    files.sort();
    for file in files {
        let Ok((ours, _)) = assemble_object_file(&file, &Options::default()) else {
            continue; // the error tests
        };
        let out = tmp.join("gnu.o");
        let status = std::process::Command::new(&gas)
            .arg("-I")
            .arg(&dir)
            .arg(&file)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        if !status.status.success() {
            continue; // GNU as refuses it too (or takes another dialect)
        }
        let theirs = Object::from_elf("gnu.o", &std::fs::read(&out).unwrap()).unwrap();
        compared += 1;
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        for (k, s) in ours.sections.iter().enumerate() {
            let Some(t) = theirs.sections.iter().position(|x| x.name == s.name) else {
                failures.push(format!("{name}: GNU as has no section {}", s.name));
                continue;
            };
            let g = &theirs.sections[t];
            if (s.size, &s.data) != (g.size, &g.data) {
                failures.push(format!(
                    "{name}: {} differs (ours {} bytes, GNU {} bytes)",
                    s.name, s.size, g.size
                ));
            }
            if relocs(&ours, k) != relocs(&theirs, t) {
                failures.push(format!(
                    "{name}: {} relocations: ours {:?}, GNU {:?}",
                    s.name,
                    relocs(&ours, k),
                    relocs(&theirs, t)
                ));
            }
        }
    }
    eprintln!("compared {compared} objects with GNU as");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
