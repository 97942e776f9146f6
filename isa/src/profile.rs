//! Profile counters of the timing model, their totals, merging, and the reports built on
//! them: the annotated `spu prof` listing and the IBM-simulator-style totals. (The static
//! `spu timing` listing drives the timing model, so it lives in [`crate::static_timing`].)
//!
//! Counting is per instruction address (word index into the 256 KiB local store): how often
//! it executed, the cycles charged to it (its own issue cycle unless it dual-issued as the
//! second of a pair, plus every stall cycle charged to it), how often it dual-issued, and
//! its stall cycles by cause. The sum of the cycles over all addresses is the total cycle
//! count. A branch miss is charged to the branch, every other stall to the instruction
//! that waited.

use crate::stall::{StallCause, STALL_CLASSES};
use crate::table::Unit;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::fmt::Write as _;

/// Counters of one instruction address.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PcStats {
    /// Times the instruction executed.
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
    /// All stall cycles charged to this instruction, over every cause.
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

/// The counters of `Totals` `$t` (all but `spus`) as an array, each read as `$($r)* $t.field`
/// (values, or `&mut` places): the one list of them.
macro_rules! counter_list {
    ($t:ident) => {
        counter_list!(@ $t [])
    };
    ($t:ident, &mut) => {
        counter_list!(@ $t [&mut])
    };
    (@ $t:ident [$($r:tt)*]) => {{
        let [s0, s1, s2, s3, s4, s5] = $($r)* $t.stall;
        let [d0, d1, d2, d3, d4, d5, d6, d7, d8, d9, d10, d11] = $($r)* $t.dep_by_unit;
        [
            $($r)* $t.instructions,
            $($r)* $t.nops,
            $($r)* $t.cycles,
            $($r)* $t.dual_cycles,
            $($r)* $t.branches_taken,
            $($r)* $t.branches_not_taken,
            $($r)* $t.branch_misses,
            $($r)* $t.hints,
            $($r)* $t.hint_hits,
            s0, s1, s2, s3, s4, s5,
            d0, d1, d2, d3, d4, d5, d6, d7, d8, d9, d10, d11,
            $($r)* $t.pair_dependency,
            $($r)* $t.ls_contention,
            $($r)* $t.dma_contention,
            $($r)* $t.idle_cycles,
        ]
    }};
}

/// How many counters [`Totals::counters`] lists.
pub(crate) const COUNTERS: usize = 9 + STALL_CLASSES + 12 + 4;
/// Where [`Totals::counters`] lists `stall[0]`.
pub(crate) const STALL_COUNTERS_AT: usize = 9;

