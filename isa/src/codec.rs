//! Binary encoding and decoding of SPU instruction words, derived from the table.
//!
//! Decoding goes through a 2048-entry table indexed by the word's top 11 bits (as RPCS3's
//! `spu_decoder` does); the table is built at compile time to reproduce the lookup order
//! of the GNU binutils disassembler (RRR first, then RI18/LBT, RI10, RI16, RI8, and finally
//! the full 11-bit opcode), so that the simulator and the disassembler agree on what every
//! one of the 2^32 words means. Decoding never fails: a word that matches nothing decodes
//! to [`Op::Unknown`] carrying the word.

use crate::ext::{Extension, Extensions};
use crate::table::{FormInfo, Format, Op, OperandKind, FORMS, OP_INFO};

/// A decoded instruction: its operation and its fields, pre-extracted for the interpreter.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Inst {
    /// The operation this instruction word encodes.
    pub op: Op,
    /// Destination register: bits 21..27 for RRR, bits 0..6 otherwise.
    pub rt: u8,
    /// Bits 7..13: register, channel or SPR number.
    pub ra: u8,
    /// Bits 14..20: register (RR, RRR); for indirect branches the feature bits.
    pub rb: u8,
    /// RRR only: the third source, bits 0..6.
    pub rc: u8,
    /// The format's immediate: I7, I10, I16 sign-extended; I8, I18, and the RR stop code
    /// (bits 0..13) zero-extended; 0 for RRR and LBTI.
    pub imm: i32,
    /// The original word.
    pub word: u32,
}

const fn sext(value: u32, bits: u32) -> i32 {
    ((value << (32 - bits)) as i32) >> (32 - bits)
}

impl Inst {
    /// Bits 7..22 unsigned (`ilh`, `fsmbi`, `iohl`, absolute addresses).
    #[inline]
    pub const fn u16(self) -> u32 {
        (self.word >> 7) & 0xffff
    }

    /// The hinted branch's offset from the hint, in words (9 bits, signed).
    #[inline]
    pub const fn hint_offset(self) -> i32 {
        let high = if matches!(self.op, Op::Hbr) {
            (self.word >> 14) & 3
        } else {
            (self.word >> 23) & 3
        };
        sext((high << 7) | (self.word & 0x7f), 9)
    }

    /// The 7-bit feature field of RR branches: D (0x20), E (0x10), `syncc`/`hbrp` (0x40).
    #[inline]
    pub const fn feature_bits(self) -> u8 {
        ((self.word >> 14) & 0x7f) as u8
    }

    /// The instruction format (field layout) of this instruction's operation.
    pub const fn format(self) -> Format {
        self.op.info().format
    }
}

const fn build_primary() -> [Op; 2048] {
    let mut primary = [Op::Unknown; 2048];
    let mut i = 0;
    while i < Op::ALL.len() {
        let op = Op::ALL[i];
        let o = OP_INFO[op as usize].opcode11 as usize;
        // The extensions' rows decode through [`EXT_DECODE_TABLE`] only.
        if matches!(primary[o], Op::Unknown) && OP_INFO[op as usize].ext.is_none() {
            primary[o] = op;
        }
        i += 1;
    }
    primary
}

const fn format_of(op: Op) -> Format {
    OP_INFO[op as usize].format
}

const fn build_decode_table() -> [Op; 2048] {
    let primary = build_primary();
    let mut table = [Op::Unknown; 2048];
    let mut i = 0;
    while i < 2048 {
        let rrr = primary[i & 0x780];
        let ri18 = primary[i & 0x7f0];
        let ri10 = primary[i & 0x7f8];
        let ri16 = primary[i & 0x7fc];
        let ri8 = primary[i & 0x7fe];
        table[i] = if !matches!(rrr, Op::Unknown) && matches!(format_of(rrr), Format::RRR) {
            rrr
        } else if !matches!(ri18, Op::Unknown)
            && matches!(format_of(ri18), Format::RI18 | Format::LBT)
        {
            ri18
        } else if !matches!(ri10, Op::Unknown) && matches!(format_of(ri10), Format::RI10) {
            ri10
        } else if !matches!(ri16, Op::Unknown) && matches!(format_of(ri16), Format::RI16) {
            ri16
        } else if !matches!(ri8, Op::Unknown) && matches!(format_of(ri8), Format::RI8) {
            ri8
        } else {
            primary[i]
        };
        i += 1;
    }
    table
}

