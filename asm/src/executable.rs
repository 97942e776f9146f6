//! The executable ELF file `spu ld` writes, laid out as GNU ld lays out an SPU program:
//! one loadable segment per run of sections with the same permissions (code and
//! read-only data R+X, data and bss R+W), section flags and alignments from the inputs,
//! section symbols, then the locals, then the globals with their types, sizes and
//! bindings kept, so that `readelf -a` reads the two linkers' outputs alike.

use crate::object::{SHF_ALLOC, SHF_EXECINSTR, SHF_TLS, SHF_WRITE};

const EM_SPU: u16 = 23;
const SHT_NOTE: u32 = 7;
const SHT_NOBITS: u32 = 8;
const SHF_STRINGS: u64 = 0x20;
/// GNU ld's page size for the SPU (`MAXPAGESIZE`): segments start at file offsets
/// congruent to their addresses modulo this.
pub const PAGE: u32 = 0x80;

/// A section that is not loaded (`.debug_*`): its contents follow the image in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Unloaded {
    pub name: String,
    /// SHT_* type: PROGBITS, NOTE (`.note.spu_name` gets a PT_NOTE segment), NOBITS
    /// (`data` is zeros of its size, not written), INIT_ARRAY...
    pub ty: u32,
    pub flags: u64,
    pub entsize: u64,
    pub align: u32,
    pub data: Vec<u8>,
}

/// One output section.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Section {
    pub name: String,
    pub addr: u32,
    pub size: u32,
    /// SHF_* flags.
    pub flags: u64,
    /// `.bss`-like: takes no file space.
    pub nobits: bool,
    /// SHT_* type (PROGBITS, NOBITS, NOTE, INIT_ARRAY...).
    pub ty: u32,
    /// Placed after the script's `_end` (an allocated note, `._ea`): its header goes
    /// among the unloaded sections', in the script's order.
    pub late: bool,
    /// The largest alignment of its inputs.
    pub align: u32,
}

/// Where a symbol of the output is defined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Place {
    /// Index into the sections.
    Section(usize),
    Absolute,
    /// Index into the unloaded sections: a global GNU ld keeps in a debugging section.
    Unloaded(usize),
    /// Undefined: the entry symbol GNU ld's `ENTRY(_start)` looked for and did not find.
    Undefined,
}

/// One symbol of the output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Symbol {
    pub name: String,
    pub value: u32,
    pub size: u32,
    /// STT_* type.
    pub kind: u8,
    /// STB_* binding: 0 local, 1 global, 2 weak.
    pub bind: u8,
    pub place: Place,
}

/// What an executable with overlays adds (`spu ld -T` with `OVERLAY`).
#[derive(Clone, Debug, Default)]
pub struct Overlaid {
    /// (section index, overlay index, contents) of each overlay section: its contents
    /// are its own, not the image's at its address.
    pub overlays: Vec<(usize, u32, Vec<u8>)>,
    /// Each section's load address (LMA), for the program headers' `p_paddr`.
    pub lma: Vec<u32>,
    /// The address of the overlay table (`.ovtab`, in the image): each overlay's file
    /// offset goes into its entry, as `spu_elf_modify_headers` writes it.
    pub table: Option<u32>,
    /// A section that stands in a segment of its own (`.toe`).
    pub alone: Option<usize>,
    /// Where a linker script leaves `.note.spu_name` (an orphan, at the location
    /// counter's end), which then has an address and a section symbol.
    pub note_addr: Option<u32>,
    /// The file laid out as BFD lays it out (see [`write_overlaid`]).
    pub gnu_offsets: bool,
}

/// `PF_OVERLAY`: the program header flag of an overlay's segment.
pub const PF_OVERLAY: u32 = 0x0800_0000;

fn be16(v: u16) -> [u8; 2] {
    v.to_be_bytes()
}
fn be32(v: u32) -> [u8; 4] {
    v.to_be_bytes()
}

