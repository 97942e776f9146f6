//! Disassembly text in the form GNU objdump prints for SPU.
//!
//! The conventions follow binutils' SPU disassembler exactly: the first table form of an
//! encoding is printed; indirect branches, `sync` and `hbr` get `d`/`e`/`p`/`c` suffixes
//! from their feature bits; registers print as `$N`, channels `$chN`, SPRs `$spN`;
//! branch and hint targets print as addresses (`a4 <y>`), a zero relative offset as `0`;
//! `ila` prints an address only when a symbol sits at address 0; a decimal immediate
//! above 16, or a relative branch target above 16, is followed by a `# hex` comment;
//! unknown words print as `.long 0x...`.

use crate::codec::{decode_ext, operand_value};
use crate::ext::Extensions;
use crate::table::{Op, OperandKind};

/// Names addresses for the disassembler.
pub trait Symbolizer {
    /// The symbol objdump would name `addr` after: the nearest one at or below it, else
    /// the first one above it. Returns the symbol's name and address.
    fn symbol_for(&self, addr: u32) -> Option<(&str, u32)>;
    /// Whether a symbol is defined exactly at `addr`.
    fn has_symbol_at(&self, addr: u32) -> bool;
    /// What precedes a bare address: objdump writes `0x38` when the file has no
    /// symbols at all (a raw image), `38` otherwise.
    fn address_prefix(&self) -> &'static str {
        ""
    }
    /// A branch or load target as objdump prints it: hex without `0x`, then `<sym>` or
    /// `<sym+0xoff>`.
    fn address_text(&self, addr: u32) -> String {
        match self.symbol_for(addr) {
            None => format!("{}{addr:x}", self.address_prefix()),
            Some((name, at)) if at == addr => format!("{addr:x} <{name}>"),
            Some((name, at)) if at < addr => format!("{addr:x} <{name}+0x{:x}>", addr - at),
            Some((name, at)) => format!("{addr:x} <{name}-0x{:x}>", at - addr),
        }
    }
}

/// No symbols: addresses print as bare hex.
pub struct NoSymbols;

impl Symbolizer for NoSymbols {
    fn symbol_for(&self, _: u32) -> Option<(&str, u32)> {
        None
    }
    fn has_symbol_at(&self, _: u32) -> bool {
        false
    }
}

/// Symbols sorted by address, for ELF files.
#[derive(Clone, Debug, Default)]
pub struct SymbolTable {
    symbols: Vec<(u32, String)>,
}

impl SymbolTable {
    /// A table of `(local-store address, name)` symbols, sorted by address here.
    pub fn new(symbols: Vec<(u32, String)>) -> Self {
        Self::ranked(symbols.into_iter().map(|(a, n)| (a, n, 0)).collect())
    }

    /// Symbols with a preference: where several share an address, the lowest rank names
    /// it (objdump prefers a section's global symbol to local labels), then the first
    /// name in order.
    pub fn ranked(mut symbols: Vec<(u32, String, u8)>) -> Self {
        symbols.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then_with(|| a.2.cmp(&b.2))
                .then_with(|| a.1.cmp(&b.1))
        });
        symbols.dedup_by(|later, earlier| later.0 == earlier.0);
        SymbolTable {
            symbols: symbols.into_iter().map(|(a, n, _)| (a, n)).collect(),
        }
    }

    /// Symbols defined exactly at `addr`.
    pub fn at(&self, addr: u32) -> impl Iterator<Item = &str> {
        self.symbols
            .iter()
            .filter(move |s| s.0 == addr)
            .map(|s| s.1.as_str())
    }

    /// Whether the table holds no symbols.
    pub fn is_empty(&self) -> bool {
        self.symbols.is_empty()
    }
}

impl Symbolizer for SymbolTable {
    fn symbol_for(&self, addr: u32) -> Option<(&str, u32)> {
        let idx = self.symbols.partition_point(|s| s.0 <= addr);
        let pick = if idx > 0 {
            self.symbols.get(idx - 1)
        } else {
            self.symbols.first()
        };
        pick.map(|s| (s.1.as_str(), s.0))
    }
    fn has_symbol_at(&self, addr: u32) -> bool {
        self.symbols.binary_search_by(|s| s.0.cmp(&addr)).is_ok()
    }
    fn address_prefix(&self) -> &'static str {
        if self.symbols.is_empty() {
            "0x"
        } else {
            ""
        }
    }
}

