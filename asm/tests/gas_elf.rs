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

/// Section header `k` of an ELF32 big-endian object: (name offset aside) type, flags,
/// offset, size, link, info, align, entsize.
fn header(elf: &[u8], k: usize) -> [u32; 8] {
    let word = |at: usize| u32::from_be_bytes(elf[at..at + 4].try_into().unwrap());
    let at = word(32) as usize + 40 * k;
    [4, 8, 16, 20, 24, 28, 32, 36].map(|f| word(at + f))
}

/// Symbol `n`: (value, info, shndx).
fn symbol(elf: &[u8], symtab: usize, n: usize) -> (u32, u8, u16) {
    let h = header(elf, symtab);
    let at = h[2] as usize + 16 * n;
    let shndx = u16::from_be_bytes([elf[at + 14], elf[at + 15]]);
    (
        u32::from_be_bytes(elf[at + 4..at + 8].try_into().unwrap()),
        elf[at + 12],
        shndx,
    )
}

const GROUPS: &str = concat!(
    "\t.text\n\tnop\n",
    "\t.section .text.foo,\"axG\",@progbits,foo,comdat\n",
    "\t.globl foo\nfoo:\tnop\n",
    "\t.section .data,\"awG\",@progbits,foo,comdat\n\t.word foo\n",
    "\t.section .text.bar,\"axG\",@progbits,bar\n\tnop\n",
);

#[test]
fn section_groups_as_spu_elf_as_writes_them() {
    // spu-elf-as 2.40 on these lines: `spu-elf-readelf -SgsW` shows the two `.group`
    // sections first, a second `.data` in group foo, and `bar` a local signature symbol
    // in its own group section; the file is 888 bytes.
    let elf = object(GROUPS).to_elf().unwrap();
    assert_eq!(elf.len(), 888);
    let word = |at: usize| u32::from_be_bytes(elf[at..at + 4].try_into().unwrap());
    // type, flags, offset, size, link, info, align, entsize
    assert_eq!(header(&elf, 1), [17, 0, 0x34, 0x10, 10, 10, 4, 4]);
    assert_eq!(header(&elf, 2), [17, 0, 0x44, 8, 10, 6, 4, 4]);
    assert_eq!(
        [word(0x34), word(0x38), word(0x3c), word(0x40)],
        [1, 6, 7, 8]
    );
    assert_eq!([word(0x44), word(0x48)], [0, 9]);
    assert_eq!(header(&elf, 4)[..2], [1, 3]); // the first .data, in no group
    assert_eq!(header(&elf, 6), [1, 0x206, 0x50, 4, 0, 0, 1, 0]);
    assert_eq!(header(&elf, 7), [1, 0x203, 0x54, 4, 0, 0, 1, 0]);
    assert_eq!(header(&elf, 8), [4, 0x240, 0x118, 12, 10, 7, 4, 12]);
    assert_eq!(header(&elf, 9), [1, 0x206, 0x58, 4, 0, 0, 1, 0]);
    assert_eq!(header(&elf, 10), [2, 0, 0x5c, 0xb0, 11, 10, 4, 16]);
    // bar (local, in group 2), the grouped .data's and the groups' section symbols,
    // then foo (global, in .text.foo).
    assert_eq!(symbol(&elf, 10, 6), (0, 0x00, 2));
    assert_eq!(symbol(&elf, 10, 7), (0, 0x03, 7));
    assert_eq!(symbol(&elf, 10, 8), (0, 0x03, 1));
    assert_eq!(symbol(&elf, 10, 9), (0, 0x03, 2));
    assert_eq!(symbol(&elf, 10, 10), (0, 0x10, 6));
    // Read back: the groups name their content sections.
    let back = Object::from_elf("g.o", &elf).unwrap();
    let groups: Vec<_> = (back.groups.iter())
        .map(|g| (g.signature.as_str(), g.comdat, g.members.clone()))
        .collect();
    assert_eq!(groups, [("foo", true, vec![3, 4]), ("bar", false, vec![5])]);
}

#[test]
fn attach_to_group_and_the_clone_flag() {
    // gas's attach-2.s: `bar` joins foo.group, so naming `bar` again makes a second,
    // ungrouped one; `?` takes the current section's group.
    let src = concat!(
        "\t.section bar\n\tnop\n\t.attach_to_group foo.group\n",
        "\t.section foo, \"G\", %note , foo.group\n\t.word 0\n",
        "\t.section bar\n\tnop\n",
        "\t.section foo, \"G\", %note , foo.group\n",
        "\t.section baz, \"a?\"\n\t.word 1\n",
    );
    let obj = object(src);
    let names: Vec<_> = (obj.sections.iter())
        .map(|s| (s.name.as_str(), s.flags))
        .collect();
    assert_eq!(
        &names[3..],
        [("bar", 0x200), ("foo", 0x200), ("bar", 0), ("baz", 0x202)]
    );
    assert_eq!(obj.groups.len(), 1);
    assert_eq!(obj.groups[0].members, [3, 4, 6]);
    assert_eq!(
        messages("\t.section x,\"G\",%progbits,g\n\t.attach_to_group h\n"),
        ["2: warning: section x already has a group (g)"]
    );
}

#[test]
fn spu_ld_keeps_the_first_comdat_group_of_a_signature() {
    // Two objects with COMDAT group `f` each defining `f`: the second copy is
    // discarded and its caller's branch reaches the first (GNU ld's rule).
    let one = concat!(
        "\t.text\n\t.globl _start\n_start:\tbrsl $0, f\n\tstop\n",
        "\t.section .text.f,\"axG\",@progbits,f,comdat\n\t.globl f\nf:\til $3, 1\n\tbi $0\n",
    );
    let two = concat!(
        "\t.text\n\t.globl g\ng:\tbrsl $0, f\n",
        "\t.section .text.f,\"axG\",@progbits,f,comdat\n\t.globl f\nf:\til $3, 2\n\tbi $0\n",
    );
    let objects = [object(one), object(two)];
    let objects: Vec<Object> = (objects.iter())
        .map(|o| Object::from_elf("x.o", &o.to_elf().unwrap()).unwrap())
        .collect();
    let linked = spu_asm::link::link(&objects, &Default::default()).unwrap();
    let at = |n: &str| linked.symbols.iter().find(|s| s.0 == n).unwrap().1;
    let f = at("f") as usize;
    // il $3, 1 (0x40800083), then bi $0; the second copy's il $3, 2 is nowhere.
    assert_eq!(linked.image[f..f + 4], [0x40, 0x80, 0x00, 0x83]);
    let second = [0x40, 0x80, 0x01, 0x03];
    assert!(!linked.image.windows(4).any(|w| w == second));
    // g's brsl reaches the kept f.
    let g = at("g") as usize;
    let word = u32::from_be_bytes(linked.image[g..g + 4].try_into().unwrap());
    let offset = ((word >> 7) & 0xffff) as i16 as i32 * 4;
    assert_eq!(g as i32 + offset, f as i32);
}
