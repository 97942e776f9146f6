//! A GNU-as compatible assembler for SPU: the statement processor (labels, directives,
//! macros and repetition), expressions, operand parsing with GNU as's range checks, and
//! the two passes that lay sections out and encode through the shared instruction table.
//!
//! Pass 1 walks the source to give every label an address (every instruction is 4 bytes,
//! so only data directives need values then); pass 2 walks it again with all symbols known
//! and emits bytes. Both passes run the same expansion of `.include`, `.macro`, `.irp`,
//! `.rept` and `.if`, so they see the same statements.

use crate::sched::{SchedError, Scheduled};
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

/// A chunk: one subsection of one section (an index into `Assembler::chunks`). A section
/// is the concatenation of its chunks in subsection order.
type Sect = usize;

/// ELF section types and flags the assembler sets.
pub const SHT_PROGBITS: u32 = 1;
pub const SHT_NOBITS: u32 = 8;
pub const SHF_WRITE: u64 = 1;
pub const SHF_ALLOC: u64 = 2;
pub const SHF_EXECINSTR: u64 = 4;

/// A section as `.section` declared it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SectionDef {
    pub name: String,
    pub ty: u32,
    pub flags: u64,
    pub entsize: u64,
}

impl SectionDef {
    /// GNU as's defaults for a section named without flags (`obj-elf.c` special sections).
    fn named(name: &str) -> SectionDef {
        let has = |p: &str| name == p || name.starts_with(&format!("{p}."));
        let (ty, flags) = if has(".text") || has(".init") || has(".fini") {
            (SHT_PROGBITS, SHF_ALLOC | SHF_EXECINSTR)
        } else if has(".bss") || has(".sbss") || has(".tbss") {
            (SHT_NOBITS, SHF_ALLOC | SHF_WRITE)
        } else if has(".data") || has(".sdata") || has(".tdata") || has(".ctors") || has(".dtors") {
            (SHT_PROGBITS, SHF_ALLOC | SHF_WRITE)
        } else if has(".rodata") {
            (SHT_PROGBITS, SHF_ALLOC)
        } else {
            (SHT_PROGBITS, 0)
        };
        SectionDef {
            name: name.to_string(),
            ty,
            flags,
            entsize: 0,
        }
    }
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

#[derive(Clone, Debug)]
enum SymVal {
    /// A value from `.set`/`=` (which may be an address).
    Abs(Val),
    Label(Sect, u32),
    /// `.comm name, size, align` in an object: allocated by the linker.
    Common(u32, u32),
}

/// A relocation the assembler leaves for the linker (objects only).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Reloc {
    /// Offset in its section.
    pub offset: u32,
    /// An `R_SPU_*` number.
    pub kind: u32,
    pub target: RelocTarget,
    pub addend: i64,
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum RelocTarget {
    /// A section of this object (by index into the section list).
    Section(usize),
    Symbol(String),
}

/// Symbol attributes set by directives.
#[derive(Clone, Debug, Default)]
struct SymAttrs {
    global: bool,
    weak: bool,
    hidden: bool,
    /// STT_* from `.type` (1 object, 2 function).
    kind: u8,
    size: Option<i64>,
}

struct Assembler<'o> {
    opts: &'o Options,
    pass: u8,
    sect: Sect,
    /// `.previous` and the `.pushsection` stack.
    prev_sect: Sect,
    sect_stack: Vec<(Sect, Sect)>,
    defs: Vec<SectionDef>,
    /// Each chunk's section definition and subsection number.
    chunks: Vec<(usize, i64)>,
    /// Writing a relocatable object: addresses are section offsets and references that
    /// depend on them become relocations.
    object: bool,
    relocs: Vec<(usize, Reloc, Location, String)>,
    attrs: HashMap<String, SymAttrs>,
    /// Total statements expanded from macros and repetitions (bounded).
    expanded: usize,
    /// Diagnostics already reported (constant-time deduplication) and the count dropped.
    seen_diags: std::collections::HashSet<(String, usize, usize, String)>,
    dropped_diags: usize,
    /// The value of the operand whose relocation `instruction` is about to record.
    pending: Option<Val>,
    /// Labels defined so far in this walk.
    defined: std::collections::HashSet<String>,
    /// Bytes other than zero were stored in a NOBITS section (reported once per statement).
    nonzero_in_nobits: bool,
    offsets: HashMap<Sect, u32>,
    align: HashMap<Sect, u32>,
    bases: HashMap<Sect, u32>,
    symbols: HashMap<String, SymVal>,
    /// The symbols as pass 1 left them (for forward references in pass 2).
    pass1_symbols: HashMap<String, SymVal>,
    /// Numeric local label definitions: label -> list of (statement number, section, offset).
    numeric: HashMap<u32, Vec<(usize, Sect, u32)>>,
    /// The same, being collected by the current layout walk.
    numeric_next: HashMap<u32, Vec<(usize, Sect, u32)>>,
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
    /// `.sched` blocks already scheduled in an earlier pass: the same lines, options and
    /// start give the same schedule when every register name the scheduler resolved
    /// still resolves the same (layout passes repeat each block unchanged).
    schedules: HashMap<SchedKey, (Vec<(String, Option<u8>)>, Result<Scheduled, SchedError>)>,
}

/// What a `.sched` block's schedule is made from: its lines, options and start address.
type SchedKey = (Vec<String>, String, u32);

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
            '(' | '[' => {
                depth += 1;
                cur.push(c)
            }
            ')' | ']' => {
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

/// SPU channel names (`$SPU_RdInMbox`) and their numbers, as gas's `ch_reg_name`.
pub const CHANNELS: &[(&str, u32)] = &[
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

/// Diagnostics reported in full; more are counted ("and N more").
const MAX_DIAGNOSTICS: usize = 100;

/// Statements that macros, `.rept` and `.irp` may expand to in all: a bound on work, so
/// nested repetitions cannot run for ever.
const MAX_EXPANDED: usize = 1_000_000;

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
    /// A register number outside its field: an error unless another form fits.
    Range(usize, String),
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
        if !self.symbols.contains_key(name) && (self.pass == 2 || !self.pass1_symbols.is_empty()) {
            // A `.set`/`.equ` symbol used before its definition: its final value.
            return match self.pass1_symbols.get(name)? {
                SymVal::Abs(v) => Some(v.clone()),
                _ => None,
            };
        }
        Some(self.value_of(name, self.symbols.get(name)?))
    }
    fn dot(&self) -> Val {
        Val {
            v: self.here() as i64,
            reloc: true,
            sect: Some(self.chunks[self.sect].0),
            ..Default::default()
        }
    }
    fn local(&self, n: u32, forward: bool) -> Option<Val> {
        self.numeric_ref(n, forward)
    }
    fn lenient(&self) -> bool {
        self.pass == 1
    }
    fn external(&self, name: &str) -> Option<Val> {
        // In an object, a symbol defined nowhere is an external reference for the linker.
        (self.object && !name.starts_with(".L")).then(|| Val {
            v: 0,
            reloc: true,
            sym: Some((name.into(), 0)),
            ..Default::default()
        })
    }
}

