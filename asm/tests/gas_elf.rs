//! gas's generic `elf` testsuite (binutils 2.40 `gas/testsuite/gas/elf`) as `spu as`
//! reads it: section directives checked as obj-elf.c's `obj_elf_change_section` checks
//! them, BFD's special sections, what gas refuses of a common symbol, and `.nop`. Each
//! expectation is spu-elf-as 2.40's on the same lines (its messages and line numbers,
//! or the flags and types `spu-elf-readelf -S` shows of its object).

use spu_asm::object::Object;
use spu_asm::{assemble_object, Options};

fn object(source: &str) -> Object {
    assemble_object(source, "t.s", &Options::default())
        .unwrap_or_else(|e| panic!("{}", e[0]))
        .0
}

/// Each message as `LINE: severity: text`, errors first when refused, else warnings.
fn messages(source: &str) -> Vec<String> {
    let show = |d: &spu_asm::Diagnostic| {
        let sev = format!("{:?}", d.severity).to_lowercase();
        format!("{}: {sev}: {}", d.location.line, d.message)
    };
    match assemble_object(source, "t.s", &Options::default()) {
        Ok((_, warnings)) => warnings.iter().map(show).collect(),
        Err(errors) => errors.iter().map(show).collect(),
    }
}

/// A section's (type, flags).
fn kind(obj: &Object, name: &str) -> (u32, u64) {
    let s = obj.sections.iter().find(|s| s.name == name).unwrap();
    (s.ty, s.flags)
}

#[test]
fn a_section_named_again_with_another_type_or_attributes() {
    // gas's section5.s, shortened: an error for a section of the source's own, a
    // warning for a special one (whose own type stays).
    let src = concat!(
        "\t.section .test1, \"\", %progbits\n",
        "\t.section .test2\n",
        "\t.section .test4, \"aw\", %nobits\n",
        "\t.section .test1, \"aw\", %nobits\n",
        "\t.section .test2, \"w\"\n",
        "\t.section .test4, \"aw\"\n",
        "\t.section .test4, \"aw\", %nobits\n",
    );
    assert_eq!(
        messages(src),
        [
            "4: error: changed section type for .test1",
            "4: error: changed section attributes for .test1",
            "5: error: changed section attributes for .test2",
            "6: error: changed section attributes for .test4",
        ]
    );
    let special = concat!(
        "\t.section .data, \"a\"\n",
        "\t.section .bss, \"a\"\n",
        "\t.section .data, \"aw\", %nobits\n",
        "\t.section .data, \"aw\", %progbits\n",
        "\t.long 1\n",
    );
    assert_eq!(
        messages(special),
        [
            "1: warning: ignoring changed section attributes for .data",
            "2: warning: ignoring changed section attributes for .bss",
            "3: warning: ignoring incorrect section type for .data",
        ]
    );
    assert_eq!(kind(&object(special), ".data"), (1, 3));
}

#[test]
fn special_sections_are_bfds_by_exact_name_or_dotted_suffix() {
    let obj = object(concat!(
        "\t.section .noinit\n\t.long 0\n",
        "\t.section .persistent.foo\n\t.long 1\n",
        "\t.section .gnu.lto_main\n\t.long 2\n",
        "\t.section .debug_str, \"MS\", %progbits, 1\n\t.asciz \"x\"\n",
        "\t.section .init.foo\n\t.long 3\n",
        "\t.section .rodata.str1.1, \"aMS\", %progbits, 1\n\t.asciz \"y\"\n",
    ));
    assert_eq!(kind(&obj, ".noinit"), (8, 3)); // NOBITS, WA
    assert_eq!(kind(&obj, ".persistent.foo"), (1, 3));
    assert_eq!(kind(&obj, ".gnu.lto_main"), (1, 0x8000_0000)); // SHF_EXCLUDE
    assert_eq!(kind(&obj, ".debug_str"), (1, 0x30));
    assert_eq!(kind(&obj, ".init.foo"), (1, 0)); // `.init` is special by its name only
    assert_eq!(kind(&obj, ".rodata.str1.1"), (1, 0x32));
    // None of them warns: .debug_str is no special section, .rodata.str* may merge.
    assert_eq!(
        messages("\t.section .debug_str, \"MS\", %progbits, 1\n\t.section .rodata.str1.1, \"aMS\", %progbits, 1\n"),
        Vec::<String>::new()
    );
    assert_eq!(
        messages(
            "\t.section .debug_info, \"G\", %progbits, foo, comdat\n\t.section .rodata, \"aw\"\n"
        ),
        ["2: warning: setting incorrect section attributes for .rodata"]
    );
}

