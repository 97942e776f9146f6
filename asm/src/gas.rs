//! A GNU-as compatible assembler for SPU: the statement processor (labels, directives,
//! macros and repetition), expressions, operand parsing with GNU as's range checks, and
//! the two passes that lay sections out and encode through the shared instruction table.
//!
//! Pass 1 walks the source to give every label an address (every instruction is 4 bytes,
//! so only data directives need values then); pass 2 walks it again with all symbols known
//! and emits bytes. Both passes run the same expansion of `.include`, `.macro`, `.irp`,
//! `.rept` and `.if`, so they see the same statements.

use spu_isa::table::{forms_named, FormInfo, Format, OperandKind};
use std::collections::HashMap;
use std::path::PathBuf;

/// Where a diagnostic points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: String,
    pub line: usize,
    pub column: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// An error or warning with its source line, shown GNU-style with a caret.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    pub location: Location,
    pub message: String,
    pub source_line: String,
}

impl std::fmt::Display for Diagnostic {
    /// Rendered by codespan-reporting: the message, `file:line:column`, the line and a caret.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use codespan_reporting::diagnostic as cd;
        use codespan_reporting::files::SimpleFile;
        use codespan_reporting::term;
        let l = &self.location;
        let plain = |f: &mut std::fmt::Formatter<'_>| {
            let kind = if self.severity == Severity::Error {
                "error"
            } else {
                "warning"
            };
            write!(
                f,
                "{}:{}:{}: {kind}: {}",
                l.file, l.line, l.column, self.message
            )
        };
        if l.line == 0 {
            return plain(f);
        }
        // A file whose line `l.line` is the source line, so the report shows the real number.
        let prefix = "\n".repeat(l.line - 1);
        let text = format!("{prefix}{}\n", self.source_line);
        let start = prefix.len() + l.column.saturating_sub(1).min(self.source_line.len());
        let end = (start + 1)
            .min(prefix.len() + self.source_line.len())
            .max(start);
        let file = SimpleFile::new(l.file.clone(), text);
        let diagnostic = match self.severity {
            Severity::Error => cd::Diagnostic::error(),
            Severity::Warning => cd::Diagnostic::warning(),
        }
        .with_message(self.message.clone())
        .with_labels(vec![cd::Label::primary((), start..end)]);
        let config = term::Config {
            chars: term::Chars::ascii(),
            ..Default::default()
        };
        match term::emit_into_string(&config, &file, &diagnostic) {
            Ok(text) => write!(f, "{}", text.trim_end()),
            Err(_) => plain(f),
        }
    }
}

/// Assembler settings.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub include_dirs: Vec<PathBuf>,
    /// In-memory files for `.include` (name, contents), tried before the directories.
    pub virtual_files: Vec<(String, String)>,
    /// Symbols defined before the source (like `--defsym`).
    pub defines: Vec<(String, i64)>,
}

/// The assembled program.
#[derive(Clone, Debug, Default)]
pub struct Output {
    /// Local-store image loaded at address 0: `.text`, then `.data`, then `.bss` (zeros).
    pub image: Vec<u8>,
    /// An SPU ELF executable of the same program.
    pub elf: Vec<u8>,
    /// Global and local symbols (not `.L` locals) with their addresses.
    pub symbols: Vec<(String, u32)>,
    pub entry: u32,
    /// Address, words and source line of every statement that emitted bytes.
    pub listing: String,
    pub warnings: Vec<Diagnostic>,
    /// Section extents: (name, address, size, is code).
    pub sections: Vec<(String, u32, u32, bool)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Sect {
    Text,
    Data,
    Bss,
}

#[derive(Clone, Debug)]
struct Line {
    text: String,
    file: String,
    line: usize,
}

#[derive(Clone, Debug)]
struct Macro {
    params: Vec<(String, Option<String>)>,
    body: Vec<Line>,
}

#[derive(Clone, Copy, Debug)]
enum SymVal {
    /// A value from `.set`/`=`, and whether it is an address.
    Abs(i64, bool),
    Label(Sect, u32),
}

struct Assembler<'o> {
    opts: &'o Options,
    pass: u8,
    sect: Sect,
    offsets: HashMap<Sect, u32>,
    align: HashMap<Sect, u32>,
    bases: HashMap<Sect, u32>,
    symbols: HashMap<String, SymVal>,
    /// The symbols as pass 1 left them (for forward references in pass 2).
    pass1_symbols: HashMap<String, SymVal>,
    globals: Vec<String>,
    /// Numeric local label definitions: label -> list of (statement number, section, offset).
    numeric: HashMap<u32, Vec<(usize, Sect, u32)>>,
    stmt: usize,
    bytes: HashMap<Sect, Vec<u8>>,
    diags: Vec<Diagnostic>,
    macros: HashMap<String, Macro>,
    macro_counter: usize,
    listing: String,
    depth: usize,
    /// Macro expansions under way, and whether `.exitm` asked the innermost one to stop.
    macro_depth: usize,
    exitm: bool,
}

use crate::expr::{is_ident, Env, Eval, Val};

/// Removes comments: `#` to end of line (outside strings) and `/* */` (single line).
fn strip_comment(s: &str) -> String {
    let mut out = String::new();
    let mut chars = s.chars().peekable();
    let mut in_str = false;
    while let Some(c) = chars.next() {
        if in_str {
            out.push(c);
            if c == '\\' {
                if let Some(n) = chars.next() {
                    out.push(n);
                }
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => {
                in_str = true;
                out.push(c);
            }
            '#' => break,
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                let mut prev = ' ';
                for d in chars.by_ref() {
                    if prev == '*' && d == '/' {
                        break;
                    }
                    prev = d;
                }
                out.push(' ');
            }
            _ => out.push(c),
        }
    }
    out
}

