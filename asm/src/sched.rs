//! List scheduling of straight-line SPU code into even/odd dual-issue pairs, with virtual
//! registers allocated from a pool: the `.sched` ... `.endsched` block of the assembler
//! and `spu sched`. Pipes and latencies come from the instruction table (`spu_isa::table`),
//! register reads and writes from `spu_isa::analysis`, so the scheduler sees the machine
//! the timing model simulates.
//!
//! A block is written in logical order. Each line is an instruction, a label, or an
//! `.irp`/`.endr` repetition; `nop`/`lnop` are dropped (the scheduler places its own). The
//! assembler expands the block's macro calls before it is scheduled. Comments (`#`, and
//! `/* */` across lines, neither inside a string), `.irp` arguments and `\name`
//! substitution are read by the assembler's own code (`crate::lex`, `crate::expand`), so
//! `spu sched` and `.sched` read a block alike.
//! - `%name` is a virtual register, allocated from the pool after scheduling.
//! - `!` before an instruction makes it a barrier: everything before it issues before it,
//!   and no load, store or write of a non-scratch register moves above it. Branches,
//!   channel instructions and `stop` are barriers anyway.
//! - Stores stay in order with earlier loads and stores; `~` before a store lets it move
//!   past other stores. Loads are not ordered after earlier stores of the block (a load
//!   that reads what a store of the block wrote needs `!` on the store).
//! - `@after %name` (or a register) orders an instruction after the one that writes it.
//! - Labels at the start stay at the start; a label inside the block is a barrier that
//!   stays with the instruction after it (a branch, typically, named by a hint).
//! - A hint (`hbr`, `hbra`, `hbrr`) is not a barrier: it fills an odd slot, at least 8
//!   instructions before the end of the block so the hinted branch can use it.
//!
//! Scheduling is in-order issue by cycles: each cycle takes the ready even-pipe instruction
//! and the ready odd-pipe one with the longest latency-weighted path to the end of the
//! block (the critical path), the odd one independent of the even one, and emits them as
//! a pair, `nop`/`lnop` filling an empty slot, so every even instruction sits at an 8-byte
//! aligned address (the block is aligned first). With a pool, an instruction that would
//! need more live virtual registers than the pool holds waits.

use crate::expand::{block_end, irp_values, substitute};
use crate::lex::{blank_block_comments, first_word, split_comment, strip_comment};
use spu_isa::analysis;
use spu_isa::table::{forms_named, FormInfo, OperandKind, Pipe};

/// What a `.sched` block may use: the pool its virtual registers are allocated from, and
/// the scratch registers (besides the pool) whose writes may move above a barrier.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SchedOptions {
    pub pool: Vec<u8>,
    pub scratch: Vec<u8>,
}

/// A scheduled block.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Scheduled {
    /// The output lines and, for each, the index of the input line it came from (`None`
    /// for the alignment and the filler `nop`/`lnop`).
    pub lines: Vec<(String, Option<usize>)>,
    /// Issue cycles of the block in the scheduler's model (no stalls beyond dependencies).
    pub cycles: u32,
    /// Instructions of the block, not counting filler.
    pub instructions: usize,
}

/// An error at an input line (its index) and column (1-based, 0 when unknown).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SchedError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

fn err(line: usize, column: usize, message: impl Into<String>) -> SchedError {
    SchedError {
        line,
        column,
        message: message.into(),
    }
}

/// Parses the operands of `.sched`: `pool=R,R-R,...` and `scratch=R,R-R,...` (register
/// numbers, optionally with `$`, or inclusive ranges), separated by spaces; a comment
/// after them is ignored.
pub fn parse_options(args: &str) -> Result<SchedOptions, String> {
    let mut opts = SchedOptions::default();
    for word in strip_comment(args).split_whitespace() {
        let (key, value) = word
            .split_once('=')
            .ok_or_else(|| format!("`{word}`: expected pool=REGS or scratch=REGS"))?;
        let regs = parse_registers(value)?;
        match key {
            "pool" => opts.pool = regs,
            "scratch" => opts.scratch = regs,
            _ => return Err(format!("`{key}`: expected pool or scratch")),
        }
    }
    Ok(opts)
}

