//! Static timing of assembly source in the manner of IBM's `spu_timing`: the instructions
//! are timed as straight-line code (no branches taken, no fetch or local-store contention),
//! in address order, with the dual-issue and latency rules of the timing model.

use crate::codec::{decode_ext, encode, Inst};
use crate::ext::Extensions;
use crate::profile::*;
use crate::table::{forms_named, OperandKind, Pipe};
use crate::timing::{Timing, TimingConfig};
use std::collections::HashMap;
use std::fmt::Write as _;

/// One source line of an assembly file, as the static analysis sees it.
#[derive(Clone, Debug)]
pub struct SourceLine {
    /// The line as written.
    pub text: String,
    /// Labels defined on the line.
    pub labels: Vec<String>,
    /// Instructions on the line (usually at most one): address, decoded instruction,
    /// mnemonic and operand text.
    pub insts: Vec<SourceInst>,
    /// Statements in a code section that name no instruction (and are not directives):
    /// not timed, and reported so that nothing is skipped silently.
    pub unknown: Vec<String>,
}

#[derive(Clone, Debug)]
/// One instruction of the assembly source, as assembled for the static timing analysis.
pub struct SourceInst {
    /// Its local-store byte address.
    pub addr: u32,
    /// The decoded instruction.
    pub inst: Inst,
    /// The mnemonic as written in the source.
    pub mnemonic: String,
    /// The operand text as written in the source.
    pub operands: String,
}

impl SourceInst {
    /// `mnemonic\toperands`, as GCC writes it.
    pub fn text(&self) -> String {
        if self.operands.is_empty() {
            self.mnemonic.clone()
        } else {
            format!("{}\t{}", self.mnemonic, self.operands)
        }
    }
}

fn strip_comments(line: &str) -> String {
    let mut out = String::new();
    let mut rest = line;
    loop {
        let hash = rest.find('#');
        let block = rest.find("/*");
        match (hash, block) {
            (Some(h), Some(b)) if b < h => {
                out.push_str(&rest[..b]);
                match rest[b + 2..].find("*/") {
                    Some(e) => rest = &rest[b + 2 + e + 2..],
                    None => return out,
                }
            }
            (None, Some(b)) => {
                out.push_str(&rest[..b]);
                match rest[b + 2..].find("*/") {
                    Some(e) => rest = &rest[b + 2 + e + 2..],
                    None => return out,
                }
            }
            (Some(h), _) => {
                out.push_str(&rest[..h]);
                return out;
            }
            (None, None) => {
                out.push_str(rest);
                return out;
            }
        }
    }
}

fn is_label_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '$'
}

fn parse_number(s: &str) -> Option<i64> {
    let s = s.trim();
    let (neg, s) = match s.strip_prefix('-') {
        Some(r) => (true, r),
        None => (false, s),
    };
    let v = if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        i64::from_str_radix(h, 16).ok()?
    } else {
        s.parse::<i64>().ok()?
    };
    Some(if neg { -v } else { v })
}

fn parse_register(s: &str) -> i64 {
    let s = s.trim();
    let name = s.strip_prefix('$').unwrap_or(s);
    match name {
        "lr" | "rp" => 0,
        "sp" => 1,
        "fp" => 127,
        _ => parse_number(name).unwrap_or(0) & 127,
    }
}

/// Splits operands at top-level commas.
fn split_operands(s: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut depth = 0i32;
    let mut cur = String::new();
    for c in s.chars() {
        match c {
            '(' => {
                depth += 1;
                cur.push(c)
            }
            ')' => {
                depth -= 1;
                cur.push(c)
            }
            ',' if depth == 0 => out.push(std::mem::take(&mut cur).trim().to_string()),
            _ => cur.push(c),
        }
    }
    if !cur.trim().is_empty() {
        out.push(cur.trim().to_string());
    }
    out
}