/// Splits on `sep` at nesting depth 0 (parentheses) outside strings.
fn split_top(s: &str, sep: char) -> Vec<String> {
    let mut parts = Vec::new();
    let mut depth = 0i32;
    let mut cur = String::new();
    let mut in_str = false;
    for c in s.chars() {
        if in_str {
            cur.push(c);
            if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => {
                in_str = true;
                cur.push(c)
            }
            '(' => {
                depth += 1;
                cur.push(c)
            }
            ')' => {
                depth -= 1;
                cur.push(c)
            }
            c if c == sep && depth == 0 => parts.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    parts.push(cur);
    parts
}

const CHANNELS: &[(&str, u32)] = &[
    ("SPU_RdEventStat", 0),
    ("SPU_WrEventMask", 1),
    ("SPU_WrEventAck", 2),
    ("SPU_RdSigNotify1", 3),
    ("SPU_RdSigNotify2", 4),
    ("SPU_WrDec", 7),
    ("SPU_RdDec", 8),
    ("MFC_WrMSSyncReq", 9),
    ("SPU_RdEventMask", 11),
    ("MFC_RdTagMask", 12),
    ("SPU_RdMachStat", 13),
    ("SPU_WrSRR0", 14),
    ("SPU_RdSRR0", 15),
    ("MFC_LSA", 16),
    ("MFC_EAH", 17),
    ("MFC_EAL", 18),
    ("MFC_Size", 19),
    ("MFC_TagID", 20),
    ("MFC_Cmd", 21),
    ("MFC_WrTagMask", 22),
    ("MFC_WrTagUpdate", 23),
    ("MFC_RdTagStat", 24),
    ("MFC_RdListStallStat", 25),
    ("MFC_WrListStallAck", 26),
    ("MFC_RdAtomicStat", 27),
    ("SPU_WrOutMbox", 28),
    ("SPU_RdInMbox", 29),
    ("SPU_WrOutIntrMbox", 30),
];

type Res<T> = Result<T, (usize, String)>;

/// Bytes of SPU local store: the most a program can occupy.
const LOCAL_STORE: usize = 256 * 1024;

/// gas `arg_encode`: field size, position and right shift of an immediate kind, its
/// error range `lo..=hi` and warning range `wlo..=whi` (checked only when hi > lo).
struct ArgEncode {
    size: u32,
    pos: u32,
    rshift: u32,
    lo: i64,
    hi: i64,
    wlo: i64,
    whi: i64,
}

fn arg_encode(kind: OperandKind) -> ArgEncode {
    use OperandKind::*;
    let e = |size, pos, rshift, lo, hi, wlo, whi| ArgEncode {
        size,
        pos,
        rshift,
        lo,
        hi,
        wlo,
        whi,
    };
    match kind {
        S3 | S7n | U3 | U7 => e(7, 14, 0, 0, -1, 0, -1),
        S6 => e(7, 14, 0, -32, 31, -31, 0),
        S7 => e(7, 14, 0, -64, 63, -63, 0),
        U5 => e(7, 14, 0, 0, 127, 0, 31),
        U6 => e(7, 14, 0, 0, 127, 0, 63),
        Scale173 | Scale155 => e(8, 14, 0, 0, 127, 0, -1),
        S10b => e(10, 14, 0, -512, 511, -128, 255),
        S10 => e(10, 14, 0, -512, 511, 0, -1),
        BrInst => e(2, 23, 9, -1024, 1023, 0, -1),
        Off14 => e(10, 14, 4, -8192, 8191, 0, -1),
        S16 => e(16, 7, 0, -32768, 32767, 0, -1),
        Abs18 => e(16, 7, 2, -131072, 262143, 0, -1),
        Rel18 => e(16, 7, 2, -262144, 262143, 0, -1),
        U14 => e(14, 0, 0, 0, 16383, 0, -1),
        X16 => e(16, 7, 0, -32768, 65535, 0, -1),
        U18 => e(18, 7, 0, 0, 262143, 0, -1),
        _ => e(7, 0, 0, 0, -1, 0, -1),
    }
}

/// One parsed operand of an instruction.
enum Operand {
    Reg(OperandKind, i64),
    Imm {
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        col: usize,
        warnings: Vec<String>,
    },
}

enum CalcErr {
    /// The operands do not have this form's shape (0-based operand index).
    Syntax(usize),
    Hard(usize, String),
}

/// gas `insn_fmt_string`: `lqd\treg,imm(reg)` with the failing operand in capitals.
fn insn_fmt_string(form: &FormInfo, failing: usize) -> String {
    let mut s = format!("{}\t", form.mnemonic);
    for (i, k) in form.operands.iter().enumerate() {
        let word = if k.is_register() { "reg" } else { "imm" };
        let word = if i == failing {
            word.to_ascii_uppercase()
        } else {
            word.to_string()
        };
        if *k == OperandKind::ParenRa {
            s.push_str(&format!("({word})"));
        } else {
            if i > 0 {
                s.push(',');
            }
            s.push_str(&word);
        }
    }
    s
}

impl Env for Assembler<'_> {
    fn symbol(&self, name: &str) -> Option<Val> {
        if !self.symbols.contains_key(name) && self.pass == 2 {
            // A `.set`/`.equ` symbol used before its definition: its final value.
            let reloc = matches!(self.pass1_symbols.get(name), Some(SymVal::Abs(_, true)));
            return self.pass1_value(name).map(|v| Val { v, reloc });
        }
        let reloc = match self.symbols.get(name)? {
            SymVal::Abs(_, r) => *r,
            SymVal::Label(..) => true,
        };
        Some(Val {
            v: Assembler::symbol(self, name)?,
            reloc,
        })
    }
    fn dot(&self) -> i64 {
        self.here() as i64
    }
    fn local(&self, n: u32, forward: bool) -> Option<i64> {
        self.numeric_ref(n, forward)
    }
    fn lenient(&self) -> bool {
        self.pass == 1
    }
}

impl<'o> Assembler<'o> {
    /// gas pads the end of each section to the largest alignment requested in it
    /// (`SUB_SEGMENT_ALIGN` with `HANDLE_ALIGN`): code with nop/lnop, data with zeros.
    fn finish_sections(&mut self) {
        let current = self.sect;
        for s in [Sect::Text, Sect::Data, Sect::Bss] {
            let boundary = self.align.get(&s).copied().unwrap_or(1);
            if boundary > 1 {
                self.sect = s;
                self.align_to(boundary, None);
            }
        }
        self.sect = current;
    }

    fn here(&self) -> u32 {
        self.bases.get(&self.sect).copied().unwrap_or(0)
            + self.offsets.get(&self.sect).copied().unwrap_or(0)
    }

    fn symbol(&self, name: &str) -> Option<i64> {
        match self.symbols.get(name)? {
            SymVal::Abs(v, _) => Some(*v),
            SymVal::Label(s, off) => Some((self.bases.get(s).copied().unwrap_or(0) + off) as i64),
        }
    }

    /// The value a symbol had at the end of pass 1: what a forward reference to a symbol
    /// defined later by `.set`/`.equ` resolves to in pass 2.
    fn pass1_value(&self, name: &str) -> Option<i64> {
        match self.pass1_symbols.get(name)? {
            SymVal::Abs(v, _) => Some(*v),
            SymVal::Label(..) => None,
        }
    }

    fn numeric_ref(&self, n: u32, forward: bool) -> Option<i64> {
        let defs = self.numeric.get(&n)?;
        let pick = if forward {
            defs.iter().find(|d| d.0 > self.stmt)
        } else {
            defs.iter().rev().find(|d| d.0 < self.stmt)
        }?;
        Some((self.bases.get(&pick.1).copied().unwrap_or(0) + pick.2) as i64)
    }

    /// Evaluates a whole expression: its value (and whether it is an address) and any
    /// warnings (division by zero, shift counts).
    fn eval_val(&self, text: &str) -> Res<(Val, bool, Vec<String>)> {
        let (val, rest, undefined, warnings) = self.eval_prefix(text)?;
        let used = text.len() - rest.len();
        if !rest.trim().is_empty() {
            return Err((
                used,
                format!("junk at end of expression: `{}`", rest.trim()),
            ));
        }
        Ok((val, undefined, warnings))
    }

    /// Evaluates the expression at the start of `text`, returning the rest as gas's
    /// `expression()` leaves it.
    fn eval_prefix<'t>(&self, text: &'t str) -> Res<(Val, &'t str, bool, Vec<String>)> {
        let lead = text.len() - text.trim_start().len();
        let Some((ast, rest)) = crate::expr::parse(text) else {
            return Err((lead, "expected an expression".into()));
        };
        let mut e = Eval {
            env: self,
            warnings: Vec::new(),
            undefined: false,
        };
        let v = e.eval(&ast)?;
        Ok((v, rest, e.undefined, e.warnings))
    }

    fn eval(&self, text: &str) -> Res<(i64, bool)> {
        self.eval_val(text).map(|(v, u, _)| (v.v, u))
    }

    fn diag(&mut self, sev: Severity, line: &Line, column: usize, message: impl Into<String>) {
        if self.pass == 2 || sev == Severity::Error {
            let d = Diagnostic {
                severity: sev,
                location: Location {
                    file: line.file.clone(),
                    line: line.line,
                    column: column.max(1),
                },
                message: message.into(),
                source_line: line.text.clone(),
            };
            if !self.diags.contains(&d) {
                self.diags.push(d);
            }
        }
    }

    fn emit(&mut self, data: &[u8]) {
        let off = self.offsets.entry(self.sect).or_insert(0);
        // Past the local store nothing can load: stop growing (the size check reports it).
        if *off as usize + data.len() > 2 * LOCAL_STORE {
            *off = (2 * LOCAL_STORE) as u32;
            return;
        }
        if self.pass == 2 && self.sect != Sect::Bss {
            let buf = self.bytes.entry(self.sect).or_default();
            let at = *off as usize;
            if buf.len() < at + data.len() {
                buf.resize(at + data.len(), 0);
            }
            buf[at..at + data.len()].copy_from_slice(data);
        }
        *off += data.len() as u32;
    }

    fn align_to(&mut self, boundary: u32, fill: Option<u8>) {
        if boundary <= 1 {
            return;
        }
        let a = self.align.entry(self.sect).or_insert(1);
        *a = (*a).max(boundary);
        let off = self.offsets.get(&self.sect).copied().unwrap_or(0);
        let pad = (boundary - off % boundary) % boundary;
        if self.sect == Sect::Text && fill.is_none() {
            // tc-spu.c spu_handle_align: zero bytes to a word, then lnop in an odd slot,
            // then nop/lnop pairs.
            let mut bytes = Vec::new();
            let mut left = pad;
            let mut pos = off;
            while left & 3 != 0 {
                bytes.push(0);
                left -= 1;
                pos += 1;
            }
            while left > 0 {
                let word: u32 = if pos & 4 != 0 {
                    0x0020_0000
                } else {
                    0x4020_0000
                };
                bytes.extend(word.to_be_bytes());
                left -= 4;
                pos += 4;
            }
            self.emit(&bytes);
        } else {
            self.emit(&vec![fill.unwrap_or(0); pad as usize]);
        }
    }

    fn read_include(&self, name: &str) -> Option<String> {
        if let Some((_, text)) = self.opts.virtual_files.iter().find(|(n, _)| n == name) {
            return Some(text.clone());
        }
        for dir in &self.opts.include_dirs {
            if let Ok(t) = std::fs::read_to_string(dir.join(name)) {
                return Some(t);
            }
        }
        std::fs::read_to_string(name).ok()
    }

    /// Processes a list of lines (one file, a macro body or a repetition).
    fn run_lines(&mut self, lines: &[Line]) {
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
            let text = strip_comment(&line.text);
            let trimmed = text.trim();
            let first_word = trimmed
                .split(|c: char| c.is_whitespace() || c == ',')
                .next()
                .unwrap_or("")
                .to_ascii_lowercase();
            let active = cond.iter().all(|c| c.0);
            // Conditionals are tracked even while inactive.
            match first_word.as_str() {
                ".if" | ".ifdef" | ".ifndef" | ".ifeq" | ".ifne" | ".ifc" | ".ifnc" => {
                    let value = if active {
                        self.condition(&first_word, trimmed[first_word.len()..].trim(), line)
                    } else {
                        false
                    };
                    cond.push((active && value, value));
                    i += 1;
                    continue;
                }
                ".elseif" => {
                    let outer = cond.len() < 2 || cond[..cond.len() - 1].iter().all(|c| c.0);
                    if let Some(top) = cond.last_mut() {
                        let taken = top.1;
                        let v = !taken && outer && self.condition(".if", trimmed[7..].trim(), line);
                        *top = (v, taken || v);
                    }
                    i += 1;
                    continue;
                }
                ".else" => {
                    let outer = cond.len() < 2 || cond[..cond.len() - 1].iter().all(|c| c.0);
                    if let Some(top) = cond.last_mut() {
                        *top = (!top.1 && outer, true);
                    } else {
                        self.diag(Severity::Error, line, 1, ".else without .if");
                    }
                    i += 1;
                    continue;
                }
                ".endif" => {
                    if cond.pop().is_none() {
                        self.diag(Severity::Error, line, 1, ".endif without .if");
                    }
                    i += 1;
                    continue;
                }
                _ => {}
            }
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
                    .position(|l| first_word_of(&l.text) == ".endsched");
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
                let args = trimmed[first_word.len()..].trim().to_string();
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

    /// `.sched OPTIONS` ... `.endsched`: the block list-scheduled into dual-issue pairs,
    /// then assembled line by line, each scheduled line keeping its source location.
    fn sched_block(&mut self, args: &str, body: &[Line], line: &Line) {
        let opts = match crate::sched::parse_options(args) {
            Ok(opts) => opts,
            Err(message) => return self.diag(Severity::Error, line, 1, message),
        };
        let texts: Vec<&str> = body.iter().map(|l| l.text.as_str()).collect();
        let resolve = |text: &str| {
            self.get_reg(text, OperandKind::Ra, true)
                .filter(|(_, rest)| rest.trim().is_empty())
                .and_then(|(v, _)| u8::try_from(v).ok())
        };
        let here = self.offsets.get(&self.sect).copied().unwrap_or(0);
        let start = (here + 7) & !7;
        match crate::sched::schedule(&texts, &opts, Some(start), &resolve) {
            Ok(scheduled) => {
                let lines: Vec<Line> = scheduled
                    .lines
                    .into_iter()
                    .map(|(text, origin)| {
                        let at = origin.and_then(|k| body.get(k)).unwrap_or(line);
                        Line {
                            text,
                            file: at.file.clone(),
                            line: at.line,
                        }
                    })
                    .collect();
                self.run_lines(&lines);
            }
            Err(e) => {
                let at = body.get(e.line).unwrap_or(line);
                self.diag(Severity::Error, at, e.column, e.message);
            }
        }
    }

    fn condition(&mut self, kind: &str, args: &str, line: &Line) -> bool {
        match kind {
            ".ifdef" => self.symbols.contains_key(args.trim()),
            ".ifndef" => !self.symbols.contains_key(args.trim()),
            ".ifc" | ".ifnc" => {
                let parts = split_top(args, ',');
                let eq = parts.first().map(|s| s.trim().trim_matches('\''))
                    == parts.get(1).map(|s| s.trim().trim_matches('\''));
                eq == (kind == ".ifc")
            }
            _ => match self.eval(args) {
                Ok((v, _)) => match kind {
                    ".ifeq" => v == 0,
                    _ => v != 0,
                },
                Err((col, m)) => {
                    self.diag(Severity::Error, line, col + 1, m);
                    false
                }
            },
        }
    }

    fn block(&mut self, kind: &str, args: &str, body: Vec<Line>, line: &Line) {
        match kind {
            ".rept" => match self.eval(args) {
                Ok((n, _)) => {
                    for _ in 0..n.clamp(0, 1 << 20) {
                        if self.exitm {
                            break;
                        }
                        self.run_lines(&body);
                    }
                }
                Err((c, m)) => self.diag(Severity::Error, line, c + 1, m),
            },
            ".irp" | ".irpc" => {
                let parts = split_top(args, ',');
                let var = parts
                    .first()
                    .map(|s| s.trim().to_string())
                    .unwrap_or_default();
                let values: Vec<String> = if kind == ".irp" {
                    parts[1..].iter().map(|s| s.trim().to_string()).collect()
                } else {
                    parts
                        .get(1)
                        .map(|s| s.trim().chars().map(|c| c.to_string()).collect())
                        .unwrap_or_default()
                };
                for v in values {
                    if self.exitm {
                        break;
                    }
                    let expanded: Vec<Line> = body
                        .iter()
                        .map(|l| Line {
                            text: substitute(&l.text, &[(var.clone(), v.clone())], None),
                            ..l.clone()
                        })
                        .collect();
                    self.run_lines(&expanded);
                }
            }
            _ => {
                // .macro NAME params
                let mut it = args.splitn(2, |c: char| c.is_whitespace() || c == ',');
                let name = it.next().unwrap_or("").to_string();
                let params = it
                    .next()
                    .unwrap_or("")
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|s| !s.is_empty())
                    .map(|p| match p.split_once('=') {
                        Some((n, d)) => (n.trim().to_string(), Some(d.trim().to_string())),
                        None => (p.trim().to_string(), None),
                    })
                    .collect();
                self.macros
                    .insert(name.to_ascii_lowercase(), Macro { params, body });
            }
        }
    }

    fn statement(&mut self, line: &Line, text: &str) {
        for piece in split_top(text, ';') {
            self.stmt += 1;
            let mut rest = piece.trim().to_string();
            // Labels.
            loop {
                let Some(colon) = rest.find(':') else { break };
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
            } else if lw.starts_with('.') {
                self.directive(&lw, &args, line, col);
            } else if args.starts_with('=') {
                let v = args[1..].trim().to_string();
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

    fn define_label(&mut self, name: &str, line: &Line) {
        let off = self.offsets.get(&self.sect).copied().unwrap_or(0);
        if let Ok(n) = name.parse::<u32>() {
            if self.pass == 1 {
                self.numeric
                    .entry(n)
                    .or_default()
                    .push((self.stmt, self.sect, off));
            }
            return;
        }
        if self.pass == 1 {
            if let Some(SymVal::Label(..)) = self.symbols.get(name) {
                self.diag(
                    Severity::Error,
                    line,
                    1,
                    format!("symbol `{name}` is already defined"),
                );
            }
        }
        self.symbols
            .insert(name.to_string(), SymVal::Label(self.sect, off));
    }

    fn set_symbol(&mut self, name: &str, expr: &str, line: &Line) {
        match self.eval_val(expr) {
            Ok((v, _, _)) => {
                self.symbols
                    .insert(name.to_string(), SymVal::Abs(v.v, v.reloc));
            }
            Err((c, m)) => self.diag(Severity::Error, line, c + 1, m),
        }
    }

    fn expand_macro(&mut self, m: &Macro, args: &str, line: &Line) {
        // `\@` is the number of expansions before this one (GNU as counts from 0).
        let counter = self.macro_counter.to_string();
        self.macro_counter += 1;
        let given: Vec<String> = if args.trim().is_empty() {
            vec![]
        } else {
            split_top(args, ',')
                .iter()
                .map(|s| s.trim().to_string())
                .collect()
        };
        let mut subst = Vec::new();
        let mut positional = given.iter();
        for (name, default) in &m.params {
            let named = given.iter().find_map(|g| {
                g.split_once('=')
                    .filter(|(n, _)| n.trim() == name)
                    .map(|(_, v)| v.trim().to_string())
            });
            let value = named
                .or_else(|| positional.next().filter(|g| !g.contains('=')).cloned())
                .or_else(|| default.clone())
                .unwrap_or_default();
            subst.push((name.clone(), value));
        }
        let mut body = Vec::new();
        for l in &m.body {
            body.push(Line {
                text: substitute(&l.text, &subst, Some(&counter)),
                file: line.file.clone(),
                line: line.line,
            });
        }
        self.macro_depth += 1;
        self.run_lines(&body);
        self.macro_depth -= 1;
        self.exitm = false;
    }

    fn data_values(&mut self, args: &str, line: &Line, col: usize) -> Vec<i64> {
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

    fn directive(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        match d {
            ".text" => self.sect = Sect::Text,
            ".data" | ".rodata" => self.sect = Sect::Data,
            ".bss" => self.sect = Sect::Bss,
            ".section" => {
                let name = args
                    .split(',')
                    .next()
                    .unwrap_or("")
                    .trim()
                    .trim_matches('"');
                self.sect = if name.starts_with(".text") {
                    Sect::Text
                } else if name.starts_with(".bss") {
                    Sect::Bss
                } else {
                    Sect::Data
                };
            }
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
                let here = self.offsets.get(&self.sect).copied().unwrap_or(0) as i64;
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
                for v in self.data_values(args, line, col) {
                    let b = v.to_be_bytes();
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
            ".global" | ".globl" => {
                for n in args.split(',') {
                    let n = n.trim().to_string();
                    if !n.is_empty() && !self.globals.contains(&n) {
                        self.globals.push(n);
                    }
                }
            }
            ".set" | ".equ" | ".eqv" => {
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
            ".local" | ".type" | ".size" | ".file" | ".ident" | ".loc" | ".cfi_startproc"
            | ".cfi_endproc" | ".brinfo" | ".weak" | ".hidden" => {}
            ".end" => {}
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
            _ => self.diag(
                Severity::Error,
                line,
                col,
                format!("unknown pseudo-op: `{d}`"),
            ),
        }
    }

    /// gas `get_reg`: `$` optional, `chN`/`spN` prefixes for channels and SPRs, decimal
    /// numbers, the names `lr sp rp fp` (or a channel name), else a constant expression
    /// (whose value is ORed in unmasked, as gas does). `None` is a syntax mismatch.
    fn get_reg<'t>(
        &self,
        p: &'t str,
        kind: OperandKind,
        accept_expr: bool,
    ) -> Option<(i64, &'t str)> {
        let mut q = p.strip_prefix('$').unwrap_or(p);
        let b = q.as_bytes();
        let prefixed = |a: u8, c: u8| {
            b.len() > 2
                && b[0].eq_ignore_ascii_case(&a)
                && b[1].eq_ignore_ascii_case(&c)
                && b[2].is_ascii_digit()
        };
        if (kind == OperandKind::Ch && prefixed(b'c', b'h'))
            || (kind == OperandKind::Spr && prefixed(b's', b'p'))
        {
            q = &q[2..];
        }
        let digits = q.bytes().take_while(u8::is_ascii_digit).count();
        if digits > 0 {
            let n: u64 = q[..digits].parse().unwrap_or(u64::MAX);
            return (n < 128).then_some((n as i64, &q[digits..]));
        }
        let names: &[(&str, u32)] = match kind {
            OperandKind::Ch => CHANNELS,
            OperandKind::Spr => &[],
            _ => &[("lr", 0), ("sp", 1), ("rp", 0), ("fp", 127)],
        };
        let best = names
            .iter()
            .filter(|(n, _)| {
                q.len() >= n.len()
                    && q.is_char_boundary(n.len())
                    && q[..n.len()].eq_ignore_ascii_case(n)
            })
            .max_by_key(|(n, _)| n.len());
        if let Some((n, v)) = best {
            return Some((*v as i64, &q[n.len()..]));
        }
        if !accept_expr {
            return None;
        }
        match self.eval_prefix(q) {
            Ok((v, rest, undefined, _)) if !v.reloc || (undefined && self.pass == 1) => {
                Some((v.v, rest))
            }
            _ => None,
        }
    }

    /// gas `calcop`: parses `param` as `form`'s operands in order. `Err(None)` is a syntax
    /// mismatch (the next form of the mnemonic is tried); `Err(Some(..))` a hard error.
    fn calcop(&self, form: &FormInfo, param: &str) -> Result<Vec<Operand>, CalcErr> {
        let kinds = form.operands;
        let mut p = param;
        let mut out = Vec::new();
        let at = |p: &str| param.len() - p.len();
        for (i, &kind) in kinds.iter().enumerate() {
            p = p.trim_start();
            if p.is_empty() || p.starts_with(',') {
                return Err(CalcErr::Syntax(i));
            }
            let col = at(p);
            if kind == OperandKind::ParenRa {
                p = p.strip_prefix('(').ok_or(CalcErr::Syntax(i))?.trim_start();
                let (v, rest) = self
                    .get_reg(p, OperandKind::Ra, true)
                    .ok_or(CalcErr::Syntax(i))?;
                p = rest
                    .trim_start()
                    .strip_prefix(')')
                    .ok_or(CalcErr::Syntax(i))?;
                out.push(Operand::Reg(kind, v));
            } else if kind.is_register() {
                let (v, rest) = self.get_reg(p, kind, true).ok_or(CalcErr::Syntax(i))?;
                p = rest;
                out.push(Operand::Reg(kind, v));
            } else {
                let mut warnings = Vec::new();
                let (mut high, mut low) = (false, false);
                let lower = p.get(..5).unwrap_or(p).to_ascii_lowercase();
                if lower.starts_with("%lo(") {
                    p = &p[3..];
                    low = true;
                    warnings.push(
                        "Using old style, %lo(expr), please change to PPC style, expr@l."
                            .to_string(),
                    );
                } else if lower.starts_with("%hi(") {
                    p = &p[3..];
                    high = true;
                    warnings.push(
                        "Using old style, %hi(expr), please change to PPC style, expr@h."
                            .to_string(),
                    );
                } else if lower.starts_with("%pic(") {
                    p = &p[4..];
                }
                if p.starts_with('$') {
                    if let Some((_, rest)) = self.get_reg(p, kind, false) {
                        let name = &p[..p.len() - rest.len()];
                        warnings.push(format!("Treating '{name}' as a symbol."));
                    }
                }
                if crate::expr::parse(p).is_none() {
                    return Err(CalcErr::Syntax(i));
                }
                let (val, rest, _, w) = self
                    .eval_prefix(p)
                    .map_err(|(c, m)| CalcErr::Hard(at(p) + c, m))?;
                warnings.extend(w);
                p = rest;
                let b = p.as_bytes();
                if b.len() >= 2
                    && b[0] == b'@'
                    && !b
                        .get(2)
                        .is_some_and(|c| c.is_ascii_alphanumeric() || *c == b'@')
                {
                    match b[1] {
                        b'h' | b'H' => {
                            high = true;
                            p = &p[2..];
                        }
                        b'l' | b'L' => {
                            low = true;
                            p = &p[2..];
                        }
                        _ => {}
                    }
                }
                out.push(Operand::Imm {
                    kind,
                    val,
                    high,
                    low,
                    col,
                    warnings,
                });
            }
            p = p.trim_start();
            if i + 1 < kinds.len() && kinds[i + 1] != OperandKind::ParenRa {
                p = p.strip_prefix(',').ok_or(CalcErr::Syntax(i + 1))?;
            }
        }
        if !p.trim().is_empty() {
            return Err(CalcErr::Syntax(kinds.len()));
        }
        Ok(out)
    }

    fn instruction(&mut self, mnemonic: &str, args: &str, line: &Line, col: usize) {
        let pc = self.here();
        let forms: Vec<&'static FormInfo> = forms_named(mnemonic).collect();
        if forms.is_empty() {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("Invalid mnemonic '{mnemonic}'"),
            );
            self.emit(&[0; 4]);
            return;
        }
        let arg_col = line
            .text
            .find(args.trim())
            .filter(|_| !args.trim().is_empty())
            .map(|p| p + 1)
            .unwrap_or(col);
        let param = args.trim();
        let mut failure = (forms[0], 0);
        let mut parsed = None;
        for form in &forms {
            match self.calcop(form, param) {
                Ok(ops) => {
                    parsed = Some((*form, ops));
                    break;
                }
                Err(CalcErr::Syntax(arg)) => failure = (form, arg),
                Err(CalcErr::Hard(c, m)) => {
                    self.diag(Severity::Error, line, arg_col + c, m);
                    self.emit(&[0; 4]);
                    return;
                }
            }
        }
        let Some((form, ops)) = parsed else {
            let (form, arg) = failure;
            self.diag(
                Severity::Error,
                line,
                arg_col,
                format!(
                    "Error in argument {}.  Expecting:  \"{}\"",
                    arg + 1,
                    insn_fmt_string(form, arg)
                ),
            );
            self.emit(&[0; 4]);
            return;
        };
        let mut word = form.base_word();
        for op in ops {
            match op {
                Operand::Reg(kind, v) => {
                    let pos = match kind {
                        OperandKind::Rt if form.format == Format::RRR => 21,
                        OperandKind::Rt | OperandKind::Rc => 0,
                        OperandKind::Rb => 14,
                        _ => 7,
                    };
                    word |= (v as u32).wrapping_shl(pos);
                }
                Operand::Imm {
                    kind,
                    val,
                    high,
                    low,
                    col: c,
                    warnings,
                } => {
                    if self.pass == 2 {
                        for w in warnings {
                            self.diag(Severity::Warning, line, arg_col + c, w);
                        }
                    }
                    match self.immediate(form.format, kind, val, high, low, pc) {
                        Ok((bits, warning)) => {
                            word |= bits;
                            if let Some(w) = warning {
                                self.diag(Severity::Warning, line, arg_col + c, w);
                            }
                        }
                        Err(m) => self.diag(Severity::Error, line, arg_col + c, m),
                    }
                }
            }
        }
        self.emit(&word.to_be_bytes());
    }

    /// The bits an immediate operand contributes, as gas's `get_imm` (constants) and
    /// `md_apply_fix` (values that depend on addresses) compute them, with the range
    /// error or warning gas gives.
    fn immediate(
        &self,
        format: Format,
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        pc: u32,
    ) -> Result<(u32, Option<String>), String> {
        use OperandKind::*;
        let enc = arg_encode(kind);
        if self.pass == 1 {
            return Ok((0, None));
        }
        if !val.reloc {
            // A constant: gas keeps it in an `int`, then applies @h/@l, checks, encodes.
            let mut v = val.v as i32 as i64;
            if high {
                v >>= 16;
            } else if low {
                v &= 0xffff;
            }
            let mut warning = None;
            if enc.hi > enc.lo && (v < enc.lo || v > enc.hi) {
                return Err(format!(
                    "Constant expression {v} out of range, [{}, {}].",
                    enc.lo, enc.hi
                ));
            } else if enc.whi > enc.wlo && (v < enc.wlo || v > enc.whi) {
                warning = Some(format!(
                    "Constant expression {v} out of range, [{}, {}].",
                    enc.wlo, enc.whi
                ));
            }
            match kind {
                Scale173 => v = 173 - v,
                Scale155 => v = 155 - v,
                _ => {}
            }
            let mut bits = 0u32;
            if kind == BrInst {
                bits |= ((v >> 2) & 0x7f) as u32;
            }
            let pos = if kind == BrInst && format == Format::LBTI {
                14
            } else {
                enc.pos
            };
            bits |= (((v >> enc.rshift) & ((1i64 << enc.size) - 1)) as u32) << pos;
            return Ok((bits, warning));
        }
        // An address: resolved here as the linker would (PC-relative kinds against this
        // instruction's address).
        let pcrel = matches!(kind, Rel18 | BrInst);
        let v = if pcrel { val.v - pc as i64 } else { val.v };
        if high {
            return Ok(((((v >> 16) & 0xffff) as u32) << 7, None));
        }
        if low {
            return Ok((((v & 0xffff) as u32) << 7, None));
        }
        if enc.hi > enc.lo && (v < enc.lo || v > enc.hi) {
            return Err(format!(
                "Relocation doesn't fit. (relocation value = 0x{:x})",
                v
            ));
        }
        let bits = match kind {
            BrInst if format == Format::LBTI => ((v & 0x1fc) >> 2) | ((v & 0x600) << 5),
            BrInst => ((v & 0x1fc) >> 2) | ((v & 0x600) << 14),
            U14 => v & 0x3fff,
            _ => ((v >> enc.rshift) & ((1i64 << enc.size) - 1)) << enc.pos,
        };
        Ok((bits as u32, None))
    }
}

fn unquote(s: &str) -> Option<Vec<u8>> {
    let inner = s.strip_prefix('"')?.strip_suffix('"')?;
    let mut out = Vec::new();
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '\\' {
            let mut buf = [0u8; 4];
            out.extend(c.encode_utf8(&mut buf).as_bytes());
            continue;
        }
        match chars.next()? {
            'n' => out.push(b'\n'),
            't' => out.push(b'\t'),
            'r' => out.push(b'\r'),
            'b' => out.push(8),
            'f' => out.push(12),
            '\\' => out.push(b'\\'),
            '"' => out.push(b'"'),
            // \xHH...: hex digits, the low byte kept (as GNU as does).
            'x' | 'X' => {
                let mut v: u32 = 0;
                while let Some(d) = chars.peek().and_then(|c| c.to_digit(16)) {
                    v = v.wrapping_mul(16).wrapping_add(d);
                    chars.next();
                }
                out.push(v as u8);
            }
            // \NNN: up to three octal digits.
            d @ '0'..='7' => {
                let mut v = d.to_digit(8).unwrap_or(0);
                for _ in 0..2 {
                    match chars.peek().and_then(|c| c.to_digit(8)) {
                        Some(n) => {
                            v = v * 8 + n;
                            chars.next();
                        }
                        None => break,
                    }
                }
                out.push(v as u8);
            }
            other => out.push(other as u8),
        }
    }
    Some(out)
}

/// Replaces `\name` (and `\@` with the macro counter) in a macro or repetition body.
fn substitute(text: &str, vars: &[(String, String)], counter: Option<&str>) -> String {
    let mut out = String::new();
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'\\' {
            if let Some(c) = counter {
                if b.get(i + 1) == Some(&b'@') {
                    out.push_str(c);
                    i += 2;
                    continue;
                }
            }
            let start = i + 1;
            let mut end = start;
            while end < b.len() && is_ident(b[end] as char) && b[end] != b'.' && b[end] != b'$' {
                end += 1;
            }
            let name = &text[start..end];
            if let Some((_, v)) = vars.iter().find(|(n, _)| n == name) {
                out.push_str(v);
                i = end;
                // `\()` separates a parameter from following text.
                if text[i..].starts_with("()") {
                    i += 2;
                }
                continue;
            }
        }
        out.push(b[i] as char);
        i += 1;
    }
    out
}

fn first_word_of(text: &str) -> String {
    strip_comment(text)
        .split_whitespace()
        .next()
        .unwrap_or("")
        .to_ascii_lowercase()
}

fn collect_block(lines: &[Line], start: usize) -> (Vec<Line>, usize) {
    let mut depth = 1;
    let mut i = start;
    while i < lines.len() {
        let w = strip_comment(&lines[i].text)
            .trim()
            .split_whitespace()
            .next()
            .unwrap_or("")
            .to_ascii_lowercase();
        match w.as_str() {
            ".macro" | ".rept" | ".irp" | ".irpc" => depth += 1,
            ".endm" | ".endr" => {
                depth -= 1;
                if depth == 0 {
                    return (lines[start..i].to_vec(), i + 1);
                }
            }
            _ => {}
        }
        i += 1;
    }
    (lines[start..].to_vec(), lines.len() + 1)
}

/// Blanks `/* */` comments (which may span lines) with spaces, keeping every newline so
/// line and column numbers stay those of the source. Strings and `#` comments are skipped.
fn blank_block_comments(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    let (mut in_block, mut in_str, mut in_line_comment) = (false, false, false);
    while let Some(c) = chars.next() {
        if c == '\n' {
            in_str = false;
            in_line_comment = false;
            out.push(c);
            continue;
        }
        if in_block {
            if c == '*' && chars.peek() == Some(&'/') {
                chars.next();
                in_block = false;
                out.push_str("  ");
            } else {
                out.push(if c == '\t' { '\t' } else { ' ' });
            }
            continue;
        }
        if in_line_comment {
            out.push(c);
            continue;
        }
        if in_str {
            out.push(c);
            if c == '\\' {
                if let Some(&n) = chars.peek() {
                    if n != '\n' {
                        out.push(n);
                        chars.next();
                    }
                }
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        match c {
            '"' => in_str = true,
            '#' => in_line_comment = true,
            '/' if chars.peek() == Some(&'*') => {
                chars.next();
                in_block = true;
                out.push_str("  ");
                continue;
            }
            _ => {}
        }
        out.push(c);
    }
    out
}

fn to_lines(text: &str, file: &str) -> Vec<Line> {
    let text = blank_block_comments(text);
    text.lines()
        .enumerate()
        .map(|(i, l)| Line {
            text: l.to_string(),
            file: file.to_string(),
            line: i + 1,
        })
        .collect()
}

/// Assembles `source` (named `file_name` in diagnostics).
pub fn assemble(source: &str, file_name: &str, opts: &Options) -> Result<Output, Vec<Diagnostic>> {
    let lines = to_lines(source, file_name);
    let mut asm = Assembler {
        opts,
        pass: 1,
        sect: Sect::Text,
        offsets: HashMap::new(),
        align: HashMap::new(),
        bases: HashMap::new(),
        symbols: HashMap::new(),
        pass1_symbols: HashMap::new(),
        globals: Vec::new(),
        numeric: HashMap::new(),
        stmt: 0,
        bytes: HashMap::new(),
        diags: Vec::new(),
        macros: HashMap::new(),
        macro_counter: 0,
        listing: String::new(),
        depth: 0,
        macro_depth: 0,
        exitm: false,
    };
    let predefine = |asm: &mut Assembler| {
        for (n, v) in &opts.defines {
            asm.symbols.insert(n.clone(), SymVal::Abs(*v, false));
        }
    };
    predefine(&mut asm);
    asm.run_lines(&lines);
    asm.finish_sections();
    // Lay the sections out: text at 0, data and bss after, each at its alignment.
    let size = |s: Sect, a: &Assembler| a.offsets.get(&s).copied().unwrap_or(0);
    let align = |s: Sect, a: &Assembler| a.align.get(&s).copied().unwrap_or(16).max(16);
    let text_size = size(Sect::Text, &asm);
    let data_base = text_size.div_ceil(align(Sect::Data, &asm)) * align(Sect::Data, &asm);
    let data_size = size(Sect::Data, &asm);
    let bss_base =
        (data_base + data_size).div_ceil(align(Sect::Bss, &asm)) * align(Sect::Bss, &asm);
    let bss_size = size(Sect::Bss, &asm);
    asm.bases = HashMap::from([
        (Sect::Text, 0),
        (Sect::Data, data_base),
        (Sect::Bss, bss_base),
    ]);
    // Pass 2.
    asm.pass = 2;
    asm.sect = Sect::Text;
    asm.offsets.clear();
    asm.stmt = 0;
    asm.macros.clear();
    asm.macro_counter = 0;
    let labels: HashMap<String, SymVal> = asm
        .symbols
        .iter()
        .filter(|(_, v)| matches!(v, SymVal::Label(..)))
        .map(|(k, v)| (k.clone(), *v))
        .collect();
    asm.pass1_symbols = std::mem::take(&mut asm.symbols);
    asm.symbols = labels;
    predefine(&mut asm);
    asm.run_lines(&lines);
    asm.finish_sections();
    let (errors, warnings): (Vec<_>, Vec<_>) = asm
        .diags
        .into_iter()
        .partition(|d| d.severity == Severity::Error);
    if !errors.is_empty() {
        let mut all = errors;
        all.extend(warnings);
        all.sort_by(|a, b| {
            (&a.location.file, a.location.line, a.location.column).cmp(&(
                &b.location.file,
                b.location.line,
                b.location.column,
            ))
        });
        return Err(all);
    }
    let end = bss_base + bss_size;
    if end as usize > 256 * 1024 {
        return Err(vec![Diagnostic {
            severity: Severity::Error,
            location: Location {
                file: file_name.into(),
                line: 1,
                column: 1,
            },
            message: format!("program of {end} bytes does not fit the 256 KiB local store"),
            source_line: lines.first().map(|l| l.text.clone()).unwrap_or_default(),
        }]);
    }
    let mut image = vec![0u8; end as usize];
    for (s, base) in [(Sect::Text, 0u32), (Sect::Data, data_base)] {
        if let Some(b) = asm.bytes.get(&s) {
            image[base as usize..base as usize + b.len()].copy_from_slice(b);
        }
    }
    let mut symbols: Vec<(String, u32)> = asm
        .symbols
        .iter()
        .filter_map(|(n, v)| match v {
            SymVal::Label(s, off) if !n.starts_with(".L") => Some((n.clone(), asm.bases[s] + off)),
            _ => None,
        })
        .collect();
    symbols.sort_by(|a, b| a.1.cmp(&b.1).then(a.0.cmp(&b.0)));
    let entry = symbols
        .iter()
        .find(|(n, _)| n == "_start")
        .map(|s| s.1)
        .unwrap_or(0);
    let sections = vec![
        (".text".to_string(), 0, text_size, true),
        (".data".to_string(), data_base, data_size, false),
        (".bss".to_string(), bss_base, bss_size, false),
    ];
    let elf = crate::elf::write_elf(&image, &sections, &symbols, &asm.globals, entry);
    Ok(Output {
        image,
        elf,
        symbols,
        entry,
        listing: asm.listing,
        warnings,
        sections,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(src: &str) -> Vec<u32> {
        let out = assemble(src, "t.s", &Options::default()).unwrap_or_else(|e| {
            panic!(
                "{}",
                e.iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join("\n")
            )
        });
        let text = out.sections[0].2 as usize;
        out.image[..text]
            .chunks(4)
            .map(|c| u32::from_be_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    #[test]
    fn readme_encodings() {
        assert_eq!(
            words("il $3,42\nfma $7,$6,$5,$4\nlqd $5,32($1)\nbi $3\nbid $3"),
            vec![0x40801503, 0xe0e14304, 0x34008085, 0x35000180, 0x35080180]
        );
    }

    #[test]
    fn labels_locals_and_set_registers() {
        // `1b` on the line that defines `1:` is that very label (offset 0), as in GNU as.
        let w = words(".set R, 5\n1: ai R, R, 1\n brnz R, 1b\n br 2f\n2: stop\n 1: brz R, 1b\n");
        assert_eq!(w[0], 0x1c004285);
        assert_eq!(w[1], 0x217fff85); // brnz $5, -4 bytes
        assert_eq!(w[2], 0x32000080); // br +4
        assert_eq!(w[4], 0x20000005); // brz $5, 0
    }

    #[test]
    fn irp_with_register_expressions() {
        let w = words(".irp J, 0, 1\n ai (\\J+80), (\\J+80), 1\n.endr\n");
        // ai $80,$80,1 and ai $81,$81,1
        assert_eq!(w, vec![0x1c006850, 0x1c0068d1]);
    }

    #[test]
    fn alignment_pads_with_nop_and_lnop() {
        // The section end is padded to its alignment too (gas SUB_SEGMENT_ALIGN).
        let w = words("il $3,1\n.align 4\nil $3,2\n");
        assert_eq!(
            w,
            vec![
                0x40800083, 0x00200000, 0x40200000, 0x00200000, 0x40800103, 0x00200000, 0x40200000,
                0x00200000
            ]
        );
    }

    #[test]
    fn errors_name_file_line_column_and_continue() {
        let e = assemble(
            "il $3, 40000\nfoo $1\nai $3,$3,1\nlqd $3, 4($1)\n",
            "bad.s",
            &Options::default(),
        )
        .unwrap_err();
        let text: Vec<String> = e
            .iter()
            .map(|d| format!("{}:{}", d.location.line, d.message))
            .collect();
        assert!(
            text.iter()
                .any(|t| t.starts_with("1:Constant expression 40000 out of range")),
            "{text:?}"
        );
        assert!(
            text.iter().any(|t| t.starts_with("2:Invalid mnemonic")),
            "{text:?}"
        );
    }

    #[test]
    fn string_escapes_and_forward_equ() {
        let out = assemble(
            ".data\nx: .ascii \"\\x41\\101\\n\"\n.text\nil $3, LATER\n.equ LATER, 7\n",
            "t.s",
            &Options::default(),
        )
        .unwrap();
        let data = &out.image[out.sections[1].1 as usize..][..3];
        assert_eq!(data, b"AA\n");
        assert_eq!(&out.image[0..4], &0x40800383u32.to_be_bytes()); // il $3,7
    }
}
