//! A relocatable object written byte for byte as GNU as 2.40 (through BFD's `elf.c` and
//! `elf-strtab.c`) writes one, so that `spu as -c` and `spu-elf-as` give the same file:
//! each section's header followed by its `.rela` section's; the contents in section order,
//! then `.symtab` and `.strtab`, then the relocations, then `.shstrtab` and the section
//! headers; string tables in first-use order with names that end another name stored
//! only inside it. The symbol table is the object's own order (gas's symbol chain, locals
//! first); a section without a section symbol gets one after the locals, as BFD's
//! `elf_map_symbols` adds them. Section groups' `SHT_GROUP` sections come first (BFD's
//! `assign_section_numbers` numbers them before the rest), each with a section symbol
//! after the others' and a local signature symbol where the source named none.

use crate::object::{
    Object, RelocTarget, SymSection, GRP_COMDAT, SHF_GROUP, SHT_GROUP, SHT_NOBITS,
};

const SHT_SYMTAB: u32 = 2;
const SHT_STRTAB: u32 = 3;
const SHT_RELA: u32 = 4;
const SHF_INFO_LINK: u64 = 0x40;
const STT_SECTION: u8 = 3;
const EM_SPU: u16 = 23;

/// A string table as BFD's `_bfd_elf_strtab_finalize` lays one out: strings in the order
/// first added, except that a string ending another one is not stored but points into it.
#[derive(Default)]
struct StringTable {
    strings: Vec<Vec<u8>>,
}

impl StringTable {
    fn add(&mut self, s: &[u8]) {
        if !s.is_empty() && !self.strings.iter().any(|x| x == s) {
            self.strings.push(s.to_vec());
        }
    }

    /// The table's bytes and each string's offset.
    fn finish(&self) -> (Vec<u8>, std::collections::HashMap<Vec<u8>, u32>) {
        let n = self.strings.len();
        // Sorted by the reversed string: a string's suffixes come just before it.
        let mut by_suffix: Vec<usize> = (0..n).collect();
        by_suffix.sort_by(|&a, &b| {
            self.strings[a]
                .iter()
                .rev()
                .cmp(self.strings[b].iter().rev())
        });
        let mut inside: Vec<Option<usize>> = vec![None; n];
        if let Some(&last) = by_suffix.last() {
            let mut keeper = last;
            for &k in by_suffix.iter().rev().skip(1) {
                let (e, s) = (&self.strings[keeper], &self.strings[k]);
                if e.len() > s.len() && e.ends_with(s) {
                    inside[k] = Some(keeper);
                } else {
                    keeper = k;
                }
            }
        }
        let mut bytes = vec![0u8];
        let mut offsets = std::collections::HashMap::new();
        for (s, within) in self.strings.iter().zip(&inside) {
            if within.is_none() {
                offsets.insert(s.clone(), bytes.len() as u32);
                bytes.extend_from_slice(s);
                bytes.push(0);
            }
        }
        for (short, within) in self.strings.iter().zip(&inside) {
            if let Some(e) = *within {
                let long = &self.strings[e];
                let at = offsets[long] + (long.len() - short.len()) as u32;
                offsets.insert(short.clone(), at);
            }
        }
        (bytes, offsets)
    }
}

/// One section header's fields.
#[derive(Clone, Default)]
struct Header {
    name: Vec<u8>,
    ty: u32,
    flags: u64,
    offset: u64,
    size: u64,
    link: u32,
    info: u32,
    align: u64,
    entsize: u64,
}

fn align_to(n: u64, a: u64) -> u64 {
    if a > 1 {
        n.div_ceil(a) * a
    } else {
        n
    }
}

