//! DWARF line numbers (gas's `dwarf2dbg.c`): `.file N "name"`, `.loc` and
//! `.loc_mark_labels` record rows of the line table as instructions are emitted, and an
//! object gets the `.debug_line` GNU as 2.40 writes for spu-elf from them: version 3 (gas's
//! `dwarf_level` is 3 unless `--gdwarf-N` says otherwise, and `.file 0`/`.loc 0`, which
//! would raise it to 5, are refused here), minimum instruction length 1 (tc-spu.h does not
//! define `DWARF2_LINE_MIN_INSN_LENGTH`), line_base -5, line_range 14, opcode_base 13, one
//! sequence per code section in the order the sections got their first row, each opened by
//! `DW_LNE_set_address` with an `R_SPU_ADDR32` relocation against the section.

use super::read::leb128;
use super::{Assembler, Line, Sect, Severity};
use crate::expr::Val;
use crate::lex::unquote;
use crate::object::{Reloc, RelocTarget, SHF_ALLOC, SHF_EXECINSTR, SHT_NOBITS};
use std::collections::HashMap;

/// The `.debug_line` version gas 2.40 writes by default.
pub const LINE_VERSION: u16 = 3;
/// dwarf2dbg.c's `DWARF2_LINE_BASE`, `DWARF2_LINE_RANGE` and `DWARF2_LINE_OPCODE_BASE`
/// (version 3).
pub const LINE_BASE: i8 = -5;
pub const LINE_RANGE: u8 = 14;
pub const OPCODE_BASE: u8 = 13;
/// Operands of the standard opcodes 1..=12 (`DW_LNS_copy` .. `DW_LNS_set_isa`).
pub const STANDARD_OPCODE_LENGTHS: [u8; 12] = [0, 1, 1, 1, 1, 0, 0, 0, 1, 0, 0, 1];

/// The largest address advance a special opcode can carry (`MAX_SPECIAL_ADDR_DELTA`).
const MAX_SPECIAL_ADDR_DELTA: u64 = ((255 - OPCODE_BASE) / LINE_RANGE) as u64;

/// File numbers beyond this are refused: every slot below one in use must be declared,
/// and the table is held in memory.
const MAX_FILE_NUMBER: i64 = 65535;

const DW_LNS_COPY: u8 = 1;
const DW_LNS_ADVANCE_PC: u8 = 2;
const DW_LNS_ADVANCE_LINE: u8 = 3;
const DW_LNS_SET_FILE: u8 = 4;
const DW_LNS_SET_COLUMN: u8 = 5;
const DW_LNS_NEGATE_STMT: u8 = 6;
const DW_LNS_SET_BASIC_BLOCK: u8 = 7;
const DW_LNS_CONST_ADD_PC: u8 = 8;
const DW_LNS_SET_PROLOGUE_END: u8 = 10;
const DW_LNS_SET_EPILOGUE_BEGIN: u8 = 11;
const DW_LNS_SET_ISA: u8 = 12;
const DW_LNE_END_SEQUENCE: u8 = 1;
const DW_LNE_SET_ADDRESS: u8 = 2;
const DW_LNE_SET_DISCRIMINATOR: u8 = 4;

/// The location the next row gets (dwarf2dbg.c's `current`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Loc {
    file: u32,
    line: u32,
    column: u32,
    isa: u32,
    discriminator: u32,
    is_stmt: bool,
    basic_block: bool,
    prologue_end: bool,
    epilogue_begin: bool,
}

impl Default for Loc {
    fn default() -> Loc {
        Loc {
            file: 1,
            line: 1,
            column: 0,
            isa: 0,
            discriminator: 0,
            is_stmt: true,
            basic_block: false,
            prologue_end: false,
            epilogue_begin: false,
        }
    }
}

/// One row: where in which chunk, and the location it gives that address.
#[derive(Clone, Debug)]
struct Row {
    chunk: Sect,
    offset: u32,
    loc: Loc,
    /// `-g`: the source file, numbered when the table is written (`do_allocate_filenum`).
    generated: Option<Vec<u8>>,
    /// Its view number: 0 where the address moved on from the chunk's previous row.
    view: u32,
}

/// The line-table state of one walk over the source.
#[derive(Clone, Debug, Default)]
pub(super) struct LineState {
    /// File slots (`.file N`): the name without its directory, and its directory index.
    files: Vec<Option<(Vec<u8>, u32)>>,
    /// Directory table; entry 0 (the compilation directory) is never written in version 3.
    dirs: Vec<Option<Vec<u8>>>,
    current: Loc,
    /// A `.loc` waits for the instruction it describes.
    loc_seen: bool,
    mark_labels: bool,
    rows: Vec<Row>,
    /// Where each section's contents end before gas pads the section to its alignment
    /// (`dwarf2_finish` runs before `subsegs_finish`): the end of its last sequence.
    pub(super) content_end: HashMap<usize, u32>,
    /// The last `.file N` line, where undeclared slots below a used one are reported.
    last_file_line: Option<Line>,
    /// A `.file N` was seen: `-g` rows are dropped and no more are made.
    compiler_lines: bool,
    /// `-g`: the source line of the last generated row (gas's `dw2_line`, `dw2_filename`).
    last_generated: Option<(String, usize)>,
    /// A `.loc` used `prologue_end`, `epilogue_begin` or `isa`, which raise gas's
    /// `dwarf_level` to 3 where `-g` had set it to 2.
    level3: bool,
}

/// A directive's operands read left to right, as gas's `input_line_pointer`.
struct Cursor<'a> {
    text: &'a str,
    at: usize,
}

