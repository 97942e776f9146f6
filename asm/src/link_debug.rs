//! The unloaded sections of a link: every input's non-allocated sections (DWARF from
//! `.file`/`.loc`, `.comment`, notes), joined by name in input order, relocated, and
//! ordered as GNU ld's default script orders them in an executable. They take no address and no part in the loaded image; a reference
//! from one to another (`.debug_info` to `.debug_line`, `.debug_abbrev`, `.debug_str`)
//! becomes an offset in the joined section.

use crate::executable::Unloaded;
use crate::object::{Object, RelocTarget, SymSection, SHF_ALLOC, SHT_PROGBITS};

const SHT_NOTE: u32 = 7;
const SHT_NOBITS: u32 = 8;
const SHF_MERGE: u64 = 0x10;
const SHF_EXCLUDE: u64 = 0x8000_0000;
/// The section types an unloaded output section takes: PROGBITS, NOTE, NOBITS and the
/// constructor arrays (INIT_ARRAY, FINI_ARRAY, PREINIT_ARRAY).
const KEPT_TYPES: [u32; 6] = [SHT_PROGBITS, SHT_NOTE, SHT_NOBITS, 14, 15, 16];

/// The type GNU ld gives an output section of the constructor arrays' names.
fn array_type(name: &str) -> Option<u32> {
    match name {
        ".init_array" => Some(14),
        ".fini_array" => Some(15),
        ".preinit_array" => Some(16),
        _ => None,
    }
}
const SHF_STRINGS: u64 = 0x20;

/// What GNU ld's default script throws away (`/DISCARD/`), by name prefix.
const DISCARDED: [&str; 3] = [".note.GNU-stack", ".gnu_debuglink", ".gnu.lto_"];

/// The unloaded output sections of GNU ld's default SPU script, in its order.
const SCRIPT: [&str; 38] = [
    ".stab",
    ".stabstr",
    ".stab.excl",
    ".stab.exclstr",
    ".stab.index",
    ".stab.indexstr",
    ".comment",
    ".gnu.build.attributes",
    ".debug",
    ".line",
    ".debug_srcinfo",
    ".debug_sfnames",
    ".debug_aranges",
    ".debug_pubnames",
    ".debug_info",
    ".debug_abbrev",
    ".debug_line",
    ".debug_frame",
    ".debug_str",
    ".debug_loc",
    ".debug_macinfo",
    ".debug_weaknames",
    ".debug_funcnames",
    ".debug_typenames",
    ".debug_varnames",
    ".debug_pubtypes",
    ".debug_ranges",
    ".debug_addr",
    ".debug_line_str",
    ".debug_loclists",
    ".debug_macro",
    ".debug_names",
    ".debug_rnglists",
    ".debug_str_offsets",
    ".debug_sup",
    ".gnu.attributes",
    ".note.spu_name",
    "._ea",
];

/// The output section the script sends an unloaded input section to (its name, or the
/// name of the statement whose wildcard takes it).
fn output_name(name: &str) -> &str {
    if name.starts_with(".gnu.linkonce.wi.") {
        ".debug_info"
    } else if name.starts_with(".debug_line.") || name == ".debug_line_end" {
        ".debug_line"
    } else if name.starts_with(".gnu.build.attributes.") {
        ".gnu.build.attributes"
    } else if name.starts_with("._ea.") {
        "._ea"
    } else if let Some(out) = crate::link::array_output(name) {
        out
    } else {
        name
    }
}

/// Where an unloaded output section stands: the script's order, and a section the
/// script does not name (an orphan) right after `.comment`, as GNU ld places one.
/// Whether the script names `name` among its unloaded sections (`NAME 0 : ...`).
pub(crate) fn in_script(name: &str) -> bool {
    SCRIPT.contains(&name)
}

pub(crate) fn script_rank(name: &str) -> usize {
    let at = |n: &str| SCRIPT.iter().position(|s| *s == n);
    match at(name) {
        Some(i) => 2 * i,
        None => 2 * at(".comment").unwrap_or(0) + 1,
    }
}
use std::collections::HashMap;

/// Where each input section went: (object, section) -> (joined section, offset in it).
pub(crate) type Joined = HashMap<(usize, usize), (usize, u32)>;

