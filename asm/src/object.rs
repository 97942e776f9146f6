//! Relocatable SPU objects (ELF32 big-endian, `ET_REL`, `EM_SPU`): the in-memory form the
//! assembler produces and the linker consumes, read with the `object` crate (one
//! well-kept ELF reader) and written as GNU as writes them (`object_write`: byte for byte
//! the same file, which no general ELF writer gives).
//!
//! It is the bottom of the assembler's house: the section types and flags, relocations
//! and the local-store placement of sections live here, so that the assembler (`gas`)
//! and the linker (`link`) both build on it and neither reaches into the other.

use object::elf;
use object::read::elf::{FileHeader, Rela as _, SectionHeader as _, Sym as _};
use object::BigEndian;

/// ELF section types and flags the assembler sets and the linker reads.
pub const SHT_PROGBITS: u32 = 1;
pub const SHT_NOBITS: u32 = 8;
pub const SHF_WRITE: u64 = 1;
pub const SHF_ALLOC: u64 = 2;
pub const SHF_EXECINSTR: u64 = 4;
pub const SHF_TLS: u64 = 0x400;
pub const SHF_GROUP: u64 = 0x200;
/// A section group's type, and the flag word of a COMDAT group (one copy kept per link).
pub const SHT_GROUP: u32 = 17;
pub const GRP_COMDAT: u32 = 1;

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
    /// STV_* visibility (0 default, 1 internal, 2 hidden, 3 protected).
    pub visibility: u8,
    /// STT_* type (0 none, 1 object, 2 function, 3 a section's own symbol (nameless; it
    /// places the section's symbol in the table), 4 a source file).
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

/// A section group (`SHT_GROUP`): sections that stay or go together, named by a
/// signature symbol; GNU ld keeps the first COMDAT group of a signature in a link.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Group {
    pub signature: String,
    pub comdat: bool,
    /// Indices into `Object::sections` (their relocations belong to the group too).
    pub members: Vec<usize>,
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
    /// The header's OS ABI (`e_ident[EI_OSABI]`): 0, or 3 (GNU) where the object uses a
    /// GNU extension of ELF (an `STT_GNU_IFUNC` symbol), as BFD marks it.
    pub osabi: u8,
    /// Section groups, in the order gas makes them (first member's section order).
    pub groups: Vec<Group>,
}

impl Object {
    /// Writes the object as GNU as lays it out (`object_write`), checked to lie inside
    /// its own bytes.
    pub fn to_elf(&self) -> Result<Vec<u8>, String> {
        let out = crate::object_write::write(self)?;
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
            osabi: header.e_ident().os_abi.0,
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
            // Past the local store an alignment means nothing more (and `spu as` makes none).
            let align = s.sh_addralign(endian).clamp(1, 1 << 18);
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
        // Section groups: a flag word, then the members' ELF indices (relocation
        // sections among them follow their sections).
        for s in sections.iter() {
            if s.sh_type(endian).0 != SHT_GROUP {
                continue;
            }
            let words = s.data(endian, data).map_err(err)?;
            if words.len() < 4 || words.len() % 4 != 0 {
                return Err(format!("{name}: a section group of {} bytes", words.len()));
            }
            let word = |i: usize| u32::from_be_bytes(words[i..i + 4].try_into().unwrap_or([0; 4]));
            let sym = s.sh_info(endian) as usize;
            let signature = symtab
                .symbol(object::SymbolIndex(sym))
                .and_then(|sym| sym.name(endian, strings))
                .map_err(|_| {
                    format!("{name}: a section group's signature symbol {sym} is not there")
                })?;
            let members = (4..words.len())
                .step_by(4)
                .filter_map(|i| ours.get(word(i) as usize).copied().flatten())
                .collect();
            obj.groups.push(Group {
                signature: String::from_utf8_lossy(signature).into_owned(),
                comdat: word(0) & GRP_COMDAT != 0,
                members,
            });
        }
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
            let bind = sym.st_bind();
            let nm = if st_type == elf::STT_SECTION.0 {
                match section {
                    SymSection::Section(k) => targets.push(RelocTarget::Section(k)),
                    _ => targets.push(RelocTarget::Symbol(String::new())),
                }
                String::new()
            } else {
                if st_type == elf::STT_FILE.0 {
                    targets.push(RelocTarget::Symbol(String::new()));
                } else {
                    targets.push(RelocTarget::Symbol(nm.clone()));
                }
                nm
            };
            obj.symbols.push(ObjSymbol {
                name: nm,
                value: sym.st_value(endian) as u64,
                size: sym.st_size(endian) as u64,
                section,
                global: bind != elf::STB_LOCAL,
                weak: bind == elf::STB_WEAK,
                visibility: sym.st_other().0 & 3,
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
