//! Profile counters of the timing model, their totals, merging, and the reports built on
//! them: the annotated `spu prof` listing, the IBM-simulator-style totals, and the static
//! `spu timing` listing in the layout of IBM's `spu_timing`.
//!
//! Counting is per instruction address (word index into the 256 KiB local store): how often
//! it executed, the cycles charged to it (its own issue cycle unless it dual-issued as the
//! second of a pair, plus every stall cycle charged to it), how often it dual-issued, and
//! its stall cycles by cause. The sum of the cycles over all addresses is the total cycle
//! count. A branch miss is charged to the branch, every other stall to the instruction
//! that waited.

use crate::table::Unit;
use crate::timing::{StallCause, STALL_CLASSES};
use std::collections::HashMap;
use std::fmt::Write as _;

/// Counters of one instruction address.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PcStats {
    pub executions: u64,
    /// Cycles charged to this instruction (issue cycle + stalls charged to it).
    pub cycles: u64,
    /// Executions in which it issued as half of a dual-issued pair.
    pub dual: u64,
    /// Stall cycles by cause, indexed by [`StallCause::index`].
    pub stall: [u64; STALL_CLASSES],
    /// The first two producing instructions its dependency stalls waited on (address,
    /// cycles); further ones go to the profile's overflow map.
    dep_from: [(u32, u64); 2],
}

impl PcStats {
    pub fn stall_total(&self) -> u64 {
        self.stall.iter().sum()
    }

    fn merge(&mut self, o: &PcStats, extra: &mut HashMap<(u32, u32), u64>, pc: u32) {
        self.executions += o.executions;
        self.cycles += o.cycles;
        self.dual += o.dual;
        for i in 0..STALL_CLASSES {
            self.stall[i] += o.stall[i];
        }
        for &(p, c) in o.dep_from.iter().filter(|e| e.1 > 0) {
            add_dep(&mut self.dep_from, extra, pc, p, c);
        }
    }
}

#[inline]
fn add_dep(
    slots: &mut [(u32, u64); 2],
    extra: &mut HashMap<(u32, u32), u64>,
    pc: u32,
    producer: u32,
    n: u64,
) {
    if slots[0].0 == producer || slots[0].1 == 0 {
        slots[0] = (producer, slots[0].1 + n);
    } else if slots[1].0 == producer || slots[1].1 == 0 {
        slots[1] = (producer, slots[1].1 + n);
    } else {
        *extra.entry((pc, producer)).or_default() += n;
    }
}

/// Whole-run counters, as IBM's full-system simulator reported them per SPU.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Totals {
    /// Instructions executed, including no-ops.
    pub instructions: u64,
    /// `nop`, `lnop` and branch hints (IBM counts hints as no-ops).
    pub nops: u64,
    /// Total cycles (filled in by `Timing::finish_profile`; summed over SPUs by `merge`).
    pub cycles: u64,
    /// Cycles in which both pipes issued.
    pub dual_cycles: u64,
    pub branches_taken: u64,
    pub branches_not_taken: u64,
    /// Branches that paid the miss penalty (taken unhinted, or hinted wrongly).
    pub branch_misses: u64,
    /// Branch hint instructions (`hbr`, `hbra`, `hbrr`; not `hbrp`).
    pub hints: u64,
    /// Taken branches whose hint named the right target.
    pub hint_hits: u64,
    /// Stall cycles by cause, indexed by [`StallCause::index`].
    pub stall: [u64; STALL_CLASSES],
    /// Dependency stall cycles by the producing instruction's class (`Unit as usize`).
    pub dep_by_unit: [u64; 12],
    /// Times a pair could not dual-issue because the second read the first's result.
    pub pair_dependency: u64,
    /// Cycles a load, store or hint took the local store while an instruction prefetch
    /// waited.
    pub ls_contention: u64,
    /// Cycles DMA took the local store while an instruction prefetch waited.
    pub dma_contention: u64,
    /// Cycles that passed without the SPU running (`Timing::advance_to`).
    pub idle_cycles: u64,
    /// Number of SPUs merged into these totals (1 for one SPU).
    pub spus: u32,
}

impl Totals {
    /// Cycles in which exactly one instruction issued.
    pub fn single_cycles(&self) -> u64 {
        self.instructions.saturating_sub(2 * self.dual_cycles)
    }

    pub fn stall_cycles(&self) -> u64 {
        self.stall.iter().sum()
    }

    pub fn cpi(&self) -> f64 {
        if self.instructions == 0 {
            0.0
        } else {
            self.cycles as f64 / self.instructions as f64
        }
    }

