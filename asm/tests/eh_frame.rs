//! Unwind tables for SPU as GNU tools make them. GNU as 2.40 has no `.cfi_*` for spu-elf
//! (tc-spu.h defines no `TARGET_USE_CFIPOP`, so dw2gencfi.c answers every one with "CFI
//! is not supported for this target", as `spu as` does: `tests/asm/bad_input.s`), and
//! spu-gcc, whose configure finds that out, writes `.eh_frame` itself with data
//! directives. This is that output for two functions (spu.h: return column 0 = `$lr`, no
//! `ASM_PREFERRED_EH_DATA_FORMAT`, so the FDE's addresses are absolute 4-byte words):
//! the bytes, the relocation gas leaves and what `spu ld` makes of them.

use spu_asm::link::{link, LinkOptions};
use spu_asm::object::Object;
use spu_asm::reloc::R_SPU_ADDR32;
use spu_asm::{assemble_object, Options, Reloc, RelocTarget};

/// As `spu-gcc -S -fexceptions` writes a leaf function with a 32-byte frame (gcc's
/// dwarf2out `output_call_frame_info` with gas's CFI unavailable), after one other function.
const SOURCE: &str = "\
	.text
	.global	first
	.type	first, @function
first:
	bi	$lr
	.size	first, .-first
	.align	3
	.global	_start
	.type	_start, @function
_start:
.LFB0:
	ai	$sp,$sp,-32
.LCFI0:
	ai	$sp,$sp,32
	stop	0x2000
.LFE0:
	.size	_start, .-_start
	.section	.eh_frame,\"a\",@progbits
.Lframe1:
	.4byte	.LECIE1-.LSCIE1
.LSCIE1:
	.4byte	0x0
	.byte	0x1
	.string	\"\"
	.uleb128 0x1
	.sleb128 -4
	.byte	0x0
	.byte	0xc
	.uleb128 0x1
	.uleb128 0x0
	.align	2
.LECIE1:
.LSFDE1:
	.4byte	.LEFDE1-.LASFDE1
.LASFDE1:
	.4byte	.LASFDE1-.Lframe1
	.4byte	.LFB0
	.4byte	.LFE0-.LFB0
	.byte	0x4
	.4byte	.LCFI0-.LFB0
	.byte	0xe
	.uleb128 0x20
	.align	2
.LEFDE1:
";

/// The table, derived by hand from the DWARF 3 call frame format:
const EH_FRAME: [u8; 40] = [
    // CIE: length 12 (id 4 + version 1 + augmentation "" 1 + code alignment 1 + data
    // alignment 1 + return column 1 + DW_CFA_def_cfa $sp, 0: 3), CIE id 0, version 1,
    0x00, 0x00, 0x00, 0x0c, 0x00, 0x00, 0x00, 0x00, 0x01, //
    // "", code alignment factor 1, data alignment factor -4 (sleb128 0x7c), return
    // address column 0, DW_CFA_def_cfa (0x0c) register 1 offset 0,
    0x00, 0x01, 0x7c, 0x00, 0x0c, 0x01, 0x00, //
    // FDE: length 20 (CIE pointer 4, pc_begin 4, pc_range 4, DW_CFA_advance_loc4 5,
    // DW_CFA_def_cfa_offset 32: 2, one byte to the 4-byte alignment), CIE pointer 0x14
    // (back from the CIE pointer itself to the CIE),
    0x00, 0x00, 0x00, 0x14, 0x00, 0x00, 0x00, 0x14, //
    // pc_begin left zero for R_SPU_ADDR32, pc_range 12 (three instructions),
    0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, //
    // DW_CFA_advance_loc4 (0x04) 4 bytes, DW_CFA_def_cfa_offset (0x0e) 32, padding.
    0x04, 0x00, 0x00, 0x00, 0x04, 0x0e, 0x20, 0x00,
];

#[test]
fn gcc_written_eh_frame_assembles_to_the_bytes_and_relocation_gnu_as_writes() {
    let (obj, warnings) = assemble_object(SOURCE, "t.s", &Options::default()).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let obj = Object::from_elf("t.o", &obj.to_elf().unwrap()).unwrap();
    let text = obj.sections.iter().position(|s| s.name == ".text").unwrap();
    let eh = obj.sections.iter().find(|s| s.name == ".eh_frame").unwrap();
    // SHT_PROGBITS, SHF_ALLOC only, 4-byte aligned (the `.align 2`).
    assert_eq!((eh.ty, eh.flags, eh.align), (1, 2, 4));
    assert_eq!(eh.data, EH_FRAME);
    // `.LFB0` is a local label: gas reduces it to the section symbol, addend its offset
    // (`_start` is 8 bytes in, after `first` and the `.align 3` padding).
    assert_eq!(
        eh.relocs,
        vec![Reloc {
            offset: 0x18,
            kind: R_SPU_ADDR32,
            target: RelocTarget::Section(text),
            addend: 8,
        }]
    );
}

#[test]
fn spu_ld_keeps_eh_frame_loaded_with_the_function_address_in_it() {
    let (obj, _) = assemble_object(SOURCE, "t.s", &Options::default()).unwrap();
    let linked = link(&[obj], &LinkOptions::default()).unwrap();
    let (_, text_at, text_size, _) = linked.sections.iter().find(|s| s.0 == ".text").unwrap();
    let (_, at, size, code) = linked
        .sections
        .iter()
        .find(|s| s.0 == ".eh_frame")
        .unwrap()
        .clone();
    // Read-only data right after the code (at its own 4-byte alignment, as GNU ld puts
    // it), in the loaded image.
    assert_eq!(
        (*text_at, *text_size, at, size, code),
        (0, 0x18, 0x18, 40, false)
    );
    let mut expected = EH_FRAME;
    expected[0x18..0x1c].copy_from_slice(&8u32.to_be_bytes()); // _start's address
    assert_eq!(&linked.image[at as usize..][..40], &expected[..]);
    let start = linked.symbols.iter().find(|s| s.0 == "_start").unwrap();
    assert_eq!(start.1, 8);
}
