//! SPU relocations: their numbers (binutils `include/elf/spu.h`) and how each one puts a
//! value into an instruction or a word (`bfd/elf32-spu.c` howto table), shared by the
//! assembler (`.reloc` in an executable) and the linker.

pub const R_SPU_NONE: u32 = 0;
pub const R_SPU_ADDR10: u32 = 1;
pub const R_SPU_ADDR16: u32 = 2;
pub const R_SPU_ADDR16_HI: u32 = 3;
pub const R_SPU_ADDR16_LO: u32 = 4;
pub const R_SPU_ADDR18: u32 = 5;
pub const R_SPU_ADDR32: u32 = 6;
pub const R_SPU_REL16: u32 = 7;
pub const R_SPU_ADDR7: u32 = 8;
pub const R_SPU_REL9: u32 = 9;
pub const R_SPU_REL9I: u32 = 10;
pub const R_SPU_ADDR10I: u32 = 11;
pub const R_SPU_ADDR16I: u32 = 12;
pub const R_SPU_REL32: u32 = 13;
pub const R_SPU_ADDR16X: u32 = 14;
pub const R_SPU_PPU32: u32 = 15;
pub const R_SPU_PPU64: u32 = 16;
pub const R_SPU_ADD_PIC: u32 = 17;

const NAMES: &[(u32, &str)] = &[
    (R_SPU_NONE, "R_SPU_NONE"),
    (R_SPU_ADDR10, "R_SPU_ADDR10"),
    (R_SPU_ADDR16, "R_SPU_ADDR16"),
    (R_SPU_ADDR16_HI, "R_SPU_ADDR16_HI"),
    (R_SPU_ADDR16_LO, "R_SPU_ADDR16_LO"),
    (R_SPU_ADDR18, "R_SPU_ADDR18"),
    (R_SPU_ADDR32, "R_SPU_ADDR32"),
    (R_SPU_REL16, "R_SPU_REL16"),
    (R_SPU_ADDR7, "R_SPU_ADDR7"),
    (R_SPU_REL9, "R_SPU_REL9"),
    (R_SPU_REL9I, "R_SPU_REL9I"),
    (R_SPU_ADDR10I, "R_SPU_ADDR10I"),
    (R_SPU_ADDR16I, "R_SPU_ADDR16I"),
    (R_SPU_REL32, "R_SPU_REL32"),
    (R_SPU_ADDR16X, "R_SPU_ADDR16X"),
    (R_SPU_PPU32, "R_SPU_PPU32"),
    (R_SPU_PPU64, "R_SPU_PPU64"),
    (R_SPU_ADD_PIC, "R_SPU_ADD_PIC"),
];

/// The name of a relocation number.
pub fn name(kind: u32) -> Option<&'static str> {
    NAMES.iter().find(|n| n.0 == kind).map(|n| n.1)
}

/// A relocation as `.reloc` names it in spu-elf-as: the howto name (`SPU_ADDR32`, the ELF
/// name without `R_`) or one of the generic BFD names (`BFD_RELOC_32`).
pub fn by_name(text: &str) -> Option<u32> {
    let upper = text.trim().to_ascii_uppercase();
    if let Some(n) = NAMES
        .iter()
        .find(|n| n.1.strip_prefix("R_") == Some(upper.as_str()))
    {
        return Some(n.0);
    }
    Some(match upper.as_str() {
        "BFD_RELOC_NONE" => R_SPU_NONE,
        "BFD_RELOC_32" => R_SPU_ADDR32,
        _ => return None,
    })
}

/// How an instruction field takes a relocated value: right shift, width, position, and
/// whether overflow is checked (signed, or either signed or unsigned as BFD's
/// "bitfield"), per the howto table.
#[derive(Clone, Copy)]
enum Check {
    None,
    Signed,
    Bitfield,
}

fn field(kind: u32) -> Option<(u32, u32, u32, Check, bool)> {
    // (rshift, bits, bit position, check, pc-relative)
    Some(match kind {
        R_SPU_ADDR10 => (4, 10, 14, Check::Bitfield, false),
        R_SPU_ADDR16 => (2, 16, 7, Check::Bitfield, false),
        R_SPU_ADDR16_HI => (16, 16, 7, Check::None, false),
        R_SPU_ADDR16_LO => (0, 16, 7, Check::None, false),
        R_SPU_ADDR18 => (0, 18, 7, Check::Bitfield, false),
        R_SPU_REL16 => (2, 16, 7, Check::Bitfield, true),
        R_SPU_ADDR7 => (0, 7, 14, Check::None, false),
        R_SPU_ADDR10I => (0, 10, 14, Check::Signed, false),
        R_SPU_ADDR16I => (0, 16, 7, Check::Signed, false),
        R_SPU_ADDR16X => (0, 16, 7, Check::Bitfield, false),
        _ => return None,
    })
}

