//! Relocatable objects (what `spu as -c` writes and `spu ld` reads) and the bounds on
//! hostile input (issue #15's assembler classes), each asserting the result or message.

use spu_asm::link::{link, LinkOptions};
use spu_asm::object::{Object, SymSection};
use spu_asm::reloc::*;
use spu_asm::{assemble, assemble_object, Options, RelocTarget, Severity};

fn object(src: &str) -> Object {
    let (obj, _) = assemble_object(src, "t.s", &Options::default()).unwrap_or_else(|e| {
        panic!(
            "{}",
            e.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        )
    });
    // Every object goes through ELF and back unchanged.
    let back = Object::from_elf("t.o", &obj.to_elf().unwrap()).unwrap();
    assert_eq!(back.sections, obj.sections);
    back
}

fn errors(src: &str) -> Vec<String> {
    match assemble(src, "t.s", &Options::default()) {
        Ok(_) => vec![],
        Err(d) => d
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .map(|d| d.message.clone())
            .collect(),
    }
}

/// Each operand kind that can name an address gets the relocation gas's `arg_encode`
/// gives it, at the instruction's offset, with the field left zero for the linker.
#[test]
fn operands_get_their_spu_relocations() {
    let obj = object(
        "\t.text\n\
         \tlqd\t$3, ext($1)\n\
         \tai\t$3, $3, ext\n\
         \til\t$3, ext\n\
         \tlqa\t$3, ext\n\
         \tila\t$3, ext+8\n\
         \tilhu\t$3, ext@h\n\
         \tiohl\t$3, ext@l\n\
         \tbrsl\t$lr, ext\n\
         \thbra\t1f, ext\n\
         \thbrr\t1f, ext\n\
         1:\tbi\t$lr\n\
         \t.data\n\
         \t.long\text+4\n",
    );
    let text = &obj.sections[0];
    let kinds: Vec<(u32, u32, i64)> = text
        .relocs
        .iter()
        .map(|r| (r.offset, r.kind, r.addend))
        .collect();
    assert_eq!(
        kinds,
        [
            (0x00, R_SPU_ADDR10, 0),
            (0x04, R_SPU_ADDR10I, 0),
            (0x08, R_SPU_ADDR16I, 0),
            (0x0c, R_SPU_ADDR16, 0),
            (0x10, R_SPU_ADDR18, 8),
            (0x14, R_SPU_ADDR16_HI, 0),
            (0x18, R_SPU_ADDR16_LO, 0),
            (0x1c, R_SPU_REL16, 0),
            (0x20, R_SPU_ADDR16, 0),
            (0x24, R_SPU_REL16, 0),
        ]
    );
    assert!(text
        .relocs
        .iter()
        .all(|r| r.target == RelocTarget::Symbol("ext".into())));
    // The fields are left for the linker: only the opcode and registers are there.
    assert_eq!(&text.data[0x1c..0x20], &0x3300_0000u32.to_be_bytes());
    let data = &obj.sections[1];
    assert_eq!(data.relocs[0].kind, R_SPU_ADDR32);
    assert_eq!(data.relocs[0].addend, 4);
    let ext = obj.symbols.iter().find(|s| s.name == "ext").unwrap();
    assert_eq!(ext.section, SymSection::Undefined);
    assert!(ext.global);
}

/// A branch to a label of its own section is resolved by the assembler (no relocation),
/// one to a local label of another section is relocated against that section's symbol.
#[test]
fn local_references_resolve_or_name_the_section() {
    let obj = object(
        "\t.text\nstart:\tbr\tnext\nnext:\tila\t$3, value\n\tbr\tstart\n\t.data\n\t.long\t0\nvalue:\t.long\t1\n",
    );
    let text = &obj.sections[0];
    assert_eq!(&text.data[0..4], &0x3200_0080u32.to_be_bytes()); // br +4
    assert_eq!(&text.data[8..12], &0x327f_ff00u32.to_be_bytes()); // br -8
    assert_eq!(text.relocs.len(), 1);
    assert_eq!(text.relocs[0].kind, R_SPU_ADDR18);
    assert_eq!(text.relocs[0].target, RelocTarget::Section(1));
    assert_eq!(text.relocs[0].addend, 4);
}