/// `78-111,113,$115` as register numbers, in the order written.
pub fn parse_registers(text: &str) -> Result<Vec<u8>, String> {
    let num = |s: &str| -> Result<u8, String> {
        let s = s.trim();
        s.strip_prefix('$')
            .unwrap_or(s)
            .parse::<u8>()
            .ok()
            .filter(|&n| n < 128)
            .ok_or_else(|| format!("`{s}`: not a register number (0..127)"))
    };
    let mut regs = Vec::new();
    for part in text.split(',').filter(|p| !p.trim().is_empty()) {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if a > b {
                    return Err(format!("`{part}`: empty range"));
                }
                regs.extend(a..=b);
            }
            None => regs.push(num(part)?),
        }
    }
    let mut seen = [false; 128];
    for &r in &regs {
        if std::mem::replace(&mut seen[r as usize], true) {
            return Err(format!("${r} is listed twice"));
        }
    }
    Ok(regs)
}

/// A register as the scheduler tracks it: physical `0..128`, virtual `128..`.
type Reg = u32;
const VIRTUAL_BASE: Reg = 128;

#[derive(Debug)]
enum Item {
    Label { text: String, origin: usize },
    Inst(Inst),
}

impl Inst {
    /// Takes a local-store cycle (and so can hold off instruction prefetch).
    fn uses_ls(&self) -> bool {
        self.load || self.any_store || self.hint
    }
}

#[derive(Debug)]
struct Inst {
    text: String,
    origin: usize,
    pipe: Pipe,
    latency: u32,
    /// Cycles it holds issue: 1, but for a gather load (its four local-store reads,
    /// docs/extensions.md).
    issue_cycles: u32,
    src: Vec<Reg>,
    dst: Vec<Reg>,
    after: Vec<Reg>,
    barrier: bool,
    /// A store that keeps its order with other memory operations.
    store: bool,
    /// Any store, `~` or not.
    any_store: bool,
    load: bool,
    hint: bool,
    /// Labels that stay with this instruction (emitted just before it).
    labels: Vec<(String, usize)>,
    /// Registers in the order the operands are written (the allocation order).
    operand_regs: Vec<Reg>,
}

/// Schedules a block. `resolve` gives the number of a register operand written as a name
/// or an expression (`$n` and `%name` are handled here).
///
/// `start` is the block's address, if known (after its 8-byte alignment): the scheduler then
/// keeps a local-store cycle free in each 128-byte line early enough for the instruction
/// prefetch of the next line.
pub fn schedule(
    lines: &[&str],
    opts: &SchedOptions,
    start: Option<u32>,
    resolve: &dyn Fn(&str) -> Option<u8>,
) -> Result<Scheduled, SchedError> {
    let expanded = expand_irp(lines)?;
    let mut virtuals: Vec<String> = Vec::new();
    let mut items = Vec::new();
    for (text, origin) in &expanded {
        parse_line(text, *origin, resolve, &mut virtuals, &mut items)?;
    }
    // Leading labels stay first; later labels travel with the next instruction.
    let mut head = Vec::new();
    let mut insts: Vec<Inst> = Vec::new();
    let mut pending: Vec<(String, usize)> = Vec::new();
    for item in items {
        match item {
            Item::Label { text, origin } if insts.is_empty() && pending.is_empty() => {
                head.push((text, Some(origin)))
            }
            Item::Label { text, origin } => pending.push((text, origin)),
            Item::Inst(mut inst) => {
                if !pending.is_empty() {
                    inst.barrier = true;
                    inst.labels = std::mem::take(&mut pending);
                }
                insts.push(inst);
            }
        }
    }
    if let Some((_, origin)) = pending.first() {
        return Err(err(
            *origin,
            1,
            "a label at the end of a .sched block labels nothing",
        ));
    }
    let scratch = |r: Reg| r < VIRTUAL_BASE && opts.scratch.contains(&(r as u8));
    let deps = dependencies(&insts, &scratch);
    let (mut slots, pair_cycles, cycles) = best_schedule(&insts, &deps, opts, &virtuals, start)?;
    place_hints(&insts, &mut slots, &pair_cycles, start);
    let assignment = allocate(&insts, &slots, &opts.pool, &virtuals)?;
    let mut out: Vec<(String, Option<usize>)> = vec![("\t.align\t3".to_string(), None)];
    out.extend(head);
    while matches!(slots.last(), Some(None)) {
        slots.pop();
    }
    for (k, slot) in slots.iter().enumerate() {
        match slot {
            Some(i) => {
                let inst = &insts[*i];
                for (label, origin) in &inst.labels {
                    out.push((label.clone(), Some(*origin)));
                }
                out.push((
                    format!("\t{}", rename(&inst.text, &virtuals, &assignment)),
                    Some(inst.origin),
                ));
            }
            None => out.push((
                if k % 2 == 0 { "\tnop" } else { "\tlnop" }.to_string(),
                None,
            )),
        }
    }
    Ok(Scheduled {
        lines: out,
        cycles,
        instructions: insts.len(),
    })
}

