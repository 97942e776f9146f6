//! Statements and directives (gas's `read.c`): the walk over a list of lines with its
//! blocks (macros, repetitions, conditionals, `.sched`), a line's labels and statements,
//! and the directives that are not about sections or the target: data, alignment, `.org`,
//! `.set`, `.include`, `.reloc`, messages.

use super::macros::collect_block;
use super::{Assembler, Macro, Severity, LOCAL_STORE, MAX_EXPANDED};
use crate::expr::{is_ident, Val};
use crate::lex::{bytes_as_text, read_source, split_top, strip_comment, to_lines, unquote, Line};
use spu_isa::table::forms_named;
use std::collections::HashMap;

impl Assembler<'_> {
    /// The text of an `.include`d file: an in-memory file, else the first found on the
    /// include path, else the name as given.
    fn read_include(&self, name: &str) -> Option<String> {
        if let Some((_, text)) = self.opts.virtual_files.iter().find(|(n, _)| n == name) {
            return Some(bytes_as_text(text.as_bytes()));
        }
        for dir in &self.opts.include_dirs {
            if let Ok(t) = read_source(&dir.join(name)) {
                return Some(t);
            }
        }
        read_source(std::path::Path::new(name)).ok()
    }

    /// Processes a list of lines (one file, a macro body or a repetition).
    pub(super) fn run_lines(&mut self, lines: &[Line]) {
        if self.expanded > MAX_EXPANDED {
            return;
        }
        self.depth += 1;
        if self.depth > 64 {
            if let Some(l) = lines.first() {
                self.diag(
                    Severity::Error,
                    l,
                    1,
                    "macros, includes or repetitions nested too deeply",
                );
            }
            self.depth -= 1;
            return;
        }
        let mut i = 0;
        let mut cond: Vec<(bool, bool)> = Vec::new(); // (active, any branch taken)
        while i < lines.len() {
            let line = &lines[i];
            self.expanded += 1;
            if self.expanded > MAX_EXPANDED {
                self.diag(
                    Severity::Error,
                    line,
                    1,
                    format!(
                        "more than {MAX_EXPANDED} statements after expanding macros, .rept and .irp: stopped"
                    ),
                );
                break;
            }
            let text = strip_comment(&line.text);
            let trimmed = text.trim();
            let word = trimmed
                .split(|c: char| c.is_whitespace() || c == ',')
                .next()
                .unwrap_or("");
            let rest_of_line = &trimmed[word.len()..];
            let first_word = block_word(word, &self.macros);
            // Conditionals are tracked even while inactive.
            if self.conditional(&mut cond, &first_word, rest_of_line.trim(), line) {
                i += 1;
                continue;
            }
            let active = cond.iter().all(|c| c.0);
            if !active {
                i += 1;
                continue;
            }
            if first_word == ".exitm" {
                if self.macro_depth > 0 {
                    self.exitm = true;
                } else {
                    self.diag(Severity::Error, line, 1, ".exitm outside a macro");
                    i += 1;
                    continue;
                }
            }
            if self.exitm {
                break;
            }
            // A list-scheduled block (crate::sched) up to its `.endsched`.
            if first_word == ".sched" {
                let end = lines[i + 1..]
                    .iter()
                    .position(|l| crate::lex::first_word(&l.text) == ".endsched");
                let Some(k) = end else {
                    self.diag(Severity::Error, line, 1, "missing .endsched");
                    break;
                };
                self.sched_block(trimmed[6..].trim(), &lines[i + 1..i + 1 + k], line);
                i += k + 2;
                continue;
            }
            // Block directives that swallow lines up to their end.
            if matches!(first_word.as_str(), ".macro" | ".rept" | ".irp" | ".irpc") {
                let (body, next) = collect_block(lines, i + 1);
                if next > lines.len() {
                    self.diag(
                        Severity::Error,
                        line,
                        1,
                        format!("missing end of {first_word}"),
                    );
                }
                let args = rest_of_line.trim().to_string();
                self.block(&first_word, &args, body, line);
                i = next;
                continue;
            }
            self.statement(line, &text);
            i += 1;
        }
        if !cond.is_empty() && !self.exitm {
            if let Some(l) = lines.last() {
                self.diag(Severity::Error, l, 1, "missing .endif");
            }
        }
        self.depth -= 1;
    }

    /// One line's statements (separated by `;`): labels, then a macro call, an assignment,
    /// a directive or an instruction; in the final walk each adds its listing line.
    fn statement(&mut self, line: &Line, text: &str) {
        for piece in split_top(text, ';') {
            self.stmt += 1;
            let mut rest = piece.trim().to_string();
            // Labels.
            while let Some(colon) = rest.find(':') {
                let name = rest[..colon].trim();
                if name.is_empty() || !name.chars().all(is_ident) || name.contains(' ') {
                    break;
                }
                self.define_label(name, line);
                self.stmt += 1;
                rest = rest[colon + 1..].trim().to_string();
            }
            if rest.is_empty() {
                continue;
            }
            let (word, args) = match rest.find(char::is_whitespace) {
                Some(p) => (rest[..p].to_string(), rest[p..].trim().to_string()),
                None => (rest.clone(), String::new()),
            };
            let lw = word.to_ascii_lowercase();
            let col = line.text.find(&word).map(|c| c + 1).unwrap_or(1);
            let before = (
                self.sect,
                self.offsets.get(&self.sect).copied().unwrap_or(0),
            );
            if let Some(m) = self.macros.get(&lw).cloned() {
                self.expand_macro(&m, &args, line);
            } else if args.starts_with('=') && !args.starts_with("==") {
                let v = args[1..].trim().to_string();
                self.set_symbol(&word, &v, line);
            } else if lw.starts_with('.') {
                self.directive(&lw, &args, line, col);
            } else if !args.starts_with('=')
                && lw != "set"
                && forms_named(&lw).next().is_none()
                && is_directive(&format!(".{lw}"))
            {
                // A pseudo-op written without its dot (`GLOBL`), as gas's NO_PSEUDO_DOT
                // targets and MRI mode read it.
                self.directive(&format!(".{lw}"), &args, line, col);
            } else if let Some(v) = args.strip_prefix('=') {
                let v = v.trim().to_string();
                self.set_symbol(&word, &v, line);
            } else if let Some((name, value)) = word
                .split_once('=')
                .filter(|(n, _)| !n.is_empty() && !n.contains(|c: char| c.is_whitespace()))
            {
                // `name=value` written without spaces, as gas accepts it.
                let v = format!("{value}{}{args}", if args.is_empty() { "" } else { " " });
                self.set_symbol(name, v.trim(), line);
            } else {
                self.instruction(&lw, &args, line, col);
            }
            if self.pass == 2 {
                let after = self.offsets.get(&before.0).copied().unwrap_or(0);
                if after > before.1 && self.sect == before.0 {
                    let base = self.bases.get(&before.0).copied().unwrap_or(0);
                    let bytes = self
                        .bytes
                        .get(&before.0)
                        .map(|b| b[before.1 as usize..(after as usize).min(b.len())].to_vec())
                        .unwrap_or_default();
                    let words: Vec<String> = bytes
                        .chunks(4)
                        .take(4)
                        .map(|c| c.iter().map(|b| format!("{b:02x}")).collect())
                        .collect();
                    self.listing.push_str(&format!(
                        "{:5} {:05x} {:<36} {}\n",
                        line.line,
                        base + before.1,
                        words.join(" "),
                        line.text.trim_end()
                    ));
                }
            }
        }
    }

    /// The comma-separated values of a directive's operands (0 for one in error).
    pub(super) fn data_values(&mut self, args: &str, line: &Line, col: usize) -> Vec<i64> {
        let mut out = Vec::new();
        if args.trim().is_empty() {
            return out;
        }
        for part in split_top(args, ',') {
            match self.eval(part.trim()) {
                Ok((v, _)) => out.push(v),
                Err((c, m)) => {
                    self.diag(Severity::Error, line, col + c, m);
                    out.push(0);
                }
            }
        }
        out
    }

    /// `.org EXPR` and `. = EXPR`: move forward to an offset in the current section.
    pub(super) fn org(&mut self, expr: &str, fill: u8, line: &Line, col: usize) {
        let (v, _, _) = match self.eval_val(expr) {
            Ok(v) => v,
            Err((c, m)) => {
                self.diag(Severity::Error, line, col + c, m);
                return;
            }
        };
        let base = self.bases.get(&self.sect).copied().unwrap_or(0) as i64;
        let target = if v.reloc {
            if v.sect != Some(self.chunks[self.sect].0) && self.pass == 2 {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    "attempt to move .org into another section",
                );
                return;
            }
            v.v - base
        } else {
            // An absolute .org is an offset from the start of the section.
            v.v - (base - self.section_start(self.sect))
        };
        let off = self.offsets.get(&self.sect).copied().unwrap_or(0) as i64;
        if target < off {
            if self.pass == 2 {
                self.diag(Severity::Error, line, col, "attempt to move .org backwards");
            }
            return;
        }
        if target - off > 2 * LOCAL_STORE as i64 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!(".org to {target:#x} is past the local store"),
            );
            return;
        }
        self.emit(&vec![fill; (target - off) as usize]);
    }

    /// `.balignw/.balignl/.p2alignw/.p2alignl BOUNDARY[, PATTERN[, MAX]]`: padding filled
    /// with a 2- or 4-byte big-endian pattern; the padding must be a multiple of it.
    fn align_pattern(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        let parts = split_top(args, ',');
        let v = self
            .data_values(&parts[0], line, col)
            .first()
            .copied()
            .unwrap_or(0);
        let boundary = if d.starts_with(".p2") {
            if !(0..=15).contains(&v) {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    format!("alignment too large: {v}"),
                );
                return;
            }
            1i64 << v
        } else {
            v
        };
        if boundary <= 0 || boundary & (boundary - 1) != 0 || boundary > 1 << 15 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("alignment not a power of 2: {boundary}"),
            );
            return;
        }
        let size = if d.ends_with('w') { 2 } else { 4 };
        let pattern = parts
            .get(1)
            .map(|p| p.trim())
            .filter(|p| !p.is_empty())
            .map(|p| self.data_values(p, line, col).first().copied().unwrap_or(0));
        let max = match parts.get(2) {
            Some(m) => self.data_values(m, line, col).first().copied(),
            None => None,
        };
        let off = self.here() as i64;
        let pad = (boundary - off % boundary) % boundary;
        if max.is_some_and(|m| pad > m) {
            return;
        }
        let Some(pattern) = pattern else {
            self.align_to(boundary as u32, None);
            return;
        };
        if pad % size != 0 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("alignment padding ({pad} bytes) not a multiple of {size}"),
            );
            return;
        }
        let a = self.align.entry(self.sect).or_insert(1);
        *a = (*a).max(boundary as u32);
        let word = pattern.to_be_bytes();
        let mut bytes = Vec::with_capacity(pad as usize);
        for _ in 0..pad / size {
            bytes.extend_from_slice(&word[8 - size as usize..]);
        }
        self.emit(&bytes);
    }

    /// `.reloc OFFSET, TYPE[, EXPR]`: an explicit relocation (objects), applied at once in
    /// an executable.
    fn reloc_directive(&mut self, args: &str, line: &Line, col: usize) {
        let parts = split_top(args, ',');
        if parts.len() < 2 {
            self.diag(
                Severity::Error,
                line,
                col,
                "expected OFFSET, TYPE[, EXPR] after .reloc",
            );
            return;
        }
        let ty = parts[1].trim();
        let kind = crate::reloc::by_name(ty).or_else(|| self.eval(ty).ok().map(|v| v.0 as u32));
        let Some(kind) = kind.filter(|k| crate::reloc::name(*k).is_some()) else {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("unrecognized reloc type `{ty}'"),
            );
            return;
        };
        let offset = match self.eval_val(parts[0].trim()) {
            Ok((v, _, _)) => v,
            Err((c, m)) => {
                self.diag(Severity::Error, line, col + c, m);
                return;
            }
        };
        let value = match parts.get(2) {
            Some(e) => match self.eval_val(e.trim()) {
                Ok((v, _, _)) => v,
                Err((c, m)) => {
                    self.diag(Severity::Error, line, col + c, m);
                    return;
                }
            },
            None => Val::abs(0),
        };
        if self.pass != 2 {
            return;
        }
        let sect = self.sect;
        let offset = if offset.reloc {
            offset.v - self.section_start(sect)
        } else {
            offset.v
        } as u32;
        self.add_reloc(sect, offset, kind, &value, line, col);
    }

    /// Records a relocation at `offset` in the section of chunk `sect` (pass 2): in an
    /// A directive other than the block and conditional ones (handled in `run_lines`).
    fn directive(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        match d {
            ".org" => {
                let parts = split_top(args, ',');
                let fill = match parts.get(1) {
                    Some(f) => self.data_values(f, line, col).first().copied().unwrap_or(0),
                    None => 0,
                };
                self.org(parts[0].trim(), fill as u8, line, col);
            }
            ".uleb128" | ".sleb128" => {
                for v in self.data_values(args, line, col) {
                    let bytes = leb128(v, d == ".sleb128");
                    self.emit(&bytes);
                }
            }
            ".balignw" | ".balignl" | ".p2alignw" | ".p2alignl" => {
                self.align_pattern(d, args, line, col)
            }
            ".reloc" => self.reloc_directive(args, line, col),
            // The paper's ISA extensions (`docs/extensions.md`), on from here.
            ".spu_ext" => {
                if let Err(m) = self.extensions.add(args.trim()) {
                    self.diag(Severity::Error, line, col, format!(".spu_ext: {m}"));
                }
            }
            ".extern" | ".file" | ".ident" | ".loc" | ".loc_mark_labels" | ".local" | ".brinfo"
            | ".end" | ".nolist" | ".list" | ".eject" | ".psize" | ".title" | ".sbttl"
            | ".version" | ".gnu_attribute" | ".lflags" => {}
            // spu-elf-as 2.40 has no CFI support and says so.
            c if c.starts_with(".cfi_") => self.diag(
                Severity::Error,
                line,
                col,
                "CFI is not supported for this target",
            ),
            ".align" | ".p2align" | ".balign" => {
                // `boundary[, [fill][, max]]`: an empty fill is the default, and the
                // alignment is skipped when it needs more than `max` bytes.
                let parts = split_top(args, ',');
                let mut vals = Vec::new();
                for (k, part) in parts.iter().enumerate() {
                    let t = part.trim();
                    if t.is_empty() && k > 0 {
                        vals.push(None);
                        continue;
                    }
                    vals.push(self.data_values(t, line, col).first().copied());
                }
                let max_skip = vals.get(2).copied().flatten();
                let v = vals.first().copied().flatten().unwrap_or(0);
                let boundary = if d == ".balign" {
                    v
                } else if v > 15 {
                    // GNU as: "alignment too large: 15 assumed".
                    self.diag(
                        Severity::Warning,
                        line,
                        col,
                        "alignment too large: 15 assumed",
                    );
                    1 << 15
                } else {
                    1i64 << v.max(0)
                };
                if boundary > 1 << 15 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("alignment too large: {boundary}"),
                    );
                    return;
                }
                if boundary <= 0 || boundary & (boundary - 1) != 0 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("alignment not a power of 2: {boundary}"),
                    );
                    return;
                }
                let fill = vals.get(1).copied().flatten().map(|f| f as u8);
                let here = self.here() as i64;
                let pad = (boundary - here % boundary) % boundary;
                if max_skip.is_some_and(|m| pad > m) {
                    return;
                }
                self.align_to(boundary as u32, fill);
            }
            ".byte" | ".short" | ".half" | ".hword" | ".2byte" | ".int" | ".long" | ".word"
            | ".4byte" | ".quad" | ".8byte" => {
                let size = match d {
                    ".byte" => 1,
                    ".short" | ".half" | ".hword" | ".2byte" => 2,
                    ".quad" | ".8byte" => 8,
                    _ => 4,
                };
                if args.trim().is_empty() {
                    return;
                }
                for part in split_top(args, ',') {
                    let (v, c) = match self.eval_val(part.trim()) {
                        Ok((v, _, _)) => (v, col),
                        Err((c, m)) => {
                            self.diag(Severity::Error, line, col + c, m);
                            (Val::abs(0), col)
                        }
                    };
                    if self.object && self.pass == 2 && (v.reloc || v.cross) {
                        // In an object an address is left to the linker: R_SPU_ADDR32 (or
                        // R_SPU_REL32 for `sym - .`); other sizes have no SPU relocation.
                        let at = self.offsets.get(&self.sect).copied().unwrap_or(0)
                            + self.bases.get(&self.sect).copied().unwrap_or(0);
                        if size != 4 {
                            self.diag(
                                Severity::Error,
                                line,
                                c,
                                format!("cannot represent a {size}-byte relocation for SPU"),
                            );
                        } else {
                            let sect = self.sect;
                            self.add_reloc(sect, at, crate::reloc::R_SPU_ADDR32, &v, line, c);
                        }
                        self.emit(&vec![0; size]);
                        continue;
                    }
                    let b = v.v.to_be_bytes();
                    self.emit(&b[8 - size..]);
                }
            }
            ".float" | ".single" | ".ffloat" | ".double" | ".dfloat" => {
                for part in split_top(args, ',') {
                    let t = part.trim();
                    let v: f64 = match t.parse::<f64>() {
                        Ok(v) => v,
                        Err(_) => match self.eval(t) {
                            Ok((v, _)) => v as f64,
                            Err((c, m)) => {
                                self.diag(Severity::Error, line, col + c, m);
                                0.0
                            }
                        },
                    };
                    if d.contains('d') {
                        self.emit(&v.to_be_bytes());
                    } else {
                        self.emit(&(v as f32).to_be_bytes());
                    }
                }
            }
            ".ascii" | ".asciz" | ".string" => {
                for part in split_top(args, ',') {
                    match unquote(part.trim()) {
                        Some(mut bytes) => {
                            if d != ".ascii" {
                                bytes.push(0);
                            }
                            self.emit(&bytes);
                        }
                        None => self.diag(Severity::Error, line, col, "expected a string"),
                    }
                }
            }
            ".space" | ".skip" | ".zero" => {
                let vals = self.data_values(args, line, col);
                let n = vals.first().copied().unwrap_or(0);
                if !(0..=LOCAL_STORE as i64 * 2).contains(&n) {
                    self.diag(Severity::Error, line, col, format!("bad .space size {n}"));
                    return;
                }
                let fill = vals.get(1).copied().unwrap_or(0) as u8;
                self.emit(&vec![fill; n as usize]);
            }
            ".fill" => {
                let vals = self.data_values(args, line, col);
                let (n, size, value) = (
                    vals.first().copied().unwrap_or(0),
                    vals.get(1).copied().unwrap_or(1).clamp(0, 8),
                    vals.get(2).copied().unwrap_or(0),
                );
                for _ in 0..n.clamp(0, LOCAL_STORE as i64 * 2) {
                    let b = value.to_be_bytes();
                    let s = size as usize;
                    let mut word = vec![0u8; s];
                    let k = s.min(4);
                    word[s - k..].copy_from_slice(&b[8 - k..]);
                    self.emit(&word);
                }
            }
            ".set" | ".equ" | ".eqv" | ".equiv" => {
                let parts = split_top(args, ',');
                if parts.len() < 2 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("{d} needs a name and a value"),
                    );
                    return;
                }
                let name = parts[0].trim().to_string();
                let expr = parts[1..].join(",");
                self.set_symbol(&name, expr.trim(), line);
            }
            ".include" => {
                let name = args.trim().trim_matches('"');
                match self.read_include(name) {
                    Some(text) => {
                        let lines = to_lines(&text, name);
                        self.run_lines(&lines);
                    }
                    None => self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("can't open {name} for reading"),
                    ),
                }
            }
            ".endm" | ".endr" | ".endsched" => self.diag(
                Severity::Error,
                line,
                col,
                format!("{d} without a matching start"),
            ),
            ".err" | ".error" => self.diag(
                Severity::Error,
                line,
                col,
                args.trim().trim_matches('"').to_string(),
            ),
            ".warning" => self.diag(
                Severity::Warning,
                line,
                col,
                args.trim().trim_matches('"').to_string(),
            ),
            _ => {
                if !self.elf_directive(d, args, line, col) {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unknown pseudo-op: `{d}`"),
                    )
                }
            }
        }
    }
}

