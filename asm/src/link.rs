//! `spu ld`: links relocatable SPU objects into an executable local-store image, as GNU
//! ld's default SPU script lays it out (code, read-only data, data, bss, commons at the
//! end of bss), resolving symbols across objects and applying the SPU relocations.
//! With a script (`-T`, `link_script`) it lays out as the script says and builds SPU
//! overlays (`link_overlay`); docs/linker.md.

use crate::archive::Archive;
use crate::object::{
    placement, Object, RelocTarget, SymSection, DATA_SEGMENT_ALIGN, SHF_ALLOC, SHF_EXECINSTR,
    SHF_WRITE, SHT_NOBITS,
};
use std::collections::{HashMap, HashSet};

#[derive(Clone, Debug, Default)]
pub struct LinkOptions {
    /// Address of the first (code) section: `-Ttext`.
    pub text_addr: u32,
    /// Entry symbol: `-e` (default `_start`, else the start of the code).
    pub entry: Option<String>,
    /// The output file's name as given (`-o`; default `a.out`), which GNU ld's SPU
    /// backend records in the `.note.spu_name` note for the PPE's embedder.
    pub output: Option<String>,
    /// The linker script (`-T`, combined): its layout replaces the default script's.
    pub script: Option<crate::link_script::Script>,
}

/// One input of a link, in command-line order.
#[derive(Clone, Debug)]
pub enum Input {
    /// An object: always linked.
    Object(Object),
    /// A library (`name` for messages): searched where it stands, as GNU ld searches.
    Archive(String, Archive),
}

/// The objects GNU ld would link from `inputs`: each object, and at each archive's place
/// the members that define a symbol still undefined there (referenced, not weakly, by an
/// object before it), the archive searched again until no member is pulled in. A member
/// is named `lib.a(member.o)`, as GNU ld names it.
pub fn resolve_inputs(inputs: Vec<Input>) -> Result<Vec<Object>, String> {
    let mut objects: Vec<Object> = Vec::new();
    let mut defined: HashSet<String> = HashSet::new();
    let mut undefined: HashSet<String> = HashSet::new();
    let add = |o: Object,
               objects: &mut Vec<Object>,
               defined: &mut HashSet<String>,
               undefined: &mut HashSet<String>| {
        for s in o.symbols.iter().filter(|s| s.global) {
            if s.section == SymSection::Undefined {
                if !s.weak && !defined.contains(&s.name) {
                    undefined.insert(s.name.clone());
                }
            } else {
                undefined.remove(&s.name);
                defined.insert(s.name.clone());
            }
        }
        objects.push(o);
    };
    for input in inputs {
        match input {
            Input::Object(o) => add(o, &mut objects, &mut defined, &mut undefined),
            Input::Archive(name, archive) => {
                // GNU ld's passes: the index in order, each symbol checked against what
                // is undefined at that moment; again while a pass pulled a member in.
                let mut loaded = vec![false; archive.members.len()];
                let mut pulled = true;
                while pulled {
                    pulled = false;
                    for (sym, m) in &archive.index {
                        if loaded[*m] || !undefined.contains(sym) {
                            continue;
                        }
                        loaded[*m] = true;
                        pulled = true;
                        let member = &archive.members[*m];
                        let label = format!("{name}({})", member.name);
                        let o = Object::from_elf(&label, &member.data)?;
                        add(o, &mut objects, &mut defined, &mut undefined);
                    }
                }
            }
        }
    }
    Ok(objects)
}

/// A linked program.
#[derive(Clone, Debug, Default)]
pub struct Linked {
    /// Local store from address 0 to the end of the last section.
    pub image: Vec<u8>,
    pub elf: Vec<u8>,
    /// Symbols (not `.L` locals) with their addresses.
    pub symbols: Vec<(String, u32)>,
    pub entry: u32,
    /// Output sections: (name, address, size, is code).
    pub sections: Vec<(String, u32, u32, bool)>,
    /// What GNU ld warns about (a missing entry symbol).
    pub warnings: Vec<String>,
}

/// The symbols GNU ld's SPU script defines (`elf32_spu.sh` over the generic `elf.sc`):
/// always `_edata` and `__bss_start` (the end of the data, where bss starts) and `_end`
/// (past bss, aligned to 16); `edata`, `end`, `etext`, `_etext`, `__etext` (past the
/// code) and `__stack` (0x3fff0) only when referenced and not defined (`PROVIDE`).
const PROVIDED: [&str; 6] = ["edata", "end", "etext", "_etext", "__etext", "__stack"];

const LOCAL_STORE: u64 = 256 * 1024;

/// The output section an input section goes to (GNU ld's default script).
fn output_name(name: &str) -> String {
    if let Some(out) = array_output(name) {
        return out.to_string();
    }
    for base in [".text", ".data", ".rodata", ".bss"] {
        if name == base || name.starts_with(&format!("{base}.")) {
            return base.to_string();
        }
    }
    name.to_string()
}

/// The constructor arrays of the default script: `.init_array` takes `.ctors` and
/// `.init_array.*`/`.ctors.*` too, `.fini_array` the `.dtors`.
pub(crate) fn array_output(name: &str) -> Option<&'static str> {
    let family = |base: &str| name == base || name.starts_with(&format!("{base}."));
    if family(".init_array") || family(".ctors") {
        Some(".init_array")
    } else if family(".fini_array") || family(".dtors") {
        Some(".fini_array")
    } else if name == ".preinit_array" {
        Some(".preinit_array")
    } else {
        None
    }
}