/// Builds the instruction a statement stands for (register fields exact, immediates
/// zero: timing depends only on the operation and its registers). `None` when the
/// mnemonic is not an SPU instruction.
pub fn statement_inst(mnemonic: &str, operands: &str, addr: u32) -> Option<Inst> {
    let forms: Vec<_> = forms_named(mnemonic).collect();
    if forms.is_empty() {
        return None;
    }
    // Expand `off($ra)` into its two operands.
    let mut values: Vec<&str> = Vec::new();
    let texts = split_operands(operands);
    for t in &texts {
        if let (Some(open), true) = (t.rfind('('), t.ends_with(')')) {
            values.push(&t[..open]);
            values.push(&t[open + 1..t.len() - 1]);
        } else {
            values.push(t.as_str());
        }
    }
    let form = forms
        .iter()
        .find(|f| f.operands.len() == values.len())
        .copied()
        .unwrap_or(forms[0]);
    let ops: Vec<i64> = form
        .operands
        .iter()
        .enumerate()
        .map(|(i, kind)| {
            let v = values.get(i).copied().unwrap_or("");
            match kind {
                OperandKind::Rt
                | OperandKind::Ra
                | OperandKind::Rb
                | OperandKind::Rc
                | OperandKind::ParenRa => parse_register(v),
                // Keep hint and branch addresses where they are plain numbers.
                OperandKind::Abs18 | OperandKind::Rel18 | OperandKind::BrInst => {
                    parse_number(v).unwrap_or(addr as i64)
                }
                _ => 0,
            }
        })
        .collect();
    // Every extension's instructions are read (`spu timing` times what it is given).
    Some(decode_ext(encode(form, &ops, addr), Extensions::ALL))
}

/// Reads assembly source: labels, instructions and their addresses in the text section
/// (counting `.align`/`.p2align`/`.balign` and data directives placed in text).
pub fn parse_source(src: &str) -> Vec<SourceLine> {
    let mut lines = Vec::new();
    let mut addr: u32 = 0;
    let mut in_text = true;
    for raw in src.lines() {
        let mut line = SourceLine {
            text: raw.to_string(),
            labels: Vec::new(),
            insts: Vec::new(),
            unknown: Vec::new(),
        };
        let code = strip_comments(raw);
        for stmt in code.split(';') {
            let mut s = stmt.trim();
            // Labels.
            loop {
                let end = s.find(|c: char| !is_label_char(c)).unwrap_or(s.len());
                if end > 0 && s[end..].starts_with(':') {
                    line.labels.push(s[..end].to_string());
                    s = s[end + 1..].trim_start();
                } else {
                    break;
                }
            }
            if s.is_empty() {
                continue;
            }
            let (word, rest) = match s.find(char::is_whitespace) {
                Some(i) => (&s[..i], s[i..].trim()),
                None => (s, ""),
            };
            let lower = word.to_ascii_lowercase();
            if lower.starts_with('.') {
                let arg = |i: usize| split_operands(rest).get(i).and_then(|a| parse_number(a));
                match lower.as_str() {
                    ".text" => in_text = true,
                    ".data" | ".bss" | ".rodata" => in_text = false,
                    ".section" => {
                        let name = rest
                            .split(|c: char| c == ',' || c.is_whitespace())
                            .next()
                            .unwrap_or("");
                        in_text = name.starts_with(".text")
                            || name.starts_with(".init")
                            || name.starts_with(".fini");
                    }
                    // Addresses wrap as the local store does, whatever the sizes.
                    ".align" | ".p2align" if in_text => {
                        let a = 1u32 << arg(0).unwrap_or(0).clamp(0, 16);
                        addr = addr.div_ceil(a).wrapping_mul(a);
                    }
                    ".balign" if in_text => {
                        let a = arg(0).unwrap_or(1).clamp(1, 1 << 16) as u32;
                        addr = addr.div_ceil(a).wrapping_mul(a);
                    }
                    ".word" | ".long" | ".int" | ".float" | ".ffloat" if in_text => {
                        addr = addr.wrapping_add(4 * split_operands(rest).len() as u32)
                    }
                    ".short" | ".half" | ".hword" if in_text => {
                        addr = addr.wrapping_add(2 * split_operands(rest).len() as u32)
                    }
                    ".byte" if in_text => {
                        addr = addr.wrapping_add(split_operands(rest).len() as u32)
                    }
                    ".quad" | ".double" | ".dfloat" if in_text => {
                        addr = addr.wrapping_add(8 * split_operands(rest).len() as u32)
                    }
                    ".space" | ".skip" if in_text => {
                        addr = addr.wrapping_add(arg(0).unwrap_or(0).max(0) as u32)
                    }
                    _ => {}
                }
                continue;
            }
            if !in_text {
                continue;
            }
            if let Some(inst) = statement_inst(&lower, rest, addr) {
                line.insts.push(SourceInst {
                    addr,
                    inst,
                    mnemonic: lower.clone(),
                    operands: rest.split_whitespace().collect::<Vec<_>>().join(" "),
                });
                addr = addr.wrapping_add(4);
            } else {
                line.unknown.push(word.to_string());
            }
        }
        lines.push(line);
    }
    lines
}

