//! SPU overlays as GNU ld 2.40's SPU backend (`bfd/elf32-spu.c`) builds them for a
//! script's `OVERLAY` statements with the default (non-icache) overlay manager: each
//! overlay section numbered, a 16-byte call stub (`ila $78,overlay; lnop; ila
//! $79,target; br __ovly_load`) for each reference that needs one, chosen as
//! `needs_ovl_stub`/`count_stub` choose, `_ovly_table` and `_ovly_buf_table` in `.ovtab`,
//! and `_EAR_` in `.toe`. The overlay manager (`__ovly_load`, `__ovly_return`) is the
//! user's: `spu ld` does not carry GNU's built-in one.

use crate::object::{ObjSection, ObjSymbol, Object, RelocTarget, SymSection, SHF_ALLOC};
use crate::object::{SHF_EXECINSTR, SHF_WRITE, SHT_NOBITS, SHT_PROGBITS};
use crate::reloc::{R_SPU_ADDR16, R_SPU_REL16};
use std::collections::HashMap;

/// The name of the synthetic input that holds the linker's own overlay sections.
pub const LINKER_OBJECT: &str = "(overlay stubs and tables)";
pub const OVLY_LOAD: &str = "__ovly_load";
pub const OVLY_RETURN: &str = "__ovly_return";
const STUB_SIZE: u32 = 16;
const STT_FUNC: u8 = 2;
const STT_SECTION: u8 = 3;

/// One overlay section of the output.
#[derive(Clone, Debug)]
pub struct OverlaySection {
    /// The output section's name.
    pub name: String,
    /// 1-based, in the script's order.
    pub index: u32,
    /// The buffer (overlay region) it loads into, 1-based.
    pub buf: u32,
}

/// What a symbol a relocation names stands for: a global by name, or an object's local
/// symbol or section.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Key {
    Global(String),
    Local(usize, String),
    Section(usize, usize),
}

/// One stub: where it lives (0 the non-overlay `.stub`, else an overlay's own) and
/// where it goes.
#[derive(Clone, Debug)]
pub struct Stub {
    pub ovl: u32,
    /// The destination: a global by name, or (object, section, offset).
    pub dest: StubDest,
    /// Its offset in its `.stub` section.
    pub offset: u32,
}

#[derive(Clone, Debug)]
pub enum StubDest {
    /// A global and an addend.
    Global(String, i64),
    /// (object, section, offset): a local symbol or section plus the addend.
    At(usize, usize, i64),
}

/// The overlays of a link and the stubs they need.
#[derive(Clone, Debug, Default)]
pub struct Overlays {
    pub sections: Vec<OverlaySection>,
    pub num_buf: u32,
    pub stubs: Vec<Stub>,
    /// The stub each relocation (object, section, relocation index) goes through.
    pub redirect: HashMap<(usize, usize, usize), usize>,
    /// `_SPUEAR_` symbols and their stubs: the output's symbol is the stub.
    pub ears: Vec<(String, usize)>,
    /// The index of the linker's object among the inputs, and of its `.stub` sections
    /// (by overlay index), `.ovtab` and `.toe` in it.
    pub object: usize,
    pub ovtab: usize,
    pub toe: usize,
}

impl Overlays {
    /// The overlay index of an output section (0: not an overlay).
    pub fn index_of(&self, out: &str) -> u32 {
        self.sections
            .iter()
            .find(|s| s.name == out)
            .map_or(0, |s| s.index)
    }
}