/// Where GNU ld's default script (or, for a section it does not name, its orphan
/// placement, `ldelf_place_orphan`) puts an allocated output section: (class, rank) as
/// `placement` gives them, class 5 for what stands after the script's `_end` (an
/// allocated note goes after `.note.spu_name`, `._ea` and the DWARF sections at 0).
fn script_placement(name: &str, ty: u32, flags: u64) -> (u8, i8) {
    let rank = placement(name, ty, flags).1;
    match name {
        ".interrupt" | ".init" | ".text" | ".fini" => return (0, rank),
        ".rodata" => return (1, 0),
        ".preinit_array" => return (2, -3),
        ".init_array" => return (2, -2),
        ".fini_array" => return (2, -1),
        ".data" => return (2, 0),
        ".bss" => return (3, 0),
        _ => {}
    }
    if is_late(name, ty) {
        return (5, (name == "._ea") as i8);
    }
    let class = if ty == SHT_NOBITS {
        3
    } else if flags & SHF_WRITE != 0 {
        2
    } else if flags & SHF_EXECINSTR != 0 {
        0
    } else {
        1
    };
    (class, rank)
}

/// An allocated section placed after the script's `_end`: a note (after
/// `.note.spu_name`) or `._ea` (at 0, as the script's `._ea 0 :` puts it).
fn is_late(name: &str, ty: u32) -> bool {
    ty == SHT_NOTE || crate::link_debug::in_script(name)
}

const SHT_NOTE: u32 = 7;
/// A `.ctors`/`.dtors` section that the script puts in `.init_array`/`.fini_array`:
/// GNU ld copies its words in reverse order (`SEC_ELF_REVERSE_COPY`), as the arrays
/// run the other way.
fn reverse_copied(s: &crate::object::ObjSection) -> bool {
    let family = |base: &str| s.name == base || s.name.starts_with(&format!("{base}."));
    (family(".ctors") || family(".dtors")) && s.ty != SHT_NOBITS && s.size.is_multiple_of(4)
}

/// `obj` with its `.ctors`/`.dtors` sections' words (and their relocations) reversed.
fn reverse_ctors(obj: &Object) -> Object {
    let mut obj = obj.clone();
    for s in obj.sections.iter_mut().filter(|s| reverse_copied(s)) {
        let size = s.size;
        let words: Vec<&[u8]> = s.data.chunks(4).collect();
        s.data = words.into_iter().rev().flatten().copied().collect();
        for r in &mut s.relocs {
            r.offset = size - 4 - (r.offset & !3) + (r.offset & 3);
        }
    }
    obj
}

/// SHF_EXCLUDE: GNU ld leaves such a section out of an executable.
const SHF_EXCLUDE: u64 = 0x8000_0000;

struct OutSection {
    name: String,
    ty: u32,
    flags: u64,
    align: u32,
    /// (object, input section, offset in this output section)
    inputs: Vec<(usize, usize, u32)>,
    size: u32,
    addr: u32,
}

/// Where a global symbol is defined.
#[derive(Clone, Debug)]
struct Definition {
    object: usize,
    section: SymSection,
    value: u64,
    weak: bool,
    size: u64,
    kind: u8,
}