/// The operation of every possible top-11-bit value.
pub static DECODE_TABLE: [Op; 2048] = build_decode_table();

const fn build_ext_table() -> [Op; 2048] {
    let mut table = [Op::Unknown; 2048];
    let mut k = 0;
    while k < Op::ALL.len() {
        let info = &OP_INFO[Op::ALL[k] as usize];
        if info.ext.is_some() {
            let mut i = 0;
            while i < 2048 {
                if i as u16 & info.format.opcode_mask() == info.opcode11 {
                    table[i] = info.op;
                }
                i += 1;
            }
        }
        k += 1;
    }
    table
}

/// The extension operation of every top-11-bit value where [`DECODE_TABLE`] has none (a
/// test over the table shows the two never overlap: no real opcode decodes there).
pub static EXT_DECODE_TABLE: [Op; 2048] = build_ext_table();

/// Decodes one instruction word as the real SPU does. Never fails; see [`Op::Unknown`]
/// (the extensions' words are unknown here: [`decode_ext`]).
#[inline]
pub fn decode(word: u32) -> Inst {
    fields(DECODE_TABLE[(word >> 21) as usize], word)
}

/// Decodes one instruction word with the extensions `ext` on: a word of an extension that
/// is off stays [`Op::Unknown`], as on the real SPU.
#[inline]
pub fn decode_ext(word: u32, ext: Extensions) -> Inst {
    let inst = decode(word);
    if inst.op != Op::Unknown || ext.is_none() {
        return inst;
    }
    match extension_of(word) {
        Some(e) if ext.enables(e) => fields(EXT_DECODE_TABLE[(word >> 21) as usize], word),
        _ => inst,
    }
}

/// The extension whose instruction `word` is, if it is one (messages name it when the
/// word is met with that extension off).
pub fn extension_of(word: u32) -> Option<Extension> {
    EXT_DECODE_TABLE[(word >> 21) as usize].info().ext
}

#[inline(always)]
fn fields(op: Op, word: u32) -> Inst {
    let low7 = (word & 0x7f) as u8;
    let ra = ((word >> 7) & 0x7f) as u8;
    let rb = ((word >> 14) & 0x7f) as u8;
    let (rt, rc, imm) = match format_of(op) {
        Format::RRR => (((word >> 21) & 0x7f) as u8, low7, 0),
        Format::RR => (low7, 0, (word & 0x3fff) as i32),
        Format::RI7 => (low7, 0, sext((word >> 14) & 0x7f, 7)),
        Format::RI8 => (low7, 0, ((word >> 14) & 0xff) as i32),
        Format::RI10 => (low7, 0, sext((word >> 14) & 0x3ff, 10)),
        Format::RI16 | Format::LBT => (low7, 0, sext((word >> 7) & 0xffff, 16)),
        Format::RI18 => (low7, 0, ((word >> 7) & 0x3ffff) as i32),
        Format::LBTI => (low7, 0, 0),
    };
    Inst {
        op,
        rt,
        ra,
        rb,
        rc,
        imm,
        word,
    }
}

/// The form a disassembler prints for a word: the operation's first listed form.
pub fn primary_form_of(inst: Inst) -> Option<&'static FormInfo> {
    if inst.op == Op::Unknown {
        None
    } else {
        crate::table::primary_form(inst.op)
    }
}

fn hint_field(format: Format, offset_words: u32) -> u32 {
    let off = offset_words & 0x1ff;
    let high = (off >> 7) & 3;
    let low = off & 0x7f;
    match format {
        Format::LBTI => (high << 14) | low,
        _ => (high << 23) | low,
    }
}