impl<'o> Assembler<'o> {
    /// A defined symbol's address or value (executables).
    fn symbol_address(&self, name: &str) -> Option<i64> {
        self.symbols.get(name).map(|s| self.value_of(name, s).v)
    }

    fn value_of(&self, name: &str, sv: &SymVal) -> Val {
        match sv {
            // A local name for an address in a section (`alias = later`) is that address:
            // gas resolves a branch to it like one to a local label.
            SymVal::Abs(v)
                if v.sect.is_some()
                    && !self.attrs.get(name).is_some_and(|a| a.global || a.weak) =>
            {
                Val {
                    sym: None,
                    ..v.clone()
                }
            }
            SymVal::Abs(v) => v.clone(),
            SymVal::Label(s, off) => {
                let v = (self.bases.get(s).copied().unwrap_or(0) + off) as i64;
                let a = self.attrs.get(name);
                let visible = a.is_some_and(|a| a.global || a.weak);
                Val {
                    v,
                    reloc: true,
                    sect: Some(self.chunks[*s].0),
                    sym: (self.object && visible).then(|| (name.into(), v)),
                    cross: false,
                }
            }
            SymVal::Common(..) => Val {
                v: 0,
                reloc: true,
                sym: Some((name.into(), 0)),
                ..Default::default()
            },
        }
    }

    /// The chunk for a section and subsection, created on first use.
    fn chunk(&mut self, def: SectionDef, sub: i64) -> Sect {
        let d = match self.defs.iter().position(|x| x.name == def.name) {
            Some(d) => d,
            None => {
                self.defs.push(def);
                self.defs.len() - 1
            }
        };
        match self.chunks.iter().position(|c| *c == (d, sub)) {
            Some(c) => c,
            None => {
                self.chunks.push((d, sub));
                self.chunks.len() - 1
            }
        }
    }

    fn switch_to(&mut self, chunk: Sect) {
        if chunk != self.sect {
            self.prev_sect = self.sect;
            self.sect = chunk;
        }
    }

    fn is_nobits(&self, s: Sect) -> bool {
        self.defs[self.chunks[s].0].ty == SHT_NOBITS
    }

    fn is_code(&self, s: Sect) -> bool {
        self.defs[self.chunks[s].0].flags & SHF_EXECINSTR != 0
    }

    /// gas pads the end of each section to the largest alignment requested in it
    /// (`SUB_SEGMENT_ALIGN` with `HANDLE_ALIGN`): code with nop/lnop, data with zeros.
    fn finish_sections(&mut self) {
        let current = self.sect;
        for d in 0..self.defs.len() {
            let mine: Vec<Sect> = (0..self.chunks.len())
                .filter(|&c| self.chunks[c].0 == d)
                .collect();
            let boundary = mine
                .iter()
                .map(|c| self.align.get(c).copied().unwrap_or(1))
                .max()
                .unwrap_or(1);
            let last = mine.iter().max_by_key(|&&c| self.chunks[c].1);
            if let (Some(&last), true) = (last, boundary > 1) {
                self.sect = last;
                self.align_to(boundary, None);
            }
        }
        self.sect = current;
    }

    fn here(&self) -> u32 {
        self.bases.get(&self.sect).copied().unwrap_or(0)
            + self.offsets.get(&self.sect).copied().unwrap_or(0)
    }

