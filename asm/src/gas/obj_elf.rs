//! Sections and symbol attributes as ELF has them (gas's `obj-elf.c`): `.section` with
//! its flags and type, subsections, `.pushsection`/`.popsection`/`.previous`, `.comm` and
//! `.lcomm`, and `.global`, `.weak`, `.hidden`, `.type`, `.size`.

use super::symbols::{quoted_name, SymVal, STT_GNU_IFUNC};
use super::{Assembler, Severity, LOCAL_STORE};
use crate::lex::{split_top, Line};
use crate::object::{SHF_ALLOC, SHF_EXECINSTR, SHF_WRITE, SHT_NOBITS, SHT_PROGBITS};

/// A section as `.section` declared it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct SectionDef {
    pub(super) name: String,
    pub(super) ty: u32,
    pub(super) flags: u64,
    pub(super) entsize: u64,
    /// The section group it belongs to (`G` or `?`, or `.attach_to_group`): a section
    /// is known by its name and group together.
    pub(super) group: Option<String>,
    /// Whether that group is COMDAT (`comdat`, or a `.gnu.linkonce` name).
    pub(super) comdat: bool,
}

/// BFD's special sections (elf.c `special_sections_*`, those of a type gas writes;
/// elf32-spu.c's `._ea` and `.toe` first): prefix, suffix rule (0: the name exactly;
/// -1: any name starting so; -2: the name or the name, a dot and more), type, flags.
const SPECIAL_SECTIONS: &[(&str, i8, u32, u64)] = &[
    ("._ea", 0, SHT_PROGBITS, SHF_WRITE),
    (".toe", 0, SHT_NOBITS, SHF_ALLOC),
    (".bss", -2, SHT_NOBITS, SHF_ALLOC | SHF_WRITE),
    (".comment", 0, SHT_PROGBITS, 0),
    (".ctf", 0, SHT_PROGBITS, 0),
    (".data", -2, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE),
    (".data1", 0, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE),
    (".debug", 0, SHT_PROGBITS, 0),
    (".debug_line", 0, SHT_PROGBITS, 0),
    (".debug_info", 0, SHT_PROGBITS, 0),
    (".debug_abbrev", 0, SHT_PROGBITS, 0),
    (".debug_aranges", 0, SHT_PROGBITS, 0),
    (".fini", 0, SHT_PROGBITS, SHF_ALLOC | SHF_EXECINSTR),
    (".fini_array", -2, 15, SHF_ALLOC | SHF_WRITE),
    (".gnu.linkonce.b", -2, SHT_NOBITS, SHF_ALLOC | SHF_WRITE),
    (".gnu.linkonce.n", -2, SHT_NOBITS, SHF_ALLOC | SHF_WRITE),
    (".gnu.linkonce.p", -2, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE),
    (".gnu.lto_", -1, SHT_PROGBITS, 0x8000_0000),
    (".got", 0, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE),
    (".init", 0, SHT_PROGBITS, SHF_ALLOC | SHF_EXECINSTR),
    (".init_array", -2, 14, SHF_ALLOC | SHF_WRITE),
    (".interp", 0, SHT_PROGBITS, 0),
    (".line", 0, SHT_PROGBITS, 0),
    (".noinit", -2, SHT_NOBITS, SHF_ALLOC | SHF_WRITE),
    (".note.GNU-stack", 0, SHT_PROGBITS, 0),
    (".note", -1, 7, 0),
    (".persistent.bss", 0, SHT_NOBITS, SHF_ALLOC | SHF_WRITE),
    (".persistent", -2, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE),
    (".preinit_array", -2, 16, SHF_ALLOC | SHF_WRITE),
    (".plt", 0, SHT_PROGBITS, SHF_ALLOC | SHF_EXECINSTR),
    (".rodata", -2, SHT_PROGBITS, SHF_ALLOC),
    (".rodata1", 0, SHT_PROGBITS, SHF_ALLOC),
    (".text", -2, SHT_PROGBITS, SHF_ALLOC | SHF_EXECINSTR),
    (".tbss", -2, SHT_NOBITS, SHF_ALLOC | SHF_WRITE | 0x400),
    (".tdata", -2, SHT_PROGBITS, SHF_ALLOC | SHF_WRITE | 0x400),
    (".zdebug_line", 0, SHT_PROGBITS, 0),
    (".zdebug_info", 0, SHT_PROGBITS, 0),
    (".zdebug_abbrev", 0, SHT_PROGBITS, 0),
    (".zdebug_aranges", 0, SHT_PROGBITS, 0),
];