#[test]
fn section_flags_types_and_subsections_as_obj_elf_reads_them() {
    let obj = object(concat!(
        "\t.section .foo, \"\", \"note\"\n\t.long 0\n",
        "\t.section sec1, \"0x06000000\"\n\t.long 1\n",
        "\t.section sec2, \"a128x\"\n\t.long 2\n",
        "\t.pushsection .bar, 2, \"a\"\n\t.byte 2\n\t.popsection\n",
        "\t.pushsection .bar, 1, \"a\", %progbits\n\t.byte 1\n\t.popsection\n",
    ));
    assert_eq!(kind(&obj, ".foo"), (7, 0));
    assert_eq!(kind(&obj, "sec1"), (1, 0x0600_0000));
    assert_eq!(kind(&obj, "sec2"), (1, 0x86)); // a, 128 (SHF_LINK_ORDER), x
    let bar = obj.sections.iter().find(|s| s.name == ".bar").unwrap();
    assert_eq!(bar.data, [1, 2]); // subsection 1 before 2
    assert_eq!(
        messages("\t.section .mbind.data,\"dw\",%nobits\n"),
        ["1: error: SHF_ALLOC isn't set for GNU_MBIND section: .mbind.data"]
    );
}

#[test]
fn a_common_symbol_is_not_weak_equated_or_versioned() {
    for src in [
        "\t.weak foobar\n\t.comm foobar,30\n",
        "\t.comm foobar,30\n\t.weak foobar\n",
    ] {
        assert_eq!(
            messages(src),
            [format!(
                "{}: error: symbol `foobar' can not be both weak and common",
                if src.starts_with("\t.weak") { 2 } else { 1 }
            )]
        );
    }
    for src in [
        "\t.set foo1,foo\n\t.globl foo1\n\t.comm foo,8,8\n",
        "\t.comm foo,8,8\n\t.set foo1,foo\n",
    ] {
        let m = messages(src);
        assert_eq!(m.len(), 1, "{m:?}");
        assert!(
            m[0].ends_with("error: `foo1' can't be equated to common symbol `foo'"),
            "{m:?}"
        );
    }
    assert_eq!(
        messages("\t.comm foo,8,8\n\t.symver foo,foo@VERS.1\n\t.symver bar,bar@VERS.1\n\t.comm bar,8,8\n"),
        [
            "2: error: `foo@VERS.1' can't be versioned to common symbol 'foo'",
            "4: error: `bar@VERS.1' can't be versioned to common symbol 'bar'",
        ]
    );
}

#[test]
fn a_section_and_a_label_share_one_name_space() {
    // gas's pr14891.s: a section's symbol bears its name.
    assert_eq!(
        messages("foo:\n\t.section foo, \"a\"\n\t.section bar, \"a\"\nbar:\n"),
        [
            "2: error: section name 'foo' already defined as another symbol",
            "4: error: symbol `bar' is already defined",
        ]
    );
}

#[test]
fn dot_nop_is_nop() {
    let obj = object("\t.section .alloc0,\"a\"\n\t.nop 16\n\t.text\n\t.nop\n\t.nop 5\n");
    let words = |n: usize| [0x40, 0x20, 0, 0].repeat(n);
    assert_eq!(
        obj.sections
            .iter()
            .find(|s| s.name == ".alloc0")
            .unwrap()
            .data,
        words(4)
    );
    assert_eq!(
        obj.sections
            .iter()
            .find(|s| s.name == ".text")
            .unwrap()
            .data,
        words(3)
    );
}

