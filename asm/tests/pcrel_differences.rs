//! Differences of addresses that only a pc-relative relocation can carry (`x - y` with
//! `y` in the word's own section and `x` elsewhere or undefined, `-y`, `ext - .`): the
//! `R_SPU_REL32` GNU as 2.40 writes for each (its symbol or section and addend, as
//! spu-elf-as gives them for the same lines), and the word `spu ld` makes of it.

use spu_asm::link::{link, LinkOptions};
use spu_asm::object::{Object, RelocTarget};
use spu_asm::reloc::{R_SPU_ADDR32, R_SPU_REL32};
use spu_asm::{assemble_object, Options};

fn object(source: &str) -> Object {
    let (obj, _) =
        assemble_object(source, "t.s", &Options::default()).unwrap_or_else(|e| panic!("{}", e[0]));
    // Through the ELF bytes and back, as the linker reads them.
    Object::from_elf("t.o", &obj.to_elf().unwrap()).unwrap()
}

/// The relocations of section `name`: (offset, type, target name, addend); the target
/// is a section's name, a symbol's, or "" for none.
fn relocs(obj: &Object, name: &str) -> Vec<(u32, u32, String, i64)> {
    let s = obj.sections.iter().find(|s| s.name == name).unwrap();
    s.relocs
        .iter()
        .map(|r| {
            let target = match &r.target {
                RelocTarget::Section(k) => obj.sections[*k].name.clone(),
                RelocTarget::Symbol(n) => n.clone(),
            };
            (r.offset, r.kind, target, r.addend)
        })
        .collect()
}

#[test]
fn label_differences_across_sections_are_rel32() {
    let obj = object(concat!(
        "\t.data\nx:\t.long 0\n",
        "\t.section .b\ny:\t.long 0\n",
        "\t.long x - y + 7\n",         // spu-elf-as: R_SPU_REL32 .data + 0xb
        "\t.long (x + 7) - (y + 2)\n", // .data + 0xd (8 - 0 + 5)
        "\t.long -y\n",                // against none, 0xc
        "\t.long 3 - y\n",             // none, 0x13
        "\t.long ext - .\n",           // ext + 0
        "\t.long ext - y\n",           // ext + 0x18
        "\t.long x\n",                 // an address stays R_SPU_ADDR32
    ));
    let s = |t: &str| t.to_string();
    assert_eq!(
        relocs(&obj, ".b"),
        vec![
            (4, R_SPU_REL32, s(".data"), 0xb),
            (8, R_SPU_REL32, s(".data"), 0xd),
            (0xc, R_SPU_REL32, s(""), 0xc),
            (0x10, R_SPU_REL32, s(""), 0x13),
            (0x14, R_SPU_REL32, s("ext"), 0),
            (0x18, R_SPU_REL32, s("ext"), 0x18),
            (0x1c, R_SPU_ADDR32, s(".data"), 0),
        ]
    );
}

#[test]
fn a_global_label_is_named_and_other_forms_are_refused() {
    let obj =
        object("\t.data\n\t.globl x\nx:\t.long 0\n\t.section .b\ny:\t.long 0\n\t.long x - y\n");
    assert_eq!(relocs(&obj, ".b"), vec![(4, R_SPU_REL32, "x".into(), 4)]);
    // Neither place is in the word's section, or no 16- or 64-bit pc-relative
    // relocation exists: spu-elf-as refuses each ("can't resolve", "expression too
    // complex").
    for bad in [
        "\t.text\ny:\tnop\n\t.data\n\t.long 0\n\t.long x - y\nx:\n",
        "\t.data\n\t.long -y\n\t.text\ny:\tnop\n",
        "\t.data\nx:\t.long 0\n\t.short -x\n",
        "\t.data\nx:\t.long 0\n\t.quad -x\n",
        "\t.data\n\t.long -ext\n",
    ] {
        let e = assemble_object(bad, "t.s", &Options::default()).unwrap_err();
        assert!(e[0].location.line >= 2, "{bad:?}: {}", e[0]);
    }
}

#[test]
fn spu_ld_applies_rel32_to_the_difference() {
    let a = object(concat!(
        "\t.text\n\t.globl _start\n_start:\tnop\n\t.globl y\ny:\tnop\n",
        "\t.data\n\t.globl x\nx:\t.long 0\n",
        "\t.long y - x\n",   // R_SPU_REL32 .text + 8
        "\t.long -x\n",      // none + 8
        "\t.long ext - .\n", // ext + 0
    ));
    let b = object("\t.data\n\t.long 1, 2, 3\n\t.globl ext\next:\t.long 4\n");
    let linked = link(&[a, b], &LinkOptions::default()).unwrap();
    let addr = |n: &str| {
        linked
            .symbols
            .iter()
            .find(|s| s.0 == n)
            .unwrap_or_else(|| panic!("{n} not linked"))
            .1
    };
    let (x, y, ext) = (addr("x"), addr("y"), addr("ext"));
    let word = |at: u32| {
        let b = &linked.image[at as usize..at as usize + 4];
        u32::from_be_bytes([b[0], b[1], b[2], b[3]])
    };
    assert_eq!(
        (y, x),
        (4, 0x80),
        "GNU ld's layout: .text at 0, .data at 0x80"
    );
    assert_eq!(word(x + 4), y.wrapping_sub(x));
    assert_eq!(word(x + 4), 0xffff_ff84);
    assert_eq!(word(x + 8), x.wrapping_neg());
    assert_eq!(word(x + 12), ext - (x + 12));
    assert_eq!(ext, 0x9c);
}