    fn numeric_ref(&self, n: u32, forward: bool) -> Option<Val> {
        // Backward references in a layout walk see this walk's definitions so far;
        // forward ones (and every reference in the final walk) the previous walk's.
        let table = if self.pass == 1 && !forward {
            &self.numeric_next
        } else {
            &self.numeric
        };
        let defs = table.get(&n)?;
        let pick = if forward {
            defs.iter().find(|d| d.0 > self.stmt)
        } else {
            defs.iter().rev().find(|d| d.0 < self.stmt)
        }?;
        Some(Val {
            v: (self.bases.get(&pick.1).copied().unwrap_or(0) + pick.2) as i64,
            reloc: true,
            sect: Some(self.chunks[pick.1].0),
            ..Default::default()
        })
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
                source_line: display_text(&line.text),
            };
            let key = (
                d.location.file.clone(),
                d.location.line,
                d.location.column,
                d.message.clone(),
            );
            if self.seen_diags.insert(key) {
                if self.diags.len() < MAX_DIAGNOSTICS {
                    self.diags.push(d);
                } else {
                    self.dropped_diags += 1;
                }
            }
        }
    }

    fn emit(&mut self, data: &[u8]) {
        let nobits = self.is_nobits(self.sect);
        let off = self.offsets.entry(self.sect).or_insert(0);
        // Past the local store nothing can load: stop growing (the size check reports it).
        if *off as usize + data.len() > 2 * LOCAL_STORE {
            *off = (2 * LOCAL_STORE) as u32;
            return;
        }
        if nobits {
            if self.pass == 2 && data.iter().any(|&b| b != 0) {
                self.nonzero_in_nobits = true;
            }
        } else if self.pass == 2 {
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
        // Padding is to an address (sections start at their alignment), so subsections
        // align as gas aligns them once they are joined.
        let off = self.here();
        let pad = (boundary - off % boundary) % boundary;
        if self.is_code(self.sect) && fill.is_none() {
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
    fn run_lines(&mut self, lines: &[Line]) {
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

    /// `.sched OPTIONS` ... `.endsched`: the block list-scheduled into dual-issue pairs,
    /// then assembled line by line, each scheduled line keeping its source location.
    fn sched_block(&mut self, args: &str, body: &[Line], line: &Line) {
        let opts = match crate::sched::parse_options(args) {
            Ok(opts) => opts,
            Err(message) => return self.diag(Severity::Error, line, 1, message),
        };
        let body = &self.sched_macros(body, 0)[..];
        let texts: Vec<&str> = body.iter().map(|l| l.text.as_str()).collect();
        let resolve = |text: &str| {
            self.get_reg(text, OperandKind::Ra, true)
                .filter(|(_, rest)| rest.trim().is_empty())
                .and_then(|(v, _)| u8::try_from(v).ok())
        };
        let here = self.offsets.get(&self.sect).copied().unwrap_or(0);
        let start = (here + 7) & !7;
        let key: SchedKey = (
            texts.iter().map(|t| t.to_string()).collect(),
            format!("{opts:?}"),
            start,
        );
        let cached = self.schedules.get(&key).filter(|(asked, _)| {
            asked
                .iter()
                .all(|(text, reg)| resolve(text.as_str()) == *reg)
        });
        let result = match cached {
            Some((_, result)) => result.clone(),
            None => {
                let asked = std::cell::RefCell::new(Vec::new());
                let logged = |text: &str| {
                    let reg = resolve(text);
                    asked.borrow_mut().push((text.to_string(), reg));
                    reg
                };
                let result = crate::sched::schedule(&texts, &opts, Some(start), &logged);
                self.schedules
                    .insert(key, (asked.into_inner(), result.clone()));
                result
            }
        };
        match result {
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
                    if n > 1 << 20 {
                        self.diag(
                            Severity::Error,
                            line,
                            1,
                            format!(".rept count {n} is more than {}", 1 << 20),
                        );
                        return;
                    }
                    for _ in 0..n.max(0) {
                        if self.exitm || self.expanded > MAX_EXPANDED {
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
                    parts[1..]
                        .iter()
                        .map(|s| macro_argument(s.trim()))
                        .collect()
                } else {
                    parts
                        .get(1)
                        .map(|s| s.trim().chars().map(|c| c.to_string()).collect())
                        .unwrap_or_default()
                };
                for v in values {
                    if self.exitm || self.expanded > MAX_EXPANDED {
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
                self.numeric_next
                    .entry(n)
                    .or_default()
                    .push((self.stmt, self.sect, off));
            }
            return;
        }
        let first = self.defined.insert(name.to_string());
        if self.pass == 1 {
            if !first || matches!(self.symbols.get(name), Some(SymVal::Common(..))) {
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
        if name == "." {
            let col = line.text.find('=').map_or(1, |c| c + 2);
            self.org(expr, 0, line, col);
            return;
        }
        match self.eval_val(expr) {
            Ok((v, _, _)) => {
                self.symbols.insert(name.to_string(), SymVal::Abs(v));
            }
            Err((c, m)) => self.diag(Severity::Error, line, c + 1, m),
        }
    }

    fn expand_macro(&mut self, m: &Macro, args: &str, line: &Line) {
        let body = self.macro_lines(m, args, line);
        self.macro_depth += 1;
        self.run_lines(&body);
        self.macro_depth -= 1;
        self.exitm = false;
    }

    /// A macro's body with its arguments substituted, at the calling line.
    fn macro_lines(&mut self, m: &Macro, args: &str, line: &Line) -> Vec<Line> {
        // `\@` is the number of expansions before this one (GNU as counts from 0).
        let counter = self.macro_counter.to_string();
        self.macro_counter += 1;
        let given: Vec<String> = if args.trim().is_empty() {
            vec![]
        } else {
            split_top(args, ',')
                .iter()
                .map(|s| macro_argument(s.trim()))
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
        body
    }

    /// Applies `word` to the open conditionals `cond` (per level: this branch is assembled,
    /// some branch was taken) if it is `.if*`, `.elseif`, `.else` or `.endif`; whether it
    /// was one.
    fn conditional(
        &mut self,
        cond: &mut Vec<(bool, bool)>,
        word: &str,
        args: &str,
        line: &Line,
    ) -> bool {
        let outer = cond.len() < 2 || cond[..cond.len() - 1].iter().all(|c| c.0);
        match word {
            ".if" | ".ifdef" | ".ifndef" | ".ifeq" | ".ifne" | ".ifc" | ".ifnc" => {
                let value = cond.iter().all(|c| c.0) && self.condition(word, args, line);
                cond.push((value, value));
            }
            ".elseif" => {
                if let Some((_, taken)) = cond.last().copied() {
                    let v = !taken && outer && self.condition(".if", args, line);
                    cond.pop();
                    cond.push((v, taken || v));
                }
            }
            ".else" => match cond.last_mut() {
                Some(top) => *top = (!top.1 && outer, true),
                None => self.diag(Severity::Error, line, 1, ".else without .if"),
            },
            ".endif" => {
                if cond.pop().is_none() {
                    self.diag(Severity::Error, line, 1, ".endif without .if");
                }
            }
            _ => return false,
        }
        true
    }

    /// A `.sched` block's lines with its conditionals resolved and its macro calls expanded
    /// (the scheduler sees only instructions, labels and `.irp`), so that one macro can serve
    /// several blocks and a block can differ by a symbol. Conditionals are resolved before
    /// the block's `.irp`, so they cannot test its parameters.
    fn sched_macros(&mut self, body: &[Line], depth: usize) -> Vec<Line> {
        let mut out = Vec::new();
        // Per open conditional: (this branch is assembled, some branch was taken).
        let mut cond: Vec<(bool, bool)> = Vec::new();
        for l in body {
            let text = strip_comment(&l.text);
            let text = text.trim();
            let (word, args) = match text.find(char::is_whitespace) {
                Some(p) => (&text[..p], text[p..].trim()),
                None => (text, ""),
            };
            let word_lower = word.to_ascii_lowercase();
            if self.conditional(&mut cond, &word_lower, args, l) {
                continue;
            }
            if !cond.iter().all(|c| c.0) {
                continue;
            }
            match self.macros.get(&word_lower).cloned() {
                Some(m) if depth < 16 => {
                    let lines = self.macro_lines(&m, args, l);
                    out.extend(self.sched_macros(&lines, depth + 1));
                }
                _ => out.push(l.clone()),
            }
        }
        if !cond.is_empty() {
            if let Some(l) = body.last() {
                self.diag(Severity::Error, l, 1, "missing .endif in the .sched block");
            }
        }
        out
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

    /// The subsection number after `.text`, `.data`, `.bss`, `.subsection` (0 if none).
    fn subsection(&mut self, args: &str, line: &Line, col: usize) -> i64 {
        if args.trim().is_empty() {
            return 0;
        }
        match self.eval(args.trim()) {
            Ok((v, _)) => v,
            Err((c, m)) => {
                self.diag(Severity::Error, line, col + c, m);
                0
            }
        }
    }

    /// `.section NAME[, "FLAGS"[, @TYPE[, ENTSIZE]]]` (also `%type`), or `NAME, SUBSECTION`.
    fn section_args(&mut self, args: &str, line: &Line, col: usize) -> Option<(SectionDef, i64)> {
        let parts = split_top(args, ',');
        let name = parts[0].trim().trim_matches('"').to_string();
        if name.is_empty() {
            self.diag(Severity::Error, line, col, "missing name");
            return None;
        }
        let mut def = SectionDef::named(&name);
        let mut sub = 0;
        if let Some(flags) = parts.get(1).map(|f| f.trim()) {
            if let Some(letters) = flags.strip_prefix('"').and_then(|f| f.strip_suffix('"')) {
                let mut f = 0;
                for c in letters.chars() {
                    match c {
                        'a' => f |= SHF_ALLOC,
                        'w' => f |= SHF_WRITE,
                        'x' => f |= SHF_EXECINSTR,
                        'M' => f |= 0x10,
                        'S' => f |= 0x20,
                        'G' => f |= 0x200,
                        'T' => f |= 0x400,
                        'o' => f |= 0x80,
                        'e' | 'R' | 'd' | '?' => {}
                        other => {
                            self.diag(
                                Severity::Error,
                                line,
                                col,
                                format!("unknown section attribute `{other}'"),
                            );
                            return None;
                        }
                    }
                }
                def.flags = f;
            } else if !flags.is_empty() && !flags.starts_with(['#', '@', '%']) {
                // `.section NAME, SUBSECTION` (the non-ELF form gas also takes).
                sub = self.subsection(flags, line, col);
            }
        }
        if let Some(ty) = parts.get(2).map(|t| t.trim()) {
            match ty.trim_start_matches(['@', '%']) {
                "progbits" => def.ty = SHT_PROGBITS,
                "nobits" => def.ty = SHT_NOBITS,
                "note" => def.ty = 7,
                "init_array" => def.ty = 14,
                "fini_array" => def.ty = 15,
                "preinit_array" => def.ty = 16,
                other => {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unrecognized section type `{other}'"),
                    );
                    return None;
                }
            }
        }
        if let Some(e) = parts.get(3) {
            if def.flags & 0x10 != 0 {
                def.entsize = self.eval(e.trim()).map(|v| v.0 as u64).unwrap_or(0);
            }
        }
        if let Some(existing) = self.defs.iter().find(|d| d.name == name).cloned() {
            // Re-entering a section keeps what it was declared with.
            if parts.len() > 1 && existing != def && self.pass == 1 {
                self.diag(
                    Severity::Warning,
                    line,
                    col,
                    format!("ignoring changed section attributes for {name}"),
                );
            }
            def = existing;
        }
        Some((def, sub))
    }

    /// `.lcomm NAME, SIZE[, ALIGN]` reserves space in `.bss`; `.comm` does too in an
    /// executable, and leaves a common symbol for the linker in an object.
    fn common(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        let parts = split_top(args, ',');
        let name = parts[0].trim().to_string();
        if name.is_empty() || parts.len() < 2 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("expected NAME, SIZE after {d}"),
            );
            return;
        }
        if d == ".lcomm" && parts.len() > 2 {
            // spu-elf-as 2.40's .lcomm takes no alignment.
            self.diag(
                Severity::Error,
                line,
                col,
                "junk at end of line, first unrecognized character is `,'",
            );
            return;
        }
        let size = self
            .data_values(&parts[1], line, col)
            .first()
            .copied()
            .unwrap_or(0);
        if !(0..=LOCAL_STORE as i64).contains(&size) {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("{d} length ({size}) out of range"),
            );
            return;
        }
        // gas TC_IMPLICIT_LCOMM_ALIGNMENT: the largest of 8, 4, 2 that the size reaches.
        let implicit = match size {
            8.. => 8,
            4..=7 => 4,
            2..=3 => 2,
            _ => 1,
        };
        let align = match parts.get(2) {
            Some(a) => self.data_values(a, line, col).first().copied().unwrap_or(1),
            None => implicit,
        };
        if align <= 0 || align & (align - 1) != 0 || align > 1 << 15 {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("alignment {align} is not a power of 2"),
            );
            return;
        }
        if d == ".comm" {
            self.attrs.entry(name.clone()).or_default().global = true;
            if self.object {
                if matches!(self.symbols.get(&name), Some(SymVal::Label(..))) {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("symbol `{name}' is already defined"),
                    );
                    return;
                }
                self.symbols
                    .insert(name, SymVal::Common(size as u32, align as u32));
                return;
            }
        }
        let here = self.sect;
        let bss = self.chunk(SectionDef::named(".bss"), 0);
        self.sect = bss;
        self.align_to(align as u32, Some(0));
        self.define_label(&name, line);
        self.emit(&vec![0; size as usize]);
        self.sect = here;
    }

    /// `.org EXPR` and `. = EXPR`: move forward to an offset in the current section.
    fn org(&mut self, expr: &str, fill: u8, line: &Line, col: usize) {
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

    /// Where the section of chunk `c` starts (its first chunk's base).
    fn section_start(&self, c: Sect) -> i64 {
        let d = self.chunks[c].0;
        (0..self.chunks.len())
            .filter(|&k| self.chunks[k].0 == d)
            .map(|k| self.bases.get(&k).copied().unwrap_or(0))
            .min()
            .unwrap_or(0) as i64
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
        let pattern = match parts.get(1).map(|p| p.trim()).filter(|p| !p.is_empty()) {
            Some(p) => Some(self.data_values(p, line, col).first().copied().unwrap_or(0)),
            None => None,
        };
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
    /// object for the linker, in an executable to be applied once all bytes are there.
    fn add_reloc(&mut self, sect: Sect, offset: u32, kind: u32, v: &Val, line: &Line, col: usize) {
        let def = self.chunks[sect].0;
        let (target, addend) = if let Some((name, value)) = &v.sym {
            (RelocTarget::Symbol(name.to_string()), v.v - value)
        } else if let Some(s) = v.sect {
            (
                RelocTarget::Section(s),
                v.v - if self.object { 0 } else { self.def_start(s) },
            )
        } else if v.reloc || v.cross {
            self.diag(
                Severity::Error,
                line,
                col,
                "expression too complex for a relocation",
            );
            return;
        } else {
            (RelocTarget::Section(usize::MAX), v.v)
        };
        let location = Location {
            file: line.file.clone(),
            line: line.line,
            column: col.max(1),
        };
        self.relocs.push((
            def,
            Reloc {
                offset,
                kind,
                target,
                addend,
            },
            location,
            line.text.clone(),
        ));
    }

    /// Where section definition `d` starts (executables).
    fn def_start(&self, d: usize) -> i64 {
        (0..self.chunks.len())
            .filter(|&k| self.chunks[k].0 == d)
            .map(|k| self.bases.get(&k).copied().unwrap_or(0))
            .min()
            .unwrap_or(0) as i64
    }

    fn directive(&mut self, d: &str, args: &str, line: &Line, col: usize) {
        match d {
            ".text" | ".data" | ".bss" | ".rodata" => {
                let sub = self.subsection(args, line, col);
                let c = self.chunk(SectionDef::named(d), sub);
                self.switch_to(c);
            }
            ".subsection" => {
                let sub = self.subsection(args, line, col);
                let def = self.defs[self.chunks[self.sect].0].clone();
                let c = self.chunk(def, sub);
                self.switch_to(c);
            }
            ".section" | ".pushsection" => {
                let Some((def, sub)) = self.section_args(args, line, col) else {
                    return;
                };
                if d == ".pushsection" {
                    self.sect_stack.push((self.sect, self.prev_sect));
                }
                let c = self.chunk(def, sub);
                self.switch_to(c);
            }
            ".popsection" => match self.sect_stack.pop() {
                Some((s, p)) => {
                    self.sect = s;
                    self.prev_sect = p;
                }
                None => self.diag(
                    Severity::Warning,
                    line,
                    col,
                    ".popsection without corresponding .pushsection; ignored",
                ),
            },
            ".previous" => {
                std::mem::swap(&mut self.sect, &mut self.prev_sect);
            }
            ".lcomm" | ".comm" => self.common(d, args, line, col),
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
            ".weak" | ".hidden" | ".internal" | ".protected" | ".global" | ".globl" => {
                for n in split_top(args, ',') {
                    let n = n.trim();
                    if n.is_empty() {
                        continue;
                    }
                    let a = self.attrs.entry(n.to_string()).or_default();
                    match d {
                        ".weak" => a.weak = true,
                        ".global" | ".globl" => a.global = true,
                        _ => a.hidden = true,
                    }
                }
            }
            ".type" => {
                let parts = split_top(args, ',');
                let name = parts[0].trim().to_string();
                let kind = parts.get(1).map(|k| {
                    k.trim()
                        .trim_start_matches(['@', '%', '#'])
                        .to_ascii_lowercase()
                });
                let kind = match kind.as_deref() {
                    Some("function" | "stt_func") => 2,
                    Some("object" | "stt_object") => 1,
                    Some("notype" | "stt_notype") => 0,
                    Some("tls_object" | "stt_tls") => 6,
                    Some("common" | "stt_common") => 5,
                    _ => {
                        self.diag(
                            Severity::Error,
                            line,
                            col,
                            format!(
                                "unrecognized symbol type \"{}\"",
                                parts.get(1).map_or("", |s| s.trim())
                            ),
                        );
                        return;
                    }
                };
                self.attrs.entry(name).or_default().kind = kind;
            }
            ".size" => {
                let parts = split_top(args, ',');
                if parts.len() < 2 {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        "expected comma after name in .size",
                    );
                    return;
                }
                let name = parts[0].trim().to_string();
                match self.eval_val(parts[1..].join(",").trim()) {
                    Ok((v, _, _)) if !v.reloc || self.pass == 1 => {
                        self.attrs.entry(name).or_default().size = Some(v.v)
                    }
                    Ok(_) => {} // a size that depends on an address: gas keeps an expression; we drop it
                    Err((c, m)) => self.diag(Severity::Error, line, col + c, m),
                }
            }
            ".reloc" => self.reloc_directive(args, line, col),
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
            // Any number is a register here; one past 127 is reported as out of range.
            let n: i64 = q[..digits].parse().unwrap_or(i64::MAX);
            return Some((n, &q[digits..]));
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
                if !(0..128).contains(&v) {
                    return Err(CalcErr::Range(
                        at(p),
                        format!("register number {v} out of range [0, 127]"),
                    ));
                }
                p = rest
                    .trim_start()
                    .strip_prefix(')')
                    .ok_or(CalcErr::Syntax(i))?;
                out.push(Operand::Reg(kind, v));
            } else if kind.is_register() {
                let (v, rest) = self.get_reg(p, kind, true).ok_or(CalcErr::Syntax(i))?;
                // gas ORs an expression's value in unmasked; a value outside the 7-bit
                // field would silently change other fields, so it is an error here.
                if !(0..128).contains(&v) {
                    let what = match kind {
                        OperandKind::Ch => "channel",
                        OperandKind::Spr => "special-purpose register",
                        _ => "register",
                    };
                    return Err(CalcErr::Range(
                        col,
                        format!("{what} number {v} out of range [0, 127]"),
                    ));
                }
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
        if mnemonic == "nop" && !split_top(args, ',').iter().skip(1).any(|_| true) {
            // GNU as for SPU reads pseudo-ops without their dot, and `nop` is gas's `.nop`:
            // the target's no-op word whatever the operand (`nop $41` is 0x40200000, as
            // spu-elf-as 2.40 writes it).
            self.emit(&0x4020_0000u32.to_be_bytes());
            return;
        }
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
        let mut range_failure: Option<(usize, String)> = None;
        let mut parsed = None;
        for form in &forms {
            match self.calcop(form, param) {
                Ok(ops) => {
                    parsed = Some((*form, ops));
                    break;
                }
                Err(CalcErr::Syntax(arg)) => failure = (form, arg),
                // Another form may take this operand as something else (`hgti $3,-16`
                // is the two-operand form); reported only if no form fits.
                Err(CalcErr::Range(c, m)) => {
                    range_failure.get_or_insert((c, m));
                }
                Err(CalcErr::Hard(c, m)) => {
                    self.diag(Severity::Error, line, arg_col + c, m);
                    self.emit(&[0; 4]);
                    return;
                }
            }
        }
        let Some((form, ops)) = parsed else {
            if let Some((c, m)) = range_failure {
                self.diag(Severity::Error, line, arg_col + c, m);
                self.emit(&[0; 4]);
                return;
            }
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
                    if self.object && self.pass == 2 && (val.reloc || val.cross) {
                        match self.object_immediate(form.format, kind, val, high, low, pc) {
                            Ok(Some(bits)) => word |= bits,
                            Ok(None) => {
                                let sect = self.sect;
                                let at = pc - self.section_start(sect) as u32;
                                let rk = reloc_kind(kind, form.format, high, low);
                                match (rk, self.pending.take()) {
                                    (Some(rk), Some(v)) => {
                                        self.add_reloc(sect, at, rk, &v, line, arg_col + c)
                                    }
                                    _ => self.diag(
                                        Severity::Error,
                                        line,
                                        arg_col + c,
                                        "no SPU relocation for this operand",
                                    ),
                                }
                            }
                            Err(m) => self.diag(Severity::Error, line, arg_col + c, m),
                        }
                        continue;
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

    /// An operand that depends on an address, in an object: a PC-relative reference to a
    /// local label of this very section is resolved now (as gas's `fixup_segment` does);
    /// anything else is left in `pending` for a relocation.
    fn object_immediate(
        &mut self,
        format: Format,
        kind: OperandKind,
        val: Val,
        high: bool,
        low: bool,
        pc: u32,
    ) -> Result<Option<u32>, String> {
        let pcrel = matches!(kind, OperandKind::Rel18 | OperandKind::BrInst);
        let here = self.chunks[self.sect].0;
        let weak = val
            .sym
            .as_ref()
            .is_some_and(|(n, _)| self.attrs.get(&**n).is_some_and(|a| a.weak));
        if val.cross || (val.sect.is_none() && val.sym.is_none()) {
            return Err("expression too complex for a relocation".into());
        }
        // Only references to local labels are resolved: gas leaves a relocation for a
        // global or weak symbol even in the same section (checked with spu-elf-as 2.40).
        if pcrel && val.sect == Some(here) && val.sym.is_none() && !weak && !high && !low {
            let local = Val { sym: None, ..val };
            return self
                .immediate(format, kind, local, false, false, pc)
                .map(|(bits, _)| Some(bits));
        }
        self.pending = Some(val);
        Ok(None)
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

/// A macro or `.irp` argument as gas's `get_any_string` takes it: a double-quoted
/// argument is its text without the quotes (so it may hold commas and spaces).
fn macro_argument(arg: &str) -> String {
    let quoted = arg.len() >= 2 && arg.starts_with('"') && arg.ends_with('"');
    if quoted && !arg[1..arg.len() - 1].contains('"') {
        return arg[1..arg.len() - 1].to_string();
    }
    // `name="value"` for a keyword argument.
    if let Some((name, value)) = arg.split_once('=') {
        let v = value.trim();
        if v.len() >= 2
            && v.starts_with('"')
            && v.ends_with('"')
            && !v[1..v.len() - 1].contains('"')
        {
            return format!("{name}={}", &v[1..v.len() - 1]);
        }
    }
    arg.to_string()
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

/// The SPU relocation gas's `arg_encode` table gives an immediate operand.
fn reloc_kind(kind: OperandKind, format: Format, high: bool, low: bool) -> Option<u32> {
    use crate::reloc::*;
    use OperandKind::*;
    if high {
        return Some(R_SPU_ADDR16_HI);
    }
    if low {
        return Some(R_SPU_ADDR16_LO);
    }
    Some(match kind {
        S3 | S6 | S7 | S7n | U3 | U5 | U6 | U7 => R_SPU_ADDR7,
        S10b | S10 => R_SPU_ADDR10I,
        Off14 => R_SPU_ADDR10,
        S16 | X16 => R_SPU_ADDR16I,
        Abs18 => R_SPU_ADDR16,
        Rel18 => R_SPU_REL16,
        U18 => R_SPU_ADDR18,
        BrInst if format == Format::LBTI => R_SPU_REL9I,
        BrInst => R_SPU_REL9,
        _ => return None,
    })
}

fn unquote(s: &str) -> Option<Vec<u8>> {
    let inner = s.strip_prefix('"')?.strip_suffix('"')?;
    let mut out = Vec::new();
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        if c != '\\' {
            // Source characters are bytes (see `bytes_as_text`).
            out.push(c as u32 as u8);
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

/// The directive a line's first word names for block and conditional handling: itself
/// lower-cased, with the dot added when written without one (`rept`, `endr`, `if`), as gas
/// for SPU reads pseudo-ops, unless it is a macro or an instruction.
fn block_word(word: &str, macros: &HashMap<String, Macro>) -> String {
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

fn collect_block(lines: &[Line], start: usize) -> (Vec<Line>, usize) {
    let mut depth = 1;
    let mut i = start;
    let no_macros = HashMap::new();
    while i < lines.len() {
        let text = strip_comment(&lines[i].text);
        let w = block_word(
            text.trim().split_whitespace().next().unwrap_or(""),
            &no_macros,
        );
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

/// Source text as gas reads it: bytes, each one character (so Latin-1 and UTF-8 text in
/// comments and strings pass through byte for byte).
fn bytes_as_text(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

/// A line of byte-characters back as text for a diagnostic (UTF-8 if it is, else Latin-1).
fn display_text(text: &str) -> String {
    let bytes: Vec<u8> = text.chars().map(|c| c as u32 as u8).collect();
    String::from_utf8(bytes).unwrap_or_else(|_| text.to_string())
}

/// The most bytes a source or included file may have.
pub const MAX_SOURCE: u64 = 64 << 20;

/// Reads a source file with a size limit.
pub(crate) fn read_source(path: &std::path::Path) -> Result<String, String> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    file.take(MAX_SOURCE + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > MAX_SOURCE {
        return Err(format!("larger than {} MiB", MAX_SOURCE >> 20));
    }
    Ok(bytes_as_text(&bytes))
}

impl<'o> Assembler<'o> {
    fn new(opts: &'o Options, object: bool) -> Assembler<'o> {
        let mut asm = Assembler {
            opts,
            pass: 1,
            sect: 0,
            prev_sect: 0,
            sect_stack: Vec::new(),
            defs: Vec::new(),
            chunks: Vec::new(),
            object,
            relocs: Vec::new(),
            attrs: HashMap::new(),
            expanded: 0,
            seen_diags: Default::default(),
            dropped_diags: 0,
            pending: None,
            defined: Default::default(),
            nonzero_in_nobits: false,
            offsets: HashMap::new(),
            align: HashMap::new(),
            bases: HashMap::new(),
            symbols: HashMap::new(),
            pass1_symbols: HashMap::new(),
            numeric: HashMap::new(),
            numeric_next: HashMap::new(),
            stmt: 0,
            bytes: HashMap::new(),
            diags: Vec::new(),
            macros: HashMap::new(),
            macro_counter: 0,
            listing: String::new(),
            depth: 0,
            macro_depth: 0,
            exitm: false,
            schedules: HashMap::new(),
        };
        // gas always has .text, .data and .bss, in that order.
        for name in [".text", ".data", ".bss"] {
            asm.chunk(SectionDef::named(name), 0);
        }
        asm
    }

    /// One walk over the source: `pass` 1 lays out (unknown symbols read as 0), pass 2
    /// emits with every address known.
    fn run_pass(&mut self, lines: &[Line], pass: u8) {
        self.pass = pass;
        self.sect = 0;
        self.prev_sect = 0;
        self.sect_stack.clear();
        self.offsets.clear();
        self.stmt = 0;
        self.macros.clear();
        self.macro_counter = 0;
        self.expanded = 0;
        self.exitm = false;
        self.defined.clear();
        if pass == 2 {
            self.bytes.clear();
            self.relocs.clear();
            self.listing.clear();
        }
        // Labels keep the values of the previous walk (forward references); `.set`
        // symbols are defined again in order, earlier ones read from the previous walk.
        let labels: HashMap<String, SymVal> = self
            .symbols
            .iter()
            .filter(|(_, v)| matches!(v, SymVal::Label(..)))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if !self.symbols.is_empty() {
            self.pass1_symbols = std::mem::replace(&mut self.symbols, labels);
        }
        for (n, v) in &self.opts.defines {
            self.symbols.insert(n.clone(), SymVal::Abs(Val::abs(*v)));
        }
        self.run_lines(lines);
        self.finish_sections();
        if pass == 1 {
            self.numeric = std::mem::take(&mut self.numeric_next);
        }
    }

    /// Gives every chunk its address: in an executable, code sections from 0, then
    /// read-only data, data and bss, each section at its alignment (at least 16) and its
    /// subsections in order; in an object, offsets within each section.
    fn lay_out(&mut self) {
        let class = |d: &SectionDef| crate::link::placement(&d.name, d.ty, d.flags).0;
        let mut order: Vec<usize> = (0..self.defs.len()).collect();
        order.sort_by_key(|&d| {
            let def = &self.defs[d];
            (crate::link::placement(&def.name, def.ty, def.flags), d)
        });
        let mut addr = 0u32;
        self.bases.clear();
        for d in order {
            let mut chunks: Vec<Sect> = (0..self.chunks.len())
                .filter(|&c| self.chunks[c].0 == d)
                .collect();
            chunks.sort_by_key(|&c| self.chunks[c].1);
            let align = chunks
                .iter()
                .map(|c| self.align.get(c).copied().unwrap_or(1))
                .max()
                .unwrap_or(1);
            let mut at = if self.object || class(&self.defs[d]) == 4 {
                0
            } else {
                addr.div_ceil(align.max(16)) * align.max(16)
            };
            // Subsections follow one another directly (their padding is to addresses).
            for c in chunks {
                self.bases.insert(c, at);
                at = at.saturating_add(self.offsets.get(&c).copied().unwrap_or(0));
            }
            if !self.object && class(&self.defs[d]) != 4 {
                addr = at;
            }
        }
    }

    /// Label addresses, for checking that layout has settled.
    fn label_values(&self) -> Vec<(String, i64)> {
        let mut v: Vec<(String, i64)> = self
            .symbols
            .iter()
            .filter(|(_, s)| matches!(s, SymVal::Label(..)))
            .map(|(n, s)| (n.clone(), self.value_of(n, s).v))
            .collect();
        v.sort();
        v
    }

    /// Lays out until addresses stop changing (sizes can depend on later symbols:
    /// `.org`, `.uleb128`, `.space`), then emits.
    fn assemble_lines(&mut self, lines: &[Line]) {
        let mut previous = None;
        for _ in 0..6 {
            self.run_pass(lines, 1);
            self.lay_out();
            let now = (
                self.label_values(),
                self.bases.clone(),
                self.offsets.clone(),
            );
            if previous.as_ref() == Some(&now) {
                break;
            }
            previous = Some(now);
            if self.diags.iter().any(|d| d.severity == Severity::Error) {
                break;
            }
        }
        if self.expanded > MAX_EXPANDED {
            return; // reported by the layout walk; a second walk would only repeat it
        }
        self.run_pass(lines, 2);
        if self.nonzero_in_nobits {
            self.diags.push(Diagnostic {
                severity: Severity::Error,
                location: Location {
                    file: lines.first().map(|l| l.file.clone()).unwrap_or_default(),
                    line: 0,
                    column: 0,
                },
                message: "attempt to store non-zero value in a NOBITS section (.bss)".into(),
                source_line: String::new(),
            });
        }
    }

    /// Errors (and warnings) sorted by place, with the count of those left out.
    fn take_diagnostics(&mut self) -> (Vec<Diagnostic>, Vec<Diagnostic>) {
        let diags = std::mem::take(&mut self.diags);
        let (mut errors, warnings): (Vec<_>, Vec<_>) = diags
            .into_iter()
            .partition(|d| d.severity == Severity::Error);
        if !errors.is_empty() {
            errors.extend(warnings.iter().cloned());
            errors.sort_by(|a, b| {
                (&a.location.file, a.location.line, a.location.column).cmp(&(
                    &b.location.file,
                    b.location.line,
                    b.location.column,
                ))
            });
        }
        if self.dropped_diags > 0 {
            let last = errors
                .last()
                .or(warnings.last())
                .map(|d| d.location.clone());
            let note = Diagnostic {
                severity: if errors.is_empty() {
                    Severity::Warning
                } else {
                    Severity::Error
                },
                location: last.unwrap_or(Location {
                    file: String::new(),
                    line: 0,
                    column: 0,
                }),
                message: format!("and {} more diagnostics", self.dropped_diags),
                source_line: String::new(),
            };
            errors.push(note);
            if errors.iter().all(|d| d.severity == Severity::Warning) {
                let w = errors;
                return (Vec::new(), w);
            }
        }
        (errors, warnings)
    }
}

/// Assembles `source` (named `file_name` in diagnostics) into an executable image at 0.
pub fn assemble(source: &str, file_name: &str, opts: &Options) -> Result<Output, Vec<Diagnostic>> {
    assemble_chars(&bytes_as_text(source.as_bytes()), file_name, opts)
}

/// `assemble` of a source whose characters are its bytes (`bytes_as_text`).
pub(crate) fn assemble_chars(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<Output, Vec<Diagnostic>> {
    let lines = to_lines(source, file_name);
    let mut asm = Assembler::new(opts, false);
    asm.assemble_lines(&lines);
    let (errors, warnings) = asm.take_diagnostics();
    if !errors.is_empty() {
        return Err(errors);
    }
    let fail = |message: String| {
        vec![Diagnostic {
            severity: Severity::Error,
            location: Location {
                file: file_name.into(),
                line: 1,
                column: 1,
            },
            message,
            source_line: lines
                .first()
                .map(|l| display_text(&l.text))
                .unwrap_or_default(),
        }]
    };
    // Sections in address order: (definition, address, size).
    let mut placed: Vec<(usize, u32, u32)> = Vec::new();
    for d in 0..asm.defs.len() {
        if asm.defs[d].flags & SHF_ALLOC == 0 {
            continue;
        }
        let chunks: Vec<Sect> = (0..asm.chunks.len())
            .filter(|&c| asm.chunks[c].0 == d)
            .collect();
        let start = chunks.iter().map(|c| asm.bases[c]).min().unwrap_or(0);
        let end = chunks
            .iter()
            .map(|c| asm.bases[c] + asm.offsets.get(c).copied().unwrap_or(0))
            .max()
            .unwrap_or(0);
        placed.push((d, start, end - start));
    }
    placed.sort_by_key(|p| (p.1, p.0));
    let end = placed.iter().map(|p| p.1 + p.2).max().unwrap_or(0);
    if end as usize > LOCAL_STORE {
        return Err(fail(format!(
            "program of {end} bytes does not fit the 256 KiB local store"
        )));
    }
    let mut image = vec![0u8; end as usize];
    for c in 0..asm.chunks.len() {
        if let Some(b) = asm.bytes.get(&c) {
            let at = asm.bases[&c] as usize;
            if asm.defs[asm.chunks[c].0].flags & SHF_ALLOC != 0 {
                image[at..at + b.len()].copy_from_slice(b);
            }
        }
    }
    // `.reloc` in an executable: applied now that every address is known.
    let mut reloc_errors = Vec::new();
    for (def, r, loc, text) in &asm.relocs {
        let start = placed.iter().find(|p| p.0 == *def).map_or(0, |p| p.1);
        let s = match &r.target {
            RelocTarget::Section(usize::MAX) => 0,
            RelocTarget::Section(t) => placed.iter().find(|p| p.0 == *t).map_or(0, |p| p.1) as i64,
            RelocTarget::Symbol(n) => asm.symbol_address(n).unwrap_or(0),
        };
        let at = start + r.offset;
        if let Err(m) = crate::reloc::apply(r.kind, &mut image, at, s + r.addend) {
            reloc_errors.push(Diagnostic {
                severity: Severity::Error,
                location: loc.clone(),
                message: m,
                source_line: display_text(text),
            });
        }
    }
    if !reloc_errors.is_empty() {
        return Err(reloc_errors);
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
    let sections: Vec<(String, u32, u32, bool)> = placed
        .iter()
        .map(|&(d, a, size)| {
            let def = &asm.defs[d];
            (def.name.clone(), a, size, def.flags & SHF_EXECINSTR != 0)
        })
        .collect();
    let globals: Vec<String> = asm
        .attrs
        .iter()
        .filter(|(_, a)| a.global)
        .map(|(n, _)| n.clone())
        .collect();
    let nobits: Vec<bool> = placed
        .iter()
        .map(|p| asm.defs[p.0].ty == SHT_NOBITS)
        .collect();
    let elf = crate::elf::write_elf(&image, &sections, &nobits, &symbols, &globals, entry);
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

/// Assembles `source` into a relocatable object: every section at offset 0, references
/// to addresses left as SPU relocations, undefined symbols external.
pub fn assemble_object(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<(crate::object::Object, Vec<Diagnostic>), Vec<Diagnostic>> {
    assemble_object_chars(&bytes_as_text(source.as_bytes()), file_name, opts)
}

/// `assemble_object` of a source whose characters are its bytes.
pub(crate) fn assemble_object_chars(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<(crate::object::Object, Vec<Diagnostic>), Vec<Diagnostic>> {
    use crate::object::{ObjSection, ObjSymbol, SymSection};
    let lines = to_lines(source, file_name);
    let mut asm = Assembler::new(opts, true);
    asm.assemble_lines(&lines);
    let (errors, warnings) = asm.take_diagnostics();
    if !errors.is_empty() {
        return Err(errors);
    }
    let mut obj = crate::object::Object {
        name: file_name.to_string(),
        ..Default::default()
    };
    for (d, def) in asm.defs.iter().enumerate() {
        let mut chunks: Vec<Sect> = (0..asm.chunks.len())
            .filter(|&c| asm.chunks[c].0 == d)
            .collect();
        chunks.sort_by_key(|&c| asm.chunks[c].1);
        let size = chunks
            .iter()
            .map(|c| asm.bases[c] + asm.offsets.get(c).copied().unwrap_or(0))
            .max()
            .unwrap_or(0);
        let mut data = Vec::new();
        if def.ty != SHT_NOBITS {
            data = vec![0u8; size as usize];
            for c in &chunks {
                if let Some(b) = asm.bytes.get(c) {
                    let at = asm.bases[c] as usize;
                    data[at..at + b.len()].copy_from_slice(b);
                }
            }
        }
        let align = chunks
            .iter()
            .map(|c| asm.align.get(c).copied().unwrap_or(1))
            .max()
            .unwrap_or(1);
        obj.sections.push(ObjSection {
            name: def.name.clone(),
            ty: def.ty,
            flags: def.flags,
            entsize: def.entsize,
            align,
            size,
            data,
            relocs: Vec::new(),
        });
    }
    for (d, r, _, _) in &asm.relocs {
        let mut r = r.clone();
        if r.target == RelocTarget::Section(usize::MAX) {
            // An absolute value: against no symbol.
            r.target = RelocTarget::Symbol(String::new());
        }
        obj.sections[*d].relocs.push(r);
    }
    let mut names: Vec<&String> = asm.symbols.keys().collect();
    names.sort();
    let mut referenced: std::collections::BTreeSet<String> = Default::default();
    for s in &obj.sections {
        for r in &s.relocs {
            if let RelocTarget::Symbol(n) = &r.target {
                if !n.is_empty() {
                    referenced.insert(n.clone());
                }
            }
        }
    }
    for name in names {
        let attrs = asm.attrs.get(name).cloned().unwrap_or_default();
        let (section, value) = match &asm.symbols[name] {
            SymVal::Label(c, off) => (
                SymSection::Section(asm.chunks[*c].0),
                (asm.bases[c] + off) as u64,
            ),
            SymVal::Common(size, align) => {
                obj.symbols.push(ObjSymbol {
                    name: name.clone(),
                    value: *align as u64,
                    size: *size as u64,
                    section: SymSection::Common,
                    global: true,
                    weak: false,
                    hidden: attrs.hidden,
                    kind: 1,
                });
                continue;
            }
            SymVal::Abs(v) if v.sect.is_some() && v.sym.is_none() => {
                (SymSection::Section(v.sect.unwrap_or(0)), v.v as u64)
            }
            SymVal::Abs(v) if !v.reloc && !v.cross => (SymSection::Absolute, v.v as u64),
            SymVal::Abs(_) => continue,
        };
        // Local labels named `.L` stay out of the symbol table, as in gas.
        if name.starts_with(".L") && !attrs.global {
            continue;
        }
        obj.symbols.push(ObjSymbol {
            name: name.clone(),
            value,
            size: attrs.size.unwrap_or(0) as u64,
            section,
            global: attrs.global || attrs.weak,
            weak: attrs.weak,
            hidden: attrs.hidden,
            kind: attrs.kind,
        });
    }
    for name in referenced {
        if !asm.symbols.contains_key(&name) {
            let attrs = asm.attrs.get(&name).cloned().unwrap_or_default();
            obj.symbols.push(ObjSymbol {
                name,
                value: 0,
                size: 0,
                section: SymSection::Undefined,
                global: true,
                weak: attrs.weak,
                hidden: attrs.hidden,
                kind: attrs.kind,
            });
        }
    }
    Ok((obj, warnings))
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