/// The ELF bytes of `obj`.
pub(crate) fn write(obj: &Object) -> Result<Vec<u8>, String> {
    // Section header indices: each content section, then its relocations'.
    let mut headers = vec![Header::default()];
    for g in &obj.groups {
        headers.push(Header {
            name: b".group".to_vec(),
            ty: SHT_GROUP,
            align: 4,
            entsize: 4,
            ..Default::default()
        });
        for &m in &g.members {
            if m >= obj.sections.len() {
                return Err(format!(
                    "group `{}' names section {m}, which is not there",
                    g.signature
                ));
            }
        }
    }
    let mut index = Vec::new();
    let mut rela_of = Vec::new();
    for s in &obj.sections {
        index.push(headers.len());
        headers.push(Header {
            name: s.name.as_bytes().to_vec(),
            ty: s.ty,
            flags: s.flags,
            size: s.size as u64,
            align: s.align.max(1) as u64,
            entsize: s.entsize,
            ..Default::default()
        });
        if s.relocs.is_empty() {
            rela_of.push(None);
        } else {
            rela_of.push(Some(headers.len()));
            headers.push(Header {
                name: format!(".rela{}", s.name).into_bytes(),
                ty: SHT_RELA,
                flags: SHF_INFO_LINK | (s.flags & SHF_GROUP),
                size: 12 * s.relocs.len() as u64,
                info: headers.len() as u32 - 1,
                align: 4,
                entsize: 12,
                ..Default::default()
            });
        }
    }
    let symtab = headers.len();
    let (strtab, shstrtab) = (symtab + 1, symtab + 2);
    // Symbols: the object's, locals first (each kind in its order), and a section symbol
    // after the locals for each section the object gave none.
    let has_section_symbol = |k: usize| {
        obj.symbols
            .iter()
            .any(|s| s.kind == STT_SECTION && s.section == SymSection::Section(k))
    };
    // (symbol, or the section whose symbol it is)
    // (symbol, or the section whose symbol it is; sections past the object's are
    // groups, and a group's signature where the object has no symbol of that name)
    let mut order: Vec<(Option<usize>, usize)> = Vec::new();
    for (i, s) in obj.symbols.iter().enumerate() {
        if !s.global {
            order.push((Some(i), 0));
        }
    }
    let n_sections = obj.sections.len();
    let n_groups = obj.groups.len();
    let named = |n: &str| {
        obj.symbols
            .iter()
            .any(|s| s.kind != STT_SECTION && s.name == n)
    };
    for (g, group) in obj.groups.iter().enumerate() {
        if !named(&group.signature) {
            order.push((None, n_sections + n_groups + g));
        }
    }
    for k in 0..n_sections {
        if !has_section_symbol(k) {
            order.push((None, k));
        }
    }
    for g in 0..n_groups {
        order.push((None, n_sections + g));
    }
    let num_local = order.len() + 1;
    for (i, s) in obj.symbols.iter().enumerate() {
        if s.global {
            order.push((Some(i), 0));
        }
    }
    let mut strings = StringTable::default();
    for (i, k) in &order {
        match i {
            Some(i) if obj.symbols[*i].kind != STT_SECTION => {
                strings.add(obj.symbols[*i].name.as_bytes());
            }
            None if *k >= n_sections + n_groups => {
                strings.add(obj.groups[k - n_sections - n_groups].signature.as_bytes());
            }
            _ => {}
        }
    }
    let (str_bytes, str_at) = strings.finish();
    // Relocation targets: a symbol's index by name (the first of that name), a section's
    // symbol by section.
    let mut by_name = std::collections::HashMap::new();
    let mut section_symbol = vec![0u32; obj.sections.len()];
    for (n, (i, k)) in order.iter().enumerate() {
        match i {
            Some(i) => {
                let s = &obj.symbols[*i];
                if s.kind == STT_SECTION {
                    if let SymSection::Section(k) = s.section {
                        if let Some(slot) = section_symbol.get_mut(k) {
                            *slot = n as u32 + 1;
                        }
                    }
                } else {
                    by_name.entry(s.name.as_str()).or_insert(n as u32 + 1);
                }
            }
            None if *k < n_sections => section_symbol[*k] = n as u32 + 1,
            None if *k >= n_sections + n_groups => {
                let g = &obj.groups[k - n_sections - n_groups];
                by_name.entry(g.signature.as_str()).or_insert(n as u32 + 1);
            }
            None => {}
        }
    }
    let mut sym_bytes = vec![0u8; 16];
    for (i, k) in &order {
        let (name, value, size, info, other, shndx) = match i {
            None if *k < n_sections => (0, 0, 0, STT_SECTION, 0, index[*k] as u16),
            None if *k < n_sections + n_groups => {
                (0, 0, 0, STT_SECTION, 0, (k - n_sections + 1) as u16)
            }
            None => {
                let g = k - n_sections - n_groups;
                let name = str_at
                    .get(obj.groups[g].signature.as_bytes())
                    .copied()
                    .unwrap_or(0);
                (name, 0, 0, 0, 0, (g + 1) as u16)
            }
            Some(i) => {
                let s = &obj.symbols[*i];
                let bind = if s.weak {
                    2
                } else if s.global {
                    1
                } else {
                    0
                };
                let shndx = match s.section {
                    SymSection::Undefined => 0,
                    SymSection::Absolute => 0xfff1,
                    SymSection::Common => 0xfff2,
                    SymSection::Section(k) => *index.get(k).ok_or_else(|| {
                        format!("symbol `{}' in section {k}, which is not there", s.name)
                    })? as u16,
                };
                let name = if s.kind == STT_SECTION {
                    0
                } else {
                    str_at.get(s.name.as_bytes()).copied().unwrap_or(0)
                };
                (
                    name,
                    s.value as u32,
                    s.size as u32,
                    (bind << 4) | (s.kind & 15),
                    s.visibility,
                    shndx,
                )
            }
        };
        sym_bytes.extend_from_slice(&name.to_be_bytes());
        sym_bytes.extend_from_slice(&value.to_be_bytes());
        sym_bytes.extend_from_slice(&size.to_be_bytes());
        sym_bytes.extend_from_slice(&[info, other]);
        sym_bytes.extend_from_slice(&shndx.to_be_bytes());
    }
    headers.push(Header {
        name: b".symtab".to_vec(),
        ty: SHT_SYMTAB,
        size: sym_bytes.len() as u64,
        link: strtab as u32,
        info: num_local as u32,
        align: 4,
        entsize: 16,
        ..Default::default()
    });
    headers.push(Header {
        name: b".strtab".to_vec(),
        ty: SHT_STRTAB,
        size: str_bytes.len() as u64,
        align: 1,
        ..Default::default()
    });
    headers.push(Header {
        name: b".shstrtab".to_vec(),
        ty: SHT_STRTAB,
        align: 1,
        ..Default::default()
    });
    let mut names = StringTable::default();
    for n in [&b".symtab"[..], b".strtab", b".shstrtab"] {
        names.add(n);
    }
    // The group sections' names last: they are last in BFD's list of sections.
    for h in headers[1 + n_groups..symtab]
        .iter()
        .chain(&headers[1..1 + n_groups])
    {
        names.add(&h.name);
    }
    let (name_bytes, name_at) = names.finish();
    headers[shstrtab].size = name_bytes.len() as u64;
    // The relocations' bytes, per section.
    for (g, group) in obj.groups.iter().enumerate() {
        let signature = by_name.get(group.signature.as_str()).copied().unwrap_or(0);
        let h = &mut headers[g + 1];
        h.link = symtab as u32;
        h.info = signature;
        h.size = 4
            * (1 + group.members.len() as u64
                + group
                    .members
                    .iter()
                    .filter(|&&m| rela_of[m].is_some())
                    .count() as u64);
    }
    let mut rela_bytes = Vec::new();
    for s in &obj.sections {
        let mut b = Vec::new();
        for r in &s.relocs {
            let sym = match &r.target {
                RelocTarget::Section(t) => *section_symbol
                    .get(*t)
                    .ok_or_else(|| format!("relocation against section {t} that is not there"))?,
                RelocTarget::Symbol(n) if n.is_empty() => 0,
                RelocTarget::Symbol(n) => *by_name.get(n.as_str()).ok_or_else(|| {
                    format!("relocation against `{n}', which is not in the symbol table")
                })?,
            };
            b.extend_from_slice(&r.offset.to_be_bytes());
            b.extend_from_slice(&((sym << 8) | (r.kind & 0xff)).to_be_bytes());
            b.extend_from_slice(&(r.addend as i32).to_be_bytes());
        }
        rela_bytes.push(b);
    }
    // File positions: contents, symtab, strtab; relocations; shstrtab; headers.
    let mut at = 52u64;
    for (k, h) in headers.iter_mut().enumerate().skip(1) {
        if h.ty == SHT_RELA || k == shstrtab {
            continue;
        }
        at = align_to(at, h.align);
        h.offset = at;
        if h.ty != SHT_NOBITS {
            at += h.size;
        }
    }
    for h in headers.iter_mut().filter(|h| h.ty == SHT_RELA) {
        at = align_to(at, h.align);
        h.offset = at;
        at += h.size;
    }
    headers[shstrtab].offset = at;
    at += headers[shstrtab].size;
    let shoff = align_to(at, 4);
    let mut out = vec![0u8; shoff as usize + 40 * headers.len()];
    out[..16].copy_from_slice(&[0x7f, b'E', b'L', b'F', 1, 2, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    out[7] = obj.osabi;
    let put16 =
        |out: &mut Vec<u8>, at: usize, v: u16| out[at..at + 2].copy_from_slice(&v.to_be_bytes());
    let put32 =
        |out: &mut Vec<u8>, at: usize, v: u32| out[at..at + 4].copy_from_slice(&v.to_be_bytes());
    put16(&mut out, 16, 1); // ET_REL
    put16(&mut out, 18, EM_SPU);
    put32(&mut out, 20, 1);
    put32(&mut out, 32, shoff as u32);
    put16(&mut out, 40, 52);
    put16(&mut out, 46, 40);
    put16(&mut out, 48, headers.len() as u16);
    put16(&mut out, 50, shstrtab as u16);
    let place = |out: &mut Vec<u8>, h: &Header, bytes: &[u8]| {
        out[h.offset as usize..h.offset as usize + bytes.len()].copy_from_slice(bytes);
    };
    for (k, s) in obj.sections.iter().enumerate() {
        if s.ty != SHT_NOBITS {
            if s.data.len() as u64 != headers[index[k]].size {
                return Err(format!(
                    "section {} has {} bytes for its size {}",
                    s.name,
                    s.data.len(),
                    s.size
                ));
            }
            place(&mut out, &headers[index[k]], &s.data);
        }
        if let Some(r) = rela_of[k] {
            place(&mut out, &headers[r], &rela_bytes[k]);
        }
    }
    for (g, group) in obj.groups.iter().enumerate() {
        let mut b = Vec::new();
        b.extend_from_slice(&(if group.comdat { GRP_COMDAT } else { 0 }).to_be_bytes());
        for &m in &group.members {
            b.extend_from_slice(&(index[m] as u32).to_be_bytes());
            if let Some(r) = rela_of[m] {
                b.extend_from_slice(&(r as u32).to_be_bytes());
            }
        }
        place(&mut out, &headers[g + 1], &b);
    }
    place(&mut out, &headers[symtab], &sym_bytes);
    place(&mut out, &headers[strtab], &str_bytes);
    place(&mut out, &headers[shstrtab], &name_bytes);
    for (k, h) in headers.iter().enumerate().skip(1) {
        let o = shoff as usize + 40 * k;
        put32(&mut out, o, name_at.get(&h.name).copied().unwrap_or(0));
        put32(&mut out, o + 4, h.ty);
        put32(&mut out, o + 8, h.flags as u32);
        put32(&mut out, o + 16, h.offset as u32);
        put32(&mut out, o + 20, h.size as u32);
        put32(
            &mut out,
            o + 24,
            if h.ty == SHT_RELA {
                symtab as u32
            } else {
                h.link
            },
        );
        put32(&mut out, o + 28, h.info);
        put32(&mut out, o + 32, h.align as u32);
        put32(&mut out, o + 36, h.entsize as u32);
    }
    Ok(out)
}