    /// CPI counting only the instructions that are not no-ops.
    pub fn cpi_without_nops(&self) -> f64 {
        let n = self.instructions - self.nops;
        if n == 0 {
            0.0
        } else {
            self.cycles as f64 / n as f64
        }
    }

    /// `self - earlier` for the counters the timing model increments.
    pub(crate) fn since(&self, earlier: &Totals) -> Totals {
        let mut d = self.clone();
        d.scale_sub(earlier);
        d.spus = 0;
        d
    }

    fn scale_sub(&mut self, o: &Totals) {
        self.instructions -= o.instructions;
        self.nops -= o.nops;
        self.cycles -= o.cycles;
        self.dual_cycles -= o.dual_cycles;
        self.branches_taken -= o.branches_taken;
        self.branches_not_taken -= o.branches_not_taken;
        self.branch_misses -= o.branch_misses;
        self.hints -= o.hints;
        self.hint_hits -= o.hint_hits;
        for i in 0..STALL_CLASSES {
            self.stall[i] -= o.stall[i];
        }
        for i in 0..12 {
            self.dep_by_unit[i] -= o.dep_by_unit[i];
        }
        self.pair_dependency -= o.pair_dependency;
        self.ls_contention -= o.ls_contention;
        self.dma_contention -= o.dma_contention;
        self.idle_cycles -= o.idle_cycles;
    }

    /// Adds `times` × `d`.
    pub(crate) fn add_scaled(&mut self, d: &Totals, times: u64) {
        self.instructions += d.instructions * times;
        self.nops += d.nops * times;
        self.cycles += d.cycles * times;
        self.dual_cycles += d.dual_cycles * times;
        self.branches_taken += d.branches_taken * times;
        self.branches_not_taken += d.branches_not_taken * times;
        self.branch_misses += d.branch_misses * times;
        self.hints += d.hints * times;
        self.hint_hits += d.hint_hits * times;
        for i in 0..STALL_CLASSES {
            self.stall[i] += d.stall[i] * times;
        }
        for i in 0..12 {
            self.dep_by_unit[i] += d.dep_by_unit[i] * times;
        }
        self.pair_dependency += d.pair_dependency * times;
        self.ls_contention += d.ls_contention * times;
        self.dma_contention += d.dma_contention * times;
        self.idle_cycles += d.idle_cycles * times;
    }

    fn merge(&mut self, o: &Totals) {
        self.instructions += o.instructions;
        self.nops += o.nops;
        self.cycles += o.cycles;
        self.dual_cycles += o.dual_cycles;
        self.branches_taken += o.branches_taken;
        self.branches_not_taken += o.branches_not_taken;
        self.branch_misses += o.branch_misses;
        self.hints += o.hints;
        self.hint_hits += o.hint_hits;
        for i in 0..STALL_CLASSES {
            self.stall[i] += o.stall[i];
        }
        for i in 0..12 {
            self.dep_by_unit[i] += o.dep_by_unit[i];
        }
        self.pair_dependency += o.pair_dependency;
        self.ls_contention += o.ls_contention;
        self.dma_contention += o.dma_contention;
        self.idle_cycles += o.idle_cycles;
        self.spus += o.spus;
    }