/// Directives `directive` handles (block directives and conditionals are handled before).
const DIRECTIVES: &[&str] = &[
    ".2byte",
    ".4byte",
    ".8byte",
    ".quad",
    ".align",
    ".ascii",
    ".asciz",
    ".balign",
    ".balignl",
    ".balignw",
    ".bss",
    ".byte",
    ".comm",
    ".data",
    ".dfloat",
    ".double",
    ".equ",
    ".eqv",
    ".equiv",
    ".err",
    ".error",
    ".extern",
    ".ffloat",
    ".file",
    ".fill",
    ".float",
    ".global",
    ".globl",
    ".half",
    ".hidden",
    ".hword",
    ".ident",
    ".include",
    ".int",
    ".internal",
    ".lcomm",
    ".loc",
    ".loc_mark_labels",
    ".local",
    ".long",
    ".org",
    ".p2align",
    ".p2alignl",
    ".p2alignw",
    ".popsection",
    ".previous",
    ".protected",
    ".pushsection",
    ".reloc",
    ".rodata",
    ".section",
    ".set",
    ".short",
    ".single",
    ".size",
    ".skip",
    ".spu_ext",
    ".sleb128",
    ".space",
    ".string",
    ".subsection",
    ".text",
    ".type",
    ".uleb128",
    ".warning",
    ".weak",
    ".word",
    ".zero",
    ".brinfo",
    ".end",
    ".nolist",
    ".list",
    ".eject",
    ".psize",
    ".title",
    ".sbttl",
    ".version",
    ".gnu_attribute",
    ".lflags",
];

