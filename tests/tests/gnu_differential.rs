//! Objects from `spu as -c` against GNU as's (spu-elf-as), section by section and
//! relocation by relocation, on the `.s` tests of `tests/asm/` that assemble. Where GNU
//! binutils for spu-elf was not found when the test was built, the test is ignored, saying
//! why (`build.rs` looks for it; `scripts/build-spu-binutils.sh` builds it, and
//! SPU_BINUTILS names its prefix when it is not the script's default).

use spu_asm::object::Object;
use spu_asm::{assemble_object_file, Options, RelocTarget};
use std::path::{Path, PathBuf};

/// GNU as, as the build script found it.
#[cfg(has_binutils)]
const GNU_AS: &str = env!("SPU_ELF_AS");
#[cfg(not(has_binutils))]
const GNU_AS: &str = "";

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
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn objects_match_gnu_as() {
    let gas = Path::new(GNU_AS);
    assert!(
        gas.is_file(),
        "{GNU_AS} is gone since the build: rebuild (cargo clean -p spu-tests)"
    );
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("asm");
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
        let status = std::process::Command::new(gas)
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
    assert!(compared > 0, "GNU as assembled none of the tests");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