    /// The totals in the layout of IBM's simulator (`spu stats`).
    pub fn report(&self) -> String {
        let mut s = String::new();
        let cyc = self.cycles.max(1) as f64;
        let pct = |n: u64| 100.0 * n as f64 / cyc;
        let _ = writeln!(s, "  Total Cycle count               {}", self.cycles);
        let _ = writeln!(
            s,
            "  Total Instruction count         {} ({})",
            self.instructions,
            self.instructions - self.nops
        );
        let _ = writeln!(
            s,
            "  Total CPI                       {:.2} ({:.2})",
            self.cpi(),
            self.cpi_without_nops()
        );
        let _ = writeln!(
            s,
            "  Branch instructions             {}",
            self.branches_taken + self.branches_not_taken
        );
        let _ = writeln!(
            s,
            "  Branch taken                    {}",
            self.branches_taken
        );
        let _ = writeln!(
            s,
            "  Branch not taken                {}",
            self.branches_not_taken
        );
        let _ = writeln!(s, "  Hint instructions               {}", self.hints);
        let _ = writeln!(s, "  Hint hit                        {}", self.hint_hits);
        let _ = writeln!(
            s,
            "  Contention at LS between Load/Store and Prefetch {}",
            self.ls_contention
        );
        let _ = writeln!(
            s,
            "  Contention at LS between DMA and Prefetch        {}",
            self.dma_contention
        );
        let rows: [(&str, u64); 9] = [
            ("Single cycle", self.single_cycles()),
            ("Dual cycle", self.dual_cycles),
            (
                "Stall due to branch miss",
                self.stall[StallCause::BranchMiss.index()],
            ),
            (
                "Stall due to prefetch miss",
                self.stall[StallCause::Fetch.index()],
            ),
            (
                "Stall due to dependency",
                self.stall[StallCause::Dependency.index()],
            ),
            (
                "Stall due to waiting for hint target",
                self.stall[StallCause::Hint.index()],
            ),
            (
                "Stall due to dp pipeline",
                self.stall[StallCause::DoublePrecision.index()],
            ),
            (
                "Channel stall cycle",
                self.stall[StallCause::Channel(0).index()],
            ),
            ("Idle cycle", self.idle_cycles),
        ];
        for (name, n) in rows {
            let _ = writeln!(s, "  {name:<48}{n:>12} ({:5.1}%)", pct(n));
        }
        let _ = writeln!(
            s,
            "  {:<48}{:>12} ({:5.1}%)",
            "Total cycle", self.cycles, 100.0
        );
        let _ = writeln!(
            s,
            "  Dual issue prevented by a dependency within the pair {}",
            self.pair_dependency
        );
        let _ = writeln!(s, "  Stall cycles due to dependency on each pipelines");
        for unit in UNITS {
            let _ = writeln!(
                s,
                "   {:<10} {}",
                unit_name(unit),
                self.dep_by_unit[unit as usize]
            );
        }
        s
    }

    /// The totals as a JSON object.
    pub fn json(&self) -> String {
        let mut s = String::from("{");
        let _ = write!(
            s,
            "\"cycles\":{},\"instructions\":{},\"instructions_without_nops\":{},\"cpi\":{},\"cpi_without_nops\":{},\
             \"single_cycles\":{},\"dual_cycles\":{},\"branches_taken\":{},\"branches_not_taken\":{},\
             \"branch_misses\":{},\"hints\":{},\"hint_hits\":{},\"pair_dependency\":{},\"ls_contention\":{},\
             \"dma_contention\":{},\"idle_cycles\":{},\"spus\":{},\"stall\":{}",
            self.cycles,
            self.instructions,
            self.instructions - self.nops,
            json_f64(self.cpi()),
            json_f64(self.cpi_without_nops()),
            self.single_cycles(),
            self.dual_cycles,
            self.branches_taken,
            self.branches_not_taken,
            self.branch_misses,
            self.hints,
            self.hint_hits,
            self.pair_dependency,
            self.ls_contention,
            self.dma_contention,
            self.idle_cycles,
            self.spus,
            stall_json(&self.stall),
        );
        s.push_str(",\"dependency_by_unit\":{");
        for (i, unit) in UNITS.iter().enumerate() {
            if i > 0 {
                s.push(',');
            }
            let _ = write!(
                s,
                "\"{}\":{}",
                unit_name(*unit),
                self.dep_by_unit[*unit as usize]
            );
        }
        s.push_str("}}");
        s
    }
}

/// The execution classes in IBM's report order.
pub const UNITS: [Unit; 12] = [
    Unit::FX2,
    Unit::SHUF,
    Unit::FX3,
    Unit::LS,
    Unit::BR,
    Unit::SPR,
    Unit::LNOP,
    Unit::NOP,
    Unit::FXB,
    Unit::FP6,
    Unit::FP7,
    Unit::FPD,
];

pub fn unit_name(u: Unit) -> &'static str {
    match u {
        Unit::FX2 => "FX2",
        Unit::FX3 => "FX3",
        Unit::FXB => "FXB",
        Unit::FP6 => "FP6",
        Unit::FP7 => "FP7",
        Unit::FPD => "FPD",
        Unit::NOP => "NOP",
        Unit::SHUF => "SHUF",
        Unit::LS => "LS",
        Unit::BR => "BR",
        Unit::SPR => "SPR",
        Unit::LNOP => "LNOP",
    }
}

/// A JSON number for a float (finite, two decimals are enough for CPI).
pub fn json_f64(x: f64) -> String {
    if x.is_finite() {
        format!("{:.4}", x)
    } else {
        "null".into()
    }
}

/// A JSON string literal.
pub fn json_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn stall_json(stall: &[u64; STALL_CLASSES]) -> String {
    let mut s = String::from("{");
    for (i, name) in StallCause::NAMES.iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        let _ = write!(s, "\"{name}\":{}", stall[i]);
    }
    s.push('}');
    s
}