/// An address as objdump prints it: hex without `0x`, then `<sym>` or `<sym+0xoff>`.
pub fn format_address(addr: u32, symbols: &dyn Symbolizer) -> String {
    symbols.address_text(addr)
}

/// The instruction text of `word` at `pc` (mnemonic, tab, operands, optional comment).
pub fn instruction_text(word: u32, pc: u32, symbols: &dyn Symbolizer) -> String {
    instruction_text_ext(word, pc, symbols, Extensions::NONE)
}

/// [`instruction_text`] with the instructions of the extensions `ext` known (the others'
/// words print as `.long`, as the real SPU's disassembler prints them).
pub fn instruction_text_ext(
    word: u32,
    pc: u32,
    symbols: &dyn Symbolizer,
    ext: Extensions,
) -> String {
    let inst = decode_ext(word, ext);
    let Some(form) = crate::codec::primary_form_of(inst) else {
        return format!(".long 0x{word:x}");
    };
    let mut out = String::from(form.mnemonic);
    if has_feature_suffix(inst.op) {
        let fb = inst.feature_bits();
        if fb & 0x40 != 0 {
            out.push(if inst.op == Op::Sync { 'c' } else { 'p' });
        }
        if fb & 0x20 != 0 {
            out.push('d');
        }
        if fb & 0x10 != 0 {
            out.push('e');
        }
    }
    if !form.operands.is_empty() {
        out.push('\t');
    }
    // binutils remembers the last decimal immediate and prints it in hex when above 16.
    let mut hex_value: i64 = 0;
    for (i, kind) in form.operands.iter().enumerate() {
        let value = operand_value(*kind, form.format, word, pc);
        match kind {
            OperandKind::ParenRa => {
                out.push_str(&format!("(${value})"));
                continue;
            }
            _ if i > 0 => out.push(','),
            _ => {}
        }
        match kind {
            OperandKind::Rt | OperandKind::Ra | OperandKind::Rb | OperandKind::Rc => {
                out.push_str(&format!("${value}"))
            }
            OperandKind::Spr => out.push_str(&format!("$sp{value}")),
            OperandKind::Ch => out.push_str(&format!("$ch{value}")),
            OperandKind::Scale173 | OperandKind::Scale155 => out.push_str(&value.to_string()),
            OperandKind::BrInst => out.push_str(&symbols.address_text(value as u32)),
            OperandKind::Rel18 => {
                if inst.imm == 0 {
                    out.push('0');
                } else {
                    // binutils keeps the unmasked target for the `# hex` comment.
                    hex_value = pc as i64 + (((word << 9) as i32) >> 16) as i64 * 4;
                    out.push_str(&symbols.address_text(value as u32));
                }
            }
            OperandKind::Abs18 => {
                if value == 0 {
                    out.push('0');
                } else {
                    out.push_str(&symbols.address_text(value as u32));
                }
            }
            OperandKind::U18 => {
                if value == 0 || !symbols.has_symbol_at(0) {
                    hex_value = value;
                    out.push_str(&value.to_string());
                } else {
                    out.push_str(&symbols.address_text(value as u32));
                }
            }
            _ => {
                hex_value = value;
                out.push_str(&value.to_string());
            }
        }
    }
    if hex_value > 16 {
        out.push_str(&format!("\t# {hex_value:x}"));
    }
    out
}

fn has_feature_suffix(op: Op) -> bool {
    matches!(
        op,
        Op::Bi
            | Op::Bisl
            | Op::Iret
            | Op::Bisled
            | Op::Bihnz
            | Op::Bihz
            | Op::Binz
            | Op::Biz
            | Op::Sync
            | Op::Hbr
    )
}

/// How many leading hex digits objdump drops from 8-digit addresses for a section that
/// ends at `end`: the leading zeros less one, rounded down to a multiple of 4.
fn skipped_address_chars(end: u32) -> usize {
    let zeros = format!("{end:08x}")
        .bytes()
        .take_while(|b| *b == b'0')
        .count();
    if zeros == 8 {
        4
    } else if zeros == 0 {
        0
    } else {
        (zeros - 1) & !3
    }
}

/// One disassembly line: `   0:\t40 80 15 03 \til\t$3,42\t# 2a`.
pub fn line(word: u32, pc: u32, section_end: u32, symbols: &dyn Symbolizer) -> String {
    line_ext(word, pc, section_end, symbols, Extensions::NONE)
}