impl<'a> Cursor<'a> {
    fn skip_space(&mut self) {
        while self.text[self.at..].starts_with([' ', '\t']) {
            self.at += 1;
        }
    }
    fn peek(&self) -> Option<char> {
        self.text[self.at..].chars().next()
    }
    /// The next whitespace-delimited token.
    fn token(&mut self) -> &'a str {
        self.skip_space();
        let rest = &self.text[self.at..];
        let len = rest.find([' ', '\t', '"']).unwrap_or(rest.len());
        self.at += len;
        &rest[..len]
    }
    /// The next name (letters, digits, `_`, `.`, `$`).
    fn name(&mut self) -> &'a str {
        let rest = &self.text[self.at..];
        let len = rest
            .find(|c: char| !(c.is_ascii_alphanumeric() || "_.$".contains(c)))
            .unwrap_or(rest.len());
        self.at += len;
        &rest[..len]
    }
    /// A double-quoted string with its escapes, as `demand_copy_C_string`.
    fn string(&mut self) -> Option<Vec<u8>> {
        self.skip_space();
        let rest = &self.text[self.at..];
        if !rest.starts_with('"') {
            return None;
        }
        let mut escaped = false;
        for (k, c) in rest.char_indices().skip(1) {
            match c {
                '\\' if !escaped => escaped = true,
                '"' if !escaped => {
                    self.at += k + 1;
                    return unquote(&rest[..=k]);
                }
                _ => escaped = false,
            }
        }
        None
    }
}

/// gas's `lbasename`, keeping a name of one separator and a file whole ("/a.c").
fn basename(path: &[u8]) -> usize {
    let file = path.iter().rposition(|&b| b == b'/').map_or(0, |p| p + 1);
    if file == 1 {
        0
    } else {
        file
    }
}

fn text(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| b as char).collect()
}

impl LineState {
    /// The directory index for `dir` (`get_directory_table_entry` without slot 0).
    fn directory(&mut self, dir: &[u8]) -> u32 {
        let dir = dir.strip_suffix(b"/").unwrap_or(dir);
        if dir.is_empty() {
            return 0;
        }
        if let Some(d) = self.dirs.iter().position(|d| d.as_deref() == Some(dir)) {
            return d as u32;
        }
        let d = self.dirs.len().max(1);
        self.dirs.resize(d + 1, None);
        self.dirs[d] = Some(dir.to_vec());
        d as u32
    }

    /// Slot `num` for `path` (`allocate_filename_to_slot`): a slot holds one file; naming
    /// it again with the same file is allowed.
    fn assign(&mut self, num: usize, path: &[u8]) -> Result<(), String> {
        let file = basename(path);
        if let Some(Some((name, dir))) = self.files.get(num) {
            let same = match self.dirs.get(*dir as usize).cloned().flatten() {
                Some(d) => {
                    path.len() > d.len()
                        && path.starts_with(&d)
                        && path[d.len()] == b'/'
                        && &path[d.len() + 1..] == name.as_slice()
                }
                None => &path[file..] == name.as_slice(),
            };
            if same {
                return Ok(());
            }
            let (d, sep) = match self.dirs.get(*dir as usize).cloned().flatten() {
                Some(d) => (text(&d), "/"),
                None => (String::new(), ""),
            };
            return Err(format!(
                "file table slot {num} is already occupied by a different file ({d}{sep}{} vs {})",
                text(name),
                text(path)
            ));
        }
        let dir = self.directory(&path[..file]);
        if self.files.len() <= num {
            self.files.resize(num + 1, None);
        }
        self.files[num] = Some((path[file..].to_vec(), dir));
        Ok(())
    }

    /// `-g`'s slot for a source path (`allocate_filenum`): the slot of the same
    /// directory and name, else the next free one.
    fn allocate(&mut self, path: &[u8]) -> u32 {
        let file = basename(path);
        let dir = self.directory(&path[..file]);
        let name = &path[file..];
        if let Some(i) = (1..self.files.len()).find(|&i| {
            self.files[i]
                .as_ref()
                .is_some_and(|(n, d)| *d == dir && n.as_slice() == name)
        }) {
            return i as u32;
        }
        let i = self.files.len().max(1);
        self.files.resize(i + 1, None);
        self.files[i] = Some((name.to_vec(), dir));
        i as u32
    }

    fn declared(&self, num: i64) -> bool {
        num >= 1 && matches!(self.files.get(num as usize), Some(Some(_)))
    }

    /// After a row is written (or a `.loc` is used up): the one-row flags go.
    fn consume(&mut self) {
        self.loc_seen = false;
        self.current.basic_block = false;
        self.current.prologue_end = false;
        self.current.epilogue_begin = false;
        self.current.discriminator = 0;
    }

    /// Whether any row was recorded: then an object has a `.debug_line`.
    pub(super) fn has_rows(&self) -> bool {
        !self.rows.is_empty()
    }
}