/// The counters of one SPU run (or of several, merged).
#[derive(Clone, Debug, Default)]
pub struct Profile {
    /// Indexed by word address (`pc >> 2`), grown on demand.
    pcs: Vec<PcStats>,
    /// Dependency stall cycles per (waiting address, producing address) beyond the two
    /// kept inline.
    dep_extra: HashMap<(u32, u32), u64>,
    /// Channel stall cycles per (address, channel).
    channels: HashMap<(u32, u8), u64>,
    pub totals: Totals,
    /// While the timing model records a block, every per-address change is also logged
    /// here so that the block's replays can repeat it.
    pub(crate) log: Option<Vec<LogEntry>>,
}

/// One per-address counter change: `field` 0 executions, 1 cycles, 2 dual, 3.. stall
/// class, `DEP` a dependency attribution to `producer`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LogEntry {
    pub(crate) pc: u32,
    pub(crate) field: u8,
    pub(crate) producer: u32,
    pub(crate) n: u64,
}

pub(crate) const DEP: u8 = 100;

impl Profile {
    pub fn new() -> Self {
        Profile {
            pcs: Vec::new(),
            dep_extra: HashMap::new(),
            channels: HashMap::new(),
            totals: Totals {
                spus: 1,
                ..Default::default()
            },
            log: None,
        }
    }

    #[inline]
    fn note(&mut self, pc: u32, field: u8, producer: u32, n: u64) {
        if let Some(log) = &mut self.log {
            log.push(LogEntry {
                pc,
                field,
                producer,
                n,
            });
        }
    }

    /// Applies logged changes `times` times.
    pub(crate) fn apply_log(&mut self, log: &[LogEntry], times: u64) {
        for e in log {
            let n = e.n * times;
            if e.field == DEP {
                let i = ((e.pc & 0x3_ffff) >> 2) as usize;
                self.at(e.pc);
                add_dep(
                    &mut self.pcs[i].dep_from,
                    &mut self.dep_extra,
                    e.pc,
                    e.producer,
                    n,
                );
                continue;
            }
            let s = self.at(e.pc);
            match e.field {
                0 => s.executions += n,
                1 => s.cycles += n,
                2 => s.dual += n,
                f => s.stall[(f - 3) as usize] += n,
            }
        }
    }

    #[inline]
    fn at(&mut self, pc: u32) -> &mut PcStats {
        let i = ((pc & 0x3_ffff) >> 2) as usize;
        if i >= self.pcs.len() {
            self.grow(i);
        }
        &mut self.pcs[i]
    }

    #[cold]
    fn grow(&mut self, i: usize) {
        let len = (i + 1).next_power_of_two().max(1024).min(0x1_0000);
        self.pcs.resize(len, PcStats::default());
    }

    /// One instruction issued at `pc` (`dual`: as the second of a pair with `pc - 4`).
    #[inline]
    pub(crate) fn issued(&mut self, pc: u32, nop: bool, dual: bool) {
        let t = &mut self.totals;
        t.instructions += 1;
        t.nops += nop as u64;
        if dual {
            t.dual_cycles += 1;
            self.at(pc.wrapping_sub(4)).dual += 1;
            let s = self.at(pc);
            s.executions += 1;
            s.dual += 1;
            if self.log.is_some() {
                self.note(pc.wrapping_sub(4), 2, 0, 1);
                self.note(pc, 0, 0, 1);
                self.note(pc, 2, 0, 1);
            }
        } else {
            let s = self.at(pc);
            s.executions += 1;
            s.cycles += 1;
            if self.log.is_some() {
                self.note(pc, 0, 0, 1);
                self.note(pc, 1, 0, 1);
            }
        }
    }

    /// `n` stall cycles of class `cause` charged to `pc`.
    #[inline]
    pub(crate) fn stall(&mut self, pc: u32, cause: StallCause, n: u64) {
        self.totals.stall[cause.index()] += n;
        let s = self.at(pc);
        s.stall[cause.index()] += n;
        s.cycles += n;
        if self.log.is_some() {
            self.note(pc, 3 + cause.index() as u8, 0, n);
            self.note(pc, 1, 0, n);
        }
    }

    /// `n` dependency stall cycles at `pc` waiting on the result of `producer`.
    #[inline]
    pub(crate) fn dependency(&mut self, pc: u32, producer: u32, unit: Unit, n: u64) {
        self.stall(pc, StallCause::Dependency, n);
        self.totals.dep_by_unit[unit as usize] += n;
        let i = ((pc & 0x3_ffff) >> 2) as usize;
        add_dep(
            &mut self.pcs[i].dep_from,
            &mut self.dep_extra,
            pc,
            producer,
            n,
        );
        self.note(pc, DEP, producer, n);
    }

