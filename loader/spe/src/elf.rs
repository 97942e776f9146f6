//! Reading SPU ELF executables (ELF32, big-endian, `e_machine` 23 = EM_SPU) for the
//! simulator and the disassembler; the assembler (`spu-asm`) writes them. Reading never
//! panics on malformed input; whether the segments can be loaded is [`crate::Program`]'s
//! check.

/// EM_SPU.
pub const EM_SPU: u16 = 23;

/// What the simulator and the disassembler need from an SPU ELF.
#[derive(Clone, Debug, Default)]
pub struct LoadedElf {
    /// The `PT_LOAD` segments: local-store address and bytes (`p_memsz` of them, the
    /// part past `p_filesz` zero).
    pub segments: Vec<(u32, Vec<u8>)>,
    /// (name, address, bytes, is code)
    pub sections: Vec<(String, u32, Vec<u8>, bool)>,
    /// Every defined symbol that names something: (name, value).
    pub symbols: Vec<(String, u32)>,
    /// The same symbols with what objdump weighs when it names an address: whether the
    /// symbol is global (or weak) and whether it is absolute (not in any section).
    pub symbol_kinds: Vec<SymbolKind>,
    /// `e_entry`: where the program starts.
    pub entry: u32,
    /// How many `PF_OVERLAY` segments it has (not among `segments`).
    pub overlays: usize,
}

/// The program header flag of an overlay segment (GNU ld's SPU backend).
pub const PF_OVERLAY: u32 = 0x0800_0000;

/// A symbol with what objdump weighs when it names an address.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SymbolKind {
    /// The symbol's name.
    pub name: String,
    /// Its value.
    pub addr: u32,
    /// Global or weak binding (not local).
    pub global: bool,
    /// Absolute (`SHN_ABS`): in no section.
    pub absolute: bool,
    /// A function or an object (`STT_FUNC`, `STT_OBJECT`), not a bare label.
    pub typed: bool,
}

