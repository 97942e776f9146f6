//! `objdump -d` for SPU ELF files, objects and executables alike: the same header lines,
//! the same `<symbol>:` blocks, the same choice of symbol for every address an instruction
//! names, objects' bytes dumped as data, runs of zeros folded to `...`. The instruction
//! text itself is `spu_isa::disasm`'s; what lives here is binutils' `objdump.c` part: which
//! sections, which symbols, and in what order (its `compare_symbols`,
//! `find_symbol_for_address` and `disassemble_bytes`).

use object::elf;
use object::read::elf::{FileHeader, SectionHeader, Sym};
use object::BigEndian;
use spu_isa::disasm::{instruction_text_ext, Symbolizer};
use spu_isa::ext::Extensions;
use std::cmp::Ordering;
use std::fmt::Write;

/// objdump's `DEFAULT_SKIP_ZEROES`: this many zero bytes or more print as `...`.
const SKIP_ZEROES: usize = 8;
/// objdump's `DEFAULT_SKIP_ZEROES_AT_END`: fewer zero bytes than this at a block's end
/// print as `...` too.
const SKIP_ZEROES_AT_END: usize = 3;

/// A symbol as BFD presents it to objdump, once the useless ones (unnamed, section and
/// file symbols, undefined and common ones) are gone.
#[derive(Clone, Debug)]
struct Symbol {
    name: String,
    value: u32,
    /// The ELF section index it is defined in; `None` for an absolute symbol.
    section: Option<usize>,
    function: bool,
    object: bool,
    local: bool,
    global: bool,
    size: u32,
}

/// A section of the file as objdump sees it.
struct Section<'a> {
    index: usize,
    name: String,
    vma: u32,
    data: &'a [u8],
    code: bool,
}

/// objdump's `compare_symbols` with `section` the one being disassembled.
fn compare_symbols(a: &Symbol, b: &Symbol, section: usize) -> Ordering {
    let file_symbol = |n: &str| n.len() > 2 && (n.ends_with(".o") || n.ends_with(".a"));
    let compiled = |n: &str| n.contains("gnu_compiled") || n.contains("gcc2_compiled");
    a.value
        .cmp(&b.value)
        .then_with(|| (b.section == Some(section)).cmp(&(a.section == Some(section))))
        .then_with(|| compiled(&a.name).cmp(&compiled(&b.name)))
        .then_with(|| file_symbol(&a.name).cmp(&file_symbol(&b.name)))
        .then_with(|| b.function.cmp(&a.function))
        .then_with(|| b.object.cmp(&a.object))
        .then_with(|| a.local.cmp(&b.local))
        .then_with(|| b.global.cmp(&a.global))
        .then_with(|| b.size.cmp(&a.size))
        .then_with(|| a.name.starts_with('.').cmp(&b.name.starts_with('.')))
        .then_with(|| a.name.cmp(&b.name))
}

/// The symbols sorted for one section, and how objdump picks among them.
struct Lookup<'a> {
    sorted: Vec<&'a Symbol>,
    section: &'a Section<'a>,
    /// BFD's HAS_RELOC: the file has relocation sections (a relocatable object), so an
    /// address inside the section being disassembled is named after that section's
    /// symbols only.
    has_reloc: bool,
}

impl<'a> Lookup<'a> {
    fn sym_ok(&self, want_section: bool, place: usize) -> bool {
        !want_section || self.sorted[place].section == Some(self.section.index)
    }

    /// objdump's `find_symbol_for_address`: the index in `sorted`.
    fn find(&self, vma: u32, require_sec: bool) -> Option<usize> {
        let n = self.sorted.len();
        if n == 0 {
            return None;
        }
        let (mut min, mut max) = (0usize, n);
        while min + 1 < max {
            let mid = (max + min) / 2;
            let v = self.sorted[mid].value;
            match v.cmp(&vma) {
                Ordering::Greater => max = mid,
                Ordering::Less => min = mid,
                Ordering::Equal => {
                    min = mid;
                    break;
                }
            }
        }
        let mut place = min;
        while place > 0 && self.sorted[place].value == self.sorted[place - 1].value {
            place -= 1;
        }
        let mut min = place;
        while min < max && self.sorted[min].value == self.sorted[place].value {
            if self.sym_ok(true, min) {
                return Some(min);
            }
            min += 1;
        }
        let s = self.section;
        let want = require_sec
            || (self.has_reloc
                && vma >= s.vma
                && (vma as u64) < s.vma as u64 + s.data.len() as u64);
        if !self.sym_ok(want, place) {
            let mut newplace = n;
            for i in (0..min).rev() {
                if self.sym_ok(want, i) {
                    if newplace == n {
                        newplace = i;
                    }
                    if self.sorted[i].value != self.sorted[newplace].value {
                        break;
                    }
                    newplace = i;
                }
            }
            if newplace != n {
                place = newplace;
            } else if let Some(i) = (place + 1..n).find(|&i| self.sym_ok(want, i)) {
                place = i;
            }
            if !self.sym_ok(want, place) {
                return None;
            }
        }
        Some(place)
    }

