//! `spu ld`: links relocatable SPU objects into an executable local-store image, as GNU
//! ld's default SPU script lays it out (code, read-only data, data, bss, commons at the
//! end of bss), resolving symbols across objects and applying the SPU relocations.
//! Overlays are not supported (docs/linker.md).

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
    let mut errors = Vec::new();
    // Output sections in GNU ld's order.
    let mut outs: Vec<OutSection> = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for (i, s) in obj.sections.iter().enumerate() {
            if s.flags & SHF_ALLOC == 0 || s.flags & SHF_EXCLUDE != 0 {
                continue;
            }
            let name = output_name(&s.name);
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
        if out.name == ".text" {
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
    for (n, &k) in order.iter().enumerate() {
        let class = script_placement(&outs[k].name, outs[k].ty, outs[k].flags).0;
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
        for b in &outs[i + 1..] {
            let b_end = b.addr as u64 + b.size as u64;
            if a.size > 0 && b.size > 0 && (a.addr as u64) < b_end && (b.addr as u64) < a_end {
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
    let script: HashMap<&str, u64> = [
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
    .filter(|(n, _)| !globals.contains_key(*n) && !common_at.contains_key(*n))
    .filter(|(n, _)| !PROVIDED.contains(n) || referenced(objects, n))
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
    let mut image = vec![0u8; image_end as usize];
    for out in &outs {
        for &(o, i, at) in &out.inputs {
            let s = &objects[o].sections[i];
            if s.ty != SHT_NOBITS {
                let start = (out.addr + at) as usize;
                let n = s.data.len().min(s.size as usize);
                image[start..start + n].copy_from_slice(&s.data[..n]);
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
            for r in &s.relocs {
                let target = match &r.target {
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
                let value = sv as i64 + r.addend;
                if let Err(m) = crate::reloc::apply(r.kind, &mut image, base + r.offset, value) {
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
    let mut out_symbols = Vec::new();
    for (o, obj) in objects.iter().enumerate() {
        for s in &obj.symbols {
            if s.global || s.name.starts_with(".L") || s.name.is_empty() {
                continue;
            }
            if let (SymSection::Section(i), Some(a)) =
                (s.section, address_of(o, s.section, s.value))
            {
                out_symbols.push(crate::executable::Symbol {
                    name: s.name.clone(),
                    value: a as u32,
                    size: s.size as u32,
                    kind: s.kind,
                    bind: 0,
                    place: by_addr
                        .iter()
                        .position(|x| x.name == output_name(&obj.sections[i].name))
                        .map_or_else(|| place_of(a), crate::executable::Place::Section),
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
    for n in names {
        if replaced.contains(n) {
            continue;
        }
        let Some(a) = global_address(n) else { continue };
        let (size, kind, bind, place) = match (globals.get(n), common_at.contains_key(n)) {
            (Some(d), _) => {
                let place = match d.section {
                    SymSection::Absolute => crate::executable::Place::Absolute,
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
            .map(|s| (s.name.clone(), s.value))
            .collect();
        v.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)));
        v
    };
    let mut warnings = Vec::new();
    let entry_name = opts.entry.clone().unwrap_or_else(|| "_start".into());
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
    let mut unloaded = crate::link_debug::sections(objects, &resolve)?;
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
    }
    let elf = crate::executable::write(&image, &out_sections, &unloaded, &out_symbols, entry);
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
fn bfd_hash_bucket(name: &str) -> u64 {
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
