//! Layout and output (gas's `write.c`): bytes emitted into chunks (subsections), alignment
//! and its padding, chunks laid out into sections and sections into local store, fixups
//! recorded as relocations, and the finished program written as an executable image and
//! ELF or as a relocatable object.

use super::obj_elf::SectionDef;
use super::symbols::{Link, SymAttrs, SymVal};
use super::target::code_padding;
use super::{Assembler, Diagnostic, Location, Output, Sect, Severity, LOCAL_STORE};
use crate::expr::Val;
use crate::lex::{display_text, Line};
use crate::object::{
    placement, ObjSection, ObjSymbol, Object, Reloc, RelocTarget, SymSection, DATA_SEGMENT_ALIGN,
    SHF_ALLOC, SHF_EXECINSTR, SHT_NOBITS,
};

impl Assembler<'_> {
    /// The chunk for a section and subsection, created on first use.
    pub(super) fn chunk(&mut self, def: SectionDef, sub: i64) -> Sect {
        let d = match (self.defs.iter()).position(|x| x.name == def.name && x.group == def.group) {
            Some(d) => d,
            None => {
                self.defs.push(def);
                self.defs.len() - 1
            }
        };
        match self.chunks.iter().position(|c| *c == (d, sub)) {
            Some(c) => c,
            None => {
                self.chunks.push((d, sub));
                self.chunks.len() - 1
            }
        }
    }

    pub(super) fn switch_to(&mut self, chunk: Sect) {
        self.absolute = None;
        if chunk != self.sect {
            self.prev_sect = self.sect;
            self.sect = chunk;
        }
    }

    pub(super) fn is_nobits(&self, s: Sect) -> bool {
        self.defs[self.chunks[s].0].ty == SHT_NOBITS
    }

    pub(super) fn is_code(&self, s: Sect) -> bool {
        self.defs[self.chunks[s].0].flags & SHF_EXECINSTR != 0
    }

    /// gas pads the end of each section to the largest alignment requested in it
    /// (`SUB_SEGMENT_ALIGN` with `HANDLE_ALIGN`): code with nop/lnop, data with zeros.
    pub(super) fn finish_sections(&mut self) {
        let current = self.sect;
        for d in 0..self.defs.len() {
            let mine: Vec<Sect> = (0..self.chunks.len())
                .filter(|&c| self.chunks[c].0 == d)
                .collect();
            let boundary = mine
                .iter()
                .map(|c| self.align.get(c).copied().unwrap_or(1))
                .max()
                .unwrap_or(1);
            let last = mine.iter().max_by_key(|&&c| self.chunks[c].1);
            if let Some(&last) = last {
                // Where the contents end before the padding: the line table's last address.
                let end = self.bases.get(&last).copied().unwrap_or(0)
                    + self.offsets.get(&last).copied().unwrap_or(0);
                self.dwarf.content_end.insert(d, end);
            }
            if let (Some(&last), true) = (last, boundary > 1) {
                self.sect = last;
                self.align_to(boundary, None);
            }
        }
        self.sect = current;
    }

    pub(super) fn here(&self) -> u32 {
        if let Some(off) = self.absolute {
            return off;
        }
        self.bases.get(&self.sect).copied().unwrap_or(0)
            + self.offsets.get(&self.sect).copied().unwrap_or(0)
    }

    pub(super) fn emit(&mut self, data: &[u8]) {
        if let Some(off) = self.absolute.as_mut() {
            // The absolute section (`.struct`) has no bytes: only the offset moves.
            *off = off
                .saturating_add(data.len() as u32)
                .min(2 * LOCAL_STORE as u32);
            self.nonzero_in_absolute |= data.iter().any(|&b| b != 0);
            return;
        }
        let nobits = self.is_nobits(self.sect);
        let off = self.offsets.entry(self.sect).or_insert(0);
        // Past the local store nothing can load: stop growing (the size check reports it).
        if *off as usize + data.len() > 2 * LOCAL_STORE {
            *off = (2 * LOCAL_STORE) as u32;
            return;
        }
        if nobits {
            if self.pass == 2 && data.iter().any(|&b| b != 0) {
                self.nonzero_in_nobits = true;
            }
        } else if self.pass == 2 {
            let buf = self.bytes.entry(self.sect).or_default();
            let at = *off as usize;
            if buf.len() < at + data.len() {
                buf.resize(at + data.len(), 0);
            }
            buf[at..at + data.len()].copy_from_slice(data);
        }
        *off += data.len() as u32;
    }

    pub(super) fn align_to(&mut self, boundary: u32, fill: Option<u8>) {
        if boundary <= 1 {
            return;
        }
        let a = self.align.entry(self.sect).or_insert(1);
        *a = (*a).max(boundary);
        // Padding is to an address (sections start at their alignment), so subsections
        // align as gas aligns them once they are joined.
        let off = self.here();
        let pad = (boundary - off % boundary) % boundary;
        if self.is_code(self.sect) && fill.is_none() {
            let bytes = code_padding(off, pad);
            self.emit(&bytes);
        } else {
            self.emit(&vec![fill.unwrap_or(0); pad as usize]);
        }
    }

    /// Where the section of chunk `c` starts (its first chunk's base).
    pub(super) fn section_start(&self, c: Sect) -> i64 {
        let d = self.chunks[c].0;
        (0..self.chunks.len())
            .filter(|&k| self.chunks[k].0 == d)
            .map(|k| self.bases.get(&k).copied().unwrap_or(0))
            .min()
            .unwrap_or(0) as i64
    }

    /// Records a relocation at `offset` in the section of chunk `sect` (pass 2): in an
    /// object for the linker, in an executable to be applied once all bytes are there.
    pub(super) fn add_reloc(
        &mut self,
        sect: Sect,
        offset: u32,
        kind: u32,
        v: &Val,
        line: &Line,
        col: usize,
    ) {
        let def = self.chunks[sect].0;
        // A difference whose subtracted address is in this section, in a word: write.c
        // makes it pc-relative (the addend moved by the place's distance from that
        // address) and tc-spu.c's `md_apply_fix` turns the word into `R_SPU_REL32`.
        let pcrel = v
            .pcrel
            .as_deref()
            .filter(|p| self.object && p.minus == def && kind == crate::reloc::R_SPU_ADDR32);
        let (kind, v) = match pcrel {
            Some(p) => (
                crate::reloc::R_SPU_REL32,
                &Val {
                    v: v.v + offset as i64,
                    sect: p.sect,
                    sym: p.sym.clone(),
                    ..Default::default()
                },
            ),
            None if v.cross => {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    "expression too complex for a relocation",
                );
                return;
            }
            None => (kind, v),
        };
        let (target, addend) = if let Some((name, value)) = &v.sym {
            (RelocTarget::Symbol(name.to_string()), v.v - value)
        } else if let Some(s) = v.sect {
            (
                RelocTarget::Section(s),
                v.v - if self.object { 0 } else { self.def_start(s) },
            )
        } else if v.reloc || v.cross {
            self.diag(
                Severity::Error,
                line,
                col,
                "expression too complex for a relocation",
            );
            return;
        } else {
            (RelocTarget::Section(usize::MAX), v.v)
        };
        let location = Location {
            file: line.file.clone(),
            line: line.line,
            column: col.max(1),
        };
        self.relocs.push((
            def,
            Reloc {
                offset,
                kind,
                target,
                addend,
            },
            location,
            line.text.clone(),
        ));
    }

    /// Where section definition `d` starts (executables).
    pub(super) fn def_start(&self, d: usize) -> i64 {
        (0..self.chunks.len())
            .filter(|&k| self.chunks[k].0 == d)
            .map(|k| self.bases.get(&k).copied().unwrap_or(0))
            .min()
            .unwrap_or(0) as i64
    }

    /// Gives every chunk its address: in an executable, code sections from 0, then
    /// read-only data, then data from the next multiple of 0x80 (as GNU ld lays them out)
    /// and bss, each section at its alignment (at least 16) and its
    /// subsections in order; in an object, offsets within each section.
    pub(super) fn lay_out(&mut self) {
        let class = |d: &SectionDef| placement(&d.name, d.ty, d.flags).0;
        let mut order: Vec<usize> = (0..self.defs.len()).collect();
        order.sort_by_key(|&d| {
            let def = &self.defs[d];
            (placement(&def.name, def.ty, def.flags), d)
        });
        let mut addr = 0u32;
        let mut data_placed = false;
        self.bases.clear();
        for d in order {
            let mut chunks: Vec<Sect> = (0..self.chunks.len())
                .filter(|&c| self.chunks[c].0 == d)
                .collect();
            chunks.sort_by_key(|&c| self.chunks[c].1);
            let align = chunks
                .iter()
                .map(|c| self.align.get(c).copied().unwrap_or(1))
                .max()
                .unwrap_or(1);
            if !self.object && matches!(class(&self.defs[d]), 2 | 3) && !data_placed {
                // GNU ld's SPU script starts the data segment at `ALIGN(0x80)`.
                addr = addr.next_multiple_of(DATA_SEGMENT_ALIGN);
                data_placed = true;
            }
            let mut at = if self.object || class(&self.defs[d]) == 4 {
                0
            } else {
                addr.div_ceil(align.max(16)) * align.max(16)
            };
            // Subsections follow one another directly (their padding is to addresses).
            for c in chunks {
                self.bases.insert(c, at);
                at = at.saturating_add(self.offsets.get(&c).copied().unwrap_or(0));
            }
            if !self.object && class(&self.defs[d]) != 4 {
                addr = at;
            }
        }
    }

    /// Label addresses, for checking that layout has settled.
    pub(super) fn label_values(&self) -> Vec<(String, i64)> {
        let mut v: Vec<(String, i64)> = self
            .symbols
            .iter()
            .filter(|(_, s)| matches!(s, SymVal::Label(..)))
            .map(|(n, s)| (n.clone(), self.value_of(n, s).v))
            .collect();
        v.sort();
        v
    }
}

