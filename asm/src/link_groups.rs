//! COMDAT section groups in a link, as GNU ld treats them: the first group of a
//! signature is kept and each later one is discarded, its sections emptied and the
//! global symbols it defined left to the kept copy. What would reach into a discarded
//! section from outside it is refused, never linked to the wrong bytes.

use crate::object::{Object, RelocTarget, SymSection};
use std::collections::HashMap;

/// `objects` with each later COMDAT group's sections emptied (their indices kept), or
/// the references into them that cannot be kept.
pub(crate) fn discard_duplicate_groups(objects: &[Object]) -> Result<Vec<Object>, Vec<String>> {
    let mut first: HashMap<&str, usize> = HashMap::new();
    let mut out = objects.to_vec();
    let mut errors = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for g in obj.groups.iter().filter(|g| g.comdat) {
            let kept = *first.entry(g.signature.as_str()).or_insert(o);
            if kept == o {
                continue;
            }
            let dropped = &mut out[o];
            for &m in &g.members {
                let s = &mut dropped.sections[m];
                (s.size, s.align) = (0, 1);
                s.data.clear();
                s.relocs.clear();
            }
            let inside =
                |k: &SymSection| matches!(k, SymSection::Section(s) if g.members.contains(s));
            for sym in &mut dropped.symbols {
                if sym.global && inside(&sym.section) {
                    (sym.section, sym.value) = (SymSection::Undefined, 0);
                }
            }
            // A section outside the group naming a local of a discarded section.
            for s in &dropped.sections {
                for r in &s.relocs {
                    let into = match &r.target {
                        RelocTarget::Section(t) => g.members.contains(t),
                        RelocTarget::Symbol(n) => dropped.symbols.iter().any(|x| {
                            !x.global && !n.is_empty() && x.name == *n && inside(&x.section)
                        }),
                    };
                    if into {
                        errors.push(format!(
                            "{}: section {} refers to COMDAT group `{}', discarded for the copy in {}",
                            obj.name, s.name, g.signature, objects[kept].name
                        ));
                        break;
                    }
                }
            }
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors)
    }
}