impl Assembler<'_> {
    /// A `.file`/`.loc` file number must be 1 or more (0 is DWARF 5's); otherwise an error.
    fn dwarf_file_number_ok(&mut self, number: i64, line: &Line, col: usize) -> bool {
        if number >= 1 {
            return true;
        }
        let m = if number == 0 {
            "file number 0 is DWARF 5's (`--gdwarf-5`): spu as writes .debug_line version 3, as GNU as does by default"
        } else {
            "file number less than one"
        };
        self.diag(Severity::Error, line, col, m);
        false
    }

    /// `.file N "name"` (dwarf2dbg.c's `dwarf2_directive_filename`; `.file "name"` alone is
    /// the ELF file symbol, handled elsewhere).
    pub(super) fn dwarf_file(&mut self, args: &str, line: &Line, col: usize) {
        let mut cur = Cursor { text: args, at: 0 };
        let num_text = cur.token();
        let Some(num) = self.absolute_operand(num_text, line, col) else {
            return;
        };
        if !self.dwarf_file_number_ok(num, line, col) {
            return;
        }
        let Some(name) = cur.string() else {
            self.diag(
                Severity::Error,
                line,
                col,
                "expected a file name in double quotes after the file number",
            );
            return;
        };
        cur.skip_space();
        if let Some(c) = cur.peek() {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("junk at end of line, first unrecognized character is `{c}'"),
            );
            return;
        }
        if num > MAX_FILE_NUMBER {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("file number {num} is too big (spu as allows up to {MAX_FILE_NUMBER})"),
            );
            return;
        }
        if let Err(m) = self.dwarf.assign(num as usize, &name) {
            self.diag(Severity::Error, line, col, m);
            return;
        }
        self.dwarf.last_file_line = Some(line.clone());
        // The source brings its own line numbers: `-g`'s go (`purge_generated_debug`).
        self.dwarf.compiler_lines = true;
        self.dwarf.rows.retain(|r| r.generated.is_none());
    }

    /// `.loc FILE LINE [COLUMN] [basic_block] [prologue_end] [epilogue_begin] [is_stmt V]
    /// [isa V] [discriminator V] [view V]` (`dwarf2_directive_loc`).
    pub(super) fn dwarf_loc(&mut self, args: &str, line: &Line, col: usize) {
        // Two `.loc`s in a row: the first one's row is written here and now.
        if self.dwarf.loc_seen {
            self.dwarf_row_here(line, col);
        }
        let mut cur = Cursor { text: args, at: 0 };
        let file_text = cur.token();
        let Some(file) = self.absolute_operand(file_text, line, col) else {
            return;
        };
        let line_text = cur.token();
        let Some(number) = self.absolute_operand(line_text, line, col) else {
            return;
        };
        if !self.dwarf_file_number_ok(file, line, col) {
            return;
        }
        if !self.dwarf.declared(file) {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("unassigned file number {file}"),
            );
            return;
        }
        let Ok(number) = u32::try_from(number) else {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("line number {number} is out of range (0 to 4294967295)"),
            );
            return;
        };
        let mut loc = self.dwarf.current;
        loc.file = file as u32;
        loc.line = number;
        loc.discriminator = 0;
        cur.skip_space();
        if cur.peek().is_some_and(|c| c.is_ascii_digit()) {
            let t = cur.token();
            let Some(c) = self.absolute_operand(t, line, col) else {
                return;
            };
            let Ok(c) = u32::try_from(c) else {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    format!("column {c} is out of range"),
                );
                return;
            };
            loc.column = c;
            cur.skip_space();
        }
        // view: (asserted zero, or a symbol to define as the view number)
        let mut view: Option<Option<String>> = None;
        while cur.peek().is_some_and(|c| c.is_ascii_alphabetic()) {
            let word = cur.name();
            let value = |asm: &mut Self, cur: &mut Cursor| {
                let t = cur.token();
                asm.absolute_operand(t, line, col)
            };
            match word {
                "basic_block" => loc.basic_block = true,
                "prologue_end" => {
                    loc.prologue_end = true;
                    self.dwarf.level3 = true;
                }
                "epilogue_begin" => {
                    loc.epilogue_begin = true;
                    self.dwarf.level3 = true;
                }
                "is_stmt" => match value(self, &mut cur) {
                    Some(0) => loc.is_stmt = false,
                    Some(1) => loc.is_stmt = true,
                    Some(_) => {
                        self.diag(Severity::Error, line, col, "is_stmt value not 0 or 1");
                        return;
                    }
                    None => return,
                },
                "isa" => match value(self, &mut cur) {
                    Some(v) if (0..=u32::MAX as i64).contains(&v) => {
                        loc.isa = v as u32;
                        self.dwarf.level3 = true;
                    }
                    Some(_) => {
                        self.diag(Severity::Error, line, col, "isa number less than zero");
                        return;
                    }
                    None => return,
                },
                "discriminator" => match value(self, &mut cur) {
                    Some(v) if (0..=u32::MAX as i64).contains(&v) => loc.discriminator = v as u32,
                    Some(_) => {
                        self.diag(Severity::Error, line, col, "discriminator less than zero");
                        return;
                    }
                    None => return,
                },
                "view" => {
                    cur.skip_space();
                    if cur.peek().is_some_and(|c| c.is_ascii_digit() || c == '-') {
                        match value(self, &mut cur) {
                            Some(0) => view = Some(None),
                            Some(_) => {
                                self.diag(
                                    Severity::Error,
                                    line,
                                    col,
                                    "numeric view can only be asserted to zero",
                                );
                                return;
                            }
                            None => return,
                        }
                    } else {
                        let name = cur.name();
                        if name.is_empty() {
                            self.diag(
                                Severity::Error,
                                line,
                                col,
                                "expected a symbol name after `view'",
                            );
                            return;
                        }
                        view = Some(Some(name.to_string()));
                    }
                }
                other => {
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unknown .loc sub-directive `{other}'"),
                    );
                    return;
                }
            }
            cur.skip_space();
        }
        if let Some(c) = cur.peek() {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("junk at end of line, first unrecognized character is `{c}'"),
            );
            return;
        }
        self.dwarf.current = loc;
        self.dwarf.loc_seen = true;
        // A view makes the row now, at this address.
        if let Some(view) = view {
            let recorded = self.dwarf_row_here(line, col);
            if let Some(v) = recorded {
                match view {
                    None if v != 0 && self.pass == 2 => {
                        self.diag(Severity::Error, line, col, "view number mismatch")
                    }
                    None => {}
                    Some(name) => {
                        self.symbols
                            .insert(name, super::symbols::SymVal::Abs(Val::abs(v as i64)));
                    }
                }
            }
        }
    }

    /// `.loc_mark_labels 0|1`: whether every code label starts a basic block row.
    pub(super) fn dwarf_mark_labels(&mut self, args: &str, line: &Line, col: usize) {
        match self.absolute_operand(args.trim(), line, col) {
            Some(v @ (0 | 1)) => self.dwarf.mark_labels = v == 1,
            Some(_) => self.diag(Severity::Error, line, col, "expected 0 or 1"),
            None => {}
        }
    }

    /// An instruction was emitted at `offset` of `chunk`: a waiting `.loc` gives it a row.
    pub(super) fn dwarf_insn(&mut self, chunk: Sect, offset: u32, line: &Line, col: usize) {
        if self.opts.debug_lines && !self.dwarf.compiler_lines {
            self.generated_row(chunk, offset, line, col);
            return;
        }
        if !self.dwarf.loc_seen {
            return;
        }
        let loc = self.dwarf.current;
        if loc.line != 0 {
            self.dwarf_row(chunk, offset, loc, line, col);
        }
        self.dwarf.consume();
    }

    /// A label was defined here: with `.loc_mark_labels 1` it starts a basic block.
    pub(super) fn dwarf_label(&mut self, line: &Line) {
        if !self.dwarf.mark_labels
            || self.absolute.is_some()
            || !self.is_code(self.sect)
            || self.dwarf.files.is_empty()
        {
            return;
        }
        let mut loc = self.dwarf.current;
        loc.basic_block = true;
        let offset = self.offsets.get(&self.sect).copied().unwrap_or(0);
        self.dwarf_row(self.sect, offset, loc, line, 1);
        self.dwarf.consume();
    }

    /// `-g`: a row for this source line (`dwarf2_where`), one per line and file.
    fn generated_row(&mut self, chunk: Sect, offset: u32, line: &Line, col: usize) {
        let here = (line.file.clone(), line.line);
        if self.dwarf.last_generated.as_ref() == Some(&here) {
            self.dwarf.consume();
            return;
        }
        let loc = Loc {
            file: 0,
            line: line.line as u32,
            column: 0,
            isa: self.dwarf.current.isa,
            discriminator: self.dwarf.current.discriminator,
            is_stmt: true,
            basic_block: false,
            prologue_end: false,
            epilogue_begin: false,
        };
        if self.dwarf_row(chunk, offset, loc, line, col).is_some() {
            if let Some(r) = self.dwarf.rows.last_mut() {
                r.generated = Some(line.file.bytes().collect());
            }
            self.dwarf.last_generated = Some(here);
        }
        self.dwarf.consume();
    }

    /// The waiting `.loc`'s row at the current position; its view number if one was made.
    fn dwarf_row_here(&mut self, line: &Line, col: usize) -> Option<u32> {
        let loc = self.dwarf.current;
        let made = if loc.line != 0 {
            let offset = self.offsets.get(&self.sect).copied().unwrap_or(0);
            self.dwarf_row(self.sect, offset, loc, line, col)
        } else {
            None
        };
        self.dwarf.consume();
        made
    }

    /// Records a row (`dwarf2_gen_line_info_1`): only code sections that load have rows;
    /// elsewhere gas warns and drops it.
    fn dwarf_row(
        &mut self,
        chunk: Sect,
        offset: u32,
        loc: Loc,
        line: &Line,
        col: usize,
    ) -> Option<u32> {
        let def = &self.defs[self.chunks[chunk].0];
        let code = def.flags & (SHF_ALLOC | SHF_EXECINSTR) == SHF_ALLOC | SHF_EXECINSTR
            && def.ty != SHT_NOBITS;
        if self.absolute.is_some() || !code {
            let name = if self.absolute.is_some() {
                "*ABS*".to_string()
            } else {
                def.name.clone()
            };
            self.diag(
                Severity::Warning,
                line,
                col,
                format!("dwarf line number information for {name} ignored"),
            );
            return None;
        }
        let view = match self.dwarf.rows.iter().rev().find(|r| r.chunk == chunk) {
            Some(prev) if prev.offset == offset => prev.view + 1,
            _ => 0,
        };
        self.dwarf.rows.push(Row {
            chunk,
            offset,
            loc,
            generated: None,
            view,
        });
        Some(view)
    }

    /// The line-table state with `-g`'s rows numbered: files get slots in the order the
    /// rows will be written (`do_allocate_filenum` in `dwarf2_finish`).
    fn numbered(&self) -> LineState {
        let mut st = self.dwarf.clone();
        let mut order: Vec<usize> = Vec::new();
        for r in &st.rows {
            let d = self.chunks[r.chunk].0;
            if !order.contains(&d) {
                order.push(d);
            }
        }
        let mut idx: Vec<usize> = (0..st.rows.len()).collect();
        idx.sort_by_key(|&i| {
            let (d, sub) = self.chunks[st.rows[i].chunk];
            (order.iter().position(|&x| x == d), sub)
        });
        for i in idx {
            if let Some(path) = st.rows[i].generated.clone() {
                st.rows[i].loc.file = st.allocate(&path);
            }
        }
        st
    }

    /// A `.file`/`.loc` operand that must be an absolute number.
    fn absolute_operand(&mut self, t: &str, line: &Line, col: usize) -> Option<i64> {
        if t.is_empty() {
            self.diag(
                Severity::Error,
                line,
                col,
                "missing expression: a number is expected",
            );
            return None;
        }
        match self.eval_reported(t, line, col) {
            Ok(v) if !v.reloc && !v.cross && v.sym.is_none() && v.sect.is_none() => Some(v.v),
            Ok(_) => {
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    format!("`{t}' is not a constant: a number is expected"),
                );
                None
            }
            Err((_, m)) => {
                self.diag(Severity::Error, line, col, format!("`{t}': {m}"));
                None
            }
        }
    }

    /// End of the final walk: with rows to write, every file slot below the highest must
    /// have been declared (gas: "unassigned file number").
    pub(super) fn dwarf_finish_checks(&mut self) {
        if !self.dwarf.has_rows() {
            return;
        }
        // The source's own non-empty .debug_line and rows of `.loc`: gas stops
        // ("duplicate .debug_line sections"); there can be one line table only.
        let own = self.defs.iter().position(|d| d.name == ".debug_line");
        if let (Some(d), Some(l)) = (own, self.dwarf.last_file_line.clone()) {
            let used = (0..self.chunks.len())
                .any(|c| self.chunks[c].0 == d && self.offsets.get(&c).is_some_and(|&n| n > 0));
            if used {
                self.diag(Severity::Error, &l, 1, "duplicate .debug_line sections");
            }
        }
        let missing: Vec<usize> = (1..self.dwarf.files.len())
            .filter(|&i| self.dwarf.files[i].is_none())
            .collect();
        if let Some(l) = self.dwarf.last_file_line.clone() {
            for i in missing {
                self.diag(
                    Severity::Error,
                    &l,
                    1,
                    format!("unassigned file number {i}"),
                );
            }
        }
    }

    /// The `.debug_line` contents and their relocations (offsets in `.debug_line`, against
    /// section definitions), or `None` without rows.
    pub(super) fn debug_line(&self) -> Option<(Vec<u8>, Vec<Reloc>)> {
        // dwarf2_finish writes a line table (its header alone, without rows) beside a
        // source's own non-empty `.debug_info` too, for that unit to point at.
        let own_info = self.defs.iter().position(|d| d.name == ".debug_info");
        let info_not_empty = own_info.is_some_and(|d| {
            (0..self.chunks.len())
                .any(|c| self.chunks[c].0 == d && self.offsets.get(&c).is_some_and(|&o| o > 0))
        });
        if !(self.dwarf.has_rows() || info_not_empty)
            || self.defs.iter().any(|d| d.name == ".debug_line")
        {
            return None;
        }
        let state = self.numbered();
        // Sections in the order of their first row; subsections in order within each.
        let mut order: Vec<usize> = Vec::new();
        for r in &state.rows {
            let d = self.chunks[r.chunk].0;
            if !order.contains(&d) {
                order.push(d);
            }
        }
        let mut sequences = Vec::new();
        for d in order {
            let mut rows: Vec<&Row> = state
                .rows
                .iter()
                .filter(|r| self.chunks[r.chunk].0 == d)
                .collect();
            rows.sort_by_key(|r| self.chunks[r.chunk].1);
            let rows: Vec<(u32, Loc)> = rows
                .iter()
                .map(|r| {
                    (
                        self.bases.get(&r.chunk).copied().unwrap_or(0) + r.offset,
                        r.loc,
                    )
                })
                .collect();
            let end = state.content_end.get(&d).copied().unwrap_or(0);
            sequences.push((d, rows, end));
        }
        let mut prog = Vec::new();
        let mut addr_fields = Vec::new();
        for (d, rows, end) in &sequences {
            sequence(&mut prog, &mut addr_fields, *d, rows, *end);
        }
        let mut header = vec![
            1, // minimum instruction length
            1, // default is_stmt
            LINE_BASE as u8,
            LINE_RANGE,
            OPCODE_BASE,
        ];
        header.extend_from_slice(&STANDARD_OPCODE_LENGTHS);
        for d in state.dirs.iter().skip(1) {
            header.extend_from_slice(d.as_deref().unwrap_or_default());
            header.push(0);
        }
        header.push(0);
        for (name, dir) in state.files.iter().skip(1).flatten() {
            header.extend_from_slice(name);
            header.push(0);
            header.extend(leb128(*dir as i64, false));
            header.push(0); // modification time: unknown
            header.push(0); // size: unknown
        }
        header.push(0);
        let mut out = Vec::new();
        let unit_length = 2 + 4 + header.len() + prog.len();
        out.extend_from_slice(&(unit_length as u32).to_be_bytes());
        out.extend_from_slice(&LINE_VERSION.to_be_bytes());
        out.extend_from_slice(&(header.len() as u32).to_be_bytes());
        out.extend_from_slice(&header);
        let program_start = out.len() as u32;
        out.extend_from_slice(&prog);
        let relocs = addr_fields
            .into_iter()
            .map(|(at, d, addend)| Reloc {
                offset: program_start + at,
                kind: crate::reloc::R_SPU_ADDR32,
                target: RelocTarget::Section(d),
                addend,
            })
            .collect();
        Some((out, relocs))
    }
}