/// Links `objects`; errors name the object and symbol concerned.
pub fn link(objects: &[Object], opts: &LinkOptions) -> Result<Linked, Vec<String>> {
    let deduplicated;
    let objects = if objects.iter().any(|o| o.groups.iter().any(|g| g.comdat)) {
        deduplicated = crate::link_groups::discard_duplicate_groups(objects)?;
        &deduplicated[..]
    } else {
        objects
    };
    let reversed;
    let objects = if objects
        .iter()
        .any(|o| o.sections.iter().any(reverse_copied))
    {
        reversed = objects.iter().map(reverse_ctors).collect::<Vec<_>>();
        &reversed[..]
    } else {
        objects
    };
    let script = opts.script.as_ref();
    // Where a script puts each input section: (output section, its statement, 1-based).
    let script_place = |objects: &[Object]| -> HashMap<(usize, usize), (String, u32)> {
        let mut at = HashMap::new();
        for (o, obj) in objects.iter().enumerate() {
            for (i, s) in obj.sections.iter().enumerate() {
                if s.flags & SHF_ALLOC == 0 || s.flags & SHF_EXCLUDE != 0 {
                    continue;
                }
                let place = script
                    .and_then(|sc| sc.assign(&obj.name, &s.name))
                    .unwrap_or_else(|| (s.name.clone(), 0));
                at.insert((o, i), place);
            }
        }
        at
    };
    // Overlays: the script's OVERLAY members that receive something, their stubs and
    // tables (the linker's own object, appended to the inputs).
    let with_overlays;
    let mut overlays = None;
    let objects = match script {
        Some(sc) if !sc.overlay_regions().is_empty() => {
            let at = script_place(objects);
            let filled = |name: &str| {
                at.iter()
                    .any(|(&(o, i), p)| p.0 == name && objects[o].sections[i].size > 0)
            };
            let regions: Vec<Vec<String>> = sc
                .overlay_regions()
                .into_iter()
                .map(|r| r.into_iter().filter(|m| filled(m)).collect::<Vec<_>>())
                .filter(|r| !r.is_empty())
                .collect();
            let mut all = objects.to_vec();
            if !regions.is_empty() {
                let ov = crate::link_overlay::build(&mut all, &regions, &|o, i| {
                    at.get(&(o, i)).map(|p| p.0.clone())
                })?;
                overlays = Some(ov);
            }
            with_overlays = all;
            &with_overlays[..]
        }
        _ => objects,
    };
    let placement_of = script.map(|_| script_place(objects));
    let mut rank: HashMap<(usize, usize), u32> = HashMap::new();
    let mut errors = Vec::new();
    // Output sections in GNU ld's order.
    let mut outs: Vec<OutSection> = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for (i, s) in obj.sections.iter().enumerate() {
            if s.flags & SHF_ALLOC == 0 || s.flags & SHF_EXCLUDE != 0 {
                continue;
            }
            let name = match (&overlays, &placement_of) {
                // The linker's sections go where GNU ld's SPU backend puts them
                // (`spu_place_special_section`): the non-overlay stubs at the end of
                // `.text`, an overlay's at its start, `.ovtab` at the end of `.data`.
                (Some(ov), _) if o == ov.object => {
                    if s.size == 0 {
                        continue;
                    }
                    let (name, r) = if i == 0 {
                        (".text".to_string(), u32::MAX)
                    } else if i <= ov.sections.len() {
                        (ov.sections[i - 1].name.clone(), 0)
                    } else if i == ov.ovtab {
                        (".data".to_string(), u32::MAX)
                    } else {
                        (".toe".to_string(), u32::MAX)
                    };
                    rank.insert((o, i), r);
                    name
                }
                (_, Some(at)) => {
                    let (name, r) = at[&(o, i)].clone();
                    rank.insert((o, i), r);
                    name
                }
                _ => output_name(&s.name),
            };
            let k = match outs.iter().position(|x| x.name == name) {
                Some(k) => k,
                None => {
                    outs.push(OutSection {
                        ty: match name.as_str() {
                            ".init_array" => 14,
                            ".fini_array" => 15,
                            ".preinit_array" => 16,
                            _ => s.ty,
                        },
                        name,
                        flags: s.flags,
                        align: 1,
                        inputs: Vec::new(),
                        size: 0,
                        addr: 0,
                    });
                    outs.len() - 1
                }
            };
            let out = &mut outs[k];
            if (out.ty == SHT_NOBITS) != (s.ty == SHT_NOBITS) {
                // Contents into a NOBITS section (or the reverse): it becomes PROGBITS.
                out.ty = 1;
            }
            out.flags |= s.flags;
            out.inputs.push((o, i, 0));
        }
    }
    // The inputs in the script's order (`.text.hot` before `.text`...), then laid out.
    for out in &mut outs {
        if script.is_some() {
            out.inputs
                .sort_by_key(|&(o, i, _)| rank.get(&(o, i)).copied().unwrap_or(0));
        } else if out.name == ".text" {
            out.inputs.sort_by_cached_key(|&(o, i, _)| {
                let name = &objects[o].sections[i].name;
                let rank = text_rank(name);
                (
                    rank,
                    if rank == 4 {
                        name.clone()
                    } else {
                        String::new()
                    },
                )
            });
        }
        // GNU ld's `lang_add_section`: the output section is read-only as its first
        // input is (in the script's order); the other flags gather from all.
        if let Some(&(o, i, _)) = out.inputs.first() {
            out.flags = (out.flags & !SHF_WRITE) | (objects[o].sections[i].flags & SHF_WRITE);
        }
        for input in &mut out.inputs {
            let s = &objects[input.0].sections[input.1];
            out.align = out.align.max(s.align.max(1));
            let at = out.size.div_ceil(s.align.max(1)) * s.align.max(1);
            input.2 = at;
            out.size = at.saturating_add(s.size);
        }
    }
    // spu_before_allocation: an overlay section is DMAed whole, so it is aligned to
    // 16 bytes and padded to a multiple of 16.
    if let Some(ov) = &overlays {
        for out in outs.iter_mut().filter(|x| ov.index_of(&x.name) != 0) {
            out.align = out.align.max(16);
            out.size = out.size.next_multiple_of(16);
        }
    }
    // Global symbols: strong over weak over common; two strong ones are an error.
    let mut globals: HashMap<String, Definition> = HashMap::new();
    let mut commons: Vec<(String, u64, u64, usize)> = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for s in &obj.symbols {
            if !s.global || s.section == SymSection::Undefined {
                continue;
            }
            if s.section == SymSection::Common {
                match commons.iter_mut().find(|c| c.0 == s.name) {
                    Some(c) => {
                        // The larger definition's object owns it (BFD's `BIG` case).
                        if s.size > c.1 {
                            c.3 = o;
                        }
                        c.1 = c.1.max(s.size);
                        c.2 = c.2.max(s.value);
                    }
                    None => commons.push((s.name.clone(), s.size, s.value.max(1), o)),
                }
                continue;
            }
            let def = Definition {
                object: o,
                section: s.section,
                value: s.value,
                weak: s.weak,
                size: s.size,
                kind: s.kind,
            };
            match globals.get(&s.name) {
                Some(prev) if !prev.weak && !s.weak => errors.push(format!(
                    "{}: multiple definition of `{}'; first defined in {}",
                    obj.name, s.name, objects[prev.object].name
                )),
                Some(prev) if !prev.weak || s.weak => {}
                _ => {
                    globals.insert(s.name.clone(), def);
                }
            }
        }
    }
    // Symbol versions (`.symver`): a default version `f@@V` stands for `f` too, so a
    // defined `f` beside it is a second definition; a hidden version `f@V` defined where
    // the same object's `f` is replaces it in the output.
    let mut replaced: HashSet<String> = HashSet::new();
    for (o, obj) in objects.iter().enumerate() {
        for s in obj.symbols.iter().filter(|s| s.global) {
            if s.section == SymSection::Undefined || s.section == SymSection::Common {
                continue;
            }
            if let Some((base, _)) = s.name.split_once("@@") {
                if globals.contains_key(base) {
                    errors.push(format!(
                        "{}: multiple definition of `{base}'; first defined in {}",
                        obj.name, objects[globals[base].object].name
                    ));
                }
            } else if let Some((base, _)) = s.name.split_once('@') {
                if globals
                    .get(base)
                    .is_some_and(|d| d.object == o && d.section == s.section && d.value == s.value)
                {
                    replaced.insert(base.to_string());
                }
            }
        }
    }
    // An undefined symbol of other than default visibility must be defined in the link.
    for obj in objects {
        for s in &obj.symbols {
            if s.section == SymSection::Undefined
                && !s.weak
                && !s.name.is_empty()
                && s.visibility != 0
                && !globals.contains_key(&s.name)
                && !commons.iter().any(|c| c.0 == s.name)
            {
                let what = match s.visibility {
                    1 => "internal",
                    2 => "hidden",
                    _ => "protected",
                };
                errors.push(format!(
                    "{}: {what} symbol `{}' isn't defined",
                    opts.output.as_deref().unwrap_or("a.out"),
                    s.name
                ));
            }
        }
    }
    // Commons not defined elsewhere go at the end of .bss.
    commons.retain(|c| !globals.contains_key(&c.0));
    let mut common_at: HashMap<String, u32> = HashMap::new();
    if !commons.is_empty() {
        let k = match outs.iter().position(|x| x.name == ".bss") {
            Some(k) => k,
            None => {
                outs.push(OutSection {
                    name: ".bss".into(),
                    ty: SHT_NOBITS,
                    flags: SHF_ALLOC | SHF_WRITE,
                    align: 1,
                    inputs: Vec::new(),
                    size: 0,
                    addr: 0,
                });
                outs.len() - 1
            }
        };
        // GNU ld gives each object a COMMON section of the commons it owns, taken by
        // `*(COMMON)` in input order; within one, the commons come in the order its
        // symbol hash table holds them (bucket by bucket, the later entry first).
        let mut first_seen: HashMap<&str, usize> = HashMap::new();
        for s in objects.iter().flat_map(|o| &o.symbols).filter(|s| s.global) {
            let n = first_seen.len();
            first_seen.entry(s.name.as_str()).or_insert(n);
        }
        commons.sort_by_key(|c| {
            let seen = first_seen.get(c.0.as_str()).copied().unwrap_or(0);
            (c.3, bfd_hash_bucket(&c.0), std::cmp::Reverse(seen))
        });
        let align_of = |c: &(String, u64, u64, usize)| c.2.clamp(1, 1 << 15) as u32;
        for (i, c) in commons.iter().enumerate() {
            let out = &mut outs[k];
            if i == 0 || commons[i - 1].3 != c.3 {
                // A new object's COMMON section, aligned to its largest common.
                let group = commons[i..].iter().take_while(|d| d.3 == c.3);
                let a = group.map(align_of).max().unwrap_or(1);
                out.size = out.size.div_ceil(a) * a;
            }
            let a = align_of(c);
            out.align = out.align.max(a);
            let at = out.size.div_ceil(a) * a;
            common_at.insert(c.0.clone(), at);
            out.size = at.saturating_add(c.1.min(LOCAL_STORE) as u32);
        }
    }
    let mut order: Vec<usize> = (0..outs.len()).collect();
    order.sort_by_key(|&k| {
        (
            script_placement(&outs[k].name, outs[k].ty, outs[k].flags),
            k,
        )
    });
    // `.note.spu_name 0 :` leaves the location counter past the note, where an
    // allocated note (an orphan placed after it) starts.
    let spu_note_size = objects
        .iter()
        .flat_map(|o| &o.sections)
        .filter(|s| s.name == SPU_NAME_NOTE)
        .map(|s| s.size as u64)
        .sum::<u64>();
    let spu_note_size = if spu_note_size == 0 {
        spu_name_note(opts.output.as_deref().unwrap_or("a.out"))
            .data
            .len() as u64
    } else {
        spu_note_size
    };
    let mut late_addr = spu_note_size;
    // Unallocated `.ctors`/`.init_array`... inputs: the script's `.init_array : {...}`
    // still moves the location counter past them, at the start of the data.
    let unallocated_arrays: u64 = objects
        .iter()
        .flat_map(|o| &o.sections)
        .filter(|s| s.flags & (SHF_ALLOC | SHF_EXCLUDE) == 0 && array_output(&s.name).is_some())
        .map(|s| s.size as u64)
        .sum();
    let mut addr = opts.text_addr as u64;
    // GNU ld's `. = DATA_ADDR` after the read-only sections: the first writable section
    // starts there, and `_edata` and `_end` stand past it even when there is none.
    let mut data_start = None;
    // A script's layout (`-T`) in place of the default script's.
    let script_layout = match script {
        Some(sc) => {
            let placed: Vec<crate::link_script::Placed> = outs
                .iter()
                .map(|x| {
                    let last = x
                        .inputs
                        .iter()
                        .map(|&(o, i, _)| rank.get(&(o, i)).copied().unwrap_or(0))
                        .filter(|&r| r != u32::MAX)
                        .max()
                        .unwrap_or(0);
                    let item_ends = (1..=last.max(1) + 8)
                        .map(|r| {
                            x.inputs
                                .iter()
                                .filter(|&&(o, i, _)| rank.get(&(o, i)).copied().unwrap_or(0) <= r)
                                .map(|&(o, i, at)| at as u64 + objects[o].sections[i].size as u64)
                                .max()
                                .unwrap_or(0)
                        })
                        .collect();
                    crate::link_script::Placed {
                        name: x.name.clone(),
                        size: x.size as u64,
                        align: x.align.max(1) as u64,
                        class: script_placement(&x.name, x.ty, x.flags).0,
                        tbss: is_tbss(x),
                        item_ends,
                    }
                })
                .collect();
            let file = "the linker script";
            Some(
                crate::link_script::lay_out(sc, &placed)
                    .map_err(|e| vec![format!("{file}: {e}")])?,
            )
        }
        None => None,
    };
    for (n, &k) in order.iter().enumerate() {
        let class = script_placement(&outs[k].name, outs[k].ty, outs[k].flags).0;
        if class != 5 {
            if let Some(l) = &script_layout {
                outs[k].addr = l.addr[k].min(u32::MAX as u64) as u32;
                continue;
            }
        }
        if class == 5 {
            let a = outs[k].align.max(1) as u64;
            let at = if crate::link_debug::in_script(&outs[k].name) {
                0 // the script's `NAME 0 :`
            } else {
                late_addr.next_multiple_of(a)
            };
            outs[k].addr = at.min(u32::MAX as u64) as u32;
            late_addr = at + outs[k].size as u64;
            continue;
        }
        if data_start.is_none() && matches!(class, 2 | 3) {
            addr = addr.next_multiple_of(DATA_SEGMENT_ALIGN as u64);
            data_start = Some(addr);
            addr += unallocated_arrays;
        }
        if outs[k].size == 0 {
            // GNU ld drops an output section that received nothing: it takes no room
            // and moves nothing; its (empty) inputs' labels stand where it would be.
            outs[k].addr = addr.min(u32::MAX as u64) as u32;
            continue;
        }
        let mut a = outs[k].align.max(1) as u64;
        if outs[k].name == ".toe" {
            a = a.max(128); // the script's `.toe ALIGN(128)` (the overlay manager's table of effective addresses)
        }
        if n > 0 || !addr.is_multiple_of(a) {
            addr = addr.div_ceil(a) * a;
        }
        outs[k].addr = addr.min(u32::MAX as u64) as u32;
        if outs[k].name == ".bss" {
            // The script's `. = ALIGN(. != 0 ? 16 : 1)` at the end of .bss.
            let end = addr + outs[k].size as u64;
            let padded = if end != 0 {
                end.next_multiple_of(16)
            } else {
                end
            };
            outs[k].size = (padded - addr).min(u32::MAX as u64) as u32;
        }
        if !is_tbss(&outs[k]) {
            addr += outs[k].size as u64;
        }
    }
    let data_start = data_start.unwrap_or_else(|| addr.next_multiple_of(DATA_SEGMENT_ALIGN as u64))
        + unallocated_arrays;
    // Overlaps and the local store.
    for (i, a) in outs.iter().enumerate() {
        let a_end = a.addr as u64 + a.size as u64;
        if a_end > LOCAL_STORE {
            errors.push(format!(
                "section {} [{:#x}, {:#x}) does not fit the 256 KiB local store",
                a.name, a.addr, a_end
            ));
        }
        let buf_of = |x: &OutSection| {
            overlays
                .as_ref()
                .and_then(|ov| ov.sections.iter().find(|s| s.name == x.name).map(|s| s.buf))
        };
        for b in &outs[i + 1..] {
            let b_end = b.addr as u64 + b.size as u64;
            let same_region = buf_of(a).is_some() && buf_of(a) == buf_of(b);
            if a.size > 0
                && b.size > 0
                && !same_region
                && (a.addr as u64) < b_end
                && (b.addr as u64) < a_end
            {
                errors.push(format!("section {} overlaps section {}", a.name, b.name));
            }
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    // Input section addresses.
    let mut placed: HashMap<(usize, usize), u32> = HashMap::new();
    for out in &outs {
        for &(o, i, at) in &out.inputs {
            placed.insert((o, i), out.addr + at);
        }
    }
    let bss_addr = outs.iter().find(|x| x.name == ".bss").map_or(0, |x| x.addr);
    let address_of = |o: usize, section: SymSection, value: u64| -> Option<u64> {
        match section {
            SymSection::Section(i) => placed.get(&(o, i)).map(|a| *a as u64 + value),
            SymSection::Absolute => Some(value),
            _ => None,
        }
    };
    let late = |x: &OutSection| is_late(&x.name, x.ty);
    let end = outs
        .iter()
        .filter(|x| !is_tbss(x) && !late(x))
        .map(|x| x.addr as u64 + x.size as u64)
        .max()
        .unwrap_or(0);
    let image_end = outs
        .iter()
        .filter(|x| !is_tbss(x))
        .map(|x| x.addr as u64 + x.size as u64)
        .max()
        .unwrap_or(0);
    // The script's symbols, where its location counter stands.
    let end_of = |keep: &dyn Fn(&OutSection) -> bool| {
        outs.iter()
            .filter(|x| keep(x) && !late(x))
            .map(|x| x.addr as u64 + x.size as u64)
            .max()
    };
    let etext = end_of(&|x| x.flags & SHF_EXECINSTR != 0).unwrap_or(opts.text_addr as u64);
    let edata = end_of(&|x| x.ty != SHT_NOBITS)
        .unwrap_or(opts.text_addr as u64)
        .max(data_start);
    let defaults = [
        ("_edata", edata),
        ("__bss_start", edata),
        ("_end", end.max(edata).next_multiple_of(16)),
        ("edata", edata),
        ("end", end.max(edata).next_multiple_of(16)),
        ("etext", etext),
        ("_etext", etext),
        ("__etext", etext),
        ("__stack", 0x3fff0),
    ]
    .into_iter()
    .filter(|(n, _)| !PROVIDED.contains(n) || referenced(objects, n));
    let script: HashMap<&str, u64> = match &script_layout {
        // A script's own assignments (`PROVIDE`d ones where referenced), and none of
        // the default script's.
        Some(l) => l
            .symbols
            .iter()
            .filter(|(n, _, provide)| !provide || referenced(objects, n))
            .map(|(n, v, _)| (n.as_str(), *v))
            .collect::<Vec<_>>(),
        None => defaults.collect(),
    }
    .into_iter()
    .filter(|(n, _)| !globals.contains_key(*n) && !common_at.contains_key(*n))
    .collect();
    let global_address = |name: &str| -> Option<u64> {
        if let Some(d) = globals.get(name) {
            return address_of(d.object, d.section, d.value);
        }
        if let Some(a) = common_at.get(name) {
            return Some((bss_addr + a) as u64);
        }
        script.get(name).copied()
    };
    // Local store from 0, and for each overlay its own copy where its section's
    // contents are put and relocated (the overlays share their addresses).
    let ovl_index = |name: &str| overlays.as_ref().map_or(0, |ov| ov.index_of(name)) as usize;
    let mut buffers = vec![vec![0u8; image_end as usize]];
    if let Some(ov) = &overlays {
        buffers.resize(ov.sections.len() + 1, vec![0u8; image_end as usize]);
    }
    let mut buffer_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut out_of_input: HashMap<(usize, usize), usize> = HashMap::new();
    for (k, out) in outs.iter().enumerate() {
        let b = ovl_index(&out.name);
        for &(o, i, at) in &out.inputs {
            buffer_of.insert((o, i), b);
            out_of_input.insert((o, i), k);
            let s = &objects[o].sections[i];
            if s.ty != SHT_NOBITS {
                let start = (out.addr + at) as usize;
                let n = s.data.len().min(s.size as usize);
                buffers[b][start..start + n].copy_from_slice(&s.data[..n]);
            }
        }
    }
    if let Some(ov) = &overlays {
        let load = global_address(crate::link_overlay::OVLY_LOAD).unwrap_or(0) as u32;
        for st in &ov.stubs {
            let from = placed[&(ov.object, st.ovl as usize)] + st.offset;
            let (dest, dest_ovl) = match &st.dest {
                crate::link_overlay::StubDest::Global(n, addend) => {
                    let d = &globals[n.as_str()];
                    let SymSection::Section(t) = d.section else {
                        continue;
                    };
                    (
                        global_address(n).unwrap_or(0).wrapping_add(*addend as u64),
                        buffer_of.get(&(d.object, t)).copied().unwrap_or(0),
                    )
                }
                crate::link_overlay::StubDest::At(o, t, v) => (
                    placed
                        .get(&(*o, *t))
                        .map_or(0, |a| (*a as u64).wrapping_add(*v as u64)),
                    buffer_of.get(&(*o, *t)).copied().unwrap_or(0),
                ),
            };
            match crate::link_overlay::stub_words(from, dest as u32, dest_ovl as u32, load) {
                Ok(words) => {
                    let b = &mut buffers[st.ovl as usize];
                    for (n, w) in words.iter().enumerate() {
                        let at = from as usize + 4 * n;
                        b[at..at + 4].copy_from_slice(&w.to_be_bytes());
                    }
                }
                Err(e) => errors.push(e),
            }
        }
        let table = placed[&(ov.object, ov.ovtab)] as usize;
        for s in &ov.sections {
            let Some(x) = outs.iter().find(|x| x.name == s.name) else {
                continue;
            };
            let entry = crate::link_overlay::table_entry(x.addr, x.size, s.buf);
            for (n, w) in entry.iter().enumerate() {
                let at = table + 16 * s.index as usize + 4 * n;
                buffers[0][at..at + 4].copy_from_slice(&w.to_be_bytes());
            }
        }
    }
    // Relocations.
    for (o, obj) in objects.iter().enumerate() {
        let locals: HashMap<&str, (SymSection, u64)> = obj
            .symbols
            .iter()
            .filter(|s| !s.global)
            .map(|s| (s.name.as_str(), (s.section, s.value)))
            .collect();
        let weak_undefined = |name: &str| {
            obj.symbols
                .iter()
                .any(|s| s.name == name && s.weak && s.section == SymSection::Undefined)
        };
        for (i, s) in obj.sections.iter().enumerate() {
            let Some(&base) = placed.get(&(o, i)) else {
                continue;
            };
            let b = buffer_of.get(&(o, i)).copied().unwrap_or(0);
            for (ri, r) in s.relocs.iter().enumerate() {
                // A reference that goes through an overlay stub.
                let stub = overlays.as_ref().and_then(|ov| {
                    let st = &ov.stubs[*ov.redirect.get(&(o, i, ri))?];
                    Some(placed[&(ov.object, st.ovl as usize)] as u64 + st.offset as u64)
                });
                let target = match &r.target {
                    _ if stub.is_some() => stub,
                    RelocTarget::Section(t) => placed.get(&(o, *t)).map(|a| *a as u64),
                    RelocTarget::Symbol(n) if n.is_empty() => Some(0),
                    RelocTarget::Symbol(n) => match locals.get(n.as_str()) {
                        Some(&(sec, v)) => address_of(o, sec, v),
                        None => global_address(n).or_else(|| weak_undefined(n).then_some(0)),
                    },
                };
                let what = match &r.target {
                    RelocTarget::Section(t) => obj
                        .sections
                        .get(*t)
                        .map_or("?".to_string(), |x| x.name.clone()),
                    RelocTarget::Symbol(n) => n.clone(),
                };
                let Some(sv) = target else {
                    errors.push(format!(
                        "{}: undefined reference to `{what}' ({}+{:#x})",
                        obj.name, s.name, r.offset
                    ));
                    continue;
                };
                let value = sv as i64 + if stub.is_some() { 0 } else { r.addend };
                if let Err(m) = crate::reloc::apply(r.kind, &mut buffers[b], base + r.offset, value)
                {
                    errors.push(format!(
                        "{}: {}+{:#x}: {m} against `{what}'",
                        obj.name, s.name, r.offset
                    ));
                }
            }
        }
    }
    if !errors.is_empty() {
        errors.sort();
        errors.dedup();
        return Err(errors);
    }
    // Output sections in address order, and the symbols of the output.
    let mut by_addr: Vec<&OutSection> = outs.iter().filter(|x| x.size > 0).collect();
    by_addr.sort_by_key(|x| (is_late(&x.name, x.ty), x.addr));
    let out_sections: Vec<crate::executable::Section> = by_addr
        .iter()
        .map(|x| crate::executable::Section {
            name: x.name.clone(),
            addr: x.addr,
            size: x.size,
            flags: x.flags,
            nobits: x.ty == SHT_NOBITS,
            ty: x.ty,
            late: is_late(&x.name, x.ty),
            align: x.align,
        })
        .collect();
    let place_of = |addr: u64| {
        use crate::executable::Place;
        by_addr
            .iter()
            .position(|x| addr >= x.addr as u64 && addr < x.addr as u64 + x.size.max(1) as u64)
            .map_or(Place::Absolute, Place::Section)
    };
    // The output section of input section `i` of object `o`.
    let section_place = |o: usize, i: usize| {
        let k = *out_of_input.get(&(o, i))?;
        by_addr
            .iter()
            .position(|x| std::ptr::eq(*x, &outs[k]))
            .map(crate::executable::Place::Section)
    };
    let mut out_symbols = Vec::new();
    // With a script the symbol table is as GNU ld writes it (the default script's
    // layout keeps today's): each input's locals after a FILE symbol naming it.
    let gnu_symbols = script_layout.is_some();
    for (o, obj) in objects.iter().enumerate() {
        let mut named = obj.symbols.iter().any(|s| s.kind == 4)
            || obj.name == crate::link_overlay::LINKER_OBJECT;
        for s in &obj.symbols {
            if s.global || s.name.starts_with(".L") || s.name.is_empty() {
                continue;
            }
            if gnu_symbols && s.kind == 4 && s.section == SymSection::Absolute {
                out_symbols.push(crate::executable::Symbol {
                    name: s.name.clone(),
                    value: s.value as u32,
                    size: 0,
                    kind: 4,
                    bind: 0,
                    place: crate::executable::Place::Absolute,
                });
                continue;
            }
            if let (SymSection::Section(i), Some(a)) =
                (s.section, address_of(o, s.section, s.value))
            {
                if gnu_symbols && !named {
                    named = true;
                    out_symbols.push(crate::executable::Symbol {
                        name: obj.name.clone(),
                        value: 0,
                        size: 0,
                        kind: 4,
                        bind: 0,
                        place: crate::executable::Place::Absolute,
                    });
                }
                out_symbols.push(crate::executable::Symbol {
                    name: s.name.clone(),
                    value: a as u32,
                    size: s.size as u32,
                    kind: s.kind,
                    bind: 0,
                    place: section_place(o, i).unwrap_or_else(|| place_of(a)),
                });
            }
        }
    }
    let mut names: Vec<&str> = globals
        .keys()
        .chain(common_at.keys())
        .map(|n| n.as_str())
        .chain(script.keys().copied())
        .collect();
    names.sort();
    if gnu_symbols {
        // GNU ld writes the globals as it walks its hash table, bucket by bucket.
        names.sort_by_key(|n| bfd_hash_bucket(n));
    }
    let mut in_unloaded: Vec<(usize, usize, usize)> = Vec::new();
    for n in names {
        if replaced.contains(n) {
            continue;
        }
        let Some(mut a) = global_address(n) else {
            // A global in a non-allocated section: GNU ld keeps it at its offset in the
            // joined section (address 0), set once those are joined below.
            if let Some(d) = globals.get(n) {
                if let SymSection::Section(i) = d.section {
                    in_unloaded.push((out_symbols.len(), d.object, i));
                    out_symbols.push(crate::executable::Symbol {
                        name: n.to_string(),
                        value: d.value as u32,
                        size: d.size as u32,
                        kind: d.kind,
                        bind: if d.weak { 2 } else { 1 },
                        place: crate::executable::Place::Unloaded(0),
                    });
                }
            }
            continue;
        };
        // spu_elf_output_symbol_hook: a `_SPUEAR_` symbol in an overlay is its stub.
        let ear = overlays.as_ref().and_then(|ov| {
            let &(_, st) = ov.ears.iter().find(|e| e.0 == n)?;
            let st = &ov.stubs[st];
            Some(placed[&(ov.object, st.ovl as usize)] + st.offset)
        });
        if let Some(stub) = ear {
            a = stub as u64;
        }
        let (size, kind, bind, place) = match (globals.get(n), common_at.contains_key(n)) {
            (Some(d), _) => {
                let place = match d.section {
                    SymSection::Absolute => crate::executable::Place::Absolute,
                    _ if ear.is_some() => place_of(a),
                    SymSection::Section(i) => {
                        section_place(d.object, i).unwrap_or_else(|| place_of(a))
                    }
                    _ => place_of(a),
                };
                (d.size, d.kind, if d.weak { 2 } else { 1 }, place)
            }
            (None, true) => {
                let size = commons.iter().find(|c| c.0 == n).map_or(0, |c| c.1);
                (size, 1, 1, place_of(a))
            }
            // The script's symbols belong to the section they stand in (or after).
            (None, false) => (0, 0, 1, place_of(a.saturating_sub(1))),
        };
        out_symbols.push(crate::executable::Symbol {
            name: n.to_string(),
            value: a as u32,
            size: size as u32,
            kind,
            bind,
            place,
        });
    }
    let symbols: Vec<(String, u32)> = {
        let mut v: Vec<(String, u32)> = out_symbols
            .iter()
            .filter(|s| !matches!(s.place, crate::executable::Place::Unloaded(_)))
            .map(|s| (s.name.clone(), s.value))
            .collect();
        v.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)));
        v
    };
    let mut warnings = Vec::new();
    let entry_name = opts
        .entry
        .clone()
        .or_else(|| opts.script.as_ref().and_then(|sc| sc.entry.clone()))
        .unwrap_or_else(|| "_start".into());
    let entry = match global_address(&entry_name).or_else(|| {
        symbols
            .iter()
            .find(|s| s.0 == entry_name)
            .map(|s| s.1 as u64)
    }) {
        Some(a) => a as u32,
        None => match opts.entry.as_deref().and_then(parse_number) {
            // GNU ld: a number is taken as the address.
            Some(a) => a,
            None => {
                // GNU ld: the start of .text, else of the first section, with a warning.
                let a = outs
                    .iter()
                    .find(|x| x.name == ".text")
                    .or_else(|| order.first().map(|&k| &outs[k]))
                    .map_or(opts.text_addr, |x| x.addr);
                warnings.push(format!(
                    "cannot find entry symbol {entry_name}; defaulting to {a:08x}"
                ));
                // GNU ld's ENTRY() leaves the name it looked for in the symbol table,
                // undefined.
                out_symbols.push(crate::executable::Symbol {
                    name: entry_name.clone(),
                    value: 0,
                    size: 0,
                    kind: 0,
                    bind: 1,
                    place: crate::executable::Place::Undefined,
                });
                a
            }
        },
    };
    let sections = out_sections
        .iter()
        .map(|x| (x.name.clone(), x.addr, x.size, x.flags & SHF_EXECINSTR != 0))
        .collect();
    // Debugging sections are kept, relocated, as GNU ld keeps them.
    let resolve = |o: usize, target: &RelocTarget| match target {
        RelocTarget::Section(t) => placed.get(&(o, *t)).map(|a| *a as u64),
        RelocTarget::Symbol(n) if n.is_empty() => Some(0),
        RelocTarget::Symbol(n) => match objects[o]
            .symbols
            .iter()
            .find(|s| !s.global && s.name == *n)
        {
            Some(s) => address_of(o, s.section, s.value),
            None => global_address(n),
        },
    };
    let (mut unloaded, unloaded_at) = crate::link_debug::sections(objects, &resolve)?;
    let mut note_at = None;
    if !objects
        .iter()
        .any(|o| o.sections.iter().any(|s| s.name == SPU_NAME_NOTE))
    {
        let note = spu_name_note(opts.output.as_deref().unwrap_or("a.out"));
        let rank = crate::link_debug::script_rank(SPU_NAME_NOTE);
        let at = unloaded
            .iter()
            .position(|u| crate::link_debug::script_rank(&u.name) > rank)
            .unwrap_or(unloaded.len());
        unloaded.insert(at, note);
        note_at = Some(at);
    }
    let mut dropped = Vec::new();
    for &(sym, o, i) in &in_unloaded {
        match unloaded_at.get(&(o, i)) {
            Some(&(k, off)) => {
                let k = k + usize::from(note_at.is_some_and(|at| k >= at));
                out_symbols[sym].value += off;
                out_symbols[sym].place = crate::executable::Place::Unloaded(k);
            }
            // Its section was discarded (`.note.GNU-stack`...): so is the symbol.
            None => dropped.push(sym),
        }
    }
    for sym in dropped.into_iter().rev() {
        out_symbols.remove(sym);
    }
    let mut image = std::mem::take(&mut buffers[0]);
    let mut overlaid = crate::executable::Overlaid::default();
    if let Some(ov) = &overlays {
        for s in &ov.sections {
            let Some(k) = out_sections.iter().position(|x| x.name == s.name) else {
                continue;
            };
            let x = &out_sections[k];
            let data =
                buffers[s.index as usize][x.addr as usize..(x.addr + x.size) as usize].to_vec();
            overlaid.overlays.push((k, s.index, data));
        }
        overlaid.lma = by_addr
            .iter()
            .map(|x| {
                let k = outs.iter().position(|y| std::ptr::eq(y, *x)).unwrap();
                script_layout.as_ref().map_or(x.addr, |l| l.lma[k] as u32)
            })
            .collect();
        let table = placed[&(ov.object, ov.ovtab)];
        overlaid.table = out_sections
            .iter()
            .position(|x| table >= x.addr && table < x.addr + x.size && x.name == ".data")
            .map(|_| table);
        overlaid.alone = out_sections.iter().position(|x| x.name == ".toe");
    } else {
        image.truncate(image_end as usize);
    }
    if let Some(l) = &script_layout {
        overlaid.gnu_offsets = true;
        overlaid.note_addr = Some(l.end.min(u32::MAX as u64) as u32);
    }
    let elf = crate::executable::write_overlaid(
        &image,
        &out_sections,
        &unloaded,
        &out_symbols,
        entry,
        &overlaid,
    );
    Ok(Linked {
        image,
        elf,
        symbols,
        entry,
        sections,
        warnings,
    })
}