fn is_directive(name: &str) -> bool {
    DIRECTIVES.contains(&name)
        || name.starts_with(".cfi_")
        || matches!(
            name,
            ".macro"
                | ".endm"
                | ".rept"
                | ".endr"
                | ".irp"
                | ".irpc"
                | ".if"
                | ".ifdef"
                | ".ifndef"
                | ".ifeq"
                | ".ifne"
                | ".ifc"
                | ".ifnc"
                | ".elseif"
                | ".else"
                | ".endif"
                | ".exitm"
        )
}

/// LEB128 bytes of `v` (signed or unsigned), as `.sleb128`/`.uleb128` write them.
fn leb128(mut v: i64, signed: bool) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let byte = (v & 0x7f) as u8;
        v = if signed {
            v >> 7
        } else {
            ((v as u64) >> 7) as i64
        };
        let done = if signed {
            (v == 0 && byte & 0x40 == 0) || (v == -1 && byte & 0x40 != 0)
        } else {
            v == 0
        };
        if done {
            out.push(byte);
            return out;
        }
        out.push(byte | 0x80);
    }
}

/// The directive a line's first word names for block and conditional handling: itself
/// lower-cased, with the dot added when written without one (`rept`, `endr`, `if`), as gas
/// for SPU reads pseudo-ops, unless it is a macro or an instruction.
pub(super) fn block_word(word: &str, macros: &HashMap<String, Macro>) -> String {
    let lw = word.to_ascii_lowercase();
    if lw.starts_with('.') || macros.contains_key(&lw) || forms_named(&lw).next().is_some() {
        return lw;
    }
    let dotted = format!(".{lw}");
    if is_directive(&dotted) && lw != "set" {
        dotted
    } else {
        lw
    }
}