/// One section's line program (`process_entries`): rows at section offsets, then the end
/// of the sequence at `end`. Address fields go to `fields` as (offset in `out`, section,
/// addend); their bytes stay zero for the relocation.
fn sequence(
    out: &mut Vec<u8>,
    fields: &mut Vec<(u32, usize, i64)>,
    def: usize,
    rows: &[(u32, Loc)],
    end: u32,
) {
    let mut state = Loc::default();
    let mut last: Option<u32> = None;
    for &(addr, loc) in rows {
        if loc.file != state.file {
            state.file = loc.file;
            out.push(DW_LNS_SET_FILE);
            out.extend(leb128(loc.file as i64, false));
        }
        if loc.column != state.column {
            state.column = loc.column;
            out.push(DW_LNS_SET_COLUMN);
            out.extend(leb128(loc.column as i64, false));
        }
        if loc.discriminator != 0 {
            let operand = leb128(loc.discriminator as i64, false);
            out.push(0);
            // dwarf2dbg.c writes this length signed.
            out.extend(leb128(1 + operand.len() as i64, true));
            out.push(DW_LNE_SET_DISCRIMINATOR);
            out.extend(operand);
        }
        if loc.isa != state.isa {
            state.isa = loc.isa;
            out.push(DW_LNS_SET_ISA);
            out.extend(leb128(loc.isa as i64, false));
        }
        if loc.is_stmt != state.is_stmt {
            state.is_stmt = loc.is_stmt;
            out.push(DW_LNS_NEGATE_STMT);
        }
        if loc.basic_block {
            out.push(DW_LNS_SET_BASIC_BLOCK);
        }
        if loc.prologue_end {
            out.push(DW_LNS_SET_PROLOGUE_END);
        }
        if loc.epilogue_begin {
            out.push(DW_LNS_SET_EPILOGUE_BEGIN);
        }
        // gas computes the line advance in `int`.
        let line_delta = loc.line.wrapping_sub(state.line) as i32;
        match last {
            None => {
                out.extend_from_slice(&[0, 5, DW_LNE_SET_ADDRESS]);
                fields.push((out.len() as u32, def, addr as i64));
                out.extend_from_slice(&[0; 4]);
                advance(out, Some(line_delta), 0);
            }
            Some(prev) => advance(out, Some(line_delta), addr.saturating_sub(prev) as u64),
        }
        state.line = loc.line;
        last = Some(addr);
    }
    let from = last.unwrap_or(0);
    advance(out, None, end.saturating_sub(from) as u64);
}