/// Linking the objects of two sources gives the program that assembling them as one
/// source gives (the same layout rules), with symbols resolved across the objects.
#[test]
fn linked_objects_equal_one_assembly() {
    let a = "\t.text\n\t.global _start\n_start:\tbrsl\t$lr, f\n\tila\t$4, tab\n\tlqa\t$5, tab\n\tstop\t0x2000\n\t.data\ntab:\t.long\tf, 2, 3, 4\n";
    let b = "\t.text\n\t.global f\nf:\tai\t$3, $3, 1\n\tbi\t$lr\n";
    let linked = link(&[object(a), object(b)], &LinkOptions::default()).unwrap();
    // As one source: a's text, b's text, then a's data (b has none).
    let one = format!("{a}\t.text\n{}", b.replace("\t.text\n", ""));
    let out = assemble(&one, "one.s", &Options::default()).unwrap();
    assert_eq!(linked.image, out.image);
    assert_eq!(linked.entry, 0);
    // -Ttext moves everything; the absolute references follow.
    let moved = link(
        &[object(a), object(b)],
        &LinkOptions {
            text_addr: 0x100,
            entry: Some("f".into()),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(moved.entry, 0x110);
    assert_eq!(&moved.image[0x100..0x104], &out.image[0..4]); // brsl is relative
                                                              // ila $4,0x180: the data segment starts at ALIGN(0x80) past the text (0x118), as in
                                                              // GNU ld.
    assert_eq!(&moved.image[0x104..0x108], &0x4200_c004u32.to_be_bytes());
}

/// The data segment starts as GNU ld's SPU script starts it, at `ALIGN(0x80)` past the
/// read-only sections (`DATA_ADDR`), in `spu ld` and single-source `spu as` alike; bss
/// follows the data at its own alignment (GNU ld's: 0x84 here, `_end` at 0x90);
/// `_edata` and `_end` stand at that boundary even when a program has no data at all.
#[test]
fn the_data_segment_starts_at_align_0x80() {
    let src = "\t.text\n\t.global _start\n_start:\tila\t$3, tab\n\tila\t$4, _edata\n\tila\t$5, _end\n\tstop\t0x2000\n\t.section .rodata\nro:\t.long\t1\n\t.data\ntab:\t.long\t2\n\t.section .bss\nb:\t.space\t4\n";
    let linked = link(&[object(src)], &LinkOptions::default()).unwrap();
    let at = |n: &str| linked.symbols.iter().find(|s| s.0 == n).unwrap().1;
    let sect = |n: &str| linked.sections.iter().find(|s| s.0 == n).unwrap().1;
    // text 0..0x10, .rodata at 0x10 (4 bytes), then data at 0x80 (not 0x20).
    assert_eq!(
        (sect(".rodata"), sect(".data"), sect(".bss")),
        (0x10, 0x80, 0x84)
    );
    assert_eq!((at("tab"), at("_edata"), at("_end")), (0x80, 0x84, 0x90));
    // One source assembled as an executable loads the same bytes (it defines no script
    // symbols, so they are left out of it; it starts its bss on a 16-byte boundary).
    let plain = src.replace("_edata", "0").replace("_end", "0");
    let one = assemble(&plain, "one.s", &Options::default()).unwrap();
    let linked = link(&[object(&plain)], &LinkOptions::default()).unwrap();
    assert_eq!(one.image[..0x84], linked.image[..0x84]);
    assert_eq!(&one.image[0x80..0x84], &2u32.to_be_bytes());
    // No data: `_edata` and `_end` at the aligned boundary past the text.
    let bare =
        "\t.text\n\t.global _start\n_start:\tila\t$4, _edata\n\tila\t$5, _end\n\tstop\t0x2000\n";
    let linked = link(&[object(bare)], &LinkOptions::default()).unwrap();
    let at = |n: &str| linked.symbols.iter().find(|s| s.0 == n).unwrap().1;
    assert_eq!((at("_edata"), at("_end")), (0x80, 0x80));
}

#[test]
fn commons_and_weak_symbols() {
    let a = "\t.text\n\t.global _start\n_start:\tila\t$3, buf\n\tila\t$4, w\n\t.comm\tbuf, 32, 16\n\t.weak\tw\n";
    let b = "\t.comm\tbuf, 64, 16\n";
    let linked = link(&[object(a), object(b)], &LinkOptions::default()).unwrap();
    let buf = linked.symbols.iter().find(|s| s.0 == "buf").unwrap().1;
    assert_eq!(buf % 16, 0);
    let bss = linked.sections.iter().find(|s| s.0 == ".bss").unwrap();
    assert_eq!(bss.2, 64, "the larger common wins");
    // An undefined weak symbol is 0.
    assert_eq!(&linked.image[4..8], &0x4200_0004u32.to_be_bytes());
}

#[test]
fn objects_for_other_machines_are_refused() {
    let mut elf = object("nop\n").to_elf().unwrap();
    elf[19] = 21; // EM_PPC64
    let e = Object::from_elf("ppu.o", &elf).unwrap_err();
    assert!(e.contains("ppu.o: ELF machine 21 is not SPU (23)"), "{e}");
    assert!(Object::from_elf("x.o", b"\x7fELF\x02\x01").is_err());
    assert!(Object::from_elf("x.o", &elf[..40]).is_err());
}

#[test]
fn expressions_of_100000_terms_or_parentheses() {
    let n = 100_000;
    let deep = format!("il $3, {}1{}\n", "(".repeat(n), ")".repeat(n));
    let out = assemble(&deep, "t.s", &Options::default()).unwrap();
    assert_eq!(&out.image[0..4], &0x4080_0083u32.to_be_bytes());
    let long = format!(".long {}\n", vec!["1"; n].join("+"));
    let out = assemble(&long, "t.s", &Options::default()).unwrap();
    assert_eq!(&out.image[0..4], &(n as u32).to_be_bytes());
}

#[test]
fn nested_repetition_stops_at_the_budget() {
    let src = ".rept 1000\n.rept 1000\n.rept 1000\nnop\n.endr\n.endr\n.endr\n";
    let e = errors(src);
    assert!(
        e.iter()
            .any(|m| m.contains("statements after expanding macros, .rept and .irp: stopped")),
        "{e:?}"
    );
}

#[test]
fn diagnostics_are_capped_with_a_count() {
    let src: String = (0..1000).map(|i| format!("frob{i} $1\n")).collect();
    let e = errors(&src);
    assert_eq!(e.len(), 101, "{:?}", &e[..3]);
    assert_eq!(e[100], "and 900 more diagnostics");
}

#[test]
fn latin1_and_utf8_bytes_pass_through() {
    let dir = std::env::temp_dir().join(format!("spu-latin1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("l.s");
    // A Latin-1 comment and string (not UTF-8), then a UTF-8 string.
    let mut bytes = b"# caf\xe9\n.data\n.ascii \"\xe9\"\n".to_vec();
    bytes.extend("\t.ascii \"é\"\n".as_bytes());
    std::fs::write(&path, bytes).unwrap();
    let out = spu_asm::assemble_file(&path, &Options::default()).unwrap();
    let data = out.sections.iter().find(|s| s.0 == ".data").unwrap();
    let at = data.1 as usize;
    assert_eq!(&out.image[at..at + 3], &[0xe9, 0xc3, 0xa9]);
}

#[test]
fn quoted_macro_arguments_and_square_brackets() {
    let out = assemble(
        ".macro ld3 v\n\til $3, \\v\n.endm\n.irp i,1,2\n\tld3 \"(\\i+1)\"\n.endr\n\til $4, [1+2]*2\n",
        "t.s",
        &Options::default(),
    )
    .unwrap();
    let words: Vec<u32> = out.image[..12]
        .chunks(4)
        .map(|c| u32::from_be_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(words, [0x4080_0103, 0x4080_0183, 0x4080_0304]);
}

/// Every truncation and many single-byte changes of an object are read or refused
/// without a panic, and whatever is read links or is refused without one either.
#[test]
fn mutated_objects_never_panic() {
    let elf = object(
        "\t.text\n\t.global _start\n_start:\tbrsl\t$lr, ext\n\tila\t$3, d\n\t.data\nd:\t.long\text\n\t.comm\tc, 8\n",
    )
    .to_elf()
    .unwrap();
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut inputs: Vec<Vec<u8>> = (0..elf.len()).map(|n| elf[..n].to_vec()).collect();
    for _ in 0..3000 {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        let mut m = elf.clone();
        let at = (seed as usize) % m.len();
        m[at] = (seed >> 32) as u8;
        inputs.push(m);
    }
    for m in inputs {
        if let Ok(obj) = Object::from_elf("m.o", &m) {
            let _ = link(&[obj], &LinkOptions::default());
        }
    }
}

/// Issue #31: seven lines with `.section .bss` and `.space` gave an object whose section
/// headers ran past the end of the file (the aligned `.bss` offset was reserved but its
/// padding never written). Every header and every section now lies inside the file, and
/// `.bss` sits at its aligned offset with no bytes of its own, as GNU as places it.
#[test]
fn bss_after_text_lies_inside_the_file() {
    let src = ".text\n\
               il $3, 1\n\
               .section .bss\n\
               .p2align 4\n\
               buf: .space 100\n\
               .data\n\
               .byte 1\n";
    assert_eq!(src.lines().count(), 7);
    let obj = object(src);
    let elf = obj.to_elf().unwrap();
    assert_eq!(
        spu_asm::elf_check::layout_errors(&elf),
        Vec::<String>::new()
    );
    let word = |at: usize| u32::from_be_bytes(elf[at..at + 4].try_into().unwrap());
    let shoff = word(32) as usize;
    let shnum = u16::from_be_bytes([elf[48], elf[49]]) as usize;
    assert_eq!(shoff + shnum * 40, elf.len());
    // .text at 52 (4 bytes), .data at 56 (1 byte), .bss at 64 (aligned to 16, NOBITS, its
    // 100 bytes padded to the alignment as every section is).
    let header = |i: usize| {
        let at = shoff + i * 40;
        (word(at + 4), word(at + 16), word(at + 20), word(at + 32))
    };
    assert_eq!(header(1), (1, 52, 4, 1));
    assert_eq!(header(2), (1, 56, 1, 1));
    assert_eq!(header(3), (8, 64, 112, 16));
}

/// tc-spu.c's decisions (md_apply_fix with the generic force-relocation rules): a branch
/// to a global or weak symbol defined in the same file stays a relocation against that
/// symbol, for the linker (another definition may win); one to a local label resolves;
/// an address of a local label is relocated against its section. The object still links
/// into the program one assembly gives.
#[test]
fn global_branches_stay_relocations_against_the_symbol() {
    let src = "\t.globl _start\n\t.text\n_start:\tnop\n\tbr _start\n\tbrsl $0, _start\n\tila $3, _start\n\t.weak w\nw:\tnop\n\tbr w\nl:\tbr l\n\tila $4, l\n\t.data\n\t.long _start, l\n";
    let obj = object(src);
    let text = &obj.sections[0];
    let got: Vec<(u32, u32, RelocTarget, i64)> = text
        .relocs
        .iter()
        .map(|r| (r.offset, r.kind, r.target.clone(), r.addend))
        .collect();
    let sym = |n: &str| RelocTarget::Symbol(n.into());
    assert_eq!(
        got,
        vec![
            (0x4, R_SPU_REL16, sym("_start"), 0),
            (0x8, R_SPU_REL16, sym("_start"), 0),
            (0xc, R_SPU_ADDR18, sym("_start"), 0),
            (0x14, R_SPU_REL16, sym("w"), 0),
            (0x1c, R_SPU_ADDR18, RelocTarget::Section(0), 0x18),
        ]
    );
    // `l: br l` resolved in place: br 0.
    assert_eq!(&text.data[0x18..0x1c], &0x3200_0000u32.to_be_bytes());
    let data: Vec<(u32, u32, RelocTarget, i64)> = obj.sections[1]
        .relocs
        .iter()
        .map(|r| (r.offset, r.kind, r.target.clone(), r.addend))
        .collect();
    assert_eq!(
        data,
        vec![
            (0, R_SPU_ADDR32, sym("_start"), 0),
            (4, R_SPU_ADDR32, RelocTarget::Section(0), 0x18),
        ]
    );
    let linked = link(&[obj], &LinkOptions::default()).unwrap();
    let one = assemble(src, "one.s", &Options::default()).unwrap();
    // The same bytes; `spu as` pads its last section to 16 bytes, GNU ld's layout does not.
    assert_eq!(linked.image[..], one.image[..linked.image.len()]);
    assert!(one.image[linked.image.len()..].iter().all(|b| *b == 0));
}

/// `.symver` (obj-elf.c): a defined symbol gets its versioned alias at the same place and
/// binding (`local`, `hidden` and `remove` as 2.40 reads them); a reference to an
/// undefined one names the versioned symbol; an alias without a version is an error.
#[test]
fn symver_aliases_and_versioned_references() {
    let obj = object(
        "\t.globl f\n\t.text\n\tnop\nf:\tnop\n\t.symver f, f@VERS_1\n\t.symver f, f_h@@VERS_2, hidden\n\t.symver ext, ext@VERS_3\n\tbrsl $0, ext\n",
    );
    let find = |n: &str| obj.symbols.iter().find(|s| s.name == n).cloned();
    let f = find("f").unwrap();
    let v1 = find("f@VERS_1").unwrap();
    assert_eq!(
        (v1.value, v1.section, v1.global, v1.visibility),
        (4, f.section, true, 0)
    );
    let v2 = find("f_h@@VERS_2").unwrap();
    // GNU as 2.40 hides the symbol itself, not the alias, and lists the aliases last first.
    assert_eq!((v2.value, v2.global, v2.visibility), (4, true, 0));
    assert_eq!(f.visibility, 2);
    let order: Vec<&str> = obj
        .symbols
        .iter()
        .map(|s| s.name.as_str())
        .filter(|n| !n.is_empty())
        .collect();
    assert_eq!(order, ["f", "ext@VERS_3", "f_h@@VERS_2", "f@VERS_1"]);
    assert_eq!(
        obj.sections[0].relocs[0].target,
        RelocTarget::Symbol("ext@VERS_3".into())
    );
    assert!(find("ext").is_none());
    assert_eq!(find("ext@VERS_3").unwrap().section, SymSection::Undefined);
    let removed = object("\t.globl g\ng:\tnop\n\t.symver g, g@V, remove\n");
    assert!(removed.symbols.iter().all(|s| s.name != "g"));
    assert!(removed.symbols.iter().any(|s| s.name == "g@V"));
    assert_eq!(
        errors("\t.symver g, gv\ng:\tnop\n"),
        vec!["missing version name in `gv' for symbol `g'".to_string()]
    );
}

/// Which references to symbols of the same file stay relocations, as tc-spu.h decides for
/// overlay-style code (sections `.ov_*` whose calls the linker routes through stubs):
/// `TC_FORCE_RELOCATION` keeps every `brsl`/`brasl` (even to a local label) and a
/// `br`/`bra` to a function; `tc_fix_adjustable` never reduces a function symbol, local
/// or not, to its section's symbol. Other branches to local symbols of the same section
/// are resolved, as before.
#[test]
fn calls_and_function_references_stay_relocations_as_tc_spu_keeps_them() {
    let obj = object(
        "\t.text
\t.type\thelper,@function
helper:\tbi\t$lr
\t.section\t.ov_a,\"ax\",@progbits
\t.type\tlocal_fn,@function
local_fn:\tbi\t$lr
\t.global\tentry
\t.type\tentry,@function
entry:\tbrsl\t$lr,helper
\tbrsl\t$lr,local_fn
\tbrsl\t$lr,.Lhere
.Lhere:\tbr\tlocal_fn
\tbr\t.Lhere
\tbrnz\t$3,local_fn
\tilhu\t$3,local_fn@h
\tiohl\t$3,local_fn@l
\t.4byte\tlocal_fn
",
    );
    let sym = |name: &str| RelocTarget::Symbol(name.to_string());
    let ov = obj.sections.iter().position(|s| s.name == ".ov_a").unwrap();
    let relocs: Vec<(u32, u32, RelocTarget, i64)> = obj.sections[ov]
        .relocs
        .iter()
        .map(|r| (r.offset, r.kind, r.target.clone(), r.addend))
        .collect();
    assert_eq!(
        relocs,
        vec![
            (0x04, R_SPU_REL16, sym("helper"), 0),
            (0x08, R_SPU_REL16, sym("local_fn"), 0),
            // A call to a local label: kept, against the section (the label is no function).
            (0x0c, R_SPU_REL16, RelocTarget::Section(ov), 0x10),
            (0x10, R_SPU_REL16, sym("local_fn"), 0),
            (0x1c, R_SPU_ADDR16_HI, sym("local_fn"), 0),
            (0x20, R_SPU_ADDR16_LO, sym("local_fn"), 0),
            (0x24, R_SPU_ADDR32, sym("local_fn"), 0),
        ]
    );
    let words: Vec<u32> = obj.sections[ov].data[0x14..0x1c]
        .chunks(4)
        .map(|c| u32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    // `br .Lhere` (back one word) and `brnz $3,local_fn` (back six) are resolved here.
    assert_eq!(words, vec![0x327fff80, 0x217ffd03]);
    // The local function is in the symbol table for the relocations to name.
    let local = obj.symbols.iter().find(|s| s.name == "local_fn").unwrap();
    assert_eq!((local.global, local.kind, local.value), (false, 2, 0));
}