/// The timing of one instruction in the static listing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StaticRow {
    /// Local-store byte address of the instruction.
    pub addr: u32,
    /// The instruction's text as shown in the listing.
    pub text: String,
    /// 0 (even) or 1 (odd).
    pub pipe: u8,
    /// Issue cycle counted from the start of the analysis.
    pub cycle: u64,
    /// Issue cycle counted from its block's first issue.
    pub issue: u64,
    /// Stall cycles before it issued.
    pub stall: u64,
    /// Dual-issued with its partner.
    pub dual: bool,
    /// `spu_timing`'s mark: 'D' dual-issued, 'd' a pipe-compatible pair that did not
    /// dual-issue, ' ' otherwise.
    pub mark: char,
    /// Result latency (cycles shown as digits).
    pub latency: u32,
    /// Index into `StaticTiming::blocks`.
    pub block: usize,
    /// Index of the source line.
    pub line: usize,
}

/// A basic block: from a label, or the instruction after a branch, to the next.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticBlock {
    /// The label the block starts at, if any.
    pub label: Option<String>,
    /// Local-store byte address of the block's first instruction.
    pub addr: u32,
    /// Number of instructions in the block.
    pub instructions: u64,
    /// From its first issue to its last, inclusive.
    pub cycles: u64,
    /// Dual-issue cycles.
    pub dual: u64,
    /// Stall cycles inside the block.
    pub stall: u64,
}

impl StaticBlock {
    /// Cycles per instruction of the block (`cycles / instructions`; 0 when it is empty).
    pub fn cpi(&self) -> f64 {
        if self.instructions == 0 {
            0.0
        } else {
            self.cycles as f64 / self.instructions as f64
        }
    }
}

#[derive(Clone, Debug)]
/// The result of the static timing analysis of one source file (`spu timing`): per-instruction rows and per-block sums.
pub struct StaticTiming {
    /// The source file's lines, in order.
    pub lines: Vec<SourceLine>,
    /// One row per timed instruction, in issue order.
    pub rows: Vec<StaticRow>,
    /// The basic blocks, in address order.
    pub blocks: Vec<StaticBlock>,
    /// The source lines shown (all, or the one block asked for).
    pub shown: std::ops::Range<usize>,
}

impl StaticTiming {
    /// Statements that were not timed because they name no instruction: (1-based line,
    /// word), in source order.
    pub fn unknown_statements(&self) -> impl Iterator<Item = (usize, &str)> {
        self.lines
            .iter()
            .enumerate()
            .flat_map(|(i, line)| line.unknown.iter().map(move |word| (i + 1, word.as_str())))
    }
}

/// The configuration `spu timing` uses: no fetch model and no hint window (as
/// `spu_timing`, which ignores fetch, local-store contention and branching).
pub fn static_config() -> TimingConfig {
    TimingConfig {
        model_fetch: false,
        hint_window: 0,
        memoize: false,
        ..Default::default()
    }
}