/// A line and address advance as few bytes as dwarf2dbg.c's `emit_inc_line_addr` makes
/// it: a special opcode where one fits, else `DW_LNS_advance_line`/`DW_LNS_const_add_pc`/
/// `DW_LNS_advance_pc`. No line advance (`None`) ends the sequence.
fn advance(out: &mut Vec<u8>, line_delta: Option<i32>, addr_delta: u64) {
    let Some(mut line_delta) = line_delta else {
        if addr_delta == MAX_SPECIAL_ADDR_DELTA {
            out.push(DW_LNS_CONST_ADD_PC);
        } else if addr_delta != 0 {
            out.push(DW_LNS_ADVANCE_PC);
            out.extend(leb128(addr_delta as i64, false));
        }
        out.extend_from_slice(&[0, 1, DW_LNE_END_SEQUENCE]);
        return;
    };
    let mut need_copy = false;
    let mut tmp = line_delta as i64 - LINE_BASE as i64;
    if !(0..LINE_RANGE as i64).contains(&tmp) {
        out.push(DW_LNS_ADVANCE_LINE);
        out.extend(leb128(line_delta as i64, true));
        line_delta = 0;
        tmp = -(LINE_BASE as i64);
        need_copy = true;
    }
    if line_delta == 0 && addr_delta == 0 {
        out.push(DW_LNS_COPY);
        return;
    }
    let tmp = tmp as u64 + OPCODE_BASE as u64;
    if addr_delta < 256 + MAX_SPECIAL_ADDR_DELTA {
        let opcode = tmp + addr_delta * LINE_RANGE as u64;
        if opcode <= 255 {
            out.push(opcode as u8);
            return;
        }
        let opcode = tmp + (addr_delta - MAX_SPECIAL_ADDR_DELTA) * LINE_RANGE as u64;
        if opcode <= 255 {
            out.push(DW_LNS_CONST_ADD_PC);
            out.push(opcode as u8);
            return;
        }
    }
    out.push(DW_LNS_ADVANCE_PC);
    out.extend(leb128(addr_delta as i64, false));
    out.push(if need_copy { DW_LNS_COPY } else { tmp as u8 });
}