/// The note section GNU ld's SPU backend adds to every executable
/// (`spu_elf_create_sections`): the PPE side's embedder names the program after it.
const SPU_NAME_NOTE: &str = ".note.spu_name";

/// `.note.spu_name`: an ELF note of type 1, name `SPUNAME`, whose descriptor is the
/// output file's name as given.
fn spu_name_note(output: &str) -> crate::executable::Unloaded {
    const NOTE_NAME: &[u8] = b"SPUNAME\0";
    let name_len = output.len() + 1;
    let mut data = Vec::new();
    data.extend((NOTE_NAME.len() as u32).to_be_bytes());
    data.extend((name_len as u32).to_be_bytes());
    data.extend(1u32.to_be_bytes());
    data.extend(NOTE_NAME);
    data.extend(output.as_bytes());
    data.resize(20 + name_len.next_multiple_of(4), 0);
    crate::executable::Unloaded {
        name: SPU_NAME_NOTE.into(),
        ty: 7,
        flags: 0,
        entsize: 0,
        align: 16,
        data,
    }
}

/// Which of the default script's `.text` input statements takes an input section: the
/// unlikely, exit, startup and hot code first, then `.text.sorted.*` by name, then the
/// rest (`.text`, `.text.*`) in input order.
fn text_rank(name: &str) -> u8 {
    let family = |base: &str| name == base || name.starts_with(&format!("{base}."));
    if family(".text.unlikely") || (name.starts_with(".text.") && name.ends_with("_unlikely")) {
        0
    } else if family(".text.exit") {
        1
    } else if family(".text.startup") {
        2
    } else if family(".text.hot") {
        3
    } else if name.starts_with(".text.sorted.") {
        4
    } else {
        5
    }
}