/// Times the whole source as one straight line (`label: None`, the timeline runs on
/// across labels as in `spu_timing`), or only the basic block at `label`, starting from
/// an idle pipeline.
pub fn analyze_source(src: &str, label: Option<&str>) -> Result<StaticTiming, String> {
    let lines = parse_source(src);
    // Blocks and the instructions in order.
    let mut order: Vec<(usize, usize)> = Vec::new(); // (line, inst index)
    let mut block_of: Vec<usize> = Vec::new();
    let mut blocks: Vec<StaticBlock> = Vec::new();
    let mut block_line: Vec<usize> = Vec::new();
    let mut pending_label: Option<(String, usize)> = None;
    // Every label at a block's address (labels may share one), for `--label`.
    let mut pending_all: Vec<String> = Vec::new();
    let mut block_labels: Vec<Vec<String>> = Vec::new();
    let mut after_branch = true;
    for (li, line) in lines.iter().enumerate() {
        if let Some(l) = line.labels.first() {
            if pending_label.is_none() {
                pending_label = Some((l.clone(), li));
            }
        }
        pending_all.extend(line.labels.iter().cloned());
        for (ii, si) in line.insts.iter().enumerate() {
            if pending_label.is_some() || after_branch || blocks.is_empty() {
                let (label, at) = match pending_label.take() {
                    Some((l, at)) => (Some(l), at),
                    None => (None, li),
                };
                blocks.push(StaticBlock {
                    label,
                    addr: si.addr,
                    instructions: 0,
                    cycles: 0,
                    dual: 0,
                    stall: 0,
                });
                block_line.push(at);
                block_labels.push(std::mem::take(&mut pending_all));
            }
            pending_all.clear();
            after_branch = crate::analysis::is_branch(si.inst.op);
            order.push((li, ii));
            block_of.push(blocks.len() - 1);
        }
    }
    let (selected, shown) = match label {
        None => (None, 0..lines.len()),
        Some(name) => {
            let b = block_labels
                .iter()
                .position(|l| l.iter().any(|l| l == name))
                .ok_or_else(|| format!("no block starts at label `{name}`"))?;
            let end = block_line.get(b + 1).copied().unwrap_or(lines.len());
            // Stop the shown lines after the block's last instruction's line.
            let last_line = order
                .iter()
                .zip(&block_of)
                .filter(|(_, bb)| **bb == b)
                .map(|((l, _), _)| *l)
                .max()
                .unwrap_or(block_line[b]);
            (
                Some(b),
                block_line[b]..end.min(last_line + 1).max(block_line[b] + 1),
            )
        }
    };
    let mut timing = Timing::new(static_config());
    let mut rows: Vec<StaticRow> = Vec::new();
    let mut first_issue: Vec<Option<u64>> = vec![None; blocks.len()];
    for (k, &(li, ii)) in order.iter().enumerate() {
        let b = block_of[k];
        if selected.is_some_and(|s| s != b) {
            continue;
        }
        let si = &lines[li].insts[ii];
        let cycle = timing.issue(si.addr, si.inst);
        let rec = timing.last_record();
        let unit = si.inst.op.info().unit;
        let first = *first_issue[b].get_or_insert(cycle);
        rows.push(StaticRow {
            addr: si.addr,
            text: si.text(),
            pipe: (unit.pipe() == Pipe::Odd) as u8,
            cycle,
            issue: cycle - first,
            stall: rec.issue - rec.base,
            dual: rec.dual,
            mark: if rec.dual { 'D' } else { ' ' },
            latency: if unit.latency() > 0 {
                si.inst.op.info().latency()
            } else {
                1
            },
            block: b,
            line: li,
        });
    }
    // 'D' on both halves of a dual-issued pair; 'd': an even-slot, even-pipe
    // instruction followed by its odd-pipe partner that did not dual-issue.
    let mut pair_cycles = vec![0u64; blocks.len()];
    for i in 1..rows.len() {
        if rows[i].dual {
            rows[i - 1].dual = true;
            rows[i - 1].mark = 'D';
            pair_cycles[rows[i].block] += 1;
            continue;
        }
        let (a, b) = (&rows[i - 1], &rows[i]);
        if !b.dual
            && a.addr & 4 == 0
            && b.addr == a.addr + 4
            && a.pipe == 0
            && b.pipe == 1
            && lines[a.line]
                .insts
                .iter()
                .all(|s| s.inst.op.info().unit != crate::table::Unit::FPD)
        {
            rows[i - 1].mark = 'd';
            rows[i].mark = 'd';
        }
    }
    for r in &rows {
        let b = &mut blocks[r.block];
        b.instructions += 1;
        b.cycles = b.cycles.max(r.issue + 1);
        b.stall += r.stall;
    }
    for (b, n) in blocks.iter_mut().zip(&pair_cycles) {
        b.dual = *n;
    }
    if let Some(s) = selected {
        let keep = blocks[s].clone();
        for r in rows.iter_mut() {
            r.block = 0;
        }
        blocks = vec![keep];
    }
    Ok(StaticTiming {
        lines,
        rows,
        blocks,
        shown,
    })
}

