//! SPU ELF executables: writing what the assembler produced. ELF32, big-endian,
//! `e_machine` 23 (EM_SPU). Reading them back, for the simulator and the disassembler, is
//! `spu_spe::elf::read_elf`.

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