/// The bucket of BFD's linker hash table (`bfd_hash_hash` on a 64-bit host, 4051
/// buckets, its default size) a name falls in: the order GNU ld walks symbols in.
pub(crate) fn bfd_hash_bucket(name: &str) -> u64 {
    let mut hash: u64 = 0;
    for &c in name.as_bytes() {
        hash = hash.wrapping_add(c as u64 + ((c as u64) << 17));
        hash ^= hash >> 2;
    }
    let len = name.len() as u64;
    hash = hash.wrapping_add(len + (len << 17));
    hash ^= hash >> 2;
    hash % 4051
}

/// Thread-local bss (`.tbss`): it has an address but, as in GNU ld, takes no room in
/// the layout (the location counter does not move past it) and no loadable segment.
fn is_tbss(x: &OutSection) -> bool {
    x.ty == SHT_NOBITS && x.flags & crate::object::SHF_TLS != 0
}

/// Whether some object refers to `name` without defining it.
fn referenced(objects: &[Object], name: &str) -> bool {
    objects.iter().any(|o| {
        o.symbols
            .iter()
            .any(|s| s.name == name && s.section == SymSection::Undefined)
    })
}

fn parse_number(s: &str) -> Option<u32> {
    match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16).ok(),
        None => s.parse().ok(),
    }
}