    pub(crate) fn channel(&mut self, pc: u32, channel: u8, n: u64) {
        *self.channels.entry((pc, channel)).or_default() += n;
    }

    pub(crate) fn undo_dual(&mut self, pc: u32) {
        self.totals.dual_cycles -= 1;
        self.at(pc.wrapping_sub(4)).dual -= 1;
        self.at(pc).dual -= 1;
    }

    pub(crate) fn add_cycles(&mut self, pc: u32, n: u64) {
        self.at(pc).cycles += n;
    }

    /// The counters of `pc`, if it ever executed.
    pub fn get(&self, pc: u32) -> Option<&PcStats> {
        self.pcs
            .get(((pc & 0x3_ffff) >> 2) as usize)
            .filter(|s| s.executions > 0 || s.cycles > 0)
    }

    /// Every address that executed (or was charged cycles), in address order.
    pub fn addresses(&self) -> impl Iterator<Item = (u32, &PcStats)> {
        self.pcs
            .iter()
            .enumerate()
            .filter(|(_, s)| s.executions > 0 || s.cycles > 0)
            .map(|(i, s)| ((i as u32) << 2, s))
    }

    /// The producing instructions `pc`'s dependency stalls waited on, most cycles first.
    pub fn dependency_sources(&self, pc: u32) -> Vec<(u32, u64)> {
        let mut v: Vec<(u32, u64)> = Vec::new();
        if let Some(s) = self.get(pc) {
            v.extend(s.dep_from.iter().copied().filter(|e| e.1 > 0));
        }
        v.extend(
            self.dep_extra
                .iter()
                .filter(|(k, _)| k.0 == pc)
                .map(|(k, c)| (k.1, *c)),
        );
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        v
    }

    /// The channels `pc` waited on, with the cycles.
    pub fn channel_stalls(&self, pc: u32) -> Vec<(u8, u64)> {
        let mut v: Vec<(u8, u64)> = self
            .channels
            .iter()
            .filter(|(k, _)| k.0 == pc)
            .map(|(k, c)| (k.1, *c))
            .collect();
        v.sort();
        v
    }

    /// Channel stall cycles per channel over the whole run.
    pub fn channel_totals(&self) -> Vec<(u8, u64)> {
        let mut m: HashMap<u8, u64> = HashMap::new();
        for ((_, ch), c) in &self.channels {
            *m.entry(*ch).or_default() += c;
        }
        let mut v: Vec<(u8, u64)> = m.into_iter().collect();
        v.sort();
        v
    }

    /// Adds another SPU's counters (same program image) to these. Cycles add up (SPU
    /// cycles), so the merged CPI is the average over all instructions of all SPUs.
    pub fn merge(&mut self, other: &Profile) {
        if self.pcs.len() < other.pcs.len() {
            self.pcs.resize(other.pcs.len(), PcStats::default());
        }
        for (i, o) in other.pcs.iter().enumerate() {
            if o.executions > 0 || o.cycles > 0 {
                self.pcs[i].merge(o, &mut self.dep_extra, (i as u32) << 2);
            }
        }
        for (k, c) in &other.dep_extra {
            *self.dep_extra.entry(*k).or_default() += c;
        }
        for (k, c) in &other.channels {
            *self.channels.entry(*k).or_default() += c;
        }
        self.totals.merge(&other.totals);
    }

    /// Sums the counters of the addresses in `[start, end)`.
    pub fn range_totals(&self, start: u32, end: u32) -> RangeSum {
        let mut r = RangeSum::default();
        for (pc, s) in self.addresses() {
            if pc >= start && pc < end {
                r.add(s);
            }
        }
        r
    }
}

/// Counters summed over a range of addresses (a label's code, `--range`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RangeSum {
    pub executions: u64,
    pub cycles: u64,
    pub dual: u64,
    pub stall: [u64; STALL_CLASSES],
}

impl RangeSum {
    pub fn add(&mut self, s: &PcStats) {
        self.executions += s.executions;
        self.cycles += s.cycles;
        self.dual += s.dual;
        for i in 0..STALL_CLASSES {
            self.stall[i] += s.stall[i];
        }
    }

    pub fn cpi(&self) -> f64 {
        if self.executions == 0 {
            0.0
        } else {
            self.cycles as f64 / self.executions as f64
        }
    }
}

pub use listing::*;

/// The annotated `spu prof` listing.
mod listing {
    use super::*;

