//! GNU as 2.40's readings that a user of it relies on and that were once known
//! differences of `spu as` (each checked against spu-elf-as 2.40 on the same lines):
//! `nop` as gas's `.nop`, `.eqv NAME, .` resolved late, character constants in macro
//! bodies, the header-only `.debug_line` beside a source's `.debug_info`, and `.symver
//! ..., remove` of a symbol with two versions that a relocation names.

use spu_asm::object::{Object, SymSection};
use spu_asm::{assemble_object, Options};

fn object(source: &str) -> Object {
    assemble_object(source, "t.s", &Options::default())
        .unwrap_or_else(|e| panic!("{}", e[0]))
        .0
}

fn section<'a>(obj: &'a Object, name: &str) -> &'a [u8] {
    &obj.sections.iter().find(|s| s.name == name).unwrap().data
}

#[test]
fn nop_takes_an_expression_and_names_its_symbols() {
    let obj = object("\t.text\n\tnop 5\n\tnop $3\n\tnop 1+2\n\tnop foo\n");
    // `nop 5` covers 5 bytes: two words; `$3` and `foo` are symbols, not registers.
    assert_eq!(section(&obj, ".text"), [0x40, 0x20, 0, 0].repeat(5));
    let undefined: Vec<&str> = obj
        .symbols
        .iter()
        .filter(|s| s.section == SymSection::Undefined && s.global)
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(undefined, ["$3", "foo"]);
}

#[test]
fn eqv_of_dot_is_the_place_of_each_use_and_of_the_end() {
    let obj =
        object("\t.data\n\t.long 1\n\t.eqv sym, .\n\t.long sym, sym\n\t.text\n\tnop\n\tnop\n");
    let addends: Vec<i64> = obj
        .sections
        .iter()
        .find(|s| s.name == ".data")
        .unwrap()
        .relocs
        .iter()
        .map(|r| r.addend)
        .collect();
    assert_eq!(addends, [4, 8]);
    let sym = obj.symbols.iter().find(|s| s.name == "sym").unwrap();
    let text = obj.sections.iter().position(|s| s.name == ".text").unwrap();
    // Where the source ends: .text, after its two words.
    assert_eq!((sym.section, sym.value), (SymSection::Section(text), 8));
}

#[test]
fn a_character_constant_in_a_body_holds_no_parameter() {
    let obj = object(concat!(
        "\t.data\n\t.irpc c, ab\n\t.byte '\\c', '\\n'\n\t.endr\n",
        "\t.macro m a\n\t.ascii \"\\a'\"\n\t.endm\n\tm 7\n",
    ));
    // `'\c'` is `c` (99) each time; `\a'` drops the apostrophe (macro.c).
    assert_eq!(section(&obj, ".data"), b"c\nc\n7");
}

#[test]
fn own_debug_info_gets_a_header_only_line_table() {
    let obj = object("\t.section .debug_info\n\t.long 0\n");
    let line = section(&obj, ".debug_line");
    assert_eq!(line.len(), 0x1d);
    // unit length 0x19, version 3, header length 0x13, then no directory and no file.
    assert_eq!(&line[..10], [0, 0, 0, 0x19, 0, 3, 0, 0, 0, 0x13]);
    assert_eq!(&line[0x1b..], [0, 0]);
    // Not beside an empty one, nor over the source's own line table.
    let empty = object("\t.section .debug_info\n");
    assert!(empty.sections.iter().all(|s| s.name != ".debug_line"));
    let own = object("\t.section .debug_info\n\t.long 0\n\t.section .debug_line\n\t.long 7\n");
    assert_eq!(section(&own, ".debug_line"), [0, 0, 0, 7]);
}

#[test]
fn removed_symbol_of_two_versions_in_a_relocation_is_refused() {
    let src = "\t.globl f\n\t.text\nf:\tnop\n\t.symver f, f@@V2, remove\n\t.symver f, f@V1\n\tbrsl $0, f\n";
    let e = assemble_object(src, "t.s", &Options::default()).unwrap_err();
    assert_eq!(
        e[0].message,
        "symbol 'f' with multiple versions cannot be used in relocation"
    );
    assert_eq!(e[0].location.line, 6);
    // Without the call the symbol just goes.
    let obj =
        object("\t.globl f\n\t.text\nf:\tnop\n\t.symver f, f@@V2, remove\n\t.symver f, f@V1\n");
    assert!(obj.symbols.iter().all(|s| s.name != "f"));
}