/// The program headers: (flags, first section, last section) for each run of allocated
/// sections (in address order) with the same permissions.
fn segments(sections: &[Section], alone: &dyn Fn(usize) -> bool) -> Vec<(u32, usize, usize)> {
    let mut out: Vec<(u32, usize, usize)> = Vec::new();
    for (i, s) in sections.iter().enumerate() {
        if s.flags & SHF_ALLOC == 0 || (s.nobits && s.flags & SHF_TLS != 0) {
            continue; // not loaded: thread-local bss takes no local store
        }
        // R, and W or X where a section of the segment is writable or code: read-only
        // data shares the code's segment, as GNU ld puts it.
        let write = if s.flags & SHF_WRITE != 0 { 2 } else { 0 };
        let exec = if s.flags & SHF_EXECINSTR != 0 { 1 } else { 0 };
        match out.last_mut() {
            Some(last)
                if last.0 & 2 == write
                    && s.late == sections[last.2].late
                    && !alone(i)
                    && !alone(last.2) =>
            {
                last.0 |= exec;
                last.2 = i;
            }
            _ => out.push((4 | write | exec, i, i)),
        }
    }
    out
}

/// The ELF file: `image` is local store from 0; `sections` in address order; `symbols`
/// locals first.
pub fn write(
    image: &[u8],
    sections: &[Section],
    unloaded: &[Unloaded],
    symbols: &[Symbol],
    entry: u32,
) -> Vec<u8> {
    write_overlaid(
        image,
        sections,
        unloaded,
        symbols,
        entry,
        &Overlaid::default(),
    )
}