    /// One line of a program listing to annotate: an address with its text, or a label.
    #[derive(Clone, Debug)]
    pub enum ListingLine {
        Label(String),
        Inst { addr: u32, text: String },
    }

    /// The listing lines of every executed address of `image` (a local-store image), in
    /// address order: its labels from `symbols`, then its disassembly.
    pub fn executed_lines(
        profile: &Profile,
        image: &[u8],
        symbols: &[(String, u32)],
    ) -> Vec<ListingLine> {
        use crate::disasm::{instruction_text, SymbolTable};
        let table = SymbolTable::new(symbols.iter().map(|(n, a)| (*a, n.clone())).collect());
        let mut addresses: Vec<u32> = profile.addresses().map(|(a, _)| a).collect();
        addresses.sort_unstable();
        let mut lines = Vec::new();
        for addr in addresses {
            let mut names: Vec<&str> = table.at(addr).collect();
            names.sort_unstable();
            lines.extend(names.into_iter().map(|n| ListingLine::Label(n.to_string())));
            let word = image
                .get(addr as usize..addr as usize + 4)
                .map_or(0, |b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
            lines.push(ListingLine::Inst {
                addr,
                text: instruction_text(word, addr, &table).replace('\t', " "),
            });
        }
        lines
    }

    /// Options of the annotated listing.
    #[derive(Clone, Debug, Default)]
    pub struct ListingOptions {
        /// Only addresses in `[start, end)`.
        pub range: Option<(u32, u32)>,
        /// Leave out instructions that never executed.
        pub executed_only: bool,
    }

    /// The listing with executions, cycles, stall columns and a dual-issue mark, then the
    /// per-label summary and the totals.
    pub fn annotated_listing(
        profile: &Profile,
        lines: &[ListingLine],
        opts: &ListingOptions,
    ) -> String {
        let in_range = |a: u32| opts.range.map_or(true, |(s, e)| a >= s && a < e);
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{:>6} {:>10} {:>10} {:>6} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6}  D  source",
            "addr", "execs", "cycles", "cpi", "dep", "branch", "hint", "dp", "chan", "fetch"
        );
        let mut labels: Vec<(String, RangeSum)> = Vec::new();
        let mut current: Option<usize> = None;
        let mut range_sum = RangeSum::default();
        for line in lines {
            match line {
                ListingLine::Label(name) => {
                    labels.push((name.clone(), RangeSum::default()));
                    current = Some(labels.len() - 1);
                    let _ = writeln!(out, "{name}:");
                }
                ListingLine::Inst { addr, text } => {
                    if !in_range(*addr) {
                        continue;
                    }
                    let s = profile.get(*addr).copied().unwrap_or_default();
                    if opts.executed_only && s.executions == 0 {
                        continue;
                    }
                    if let Some(i) = current {
                        labels[i].1.add(&s);
                    }
                    range_sum.add(&s);
                    let cpi = if s.executions > 0 {
                        format!("{:.2}", s.cycles as f64 / s.executions as f64)
                    } else {
                        String::new()
                    };
                    let dual = if s.dual == 0 {
                        ' '
                    } else if s.dual == s.executions {
                        'D'
                    } else {
                        'd'
                    };
                    let col = |n: u64| if n == 0 { String::new() } else { n.to_string() };
                    let _ = write!(
                        out,
                        "{:>6x} {:>10} {:>10} {:>6} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6}  {}  {}",
                        addr,
                        col(s.executions),
                        col(s.cycles),
                        cpi,
                        col(s.stall[0]),
                        col(s.stall[1]),
                        col(s.stall[2]),
                        col(s.stall[3]),
                        col(s.stall[4]),
                        col(s.stall[5]),
                        dual,
                        text.replace('\t', " ")
                    );
                    let deps = profile.dependency_sources(*addr);
                    if !deps.is_empty() {
                        let list: Vec<String> =
                            deps.iter().map(|(p, c)| format!("{p:x}:{c}")).collect();
                        let _ = write!(out, "   # waits on {}", list.join(" "));
                    }
                    let chans = profile.channel_stalls(*addr);
                    if !chans.is_empty() {
                        let list: Vec<String> =
                            chans.iter().map(|(ch, c)| format!("$ch{ch}:{c}")).collect();
                        let _ = write!(out, "   # channel {}", list.join(" "));
                    }
                    out.push('\n');
                }
            }
        }
        out.push('\n');
        let _ = writeln!(out, "Per label:");
        let _ = writeln!(
            out,
            "  {:<24} {:>10} {:>10} {:>6} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6} {:>6}",
            "label",
            "execs",
            "cycles",
            "cpi",
            "dep",
            "branch",
            "hint",
            "dp",
            "chan",
            "fetch",
            "%cyc"
        );
        let total_cycles = range_sum.cycles.max(1) as f64;
        for (name, s) in labels
            .iter()
            .filter(|(_, s)| s.executions > 0 || s.cycles > 0)
        {
            let _ = writeln!(
                out,
                "  {:<24} {:>10} {:>10} {:>6.2} {:>8} {:>7} {:>6} {:>6} {:>6} {:>6} {:>5.1}%",
                name,
                s.executions,
                s.cycles,
                s.cpi(),
                s.stall[0],
                s.stall[1],
                s.stall[2],
                s.stall[3],
                s.stall[4],
                s.stall[5],
                100.0 * s.cycles as f64 / total_cycles
            );
        }
        out.push('\n');
        if opts.range.is_some() {
            let _ = writeln!(
                out,
                "Range: {} instructions, {} cycles, CPI {:.2}, {} dual-issued, stalls dep {} branch {} hint {} dp {} chan {} fetch {}",
                range_sum.executions,
                range_sum.cycles,
                range_sum.cpi(),
                range_sum.dual,
                range_sum.stall[0],
                range_sum.stall[1],
                range_sum.stall[2],
                range_sum.stall[3],
                range_sum.stall[4],
                range_sum.stall[5]
            );
            out.push('\n');
        }
        let _ = writeln!(out, "Totals:");
        out.push_str(&profile.totals.report());
        let chans = profile.channel_totals();
        if !chans.is_empty() {
            let _ = writeln!(out, "  Channel stall cycles by channel");
            for (ch, c) in chans {
                let _ = writeln!(out, "   $ch{ch:<8} {c}");
            }
        }
        out
    }

    /// The same data as JSON: `{"totals":{..},"instructions":[{addr,text,executions,
    /// cycles,dual,stall:{..},waits_on:[{addr,cycles}],channels:[..]}],"labels":[..]}`.
    pub fn listing_json(profile: &Profile, lines: &[ListingLine], opts: &ListingOptions) -> String {
        let in_range = |a: u32| opts.range.map_or(true, |(s, e)| a >= s && a < e);
        let mut insts = Vec::new();
        let mut labels: Vec<(String, u32, RangeSum)> = Vec::new();
        let mut range_sum = RangeSum::default();
        for line in lines {
            match line {
                ListingLine::Label(name) => {
                    labels.push((name.clone(), u32::MAX, RangeSum::default()))
                }
                ListingLine::Inst { addr, text } => {
                    if !in_range(*addr) {
                        continue;
                    }
                    let s = profile.get(*addr).copied().unwrap_or_default();
                    if opts.executed_only && s.executions == 0 {
                        continue;
                    }
                    if let Some(l) = labels.last_mut() {
                        l.1 = l.1.min(*addr);
                        l.2.add(&s);
                    }
                    range_sum.add(&s);
                    let deps: Vec<String> = profile
                        .dependency_sources(*addr)
                        .iter()
                        .map(|(p, c)| format!("{{\"addr\":{p},\"cycles\":{c}}}"))
                        .collect();
                    let chans: Vec<String> = profile
                        .channel_stalls(*addr)
                        .iter()
                        .map(|(ch, c)| format!("{{\"channel\":{ch},\"cycles\":{c}}}"))
                        .collect();
                    insts.push(format!(
                        "{{\"addr\":{},\"text\":{},\"executions\":{},\"cycles\":{},\"dual\":{},\"stall\":{},\"waits_on\":[{}],\"channels\":[{}]}}",
                        addr,
                        json_str(text),
                        s.executions,
                        s.cycles,
                        s.dual,
                        stall_json(&s.stall),
                        deps.join(","),
                        chans.join(",")
                    ));
                }
            }
        }
        let labels: Vec<String> = labels
            .iter()
            .filter(|l| l.2.executions > 0 || l.2.cycles > 0)
            .map(|(name, addr, s)| {
                format!(
                    "{{\"label\":{},\"addr\":{},\"executions\":{},\"cycles\":{},\"cpi\":{},\"dual\":{},\"stall\":{}}}",
                    json_str(name),
                    addr,
                    s.executions,
                    s.cycles,
                    json_f64(s.cpi()),
                    s.dual,
                    stall_json(&s.stall)
                )
            })
            .collect();
        let range = format!(
            "{{\"executions\":{},\"cycles\":{},\"cpi\":{},\"dual\":{},\"stall\":{}}}",
            range_sum.executions,
            range_sum.cycles,
            json_f64(range_sum.cpi()),
            range_sum.dual,
            stall_json(&range_sum.stall)
        );
        let chans: Vec<String> = profile
            .channel_totals()
            .iter()
            .map(|(ch, c)| format!("{{\"channel\":{ch},\"cycles\":{c}}}"))
            .collect();
        format!(
            "{{\"totals\":{},\"range\":{},\"channels\":[{}],\"labels\":[{}],\"instructions\":[{}]}}\n",
            profile.totals.json(),
            range,
            chans.join(","),
            labels.join(","),
            insts.join(",")
        )
    }
}