/// An assembled program (without errors) as an executable: its sections placed in one
/// local-store image, `.reloc`s applied, symbols, and the same as an SPU ELF executable.
pub(super) fn executable(
    asm: Assembler<'_>,
    lines: &[Line],
    file_name: &str,
    warnings: Vec<Diagnostic>,
) -> Result<Output, Vec<Diagnostic>> {
    let fail = |message: String| {
        vec![Diagnostic {
            severity: Severity::Error,
            location: Location {
                file: file_name.into(),
                line: 1,
                column: 1,
            },
            message,
            source_line: lines
                .first()
                .map(|l| display_text(&l.text))
                .unwrap_or_default(),
        }]
    };
    // Sections in address order: (definition, address, size).
    let mut placed: Vec<(usize, u32, u32)> = Vec::new();
    for d in 0..asm.defs.len() {
        if asm.defs[d].flags & SHF_ALLOC == 0 {
            continue;
        }
        let chunks: Vec<Sect> = (0..asm.chunks.len())
            .filter(|&c| asm.chunks[c].0 == d)
            .collect();
        let start = chunks.iter().map(|c| asm.bases[c]).min().unwrap_or(0);
        let end = chunks
            .iter()
            .map(|c| asm.bases[c] + asm.offsets.get(c).copied().unwrap_or(0))
            .max()
            .unwrap_or(0);
        placed.push((d, start, end - start));
    }
    placed.sort_by_key(|p| (p.1, p.0));
    let end = placed.iter().map(|p| p.1 + p.2).max().unwrap_or(0);
    if end as usize > LOCAL_STORE {
        return Err(fail(format!(
            "program of {end} bytes does not fit the 256 KiB local store"
        )));
    }
    let mut image = vec![0u8; end as usize];
    for c in 0..asm.chunks.len() {
        if let Some(b) = asm.bytes.get(&c) {
            let at = asm.bases[&c] as usize;
            if asm.defs[asm.chunks[c].0].flags & SHF_ALLOC != 0 {
                image[at..at + b.len()].copy_from_slice(b);
            }
        }
    }
    // `.reloc` in an executable: applied now that every address is known.
    let mut reloc_errors = Vec::new();
    for (def, r, loc, text) in &asm.relocs {
        let start = placed.iter().find(|p| p.0 == *def).map_or(0, |p| p.1);
        let s = match &r.target {
            RelocTarget::Section(usize::MAX) => 0,
            RelocTarget::Section(t) => placed.iter().find(|p| p.0 == *t).map_or(0, |p| p.1) as i64,
            RelocTarget::Symbol(n) => asm.symbol_address(n).unwrap_or(0),
        };
        let at = start + r.offset;
        if let Err(m) = crate::reloc::apply(r.kind, &mut image, at, s + r.addend) {
            reloc_errors.push(Diagnostic {
                severity: Severity::Error,
                location: loc.clone(),
                message: m,
                source_line: display_text(text),
            });
        }
    }
    if !reloc_errors.is_empty() {
        return Err(reloc_errors);
    }
    let mut symbols: Vec<(String, u32)> = asm
        .symbols
        .iter()
        .filter_map(|(n, v)| match v {
            SymVal::Label(s, off) if !n.starts_with(".L") => Some((n.clone(), asm.bases[s] + off)),
            _ => None,
        })
        .collect();
    symbols.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)));
    let entry = symbols
        .iter()
        .find(|(n, _)| n == "_start")
        .map(|s| s.1)
        .unwrap_or(0);
    // The executable as `spu ld` writes one (`crate::executable`): the sections' flags and
    // alignments, and the symbols' types, sizes and bindings, from the source.
    let out_sections: Vec<crate::executable::Section> = placed
        .iter()
        .map(|&(d, a, size)| {
            let def = &asm.defs[d];
            let align = (0..asm.chunks.len())
                .filter(|&c| asm.chunks[c].0 == d)
                .map(|c| asm.align.get(&c).copied().unwrap_or(1))
                .max()
                .unwrap_or(1);
            crate::executable::Section {
                name: def.name.clone(),
                addr: a,
                size,
                flags: def.flags,
                nobits: def.ty == SHT_NOBITS,
                ty: if def.ty == SHT_NOBITS { 8 } else { 1 },
                late: false,
                align,
            }
        })
        .collect();
    let place_of = |name: &str| match asm.symbols.get(name) {
        Some(SymVal::Label(c, _)) => placed.iter().position(|p| p.0 == asm.chunks[*c].0).map_or(
            crate::executable::Place::Absolute,
            crate::executable::Place::Section,
        ),
        _ => crate::executable::Place::Absolute,
    };
    let mut out_symbols: Vec<crate::executable::Symbol> = symbols
        .iter()
        .map(|(name, value)| {
            let attrs = asm.attrs.get(name);
            let bind = match attrs {
                Some(a) if a.weak => 2,
                Some(a) if a.global => 1,
                _ => 0,
            };
            crate::executable::Symbol {
                name: name.clone(),
                value: *value,
                size: attrs
                    .and_then(|a| a.size)
                    .unwrap_or(0)
                    .clamp(0, u32::MAX as i64) as u32,
                kind: attrs.map_or(0, |a| a.kind),
                bind,
                place: place_of(name),
            }
        })
        .collect();
    // Locals first, as ELF requires; the order within each kind is kept (by address).
    out_symbols.sort_by_key(|s| s.bind != 0);
    let elf = crate::executable::write(&image, &out_sections, &[], &out_symbols, entry);
    Ok(Output {
        image,
        elf,
        symbols,
        entry,
        listing: asm.listing,
        included: asm.included,
        warnings,
        sections: out_sections
            .iter()
            .map(|x| (x.name.clone(), x.addr, x.size, x.flags & SHF_EXECINSTR != 0))
            .collect(),
    })
}

