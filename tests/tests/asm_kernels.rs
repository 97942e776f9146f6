//! The project's kernels assemble, with the includes the host provides in memory
//! (`layout.inc`: the frame layout and the kernel ABI; the kernel modules), and come back
//! out of their ELF.

use spu_asm::{assemble, Options};
use spu_spe::elf::read_elf;

fn options() -> Options {
    Options {
        virtual_files: spu_loader::kernels::include_files(),
        ..Default::default()
    }
}

fn kernel(name: &str) {
    let path = format!("{}/../kernels/{name}", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(&path).unwrap();
    let out = match assemble(&src, name, &options()) {
        Ok(out) => out,
        Err(diags) => {
            let text: Vec<String> = diags.iter().map(|d| d.to_string()).collect();
            panic!("{name} does not assemble:\n{}", text.join("\n"));
        }
    };
    assert!(out.warnings.is_empty(), "{name}: {:?}", out.warnings);
    assert!(
        out.image.len() >= 64,
        "{name}: image of {} bytes",
        out.image.len()
    );
    assert!(
        out.image.len() <= 256 * 1024,
        "{name}: larger than the local store"
    );
    let start = out.symbols.iter().find(|(n, _)| n == "_start").map(|s| s.1);
    assert_eq!(Some(out.entry), start, "{name}: entry is _start");
    let elf = read_elf(&out.elf).unwrap();
    assert_eq!(elf.entry, out.entry);
    // The loaded segments reproduce the image.
    let mut image = vec![0u8; out.image.len()];
    for (addr, bytes) in &elf.segments {
        let a = *addr as usize;
        image[a..a + bytes.len()].copy_from_slice(bytes);
    }
    assert_eq!(
        image, out.image,
        "{name}: ELF segments differ from the image"
    );
    assert!(elf
        .symbols
        .iter()
        .any(|(n, a)| n == "_start" && *a == out.entry));
    // No `.L` locals in the ELF symbol table.
    assert!(elf.symbols.iter().all(|(n, _)| !n.starts_with(".L")));
    // Every word of the code disassembles to an instruction.
    let text = elf.sections.iter().find(|s| s.0 == ".text").expect(".text");
    for (i, w) in text.2.chunks(4).enumerate() {
        let word = u32::from_be_bytes(w.try_into().unwrap());
        let t = spu_isa::disasm::instruction_text(
            word,
            text.1 + 4 * i as u32,
            &spu_isa::disasm::NoSymbols,
        );
        assert!(
            !t.starts_with(".long"),
            "{name}: {:#x}: {word:08x} is not an instruction",
            text.1 + 4 * i as u32
        );
    }
    // Assembling is deterministic.
    let again = assemble(&src, name, &options()).unwrap();
    assert_eq!(again.elf, out.elf);
    // As a relocatable object, written to ELF, read back and linked, the kernel is the
    // same program: every relocation reproduces what the assembler resolved itself.
    let (obj, _) = spu_asm::assemble_object(&src, name, &options()).unwrap_or_else(|d| {
        let text: Vec<String> = d.iter().map(|x| x.to_string()).collect();
        panic!("{name} as an object:\n{}", text.join("\n"))
    });
    let bytes = obj.to_elf().unwrap();
    let back = spu_asm::object::Object::from_elf(name, &bytes).unwrap();
    assert_eq!(
        back.sections, obj.sections,
        "{name}: object sections round trip"
    );
    let linked = spu_asm::link::link(&[back], &Default::default()).unwrap();
    assert_eq!(linked.entry, out.entry, "{name}: linked entry");
    assert!(
        linked.image == out.image,
        "{name}: the linked image differs"
    );
}

#[test]
fn primary_assembles() {
    kernel("primary.s");
}

#[test]
fn fill_assembles() {
    kernel("fill.s");
}

#[test]
fn kernels_need_their_include() {
    let path = format!("{}/../kernels/fill.s", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(&path).unwrap();
    let diags = assemble(&src, "fill.s", &Options::default()).unwrap_err();
    assert!(
        diags.iter().any(|d| d.message.contains("layout.inc")),
        "{diags:?}"
    );
}