/// Puts `value` (S + A) into the 4 (or 8) bytes at `at` of `bytes` (which start at
/// address 0 of the local store, so `at` is also P) as relocation `kind` does.
pub fn apply(kind: u32, bytes: &mut [u8], at: u32, value: i64) -> Result<(), String> {
    let p = at as i64;
    let size = if kind == R_SPU_PPU64 { 8 } else { 4 };
    let Some(place) = bytes.get_mut(at as usize..at as usize + size) else {
        return Err(format!(
            "relocation {} at {at:#x} is outside its section",
            name(kind).unwrap_or("?")
        ));
    };
    let mut word = u32::from_be_bytes([place[0], place[1], place[2], place[3]]);
    let overflow = || {
        format!(
            "relocation truncated to fit: {} (value {value:#x})",
            name(kind).unwrap_or("?")
        )
    };
    match kind {
        R_SPU_NONE | R_SPU_PPU32 | R_SPU_PPU64 | R_SPU_ADD_PIC => return Ok(()),
        R_SPU_ADDR32 => word = value as u32,
        R_SPU_REL32 => word = (value - p) as u32,
        R_SPU_REL9 | R_SPU_REL9I => {
            let v = (value - p) >> 2;
            if !(-256..=255).contains(&v) {
                return Err(overflow());
            }
            let v = v as u32;
            let high = if kind == R_SPU_REL9 { 23 } else { 14 };
            let mask = 0x7f | (3 << high);
            word = (word & !mask) | (v & 0x7f) | (((v >> 7) & 3) << high);
        }
        _ => {
            let Some((shift, bits, pos, check, pcrel)) = field(kind) else {
                return Err(format!("unsupported relocation type {kind}"));
            };
            let v = if pcrel { value - p } else { value } >> shift;
            let fits = match check {
                Check::None => true,
                Check::Signed => (-(1i64 << (bits - 1))..(1i64 << (bits - 1))).contains(&v),
                Check::Bitfield => (-(1i64 << (bits - 1))..(1i64 << bits)).contains(&v),
            };
            if !fits {
                return Err(overflow());
            }
            let mask = ((1u32 << bits) - 1) << pos;
            word = (word & !mask) | (((v as u32) << pos) & mask);
        }
    }
    place[..4].copy_from_slice(&word.to_be_bytes());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn put(kind: u32, word: u32, at: u32, value: i64) -> Result<u32, String> {
        let mut bytes = vec![0u8; at as usize + 4];
        bytes[at as usize..].copy_from_slice(&word.to_be_bytes());
        apply(kind, &mut bytes, at, value)?;
        let w = &bytes[at as usize..];
        Ok(u32::from_be_bytes([w[0], w[1], w[2], w[3]]))
    }

    #[test]
    fn fields_match_the_encoder() {
        // brsl $lr,0x100 at 0x40: I16 = (0x100-0x40)>>2 = 0x30 -> 0x33001800.
        assert_eq!(put(R_SPU_REL16, 0x3300_0000, 0x40, 0x100), Ok(0x3300_1800));
        // ila $3,0x12345: I18 at bit 7.
        assert_eq!(put(R_SPU_ADDR18, 0x4200_0003, 0, 0x12345), Ok(0x4291_a283));
        // lqa $8,0x100: I16 = 0x40.
        assert_eq!(put(R_SPU_ADDR16, 0x3080_0008, 0, 0x100), Ok(0x3080_2008));
        // lqd $5,32($1): I10 = 2.
        assert_eq!(put(R_SPU_ADDR10, 0x3400_0085, 0, 32), Ok(0x3400_8085));
        assert_eq!(
            put(R_SPU_ADDR16_HI, 0x4180_0003, 0, 0x12345),
            Ok(0x4180_0083)
        );
        assert_eq!(
            put(R_SPU_ADDR16_LO, 0x6080_0003, 0, 0x12345),
            Ok(0x6091_a283)
        );
        assert_eq!(put(R_SPU_ADDR32, 0, 0, 0xdead_beef), Ok(0xdead_beef));
        // hbr at 0: brinst (0x40) -> low 7 bits 0x10 at 0, high 2 bits at 23.
        assert_eq!(put(R_SPU_REL9, 0x1000_0000, 0, 0x40), Ok(0x1000_0010));
        assert_eq!(put(R_SPU_REL9I, 0x1000_0000, 0, -4), Ok(0x1000_c07f));
    }

    #[test]
    fn overflow_is_an_error() {
        assert!(put(R_SPU_ADDR10I, 0, 0, 600).is_err());
        assert!(put(R_SPU_REL16, 0, 0, 0x4_0000).is_err());
        assert!(apply(R_SPU_ADDR32, &mut [0; 8], 6, 0).is_err());
    }
}