/// Expands `.irp VAR, values` ... `.endr` (nested) with `\VAR` substitution, as the
/// assembler does (`crate::expand`), after blanking `/* */` comments as the assembler
/// reads them (`crate::lex`): each line keeps its index.
fn expand_irp(lines: &[&str]) -> Result<Vec<(String, usize)>, SchedError> {
    let input: Vec<(String, usize)> = code_lines(lines).into_iter().zip(0..).collect();
    expand(&input, 0)
}

/// The lines with `/* */` comments (which may span lines) blanked, one for each line.
fn code_lines(lines: &[&str]) -> Vec<String> {
    if !lines.iter().any(|l| l.contains("/*")) {
        return lines.iter().map(|l| l.to_string()).collect();
    }
    let blanked = blank_block_comments(&lines.join("\n"));
    let mut out: Vec<String> = blanked.split('\n').map(str::to_string).collect();
    out.resize(lines.len(), String::new());
    out
}

fn expand(lines: &[(String, usize)], depth: usize) -> Result<Vec<(String, usize)>, SchedError> {
    if depth > 16 {
        return Err(err(
            lines.first().map_or(0, |l| l.1),
            1,
            ".irp nested too deeply",
        ));
    }
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let (text, origin) = &lines[i];
        if first_word(text) != ".irp" {
            out.push(lines[i].clone());
            i += 1;
            continue;
        }
        let Some(j) = block_end(lines, i + 1, |l| first_word(&l.0)) else {
            return Err(err(*origin, 1, "missing .endr"));
        };
        let args = strip_comment(text);
        let args = args.trim()[4..].trim();
        let (var, values) = irp_values(false, args);
        if var.is_empty() {
            return Err(err(*origin, 1, ".irp needs a name"));
        }
        for value in values {
            let vars = [(var.clone(), value)];
            let body: Vec<(String, usize)> = lines[i + 1..j]
                .iter()
                .map(|(t, o)| (substitute(t, &vars, None), *o))
                .collect();
            out.extend(expand(&body, depth + 1)?);
        }
        i = j + 1;
    }
    Ok(out)
}