impl SectionDef {
    /// A section BFD knows by name (`_bfd_elf_get_special_section`, the first entry of
    /// `SPECIAL_SECTIONS` that matches): its type and flags, if `name` is one.
    pub(super) fn special(name: &str) -> Option<SectionDef> {
        let (_, _, ty, flags) = SPECIAL_SECTIONS.iter().find(|(prefix, suffix, _, _)| {
            let Some(rest) = name.strip_prefix(prefix) else {
                return false;
            };
            match suffix {
                0 => rest.is_empty(),
                -2 => rest.is_empty() || rest.starts_with('.'),
                _ => true,
            }
        })?;
        Some(SectionDef {
            name: name.to_string(),
            ty: *ty,
            flags: *flags,
            // BFD gives the array sections their entries' size.
            entsize: if matches!(ty, 14..=16) { 4 } else { 0 },
            group: None,
            comdat: false,
        })
    }

    /// GNU as's defaults for a section named without flags: a special section's, else
    /// data of no attributes.
    pub(super) fn named(name: &str) -> SectionDef {
        SectionDef::special(name).unwrap_or(SectionDef {
            name: name.to_string(),
            ty: SHT_PROGBITS,
            flags: 0,
            entsize: 0,
            group: None,
            comdat: false,
        })
    }
}