    /// objdump's `objdump_print_addr_with_sym` without the address.
    fn named(&self, sym: Option<usize>, vma: u32) -> String {
        let (name, at) = match sym {
            Some(i) => (self.sorted[i].name.as_str(), self.sorted[i].value),
            None => (self.section.name.as_str(), self.section.vma),
        };
        match at.cmp(&vma) {
            Ordering::Equal => format!("<{name}>"),
            Ordering::Less => format!("<{name}+0x{:x}>", vma - at),
            Ordering::Greater => format!("<{name}-0x{:x}>", at - vma),
        }
    }
}

impl Symbolizer for Lookup<'_> {
    fn symbol_for(&self, addr: u32) -> Option<(&str, u32)> {
        self.find(addr, false)
            .map(|i| (self.sorted[i].name.as_str(), self.sorted[i].value))
    }
    fn has_symbol_at(&self, addr: u32) -> bool {
        self.find(addr, false)
            .is_some_and(|i| self.sorted[i].value == addr)
    }
    fn address_text(&self, addr: u32) -> String {
        if self.sorted.is_empty() {
            return format!("0x{addr:x}");
        }
        format!("{addr:x} {}", self.named(self.find(addr, false), addr))
    }
}

/// The sections and symbols of an SPU ELF file, as BFD reads them.
type Parsed<'a> = (Vec<Section<'a>>, Vec<Symbol>, bool);

fn read<'a>(name: &str, data: &'a [u8]) -> Result<Parsed<'a>, String> {
    let err = |e: object::read::Error| format!("{name}: {e}");
    let header = elf::FileHeader32::<BigEndian>::parse(data)
        .map_err(|_| format!("{name}: not a 32-bit big-endian ELF file"))?;
    let endian = header.endian().map_err(err)?;
    if header.e_machine(endian) != elf::EM_SPU {
        return Err(format!(
            "{name}: ELF machine {} is not SPU",
            header.e_machine(endian)
        ));
    }
    let executable = header.e_type(endian) != elf::ET_REL;
    let table = header.sections(endian, data).map_err(err)?;
    let symtab = table.symbols(endian, data, elf::SHT_SYMTAB).map_err(err)?;
    let mut sections = Vec::new();
    let mut has_reloc = false;
    for (index, s) in table.iter().enumerate() {
        let ty = s.sh_type(endian);
        if matches!(ty, elf::SHT_REL | elf::SHT_RELA) {
            let target = s.sh_info(endian) as usize;
            has_reloc |= !(executable && s.sh_flags(endian).0 & elf::SHF_ALLOC.0 != 0)
                && s.sh_link(endian) as usize == symtab.section().0
                && symtab.section().0 != 0
                && target != 0
                && table
                    .section(object::SectionIndex(target))
                    .is_ok_and(|t| !matches!(t.sh_type(endian), elf::SHT_REL | elf::SHT_RELA));
        }
        let code = s.sh_flags(endian).0 & elf::SHF_EXECINSTR.0 != 0 && ty != elf::SHT_NOBITS;
        let bytes = if code {
            s.data(endian, data).map_err(err)?
        } else {
            &[]
        };
        sections.push(Section {
            index,
            name: String::from_utf8_lossy(table.section_name(endian, s).map_err(err)?).into_owned(),
            vma: s.sh_addr(endian),
            data: bytes,
            code,
        });
    }
    let mut symbols = Vec::new();
    for sym in symtab.symbols().iter().skip(1) {
        let name =
            String::from_utf8_lossy(symtab.symbol_name(endian, sym).map_err(err)?).into_owned();
        let shndx = sym.st_shndx(endian);
        let kind = sym.st_type();
        if name.is_empty()
            || matches!(kind, elf::STT_SECTION | elf::STT_FILE)
            || shndx == elf::SHN_UNDEF
            || shndx == elf::SHN_COMMON
        {
            continue;
        }
        let section = match shndx {
            elf::SHN_ABS => None,
            i if (i.0 as usize) < sections.len() => Some(i.0 as usize),
            _ => continue,
        };
        let base = match section {
            Some(i) if !executable => sections[i].vma,
            _ => 0,
        };
        let bind = sym.st_bind();
        symbols.push(Symbol {
            name,
            value: base.wrapping_add(sym.st_value(endian)),
            section,
            function: kind == elf::STT_FUNC,
            object: kind == elf::STT_OBJECT,
            local: bind == elf::STB_LOCAL,
            global: bind == elf::STB_GLOBAL,
            size: sym.st_size(endian),
        });
    }
    Ok((sections, symbols, has_reloc))
}

/// How many leading hex digits objdump drops from the 8-digit addresses of a section
/// that ends at `end`: the leading zeros less one, in fours.
fn skipped_address_chars(vma: u32, end: u32) -> usize {
    let zeros = format!("{end:08x}")
        .bytes()
        .take_while(|b| *b == b'0')
        .count();
    // No zeros, or all eight on an overflow past the end of the address space: none go.
    if zeros == 0 || (zeros == 8 && vma != 0) {
        0
    } else {
        (zeros - 1) & !3
    }
}