fn parse_line(
    raw: &str,
    origin: usize,
    resolve: &dyn Fn(&str) -> Option<u8>,
    virtuals: &mut Vec<String>,
    items: &mut Vec<Item>,
) -> Result<(), SchedError> {
    let (code, comment) = split_comment(raw);
    let comment = comment.map(str::trim);
    let mut body = code.trim();
    if body.is_empty() {
        return Ok(());
    }
    let column = |part: &str| raw.find(part).map_or(1, |k| k + 1);
    let mut barrier = false;
    let mut free_store = false;
    loop {
        if let Some(rest) = body.strip_prefix('!') {
            barrier = true;
            body = rest.trim_start();
        } else if let Some(rest) = body.strip_prefix('~') {
            free_store = true;
            body = rest.trim_start();
        } else {
            break;
        }
    }
    // Labels (possibly followed by an instruction on the same line).
    while let Some(colon) = body.find(':') {
        let name = body[..colon].trim();
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '$'))
        {
            break;
        }
        items.push(Item::Label {
            text: format!("{name}:"),
            origin,
        });
        body = body[colon + 1..].trim();
    }
    if body.is_empty() {
        return Ok(());
    }
    let mut after_regs = Vec::new();
    let mut text = body.to_string();
    while let Some(k) = text.find("@after") {
        let rest = text[k + 6..].trim_start();
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        after_regs.push(rest[..end].to_string());
        text = format!("{}{}", text[..k].trim_end(), &rest[end..]);
    }
    let text = text.trim();
    let (mnemonic, operand_text) = match text.find(char::is_whitespace) {
        Some(k) => (&text[..k], text[k..].trim()),
        None => (text, ""),
    };
    let mnemonic_lc = mnemonic.to_ascii_lowercase();
    if mnemonic_lc.starts_with('.') {
        return Err(err(
            origin,
            column(mnemonic),
            format!("{mnemonic} in a .sched block (only instructions, labels and .irp)"),
        ));
    }
    if mnemonic_lc == "nop" || mnemonic_lc == "lnop" {
        return Ok(());
    }
    let operands: Vec<&str> = if operand_text.is_empty() {
        Vec::new()
    } else {
        operand_text.split(',').map(str::trim).collect()
    };
    let form = find_form(&mnemonic_lc, operands.len()).ok_or_else(|| {
        err(
            origin,
            column(mnemonic),
            format!(
                "`{mnemonic}` with {} operands is not an SPU instruction",
                operands.len()
            ),
        )
    })?;
    let op = form.op;
    let unit = op.info().unit;
    let usage = analysis::regs(op);
    let mut reg_of = |operand: &str| -> Result<Reg, SchedError> {
        register(operand, resolve, virtuals).ok_or_else(|| {
            err(
                origin,
                column(operand),
                format!("`{operand}`: not a register"),
            )
        })
    };
    let mut src = Vec::new();
    let mut dst = Vec::new();
    let mut operand_regs = Vec::new();
    let mut k = 0;
    for kind in form.operands {
        if *kind == OperandKind::ParenRa {
            // `offset(reg)`: the register is in the previous operand's parentheses.
            let operand = operands[k - 1];
            let inner = operand
                .rfind('(')
                .filter(|_| operand.ends_with(')'))
                .map(|p| &operand[p + 1..operand.len() - 1])
                .ok_or_else(|| {
                    err(
                        origin,
                        column(operand),
                        format!("`{operand}`: expected offset(register)"),
                    )
                })?;
            if usage.reads_ra {
                let r = reg_of(inner.trim())?;
                src.push(r);
                operand_regs.push(r);
            }
            continue;
        }
        let operand = operands[k];
        k += 1;
        match kind {
            OperandKind::Rt => {
                let r = reg_of(operand)?;
                if usage.reads_rt {
                    src.push(r);
                }
                if usage.writes_rt {
                    dst.push(r);
                }
                if usage.reads_rt || usage.writes_rt {
                    operand_regs.push(r);
                }
            }
            OperandKind::Ra | OperandKind::Rb | OperandKind::Rc => {
                let reads = match kind {
                    OperandKind::Ra => usage.reads_ra,
                    OperandKind::Rb => usage.reads_rb,
                    _ => usage.reads_rc,
                };
                if reads {
                    let r = reg_of(operand)?;
                    src.push(r);
                    operand_regs.push(r);
                }
            }
            _ => {}
        }
    }
    let mut after = Vec::new();
    for name in &after_regs {
        after.push(reg_of(name)?);
    }
    let hint = analysis::is_hint(op);
    let store = analysis::is_store(op);
    let channel = matches!(
        mnemonic_lc.as_str(),
        "wrch" | "rdch" | "rchcnt" | "stop" | "stopd"
    );
    let line_text = match comment {
        Some(c) if !c.is_empty() => format!("{}   # {c}", canonical(mnemonic, &operands)),
        _ => canonical(mnemonic, &operands),
    };
    items.push(Item::Inst(Inst {
        text: line_text,
        origin,
        pipe: unit.pipe(),
        latency: op.info().latency(),
        issue_cycles: if op.info().ext == Some(spu_isa::Extension::Gather) {
            spu_isa::ext::GATHER_LS_CYCLES
        } else {
            1
        },
        src,
        dst,
        after,
        barrier: barrier || analysis::is_branch(op) || channel,
        store: store && !free_store,
        any_store: store,
        load: analysis::is_load(op),
        hint,
        labels: Vec::new(),
        operand_regs,
    }));
    Ok(())
}

fn canonical(mnemonic: &str, operands: &[&str]) -> String {
    if operands.is_empty() {
        mnemonic.to_string()
    } else {
        format!("{mnemonic:<8}{}", operands.join(", "))
    }
}

/// The assembler form of `mnemonic` with `count` comma-separated operands.
fn find_form(mnemonic: &str, count: usize) -> Option<&'static FormInfo> {
    forms_named(mnemonic).find(|f| {
        f.operands
            .iter()
            .filter(|k| **k != OperandKind::ParenRa)
            .count()
            == count
    })
}

fn register(
    text: &str,
    resolve: &dyn Fn(&str) -> Option<u8>,
    virtuals: &mut Vec<String>,
) -> Option<Reg> {
    let text = text.trim();
    if let Some(name) = text.strip_prefix('%') {
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return None;
        }
        let k = match virtuals.iter().position(|v| v == name) {
            Some(k) => k,
            None => {
                virtuals.push(name.to_string());
                virtuals.len() - 1
            }
        };
        return Some(VIRTUAL_BASE + k as Reg);
    }
    if let Some(n) = text.strip_prefix('$').and_then(|d| d.parse::<u8>().ok()) {
        return (n < 128).then_some(n as Reg);
    }
    resolve(text).filter(|&n| n < 128).map(Reg::from)
}