/// Reads an SPU ELF executable; never panics on malformed input.
pub fn read_elf(bytes: &[u8]) -> Result<LoadedElf, String> {
    let u16_at = |o: usize| {
        bytes
            .get(o..o + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .ok_or("truncated ELF file")
    };
    let u32_at = |o: usize| {
        bytes
            .get(o..o + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or("truncated ELF file")
    };
    if bytes.get(0..4) != Some(&[0x7f, b'E', b'L', b'F']) {
        return Err("not an ELF file".into());
    }
    if bytes.get(4) != Some(&1) || bytes.get(5) != Some(&2) {
        return Err("not a 32-bit big-endian ELF file".into());
    }
    if u16_at(18)? != EM_SPU {
        return Err(format!("ELF machine {} is not SPU (23)", u16_at(18)?));
    }
    let entry = u32_at(24)?;
    let (phoff, shoff) = (u32_at(28)? as usize, u32_at(32)? as usize);
    let (phentsize, phnum) = (u16_at(42)? as usize, u16_at(44)? as usize);
    let (shentsize, shnum, shstrndx) = (
        u16_at(46)? as usize,
        u16_at(48)? as usize,
        u16_at(50)? as usize,
    );
    let slice = |off: u32, size: u32| -> Result<&[u8], String> {
        bytes
            .get(
                off as usize
                    ..(off as usize)
                        .checked_add(size as usize)
                        .ok_or("bad size")?,
            )
            .ok_or_else(|| "ELF data out of bounds".to_string())
    };
    let mut out = LoadedElf {
        entry,
        ..Default::default()
    };
    for i in 0..phnum.min(64) {
        let p = phoff + i * phentsize.max(32);
        if u32_at(p)? != 1 {
            continue;
        }
        let (off, vaddr, filesz, memsz) = (
            u32_at(p + 4)?,
            u32_at(p + 8)?,
            u32_at(p + 16)?,
            u32_at(p + 20)?,
        );
        if u32_at(p + 24)? & PF_OVERLAY != 0 {
            // An overlay: not loaded, but DMAed from the image by the program's overlay
            // manager (libspe2 leaves the image's address in `_EAR_`).
            slice(off, filesz)?;
            out.overlays += 1;
            continue;
        }
        if memsz > 256 * 1024 || filesz > memsz {
            return Err(format!(
                "segment at {vaddr:#x} of {memsz} bytes does not fit the local store"
            ));
        }
        let mut data = slice(off, filesz)?.to_vec();
        data.resize(memsz as usize, 0);
        out.segments.push((vaddr, data));
    }
    let sh = |i: usize, f: usize| u32_at(shoff + i * shentsize.max(40) + 4 * f);
    if shnum > 0 && shoff > 0 {
        let strtab_of = |i: usize| -> Result<(u32, u32), String> { Ok((sh(i, 4)?, sh(i, 5)?)) };
        let name = |table: (u32, u32), off: u32| -> String {
            // Offsets from the file: sums that overflow name nothing, never panic.
            let start = (table.0 as usize).saturating_add(off as usize);
            let end = (table.0 as usize).saturating_add(table.1 as usize);
            bytes
                .get(start..end.min(bytes.len()))
                .map(|b| {
                    String::from_utf8_lossy(b.split(|c| *c == 0).next().unwrap_or(&[])).into_owned()
                })
                .unwrap_or_default()
        };
        let shstr = strtab_of(shstrndx.min(shnum.saturating_sub(1)))?;
        for i in 1..shnum.min(256) {
            let (ty, flags, addr, off, size, link) = (
                sh(i, 1)?,
                sh(i, 2)?,
                sh(i, 3)?,
                sh(i, 4)?,
                sh(i, 5)?,
                sh(i, 6)?,
            );
            let nm = name(shstr, sh(i, 0)?);
            if ty == 1 && flags & 2 != 0 {
                out.sections
                    .push((nm, addr, slice(off, size)?.to_vec(), flags & 4 != 0));
            } else if ty == 2 {
                let strtab = strtab_of(link as usize)?;
                let data = slice(off, size)?;
                for sym in data.chunks_exact(16).skip(1) {
                    let n = u32::from_be_bytes([sym[0], sym[1], sym[2], sym[3]]);
                    let v = u32::from_be_bytes([sym[4], sym[5], sym[6], sym[7]]);
                    let info = sym[12];
                    let shndx = u16::from_be_bytes([sym[14], sym[15]]);
                    if info & 0xf == 3 || info & 0xf == 4 || shndx == 0 {
                        continue; // section, file and undefined symbols
                    }
                    let s = name(strtab, n);
                    if !s.is_empty() {
                        out.symbol_kinds.push(SymbolKind {
                            name: s.clone(),
                            addr: v,
                            global: info >> 4 != 0,
                            absolute: shndx == 0xfff1,
                            typed: matches!(info & 0xf, 1 | 2),
                        });
                        out.symbols.push((s, v));
                    }
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An executable of one PT_LOAD segment (`data` at `vaddr`, `memsz` bytes) and no
    /// sections, built by hand so the reader is tested apart from the assembler.
    fn executable(segments: &[(u32, &[u8], u32)]) -> Vec<u8> {
        let mut elf = vec![0u8; 52];
        elf[0..4].copy_from_slice(b"\x7fELF");
        elf[4] = 1;
        elf[5] = 2;
        elf[6] = 1;
        elf[16..18].copy_from_slice(&2u16.to_be_bytes());
        elf[18..20].copy_from_slice(&EM_SPU.to_be_bytes());
        elf[28..32].copy_from_slice(&52u32.to_be_bytes());
        elf[42..44].copy_from_slice(&32u16.to_be_bytes());
        elf[44..46].copy_from_slice(&(segments.len() as u16).to_be_bytes());
        let mut data_at = 52 + 32 * segments.len() as u32;
        let mut bodies = Vec::new();
        for (vaddr, data, memsz) in segments {
            let mut ph = Vec::new();
            for w in [1, data_at, *vaddr, *vaddr, data.len() as u32, *memsz, 7, 16] {
                ph.extend(w.to_be_bytes());
            }
            elf.extend(ph);
            bodies.extend_from_slice(data);
            data_at += data.len() as u32;
        }
        elf.extend(bodies);
        elf
    }

    #[test]
    fn segments_are_read_with_their_zero_fill() {
        let elf = executable(&[(0x100, &[1, 2, 3, 4], 8)]);
        let back = read_elf(&elf).unwrap();
        assert_eq!(back.segments, vec![(0x100, vec![1, 2, 3, 4, 0, 0, 0, 0])]);
        assert_eq!(back.entry, 0);
    }

    #[test]
    fn malformed_input_is_an_error() {
        assert_eq!(read_elf(&[]).unwrap_err(), "not an ELF file");
        assert_eq!(
            read_elf(b"\x7fELF").unwrap_err(),
            "not a 32-bit big-endian ELF file"
        );
        let mut elf = executable(&[(0, &[0; 4], 4)]);
        elf.truncate(60);
        assert_eq!(read_elf(&elf).unwrap_err(), "truncated ELF file");
        let mut elf = executable(&[(0, &[0; 4], 4)]);
        elf[19] = 20;
        assert_eq!(
            read_elf(&elf).unwrap_err(),
            "ELF machine 20 is not SPU (23)"
        );
    }

    // Executables as the assembler and the linker write them.
    use spu_asm::executable::{write, Place, Section, Symbol};

    /// A `.text` of `size` bytes at 0 and its symbols, `(name, value, binding)`.
    fn linked_text(image: &[u8], symbols: &[(&str, u32, u8)]) -> Vec<u8> {
        let text = Section {
            name: ".text".into(),
            addr: 0,
            size: image.len() as u32,
            flags: 6, // SHF_ALLOC | SHF_EXECINSTR
            nobits: false,
            ty: 1, // SHT_PROGBITS
            late: false,
            align: 8,
        };
        let symbols: Vec<Symbol> = symbols
            .iter()
            .map(|&(name, value, bind)| Symbol {
                name: name.into(),
                value,
                size: 0,
                kind: 0,
                bind,
                place: Place::Section(0),
            })
            .collect();
        write(image, &[text], &[], &symbols, 0)
    }

    #[test]
    fn round_trip() {
        let image = vec![0x40, 0x80, 0x15, 0x03, 0, 0, 0x20, 0];
        let elf = linked_text(&image, &[("x", 4, 0), ("_start", 0, 1)]);
        let back = read_elf(&elf).unwrap();
        // The segment's sizes are rounded up to 16, zeros past the code, as GNU ld's SPU
        // backend writes them.
        let mut loaded = image.clone();
        loaded.resize(16, 0);
        assert_eq!(back.segments, vec![(0, loaded)]);
        assert_eq!(back.sections[0].2, image);
        assert!(back.symbols.contains(&("x".to_string(), 4)));
        assert!(back.symbols.contains(&("_start".to_string(), 0)));
    }

    #[test]
    fn string_offsets_that_overflow_name_nothing() {
        let mut elf = linked_text(&[0; 4], &[("_start", 0, 1)]);
        // Every section's name offset (sh_name, the first word of each header) at the
        // largest u32: added to the string table's offset it used to overflow.
        let shoff = u32::from_be_bytes(elf[32..36].try_into().unwrap()) as usize;
        let shnum = u16::from_be_bytes(elf[48..50].try_into().unwrap()) as usize;
        for i in 1..shnum {
            elf[shoff + 40 * i..shoff + 40 * i + 4].copy_from_slice(&u32::MAX.to_be_bytes());
        }
        let back = read_elf(&elf).unwrap();
        assert!(back.sections.iter().all(|s| s.0.is_empty()));
        assert_eq!(back.segments[0].1, vec![0; 16]); // 4 bytes, rounded up to 16
    }
}
