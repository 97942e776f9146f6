//! Relocatable SPU objects (ELF32 big-endian, `ET_REL`, `EM_SPU`): the in-memory form the
//! assembler produces and the linker consumes, written and read with the `object` crate
//! (one well-kept ELF implementation for section headers, symbol tables, string tables
//! and RELA sections, rather than a second hand-written one).
//!
//! It is the bottom of the assembler's house: the section types and flags, relocations
//! and the local-store placement of sections live here, so that the assembler (`gas`)
//! and the linker (`link`) both build on it and neither reaches into the other.

use object::elf;
use object::read::elf::{FileHeader, Rela as _, SectionHeader as _, Sym as _};
use object::write::elf::{FileHeader as WFileHeader, Rel, SectionHeader, Sym, Writer};
use object::BigEndian;

/// ELF section types and flags the assembler sets and the linker reads.
pub const SHT_PROGBITS: u32 = 1;
pub const SHT_NOBITS: u32 = 8;
pub const SHF_WRITE: u64 = 1;
pub const SHF_ALLOC: u64 = 2;
pub const SHF_EXECINSTR: u64 = 4;
pub const SHF_TLS: u64 = 0x400;

/// A relocation the assembler leaves for the linker (objects only), or applies itself
/// (`.reloc` in an executable).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reloc {
    /// Offset in its section.
    pub offset: u32,
    /// An `R_SPU_*` number.
    pub kind: u32,
    pub target: RelocTarget,
    pub addend: i64,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RelocTarget {
    /// A section of this object (by index into the section list).
    Section(usize),
    Symbol(String),
}

/// Where the data segment (the first writable section, data or bss) starts: GNU ld's SPU
/// script sets `DATA_ADDR` to `ALIGN(MAXPAGESIZE)`, 0x80, after the read-only sections.
pub(crate) const DATA_SEGMENT_ALIGN: u32 = 0x80;

/// Where a section goes in local store (sorted by this, then by first appearance), for
/// the linker's output sections and the assembler's executables alike: the
/// order of GNU ld's SPU script (`.interrupt`, `.init`, `.text`, `.fini`, read-only
/// data, data, bss); non-allocated sections last (they take no address).
pub(crate) fn placement(name: &str, ty: u32, flags: u64) -> (u8, i8) {
    let class = if flags & SHF_ALLOC == 0 {
        4
    } else if flags & SHF_EXECINSTR != 0 {
        0
    } else if ty == SHT_NOBITS {
        3
    } else if flags & SHF_WRITE == 0 {
        1
    } else {
        2
    };
    let rank = match name {
        ".interrupt" => -3,
        ".init" => -2,
        ".text" => -1,
        ".fini" => 1,
        _ => 0,
    };
    (class, rank)
}

/// Where a symbol is defined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SymSection {
    Undefined,
    Absolute,
    /// A common symbol: `value` is its alignment, `size` its size.
    Common,
    /// Index into `Object::sections`.
    Section(usize),
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjSymbol {
    pub name: String,
    pub value: u64,
    pub size: u64,
    pub section: SymSection,
    pub global: bool,
    pub weak: bool,
    pub hidden: bool,
    /// STT_* type (0 none, 1 object, 2 function).
    pub kind: u8,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ObjSection {
    pub name: String,
    pub ty: u32,
    pub flags: u64,
    pub entsize: u64,
    pub align: u32,
    pub size: u32,
    /// The contents (empty for NOBITS).
    pub data: Vec<u8>,
    /// Relocations against this section's contents; symbol targets name `symbols`
    /// entries (an empty name is no symbol: an absolute value).
    pub relocs: Vec<Reloc>,
}

#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Object {
    /// Where it came from (for messages).
    pub name: String,
    pub sections: Vec<ObjSection>,
    pub symbols: Vec<ObjSymbol>,
    /// For an object assembled here, the files its source's `.include` and `.incbin`
    /// read from disk (inputs of the command that assembles it); empty for one read.
    pub included: Vec<std::path::PathBuf>,
}