pub use static_timing::*;

/// Static timing of assembly source in the manner of IBM's `spu_timing`: the instructions
/// are timed as straight-line code (no branches taken, no fetch or local-store contention),
/// in address order, with the dual-issue and latency rules of the timing model.
mod static_timing {
    use super::*;
    use crate::codec::{decode, encode, Inst};
    use crate::table::{forms_named, OperandKind, Pipe};
    use crate::timing::{Timing, TimingConfig};

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
    }

    #[derive(Clone, Debug)]
    pub struct SourceInst {
        pub addr: u32,
        pub inst: Inst,
        pub mnemonic: String,
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
        Some(decode(encode(form, &ops, addr)))
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
                        ".align" | ".p2align" if in_text => {
                            let a = 1u32 << arg(0).unwrap_or(0).clamp(0, 16);
                            addr = addr.div_ceil(a) * a;
                        }
                        ".balign" if in_text => {
                            let a = arg(0).unwrap_or(1).clamp(1, 1 << 16) as u32;
                            addr = addr.div_ceil(a) * a;
                        }
                        ".word" | ".long" | ".int" | ".float" | ".ffloat" if in_text => {
                            addr += 4 * split_operands(rest).len() as u32
                        }
                        ".short" | ".half" | ".hword" if in_text => {
                            addr += 2 * split_operands(rest).len() as u32
                        }
                        ".byte" if in_text => addr += split_operands(rest).len() as u32,
                        ".quad" | ".double" | ".dfloat" if in_text => {
                            addr += 8 * split_operands(rest).len() as u32
                        }
                        ".space" | ".skip" if in_text => addr += arg(0).unwrap_or(0).max(0) as u32,
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
                    addr += 4;
                }
            }
            lines.push(line);
        }
        lines
    }

    /// The timing of one instruction in the static listing.
    #[derive(Clone, Debug, PartialEq, Eq)]
    pub struct StaticRow {
        pub addr: u32,
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
        pub label: Option<String>,
        pub addr: u32,
        pub instructions: u64,
        /// From its first issue to its last, inclusive.
        pub cycles: u64,
        /// Dual-issue cycles.
        pub dual: u64,
        pub stall: u64,
    }

    impl StaticBlock {
        pub fn cpi(&self) -> f64 {
            if self.instructions == 0 {
                0.0
            } else {
                self.cycles as f64 / self.instructions as f64
            }
        }
    }

    #[derive(Clone, Debug)]
    pub struct StaticTiming {
        pub lines: Vec<SourceLine>,
        pub rows: Vec<StaticRow>,
        pub blocks: Vec<StaticBlock>,
        /// The source lines shown (all, or the one block asked for).
        pub shown: std::ops::Range<usize>,
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
                    unit.latency()
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
        let insts: Vec<String> = t
            .rows
            .iter()
            .map(|r| {
                format!(
                    "{{\"addr\":{},\"text\":{},\"pipe\":{},\"issue\":{},\"cycle\":{},\"stall\":{},\"dual\":{},\"mark\":{},\"latency\":{},\"block\":{}}}",
                    r.addr,
                    json_str(&r.text),
                    r.pipe,
                    r.issue,
                    r.cycle,
                    r.stall,
                    r.dual,
                    json_str(r.mark.to_string().trim()),
                    r.latency,
                    r.block
                )
            })
            .collect();
        let blocks: Vec<String> = t
            .blocks
            .iter()
            .map(|b| {
                format!(
                    "{{\"label\":{},\"addr\":{},\"instructions\":{},\"cycles\":{},\"cpi\":{},\"dual\":{},\"stall\":{}}}",
                    b.label.as_deref().map(json_str).unwrap_or_else(|| "null".into()),
                    b.addr,
                    b.instructions,
                    b.cycles,
                    json_f64(b.cpi()),
                    b.dual,
                    b.stall
                )
            })
            .collect();
        format!(
            "{{\"blocks\":[{}],\"instructions\":[{}]}}\n",
            blocks.join(","),
            insts.join(",")
        )
    }
}