impl Assembler<'_> {
    /// The subsection number after `.text`, `.data`, `.bss`, `.subsection` (0 if none).
    pub(super) fn subsection(&mut self, args: &str, line: &Line, col: usize) -> i64 {
        if args.trim().is_empty() {
            return 0;
        }
        match self.eval(args.trim()) {
            Ok((v, _)) => v,
            Err((c, m)) => {
                self.diag(Severity::Error, line, col + c, m);
                0
            }
        }
    }

    /// `.section NAME[, "FLAGS"[, @TYPE[, ENTSIZE]]]` (also `%type` and a quoted type),
    /// or `NAME, SUBSECTION`; `.pushsection NAME, SUBSECTION, "FLAGS", ...` (`push`).
    /// The checks of obj-elf.c's `obj_elf_change_section` on a special section's type
    /// and attributes, and on a section named again with others.
    pub(super) fn section_args(
        &mut self,
        args: &str,
        line: &Line,
        col: usize,
        push: bool,
    ) -> Option<(SectionDef, i64)> {
        let mut parts = split_top(args, ',');
        let name = parts[0].trim().trim_matches('"').to_string();
        if name.is_empty() {
            self.diag(Severity::Error, line, col, "missing name");
            return None;
        }
        let mut def = SectionDef::named(&name);
        let mut sub = 0;
        // obj_elf_section: `.pushsection` takes a subsection right after the name.
        if push && parts.len() > 1 && parts[1].trim().starts_with(|c: char| c.is_ascii_digit()) {
            sub = self.subsection(&parts[1], line, col);
            parts.remove(1);
        }
        (def.group, def.comdat) = self.group_of(&parts, &name);
        // Whether gas made the section before this directive (`old_sec`), known in the
        // final walk only; errors that depend on it are given there.
        let fresh = self.first_in_walk(&name, &def.group);
        let old = self.pass == 2 && !fresh;
        let special = SectionDef::special(&name);
        let mut attr = 0u64;
        if let Some(flags) = parts.get(1).map(|f| f.trim()) {
            if let Some(letters) = flags.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
                let mut f = 0;
                let mut mbind = false;
                // obj-elf.c's compatibility spellings: "am" is "aM", "ams" is "aMS".
                let letters = letters.replacen("ams", "aMS", 1).replacen("am", "aM", 1);
                let mut chars = letters.char_indices().peekable();
                while let Some((at, c)) = chars.next() {
                    match c {
                        'e' => f |= 0x8000_0000,
                        'a' => f |= SHF_ALLOC,
                        'w' => f |= SHF_WRITE,
                        'x' => f |= SHF_EXECINSTR,
                        'M' => f |= 0x10,
                        'S' => f |= 0x20,
                        'G' => f |= 0x200,
                        'T' => f |= 0x400,
                        'o' => f |= 0x80,
                        'd' => mbind = true,
                        'R' | '?' => {}
                        '0'..='9' => {
                            // A number among the letters (strtoul, base 0) adds its bits.
                            let rest = &letters[at..];
                            let (digits, radix) =
                                match rest.strip_prefix("0x").or(rest.strip_prefix("0X")) {
                                    Some(hex) => (hex, 16),
                                    None if rest.starts_with('0') => (rest, 8),
                                    None => (rest, 10),
                                };
                            let len = digits
                                .find(|c: char| !c.is_digit(radix))
                                .unwrap_or(digits.len());
                            f |= u64::from_str_radix(&digits[..len], radix).unwrap_or(0)
                                & 0xffff_ffff;
                            let end = at + (rest.len() - digits.len()) + len;
                            while chars.peek().is_some_and(|(i, _)| *i < end) {
                                chars.next();
                            }
                        }
                        other => {
                            self.diag(
                                Severity::Error,
                                line,
                                col,
                                format!("unknown section attribute `{other}'"),
                            );
                            return None;
                        }
                    }
                }
                if mbind && f & SHF_ALLOC == 0 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("SHF_ALLOC isn't set for GNU_MBIND section: {name}"),
                    );
                    return None;
                }
                if f & 0x10 != 0 && parts.len() < 4 {
                    f &= !0x10; // obj-elf.c drops SHF_MERGE without an entity size
                    self.diag(
                        Severity::Warning,
                        line,
                        col,
                        "entity size for SHF_MERGE not specified",
                    );
                }
                if def.group.is_some() {
                    f |= 0x200;
                } else if f & 0x200 != 0 {
                    f &= !0x200; // and SHF_GROUP without a group
                    self.diag(
                        Severity::Warning,
                        line,
                        col,
                        "group name for SHF_GROUP not specified",
                    );
                }
                attr = f;
                // A special section named with attributes it lacks takes them as given,
                // with a warning (none in a group); a .note may be allocated or code,
                // and `.rodata.str1.1` and the like may merge strings; otherwise it
                // keeps its own as well (obj-elf.c).
                const LINK_ORDER_OS_PROC: u64 = 0x80 | 0x0ff0_0000 | 0xf000_0000;
                match &special {
                    Some(sp) if !old && f & !LINK_ORDER_OS_PROC & !sp.flags != 0 => {
                        let extra = f & !LINK_ORDER_OS_PROC & !sp.flags;
                        let note_alloc = sp.ty == 7 && (f == SHF_ALLOC || f == SHF_EXECINSTR);
                        let merge = name[1..].contains('.') && extra & !0x30 == 0;
                        if note_alloc || merge {
                            def.flags = f | sp.flags;
                        } else {
                            if fresh && f & 0x200 == 0 {
                                self.diag(
                                    Severity::Warning,
                                    line,
                                    col,
                                    format!("setting incorrect section attributes for {name}"),
                                );
                            }
                            def.flags = f;
                        }
                    }
                    Some(sp) => def.flags = f | sp.flags,
                    None => def.flags = f,
                }
            } else if !flags.is_empty() && !flags.starts_with(['#', '@', '%']) {
                // `.section NAME, SUBSECTION` (the non-ELF form gas also takes).
                sub = self.subsection(flags, line, col);
            }
        }
        let mut ty_given = None;
        if let Some(ty) = parts.get(2).map(|t| t.trim()) {
            match ty.trim_matches('"').trim_start_matches(['@', '%']) {
                "progbits" => def.ty = SHT_PROGBITS,
                "nobits" => def.ty = SHT_NOBITS,
                "note" => def.ty = 7,
                // BFD gives the array sections their entries' size.
                "init_array" => (def.ty, def.entsize) = (14, 4),
                "fini_array" => (def.ty, def.entsize) = (15, 4),
                "preinit_array" => (def.ty, def.entsize) = (16, 4),
                other => {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unrecognized section type `{other}'"),
                    );
                    return None;
                }
            }
            ty_given = Some(def.ty);
        }
        if let (Some(sp), Some(ty)) = (&special, ty_given) {
            if ty != sp.ty {
                let array = matches!(sp.ty, 14..=16);
                if !old && !array {
                    if sp.ty != 7 {
                        self.diag(
                            Severity::Warning,
                            line,
                            col,
                            format!("setting incorrect section type for {name}"),
                        );
                    }
                } else {
                    self.diag(
                        Severity::Warning,
                        line,
                        col,
                        format!("ignoring incorrect section type for {name}"),
                    );
                    ty_given = Some(sp.ty);
                }
            }
        }
        if let Some(e) = parts.get(3) {
            if def.flags & 0x10 != 0 {
                def.entsize = self.eval(e.trim()).map(|v| v.0 as u64).unwrap_or(0);
            }
        }
        if self.pass == 2 && !old && self.defined.contains(&name) {
            // gas's section symbol is named as the section (obj-elf.c).
            self.diag(
                Severity::Error,
                line,
                col,
                format!("section name '{name}' already defined as another symbol"),
            );
        }
        if let Some(existing) = (self.defs.iter())
            .find(|d| d.name == name && d.group == def.group)
            .cloned()
        {
            // Re-entering a section keeps what it was declared with; a different type
            // or different attributes are an error, a warning for a special section.
            if old {
                if ty_given.is_some_and(|t| t != existing.ty) {
                    let m = format!("changed section type for {name}");
                    match special {
                        Some(_) => self.diag(Severity::Warning, line, col, format!("ignoring {m}")),
                        None => self.diag(Severity::Error, line, col, m),
                    }
                }
                // The BFD flags gas compares: alloc, load, read-only, code, exclude,
                // merge, strings, TLS.
                let bfd = |f: u64, ty: u32| {
                    let alloc = f & SHF_ALLOC != 0;
                    (
                        alloc,
                        alloc && ty != SHT_NOBITS,
                        f & SHF_WRITE == 0,
                        f & (SHF_EXECINSTR | 0x8000_0000 | 0x10 | 0x20 | 0x400),
                    )
                };
                let ty = ty_given.or(special.as_ref().map(|s| s.ty)).unwrap_or(0);
                if attr != 0 && bfd(attr, ty) != bfd(existing.flags, existing.ty) {
                    let m = format!("changed section attributes for {name}");
                    match special {
                        Some(_) => self.diag(Severity::Warning, line, col, format!("ignoring {m}")),
                        None => self.diag(Severity::Error, line, col, m),
                    }
                }
            }
            def = existing;
        }
        Some((def, sub))
    }

    /// The group a `.section` names (obj-elf.c `obj_elf_section`): after `G`, the
    /// argument past the type, entity size (`M`) and linked-to section (`o`), then
    /// `comdat`; with `?`, the current section's group.
    fn group_of(&self, parts: &[String], name: &str) -> (Option<String>, bool) {
        let Some(letters) = parts.get(1).and_then(|f| {
            let f = f.trim();
            f.strip_prefix('"').and_then(|f| f.strip_suffix('"'))
        }) else {
            return (None, false);
        };
        if letters.contains('G') {
            let typed = parts
                .get(2)
                .is_some_and(|t| t.trim().starts_with(['"', '@', '%']));
            let at = 2
                + typed as usize
                + letters.contains('M') as usize
                + letters.contains('o') as usize;
            let Some(group) = parts
                .get(at)
                .map(|g| g.trim().trim_matches('"').to_string())
            else {
                return (None, false);
            };
            if group.is_empty() {
                return (None, false);
            }
            let comdat = parts
                .get(at + 1)
                .is_some_and(|c| c.trim().starts_with("comdat"))
                || (parts.len() == at + 1 && name.starts_with(".gnu.linkonce"));
            return (Some(group), comdat);
        }
        if letters.contains('?') {
            let now = &self.defs[self.chunks[self.sect].0];
            return (now.group.clone(), now.comdat);
        }
        (None, false)
    }

    /// Whether the final walk meets section `name` here for the first time (gas makes it
    /// now; .text, .data and .bss are made before): where gas warns of attributes.
    fn first_in_walk(&self, name: &str, group: &Option<String>) -> bool {
        self.pass == 2
            && self
                .defs
                .iter()
                .position(|d| d.name == name && d.group == *group)
                .is_none_or(|d| !self.chain.borrow().has_section(d))
    }

    /// `.lcomm NAME, SIZE[, ALIGN]` reserves space in `.bss`; `.comm` does too in an
    /// executable, and leaves a common symbol for the linker in an object.
    pub(super) fn common(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        let parts = split_top(args, ',');
        let name = parts[0].trim().to_string();
        if d == ".bss" && (name.is_empty() || parts.len() < 3) {
            let m = if name.is_empty() {
                "expected symbol name"
            } else {
                "expected alignment after size"
            };
            self.diag(Severity::Error, line, col, m);
            return;
        }
        if name.is_empty() || parts.len() < 2 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("expected NAME, SIZE after {d}"),
            );
            return;
        }
        if d == ".lcomm" && parts.len() > 2 {
            // spu-elf-as 2.40's .lcomm takes no alignment.
            self.diag(
                Severity::Error,
                line,
                col,
                "junk at end of line, first unrecognized character is `,'",
            );
            return;
        }
        let size = self
            .data_values(&parts[1], line, col)
            .first()
            .copied()
            .unwrap_or(0);
        if !(0..=LOCAL_STORE as i64).contains(&size) {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("{d} length ({size}) out of range"),
            );
            return;
        }
        // gas TC_IMPLICIT_LCOMM_ALIGNMENT: the largest of 8, 4, 2 that the size reaches.
        let implicit = match size {
            8.. => 8,
            4..=7 => 4,
            2..=3 => 2,
            _ => 1,
        };
        let align = match parts.get(2) {
            Some(a) => self.data_values(a, line, col).first().copied().unwrap_or(1),
            None => implicit,
        };
        if align <= 0 || align & (align - 1) != 0 || align > 1 << 15 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("alignment {align} is not a power of 2"),
            );
            return;
        }
        self.note_symbol(&name);
        if d == ".comm" {
            self.attrs.entry(name.clone()).or_default().global = true;
            if let Some(SymVal::Common(old, _)) = self.symbols.get(&name) {
                // read.c s_comm_internal: the first size stays.
                if *old as i64 != size {
                    let m = format!("size of \"{name}\" is already {old}; not changing to {size}");
                    self.diag(Severity::Warning, line, col, m);
                }
                if self.object {
                    return;
                }
            }
            if self.object && self.pass == 2 {
                self.common_conflicts(&name, line, col);
            }
            if self.object {
                if matches!(self.symbols.get(&name), Some(SymVal::Label(..))) {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("symbol `{name}' is already defined"),
                    );
                    return;
                }
                self.symbols
                    .insert(name, SymVal::Common(size as u32, align as u32));
                return;
            }
        }
        // read.c bss_alloc: a symbol of its size, an object unless `.bss` made it.
        let a = self.attrs.entry(name.clone()).or_default();
        a.kind = if d == ".bss" { 0 } else { 1 };
        a.size = Some(size);
        let here = self.sect;
        let bss = self.chunk(SectionDef::named(".bss"), 0);
        self.sect = bss;
        self.align_to(align as u32, Some(0));
        self.define_label(&name, line);
        self.emit(&vec![0; size as usize]);
        self.sect = here;
    }

    /// `.ident "TEXT"` (obj-elf.c obj_elf_ident): the string into `.comment` (mergeable
    /// strings), after one zero byte the first time, without changing the section.
    pub(super) fn ident(&mut self, args: &str, line: &Line, col: usize) {
        let Some(mut text) = crate::lex::unquote(args.trim()) else {
            self.diag(Severity::Error, line, col, "expected a string");
            return;
        };
        let def = SectionDef {
            name: ".comment".into(),
            ty: crate::object::SHT_PROGBITS,
            flags: 0x30, // SHF_MERGE | SHF_STRINGS
            entsize: 1,
            group: None,
            comdat: false,
        };
        let (here, absolute) = (self.sect, self.absolute.take());
        let c = self.chunk(def, 0);
        self.sect = c;
        if self.offsets.get(&c).copied().unwrap_or(0) == 0 {
            self.emit(&[0]);
        }
        text.push(0);
        self.emit(&text);
        self.sect = here;
        self.absolute = absolute;
    }

    /// The section and symbol-attribute directives; whether `d` was one.
    pub(super) fn elf_directive(&mut self, d: &str, args: &str, line: &Line, col: usize) -> bool {
        match d {
            // tc-spu.c: `.bss NAME, SIZE, ALIGN` reserves space in .bss (s_lcomm_bytes);
            // it does not switch to it, and there is no `.rodata` directive.
            ".bss" => self.common(d, args, line, col),
            ".text" | ".data" => {
                let sub = self.subsection(args, line, col);
                let c = self.chunk(SectionDef::named(d), sub);
                self.note_section(self.chunks[c].0);
                self.switch_to(c);
            }
            ".subsection" => {
                let sub = self.subsection(args, line, col);
                let def = self.defs[self.chunks[self.sect].0].clone();
                let c = self.chunk(def, sub);
                self.switch_to(c);
            }
            ".section" | ".pushsection" => {
                let Some((def, sub)) = self.section_args(args, line, col, d == ".pushsection")
                else {
                    return true;
                };
                if d == ".pushsection" {
                    self.sect_stack.push((self.sect, self.prev_sect));
                }
                let c = self.chunk(def, sub);
                self.note_section(self.chunks[c].0);
                self.switch_to(c);
            }
            ".attach_to_group" => {
                let name = args.trim().trim_matches('"').to_string();
                let d = self.chunks[self.sect].0;
                if name.is_empty() {
                    self.diag(Severity::Warning, line, col, "group name not parseable");
                } else if let Some(group) = &self.defs[d].group {
                    let m = format!(
                        "section {} already has a group ({group})",
                        self.defs[d].name
                    );
                    self.diag(Severity::Warning, line, col, m);
                } else {
                    self.attached.push((d, self.defs[d].flags));
                    self.defs[d].group = Some(name);
                    self.defs[d].flags |= 0x200;
                }
            }
            ".popsection" => match self.sect_stack.pop() {
                Some((s, p)) => {
                    self.sect = s;
                    self.prev_sect = p;
                }
                None => self.diag(
                    Severity::Warning,
                    line,
                    col,
                    ".popsection without corresponding .pushsection; ignored",
                ),
            },
            ".previous" => {
                std::mem::swap(&mut self.sect, &mut self.prev_sect);
            }
            ".lcomm" | ".comm" => self.common(d, args, line, col),
            ".tls_common" => {
                // obj-elf.c obj_elf_tls_common: `.comm` of a thread-local object.
                self.common(".comm", args, line, col);
                let name = split_top(args, ',')[0].trim().to_string();
                if matches!(self.symbols.get(&name), Some(SymVal::Common(..))) {
                    self.attrs.entry(name).or_default().kind = 6;
                }
            }
            ".symver" => {
                // obj-elf.c obj_elf_symver: `NAME, ALIAS@VERSION` (or `@@`, `@@@`), then
                // an optional visibility for the alias.
                let parts = split_top(args, ',');
                let name = parts.first().map(|p| p.trim()).unwrap_or("");
                let alias = parts.get(1).map(|p| p.trim()).unwrap_or("");
                let vis = parts.get(2).map(|p| p.trim()).unwrap_or("");
                if name.is_empty() || alias.is_empty() {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        "expected comma after name in .symver",
                    );
                } else if !alias.contains('@') {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("missing version name in `{alias}' for symbol `{name}'"),
                    );
                } else if !matches!(vis, "" | "local" | "hidden" | "remove") {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unknown visibility `{vis}' for .symver (local, hidden or remove)"),
                    );
                } else if self.pass == 2 {
                    if matches!(self.symbols.get(name), Some(SymVal::Common(..))) {
                        self.diag(
                            Severity::Error,
                            line,
                            col,
                            format!("`{alias}' can't be versioned to common symbol '{name}'"),
                        );
                    }
                    self.symvers
                        .push((name.to_string(), alias.to_string(), vis.to_string()));
                }
            }
            ".weak" | ".hidden" | ".internal" | ".protected" | ".global" | ".globl" => {
                for n in split_top(args, ',') {
                    let n = n.trim();
                    if n.is_empty() {
                        continue;
                    }
                    let quoted = quoted_name(n).filter(|(_, after)| after.trim().is_empty());
                    let n = quoted.as_ref().map_or(n, |(name, _)| name.as_str());
                    if matches!(d, ".global" | ".globl") && self.defs.iter().any(|s| s.name == n) {
                        // symbols.c S_SET_EXTERNAL: the name is the section's own symbol.
                        self.diag(
                            Severity::Warning,
                            line,
                            col,
                            "can't make section symbol global",
                        );
                        continue;
                    }
                    self.note_symbol(n);
                    let a = self.attrs.entry(n.to_string()).or_default();
                    match d {
                        ".weak" => a.weak = true,
                        ".global" | ".globl" => a.global = true,
                        ".internal" => a.visibility = 1,
                        ".hidden" => a.visibility = 2,
                        _ => a.visibility = 3,
                    }
                }
            }
            ".type" => {
                let parts = split_top(args, ',');
                let name = parts[0].trim().to_string();
                let kind = parts.get(1).map(|k| {
                    k.trim()
                        .trim_matches('"')
                        .trim_start_matches(['@', '%', '#'])
                        .to_ascii_lowercase()
                });
                // BFD's flags for each type: function, object, indirect, thread-local.
                let (f, o, i, t) = (1u8, 2u8, 4u8, 8u8);
                let bits = match kind.as_deref() {
                    Some("function" | "stt_func" | "2") => f,
                    Some("object" | "stt_object" | "1") => o,
                    Some("notype" | "stt_notype" | "0") => 0,
                    Some("tls_object" | "stt_tls" | "6") => o | t,
                    Some("gnu_indirect_function" | "stt_gnu_ifunc" | "10") => f | i,
                    // obj-elf.c: a common-typed symbol is a global object.
                    Some("common" | "stt_common" | "5") => {
                        self.note_symbol(&name);
                        let a = self.attrs.entry(name).or_default();
                        a.kind = 1;
                        a.global = true;
                        return true;
                    }
                    _ => {
                        self.diag(
                            Severity::Error,
                            line,
                            col,
                            format!(
                                "unrecognized symbol type \"{}\"",
                                parts.get(1).map_or("", |s| s.trim())
                            ),
                        );
                        return true;
                    }
                };
                self.note_symbol(&name);
                let pass = self.pass;
                let a = self.attrs.entry(name.clone()).or_default();
                // obj-elf.c obj_elf_type: a new type clears the flags of the others but
                // keeps an indirect function's under `function` and thread-local under
                // `object`; a change other than to notype warns.
                let old = if a.type_pass == pass { a.type_bits } else { 0 };
                let mut mask = f | o;
                if bits != f {
                    mask |= i;
                }
                if bits != o {
                    mask |= t;
                }
                let new = (old & !mask) | bits;
                let warn = bits != 0 && new != old | bits;
                a.type_bits = new;
                a.type_pass = pass;
                a.gnu_osabi |= bits & i != 0;
                a.kind = if new & t != 0 {
                    6
                } else if new & i != 0 {
                    STT_GNU_IFUNC
                } else if new & f != 0 {
                    2
                } else if new & o != 0 {
                    1
                } else {
                    0
                };
                if warn {
                    let m = format!("symbol '{name}' already has its type set");
                    self.diag(Severity::Warning, line, col, m);
                }
            }
            ".size" => {
                let parts = split_top(args, ',');
                if parts.len() < 2 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        "expected comma after name in .size",
                    );
                    return true;
                }
                let name = parts[0].trim().to_string();
                self.note_symbol(&name);
                match self.eval_val(parts[1..].join(",").trim()) {
                    Ok((v, _, _)) if v.cross && self.object && self.pass == 2 => {
                        // obj-elf.c elf_frob_symbol: a size across sections stays an
                        // expression, which the object cannot hold.
                        let m =
                            format!(".size expression for {name} does not evaluate to a constant");
                        self.diag(Severity::Error, line, col, m);
                    }
                    Ok((v, _, _)) if !v.reloc || self.pass == 1 => {
                        let a = self.attrs.entry(name).or_default();
                        a.size = Some(v.v);
                        a.size_copied = false;
                    }
                    Ok(_) => {} // a size that depends on an address: gas keeps an expression; we drop it
                    Err((c, m)) => self.diag(Severity::Error, line, col + c, m),
                }
            }
            _ => return false,
        }
        true
    }

    /// What gas refuses of a common symbol `name` (obj-elf.c `elf_frob_symbol`,
    /// symbols.c `resolve_symbol_value`, write.c): being weak too, having an equate, or
    /// a versioned name; checked at its `.comm` in the final walk, where the directives
    /// before and after it are both known.
    fn common_conflicts(&mut self, name: &str, line: &Line, col: usize) {
        if self.attrs.get(name).is_some_and(|a| a.weak) {
            let m = format!("symbol `{name}' can not be both weak and common");
            self.diag(Severity::Error, line, col, m);
        }
        let equated = |m: &std::collections::HashMap<String, SymVal>| {
            m.iter()
                .filter(|(_, v)| {
                    matches!(v, SymVal::Abs(v) if v.sym.as_ref().is_some_and(|s| &*s.0 == name))
                })
                .map(|(k, _)| k.clone())
                .collect::<Vec<_>>()
        };
        let mut names = equated(&self.symbols);
        names.extend(equated(&self.pass1_symbols));
        names.sort();
        names.dedup();
        for e in names {
            let m = format!("`{e}' can't be equated to common symbol `{name}'");
            self.diag(Severity::Error, line, col, m);
        }
        let versioned: Vec<String> = (self.symvers.iter())
            .filter(|v| v.0 == name)
            .map(|v| v.1.clone())
            .collect();
        for alias in versioned {
            let m = format!("`{alias}' can't be versioned to common symbol '{name}'");
            self.diag(Severity::Error, line, col, m);
        }
    }

    /// End of the final walk (obj-elf.c `elf_frob_symbol`): a symbol `.symver ...,
    /// remove` would take out stays when a relocation names it, which cannot be when it
    /// has more than one versioned name.
    pub(super) fn symver_checks(&mut self) {
        let mut named: Vec<&str> = Vec::new();
        for (name, _, vis) in &self.symvers {
            let versions = self.symvers.iter().filter(|v| v.0 == *name).count();
            if vis == "remove" && versions > 1 && !named.contains(&name.as_str()) {
                named.push(name);
            }
        }
        let mut found = Vec::new();
        for name in named {
            let target = crate::object::RelocTarget::Symbol(name.to_string());
            if let Some((_, _, at, text)) = self.relocs.iter().find(|r| r.1.target == target) {
                let line = Line {
                    text: text.clone(),
                    file: at.file.clone(),
                    line: at.line,
                };
                found.push((line, at.column, name.to_string()));
            }
        }
        for (line, column, name) in found {
            self.diag(
                Severity::Error,
                &line,
                column,
                format!("symbol '{name}' with multiple versions cannot be used in relocation"),
            );
        }
    }
}