/// The overlays of `regions` (each an `OVERLAY` statement's members that received
/// something), the stubs the relocations of `objects` need, and the linker's object
/// with the `.stub`, `.ovtab` and `.toe` sections, appended to `objects`.
/// `out_of(o, i)` names the output section of input section `i` of object `o`.
pub fn build(
    objects: &mut Vec<Object>,
    regions: &[Vec<String>],
    out_of: &dyn Fn(usize, usize) -> Option<String>,
) -> Result<Overlays, Vec<String>> {
    let mut ov = Overlays::default();
    for (b, members) in regions.iter().enumerate() {
        for name in members {
            let index = ov.sections.len() as u32 + 1;
            ov.sections.push(OverlaySection {
                name: name.clone(),
                index,
                buf: b as u32 + 1,
            });
        }
    }
    ov.num_buf = regions.len() as u32;
    let n = ov.sections.len();
    // Where each global is defined (strong over weak): (object, section, value, type).
    let mut globals: HashMap<&str, (usize, SymSection, u64, u8, bool)> = HashMap::new();
    for (o, obj) in objects.iter().enumerate() {
        for s in obj.symbols.iter().filter(|s| s.global) {
            if !matches!(s.section, SymSection::Section(_) | SymSection::Absolute) {
                continue;
            }
            match globals.get(s.name.as_str()) {
                Some(prev) if !prev.4 || s.weak => {}
                _ => {
                    globals.insert(&s.name, (o, s.section, s.value, s.kind, s.weak));
                }
            }
        }
    }
    if !globals.contains_key(OVLY_LOAD) {
        return Err(vec![format!(
            "overlays need an overlay manager: no `{OVLY_LOAD}' is defined (spu ld does \
             not carry GNU ld's built-in one; link one, e.g. tests/overlay/manager.s)"
        )]);
    }
    let ovl_of = |o: usize, i: usize| out_of(o, i).map_or(0, |name| ov.index_of(&name));
    let mut errors = Vec::new();
    for k in [OVLY_LOAD, OVLY_RETURN] {
        if let Some(&(o, SymSection::Section(i), ..)) = globals.get(k) {
            if ovl_of(o, i) != 0 {
                errors.push(format!("{k} in overlay section"));
            }
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    // needs_ovl_stub for each relocation: (object, section, reloc) -> (stub overlay,
    // key, addend, destination).
    let mut needs = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for (i, s) in obj.sections.iter().enumerate() {
            if s.flags & SHF_ALLOC == 0 || s.name == ".eh_frame" {
                continue;
            }
            let from_ovl = ovl_of(o, i);
            for (ri, r) in s.relocs.iter().enumerate() {
                let (key, dest, sec, kind) = match &r.target {
                    RelocTarget::Section(t) => (
                        Key::Section(o, *t),
                        StubDest::At(o, *t, r.addend),
                        (o, *t),
                        STT_SECTION,
                    ),
                    RelocTarget::Symbol(name) if name.is_empty() => continue,
                    RelocTarget::Symbol(name) => {
                        match obj.symbols.iter().find(|x| !x.global && x.name == *name) {
                            Some(x) => {
                                let SymSection::Section(t) = x.section else {
                                    continue;
                                };
                                (
                                    Key::Local(o, name.clone()),
                                    StubDest::At(o, t, x.value as i64 + r.addend),
                                    (o, t),
                                    x.kind,
                                )
                            }
                            None => match globals.get(name.as_str()) {
                                Some(&(d, SymSection::Section(t), _, kind, _)) => {
                                    if name == OVLY_LOAD || name == OVLY_RETURN {
                                        continue;
                                    }
                                    (
                                        Key::Global(name.clone()),
                                        StubDest::Global(name.clone(), r.addend),
                                        (d, t),
                                        kind,
                                    )
                                }
                                _ => continue,
                            },
                        }
                    }
                };
                let setjmp =
                    matches!(&key, Key::Global(n) if n == "setjmp" || n.starts_with("setjmp@"));
                let insn = s
                    .data
                    .get(r.offset as usize..r.offset as usize + 4)
                    .unwrap_or(&[0; 4]);
                let (branch, hint) = if r.kind == R_SPU_REL16 || r.kind == R_SPU_ADDR16 {
                    (
                        (insn[0] & 0xec) == 0x20 && (insn[1] & 0x80) == 0,
                        (insn[0] & 0xfc) == 0x10,
                    )
                } else {
                    (false, false)
                };
                let target_code = objects[sec.0].sections[sec.1].flags & SHF_EXECINSTR != 0;
                if kind != STT_FUNC && !(branch || hint) && !target_code {
                    continue;
                }
                let to_ovl = ovl_of(sec.0, sec.1);
                let mut stub = setjmp;
                let mut nonovl = false;
                if to_ovl != 0 {
                    if to_ovl != from_ovl {
                        stub = true;
                    }
                    if !(branch || hint) && kind == STT_FUNC {
                        stub = true;
                        nonovl = true;
                    }
                }
                if stub {
                    let ovl = if nonovl { 0 } else { from_ovl };
                    needs.push(((o, i, ri), ovl, key, r.addend, dest));
                }
            }
        }
    }
    // allocate_spuear_stubs: a `_SPUEAR_` global defined in an overlay gets a
    // non-overlay stub (the PPE side calls it there), after the relocations' stubs, in
    // the order of GNU ld's symbol hash table.
    let mut ears: Vec<(&str, usize, usize)> = globals
        .iter()
        .filter(|(n, _)| n.starts_with("_SPUEAR_"))
        .filter_map(|(n, d)| match d.1 {
            SymSection::Section(t) if ovl_of(d.0, t) != 0 => Some((*n, d.0, t)),
            _ => None,
        })
        .collect();
    ears.sort_by_key(|e| (crate::link::bfd_hash_bucket(e.0), e.0));
    for &(name, ..) in &ears {
        let key = Key::Global(name.to_string());
        needs.push((
            (usize::MAX, 0, 0),
            0,
            key,
            0,
            StubDest::Global(name.to_string(), 0),
        ));
    }
    // count_stub: one stub per symbol and addend per overlay, a non-overlay one
    // replacing the others.
    let mut got: Vec<(Key, i64, u32)> = Vec::new();
    for (_, ovl, key, addend, _) in &needs {
        let same = |g: &(Key, i64, u32)| g.0 == *key && g.1 == *addend;
        if *ovl == 0 {
            if !got.iter().any(|g| same(g) && g.2 == 0) {
                got.retain(|g| !same(g));
                got.push((key.clone(), *addend, 0));
            }
        } else if !got.iter().any(|g| same(g) && (g.2 == *ovl || g.2 == 0)) {
            got.push((key.clone(), *addend, *ovl));
        }
    }
    // build_stub: in the relocations' order, each stub where its first user is.
    let mut size = vec![0u32; n + 1];
    let mut built: HashMap<(Key, i64, u32), usize> = HashMap::new();
    for (at, ovl, key, addend, dest) in needs {
        let Some(g) = got
            .iter()
            .find(|g| g.0 == key && g.1 == addend && (g.2 == ovl || g.2 == 0))
        else {
            continue;
        };
        let id = g.clone();
        let stub = match built.get(&id) {
            Some(&s) => s,
            None => {
                let home = id.2;
                ov.stubs.push(Stub {
                    ovl: home,
                    dest,
                    offset: size[home as usize],
                });
                size[home as usize] += STUB_SIZE;
                built.insert(id, ov.stubs.len() - 1);
                ov.stubs.len() - 1
            }
        };
        if at.0 == usize::MAX {
            if let Key::Global(n) = &key {
                ov.ears.push((n.clone(), stub));
            }
        } else {
            ov.redirect.insert(at, stub);
        }
    }
    // The linker's object: `.stub` for each overlay index, `.ovtab`, `.toe`.
    let mut sections: Vec<ObjSection> = size
        .iter()
        .map(|&s| ObjSection {
            name: ".stub".into(),
            ty: SHT_PROGBITS,
            flags: SHF_ALLOC | SHF_EXECINSTR,
            entsize: 0,
            align: 16,
            size: s,
            data: vec![0; s as usize],
            relocs: Vec::new(),
        })
        .collect();
    let ovtab_size = 16 * n as u32 + 16 + 4 * ov.num_buf;
    let mut ovtab = vec![0u8; ovtab_size as usize];
    // The non-overlay area's entry: present (the low bit of its size).
    ovtab[7] = 1;
    sections.push(ObjSection {
        name: ".ovtab".into(),
        ty: SHT_PROGBITS,
        flags: SHF_ALLOC | SHF_WRITE,
        entsize: 0,
        align: 16,
        size: ovtab_size,
        data: ovtab,
        relocs: Vec::new(),
    });
    sections.push(ObjSection {
        name: ".toe".into(),
        ty: SHT_NOBITS,
        flags: SHF_ALLOC | SHF_WRITE,
        entsize: 0,
        align: 16,
        size: 16,
        data: Vec::new(),
        relocs: Vec::new(),
    });
    ov.ovtab = n + 1;
    ov.toe = n + 2;
    let table = |name: &str, section: usize, value: u64, size: u64| ObjSymbol {
        name: name.into(),
        value,
        size,
        section: SymSection::Section(section),
        global: true,
        weak: false,
        visibility: 0,
        kind: 1,
    };
    let buf_at = 16 + 16 * n as u64;
    let symbols = vec![
        table("_ovly_table", ov.ovtab, 16, 16 * n as u64),
        table("_ovly_table_end", ov.ovtab, buf_at, 0),
        table("_ovly_buf_table", ov.ovtab, buf_at, 4 * ov.num_buf as u64),
        table(
            "_ovly_buf_table_end",
            ov.ovtab,
            buf_at + 4 * ov.num_buf as u64,
            0,
        ),
        table("_EAR_", ov.toe, 0, 16),
    ];
    ov.object = objects.len();
    objects.push(Object {
        name: LINKER_OBJECT.into(),
        sections,
        symbols,
        included: Vec::new(),
        osabi: 0,
        groups: Vec::new(),
    });
    Ok(ov)
}

/// A stub's four words, at `from`, for a destination `dest` in overlay `dest_ovl`,
/// through the overlay manager's entry at `to`.
pub fn stub_words(from: u32, dest: u32, dest_ovl: u32, to: u32) -> Result<[u32; 4], String> {
    if (from | dest | to) & 3 != 0 {
        return Err("overlay stub relocation overflow".into());
    }
    const ILA: u32 = 0x4200_0000;
    const LNOP: u32 = 0x0020_0000;
    const BR: u32 = 0x3200_0000;
    Ok([
        ILA + ((dest_ovl << 7) & 0x01ff_ff80) + 78,
        LNOP,
        ILA + ((dest << 7) & 0x01ff_ff80) + 79,
        BR + ((to.wrapping_sub(from + 12) << 5) & 0x007f_ff80),
    ])
}

/// `_ovly_table`'s entries (after the non-overlay area's): each overlay's address,
/// size rounded to 16, file offset (filled in when the file is laid out) and buffer.
pub fn table_entry(addr: u32, size: u32, buf: u32) -> [u32; 4] {
    [addr, size.next_multiple_of(16), 0, buf]
}