/// Section `d`'s own symbol (nameless, placing it in the table).
fn section_symbol(d: usize) -> ObjSymbol {
    ObjSymbol {
        name: String::new(),
        value: 0,
        size: 0,
        section: SymSection::Section(d),
        global: false,
        weak: false,
        visibility: 0,
        kind: 3,
    }
}

/// An assembled program (without errors) as a relocatable object: each section from
/// offset 0 with its relocations, and the symbol table gas would write.
pub(super) fn object(asm: Assembler<'_>, file_name: &str) -> Object {
    let mut obj = Object {
        name: file_name.to_string(),
        included: asm.included.clone(),
        // obj-elf.c `obj_elf_type`: an indirect function marks the object GNU's.
        osabi: if asm.attrs.values().any(|a| a.gnu_osabi) {
            3
        } else {
            0
        },
        ..Default::default()
    };
    for (d, def) in asm.defs.iter().enumerate() {
        let mut chunks: Vec<Sect> = (0..asm.chunks.len())
            .filter(|&c| asm.chunks[c].0 == d)
            .collect();
        chunks.sort_by_key(|&c| asm.chunks[c].1);
        let size = chunks
            .iter()
            .map(|c| asm.bases[c] + asm.offsets.get(c).copied().unwrap_or(0))
            .max()
            .unwrap_or(0);
        let mut data = Vec::new();
        if def.ty != SHT_NOBITS {
            data = vec![0u8; size as usize];
            for c in &chunks {
                if let Some(b) = asm.bytes.get(c) {
                    let at = asm.bases[c] as usize;
                    data[at..at + b.len()].copy_from_slice(b);
                }
            }
        }
        let align = chunks
            .iter()
            .map(|c| asm.align.get(c).copied().unwrap_or(1))
            .max()
            .unwrap_or(1);
        obj.sections.push(ObjSection {
            name: def.name.clone(),
            ty: def.ty,
            flags: def.flags,
            entsize: def.entsize,
            align,
            size,
            data,
            relocs: Vec::new(),
        });
    }
    // obj-elf.c elf_adjust_symtab: a group per name, in its first section's order; COMDAT
    // where any member is.
    for (d, def) in asm.defs.iter().enumerate() {
        let Some(name) = &def.group else { continue };
        match obj.groups.iter_mut().find(|g| g.signature == *name) {
            Some(g) => {
                g.members.push(d);
                g.comdat |= def.comdat;
            }
            None => obj.groups.push(crate::object::Group {
                signature: name.clone(),
                comdat: def.comdat,
                members: vec![d],
            }),
        }
    }
    // gas writes `.debug_line` after every section the source made (`dwarf2_finish`).
    if let Some((data, relocs)) = asm.debug_line() {
        obj.sections.push(ObjSection {
            name: ".debug_line".into(),
            ty: crate::object::SHT_PROGBITS,
            flags: 0,
            entsize: 0,
            align: 1,
            size: data.len() as u32,
            data,
            relocs,
        });
        for s in asm.debug_unit(obj.sections.len()) {
            obj.sections.push(ObjSection {
                name: s.name.into(),
                ty: crate::object::SHT_PROGBITS,
                flags: s.flags,
                entsize: s.entsize,
                align: s.align,
                size: s.data.len() as u32,
                data: s.data,
                relocs: s.relocs,
            });
        }
    }
    for (d, r, _, _) in &asm.relocs {
        let mut r = r.clone();
        if let RelocTarget::Symbol(n) = &r.target {
            if let Some(t) = asm.weakref_target(n) {
                r.target = RelocTarget::Symbol(t);
            }
        }
        if r.target == RelocTarget::Section(usize::MAX) {
            // An absolute value: against no symbol.
            r.target = RelocTarget::Symbol(String::new());
        }
        obj.sections[*d].relocs.push(r);
    }
    let mut referenced: std::collections::BTreeSet<String> = Default::default();
    for s in &obj.sections {
        for r in &s.relocs {
            if let RelocTarget::Symbol(n) = &r.target {
                if !n.is_empty() {
                    referenced.insert(n.clone());
                }
            }
        }
    }
    // The symbols in chain order (names no walk mentioned, from the options, last).
    let mut links = asm.chain.borrow().links.clone();
    let mut rest: Vec<&String> = asm
        .symbols
        .keys()
        .filter(|n| !links.contains(&Link::Symbol(n.to_string())))
        .collect();
    rest.sort();
    links.extend(rest.into_iter().map(|n| Link::Symbol(n.clone())));
    // dwarf2dbg.c's dwarf2_finish makes the debug unit's section symbols after the
    // source's, in the order its fixups first name them.
    for debug in [
        ".debug_info",
        ".debug_abbrev",
        ".debug_line",
        ".debug_ranges",
        ".debug_str",
        ".debug_aranges",
    ] {
        if debug == ".debug_ranges" {
            // A section of a name another has (in a group) gets its symbol when the
            // line table's fixups first name it.
            for d in 0..asm.defs.len() {
                let named = obj
                    .sections
                    .iter()
                    .any(|s| s.relocs.iter().any(|r| r.target == RelocTarget::Section(d)));
                if named && !links.contains(&Link::Section(d)) {
                    links.push(Link::Section(d));
                }
            }
        }
        if let Some(k) = obj.sections.iter().position(|s| s.name == debug) {
            if asm.defs.iter().all(|d| d.name != debug) {
                links.push(Link::Section(k));
            }
        }
    }
    for link in links {
        let name = match link {
            Link::Section(d) => {
                obj.symbols.push(section_symbol(d));
                continue;
            }
            Link::File(name) => {
                obj.symbols.push(ObjSymbol {
                    name,
                    value: 0,
                    size: 0,
                    section: SymSection::Absolute,
                    global: false,
                    weak: false,
                    visibility: 0,
                    kind: 4,
                });
                continue;
            }
            Link::Symbol(name) if asm.weakrefs.contains_key(&name) => continue,
            Link::Symbol(name) => name,
        };
        let attrs = asm.attrs.get(&name).cloned().unwrap_or_default();
        let Some(sym) = asm.symbols.get(&name) else {
            let attrs = weak_through_weakref(&asm, &name, attrs);
            // Made but never defined: an undefined symbol, global (write.c), unless a
            // local label or only `.weak` named it and nothing refers to it.
            let used = referenced.contains(&name);
            if name.starts_with(".L") || (attrs.weak && !used) {
                continue;
            }
            obj.symbols.push(ObjSymbol {
                name,
                value: 0,
                size: attrs.size.unwrap_or(0) as u64,
                section: SymSection::Undefined,
                global: true,
                weak: attrs.weak,
                visibility: attrs.visibility,
                kind: attrs.kind,
            });
            continue;
        };
        let (section, value) = match sym {
            _ if asm.dot_eqv.contains_key(&name) => match asm.eqv_here(&name) {
                Some(v) if v.sect.is_some() => {
                    (SymSection::Section(v.sect.unwrap_or(0)), v.v as u64)
                }
                Some(v) if !v.reloc && !v.cross => (SymSection::Absolute, v.v as u64),
                _ => continue,
            },
            SymVal::Label(c, off) => (
                SymSection::Section(asm.chunks[*c].0),
                (asm.bases[c] + off) as u64,
            ),
            SymVal::Common(size, align) => {
                obj.symbols.push(ObjSymbol {
                    name: name.clone(),
                    value: *align as u64,
                    size: *size as u64,
                    section: SymSection::Common,
                    global: true,
                    weak: false,
                    visibility: attrs.visibility,
                    // An object, or thread-local from `.tls_common`.
                    kind: if attrs.kind == 6 { 6 } else { 1 },
                });
                continue;
            }
            // Equated to a place in a section (through a global label too): that place.
            SymVal::Abs(v) if v.sect.is_some() => {
                (SymSection::Section(v.sect.unwrap_or(0)), v.v as u64)
            }
            SymVal::Abs(v) if !v.reloc && !v.cross => (SymSection::Absolute, v.v as u64),
            SymVal::Abs(_) => continue,
        };
        // Local labels named `.L` stay out of the symbol table, as in gas.
        if name.starts_with(".L") && !attrs.global {
            continue;
        }
        obj.symbols.push(ObjSymbol {
            name: name.clone(),
            value,
            size: attrs.size.unwrap_or(0) as u64,
            section,
            global: attrs.global || attrs.weak,
            weak: attrs.weak,
            visibility: attrs.visibility,
            kind: attrs.kind,
        });
    }
    // `.symver` (obj-elf.c elf_frob_symbol): a defined symbol's versioned names follow
    // the symbols, each symbol's last first, with its place, size, type and binding; the
    // visibility given (`local`, `hidden`, `remove`) applies to the symbol itself. An
    // undefined symbol takes its versioned name in its place (`@@@` reads as `@`).
    let mut aliases = Vec::new();
    for s in &obj.symbols {
        if s.kind == 3 || s.section == SymSection::Undefined {
            continue;
        }
        for (name, alias, _) in asm.symvers.iter().rev() {
            if *name == s.name {
                let mut a = s.clone();
                a.name = alias.replace("@@@", "@@");
                aliases.push(a);
            }
        }
    }
    for (name, alias, vis) in &asm.symvers {
        let Some(k) = obj
            .symbols
            .iter()
            .position(|s| &s.name == name && s.kind != 3)
        else {
            continue;
        };
        if obj.symbols[k].section == SymSection::Undefined {
            let versioned = alias.replace("@@@", "@");
            for s in &mut obj.sections {
                for r in &mut s.relocs {
                    if r.target == RelocTarget::Symbol(name.clone()) {
                        r.target = RelocTarget::Symbol(versioned.clone());
                    }
                }
            }
            obj.symbols[k].name = versioned.clone();
            if referenced.remove(name) {
                referenced.insert(versioned);
            }
            continue;
        }
        match vis.as_str() {
            "local" => {
                obj.symbols[k].global = false;
                obj.symbols[k].weak = false;
            }
            "hidden" => obj.symbols[k].visibility = 2,
            "remove" if !referenced.contains(name) => {
                obj.symbols.remove(k);
            }
            _ => {}
        }
    }
    obj.symbols.extend(aliases);
    for name in referenced {
        if !obj.symbols.iter().any(|s| s.name == name && s.kind != 3) {
            let attrs = asm.attrs.get(&name).cloned().unwrap_or_default();
            let attrs = weak_through_weakref(&asm, &name, attrs);
            obj.symbols.push(ObjSymbol {
                name,
                value: 0,
                size: 0,
                section: SymSection::Undefined,
                global: true,
                weak: attrs.weak,
                visibility: attrs.visibility,
                kind: attrs.kind,
            });
        }
    }
    // The source was read a byte to a character: names go out as the bytes they were
    // written in (UTF-8 names as UTF-8).
    for s in &mut obj.symbols {
        s.name = display_text(&s.name);
    }
    for s in &mut obj.sections {
        for r in &mut s.relocs {
            if let RelocTarget::Symbol(n) = &mut r.target {
                *n = display_text(n);
            }
        }
    }
    obj
}

/// An undefined weakref target that no expression uses by itself and no `.globl` names
/// is weak (symbols.c `S_IS_WEAKREFD`; write.c drops it if nothing refers to it).
fn weak_through_weakref(asm: &Assembler<'_>, name: &str, mut attrs: SymAttrs) -> SymAttrs {
    let targeted = asm
        .weakrefs
        .keys()
        .any(|a| asm.weakref_target(a).as_deref() == Some(name));
    if targeted && !attrs.global && !asm.direct_uses.borrow().contains(name) {
        attrs.weak = true;
    }
    attrs
}