/// Whole-run counters, as IBM's full-system simulator reported them per SPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Totals {
    /// Instructions executed, including no-ops.
    pub instructions: u64,
    /// `nop`, `lnop` and branch hints (IBM counts hints as no-ops).
    pub nops: u64,
    /// Total cycles (filled in by `Timing::finish_profile`; summed over SPUs by `merge`).
    pub cycles: u64,
    /// Cycles in which both pipes issued.
    pub dual_cycles: u64,
    /// Conditional and unconditional branches that were taken.
    pub branches_taken: u64,
    /// Conditional branches that fell through.
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

    /// All stall cycles, over every cause.
    pub fn stall_cycles(&self) -> u64 {
        self.stall.iter().sum()
    }

    /// Cycles per instruction over the run (0 before any instruction).
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

    /// `self - earlier` for the counters the timing model increments, in the order of
    /// [`Totals::counters`], when each fits 32 bits (as within one block it does).
    pub(crate) fn counters_since(&self, earlier: &Totals) -> Option<[u32; COUNTERS]> {
        let (now, then) = (self.counters(), earlier.counters());
        let mut d = [0u32; COUNTERS];
        for i in 0..COUNTERS {
            d[i] = u32::try_from(now[i] - then[i]).ok()?;
        }
        Some(d)
    }

    /// Adds `times` × `d` (counters in the order of [`Totals::counters`]).
    pub(crate) fn add_counters(&mut self, d: &[u32; COUNTERS], times: u64) {
        for (c, &v) in self.counters_mut().into_iter().zip(d) {
            *c += v as u64 * times;
        }
    }

    fn merge(&mut self, o: &Totals) {
        for (c, v) in self.counters_mut().into_iter().zip(o.counters()) {
            *c += v;
        }
        self.spus += o.spus;
    }

    /// Every counter the timing model increments (all but `spus`), in one order.
    pub(crate) fn counters(&self) -> [u64; COUNTERS] {
        counter_list!(self)
    }

    /// [`Totals::counters`], to change them.
    fn counters_mut(&mut self) -> [&mut u64; COUNTERS] {
        counter_list!(self, &mut)
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
        self.json_value().to_string()
    }

    /// The totals as a JSON value (keys in the order of IBM's report).
    pub fn json_value(&self) -> Value {
        let dependency_by_unit: serde_json::Map<String, Value> = UNITS
            .iter()
            .map(|&unit| {
                (
                    unit_name(unit).to_string(),
                    json!(self.dep_by_unit[unit as usize]),
                )
            })
            .collect();
        json!({
            "cycles": self.cycles,
            "instructions": self.instructions,
            "instructions_without_nops": self.instructions - self.nops,
            "cpi": json_ratio(self.cpi()),
            "cpi_without_nops": json_ratio(self.cpi_without_nops()),
            "single_cycles": self.single_cycles(),
            "dual_cycles": self.dual_cycles,
            "branches_taken": self.branches_taken,
            "branches_not_taken": self.branches_not_taken,
            "branch_misses": self.branch_misses,
            "hints": self.hints,
            "hint_hits": self.hint_hits,
            "pair_dependency": self.pair_dependency,
            "ls_contention": self.ls_contention,
            "dma_contention": self.dma_contention,
            "idle_cycles": self.idle_cycles,
            "spus": self.spus,
            "stall": stall_json(&self.stall),
            "dependency_by_unit": dependency_by_unit,
        })
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

/// The upper-case name of an execution class, as the reports print it (`FX2`, `LS`, ...).
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

/// A JSON number for a ratio such as a CPI: four decimals, `null` where it is not finite
/// (no instructions), so that the output is always valid JSON.
pub fn json_ratio(x: f64) -> Value {
    if x.is_finite() {
        json!((x * 1e4).round() / 1e4)
    } else {
        Value::Null
    }
}

fn stall_json(stall: &[u64; STALL_CLASSES]) -> Value {
    let map: serde_json::Map<String, Value> = StallCause::NAMES
        .iter()
        .zip(stall)
        .map(|(name, cycles)| (name.to_string(), json!(cycles)))
        .collect();
    Value::Object(map)
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
    /// The whole-run counters.
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
    /// An empty profile (every counter zero).
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
        let len = (i + 1).next_power_of_two().clamp(1024, 0x1_0000);
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
    /// Times instructions in the range executed.
    pub executions: u64,
    /// Cycles charged to the range's instructions.
    pub cycles: u64,
    /// Executions that issued as half of a dual-issued pair.
    pub dual: u64,
    /// Stall cycles by cause, indexed by [`StallCause::index`].
    pub stall: [u64; STALL_CLASSES],
}

impl RangeSum {
    /// Adds one address's counters to the sums.
    pub fn add(&mut self, s: &PcStats) {
        self.executions += s.executions;
        self.cycles += s.cycles;
        self.dual += s.dual;
        for i in 0..STALL_CLASSES {
            self.stall[i] += s.stall[i];
        }
    }

    /// Cycles per executed instruction in the range (0 when none executed).
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
        /// A label line: the symbol name.
        Label(String),
        /// An instruction line.
        Inst {
            /// The instruction's local-store byte address.
            addr: u32,
            /// Its disassembly.
            text: String,
        },
    }

    /// The listing lines of every executed address of `image` (a local-store image), in
    /// address order: its labels from `symbols`, then its disassembly.
    pub fn executed_lines(
        profile: &Profile,
        image: &[u8],
        symbols: &[(String, u32)],
    ) -> Vec<ListingLine> {
        use crate::disasm::{instruction_text_ext, SymbolTable};
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
                // An executed extension instruction ran with its extension on.
                text: instruction_text_ext(word, addr, &table, crate::Extensions::ALL)
                    .replace('\t', " "),
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
        let in_range = |a: u32| opts.range.is_none_or(|(s, e)| a >= s && a < e);
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
        let in_range = |a: u32| opts.range.is_none_or(|(s, e)| a >= s && a < e);
        let mut insts = Vec::new();
        let mut labels: Vec<(String, u32, RangeSum)> = Vec::new();
        let mut range_sum = RangeSum::default();
        let pairs = |items: &[(u32, u64)], key: &str| -> Value {
            items
                .iter()
                .map(|(k, c)| json!({ key: k, "cycles": c }))
                .collect()
        };
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
                    let channels: Vec<(u32, u64)> = profile
                        .channel_stalls(*addr)
                        .iter()
                        .map(|&(ch, c)| (ch as u32, c))
                        .collect();
                    insts.push(json!({
                        "addr": addr,
                        "text": text,
                        "executions": s.executions,
                        "cycles": s.cycles,
                        "dual": s.dual,
                        "stall": stall_json(&s.stall),
                        "waits_on": pairs(&profile.dependency_sources(*addr), "addr"),
                        "channels": pairs(&channels, "channel"),
                    }));
                }
            }
        }
        let sum_json = |s: &RangeSum| {
            json!({
                "executions": s.executions,
                "cycles": s.cycles,
                "cpi": json_ratio(s.cpi()),
                "dual": s.dual,
                "stall": stall_json(&s.stall),
            })
        };
        let labels: Vec<Value> = labels
            .iter()
            .filter(|l| l.2.executions > 0 || l.2.cycles > 0)
            .map(|(name, addr, s)| {
                let mut entry = json!({ "label": name, "addr": addr });
                if let (Value::Object(entry), Value::Object(sum)) = (&mut entry, sum_json(s)) {
                    entry.extend(sum);
                }
                entry
            })
            .collect();
        let channels: Vec<(u32, u64)> = profile
            .channel_totals()
            .iter()
            .map(|&(ch, c)| (ch as u32, c))
            .collect();
        let report = json!({
            "totals": profile.totals.json_value(),
            "range": sum_json(&range_sum),
            "channels": pairs(&channels, "channel"),
            "labels": labels,
            "instructions": insts,
        });
        format!("{report}\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Totals whose every counter differs: counter `i` (in [`Totals::counters`]' order)
    /// holds `base + i`.
    fn numbered(base: u64) -> Totals {
        let mut t = Totals::default();
        for (i, c) in t.counters_mut().into_iter().enumerate() {
            *c = base + i as u64;
        }
        t.spus = 1;
        t
    }

    #[test]
    fn counters_list_every_field_once_in_one_order() {
        let t = numbered(100);
        assert_eq!(t.counters(), std::array::from_fn(|i| 100 + i as u64));
        // each field is in the list: a field left out would still be 0
        assert_eq!(
            (t.instructions, t.hint_hits, t.idle_cycles, t.spus),
            (100, 108, 130, 1)
        );
        assert_eq!(t.stall, std::array::from_fn(|i| 109 + i as u64));
        assert_eq!(t.dep_by_unit, std::array::from_fn(|i| 115 + i as u64));
        assert_eq!(t.counters()[STALL_COUNTERS_AT], t.stall[0]);
    }

    #[test]
    fn a_steps_counters_add_back_to_the_later_totals() {
        let (earlier, later) = (numbered(5), numbered(1000));
        let d = later.counters_since(&earlier).expect("fits 32 bits");
        assert_eq!(d, [995; COUNTERS]);
        let mut t = earlier;
        t.add_counters(&d, 1);
        assert_eq!(t, later);
        t.add_counters(&d, 2);
        assert_eq!(
            t.counters(),
            std::array::from_fn(|i| 1000 + i as u64 + 2 * 995)
        );
        // a difference beyond 32 bits is not a step's
        let mut far = later;
        far.cycles += 1 << 32;
        assert_eq!(far.counters_since(&earlier), None);
        // merging adds every counter and the SPUs
        let mut m = earlier;
        m.merge(&later);
        assert_eq!(m.counters(), std::array::from_fn(|i| 1005 + 2 * i as u64));
        assert_eq!(m.spus, 2);
    }
}
