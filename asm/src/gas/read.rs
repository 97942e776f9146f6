//! Statements and directives (gas's `read.c`): the walk over a list of lines with its
//! blocks (macros, repetitions, conditionals, `.sched`), a line's labels and statements,
//! and the directives that are not about sections or the target: data, alignment, `.org`,
//! `.set`, `.include`, `.reloc`, messages.

use super::macros::collect_block;
use super::symbols::{quoted_name, SymVal};
use super::{Assembler, Macro, Severity, LOCAL_STORE, MAX_EXPANDED, MAX_NESTING};
use crate::expr::{is_ident, Val};
use crate::lex::{bytes_as_text, read_source, split_top, strip_comment, to_lines, unquote, Line};
use spu_isa::table::forms_named;
use std::collections::HashMap;

impl Assembler<'_> {
    /// The text of an `.include`d file: an in-memory file, else the first found on the
    /// include path, else the name as given.
    fn read_include(&mut self, name: &str) -> Option<String> {
        if let Some((_, text)) = self.opts.virtual_files.iter().find(|(n, _)| n == name) {
            return Some(bytes_as_text(text.as_bytes()));
        }
        let named = std::path::PathBuf::from(name);
        let (path, text) = self
            .opts
            .include_dirs
            .iter()
            .map(|dir| dir.join(name))
            .chain(std::iter::once(named))
            .find_map(|path| Some((read_source(&path).ok()?, path)))
            .map(|(text, path)| (path, text))?;
        self.note_included(path);
        Some(text)
    }

    /// Records a file read from disk, once.
    fn note_included(&mut self, path: std::path::PathBuf) {
        if !self.included.contains(&path) {
            self.included.push(path);
        }
    }

    /// Processes a list of lines (one file, a macro body or a repetition).
    pub(super) fn run_lines(&mut self, lines: &[Line]) {
        if self.expanded > MAX_EXPANDED {
            return;
        }
        self.depth += 1;
        if self.depth > MAX_NESTING {
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
        while i < lines.len() && !self.ended {
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
            if self.nonzero_in_nobits {
                // write.c (subsegs) refuses it at the statement that stored it.
                self.nonzero_in_nobits = false;
                let name = self.defs[self.chunks[self.sect].0].name.clone();
                self.diag(
                    Severity::Error,
                    line,
                    1,
                    format!("attempt to store non-zero value in section `{name}'"),
                );
            }
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
                if let Some((name, after)) = quoted_name(&rest) {
                    // A quoted label (`"test-a":`), whatever bytes its name holds.
                    let Some(after) = after.trim_start().strip_prefix(':') else {
                        break;
                    };
                    let after = after.trim().to_string();
                    self.define_label(&name, line);
                    self.dwarf_label(line);
                    self.stmt += 1;
                    rest = after;
                    continue;
                }
                let name = rest[..colon].trim();
                if name.is_empty() || !name.chars().all(is_ident) || name.contains(' ') {
                    break;
                }
                self.define_label(name, line);
                self.dwarf_label(line);
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
            let mut lw = word.to_ascii_lowercase();
            if lw == ".nop" {
                // read.c s_nop assembles `nop` (on SPU that is the same s_nop again,
                // pseudo-ops being read without their dot): one path for both spellings.
                lw = "nop".into();
            }
            let col = line.text.find(&word).map(|c| c + 1).unwrap_or(1);
            let before = (
                self.sect,
                self.offsets.get(&self.sect).copied().unwrap_or(0),
            );
            let macro_named = self
                .macros
                .get(&lw)
                .filter(|_| !names_pseudo_op(&lw))
                .cloned();
            if let Some(m) = macro_named {
                self.expand_macro(&m, &args, line);
            } else if let Some(v) = args.strip_prefix("==") {
                // `NAME == EXPR` is `.eqv NAME, EXPR` (read.c, `==` after a name).
                self.directive(".eqv", &format!("{word},{v}"), line, col);
            } else if let Some(v) = args.strip_prefix('=') {
                let v = v.trim().to_string();
                if self.may_assign(&word, true, line, col) {
                    self.set_symbol(&word, &v, line);
                }
            } else if lw.starts_with('.') {
                self.directive(&lw, &args, line, col);
            } else if lw != "set"
                && forms_named(&lw).next().is_none()
                && is_directive(&format!(".{lw}"))
            {
                // A pseudo-op written without its dot (`GLOBL`), as gas's NO_PSEUDO_DOT
                // targets and MRI mode read it.
                self.directive(&format!(".{lw}"), &args, line, col);
            } else if let Some((name, value)) = word
                .split_once('=')
                .filter(|(n, _)| !n.is_empty() && !n.contains(|c: char| c.is_whitespace()))
            {
                // `name=value` written without spaces, as gas accepts it (`name==value`:
                // `.eqv`).
                let v = format!("{value}{}{args}", if args.is_empty() { "" } else { " " });
                if let Some(v) = v.strip_prefix('=') {
                    self.directive(".eqv", &format!("{name},{v}"), line, col);
                } else if self.may_assign(name, true, line, col) {
                    self.set_symbol(name, v.trim(), line);
                }
            } else {
                let at = (
                    self.sect,
                    self.offsets.get(&self.sect).copied().unwrap_or(0),
                );
                self.instruction(&lw, &args, line, col);
                self.dwarf_insn(at.0, at.1, line, col);
            }
            if std::mem::take(&mut self.nonzero_in_absolute) {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    "attempt to store non-zero value in section `*ABS*'",
                );
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

    /// read.c parse_one_float: one float of directive D, after an optional `0LETTER`
    /// (`0r1.5`, `0d-2e3`); `:HEX` gives its bytes from the first (`0f:1234` is
    /// 0x12340000, hex_float), the only form of the 12-byte `.dc.x` on SPU. None after an
    /// error or gas's warning that the hex is too long (which stores nothing).
    fn one_float(&mut self, d: &str, t: &str, line: &Line, col: usize) -> Option<Vec<u8>> {
        let length = float_length(d);
        let bare = match t.as_bytes() {
            [b'0', l, ..] if l.is_ascii_alphabetic() => &t[2..],
            _ => t,
        };
        if let Some(hex) = bare.strip_prefix(':') {
            let digits: Vec<u8> = hex
                .bytes()
                .filter(|&b| b != b'_')
                .map_while(|b| (b as char).to_digit(16).map(|v| v as u8))
                .collect();
            if digits.len() > 2 * length {
                let m = "floating point constant too large";
                self.diag(Severity::Warning, line, col, m);
                return None;
            }
            let mut bytes = vec![0u8; length];
            for (i, pair) in digits.chunks(2).enumerate() {
                bytes[i] = pair[0] << 4 | pair.get(1).copied().unwrap_or(0);
            }
            return Some(bytes);
        }
        let v: f64 = match bare.parse::<f64>() {
            Ok(v) if length < 12 => v,
            _ if length == 12 => {
                let m = "bad floating literal: Unrecognized or unsupported floating point \
                         constant";
                self.diag(Severity::Error, line, col, m);
                return None;
            }
            _ => match self.eval(t) {
                Ok((v, _)) => v as f64,
                Err((c, m)) => {
                    self.diag(Severity::Error, line, col + c, m);
                    0.0
                }
            },
        };
        Some(if length == 8 {
            v.to_be_bytes().to_vec()
        } else {
            (v as f32).to_be_bytes().to_vec()
        })
    }

    /// The comma-separated values of a directive's operands (0 for one in error).
    pub(super) fn data_values(&mut self, args: &str, line: &Line, col: usize) -> Vec<i64> {
        let mut out = Vec::new();
        if args.trim().is_empty() {
            return out;
        }
        for part in split_top(args, ',') {
            let col = operand_column(line, &part, col);
            match self.eval_reported(part.trim(), line, col) {
                Ok(v) => out.push(v.v),
                Err((c, m)) => {
                    self.diag(Severity::Error, line, col + c, m);
                    out.push(0);
                }
            }
        }
        out
    }

    /// `.incbin "FILE"[, SKIP[, COUNT]]` (read.c s_incbin): the file's bytes from SKIP,
    /// COUNT of them (all the rest by default); the file is looked for as named, then in
    /// the source's directory and each `-I` directory.
    fn incbin(&mut self, args: &str, line: &Line, col: usize) {
        let parts = split_top(args, ',');
        let Some(name) = parts.first().and_then(|p| unquote(p.trim())) else {
            self.diag(Severity::Error, line, col, "missing file name for .incbin");
            return;
        };
        let name: String = name.iter().map(|&b| b as char).collect();
        let mut numbers = Vec::new();
        for p in parts.iter().skip(1) {
            let c = operand_column(line, p, col);
            match self.eval_reported(p.trim(), line, c) {
                Ok(v) => numbers.push(v.v),
                Err((k, m)) => {
                    self.diag(Severity::Error, line, c + k, m);
                    return;
                }
            }
        }
        let Some((path, file_len)) = self.find_binary(&name) else {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("file not found: {name}"),
            );
            return;
        };
        let skip = numbers.first().copied().unwrap_or(0);
        let count = numbers.get(1).copied().unwrap_or(file_len as i64 - skip);
        if skip < 0 || count < 0 || skip.saturating_add(count) > file_len as i64 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("skip ({skip}) or count ({count}) invalid for file size ({file_len})"),
            );
            return;
        }
        if count > 2 * LOCAL_STORE as i64 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!(".incbin of {count} bytes is more than the local store holds"),
            );
            return;
        }
        if let Ok(p) = &path {
            self.note_included(p.clone());
        }
        let bytes = match &path {
            Ok(p) => {
                use std::io::{Read, Seek};
                let read = std::fs::File::open(p).and_then(|mut f| {
                    f.seek(std::io::SeekFrom::Start(skip as u64))?;
                    let mut buf = Vec::with_capacity(count as usize);
                    f.take(count as u64).read_to_end(&mut buf)?;
                    Ok(buf)
                });
                match read {
                    Ok(b) if b.len() == count as usize => b,
                    Ok(_) | Err(_) => {
                        self.diag(Severity::Error, line, col, format!("can't read {name}"));
                        return;
                    }
                }
            }
            Err(text) => text[skip as usize..(skip + count) as usize].to_vec(),
        };
        self.emit(&bytes);
    }

    /// A binary file for `.incbin`: a path on disk (or an in-memory file's bytes) and its
    /// length.
    #[allow(clippy::type_complexity)]
    fn find_binary(&self, name: &str) -> Option<(Result<std::path::PathBuf, Vec<u8>>, u64)> {
        if let Some((_, text)) = self.opts.virtual_files.iter().find(|(n, _)| n == name) {
            let bytes = text.as_bytes().to_vec();
            let len = bytes.len() as u64;
            return Some((Err(bytes), len));
        }
        let named = std::path::Path::new(name).to_path_buf();
        std::iter::once(named)
            .chain(self.opts.include_dirs.iter().map(|d| d.join(name)))
            .find_map(|p| {
                let meta = std::fs::metadata(&p).ok().filter(|m| m.is_file())?;
                Some((Ok(p), meta.len()))
            })
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
        // Names only, as spu-elf-as 2.40 takes them (a number is refused there too).
        let Some(kind) = crate::reloc::by_name(ty) else {
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
                Ok((mut v, _, _)) => {
                    // write.c leaves a `.reloc` against the symbol named, local or not
                    // (never its section's symbol), unless gas made the name (`.L`).
                    let name: String = e.trim().chars().take_while(|&c| is_ident(c)).collect();
                    if self.object && v.sym.is_none() && !name.starts_with(".L") {
                        if let Some(SymVal::Label(c, off)) = self.symbols.get(&name) {
                            let at = self.bases.get(c).copied().unwrap_or(0) + off;
                            v.sym = Some((name.as_str().into(), at as i64));
                        }
                    }
                    v
                }
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
        // Other names gas gives the same directives (tc-spu.c's `.def` is `.set`;
        // read.c's `.offset` is `.struct`, `.dc.*` are the data directives; obj-elf.c's
        // `.sect`, `.section.s` and `.common`).
        let d = match d {
            ".def" => ".set",
            ".offset" => ".struct",
            ".dc.b" => ".byte",
            ".dc" | ".dc.w" => ".short",
            ".dc.l" | ".dc.a" => ".long",
            ".dc.s" => ".float",
            ".dc.d" => ".double",
            ".sect" | ".sect.s" | ".section.s" => ".section",
            ".common" | ".common.s" => ".comm",
            other => other,
        };
        match d {
            ".weakref" => {
                // read.c s_weakref: `ALIAS, TARGET`. A use of the alias, before or after,
                // is a use of the target, which stays weak while nothing uses it itself.
                let Some((alias, target)) = args.split_once(',') else {
                    let m = format!("expected comma after \"{}\"", args.trim());
                    self.diag(Severity::Error, line, col, m);
                    return;
                };
                let (alias, target) = (alias.trim().to_string(), target.trim().to_string());
                if self.pass == 1 && self.symbols.contains_key(&alias) {
                    let m = format!("symbol `{alias}' is already defined");
                    self.diag(Severity::Error, line, col, m);
                    return;
                }
                // The aliases the target leads through, refused if they lead back.
                let mut path = vec![alias.clone(), target.clone()];
                while let Some(next) = self.weakrefs.get(&path[path.len() - 1]) {
                    if path.len() > self.weakrefs.len() + 1 || *next == alias {
                        path.push(next.clone());
                        break;
                    }
                    path.push(next.clone());
                }
                if path[1..].contains(&alias) {
                    let m = format!("{alias}: would close weakref loop: {}", path.join(" => "));
                    self.diag(Severity::Error, line, col, m);
                    return;
                }
                self.weakrefs.insert(alias.clone(), target);
                if let Some(t) = self.weakref_target(&alias) {
                    self.note_symbol(&t);
                }
            }
            ".ds" | ".ds.b" | ".ds.w" | ".ds.l" | ".ds.d" | ".ds.s" | ".ds.p" | ".ds.x" => {
                // read.c s_space with a unit: `.ds.l 3` is 12 zero bytes.
                let unit: i64 = match d {
                    ".ds.b" => 1,
                    ".ds" | ".ds.w" => 2,
                    ".ds.d" => 8,
                    ".ds.p" | ".ds.x" => 12,
                    _ => 4,
                };
                let vals = self.data_values(args, line, col);
                let n = vals.first().copied().unwrap_or(0).saturating_mul(unit);
                if !(0..=LOCAL_STORE as i64 * 2).contains(&n) {
                    self.diag(Severity::Error, line, col, format!("bad {d} size {n}"));
                    return;
                }
                let fill = vals.get(1).copied().unwrap_or(0);
                let mut bytes = Vec::with_capacity(n as usize);
                for _ in 0..n / unit {
                    // A unit wider than 8 bytes (`.ds.x`, `.ds.p`) takes the fill
                    // sign-extended, as emit_expr writes a constant.
                    let sign = if fill < 0 { 0xff } else { 0 };
                    bytes.resize(bytes.len() + (unit - unit.min(8)) as usize, sign);
                    bytes.extend_from_slice(&fill.to_be_bytes()[8 - unit.min(8) as usize..]);
                }
                self.emit(&bytes);
            }
            ".dcb" | ".dcb.b" | ".dcb.w" | ".dcb.l" => {
                // `.dcb.w N, V`: N copies of V, each of the unit's size.
                let unit = match d {
                    ".dcb.b" => 1,
                    ".dcb.l" => 4,
                    _ => 2,
                };
                let vals = self.data_values(args, line, col);
                let n = vals.first().copied().unwrap_or(0);
                if !(0..=LOCAL_STORE as i64 * 2 / unit as i64).contains(&n) {
                    self.diag(Severity::Error, line, col, format!("bad {d} count {n}"));
                    return;
                }
                let v = vals.get(1).copied().unwrap_or(0);
                self.truncation_warning(v, unit, line, col);
                let word = &v.to_be_bytes()[8 - unit..];
                let bytes: Vec<u8> = (0..n).flat_map(|_| word.iter().copied()).collect();
                self.emit(&bytes);
            }
            ".octa" => {
                // 16 bytes, big-endian, the value sign-extended.
                for v in self.data_values(args, line, col) {
                    let fill = if v < 0 { [0xff; 8] } else { [0; 8] };
                    self.emit(&fill);
                    self.emit(&v.to_be_bytes());
                }
            }
            // write.c without md_generate_nops (only x86 has one): gas 2.40 for SPU
            // refuses `.nops` when it writes the frag.
            ".nops" => self.diag(Severity::Error, line, col, "unimplemented .nops directive"),
            ".abort" => self.diag(
                Severity::Error,
                line,
                col,
                ".abort detected.  Abandoning ship.",
            ),
            ".fail" => {
                // read.c s_fail: a warning from 500 up, an error below.
                let v = self
                    .data_values(args, line, col)
                    .first()
                    .copied()
                    .unwrap_or(0);
                let sev = if v >= 500 {
                    Severity::Warning
                } else {
                    Severity::Error
                };
                self.diag(sev, line, col, format!(".fail {v} encountered"));
            }
            ".ident" => self.ident(args, line, col),
            ".altmacro" => self.altmacro = true,
            ".noaltmacro" => self.altmacro = false,
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
            ".purgem" => self.purge_macro(args, line, col),
            ".struct" => {
                // read.c s_struct: into the absolute section at the offset given.
                let off = self
                    .data_values(args, line, col)
                    .first()
                    .copied()
                    .unwrap_or(0);
                if !(0..=2 * LOCAL_STORE as i64).contains(&off) {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("bad .struct offset {off}"),
                    );
                    return;
                }
                self.absolute = Some(off as u32);
            }
            ".incbin" => self.incbin(args, line, col),
            ".popsection" | ".previous" if self.absolute.is_some() => {
                self.absolute = None;
                // s_struct calls obj_elf_section_change_hook: the previous section is
                // the one `.struct` was entered from, where `.previous` returns.
                if d == ".popsection" {
                    self.elf_directive(d, args, line, col);
                }
            }
            // `.file "name"` alone is the ELF file symbol; anything else is `.file N`.
            ".file" if !args.trim_start().starts_with('"') => self.dwarf_file(args, line, col),
            ".loc" => self.dwarf_loc(args, line, col),
            ".loc_mark_labels" => self.dwarf_mark_labels(args, line, col),
            ".file" => {
                if let Some(name) = crate::lex::unquote(args.trim()) {
                    if self.pass == 2 {
                        let name: String = name.iter().map(|&b| b as char).collect();
                        self.chain.borrow_mut().file(&name);
                    }
                }
            }
            ".local" => {
                // obj-elf.c obj_elf_local makes each symbol (an undefined one stays global).
                for n in split_top(args, ',') {
                    self.note_symbol(n.trim());
                }
            }
            // read.c s_print writes its string to standard output: here, nothing.
            ".print" => {}
            // read.c s_end: nothing after it is read.
            ".end" => self.ended = true,
            // listing.c listing_psize: the page's lines, then (after a comma) its width.
            ".psize" => {
                let parts = split_top(args, ',');
                if let Some(lines) = parts.first().filter(|p| !p.trim().is_empty()) {
                    if !matches!(self.eval_val(lines), Ok((v, false, _)) if !v.reloc) {
                        self.diag(
                            Severity::Error,
                            line,
                            col,
                            "bad or irreducible absolute expression",
                        );
                    }
                }
                if let Some(width) = parts.get(1) {
                    match self.eval_val(width) {
                        Ok((v, false, _)) if !v.reloc && v.v <= 7 => {
                            self.diag(Severity::Error, line, col, "new paper width is too small")
                        }
                        Ok((v, false, _)) if !v.reloc => {}
                        _ => self.diag(
                            Severity::Error,
                            line,
                            col,
                            "bad or irreducible absolute expression",
                        ),
                    }
                }
            }
            ".extern" | ".brinfo" | ".nolist" | ".list" | ".eject" | ".title" | ".sbttl"
            | ".version" | ".gnu_attribute" | ".lflags" => {}
            // read.c's s_ignore entries (COFF debugging and MRI listing control), and
            // `.func`/`.endfunc`, which emit nothing without stabs debugging.
            ".debug" | ".dim" | ".endef" | ".scl" | ".tag" | ".val" | ".ln" | ".func"
            | ".endfunc" | ".page" | ".plen" | ".spc" | ".ttl" | ".nopage" | ".noformat"
            | ".format" | ".name" => {}
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
                } else if v > 31 {
                    // read.c s_align: past the address size, with a warning.
                    self.diag(
                        Severity::Warning,
                        line,
                        col,
                        "alignment too large: 31 assumed",
                    );
                    1 << 31
                } else {
                    1i64 << v.max(0)
                };
                if boundary > LOCAL_STORE as i64 {
                    // GNU as pads that far; nothing so aligned fits the local store.
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("alignment too large: {boundary}"),
                    );
                    return;
                }
                if boundary == 0 {
                    return; // `.balign 0`: no alignment, as in gas
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
                    // Skipped, but the section is aligned still (gas's record_alignment).
                    if self.absolute.is_none() {
                        let a = self.align.entry(self.sect).or_insert(1);
                        *a = (*a).max(boundary as u32);
                    }
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
                    let col = operand_column(line, &part, col);
                    let (v, c) = match self.eval_reported(part.trim(), line, col) {
                        Ok(v) => (v, col),
                        Err((c, m)) => {
                            self.diag(Severity::Error, line, col + c, m);
                            (Val::abs(0), col)
                        }
                    };
                    // An equate not yet defined here: gas leaves a fixup, and write.c's
                    // fixup_segment refuses a value the field cannot hold.
                    let fixup = !self.forward_refs.borrow().is_empty();
                    if fixup && !v.reloc && !v.cross && size < 8 {
                        let mask = !0u64 << (8 * size);
                        let (high, negated_high) =
                            (v.v as u64 & mask, (v.v as u64).wrapping_neg() & mask);
                        if high != 0 && negated_high != 0 {
                            let at = self.offsets.get(&self.sect).copied().unwrap_or(0);
                            let value = if v.v as u64 > 1000 {
                                format!("{:08x}", v.v as u32)
                            } else {
                                v.v.to_string()
                            };
                            let s = if size == 1 { "" } else { "s" };
                            self.diag(
                                Severity::Error,
                                line,
                                c,
                                format!("value of {value} too large for field of {size} byte{s} at {at:08x}"),
                            );
                        }
                        let b = v.v.to_be_bytes();
                        self.emit(&b[8 - size..]);
                        continue;
                    }
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
                    self.truncation_warning(v.v, size, line, c);
                    let b = v.v.to_be_bytes();
                    self.emit(&b[8 - size..]);
                }
            }
            ".float" | ".single" | ".ffloat" | ".double" | ".dfloat" | ".dc.x" => {
                for part in split_top(args, ',') {
                    if let Some(bytes) = self.one_float(d, part.trim(), line, col) {
                        self.emit(&bytes);
                    }
                }
            }
            ".dcb.s" | ".dcb.d" | ".dcb.x" => {
                // read.c s_float_space: `COUNT[, FLOAT]`, the float zero when not given.
                let (count, value) = match args.split_once(',') {
                    Some((n, v)) => (n, Some(v.trim())),
                    None => (args, None),
                };
                let count = match self.eval(count.trim()) {
                    Ok((n, _)) => n,
                    Err((c, m)) => {
                        self.diag(Severity::Error, line, col + c, m);
                        return;
                    }
                };
                let one = match value {
                    Some(v) => self.one_float(d, v, line, col),
                    None => Some(vec![0; float_length(d)]),
                };
                if let Some(one) = one {
                    for _ in 0..count.clamp(0, LOCAL_STORE as i64) {
                        self.emit(&one);
                    }
                }
            }
            ".ascii" | ".asciz" | ".string" | ".string8" | ".string16" | ".string32"
            | ".string64" => {
                // read.c stringer: each character a unit of 1, 2, 4 or 8 bytes (big-endian).
                let unit = d
                    .strip_prefix(".string")
                    .and_then(|bits| bits.parse::<usize>().ok())
                    .map_or(1, |bits| bits / 8);
                for part in split_top(args, ',') {
                    match adjacent_strings(part.trim()) {
                        Some(mut bytes) => {
                            if d != ".ascii" {
                                bytes.push(0);
                            }
                            let units: Vec<u8> = bytes
                                .iter()
                                .flat_map(|&b| {
                                    let mut u = vec![0u8; unit];
                                    u[unit - 1] = b;
                                    u
                                })
                                .collect();
                            self.emit(&units);
                        }
                        None => self.diag(Severity::Error, line, col, "expected a string"),
                    }
                }
            }
            ".space" | ".skip" | ".zero" => {
                let vals = self.data_values(args, line, col);
                let n = vals.first().copied().unwrap_or(0);
                // read.c s_space: a count of zero or below is ignored with a warning.
                if n <= 0 {
                    let m = if n == 0 {
                        ".space repeat count is zero, ignored"
                    } else {
                        ".space repeat count is negative, ignored"
                    };
                    self.diag(Severity::Warning, line, col, m);
                    return;
                }
                if n > LOCAL_STORE as i64 * 2 {
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
                    vals.get(1).copied().unwrap_or(1),
                    vals.get(2).copied().unwrap_or(0),
                );
                // read.c s_fill's leniencies: ignored or clamped, with a warning.
                if n < 0 {
                    self.diag(Severity::Warning, line, col, "repeat < 0; .fill ignored");
                    return;
                }
                if size < 0 {
                    self.diag(Severity::Warning, line, col, "size negative; .fill ignored");
                    return;
                }
                if size > 8 && n > 0 {
                    self.diag(Severity::Warning, line, col, ".fill size clamped to 8");
                }
                let size = size.min(8);
                for _ in 0..n.clamp(0, LOCAL_STORE as i64 * 2) {
                    let b = value.to_be_bytes();
                    let s = size as usize;
                    let mut word = vec![0u8; s];
                    // md_number_to_chars of at most 4 bytes at the start; zeros after.
                    let k = s.min(4);
                    word[..k].copy_from_slice(&b[8 - k..]);
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
                let volatile = d == ".set" || d == ".equ";
                let name_col = line.text.find(&name).map_or(col, |c| c + 1);
                if !self.may_assign(&name, volatile, line, name_col) {
                    return;
                }
                if d == ".eqv" && mentions_dot(&expr) && self.absolute.is_none() {
                    self.dot_eqv.insert(name.clone(), expr.trim().to_string());
                } else {
                    self.dot_eqv.remove(&name);
                }
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
            ".err" => self.diag(Severity::Error, line, col, ".err encountered"),
            ".error" | ".warning" => {
                // read.c s_errwarn: a string, or nothing for gas's own words.
                let severity = if d == ".error" {
                    Severity::Error
                } else {
                    Severity::Warning
                };
                let text = args.trim();
                let message = if text.is_empty() {
                    format!("{d} directive invoked in source file")
                } else if let Some(bytes) = text
                    .starts_with('"')
                    .then(|| adjacent_strings(text))
                    .flatten()
                {
                    String::from_utf8_lossy(&bytes).into_owned()
                } else {
                    let m = format!("{d} argument must be a string");
                    self.diag(Severity::Error, line, col, m);
                    return;
                };
                self.diag(severity, line, col, message);
            }
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
    ".symver",
    ".altmacro",
    ".noaltmacro",
    ".def",
    ".offset",
    ".dc",
    ".dc.a",
    ".dc.b",
    ".dc.d",
    ".dc.l",
    ".dc.s",
    ".dc.w",
    ".dcb",
    ".dcb.b",
    ".dcb.l",
    ".dcb.w",
    ".ds",
    ".ds.b",
    ".ds.d",
    ".ds.l",
    ".ds.p",
    ".ds.s",
    ".ds.w",
    ".sect",
    ".sect.s",
    ".section.s",
    ".common",
    ".common.s",
    ".octa",
    ".nops",
    ".abort",
    ".fail",
    ".debug",
    ".dim",
    ".endef",
    ".scl",
    ".tag",
    ".val",
    ".ln",
    ".func",
    ".endfunc",
    ".page",
    ".plen",
    ".spc",
    ".ttl",
    ".nopage",
    ".noformat",
    ".format",
    ".name",
    ".2byte",
    ".4byte",
    ".8byte",
    ".quad",
    ".align",
    ".ascii",
    ".asciz",
    ".nop",
    ".string8",
    ".string16",
    ".string32",
    ".string64",
    ".balign",
    ".balignl",
    ".balignw",
    ".bss",
    ".byte",
    ".comm",
    ".tls_common",
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
    ".purgem",
    ".struct",
    ".incbin",
    ".previous",
    ".protected",
    ".pushsection",
    ".reloc",
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
    ".weakref",
    ".dc.x",
    ".dcb.s",
    ".dcb.d",
    ".dcb.x",
    ".ds.x",
    ".word",
    ".zero",
    ".brinfo",
    ".end",
    ".print",
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

/// The bytes of one float of a float directive (`.dc.x`'s are 12, `d`'s 8, the rest 4).
fn float_length(d: &str) -> usize {
    match d {
        ".dc.x" | ".dcb.x" => 12,
        ".double" | ".dfloat" | ".dcb.d" => 8,
        _ => 4,
    }
}

/// Whether a statement's first word names a pseudo-op, with its dot or without (tc-spu.h's
/// `NO_PSEUDO_DOT`): read.c reads it as the pseudo-op before looking for a macro.
pub(super) fn names_pseudo_op(word: &str) -> bool {
    let lw = word.to_ascii_lowercase();
    match lw.strip_prefix('.') {
        Some(_) => is_directive(&lw),
        None => lw != "set" && forms_named(&lw).next().is_none() && is_directive(&format!(".{lw}")),
    }
}

fn is_directive(name: &str) -> bool {
    DIRECTIVES.contains(&name)
        || super::cond::CONDITIONALS.contains(&name)
        || name.starts_with(".cfi_")
        || matches!(
            name,
            ".macro"
                | ".endm"
                | ".rept"
                | ".endr"
                | ".irp"
                | ".irpc"
                | ".elseif"
                | ".else"
                | ".endif"
                | ".endc"
                | ".exitm"
        )
}

/// The column of operand `part` in `line` (1-based; `fallback` when it is not found as
/// written, as after macro substitution).
pub(super) fn operand_column(line: &Line, part: &str, fallback: usize) -> usize {
    let p = part.trim();
    if p.is_empty() {
        return fallback;
    }
    line.text
        .get(fallback.saturating_sub(1)..)
        .and_then(|t| t.find(p))
        .map_or(fallback, |c| c + fallback)
}

/// LEB128 bytes of `v` (signed or unsigned), as `.sleb128`/`.uleb128` write them.
pub(super) fn leb128(mut v: i64, signed: bool) -> Vec<u8> {
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
    // read.c's other spellings of the block directives.
    let lw = match lw.as_str() {
        ".irep" => ".irp".to_string(),
        ".irepc" => ".irpc".to_string(),
        ".rep" => ".rept".to_string(),
        ".mexit" => ".exitm".to_string(),
        _ => lw,
    };
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

/// A string operand of `.ascii` and its kin: one or more quoted strings side by side
/// (`"a" "b"`), joined as read.c's stringer joins them.
fn adjacent_strings(text: &str) -> Option<Vec<u8>> {
    let mut out = Vec::new();
    let mut rest = text.trim_start();
    if rest.is_empty() {
        return None;
    }
    while !rest.is_empty() {
        let body = rest.strip_prefix('"')?;
        let mut end = None;
        let mut escaped = false;
        for (k, c) in body.char_indices() {
            match c {
                _ if escaped => escaped = false,
                '\\' => escaped = true,
                '"' => {
                    end = Some(k);
                    break;
                }
                _ => {}
            }
        }
        let end = end?;
        out.extend(unquote(&rest[..end + 2])?);
        rest = body[end + 1..].trim_start();
    }
    Some(out)
}

/// Whether an expression names the location counter `.` (not a `.`-led symbol such as
/// `.L1`, nor a `.` inside a name).
fn mentions_dot(expr: &str) -> bool {
    let b = expr.as_bytes();
    let name_byte = |c: u8| c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || c == b'$';
    (0..b.len()).any(|k| {
        b[k] == b'.'
            && (k == 0 || !name_byte(b[k - 1]))
            && b.get(k + 1).is_none_or(|&c| !name_byte(c))
    })
}