/// gas's producer string (`"GNU AS " VERSION`): the version whose output this matches.
const PRODUCER: &str = "GNU AS 2.40";

const DW_TAG_COMPILE_UNIT: u8 = 0x11;
const DW_TAG_SUBPROGRAM: u8 = 0x2e;
const DW_TAG_UNSPECIFIED_TYPE: u8 = 0x3b;
const DW_AT_NAME: u8 = 0x03;
const DW_AT_STMT_LIST: u8 = 0x10;
const DW_AT_LOW_PC: u8 = 0x11;
const DW_AT_HIGH_PC: u8 = 0x12;
const DW_AT_LANGUAGE: u8 = 0x13;
const DW_AT_COMP_DIR: u8 = 0x1b;
const DW_AT_PRODUCER: u8 = 0x25;
const DW_AT_EXTERNAL: u8 = 0x3f;
const DW_AT_TYPE: u8 = 0x49;
const DW_AT_RANGES: u8 = 0x55;
const DW_FORM_ADDR: u8 = 0x01;
const DW_FORM_DATA2: u8 = 0x05;
const DW_FORM_DATA4: u8 = 0x06;
const DW_FORM_FLAG: u8 = 0x0c;
const DW_FORM_STRP: u8 = 0x0e;
const DW_FORM_REF_UDATA: u8 = 0x15;
/// gas's `DW_LANG_Mips_Assembler`.
const DW_LANG_MIPS_ASSEMBLER: u16 = 0x8001;

