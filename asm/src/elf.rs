//! SPU ELF executables: writing what the assembler produced, and reading them back for the
//! simulator and the disassembler. ELF32, big-endian, `e_machine` 23 (EM_SPU).

/// EM_SPU.
pub const EM_SPU: u16 = 23;

fn be16(v: u16) -> [u8; 2] {
    v.to_be_bytes()
}
fn be32(v: u32) -> [u8; 4] {
    v.to_be_bytes()
}

/// Writes an executable: one PT_LOAD segment covering the image at address 0, section
/// headers for the sections, a symbol table and the string tables.
pub fn write_elf(
    image: &[u8],
    sections: &[(String, u32, u32, bool)],
    nobits: &[bool],
    symbols: &[(String, u32)],
    globals: &[String],
    entry: u32,
) -> Vec<u8> {
    let mut shstr = vec![0u8];
    let name_off = |s: &str, table: &mut Vec<u8>| {
        let off = table.len() as u32;
        table.extend(s.as_bytes());
        table.push(0);
        off
    };
    let mut strtab = vec![0u8];
    let mut symtab = vec![0u8; 16];
    // Locals first, then globals (sh_info = first global).
    let section_index = |addr: u32| -> u16 {
        for (i, (_, a, size, _)) in sections.iter().enumerate() {
            if addr >= *a && addr < a + size.max(&1) {
                return (i + 1) as u16;
            }
        }
        1
    };
    let mut ordered: Vec<&(String, u32)> =
        symbols.iter().filter(|s| !globals.contains(&s.0)).collect();
    let first_global = ordered.len() + 1;
    ordered.extend(symbols.iter().filter(|s| globals.contains(&s.0)));
    for (name, addr) in ordered {
        let n = name_off(name, &mut strtab);
        let global = globals.contains(name);
        let info = if global { 0x10 } else { 0 };
        symtab.extend(be32(n));
        symtab.extend(be32(*addr));
        symtab.extend(be32(0));
        symtab.push(info);
        symtab.push(0);
        symtab.extend(be16(section_index(*addr)));
    }
    let ehsize = 52u32;
    let phoff = ehsize;
    let image_off = 0x80u32;
    let mut out = Vec::new();
    // Section contents after the image.
    let mut body = image.to_vec();
    let align4 = |v: &mut Vec<u8>| {
        while !v.len().is_multiple_of(4) {
            v.push(0)
        }
    };
    align4(&mut body);
    let symtab_off = image_off + body.len() as u32;
    body.extend(&symtab);
    let strtab_off = image_off + body.len() as u32;
    body.extend(&strtab);
    align4(&mut body);
    let mut names = Vec::new();
    for (n, ..) in sections {
        names.push(name_off(n, &mut shstr));
    }
    let symtab_name = name_off(".symtab", &mut shstr);
    let strtab_name = name_off(".strtab", &mut shstr);
    let shstrtab_name = name_off(".shstrtab", &mut shstr);
    let shstr_off = image_off + body.len() as u32;
    body.extend(&shstr);
    align4(&mut body);
    let shoff = image_off + body.len() as u32;
    let shnum = sections.len() as u16 + 4;
    // ELF header.
    out.extend([0x7f, b'E', b'L', b'F', 1, 2, 1, 0]);
    out.extend([0u8; 8]);
    out.extend(be16(2)); // ET_EXEC
    out.extend(be16(EM_SPU));
    out.extend(be32(1));
    out.extend(be32(entry));
    out.extend(be32(phoff));
    out.extend(be32(shoff));
    out.extend(be32(0));
    out.extend(be16(ehsize as u16));
    out.extend(be16(32));
    out.extend(be16(1));
    out.extend(be16(40));
    out.extend(be16(shnum));
    out.extend(be16(shnum - 1));
    // Program header: PT_LOAD, RWX.
    out.extend(be32(1));
    out.extend(be32(image_off));
    out.extend(be32(0));
    out.extend(be32(0));
    let file_size = sections
        .iter()
        .enumerate()
        .filter(|(k, s)| !nobits.get(*k).copied().unwrap_or(s.0 == ".bss"))
        .map(|(_, s)| s)
        .map(|s| s.1 + s.2)
        .max()
        .unwrap_or(0);
    out.extend(be32(file_size));
    out.extend(be32(image.len() as u32));
    out.extend(be32(7));
    out.extend(be32(128));
    out.resize(image_off as usize, 0);
    out.extend(&body);
    // Section headers.
    let sh = |out: &mut Vec<u8>,
              name: u32,
              ty: u32,
              flags: u32,
              addr: u32,
              off: u32,
              size: u32,
              link: u32,
              info: u32,
              align: u32,
              entsize: u32| {
        for v in [name, ty, flags, addr, off, size, link, info, align, entsize] {
            out.extend(be32(v));
        }
    };
    sh(&mut out, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
    for (k, ((name, addr, size, code), n)) in sections.iter().zip(&names).enumerate() {
        let (ty, flags) = if nobits.get(k).copied().unwrap_or(name == ".bss") {
            (8, 3)
        } else if *code {
            (1, 6)
        } else {
            (1, 3)
        };
        sh(
            &mut out,
            *n,
            ty,
            flags,
            *addr,
            image_off + addr,
            *size,
            0,
            0,
            16,
            0,
        );
    }
    let symtab_index = sections.len() as u32 + 1;
    sh(
        &mut out,
        symtab_name,
        2,
        0,
        0,
        symtab_off,
        symtab.len() as u32,
        symtab_index + 1,
        first_global as u32,
        4,
        16,
    );
    sh(
        &mut out,
        strtab_name,
        3,
        0,
        0,
        strtab_off,
        strtab.len() as u32,
        0,
        0,
        1,
        0,
    );
    sh(
        &mut out,
        shstrtab_name,
        3,
        0,
        0,
        shstr_off,
        shstr.len() as u32,
        0,
        0,
        1,
        0,
    );
    out
}

/// What the simulator and the disassembler need from an SPU ELF.
#[derive(Clone, Debug, Default)]
pub struct LoadedElf {
    pub segments: Vec<(u32, Vec<u8>)>,
    /// (name, address, bytes, is code)
    pub sections: Vec<(String, u32, Vec<u8>, bool)>,
    pub symbols: Vec<(String, u32)>,
    /// The same symbols with what objdump weighs when it names an address: whether the
    /// symbol is global (or weak) and whether it is absolute (not in any section).
    pub symbol_kinds: Vec<SymbolKind>,
    pub entry: u32,
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SymbolKind {
    pub name: String,
    pub addr: u32,
    pub global: bool,
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

    #[test]
    fn round_trip() {
        let image = vec![0x40, 0x80, 0x15, 0x03, 0, 0, 0x20, 0];
        let sections = vec![(".text".to_string(), 0, 8, true)];
        let elf = write_elf(
            &image,
            &sections,
            &[false],
            &[("_start".into(), 0), ("x".into(), 4)],
            &["_start".into()],
            0,
        );
        let back = read_elf(&elf).unwrap();
        assert_eq!(back.segments, vec![(0, image.clone())]);
        assert_eq!(back.sections[0].2, image);
        assert!(back.symbols.contains(&("x".to_string(), 4)));
        assert!(back.symbols.contains(&("_start".to_string(), 0)));
    }

    #[test]
    fn malformed_input_is_an_error() {
        assert!(read_elf(b"\x7fELF").is_err());
        assert!(read_elf(&[]).is_err());
        let mut elf = write_elf(
            &[0; 4],
            &[(".text".into(), 0, 4, true)],
            &[false],
            &[],
            &[],
            0,
        );
        elf.truncate(60);
        assert!(read_elf(&elf).is_err());
    }

    #[test]
    fn string_offsets_that_overflow_name_nothing() {
        let mut elf = write_elf(
            &[0; 4],
            &[(".text".into(), 0, 4, true)],
            &[false],
            &[("_start".into(), 0)],
            &["_start".into()],
            0,
        );
        // Every section's name offset (sh_name, the first word of each header) at the
        // largest u32: added to the string table's offset it used to overflow.
        let shoff = u32::from_be_bytes(elf[32..36].try_into().unwrap()) as usize;
        let shnum = u16::from_be_bytes(elf[48..50].try_into().unwrap()) as usize;
        for i in 1..shnum {
            elf[shoff + 40 * i..shoff + 40 * i + 4].copy_from_slice(&u32::MAX.to_be_bytes());
        }
        let back = read_elf(&elf).unwrap();
        assert!(back.sections.iter().all(|s| s.0.is_empty()));
        assert_eq!(back.segments[0].1, vec![0; 4]);
    }
}