/// Width of `spu_timing`'s timeline (cycles shown before it wraps).
pub const TIMELINE: usize = 50;

/// The listing in `spu_timing`'s layout: pipe, dual-issue mark, a 50-column timeline in
/// which each instruction shows `-` for the cycles it stalled and the last digit of
/// each cycle its result is in flight, then the instruction. Other source lines are
/// printed after a blank annotation. With `running_count`, each instruction line starts
/// with its issue cycle. A summary of the blocks follows.
pub fn render_static(t: &StaticTiming, running_count: bool) -> String {
    let mut out = String::new();
    let mut by_line: HashMap<usize, Vec<&StaticRow>> = HashMap::new();
    for r in &t.rows {
        by_line.entry(r.line).or_default().push(r);
    }
    let blank = " ".repeat(3 + TIMELINE);
    for li in t.shown.clone() {
        let line = &t.lines[li];
        match by_line.get(&li) {
            None => {
                if running_count {
                    out.push_str("       ");
                }
                let _ = writeln!(out, "{blank}{}", line.text.trim_end());
            }
            Some(rows) => {
                for r in rows {
                    if running_count {
                        let _ = write!(out, "{:06} ", r.cycle);
                    }
                    let mut ring = [' '; TIMELINE];
                    let base = r.cycle - r.stall;
                    for c in base..r.cycle {
                        ring[c as usize % TIMELINE] = '-';
                    }
                    for c in r.cycle..r.cycle + r.latency as u64 {
                        ring[c as usize % TIMELINE] = char::from(b'0' + (c % 10) as u8);
                    }
                    let ring: String = ring.iter().collect();
                    let _ = writeln!(out, "{}{} {}\t{}", r.pipe, r.mark, ring, r.text);
                }
            }
        }
    }
    out.push('\n');
    let _ = writeln!(
        out,
        "# block                      addr  insts  cycles    CPI  dual  stall"
    );
    for b in &t.blocks {
        let _ = writeln!(
            out,
            "# {:<24} {:>6x} {:>6} {:>7} {:>6.2} {:>5} {:>6}",
            b.label.as_deref().unwrap_or("-"),
            b.addr,
            b.instructions,
            b.cycles,
            b.cpi(),
            b.dual,
            b.stall
        );
    }
    out
}

/// The analysis as JSON: `{"blocks":[{label,addr,instructions,cycles,cpi,dual,stall,
/// instructions_detail:[..]}],"instructions":[{addr,text,pipe,issue,cycle,stall,dual,
/// mark,latency,block}]}`.
pub fn static_json(t: &StaticTiming) -> String {
    use serde_json::{json, Value};
    let instructions: Vec<Value> = t
        .rows
        .iter()
        .map(|r| {
            json!({
                "addr": r.addr,
                "text": r.text,
                "pipe": r.pipe,
                "issue": r.issue,
                "cycle": r.cycle,
                "stall": r.stall,
                "dual": r.dual,
                "mark": r.mark.to_string().trim(),
                "latency": r.latency,
                "block": r.block,
            })
        })
        .collect();
    let blocks: Vec<Value> = t
        .blocks
        .iter()
        .map(|b| {
            json!({
                "label": b.label,
                "addr": b.addr,
                "instructions": b.instructions,
                "cycles": b.cycles,
                "cpi": json_ratio(b.cpi()),
                "dual": b.dual,
                "stall": b.stall,
            })
        })
        .collect();
    let report = json!({ "blocks": blocks, "instructions": instructions });
    format!("{report}\n")
}