/// Packs operand values, given as an assembler writes them (register numbers, byte
/// offsets, absolute target addresses), into a word for `form` at address `pc`.
///
/// This only places bits: each value is truncated to its field. Range checks and their
/// diagnostics belong to the assembler (see [`OperandKind`] and `../shared/isa/README.md`).
/// Missing operands encode as zero.
pub fn encode(form: &FormInfo, operands: &[i64], pc: u32) -> u32 {
    let mut word = form.base_word();
    for (i, kind) in form.operands.iter().enumerate() {
        let v = operands.get(i).copied().unwrap_or(0);
        let u = v as u32;
        word |= match kind {
            OperandKind::Rt if form.format == Format::RRR => (u & 0x7f) << 21,
            OperandKind::Rt | OperandKind::Rc => u & 0x7f,
            OperandKind::Ra | OperandKind::ParenRa | OperandKind::Ch | OperandKind::Spr => {
                (u & 0x7f) << 7
            }
            OperandKind::Rb => (u & 0x7f) << 14,
            OperandKind::S7
            | OperandKind::S6
            | OperandKind::S3
            | OperandKind::S7n
            | OperandKind::U3
            | OperandKind::U5
            | OperandKind::U6
            | OperandKind::U7 => (u & 0x7f) << 14,
            OperandKind::Scale173 => ((173i64 - v) as u32 & 0xff) << 14,
            OperandKind::Scale155 => ((155i64 - v) as u32 & 0xff) << 14,
            OperandKind::S10 | OperandKind::S10b => (u & 0x3ff) << 14,
            OperandKind::Off14 => (((v >> 4) as u32) & 0x3ff) << 14,
            OperandKind::S16 | OperandKind::X16 => (u & 0xffff) << 7,
            OperandKind::U18 => (u & 0x3ffff) << 7,
            OperandKind::Abs18 => (((v >> 2) as u32) & 0xffff) << 7,
            OperandKind::Rel18 => ((((v - pc as i64) >> 2) as u32) & 0xffff) << 7,
            OperandKind::BrInst => hint_field(form.format, ((v - pc as i64) >> 2) as u32),
            OperandKind::U14 => u & 0x3fff,
        };
    }
    word
}

/// Recovers the assembler-level operand values of `word` read as `form` at `pc`: the
/// inverse of [`encode`] up to field truncation (immediates come back sign-extended where
/// the disassembler prints them signed; addresses come back absolute).
pub fn operand_values(form: &FormInfo, word: u32, pc: u32) -> Vec<i64> {
    form.operands
        .iter()
        .map(|kind| operand_value(*kind, form.format, word, pc))
        .collect()
}

/// One operand's value; see [`operand_values`].
pub fn operand_value(kind: OperandKind, format: Format, word: u32, pc: u32) -> i64 {
    let field = |shift: u32, bits: u32| (word >> shift) & ((1u32 << bits) - 1);
    match kind {
        OperandKind::Rt if format == Format::RRR => field(21, 7) as i64,
        OperandKind::Rt | OperandKind::Rc => field(0, 7) as i64,
        OperandKind::Ra | OperandKind::ParenRa | OperandKind::Ch | OperandKind::Spr => {
            field(7, 7) as i64
        }
        OperandKind::Rb => field(14, 7) as i64,
        OperandKind::S7
        | OperandKind::S6
        | OperandKind::S3
        | OperandKind::S7n
        | OperandKind::U3
        | OperandKind::U5
        | OperandKind::U6
        | OperandKind::U7 => sext(field(14, 7), 7) as i64,
        OperandKind::Scale173 => 173 - field(14, 8) as i64,
        OperandKind::Scale155 => 155 - field(14, 8) as i64,
        OperandKind::S10 | OperandKind::S10b => sext(field(14, 10), 10) as i64,
        OperandKind::Off14 => sext(field(14, 10), 10) as i64 * 16,
        OperandKind::S16 => sext(field(7, 16), 16) as i64,
        OperandKind::X16 => field(7, 16) as i64,
        OperandKind::U18 => field(7, 18) as i64,
        OperandKind::Abs18 => field(7, 16) as i64 * 4,
        OperandKind::Rel18 => (pc as i64 + sext(field(7, 16), 16) as i64 * 4) & 0x3ffff,
        OperandKind::BrInst => {
            let high = if format == Format::LBTI {
                field(14, 2)
            } else {
                field(23, 2)
            };
            let off = sext((high << 7) | field(0, 7), 9) as i64;
            (pc as i64 + off * 4) & 0xffff_ffff
        }
        OperandKind::U14 => field(0, 14) as i64,
    }
}