/// For each instruction, the earlier ones it must follow and the cycles it must wait after
/// each (the producer's latency for a register it reads, else one).
fn dependencies(insts: &[Inst], scratch: &dyn Fn(Reg) -> bool) -> Vec<Vec<(usize, u32)>> {
    let mut deps = vec![Vec::new(); insts.len()];
    for (i, a) in insts.iter().enumerate() {
        let memory_a = a.load || a.any_store;
        for (j, b) in insts[..i].iter().enumerate() {
            let raw = a.src.iter().any(|r| b.dst.contains(r));
            let ordered = raw
                || a.dst.iter().any(|r| b.src.contains(r) || b.dst.contains(r))
                || a.after.iter().any(|r| b.dst.contains(r))
                || a.barrier
                || (a.store && (b.load || b.store || b.barrier))
                || (b.barrier && memory_a)
                || (b.barrier && a.dst.iter().any(|&r| !scratch(r)))
                || (a.hint && b.barrier)
                || (b.hint && a.barrier);
            if ordered {
                deps[i].push((j, if raw { b.latency } else { 1 }));
            }
        }
    }
    deps
}

/// Instruction fetch reads 128-byte lines (docs/timing.md, R8).
const FETCH_LINE: u32 = 128;
/// The last pair of a line (0..15) that may leave the prefetch of the next line waiting
/// for a free local-store cycle: a fill takes 6 cycles after it, so a line whose first
/// free cycle comes later makes the next line wait (8 rather than 10 leaves a margin for
/// the request itself, measured on the kernels' loops).
const LATEST_FETCH_SLOT: u32 = 8;

/// The slots of a schedule (even, odd, even, odd, ...), the issue cycle of each pair, and
/// the number of issue cycles.
type Schedule = (Vec<Option<usize>>, Vec<u32>, u32);

/// How the list scheduler picks among the ready instructions.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Rank {
    /// The longest path to the block's end first (ties: program order).
    CriticalPath,
    /// Program order. With many independent chains and a small pool, ranking by critical
    /// path issues every chain's loads first, fills the pool and then waits on it.
    ProgramOrder,
    /// The critical path while at most half the pool is live, program order above.
    Pressure,
}

/// The schedule with the fewest cycles of the three ranks (the earlier rank on a tie), so
/// no block takes longer than the critical path's schedule alone gave it.
fn best_schedule(
    insts: &[Inst],
    deps: &[Vec<(usize, u32)>],
    opts: &SchedOptions,
    virtuals: &[String],
    start: Option<u32>,
) -> Result<Schedule, SchedError> {
    let schedule = |rank| list_schedule(insts, deps, opts.pool.len(), virtuals.len(), start, rank);
    let mut best = schedule(Rank::CriticalPath);
    for rank in [Rank::ProgramOrder, Rank::Pressure] {
        let s = schedule(rank);
        let better = match (&best, &s) {
            (Err(_), _) => true,
            (Ok(a), Ok(b)) => b.2 < a.2,
            (Ok(_), Err(_)) => false,
        };
        if better {
            best = s;
        }
    }
    best
}

