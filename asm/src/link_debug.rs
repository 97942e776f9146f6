//! The debugging sections of a link: every input's `.debug_*` sections (DWARF from
//! `.file`/`.loc`), joined by name in input order and relocated, as GNU ld keeps them in
//! an executable. They take no address and no part in the loaded image; a reference
//! from one to another (`.debug_info` to `.debug_line`, `.debug_abbrev`, `.debug_str`)
//! becomes an offset in the joined section.

use crate::executable::Unloaded;
use crate::object::{Object, RelocTarget, SymSection, SHF_ALLOC, SHT_PROGBITS};
use std::collections::HashMap;

/// The joined and relocated debugging sections. `resolve` gives the address of a
/// relocation target in the loaded program (object index, target), `None` if undefined.
pub(crate) fn sections(
    objects: &[Object],
    resolve: &dyn Fn(usize, &RelocTarget) -> Option<u64>,
) -> Result<Vec<Unloaded>, Vec<String>> {
    let mut out: Vec<Unloaded> = Vec::new();
    // (object, section) -> (output index, offset in it).
    let mut at: HashMap<(usize, usize), (usize, u32)> = HashMap::new();
    for (o, obj) in objects.iter().enumerate() {
        for (i, s) in obj.sections.iter().enumerate() {
            if s.flags & SHF_ALLOC != 0 || s.ty != SHT_PROGBITS || !s.name.starts_with(".debug") {
                continue;
            }
            let k = match out.iter().position(|u| u.name == s.name) {
                Some(k) => k,
                None => {
                    out.push(Unloaded {
                        name: s.name.clone(),
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
            u.data.extend_from_slice(&s.data);
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
        Ok(out)
    } else {
        errors.sort();
        Err(errors)
    }
}