/// Every form of the table, for tests and tools that enumerate the instruction set.
pub fn all_forms() -> &'static [FormInfo] {
    FORMS
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::forms_named;

    fn form(m: &str) -> &'static FormInfo {
        forms_named(m).next().unwrap()
    }

    #[test]
    fn pinned_encodings_one_per_format() {
        // RRR: fma rt,ra,rb,rc with rt in bits 21..27 (../shared/isa/README.md).
        assert_eq!(encode(form("fma"), &[7, 6, 5, 4], 0), 0xe0e14304);
        // RR with feature bits: bi $3 and bid $3.
        assert_eq!(encode(form("bi"), &[3], 0), 0x35000180);
        assert_eq!(encode(form("bid"), &[3], 0), 0x35080180);
        // RI16, RI10 with the /16 offset, RI18, RI8 scale, RI7 negative.
        assert_eq!(encode(form("il"), &[3, 42], 0), 0x40801503);
        assert_eq!(encode(form("lqd"), &[5, 32, 1], 0), 0x34008085);
        assert_eq!(encode(form("ila"), &[4, 0x3ffff], 0), 0x43ffff84);
        assert_eq!(encode(form("cflts"), &[4, 5, 10], 0), 0x7628c284);
        assert_eq!(encode(form("rotmi"), &[3, 4, -7], 0), 0x0f3e4203);
        // Relative branch backwards, hint forms (LBT and LBTI).
        assert_eq!(encode(form("br"), &[0], 0x58), 0x327ff500);
        assert_eq!(encode(form("hbrr"), &[0xa4, 0], 0x68), 0x127ff30f);
        assert_eq!(encode(form("hbr"), &[0xa4, 0], 0x70), 0x3580000d);
    }

    #[test]
    fn decode_fields() {
        let i = decode(0xe0e14304);
        assert_eq!((i.op, i.rt, i.ra, i.rb, i.rc), (Op::Fma, 7, 6, 5, 4));
        let i = decode(0x40fffd83); // il $3,-5
        assert_eq!((i.op, i.rt, i.imm), (Op::Il, 3, -5));
        let i = decode(0x127ff30f);
        assert_eq!(i.op, Op::Hbrr);
        assert_eq!(i.hint_offset(), (0xa4 - 0x68) / 4);
        assert_eq!(decode(0x00f00000).op, Op::Unknown);
        assert_eq!(decode(0x35080180).feature_bits(), 0x20);
    }

    #[test]
    fn decode_prefers_the_first_table_form() {
        // mtspr and syscall share an opcode; mtspr comes first.
        assert_eq!(decode(encode(form("syscall"), &[1, 2, 3], 0)).op, Op::Mtspr);
        assert_eq!(primary_form_of(decode(0x04000285)).unwrap().mnemonic, "ori");
    }

    /// The extensions' opcodes lie where no real operation decodes, in every word they
    /// cover; there, the real SPU's decoding is `Unknown` and only [`decode_ext`] with the
    /// extension on finds them.
    #[test]
    fn extension_opcodes_are_unused_by_the_real_isa() {
        let mut covered = 0;
        for i in 0..2048usize {
            if EXT_DECODE_TABLE[i] != Op::Unknown {
                covered += 1;
                assert_eq!(DECODE_TABLE[i], Op::Unknown, "top bits {i:#x}");
            }
        }
        assert_eq!(covered, 2);
        for op in crate::table::real_ops() {
            let info = op.info();
            for i in 0..2048u16 {
                if i & info.format.opcode_mask() == info.opcode11 {
                    assert_eq!(EXT_DECODE_TABLE[i as usize], Op::Unknown, "{}", info.name);
                }
            }
        }
        let w = encode(form("lgwx"), &[3, 4, 5], 0);
        assert_eq!(w, 0x38c14203);
        assert_eq!(decode(w).op, Op::Unknown);
        assert_eq!(decode_ext(w, Extensions::NONE).op, Op::Unknown);
        let multihint_only = Extensions::parse("multihint=2").unwrap();
        assert_eq!(decode_ext(w, multihint_only).op, Op::Unknown);
        let i = decode_ext(w, Extensions::parse("gather").unwrap());
        assert_eq!((i.op, i.rt, i.ra, i.rb), (Op::Lgwx, 3, 4, 5));
        assert_eq!(extension_of(w), Some(Extension::Gather));
        assert_eq!(extension_of(0x00f00000), None);
        let w = encode(form("lgw"), &[3, 4], 0);
        assert_eq!(w, 0x38a00203);
        assert_eq!(decode_ext(w, Extensions::ALL).op, Op::Lgw);
    }
}