/// The joined and relocated debugging sections, and where each input went. `resolve`
/// gives the address of a relocation target in the loaded program (object index,
/// target), `None` if undefined.
pub(crate) fn sections(
    objects: &[Object],
    resolve: &dyn Fn(usize, &RelocTarget) -> Option<u64>,
) -> Result<(Vec<Unloaded>, Joined), Vec<String>> {
    let mut out: Vec<Unloaded> = Vec::new();
    // (object, section) -> (output index, offset in it).
    let mut at: Joined = HashMap::new();
    for (o, obj) in objects.iter().enumerate() {
        for (i, s) in obj.sections.iter().enumerate() {
            if s.flags & SHF_ALLOC != 0
                || s.flags & SHF_EXCLUDE != 0
                || !KEPT_TYPES.contains(&s.ty)
                || DISCARDED.iter().any(|d| s.name.starts_with(d))
            {
                continue;
            }
            let name = output_name(&s.name);
            let k = match out.iter().position(|u| u.name == name) {
                Some(k) => k,
                None => {
                    out.push(Unloaded {
                        name: name.to_string(),
                        ty: array_type(name).unwrap_or(s.ty),
                        flags: s.flags,
                        entsize: s.entsize,
                        align: 1,
                        data: Vec::new(),
                    });
                    out.len() - 1
                }
            };
            let u = &mut out[k];
            let align = s.align.max(1) as usize;
            u.align = u.align.max(align as u32);
            u.data.resize(u.data.len().next_multiple_of(align), 0);
            at.insert((o, i), (k, u.data.len() as u32));
            if s.ty == SHT_NOBITS {
                u.data.resize(u.data.len() + s.size as usize, 0);
            } else {
                u.data.extend_from_slice(&s.data);
            }
        }
    }
    let mut errors = Vec::new();
    for (&(o, i), &(k, base)) in &at {
        let obj = &objects[o];
        let s = &obj.sections[i];
        for r in &s.relocs {
            // A debugging section is at its offset in the joined one (address 0).
            let in_debug = |t: usize| at.get(&(o, t)).map(|&(_, off)| off as u64);
            let local = |n: &str| {
                obj.symbols
                    .iter()
                    .find(|x| !x.global && x.name == n)
                    .and_then(|x| match x.section {
                        SymSection::Section(t) => in_debug(t).map(|off| off + x.value),
                        _ => None,
                    })
            };
            let value = match &r.target {
                RelocTarget::Section(t) => in_debug(*t).or_else(|| resolve(o, &r.target)),
                RelocTarget::Symbol(n) => local(n).or_else(|| resolve(o, &r.target)),
            };
            let Some(value) = value else {
                let what = match &r.target {
                    RelocTarget::Section(t) => obj
                        .sections
                        .get(*t)
                        .map_or("?".to_string(), |x| x.name.clone()),
                    RelocTarget::Symbol(n) => n.clone(),
                };
                errors.push(format!(
                    "{}: undefined reference to `{what}' ({}+{:#x})",
                    obj.name, s.name, r.offset
                ));
                continue;
            };
            if let Err(m) = crate::reloc::apply(
                r.kind,
                &mut out[k].data,
                base + r.offset,
                value as i64 + r.addend,
            ) {
                errors.push(format!("{}: {}+{:#x}: {m}", obj.name, s.name, r.offset));
            }
        }
    }
    if errors.is_empty() {
        let targeted = targeted_sections(objects);
        for u in &mut out {
            if u.flags & (SHF_MERGE | SHF_STRINGS) == SHF_MERGE | SHF_STRINGS
                && u.entsize <= 1
                && !targeted.contains(u.name.as_str())
            {
                merge_strings(&mut u.data);
            }
        }
        // GNU ld drops an output section that received nothing.
        let mut kept: Vec<usize> = (0..out.len())
            .filter(|&k| !out[k].data.is_empty())
            .collect();
        kept.sort_by_key(|&k| script_rank(&out[k].name));
        let mut new_index = vec![None; out.len()];
        for (n, &k) in kept.iter().enumerate() {
            new_index[k] = Some(n);
        }
        let joined: Joined = at
            .into_iter()
            .filter_map(|(key, (k, off))| new_index[k].map(|n| (key, (n, off))))
            .collect();
        let mut slots: Vec<Option<Unloaded>> = out.into_iter().map(Some).collect();
        let out = kept.iter().filter_map(|&k| slots[k].take()).collect();
        Ok((out, joined))
    } else {
        errors.sort();
        Err(errors)
    }
}

/// The names of the sections some relocation points into (by section or by a symbol
/// defined in it): their contents must keep their offsets.
fn targeted_sections(objects: &[Object]) -> std::collections::HashSet<&str> {
    let mut out = std::collections::HashSet::new();
    for obj in objects {
        for s in &obj.sections {
            for r in &s.relocs {
                let t = match &r.target {
                    RelocTarget::Section(t) => Some(*t),
                    RelocTarget::Symbol(n) => {
                        obj.symbols
                            .iter()
                            .find(|x| x.name == *n)
                            .and_then(|x| match x.section {
                                SymSection::Section(t) => Some(t),
                                _ => None,
                            })
                    }
                };
                if let Some(t) = t.and_then(|t| obj.sections.get(t)) {
                    out.insert(output_name(&t.name));
                }
            }
        }
    }
    out
}

/// GNU ld's merging of a string section (`SHF_MERGE|SHF_STRINGS`, as `.comment`): each
/// string once, in the order first seen, and none that is the tail of another (the
/// empty string `.ident` puts first is the tail of every string).
fn merge_strings(data: &mut Vec<u8>) {
    if data.last() != Some(&0) {
        return; // not a string table: left as it is
    }
    let mut unique: Vec<&[u8]> = Vec::new();
    for s in data[..data.len() - 1].split(|b| *b == 0) {
        if !unique.contains(&s) {
            unique.push(s);
        }
    }
    let kept: Vec<&[u8]> = unique
        .iter()
        .filter(|s| !unique.iter().any(|t| t.len() > s.len() && t.ends_with(s)))
        .copied()
        .collect();
    let mut merged = Vec::new();
    for s in kept {
        merged.extend_from_slice(s);
        merged.push(0);
    }
    *data = merged;
}