/// [`write()`] for a program with overlays: each overlay section in a segment of its own
/// flagged `PF_OVERLAY`, those segments first, and the file laid out as BFD lays it
/// out (each segment after the last, at an offset congruent to its address modulo the
/// page), since the overlay table names the overlays' file offsets.
pub fn write_overlaid(
    image: &[u8],
    sections: &[Section],
    unloaded: &[Unloaded],
    symbols: &[Symbol],
    entry: u32,
    overlaid: &Overlaid,
) -> Vec<u8> {
    let overlay_of = |k: usize| overlaid.overlays.iter().find(|o| o.0 == k);
    let alone = |k: usize| overlay_of(k).is_some() || overlaid.alone == Some(k);
    let mut segs = segments(sections, &alone);
    // spu_elf_modify_segment_map: the overlays' segments first.
    segs.sort_by_key(|s| overlay_of(s.1).map_or(u32::MAX, |o| o.1));
    let gnu_offsets = overlaid.gnu_offsets || !overlaid.overlays.is_empty();
    // The section headers' order: the loaded sections, then the unloaded and late ones
    // by the script's order; `index[k]` is loaded section k's header index.
    let mut tail: Vec<(usize, bool, usize)> = unloaded
        .iter()
        .enumerate()
        .map(|(j, u)| (crate::link_debug::script_rank(&u.name), false, j))
        .chain(
            sections
                .iter()
                .enumerate()
                .filter(|(_, s)| s.late)
                .map(|(k, s)| {
                    // An orphan note stands after `.note.spu_name`.
                    let name = if crate::link_debug::in_script(&s.name) {
                        s.name.as_str()
                    } else {
                        ".note.spu_name"
                    };
                    (crate::link_debug::script_rank(name) + 1, true, k)
                }),
        )
        .collect();
    tail.sort_by_key(|t| t.0);
    let early: Vec<usize> = (0..sections.len()).filter(|&k| !sections[k].late).collect();
    let mut index = vec![0u16; sections.len()];
    for (n, &k) in early.iter().enumerate() {
        index[k] = n as u16 + 1;
    }
    let mut unloaded_index = vec![0u16; unloaded.len()];
    for (n, t) in tail.iter().enumerate() {
        let at = (early.len() + n) as u16 + 1;
        if t.1 {
            index[t.2] = at;
        } else {
            unloaded_index[t.2] = at;
        }
    }
    let notes = unloaded.iter().filter(|u| u.ty == SHT_NOTE).count();
    let phnum = segs.len() + notes;
    let ehsize = 52u32;
    let phoff = ehsize;
    // The image at an offset congruent to address 0 modulo the page, after the headers.
    let image_off = if gnu_offsets {
        ehsize + 32 * phnum as u32
    } else {
        (ehsize + 32 * phnum as u32).div_ceil(PAGE) * PAGE
    };
    // Where each segment and section stands in the file (`seg_off`, `sec_off`) and the
    // loaded contents from `image_off` on (`loaded`).
    let mut seg_off: Vec<u32> = segs
        .iter()
        .map(|s| image_off + sections[s.1].addr)
        .collect();
    let mut sec_off: Vec<u32> = sections.iter().map(|s| image_off + s.addr).collect();
    let mut loaded = image.to_vec();
    if gnu_offsets {
        // BFD's assign_file_positions_for_load_sections: each segment with contents
        // after the last, at an offset congruent to its address modulo the page.
        loaded.clear();
        let mut off = image_off;
        for (j, &(_, first, last)) in segs.iter().enumerate() {
            let start = sections[first].addr;
            let file_end = sections[first..=last]
                .iter()
                .filter(|s| !s.nobits)
                .map(|s| s.addr + s.size)
                .max();
            let Some(file_end) = file_end else {
                // No contents: BFD gives it the offset its address has in a page.
                seg_off[j] = start & (PAGE - 1);
                for k in first..=last {
                    sec_off[k] = off + (sections[k].addr.wrapping_sub(off) & (PAGE - 1));
                }
                continue;
            };
            off += start.wrapping_sub(off) & (PAGE - 1);
            seg_off[j] = off;
            loaded.resize((off - image_off) as usize, 0);
            // A NOBITS section stands where the file's contents have got to.
            let mut pos = off;
            for k in first..=last {
                let s = &sections[k];
                if s.nobits {
                    sec_off[k] = pos;
                    continue;
                }
                sec_off[k] = off + (s.addr - start);
                pos = sec_off[k] + s.size;
                let data = match overlay_of(k) {
                    Some(o) => &o.2[..],
                    None => &image[s.addr as usize..(s.addr + s.size) as usize],
                };
                let at = (sec_off[k] - image_off) as usize;
                loaded.resize(loaded.len().max(at + data.len()), 0);
                loaded[at..at + data.len()].copy_from_slice(data);
            }
            off += file_end - start;
        }
        // spu_elf_modify_headers: each overlay's file offset into `_ovly_table`.
        if let Some(table) = overlaid.table {
            let k = (0..sections.len())
                .find(|&k| table >= sections[k].addr && table < sections[k].addr + sections[k].size)
                .filter(|&k| overlay_of(k).is_none());
            for (j, seg) in segs.iter().enumerate() {
                let (Some(k), Some(o)) = (k, overlay_of(seg.1)) else {
                    continue;
                };
                let at = (sec_off[k] - image_off + (table - sections[k].addr)) as usize
                    + 16 * o.1 as usize
                    + 8;
                if at + 4 <= loaded.len() {
                    loaded[at..at + 4].copy_from_slice(&be32(seg_off[j]));
                }
            }
        }
    }
    let mut shstr = vec![0u8];
    let mut strtab = vec![0u8];
    let add_name = |s: &str, table: &mut Vec<u8>| {
        let off = table.len() as u32;
        table.extend(s.as_bytes());
        table.push(0);
        off
    };
    // Symbols: null, one per section, locals, globals.
    let mut symtab = vec![0u8; 16];
    let note = |u: &Unloaded| u.name == ".note.spu_name";
    // (header index, address) of each section symbol: the loaded sections', and as
    // BFD writes them (`gnu_offsets`) every section's, in header order.
    let mut section_symbols: Vec<(u16, u32)> = sections
        .iter()
        .enumerate()
        .map(|(k, s)| (index[k], s.addr))
        .collect();
    if gnu_offsets {
        for (n, t) in tail.iter().enumerate() {
            if !t.1 {
                let a = overlaid.note_addr.filter(|_| note(&unloaded[t.2]));
                section_symbols.push(((early.len() + n + 1) as u16, a.unwrap_or(0)));
            }
        }
        section_symbols.sort();
    }
    for &(index, addr) in &section_symbols {
        symtab.extend(be32(0));
        symtab.extend(be32(addr));
        symtab.extend(be32(0));
        symtab.push(3); // STB_LOCAL, STT_SECTION
        symtab.push(0);
        symtab.extend(be16(index));
    }
    let mut ordered: Vec<&Symbol> = symbols.iter().filter(|s| s.bind == 0).collect();
    let first_global = section_symbols.len() + 1 + ordered.len();
    ordered.extend(symbols.iter().filter(|s| s.bind != 0));
    // BFD's string table keeps a name that ends another once, inside the longer one.
    let merged: Option<std::collections::HashMap<&str, u32>> = gnu_offsets.then(|| {
        let names: Vec<&str> = ordered.iter().map(|s| s.name.as_str()).collect();
        let inside = |n: &str| {
            names
                .iter()
                .find(|m| m.len() > n.len() && m.ends_with(n))
                .copied()
        };
        let mut at = std::collections::HashMap::new();
        for &n in &names {
            if inside(n).is_none() && !at.contains_key(n) {
                at.insert(n, add_name(n, &mut strtab));
            }
        }
        for &n in &names {
            if let Some(m) = inside(n) {
                let off = at[m] + (m.len() - n.len()) as u32;
                at.insert(n, off);
            }
        }
        at
    });
    for s in ordered {
        let n = match &merged {
            Some(at) => at[s.name.as_str()],
            None => add_name(&s.name, &mut strtab),
        };
        symtab.extend(be32(n));
        symtab.extend(be32(s.value));
        symtab.extend(be32(s.size));
        symtab.push((s.bind << 4) | (s.kind & 0xf));
        symtab.push(0);
        symtab.extend(be16(match s.place {
            Place::Section(k) => index[k],
            Place::Unloaded(k) => unloaded_index[k],
            Place::Absolute => 0xfff1,
            Place::Undefined => 0,
        }));
    }
    let mut body = loaded;
    // Zeros to the next 16 bytes: the LOAD sizes are rounded up to 16 (`round_loads`),
    // and what they load past the last section must be zeros, as in GNU ld's file.
    // (Alignments are of file offsets: the body starts at `image_off`.)
    let file_align = |v: &mut Vec<u8>, a: u32| {
        let end = (image_off as usize + v.len()).next_multiple_of(a.max(1) as usize);
        v.resize(end - image_off as usize, 0);
    };
    if !gnu_offsets {
        file_align(&mut body, 16);
    }
    let align4 = |v: &mut Vec<u8>| file_align(v, 4);
    let mut unloaded_off = Vec::new();
    for u in unloaded {
        file_align(&mut body, u.align);
        unloaded_off.push(image_off + body.len() as u32);
        if u.ty != SHT_NOBITS {
            body.extend(&u.data);
        }
    }
    align4(&mut body);
    let symtab_off = image_off + body.len() as u32;
    body.extend(&symtab);
    let strtab_off = image_off + body.len() as u32;
    body.extend(&strtab);
    // BFD names its own tables first.
    let tables =
        |shstr: &mut Vec<u8>| [".symtab", ".strtab", ".shstrtab"].map(|n| add_name(n, shstr));
    let first = gnu_offsets.then(|| tables(&mut shstr));
    let names: Vec<u32> = sections
        .iter()
        .map(|s| add_name(&s.name, &mut shstr))
        .collect();
    let unloaded_names: Vec<u32> = unloaded
        .iter()
        .map(|u| add_name(&u.name, &mut shstr))
        .collect();
    let [symtab_name, strtab_name, shstrtab_name] = first.unwrap_or_else(|| tables(&mut shstr));
    let shstr_off = image_off + body.len() as u32;
    body.extend(&shstr);
    align4(&mut body);
    let shoff = image_off + body.len() as u32;
    let shnum = (sections.len() + unloaded.len()) as u16 + 4;
    let mut out = Vec::new();
    out.extend([0x7f, b'E', b'L', b'F', 1, 2, 1, 0]);
    out.extend([0u8; 8]);
    out.extend(be16(2)); // ET_EXEC
    out.extend(be16(EM_SPU));
    out.extend(be32(1));
    out.extend(be32(entry));
    out.extend(be32(if phnum == 0 { 0 } else { phoff }));
    out.extend(be32(shoff));
    out.extend(be32(0));
    out.extend(be16(ehsize as u16));
    out.extend(be16(32));
    out.extend(be16(phnum as u16));
    out.extend(be16(40));
    out.extend(be16(shnum));
    out.extend(be16(shnum - 1));
    // (offset, address, file size, memory size, flags) of each loadable segment.
    let mut loads: Vec<[u32; 5]> = segs
        .iter()
        .map(|&(flags, first, last)| {
            let start = sections[first].addr;
            let end = |s: &Section| s.addr + s.size;
            let file_end = sections[first..=last]
                .iter()
                .filter(|s| !s.nobits)
                .map(end)
                .max()
                .unwrap_or(start);
            let mem_end = sections[first..=last]
                .iter()
                .map(end)
                .max()
                .unwrap_or(start);
            [start, start, file_end - start, mem_end - start, flags]
        })
        .collect();
    for (j, l) in loads.iter_mut().enumerate() {
        l[0] = seg_off[j];
    }
    round_loads(&mut loads);
    for (j, [off, addr, filesz, memsz, flags]) in loads.into_iter().enumerate() {
        let first = segs[j].1;
        let paddr = overlaid.lma.get(first).copied().unwrap_or(addr);
        let flags = if overlay_of(first).is_some() {
            flags | PF_OVERLAY
        } else {
            flags
        };
        for v in [1, off, addr, paddr, filesz, memsz, flags, PAGE] {
            out.extend(be32(v));
        }
    }
    for (u, &off) in unloaded.iter().zip(&unloaded_off) {
        if u.ty == SHT_NOTE {
            let a = overlaid.note_addr.filter(|_| note(u)).unwrap_or(0);
            for v in [4, off, a, a, u.data.len() as u32, 0, 4, u.align] {
                out.extend(be32(v));
            }
        }
    }
    out.resize(image_off as usize, 0);
    out.extend(&body);
    let sh = |out: &mut Vec<u8>, fields: [u32; 10]| {
        for v in fields {
            out.extend(be32(v));
        }
    };
    sh(&mut out, [0; 10]);
    let loaded_header = |out: &mut Vec<u8>, k: usize, n: u32| {
        let s = &sections[k];
        let ty = s.ty;
        // GNU ld keeps SHF_STRINGS on an output section and drops SHF_MERGE.
        let flags =
            (s.flags & (SHF_ALLOC | SHF_WRITE | SHF_EXECINSTR | SHF_TLS | SHF_STRINGS)) as u32;
        let off = sec_off[k];
        sh(out, [n, ty, flags, s.addr, off, s.size, 0, 0, s.align, 0]);
    };
    for &k in &early {
        loaded_header(&mut out, k, names[k]);
    }
    for &(_, late, j) in &tail {
        if late {
            loaded_header(&mut out, j, names[j]);
            continue;
        }
        let (u, n, off) = (&unloaded[j], unloaded_names[j], unloaded_off[j]);
        let flags = u.flags as u32;
        let size = u.data.len() as u32;
        sh(
            &mut out,
            [
                n,
                u.ty,
                flags,
                overlaid.note_addr.filter(|_| note(u)).unwrap_or(0),
                off,
                size,
                0,
                0,
                u.align,
                u.entsize as u32,
            ],
        );
    }
    let symtab_index = (sections.len() + unloaded.len()) as u32 + 1;
    sh(
        &mut out,
        [
            symtab_name,
            2,
            0,
            0,
            symtab_off,
            symtab.len() as u32,
            symtab_index + 1,
            first_global as u32,
            4,
            16,
        ],
    );
    sh(
        &mut out,
        [
            strtab_name,
            3,
            0,
            0,
            strtab_off,
            strtab.len() as u32,
            0,
            0,
            1,
            0,
        ],
    );
    sh(
        &mut out,
        [
            shstrtab_name,
            3,
            0,
            0,
            shstr_off,
            shstr.len() as u32,
            0,
            0,
            1,
            0,
        ],
    );
    out
}

/// GNU ld's SPU backend (`spu_elf_modify_headers`) rounds the loadable segments' file
/// and memory sizes up to multiples of 16, unless that would make one run into the next.
fn round_loads(loads: &mut [[u32; 5]]) {
    let mut last: Option<[u32; 5]> = None;
    for l in loads.iter().rev() {
        let [off, addr, filesz, memsz, _] = *l;
        if let Some([last_off, last_addr, ..]) = last {
            let adjust = filesz.wrapping_neg() & 15;
            if adjust != 0 && off + filesz > last_off.wrapping_sub(adjust) {
                return;
            }
            let adjust = memsz.wrapping_neg() & 15;
            if adjust != 0
                && filesz != 0
                && addr + memsz > last_addr.wrapping_sub(adjust)
                && addr + memsz <= last_addr
            {
                return;
            }
        }
        if filesz != 0 {
            last = Some(*l);
        }
    }
    for l in loads.iter_mut() {
        l[2] = l[2].next_multiple_of(16);
        l[3] = l[3].next_multiple_of(16);
    }
}