/// A debugging section gas adds: name, alignment, flags, entry size, contents and
/// relocations.
pub(super) struct DebugSection {
    pub name: &'static str,
    pub align: u32,
    pub flags: u64,
    pub entsize: u64,
    pub data: Vec<u8>,
    pub relocs: Vec<Reloc>,
}

/// gas's `getpwd`: `$PWD` where it names the current directory, else the current
/// directory (`DW_AT_comp_dir`).
fn working_directory() -> Vec<u8> {
    let cwd = std::env::current_dir().unwrap_or_default();
    let pwd = std::env::var_os("PWD")
        .map(std::path::PathBuf::from)
        .filter(|p| p.is_absolute())
        .filter(|p| p.canonicalize().ok() == cwd.canonicalize().ok());
    pwd.unwrap_or(cwd).to_string_lossy().as_bytes().to_vec()
}

impl Assembler<'_> {
    /// The unit gas writes around its line table when the source has no `.debug_info` of
    /// its own (`dwarf2_finish`'s `emit_other_sections`): `.debug_info` (one
    /// compilation unit, DWARF 3, with a subprogram per sized function), `.debug_abbrev`,
    /// `.debug_aranges`, `.debug_str` and, for code in more than one section,
    /// `.debug_ranges`. `first` is the object section index the first of them gets
    /// (`.debug_line` is at `first - 1`).
    pub(super) fn debug_unit(&self, first: usize) -> Vec<DebugSection> {
        if !self.dwarf.has_rows() || self.defs.iter().any(|d| d.name == ".debug_info") {
            return Vec::new();
        }
        // In the order they are pushed below (`.debug_aranges` is `first + 2`).
        let (line, info, abbrev, strs, ranges) =
            (first - 1, first, first + 1, first + 3, first + 4);
        let reloc = |offset: usize, target: RelocTarget, addend: i64| Reloc {
            offset: offset as u32,
            kind: crate::reloc::R_SPU_ADDR32,
            target,
            addend,
        };
        let state = self.numbered();
        // Sections with rows, in the order they got their first, and where each ends.
        let mut segs: Vec<(usize, u32)> = Vec::new();
        for r in &state.rows {
            let d = self.chunks[r.chunk].0;
            if !segs.iter().any(|s| s.0 == d) {
                segs.push((d, state.content_end.get(&d).copied().unwrap_or(0)));
            }
        }
        // Defined functions with a size, in address order; whether any is external.
        let mut funcs: Vec<(usize, u32, String, bool, i64)> = self
            .symbols
            .iter()
            .filter_map(|(name, v)| {
                let a = self.attrs.get(name)?;
                let super::symbols::SymVal::Label(c, off) = v else {
                    return None;
                };
                let size = a.size.filter(|&s| s != 0)?;
                (a.kind == 2).then(|| {
                    let at = self.bases.get(c).copied().unwrap_or(0) + off;
                    (
                        self.chunks[*c].0,
                        at,
                        name.clone(),
                        a.global && !a.weak,
                        size,
                    )
                })
            })
            .collect();
        funcs.sort();
        let have_efunc = funcs.iter().any(|f| f.3);
        // gas's `dwarf_level`: 2 under `-g` unless a `.loc` option raised it, else 3.
        let version: u16 = if self.opts.debug_lines && !state.level3 {
            2
        } else {
            3
        };
        let typed = version > 2;

        // .debug_str: the unit's name, directory and producer, then function names.
        let mut str_data = Vec::new();
        let name_at = str_data.len();
        if let Some(Some((file, dir))) = state.files.get(1) {
            if let Some(Some(d)) = state.dirs.get(*dir as usize) {
                str_data.extend_from_slice(d);
                str_data.push(b'/');
            }
            str_data.extend_from_slice(file);
        }
        str_data.push(0);
        let comp_dir_at = str_data.len();
        str_data.extend(working_directory());
        str_data.push(0);
        let producer_at = str_data.len();
        str_data.extend_from_slice(PRODUCER.as_bytes());
        str_data.push(0);

        // .debug_abbrev.
        let mut ab = vec![1, DW_TAG_COMPILE_UNIT, u8::from(!funcs.is_empty())];
        ab.extend_from_slice(&[DW_AT_STMT_LIST, DW_FORM_DATA4]);
        if segs.len() == 1 {
            ab.extend_from_slice(&[DW_AT_LOW_PC, DW_FORM_ADDR, DW_AT_HIGH_PC, DW_FORM_ADDR]);
        } else {
            ab.extend_from_slice(&[DW_AT_RANGES, DW_FORM_DATA4]);
        }
        ab.extend_from_slice(&[
            DW_AT_NAME,
            DW_FORM_STRP,
            DW_AT_COMP_DIR,
            DW_FORM_STRP,
            DW_AT_PRODUCER,
            DW_FORM_STRP,
            DW_AT_LANGUAGE,
            DW_FORM_DATA2,
            0,
            0,
        ]);
        if !funcs.is_empty() {
            ab.extend_from_slice(&[2, DW_TAG_SUBPROGRAM, 0, DW_AT_NAME, DW_FORM_STRP]);
            if have_efunc {
                ab.extend_from_slice(&[DW_AT_EXTERNAL, DW_FORM_FLAG]);
            }
            if typed {
                ab.extend_from_slice(&[DW_AT_TYPE, DW_FORM_REF_UDATA]);
            }
            ab.extend_from_slice(&[
                DW_AT_LOW_PC,
                DW_FORM_ADDR,
                DW_AT_HIGH_PC,
                DW_FORM_ADDR,
                0,
                0,
            ]);
            if typed {
                ab.extend_from_slice(&[3, DW_TAG_UNSPECIFIED_TYPE, 0, 0, 0]);
            }
        }
        ab.push(0);

        // .debug_info.
        let mut di = vec![0; 4];
        let mut di_relocs = Vec::new();
        di.extend_from_slice(&version.to_be_bytes());
        di_relocs.push(reloc(di.len(), RelocTarget::Section(abbrev), 0));
        di.extend_from_slice(&[0; 4]);
        di.push(4); // address size
        di.push(1); // the compilation unit's abbreviation
        di_relocs.push(reloc(di.len(), RelocTarget::Section(line), 0));
        di.extend_from_slice(&[0; 4]);
        if let [(d, end)] = segs[..] {
            di_relocs.push(reloc(di.len(), RelocTarget::Section(d), 0));
            di.extend_from_slice(&[0; 4]);
            di_relocs.push(reloc(di.len(), RelocTarget::Section(d), end as i64));
            di.extend_from_slice(&[0; 4]);
        } else {
            di_relocs.push(reloc(di.len(), RelocTarget::Section(ranges), 0));
            di.extend_from_slice(&[0; 4]);
        }
        for at in [name_at, comp_dir_at, producer_at] {
            di_relocs.push(reloc(di.len(), RelocTarget::Section(strs), at as i64));
            di.extend_from_slice(&[0; 4]);
        }
        di.extend_from_slice(&DW_LANG_MIPS_ASSEMBLER.to_be_bytes());
        if !funcs.is_empty() {
            // Where the unspecified type's entry will be: after every subprogram, whose
            // DW_AT_type (a ULEB128) holds that very offset.
            let per_func = 1 + 4 + usize::from(have_efunc) + 4 + 4;
            let type_len = |tag: usize| {
                if typed {
                    leb128(tag as i64, false).len()
                } else {
                    0
                }
            };
            let mut tag = di.len() + funcs.len() * (per_func + type_len(0));
            while tag != di.len() + funcs.len() * (per_func + type_len(tag)) {
                tag = di.len() + funcs.len() * (per_func + type_len(tag));
            }
            for (_, _, name, external, size) in &funcs {
                di.push(2);
                di_relocs.push(reloc(
                    di.len(),
                    RelocTarget::Section(strs),
                    str_data.len() as i64,
                ));
                di.extend_from_slice(&[0; 4]);
                str_data.extend_from_slice(name.as_bytes());
                str_data.push(0);
                if have_efunc {
                    di.push(u8::from(*external));
                }
                if typed {
                    di.extend(leb128(tag as i64, false));
                }
                di_relocs.push(reloc(di.len(), RelocTarget::Symbol(name.clone()), 0));
                di.extend_from_slice(&[0; 4]);
                di_relocs.push(reloc(di.len(), RelocTarget::Symbol(name.clone()), *size));
                di.extend_from_slice(&[0; 4]);
            }
            debug_assert_eq!(di.len(), tag);
            if typed {
                di.push(3);
            }
            di.push(0); // end of the unit's children
        }
        let len = (di.len() - 4) as u32;
        di[..4].copy_from_slice(&len.to_be_bytes());

        // .debug_aranges: version 2, the header padded to twice the address size.
        let mut ar = vec![0; 4];
        let mut ar_relocs = Vec::new();
        ar.extend_from_slice(&2u16.to_be_bytes());
        ar_relocs.push(reloc(ar.len(), RelocTarget::Section(info), 0));
        ar.extend_from_slice(&[0; 4]);
        ar.extend_from_slice(&[4, 0, 0, 0, 0, 0]);
        for &(d, end) in &segs {
            ar_relocs.push(reloc(ar.len(), RelocTarget::Section(d), 0));
            ar.extend_from_slice(&[0; 4]);
            ar.extend_from_slice(&end.to_be_bytes());
        }
        ar.extend_from_slice(&[0; 8]);
        let len = (ar.len() - 4) as u32;
        ar[..4].copy_from_slice(&len.to_be_bytes());

        let debug = |name, align, data, relocs| DebugSection {
            name,
            align,
            flags: 0,
            entsize: 0,
            data,
            relocs,
        };
        let mut out = vec![
            debug(".debug_info", 1, di, di_relocs),
            debug(".debug_abbrev", 1, ab, Vec::new()),
            debug(".debug_aranges", 8, ar, ar_relocs),
            DebugSection {
                name: ".debug_str",
                align: 1,
                flags: 0x30, // SHF_MERGE | SHF_STRINGS
                entsize: 1,
                data: str_data,
                relocs: Vec::new(),
            },
        ];
        if segs.len() > 1 {
            // .debug_ranges: a base address selection entry (base 0), each section's
            // start and end, and the end of the list.
            let mut rg = vec![0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0];
            let mut rg_relocs = Vec::new();
            for &(d, end) in &segs {
                rg_relocs.push(reloc(rg.len(), RelocTarget::Section(d), 0));
                rg.extend_from_slice(&[0; 4]);
                rg_relocs.push(reloc(rg.len(), RelocTarget::Section(d), end as i64));
                rg.extend_from_slice(&[0; 4]);
            }
            rg.extend_from_slice(&[0; 8]);
            out.push(debug(".debug_ranges", 8, rg, rg_relocs));
        }
        out
    }
}