/// Cycle-by-cycle list scheduling.
fn list_schedule(
    insts: &[Inst],
    deps: &[Vec<(usize, u32)>],
    pool: usize,
    virtual_count: usize,
    start: Option<u32>,
    rank: Rank,
) -> Result<Schedule, SchedError> {
    let n = insts.len();
    // Critical path to the end of the block.
    let mut succs = vec![Vec::new(); n];
    for (i, d) in deps.iter().enumerate() {
        for &(j, _) in d {
            succs[j].push(i);
        }
    }
    let mut prio = vec![0u32; n];
    for i in (0..n).rev() {
        let tail = succs[i].iter().map(|&k| prio[k]).max().unwrap_or(0);
        prio[i] = insts[i].latency + tail;
    }
    // Register pressure: uses left per virtual register, and which are live.
    let mut uses_left = vec![0u32; virtual_count];
    let virtual_regs = |inst: &Inst| -> Vec<usize> {
        let mut v: Vec<usize> = inst
            .src
            .iter()
            .chain(&inst.dst)
            .filter(|&&r| r >= VIRTUAL_BASE)
            .map(|&r| (r - VIRTUAL_BASE) as usize)
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let regs_of: Vec<Vec<usize>> = insts.iter().map(virtual_regs).collect();
    for regs in &regs_of {
        for &v in regs {
            uses_left[v] += 1;
        }
    }
    let mut live = vec![false; virtual_count];
    let limited = virtual_count > 0;
    // `live_now`: how many of `live` are set.
    let pressure_ok = |i: usize, live: &[bool], uses_left: &[u32], live_now: usize| -> bool {
        if !limited {
            return true;
        }
        let regs = &regs_of[i];
        let new = regs.iter().filter(|&&v| !live[v]).count();
        let freed = regs
            .iter()
            .filter(|&&v| live[v] && uses_left[v] == 1)
            .count();
        if live_now + new > pool {
            return false;
        }
        // Growth keeps a margin so that work that frees registers can always issue.
        let margin = if pool >= 16 { 4 } else { (pool / 4).max(1) };
        new <= freed || live_now + new + margin <= pool
    };
    let retire = |i: usize, live: &mut [bool], uses_left: &mut [u32]| {
        for &v in &regs_of[i] {
            uses_left[v] -= 1;
            live[v] = uses_left[v] > 0;
        }
    };
    let mut issued: Vec<Option<u32>> = vec![None; n];
    let ready = |i: usize, t: u32, issued: &[Option<u32>]| {
        deps[i]
            .iter()
            .all(|&(j, lat)| issued[j].is_some_and(|c| c + lat <= t))
    };
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut slots = Vec::new();
    let mut pair_cycles = Vec::new();
    // A block is entered by a branch or falls in: either way its line's successor may be
    // waiting for a free local-store cycle.
    let mut fetch_pending = true;
    let mut t = 0u32;
    let mut idle = 0u32;
    while !remaining.is_empty() {
        // The pair's place in its 128-byte fetch line: a line that starts requests the
        // next one, which is filled in the first cycle without a load, store or hint.
        let line_slot = start.map(|a| ((a + 4 * slots.len() as u32) % FETCH_LINE) / 8);
        if line_slot == Some(0) {
            fetch_pending = true;
        }
        let avoid_ls = fetch_pending && line_slot.is_some_and(|p| p >= LATEST_FETCH_SLOT);
        let best = |pipe: Pipe,
                    exclude: Option<usize>,
                    issued: &[Option<u32>],
                    live: &[bool],
                    uses: &[u32]| {
            let live_now = live.iter().filter(|&&l| l).count();
            let by_order = match rank {
                Rank::CriticalPath => false,
                Rank::ProgramOrder => true,
                Rank::Pressure => 2 * live_now > pool,
            };
            remaining
                .iter()
                .copied()
                .filter(|&i| insts[i].pipe == pipe && Some(i) != exclude)
                .filter(|&i| !(avoid_ls && pipe == Pipe::Odd && insts[i].uses_ls()))
                .filter(|&i| ready(i, t, issued) && pressure_ok(i, live, uses, live_now))
                .filter(|&i| exclude.is_none_or(|e| !deps[i].iter().any(|d| d.0 == e)))
                .min_by_key(|&i| (std::cmp::Reverse(if by_order { 0 } else { prio[i] }), i))
        };
        let even = best(Pipe::Even, None, &issued, &live, &uses_left);
        if let Some(e) = even {
            retire(e, &mut live, &mut uses_left);
        }
        let odd = best(Pipe::Odd, even, &issued, &live, &uses_left);
        if let Some(o) = odd {
            retire(o, &mut live, &mut uses_left);
        }
        if even.is_none() && odd.is_none() {
            // Nothing fits the pool: after a while take the oldest ready instruction.
            if idle > 12 {
                if let Some(i) = remaining.iter().copied().find(|&i| ready(i, t, &issued)) {
                    retire(i, &mut live, &mut uses_left);
                    issued[i] = Some(t);
                    remaining.retain(|&k| k != i);
                    if insts[i].pipe == Pipe::Even {
                        slots.extend([Some(i), None]);
                    } else {
                        slots.extend([None, Some(i)]);
                    }
                    pair_cycles.push(t);
                    fetch_pending &= insts[i].uses_ls();
                    idle = 0;
                    t += insts[i].issue_cycles;
                    continue;
                }
            }
            fetch_pending = false;
            idle += 1;
            if idle > 10_000 {
                return Err(err(
                    insts[remaining[0]].origin,
                    0,
                    "the block cannot be scheduled with this pool",
                ));
            }
            t += 1;
            continue;
        }
        idle = 0;
        for slot in [even, odd] {
            if let Some(i) = slot {
                issued[i] = Some(t);
                remaining.retain(|&k| k != i);
            }
            slots.push(slot);
        }
        pair_cycles.push(t);
        fetch_pending &= odd.is_some_and(|o| insts[o].uses_ls());
        t += odd.map_or(1, |o| insts[o].issue_cycles);
    }
    Ok((slots, pair_cycles, t))
}

/// Moves each hint that is not a barrier to the latest free odd slot from which the
/// branch ending the block can still use it: at least 8 instructions and 11 cycles ahead
/// (docs/timing.md, R5). Late hints keep the local store free for the loads and the
/// instruction fetch of the block's start; a hint with no such slot stays where it is.
fn place_hints(
    insts: &[Inst],
    slots: &mut [Option<usize>],
    pair_cycles: &[u32],
    start: Option<u32>,
) {
    const MIN_INSTRUCTIONS: usize = 8;
    const MIN_CYCLES: u32 = 11;
    let Some(end) = slots.iter().rposition(Option::is_some) else {
        return;
    };
    let end_cycle = pair_cycles[end / 2];
    for k in 0..slots.len() {
        let Some(i) = slots[k] else { continue };
        if !insts[i].hint || insts[i].barrier {
            continue;
        }
        // A slot the instruction prefetch of its line relies on stays free.
        let keeps_fetch = |slots: &[Option<usize>], s: usize| {
            let Some(a) = start else { return true };
            let line_of = |p: usize| (a + 8 * p as u32) / FETCH_LINE;
            let slot_in_line = |p: usize| ((a + 8 * p as u32) % FETCH_LINE) / 8;
            let pair = s / 2;
            if slot_in_line(pair) > LATEST_FETCH_SLOT {
                return true;
            }
            (0..slots.len() / 2).any(|p| {
                p != pair
                    && line_of(p) == line_of(pair)
                    && slot_in_line(p) <= LATEST_FETCH_SLOT
                    && slots[2 * p + 1].is_none_or(|o| !insts[o].uses_ls())
            })
        };
        let target = (k..end.saturating_sub(MIN_INSTRUCTIONS - 1))
            .rev()
            .find(|&s| {
                s % 2 == 1
                    && slots[s].is_none()
                    && pair_cycles[s / 2] + MIN_CYCLES <= end_cycle
                    && keeps_fetch(slots, s)
            });
        if let Some(free) = target {
            slots[free] = Some(i);
            slots[k] = None;
        }
    }
}

/// Assigns pool registers to virtual ones in issue order: a virtual register keeps one
/// register from its first appearance to its last, which is then free for the next.
fn allocate(
    insts: &[Inst],
    slots: &[Option<usize>],
    pool: &[u8],
    virtuals: &[String],
) -> Result<Vec<u8>, SchedError> {
    let order: Vec<usize> = slots.iter().flatten().copied().collect();
    let mut last = vec![0usize; virtuals.len()];
    for (k, &i) in order.iter().enumerate() {
        for &r in &insts[i].operand_regs {
            if r >= VIRTUAL_BASE {
                last[(r - VIRTUAL_BASE) as usize] = k;
            }
        }
    }
    let mut free: std::collections::VecDeque<u8> = pool.iter().copied().collect();
    let mut assignment: Vec<Option<u8>> = vec![None; virtuals.len()];
    for (k, &i) in order.iter().enumerate() {
        let inst = &insts[i];
        let mut regs: Vec<usize> = Vec::new();
        for &r in &inst.operand_regs {
            if r >= VIRTUAL_BASE && !regs.contains(&((r - VIRTUAL_BASE) as usize)) {
                regs.push((r - VIRTUAL_BASE) as usize);
            }
        }
        for &v in &regs {
            if assignment[v].is_none() {
                assignment[v] = Some(free.pop_front().ok_or_else(|| {
                    err(
                        inst.origin,
                        0,
                        format!("the pool has no register left for %{}", virtuals[v]),
                    )
                })?);
            }
        }
        for &v in &regs {
            if last[v] == k {
                free.extend(assignment[v]);
            }
        }
    }
    Ok(assignment.into_iter().map(|a| a.unwrap_or(0)).collect())
}

/// `%name` replaced by its register.
fn rename(text: &str, virtuals: &[String], assignment: &[u8]) -> String {
    let (code, comment) = split_comment(text);
    let mut out = String::new();
    let mut rest = code.as_str();
    while let Some(k) = rest.find('%') {
        out.push_str(&rest[..k]);
        let name_len = rest[k + 1..]
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(rest.len() - k - 1);
        let name = &rest[k + 1..k + 1 + name_len];
        match virtuals.iter().position(|v| v == name) {
            Some(v) => out.push_str(&format!("${}", assignment[v])),
            None => out.push_str(&rest[k..k + 1 + name_len]),
        }
        rest = &rest[k + 1 + name_len..];
    }
    out.push_str(rest);
    if let Some(comment) = comment {
        out.push('#');
        out.push_str(comment);
    }
    out
}

/// Register names for scheduling outside the assembler (`spu sched`): the `.set`/`.equ`
/// definitions of a source and its includes, evaluated in order as the assembler would.
#[derive(Clone, Debug, Default)]
pub struct Names {
    values: std::collections::HashMap<String, i64>,
}

impl crate::expr::Env for Names {
    fn symbol(&self, name: &str) -> Option<crate::expr::Val> {
        self.values.get(name).map(|&v| crate::expr::Val::abs(v))
    }
    fn dot(&self) -> crate::expr::Val {
        crate::expr::Val::abs(0)
    }
    fn local(&self, _: u32, _: bool) -> Option<crate::expr::Val> {
        None
    }
    fn lenient(&self) -> bool {
        false
    }
}

impl Names {
    /// Takes the `.set NAME, EXPR` / `.equ` / `.eqv` / `NAME = EXPR` lines of `text` whose
    /// value is a constant; `include` gives the text of an `.include`d file, if found.
    pub fn collect(&mut self, text: &str, include: &mut dyn FnMut(&str) -> Option<String>) {
        self.collect_depth(text, include, 0);
    }

    fn collect_depth(
        &mut self,
        text: &str,
        include: &mut dyn FnMut(&str) -> Option<String>,
        depth: usize,
    ) {
        for line in blank_block_comments(text).lines() {
            let code = strip_comment(line);
            let code = code.trim();
            let word = code
                .split_whitespace()
                .next()
                .unwrap_or("")
                .to_ascii_lowercase();
            let rest = code[word.len().min(code.len())..].trim();
            let (name, expr) = match word.as_str() {
                ".set" | ".equ" | ".eqv" => match rest.split_once(',') {
                    Some((n, e)) => (n.trim(), e.trim()),
                    None => continue,
                },
                ".include" if depth < 16 => {
                    if let Some(inner) = include(rest.trim_matches('"')) {
                        self.collect_depth(&inner, include, depth + 1);
                    }
                    continue;
                }
                _ => match code.split_once('=') {
                    Some((n, e))
                        if !n.trim().contains(char::is_whitespace) && !e.starts_with('=') =>
                    {
                        (n.trim(), e.trim())
                    }
                    _ => continue,
                },
            };
            if let Some(v) = self.value(expr) {
                self.values.insert(name.to_string(), v);
            }
        }
    }

    fn value(&self, expr: &str) -> Option<i64> {
        let (ast, rest) = crate::expr::parse(expr)?;
        if !rest.trim().is_empty() {
            return None;
        }
        let mut eval = crate::expr::Eval {
            env: self,
            warnings: Vec::new(),
            undefined: false,
        };
        eval.eval(&ast).ok().map(|v| v.v)
    }

    /// The value of a defined name.
    pub fn value_of(&self, name: &str) -> Option<i64> {
        self.values.get(name).copied()
    }

    /// The register a scheduled operand names: `$lr`, `$sp`, a name or an expression.
    pub fn register(&self, text: &str) -> Option<u8> {
        let t = text.trim();
        let t = t.strip_prefix('$').unwrap_or(t);
        match t {
            "lr" | "rp" => return Some(0),
            "sp" => return Some(1),
            "fp" => return Some(127),
            _ => {}
        }
        self.value(t)
            .and_then(|v| u8::try_from(v).ok())
            .filter(|&r| r < 128)
    }
}

/// The `.sched` blocks of a source: (index of the `.sched` line, index of `.endsched`).
pub fn find_blocks(lines: &[&str]) -> Result<Vec<(usize, usize)>, SchedError> {
    let mut blocks = Vec::new();
    let mut open: Option<usize> = None;
    for (k, line) in code_lines(lines).iter().enumerate() {
        match first_word(line).as_str() {
            ".sched" if open.is_some() => return Err(err(k, 1, ".sched inside a .sched block")),
            ".sched" => open = Some(k),
            ".endsched" => match open.take() {
                Some(start) => blocks.push((start, k)),
                None => return Err(err(k, 1, ".endsched without a matching start")),
            },
            _ => {}
        }
    }
    match open {
        Some(start) => Err(err(start, 1, "missing .endsched")),
        None => Ok(blocks),
    }
}