impl Object {
    /// Writes the object as gas lays it out: the sections, their `.rela` sections, then
    /// `.symtab` (section symbols and locals first), `.strtab` and `.shstrtab`.
    pub fn to_elf(&self) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        let mut w = Writer::new(object::Endianness::Big, false, &mut out);
        w.reserve_file_header();
        // Section indices: every content section, then each one's .rela.
        let names: Vec<String> = self.sections.iter().map(|s| s.name.clone()).collect();
        let rela_names: Vec<String> = names.iter().map(|n| format!(".rela{n}")).collect();
        let mut index = Vec::new();
        let mut name_ids = Vec::new();
        w.reserve_null_section_index();
        for s in &self.sections {
            index.push(w.reserve_section_index());
            name_ids.push(w.add_section_name(s.name.as_bytes()));
        }
        let mut rela_index = Vec::new();
        for (k, s) in self.sections.iter().enumerate() {
            if s.relocs.is_empty() {
                rela_index.push(None);
            } else {
                let id = w.add_section_name(rela_names[k].as_bytes());
                rela_index.push(Some((w.reserve_section_index(), id)));
            }
        }
        // Symbols: null, one per section, locals, then globals.
        w.reserve_null_symbol_index();
        let mut section_sym = Vec::new();
        for i in &index {
            section_sym.push(w.reserve_symbol_index(Some(*i)));
        }
        let mut order: Vec<&ObjSymbol> = self.symbols.iter().filter(|s| !s.global).collect();
        let num_local = (1 + self.sections.len() + order.len()) as u32;
        order.extend(self.symbols.iter().filter(|s| s.global));
        let mut sym_index = std::collections::HashMap::new();
        let mut str_ids = Vec::new();
        for s in &order {
            let sect = match s.section {
                SymSection::Section(k) => index.get(k).copied(),
                _ => None,
            };
            let i = w.reserve_symbol_index(sect);
            sym_index.insert(s.name.clone(), i);
            str_ids.push(w.add_string(s.name.as_bytes()));
        }
        let symtab_index = w.reserve_symtab_section_index();
        w.reserve_strtab_section_index();
        w.reserve_shstrtab_section_index();
        // File layout.
        let mut offsets = Vec::new();
        for s in &self.sections {
            let len = if s.ty == SHT_NOBITS { 0 } else { s.data.len() };
            offsets.push(w.reserve(len as u64, s.align.max(1) as usize as u64));
        }
        let mut rela_offsets = Vec::new();
        for s in &self.sections {
            rela_offsets.push(if s.relocs.is_empty() {
                0
            } else {
                w.reserve_relocations(s.relocs.len(), true)
            });
        }
        w.reserve_symtab();
        w.reserve_strtab().map_err(|e| e.to_string())?;
        w.reserve_shstrtab().map_err(|e| e.to_string())?;
        w.reserve_section_headers();
        // Contents.
        w.write_file_header(&WFileHeader {
            os_abi: elf::ELFOSABI_NONE,
            abi_version: 0,
            e_type: elf::ET_REL,
            e_machine: elf::EM_SPU,
            e_entry: 0,
            e_flags: elf::FileFlags(0),
        })
        .map_err(|e| e.to_string())?;
        for (k, s) in self.sections.iter().enumerate() {
            // A NOBITS section's offset is aligned too (`reserve` aligned it): the padding
            // must be written, or every offset after it points past what was written.
            w.write_align(s.align.max(1) as usize as u64);
            debug_assert_eq!(w.len(), offsets[k]);
            if s.ty != SHT_NOBITS {
                w.write(&s.data);
            }
        }
        for (k, s) in self.sections.iter().enumerate() {
            if s.relocs.is_empty() {
                continue;
            }
            w.write_align_relocation();
            for r in &s.relocs {
                let r_sym = match &r.target {
                    RelocTarget::Section(t) => {
                        section_sym.get(*t).map(|i| i.0).ok_or_else(|| {
                            format!("relocation against section {t} that is not there")
                        })?
                    }
                    RelocTarget::Symbol(n) if n.is_empty() => 0,
                    RelocTarget::Symbol(n) => sym_index.get(n).map(|i| i.0).ok_or_else(|| {
                        format!("relocation against `{n}', which is not in the symbol table")
                    })?,
                };
                w.write_relocation(
                    true,
                    &Rel {
                        r_offset: r.offset as u64,
                        r_sym,
                        r_type: elf::RelocationType(r.kind),
                        r_addend: r.addend,
                    },
                );
            }
            let _ = k;
        }
        w.write_null_symbol();
        for i in &index {
            w.write_symbol(&Sym {
                st_name: 0,
                section: Some(i.0),
                st_info: elf::SymbolInfo::new(elf::STB_LOCAL, elf::STT_SECTION),
                st_other: elf::SymbolOther(0),
                st_shndx: elf::SymbolSection(0),
                st_value: 0,
                st_size: 0,
            });
        }
        for (s, id) in order.iter().zip(&str_ids) {
            let (section, shndx) = match s.section {
                SymSection::Section(k) => (index.get(k).copied(), elf::SymbolSection(0)),
                SymSection::Undefined => (None, elf::SHN_UNDEF),
                SymSection::Absolute => (None, elf::SHN_ABS),
                SymSection::Common => (None, elf::SHN_COMMON),
            };
            let bind = if s.weak {
                elf::STB_WEAK
            } else if s.global {
                elf::STB_GLOBAL
            } else {
                elf::STB_LOCAL
            };
            w.write_symbol(&Sym {
                st_name: w.string_offset(Some(*id)),
                section: section.map(|i| i.0),
                st_info: elf::SymbolInfo::new(bind, elf::SymbolType(s.kind)),
                st_other: if s.hidden {
                    elf::SymbolOther(elf::STV_HIDDEN.0)
                } else {
                    elf::SymbolOther(0)
                },
                st_shndx: shndx,
                st_value: s.value,
                st_size: s.size,
            });
        }
        w.write_strtab();
        w.write_shstrtab();
        w.write_null_section_header();
        for (k, s) in self.sections.iter().enumerate() {
            w.write_section_header(&SectionHeader {
                sh_name: w.section_name_offset(Some(name_ids[k])),
                sh_type: elf::SectionType(s.ty),
                sh_flags: elf::SectionFlags(s.flags),
                sh_addr: 0,
                sh_offset: offsets[k],
                sh_size: s.size as u64,
                sh_link: 0,
                sh_info: 0,
                sh_addralign: s.align.max(1) as u64,
                sh_entsize: s.entsize,
            });
        }
        for (k, r) in rela_index.iter().enumerate() {
            if let Some((_, id)) = r {
                w.write_relocation_section_header(
                    *id,
                    index[k],
                    symtab_index,
                    rela_offsets[k],
                    self.sections[k].relocs.len(),
                    true,
                );
            }
        }
        w.write_symtab_section_header(num_local);
        w.write_strtab_section_header();
        w.write_shstrtab_section_header();
        drop(w);
        let broken = crate::elf_check::layout_errors(&out);
        if !broken.is_empty() {
            return Err(format!(
                "internal error: object layout: {}",
                broken.join("; ")
            ));
        }
        Ok(out)
    }

    /// Reads a relocatable SPU object; every malformed or foreign input is an error.
    pub fn from_elf(name: &str, data: &[u8]) -> Result<Object, String> {
        let err = |e: object::read::Error| format!("{name}: {e}");
        let header = elf::FileHeader32::<BigEndian>::parse(data).map_err(|_| {
            format!("{name}: not a 32-bit big-endian ELF file (SPU objects are ELF32 MSB)")
        })?;
        let endian = header.endian().map_err(err)?;
        let machine = header.e_machine(endian);
        if machine != elf::EM_SPU {
            return Err(format!(
                "{name}: ELF machine {} is not SPU ({})",
                machine.0,
                elf::EM_SPU.0
            ));
        }
        if header.e_type(endian) != elf::ET_REL {
            return Err(format!("{name}: not a relocatable object (ET_REL)"));
        }
        let sections = header.sections(endian, data).map_err(err)?;
        let mut obj = Object {
            name: name.to_string(),
            ..Default::default()
        };
        // Content sections keep their ELF index -> our index.
        let mut ours = vec![None; sections.len()];
        for (i, s) in sections.iter().enumerate() {
            let ty = s.sh_type(endian).0;
            let is_content = matches!(ty, 1 | 7 | 8 | 14 | 15 | 16);
            if !is_content {
                continue;
            }
            let nm = String::from_utf8_lossy(sections.section_name(endian, s).map_err(err)?)
                .into_owned();
            let size = s.sh_size(endian);
            if size > 16 << 20 {
                return Err(format!("{name}: section {nm} of {size} bytes is too large"));
            }
            let bytes = if ty == SHT_NOBITS {
                Vec::new()
            } else {
                s.data(endian, data).map_err(err)?.to_vec()
            };
            let align = s.sh_addralign(endian).clamp(1, 1 << 15);
            ours[i] = Some(obj.sections.len());
            obj.sections.push(ObjSection {
                name: nm,
                ty,
                flags: s.sh_flags(endian).0,
                entsize: s.sh_entsize(endian) as u64,
                align,
                size,
                data: bytes,
                relocs: Vec::new(),
            });
        }
        let symtab = sections
            .symbols(endian, data, elf::SHT_SYMTAB)
            .map_err(err)?;
        let strings = symtab.strings();
        // ELF symbol index -> relocation target.
        let mut targets: Vec<RelocTarget> = Vec::with_capacity(symtab.len());
        for (i, sym) in symtab.symbols().iter().enumerate() {
            let nm = String::from_utf8_lossy(sym.name(endian, strings).map_err(err)?).into_owned();
            let shndx = sym.st_shndx(endian);
            let st_type = sym.st_type().0;
            let section = match shndx {
                elf::SHN_UNDEF => SymSection::Undefined,
                elf::SHN_ABS => SymSection::Absolute,
                elf::SHN_COMMON => SymSection::Common,
                s => match ours.get(s.0 as usize).copied().flatten() {
                    Some(k) => SymSection::Section(k),
                    None => {
                        targets.push(RelocTarget::Symbol(String::new()));
                        continue; // a symbol of a section we do not keep
                    }
                },
            };
            if i == 0 {
                targets.push(RelocTarget::Symbol(String::new()));
                continue;
            }
            if st_type == elf::STT_SECTION.0 {
                if let SymSection::Section(k) = section {
                    targets.push(RelocTarget::Section(k));
                    continue;
                }
            }
            if st_type == elf::STT_FILE.0 {
                targets.push(RelocTarget::Symbol(String::new()));
                continue;
            }
            let bind = sym.st_bind();
            targets.push(RelocTarget::Symbol(nm.clone()));
            obj.symbols.push(ObjSymbol {
                name: nm,
                value: sym.st_value(endian) as u64,
                size: sym.st_size(endian) as u64,
                section,
                global: bind != elf::STB_LOCAL,
                weak: bind == elf::STB_WEAK,
                hidden: sym.st_visibility() == elf::STV_HIDDEN,
                kind: st_type,
            });
        }
        for s in sections.iter() {
            let Some((relas, _symtab)) = s.rela(endian, data).map_err(err)? else {
                continue;
            };
            // sh_info names the section the relocations apply to.
            let target = s.sh_info(endian) as usize;
            let Some(k) = ours.get(target).copied().flatten() else {
                continue;
            };
            for r in relas {
                let sym = r.r_sym(endian) as usize;
                let target = targets.get(sym).cloned().ok_or_else(|| {
                    format!("{name}: relocation names symbol {sym}, which is not there")
                })?;
                obj.sections[k].relocs.push(Reloc {
                    offset: r.r_offset(endian),
                    kind: r.r_type(endian).0,
                    target,
                    addend: r.r_addend(endian) as i64,
                });
            }
        }
        Ok(obj)
    }
}