/// [`line()`] with the instructions of the extensions `ext` known.
pub fn line_ext(
    word: u32,
    pc: u32,
    section_end: u32,
    symbols: &dyn Symbolizer,
    ext: Extensions,
) -> String {
    let skip = skipped_address_chars(section_end);
    let full = format!("{pc:08x}");
    let digits = &full[skip..];
    let trimmed = digits.trim_start_matches('0');
    let shown = if trimmed.is_empty() { "0" } else { trimmed };
    let b = word.to_be_bytes();
    format!(
        "{shown:>width$}:\t{:02x} {:02x} {:02x} {:02x} \t{}",
        b[0],
        b[1],
        b[2],
        b[3],
        instruction_text_ext(word, pc, symbols, ext),
        width = digits.len()
    )
}

/// Disassembles `bytes` loaded at `base`, with objdump's `<symbol>:` headers where the
/// table has symbols. A trailing partial word is printed as bytes.
pub fn listing(bytes: &[u8], base: u32, symbols: &SymbolTable) -> String {
    listing_ext(bytes, base, symbols, Extensions::NONE)
}

/// [`listing`] with the instructions of the extensions `ext` known.
pub fn listing_ext(bytes: &[u8], base: u32, symbols: &SymbolTable, ext: Extensions) -> String {
    let mut out = String::new();
    let end = base.wrapping_add(bytes.len() as u32);
    for (i, chunk) in bytes.chunks(4).enumerate() {
        let pc = base.wrapping_add(4 * i as u32);
        for name in symbols.at(pc) {
            out.push_str(&format!("\n{pc:08x} <{name}>:\n"));
        }
        if chunk.len() == 4 {
            let word = u32::from_be_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]);
            out.push_str(&line_ext(word, pc, end, symbols, ext));
        } else {
            let hex: Vec<String> = chunk.iter().map(|b| format!("{b:02x}")).collect();
            out.push_str(&format!("{pc:>4x}:\t{} ", hex.join(" ")));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn syms() -> SymbolTable {
        SymbolTable::new(vec![(0, "x".into()), (0xa4, "y".into())])
    }

    #[test]
    fn readme_examples() {
        let s = syms();
        let cases: &[(u32, u32, &str)] = &[
            (0x0, 0x40801503, "il\t$3,42\t# 2a"),
            (0x4, 0x40fffd83, "il\t$3,-5"),
            (0x8, 0x43ffff84, "ila\t$4,3ffff <y+0x3ff5b>"),
            (0x10, 0x60ffff04, "iohl\t$4,65534\t# fffe"),
            (0x18, 0x1cfc0080, "ai\t$0,$1,-16"),
            (0x20, 0x34008085, "lqd\t$5,32($1)\t# 20"),
            (0x28, 0x30802006, "lqa\t$6,100 <y+0x5c>"),
            (0x34, 0x3e810083, "cbd\t$3,4($1)"),
            (0x38, 0xe0e14304, "fma\t$7,$6,$5,$4"),
            (0x48, 0x0f3e4203, "rotmi\t$3,$4,-7"),
            (0x50, 0x7628c284, "cflts\t$4,$5,10"),
            (0x58, 0x327ff500, "br\t0 <x>"),
            (0x68, 0x127ff30f, "hbrr\ta4 <y>,0 <x>"),
            (0x70, 0x3580000d, "hbr\ta4 <y>,$0"),
            (0x7c, 0x01a00c03, "rdch\t$3,$ch24"),
            (0x88, 0x01800103, "mfspr\t$3,$sp2"),
            (0x9c, 0x40200000, "nop\t$0"),
            (0xa0, 0x00002000, "stop"),
            (0xa8, 0x00f00000, ".long 0xf00000"),
        ];
        for (pc, word, text) in cases {
            assert_eq!(instruction_text(*word, *pc, &s), *text, "word {word:#010x}");
        }
    }

    #[test]
    fn feature_suffixes() {
        assert_eq!(instruction_text(0x35080180, 0, &NoSymbols), "bid\t$3");
        assert_eq!(instruction_text(0x35040180, 0, &NoSymbols), "bie\t$3");
        assert_eq!(instruction_text(0x00500000, 0, &NoSymbols), "syncc");
    }

    #[test]
    fn line_format() {
        assert_eq!(
            line(0x40801503, 0, 0xb0, &NoSymbols),
            "   0:\t40 80 15 03 \til\t$3,42\t# 2a"
        );
        assert_eq!(
            line(0x40801503, 0x1000c, 0x12345, &NoSymbols),
            "   1000c:\t40 80 15 03 \til\t$3,42\t# 2a"
        );
    }
}