#[test]
fn a_section_symbol_is_not_made_global() {
    let src = "\t.section AAA\n\t.global AAA\n\t.byte 49\n";
    assert_eq!(
        messages(src),
        ["2: warning: can't make section symbol global"]
    );
    assert!(object(src).symbols.iter().all(|s| s.name != "AAA"));
}

#[test]
fn types_as_obj_elf_sets_them() {
    // gas's type-2.s, in part: which flags a later type keeps, and when it warns.
    let src = concat!(
        "\t.text\n",
        "\t.type test1,%function\n\t.type test1,%object\ntest1: .byte 0\n",
        "\t.type test6,%gnu_indirect_function\n\t.type test6,%notype\ntest6: .byte 0\n",
        "\t.type test8,%object\n\t.type test8,%tls_object\n\t.type test8,%object\ntest8: .byte 0\n",
        "\t.type test9,%function\n\t.type test9,%gnu_indirect_function\n\t.type test9,%function\ntest9: .byte 0\n",
        "\t.type test10,2\ntest10: .byte 0\n",
    );
    assert_eq!(
        messages(src),
        ["3: warning: symbol 'test1' already has its type set"]
    );
    let obj = object(src);
    let kind = |n: &str| obj.symbols.iter().find(|s| s.name == n).unwrap().kind;
    assert_eq!(
        ["test1", "test6", "test8", "test9", "test10"].map(kind),
        [1, 0, 6, 10, 2]
    );
    // An indirect function, even one typed again since, makes the object GNU's.
    assert_eq!(obj.osabi, 3);
    assert_eq!(obj.to_elf().unwrap()[7], 3);
    assert_eq!(object("\t.type f,%function\nf: nop\n").osabi, 0);
}

#[test]
fn sizes_of_equates_and_across_sections() {
    // gas's size.s: an explicit size stays; a later equate's size replaces an earlier's.
    let obj = object(concat!(
        ".text\n.size foo1, 1\nfoo1:\n",
        ".size bar2, 2\n.set bar2, foo1\n",
        ".set bar6, foo2\n",
        ".size foo2, 3\nfoo2:\n",
        ".set bar7, foo1\n.set bar7, foo2\n",
    ));
    let size = |n: &str| obj.symbols.iter().find(|s| s.name == n).unwrap().size;
    assert_eq!(["bar2", "bar6", "bar7"].map(size), [2, 3, 3]);
    // gas's bad-size.s: a size across sections cannot be written.
    let src = "\t.text\nt:\n\t.byte 0\n\t.section .text.b, \"xa\"\n\t.byte 0\n\t.size t, .-t\n";
    assert_eq!(
        messages(src),
        ["6: error: .size expression for t does not evaluate to a constant"]
    );
}

#[test]
fn previous_after_struct_returns_to_the_section_it_left() {
    // gas's struct.s: s_struct is a section change for `.previous`.
    let obj = object(concat!(
        "\t.globl l1, l2\n\t.data\nl1:\t.long 0\n",
        "\t.struct 2\nw1:\t.short 0\n\t.previous\nl2:\t.long 0\n",
    ));
    let data = obj.sections.iter().position(|s| s.name == ".data").unwrap();
    let l2 = obj.symbols.iter().find(|s| s.name == "l2").unwrap();
    assert_eq!(
        (l2.section, l2.value),
        (spu_asm::object::SymSection::Section(data), 4)
    );
    assert!(obj
        .sections
        .iter()
        .find(|s| s.name == ".text")
        .unwrap()
        .data
        .is_empty());
}

#[test]
fn tls_common_is_a_thread_local_common_symbol() {
    // gas's common4.s.
    let obj = object("\t.tls_common foobar,30,4\n");
    let s = obj.symbols.iter().find(|s| s.name == "foobar").unwrap();
    assert_eq!(
        (s.section, s.value, s.size, s.kind, s.global),
        (spu_asm::object::SymSection::Common, 4, 30, 6, true)
    );
}
