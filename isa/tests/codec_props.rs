//! Property tests of the codec: encode/decode round trips for every form, and decoding any
//! word never panics and re-encodes to the bits it uses.

use proptest::prelude::*;
use spu_isa::codec::{decode, decode_ext, encode, operand_values, primary_form_of};
use spu_isa::disasm::{instruction_text, NoSymbols};
use spu_isa::table::{FormInfo, Format, OperandKind, FORMS};

/// Bits of a word that a form's operands occupy.
fn field_mask(kind: OperandKind, format: Format) -> u32 {
    match kind {
        OperandKind::Rt if format == Format::RRR => 0x7f << 21,
        OperandKind::Rt | OperandKind::Rc => 0x7f,
        OperandKind::Ra | OperandKind::ParenRa | OperandKind::Ch | OperandKind::Spr => 0x7f << 7,
        OperandKind::Rb => 0x7f << 14,
        OperandKind::Scale173 | OperandKind::Scale155 => 0xff << 14,
        OperandKind::S10 | OperandKind::S10b | OperandKind::Off14 => 0x3ff << 14,
        OperandKind::S16 | OperandKind::X16 | OperandKind::Abs18 | OperandKind::Rel18 => {
            0xffff << 7
        }
        OperandKind::U18 => 0x3ffff << 7,
        OperandKind::BrInst if format == Format::LBTI => (3 << 14) | 0x7f,
        OperandKind::BrInst => (3 << 23) | 0x7f,
        OperandKind::U14 => 0x3fff,
        _ => 0x7f << 14, // the I7 kinds
    }
}

fn used_mask(form: &FormInfo) -> u32 {
    let opcode = (form.format.opcode_mask() as u32) << 21;
    use spu_isa::Op::*;
    let features = match form.op {
        Bi | Bisl | Iret | Bisled | Bihnz | Bihz | Binz | Biz => 0x30 << 14,
        Sync | Hbr => 0x70 << 14,
        _ => 0,
    };
    form.operands
        .iter()
        .fold(opcode | features, |m, k| m | field_mask(*k, form.format))
}

/// A random operand value in the field's natural range, as an assembler would write it.
fn value_for(kind: OperandKind, raw: u32, pc: u32) -> i64 {
    let r = raw as i64;
    match kind {
        OperandKind::Rt | OperandKind::Ra | OperandKind::Rb | OperandKind::Rc => r & 0x7f,
        OperandKind::ParenRa | OperandKind::Ch | OperandKind::Spr => r & 0x7f,
        OperandKind::Scale173 | OperandKind::Scale155 => r & 0x7f,
        OperandKind::S10 | OperandKind::S10b => (r & 0x3ff) - 512,
        OperandKind::Off14 => ((r & 0x3ff) - 512) * 16,
        OperandKind::S16 => (r & 0xffff) - 32768,
        OperandKind::X16 => r & 0xffff,
        OperandKind::U18 => r & 0x3ffff,
        OperandKind::Abs18 => (r & 0xffff) * 4,
        OperandKind::Rel18 => (pc as i64 + ((r & 0xffff) - 32768) * 4) & 0x3ffff,
        OperandKind::BrInst => (pc as i64 + ((r & 0x1ff) - 256) * 4) & 0xffff_ffff,
        OperandKind::U14 => r & 0x3fff,
        _ => (r & 0x7f) - 64,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    #[test]
    fn every_form_round_trips(form_index in 0..FORMS.len(), raws in proptest::array::uniform4(any::<u32>()), pc_words in 0u32..0x10000) {
        let form = &FORMS[form_index];
        let pc = pc_words * 4;
        let values: Vec<i64> = form.operands.iter().zip(raws).map(|(k, r)| value_for(*k, r, pc)).collect();
        let word = encode(form, &values, pc);
        // The extensions' forms decode with their extension on (and only then).
        let inst = decode_ext(word, spu_isa::Extensions::ALL);
        prop_assert_eq!(decode(word).op == inst.op, form.op.info().ext.is_none());
        prop_assert_eq!(inst.op, form.op, "{} decoded as {:?}", form.mnemonic, inst.op);
        // The same form reads back the same values.
        prop_assert_eq!(operand_values(form, word, pc), values.clone(), "{}", form.mnemonic);
        // The primary form re-encodes the same word.
        let primary = primary_form_of(inst).unwrap();
        let again = encode(primary, &operand_values(primary, word, pc), pc) | ((form.extra as u32) << 14);
        // (A primary form may print fewer fields than an alternate: `stop` drops its code.)
        let mask = used_mask(primary);
        prop_assert_eq!(again & mask, word & mask, "{}", form.mnemonic);
    }

    #[test]
    fn any_word_decodes_and_reencodes_its_used_bits(word in any::<u32>(), pc_words in 0u32..0x10000) {
        let pc = pc_words * 4;
        let inst = decode(word);
        let text = instruction_text(word, pc, &NoSymbols);
        prop_assert!(!text.is_empty());
        if let Some(form) = primary_form_of(inst) {
            let features = word & used_mask(form) & (0x70 << 14);
            let again = encode(form, &operand_values(form, word, pc), pc) | features;
            prop_assert_eq!(again, word & used_mask(form), "{} {:#010x}", form.mnemonic, word);
        }
    }
}

/// Every top-11-bit pattern with a few field patterns: decoding is total.
#[test]
fn every_opcode_pattern_decodes() {
    let mut known = 0;
    for top in 0u32..2048 {
        for low in [0u32, 0x1f_ffff, 0x15_5555, 0x0a_aaaa] {
            let word = (top << 21) | low;
            let inst = decode(word);
            let _ = instruction_text(word, 0x100, &NoSymbols);
            if inst.op != spu_isa::Op::Unknown {
                known += 1;
            }
        }
    }
    assert!(known > 0);
}