/// An instruction line's address column.
fn address_column(addr: u32, skip: usize) -> String {
    let full = format!("{addr:08x}");
    let digits = &full[skip..];
    let trimmed = digits.trim_start_matches('0');
    let shown = if trimmed.is_empty() { "0" } else { trimmed };
    format!("{shown:>width$}:\t", width = digits.len())
}

/// objdump's `disassemble_bytes` for `[start, stop)` of `section`: instructions, or data
/// lines of 16 bytes when `insns` is false.
fn disassemble_bytes(
    out: &mut String,
    lookup: &Lookup,
    insns: bool,
    start: usize,
    stop: usize,
    ext: Extensions,
) {
    let s = lookup.section;
    let end = s.vma.wrapping_add(s.data.len() as u32);
    let skip = skipped_address_chars(s.vma, end);
    let per_line = if insns { 4 } else { 16 };
    let mut at = start;
    while at < stop {
        let zeros = s.data[at..stop].iter().take_while(|b| **b == 0).count();
        if zeros >= SKIP_ZEROES || (at + zeros == stop && zeros < SKIP_ZEROES_AT_END) {
            let skipped = if at + zeros != stop {
                zeros & !3
            } else {
                zeros
            };
            out.push_str("\t...\n");
            at += skipped;
            continue;
        }
        let pc = s.vma.wrapping_add(at as u32);
        out.push_str(&address_column(pc, skip));
        if insns {
            if at + 4 > stop {
                let _ = write!(out, "Address 0x{pc:x} is out of bounds.\n\n");
                break;
            }
            let word = u32::from_be_bytes(s.data[at..at + 4].try_into().unwrap());
            for b in word.to_be_bytes() {
                let _ = write!(out, "{b:02x} ");
            }
            out.push('\t');
            out.push_str(&instruction_text_ext(word, pc, lookup, ext));
            out.push('\n');
            at += 4;
        } else {
            let n = per_line.min(stop - at);
            let bytes = &s.data[at..at + n];
            for b in bytes {
                let _ = write!(out, "{b:02x} ");
            }
            for _ in n..per_line {
                out.push_str("   ");
            }
            out.push_str("    ");
            for &b in bytes {
                out.push(if (0x20..0x7f).contains(&b) {
                    b as char
                } else {
                    '.'
                });
            }
            out.push('\n');
            at += n;
        }
    }
}

/// objdump's `disassemble_section`.
fn disassemble_section(
    out: &mut String,
    section: &Section,
    symbols: &[Symbol],
    has_reloc: bool,
    ext: Extensions,
) {
    let mut sorted: Vec<&Symbol> = symbols.iter().collect();
    sorted.sort_by(|a, b| compare_symbols(a, b, section.index));
    let lookup = Lookup {
        sorted,
        section,
        has_reloc,
    };
    let _ = write!(out, "\nDisassembly of section {}:\n", section.name);
    let stop = section.data.len();
    let mut place = lookup.find(section.vma, true);
    let mut sym = place;
    let mut offset = 0usize;
    while offset < stop {
        let addr = section.vma.wrapping_add(offset as u32);
        let _ = write!(out, "\n{addr:08x} {}:\n", lookup.named(sym, addr));
        let value = |i: usize| lookup.sorted[i].value;
        let next = match sym {
            Some(i) if value(i) > addr => Some(i),
            None => None,
            Some(i) => {
                let mut p = place.unwrap_or(i);
                while p < lookup.sorted.len()
                    && !(lookup.sorted[p].section == Some(section.index) && value(p) > value(i))
                {
                    p += 1;
                }
                place = Some(p);
                (p < lookup.sorted.len()).then_some(p)
            }
        };
        let mut next_stop = match (sym, next) {
            (Some(i), _) if value(i) > addr => (value(i) - section.vma) as usize,
            (_, None) => stop,
            (_, Some(n)) => value(n).wrapping_sub(section.vma) as usize,
        };
        if next_stop > stop || next_stop <= offset {
            next_stop = stop;
        }
        let insns = match sym.map(|i| lookup.sorted[i]) {
            None => true,
            Some(s) => {
                s.section != Some(section.index)
                    || s.value > addr
                    || !s.object
                    || s.function
                    || s.name.contains("gnu_compiled")
                    || s.name.contains("gcc2_compiled")
            }
        };
        disassemble_bytes(out, &lookup, insns, offset, next_stop, ext);
        offset = next_stop;
        sym = next;
    }
}

/// The text `objdump -d NAME` prints for the SPU ELF file `data` (object or executable),
/// with the instructions of the extensions `ext` known.
pub fn objdump(name: &str, data: &[u8], ext: Extensions) -> Result<String, String> {
    let (sections, symbols, has_reloc) = read(name, data)?;
    let mut out = format!("\n{name}:     file format elf32-spu\n\n");
    for section in sections.iter().filter(|s| s.code && !s.data.is_empty()) {
        disassemble_section(&mut out, section, &symbols, has_reloc, ext);
    }
    Ok(out)
}
