//! The SPU timing model: in-order dual issue, result latencies, double-precision issue
//! blocking, static branch prediction with one hint entry, channel stalls, instruction
//! fetch competing with loads, stores and DMA for the local store, and DMA timing.
//!
//! The core calls these hooks in program order for every executed instruction when timing
//! is enabled. The model owns the notion of "now" (the current cycle), which the MFC uses
//! to time DMA completion. Every rule is written out, with its source, in `docs/timing.md`;
//! the rule numbers in the comments below (R1..R10) refer to that document.
//!
//! The model also keeps the profile counters ([`crate::profile::Profile`]): per instruction
//! address executions, cycles, dual issues and stall cycles by cause, and the totals IBM's
//! simulator printed.

use crate::analysis;
use crate::codec::Inst;
use crate::profile::{Profile, Totals};
use crate::table::{Op, Pipe, Unit, OP_INFO};
use std::sync::OnceLock;

/// Why an instruction waited (the stall classes IBM's simulator reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StallCause {
    Dependency,
    BranchMiss,
    Hint,
    DoublePrecision,
    Channel(u8),
    Fetch,
}

impl StallCause {
    /// Index of the cause's counter in [`crate::profile::PcStats::stall`].
    pub const fn index(self) -> usize {
        match self {
            StallCause::Dependency => 0,
            StallCause::BranchMiss => 1,
            StallCause::Hint => 2,
            StallCause::DoublePrecision => 3,
            StallCause::Channel(_) => 4,
            StallCause::Fetch => 5,
        }
    }

    /// Short column names, in index order.
    pub const NAMES: [&'static str; 6] = ["dep", "branch", "hint", "dp", "chan", "fetch"];
}

/// Number of stall classes.
pub const STALL_CLASSES: usize = 6;

/// Settings of the timing model.
#[derive(Clone, Debug)]
pub struct TimingConfig {
    /// Core clock in GHz (2.4 for the paper's blade, 3.2 for a PlayStation 3).
    pub clock_ghz: f64,
    /// Latency of a DMA command in nanoseconds before its bytes start to move.
    pub dma_latency_ns: f64,
    /// Main-memory bandwidth of the chip in GB/s, shared by all SPUs.
    pub memory_bandwidth_gbs: f64,
    /// Bytes one SPU's MFC moves per cycle in each direction (8, Cell BE Handbook).
    pub spu_bytes_per_cycle: f64,
    /// Cycles a mispredicted (or unhinted taken) branch costs before the next instruction
    /// issues (18, SDK Programmer's Guide: "18-19 cycles").
    pub branch_miss_penalty: u32,
    /// A hinted branch issues at least this many cycles after its hint (11).
    pub hint_window: u32,
    /// A hint is ignored when the branch follows it by fewer than this many executed
    /// instructions (8 = 4 pairs; GCC pads hints to this distance).
    pub hint_min_distance: u32,
    /// Cycles during which nothing issues after a double-precision instruction (6).
    pub dp_issue_block: u32,
    /// Model instruction fetch from the local store (set false for `spu_timing`-style
    /// static analysis, which ignores fetch).
    pub model_fetch: bool,
    /// Cycles from the local-store access that fills an instruction line buffer until its
    /// instructions may issue (6: the local-store access pipeline a load also takes).
    pub fetch_latency: u32,
    /// Replay the timing of basic blocks whose entry state repeats (exact; only a speed-up).
    pub memoize: bool,
}

impl Default for TimingConfig {
    fn default() -> Self {
        TimingConfig {
            clock_ghz: 2.4,
            dma_latency_ns: 100.0,
            memory_bandwidth_gbs: 25.6,
            spu_bytes_per_cycle: 8.0,
            branch_miss_penalty: 18,
            hint_window: 11,
            hint_min_distance: 8,
            dp_issue_block: 6,
            model_fetch: true,
            fetch_latency: 6,
            memoize: true,
        }
    }
}

impl TimingConfig {
    /// The PlayStation 3's clock (3.2 GHz), everything else default.
    pub fn ps3() -> Self {
        TimingConfig {
            clock_ghz: 3.2,
            ..Default::default()
        }
    }

    /// The DMA command latency in cycles at the configured clock (100 ns at 2.4 GHz = 240).
    pub fn dma_latency_cycles(&self) -> u64 {
        (self.dma_latency_ns * self.clock_ghz).round() as u64
    }

    /// The chip's main-memory bandwidth in bytes per SPU cycle (25.6 GB/s at 2.4 GHz =
    /// 10.67 B/cycle), shared by all SPUs.
    pub fn chip_bytes_per_cycle(&self) -> f64 {
        self.memory_bandwidth_gbs / self.clock_ghz
    }

    /// Cycles one SPU needs to move `bytes` at its own MFC rate (8 B/cycle), rounded up.
    pub fn dma_transfer_cycles(&self, bytes: u32) -> u64 {
        (bytes as f64 / self.spu_bytes_per_cycle).ceil() as u64
    }

    /// Completion cycle of a DMA command of `bytes` issued at `issue` on an otherwise idle
    /// chip: issue + latency + bytes / (8 B/cycle).
    pub fn dma_completion(&self, issue: u64, bytes: u32) -> u64 {
        issue + self.dma_latency_cycles() + self.dma_transfer_cycles(bytes)
    }

    /// Cycles to seconds at the configured clock.
    pub fn seconds(&self, cycles: u64) -> f64 {
        cycles as f64 / (self.clock_ghz * 1e9)
    }
}

// ---- per-operation facts, precomputed once ------------------------------------------------

const R_RA: u8 = 1;
const R_RB: u8 = 2;
const R_RC: u8 = 4;
const R_RT: u8 = 8;
const W_RT: u8 = 16;

const F_ODD: u16 = 1;
const F_FPD: u16 = 2;
const F_BRANCH: u16 = 4;
const F_HINT: u16 = 8;
/// Uses the local store in its issue cycle (loads, stores, branch hints fetching their
/// target line).
const F_LS: u16 = 16;
const F_NOP: u16 = 32;
const F_MEM: u16 = 64;

/// What the model needs to know about one operation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OpClass {
    pub(crate) regs: u8,
    pub(crate) flags: u16,
    pub(crate) latency: u8,
    pub(crate) unit: Unit,
}

fn build_classes() -> Vec<OpClass> {
    OP_INFO
        .iter()
        .map(|info| {
            let op = info.op;
            let u = analysis::regs(op);
            let mut regs = 0;
            if u.reads_ra {
                regs |= R_RA;
            }
            if u.reads_rb {
                regs |= R_RB;
            }
            if u.reads_rc {
                regs |= R_RC;
            }
            if u.reads_rt {
                regs |= R_RT;
            }
            if u.writes_rt {
                regs |= W_RT;
            }
            let mut flags = 0;
            if info.unit.pipe() == Pipe::Odd {
                flags |= F_ODD;
            }
            if info.unit == Unit::FPD {
                flags |= F_FPD;
            }
            if analysis::is_branch(op) {
                flags |= F_BRANCH;
            }
            if analysis::is_hint(op) {
                flags |= F_HINT | F_LS;
            }
            if analysis::is_load(op) || analysis::is_store(op) {
                flags |= F_LS | F_MEM;
            }
            if analysis::is_nop(op) {
                flags |= F_NOP;
            }
            OpClass {
                regs,
                flags,
                latency: info.unit.latency() as u8,
                unit: info.unit,
            }
        })
        .collect()
}

pub(crate) fn classes() -> &'static [OpClass] {
    static CLASSES: OnceLock<Vec<OpClass>> = OnceLock::new();
    CLASSES.get_or_init(build_classes)
}

/// Whether `inst` is `hbrp` (the inline-prefetch form of `hbr`, P bit set).
#[inline]
pub fn is_hbrp(inst: Inst) -> bool {
    inst.op == Op::Hbr && inst.feature_bits() & 0x40 != 0
}

/// The address of the branch a hint names (its 9-bit word offset from the hint).
#[inline]
pub fn hint_branch_address(pc: u32, inst: Inst) -> u32 {
    pc.wrapping_add((inst.hint_offset() * 4) as u32) & 0x3_ffff
}

/// The target a `hbra`/`hbrr` names (`hbr` takes its target from a register: `None`).
#[inline]
pub fn hint_static_target(pc: u32, inst: Inst) -> Option<u32> {
    match inst.op {
        Op::Hbra => Some(((inst.u16() << 2) & 0x3_ffff) as u32),
        Op::Hbrr => Some(pc.wrapping_add((inst.imm << 2) as u32) & 0x3_ffff),
        _ => None,
    }
}

const NO_PC: u32 = u32::MAX;
const UNKNOWN_TARGET: u32 = u32::MAX;

/// The one branch-hint entry (R5).
#[derive(Clone, Copy, Debug)]
struct HintEntry {
    valid: bool,
    branch: u32,
    target: u32,
    /// Issue cycle of the hint instruction.
    issued: u64,
    /// Dynamic instruction index of the hint.
    index: u64,
}

/// What the last issued instruction was, for pairing and for the hooks that follow it.
#[derive(Clone, Copy, Debug)]
struct Last {
    pc: u32,
    issue: u64,
    /// An even-slot, even-pipe, non-FPD instruction that issued as the first of its
    /// group: the odd-slot instruction at `pc + 4` may join it (R1).
    pairable: bool,
    /// It issued as the second of a dual-issued pair.
    dual: bool,
    /// Register it writes (128 = none) and the result latency.
    writes: u8,
    latency: u8,
    /// It is an `hbrp`, whose `hint` hook call (if any) must not set the branch hint.
    hbrp: bool,
    /// It was a branch, and whether it was correctly hinted (target) when it issued.
    branch_hint: Option<u32>,
}

/// Per-issue detail of one instruction, for the static `spu timing` listing and tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IssueRecord {
    pub pc: u32,
    /// The cycle it issued.
    pub issue: u64,
    /// The earliest it could have issued had nothing stalled it (the previous issue + 1,
    /// or the previous issue when it joined a pair).
    pub base: u64,
    /// Issued as either half of a dual-issued pair.
    pub dual: bool,
    /// The main cause of its stall, when `issue > base`.
    pub cause: Option<StallCause>,
}

/// The per-SPU pipeline model.
#[derive(Clone, Debug)]
pub struct Timing {
    pub config: TimingConfig,
    classes: &'static [OpClass],
    /// The earliest cycle the next instruction may issue, ignoring stalls.
    now: u64,
    last: Last,
    /// Cycle at which each register's newest value can be used, and which instruction
    /// address produces it.
    ready: [u64; 128],
    /// At least the latest of `ready` (the latest ever written).
    max_ready: u64,
    /// A fully replayed block (memo, entry cycle) whose final register writes are not in
    /// `ready`, `producer` and `producer_unit` yet: they are applied when something reads
    /// or writes those ([`Timing::apply_deferred_writes`]), or dropped when the next
    /// replayed block writes all the same registers. Every other register is up to date.
    deferred_writes: Option<(usize, u64)>,
    producer: [u32; 128],
    producer_unit: [Unit; 128],
    /// Nothing issues before this cycle after a branch miss (R4), charged to `miss_pc`.
    redirect: u64,
    miss_pc: u32,
    /// Nothing issues before this cycle after a double-precision instruction (R3).
    dp_until: u64,
    hint: HintEntry,
    /// Executed instructions so far.
    index: u64,
    fetch: Fetch,
    /// Profile counters.
    profile: Profile,
    /// Keep the issue record of the last instruction (`last_record`).
    record: IssueRecord,
    memo: memo::Memos,
}

/// Instruction fetch state (R8).
#[derive(Clone, Debug)]
struct Fetch {
    /// The 128-byte line the last instruction came from (`u32::MAX` before the first).
    line: u32,
    /// A prefetch of line `line + 1` is waiting for a free local-store cycle; `probe` is
    /// the earliest cycle not yet known to be taken by a load, store, hint or DMA.
    pending: bool,
    probe: u64,
    /// Cycle from which the instructions of line `line + 1` may issue.
    next_ready: u64,
    /// Local-store cycles taken by DMA (sorted), and the first of them (or `u64::MAX`).
    dma: std::collections::VecDeque<u64>,
    dma_min: u64,
}

impl Fetch {
    fn new() -> Self {
        Fetch {
            line: u32::MAX,
            pending: false,
            probe: 0,
            next_ready: 0,
            dma: Default::default(),
            dma_min: u64::MAX,
        }
    }
}

impl Timing {
    pub fn new(config: TimingConfig) -> Self {
        Timing {
            config,
            classes: classes(),
            now: 0,
            last: Last {
                pc: NO_PC,
                issue: 0,
                pairable: false,
                dual: false,
                writes: 128,
                latency: 0,
                hbrp: false,
                branch_hint: None,
            },
            ready: [0; 128],
            max_ready: 0,
            deferred_writes: None,
            producer: [NO_PC; 128],
            producer_unit: [Unit::NOP; 128],
            redirect: 0,
            miss_pc: NO_PC,
            dp_until: 0,
            hint: HintEntry {
                valid: false,
                branch: NO_PC,
                target: UNKNOWN_TARGET,
                issued: 0,
                index: 0,
            },
            index: 0,
            fetch: Fetch::new(),
            profile: Profile::new(),
            record: IssueRecord {
                pc: NO_PC,
                issue: 0,
                base: 0,
                dual: false,
                cause: None,
            },
            memo: memo::Memos::default(),
        }
    }

    /// Issues `inst` at `pc` (call in program order, before executing it); returns the
    /// cycle at which it issues.
    #[inline]
    pub fn issue(&mut self, pc: u32, inst: Inst) -> u64 {
        if self.memo.replaying() {
            if let Some(t) = self.replay_next(pc, inst) {
                return t;
            }
        }
        if self.config.memoize {
            return self.issue_memo(pc, inst);
        }
        self.issue_slow(pc, inst)
    }

    /// The model itself: times one instruction from the current state (no memoization).
    ///
    #[inline]
    fn issue_slow(&mut self, pc: u32, inst: Inst) -> u64 {
        self.apply_deferred_writes();
        let class = self.classes[inst.op as usize];
        let flags = class.flags;
        let regs = class.regs;

        // Source operands: the latest ready cycle and its producer (R2).
        let mut ready_at = 0u64;
        let mut src = 128u8;
        if regs & R_RA != 0 {
            let r = inst.ra & 127;
            if self.ready[r as usize] > ready_at {
                ready_at = self.ready[r as usize];
                src = r;
            }
        }
        if regs & R_RB != 0 {
            let r = inst.rb & 127;
            if self.ready[r as usize] > ready_at {
                ready_at = self.ready[r as usize];
                src = r;
            }
        }
        if regs & R_RC != 0 {
            let r = inst.rc & 127;
            if self.ready[r as usize] > ready_at {
                ready_at = self.ready[r as usize];
                src = r;
            }
        }
        if regs & R_RT != 0 {
            let r = inst.rt & 127;
            if self.ready[r as usize] > ready_at {
                ready_at = self.ready[r as usize];
                src = r;
            }
        }

        // Branch hint (R5): a hint names this branch and is far enough ahead.
        let mut hinted: Option<u32> = None;
        let mut hint_ready = 0u64;
        if flags & F_BRANCH != 0 {
            let h = &self.hint;
            if h.valid && h.branch == pc {
                if self.index - h.index >= self.config.hint_min_distance as u64 {
                    hinted = Some(h.target);
                    hint_ready = h.issued + self.config.hint_window as u64;
                }
            }
        }

        // Instruction fetch (R8): crossing into the next sequential line needs it fetched.
        let line = pc >> 7;
        let mut fetch_ready = 0u64;
        let mut new_line = false;
        if line != self.fetch.line {
            new_line = true;
            if self.config.model_fetch
                && self.fetch.line != u32::MAX
                && line == self.fetch.line.wrapping_add(1)
                && self.last.pc.wrapping_add(4) == pc
            {
                if self.fetch.pending {
                    // Nothing else competes any more: the first free cycle fills it.
                    let fill = self.fetch_first_free(self.fetch.probe);
                    self.fetch.pending = false;
                    self.fetch.next_ready = fill + self.config.fetch_latency as u64;
                }
                fetch_ready = self.fetch.next_ready;
            }
        }

        // Dual issue (R1): the odd-slot, odd-pipe partner of a pairable even-slot
        // instruction at pc - 4 joins it when it is ready in that same cycle.
        let last_issue = self.last.issue;
        let mut dual = false;
        let base;
        let mut issue;
        let mut cause = None;
        if self.last.pairable && flags & F_ODD != 0 && self.last.pc.wrapping_add(4) == pc {
            if ready_at <= last_issue && hint_ready <= last_issue {
                dual = true;
            } else if (regs & R_RA != 0 && inst.ra == self.last.writes)
                || (regs & R_RB != 0 && inst.rb == self.last.writes)
                || (regs & R_RC != 0 && inst.rc == self.last.writes)
                || (regs & R_RT != 0 && inst.rt == self.last.writes)
            {
                self.profile.totals.pair_dependency += 1;
            }
        }
        if dual {
            base = last_issue;
            issue = last_issue;
        } else {
            base = self.now;
            issue = base;
            // Stall causes in a fixed order; each cycle is charged to one cause.
            if self.redirect > issue {
                let pc_miss = self.miss_pc;
                self.profile
                    .stall(pc_miss, StallCause::BranchMiss, self.redirect - issue);
                issue = self.redirect;
                cause = Some(StallCause::BranchMiss);
            }
            if fetch_ready > issue {
                self.profile
                    .stall(pc, StallCause::Fetch, fetch_ready - issue);
                issue = fetch_ready;
                cause = Some(StallCause::Fetch);
            }
            if self.dp_until > issue {
                self.profile
                    .stall(pc, StallCause::DoublePrecision, self.dp_until - issue);
                issue = self.dp_until;
                cause = Some(StallCause::DoublePrecision);
            }
            if hint_ready > issue {
                self.profile.stall(pc, StallCause::Hint, hint_ready - issue);
                issue = hint_ready;
                cause = Some(StallCause::Hint);
            }
            if ready_at > issue {
                let producer = self.producer[src as usize];
                let unit = self.producer_unit[src as usize];
                self.profile
                    .dependency(pc, producer, unit, ready_at - issue);
                issue = ready_at;
                cause = Some(StallCause::Dependency);
            }
        }

        // Local-store arbitration for a pending prefetch (R8): cycles before this issue
        // that no load/store/hint/DMA took are free, so the prefetch happened in the first.
        if self.fetch.pending {
            let probe = self.fetch_first_free(self.fetch.probe);
            if probe < issue {
                self.fetch.pending = false;
                self.fetch.next_ready = probe + self.config.fetch_latency as u64;
            } else {
                self.fetch.probe = probe;
            }
        }
        if new_line {
            // Executing a new line: the next sequential line is requested now.
            self.fetch.line = line;
            self.fetch.pending = self.config.model_fetch;
            self.fetch.probe = issue;
        }
        if self.fetch.pending {
            if is_hbrp(inst) {
                // hbrp takes its own local-store cycle for the inline prefetch (R8).
                self.fetch.pending = false;
                self.fetch.next_ready = issue + self.config.fetch_latency as u64;
            } else if flags & F_LS != 0 && self.fetch.probe == issue {
                // This load/store/hint takes the cycle; the prefetch waits.
                self.fetch.probe = issue + 1;
                self.profile.totals.ls_contention += 1;
            }
        }

        // Results (R2).
        let writes = if regs & W_RT != 0 { inst.rt & 127 } else { 128 };
        if writes < 128 {
            self.ready[writes as usize] = issue + class.latency as u64;
            self.max_ready = self.max_ready.max(issue + class.latency as u64);
            self.producer[writes as usize] = pc;
            self.producer_unit[writes as usize] = class.unit;
        }
        if flags & F_FPD != 0 {
            self.dp_until = issue + 1 + self.config.dp_issue_block as u64;
        }
        let hbrp = is_hbrp(inst);
        if flags & F_HINT != 0 && !hbrp {
            // hbra/hbrr name their target; hbr's comes through the `hint` hook.
            self.hint = HintEntry {
                valid: true,
                branch: hint_branch_address(pc, inst),
                target: hint_static_target(pc, inst).unwrap_or(UNKNOWN_TARGET),
                issued: issue,
                index: self.index,
            };
        }

        // Counters.
        self.profile.issued(pc, flags & (F_NOP | F_HINT) != 0, dual);
        if flags & F_HINT != 0 && !hbrp {
            self.profile.totals.hints += 1;
        }

        self.record = IssueRecord {
            pc,
            issue,
            base,
            dual,
            cause,
        };
        self.last = Last {
            pc,
            issue,
            pairable: !dual && pc & 4 == 0 && flags & (F_ODD | F_FPD) == 0,
            dual,
            writes,
            latency: class.latency,
            hbrp,
            branch_hint: if flags & F_BRANCH != 0 {
                Some(hinted.unwrap_or(NO_PC))
            } else {
                None
            },
        };
        self.now = issue + 1;
        self.index += 1;
        issue
    }

    /// The first cycle at or after `from` that no DMA takes (drops older DMA cycles).
    #[inline]
    fn fetch_first_free(&mut self, from: u64) -> u64 {
        if from < self.fetch.dma_min {
            return from;
        }
        self.fetch_first_free_dma(from)
    }

    #[cold]
    fn fetch_first_free_dma(&mut self, mut from: u64) -> u64 {
        while let Some(&c) = self.fetch.dma.front() {
            if c < from {
                self.fetch.dma.pop_front();
            } else if c == from {
                self.fetch.dma.pop_front();
                self.profile.totals.dma_contention += 1;
                from += 1;
            } else {
                break;
            }
        }
        self.fetch.dma_min = self.fetch.dma.front().copied().unwrap_or(u64::MAX);
        from
    }

    /// After a branch instruction executed: whether it was taken and where it went.
    #[inline]
    pub fn branch_resolved(&mut self, pc: u32, _inst: Inst, taken: bool, target: u32) {
        self.sync();
        if self.last.pc != pc {
            self.memo.chain_from = None;
            return;
        }
        if let Some(from) = &mut self.memo.chain_from {
            from.taken = taken;
        }
        let hinted = match self.last.branch_hint {
            Some(NO_PC) | None => None,
            Some(t) => Some(t),
        };
        let target = target & 0x3_ffff;
        let miss = match (taken, hinted) {
            (true, Some(t)) => t != target,
            (true, None) => true,
            (false, Some(_)) => true,
            (false, None) => false,
        };
        let t = &mut self.profile.totals;
        if taken {
            t.branches_taken += 1;
        } else {
            t.branches_not_taken += 1;
        }
        if taken && hinted == Some(target) {
            t.hint_hits += 1;
        }
        if miss {
            t.branch_misses += 1;
            // R4: the next instruction issues 18 cycles later than it otherwise could.
            self.redirect = self.last.issue + 1 + self.config.branch_miss_penalty as u64;
            self.miss_pc = pc;
        }
        if taken {
            // The target line arrives with the redirect (or the hint's target buffer); the
            // line after it is prefetched from then on.
            self.fetch.line = u32::MAX;
            self.fetch.pending = false;
        }
    }

    /// After a hint executed: the branch address it names and the target it predicts
    /// (for `hbr` the target comes from a register, so the core supplies it).
    pub fn hint(&mut self, pc: u32, branch: u32, target: u32) {
        self.memo.chain_from = None;
        if self.replay_hint_matches(pc, branch, target) {
            return;
        }
        self.sync();
        if self.last.pc == pc && self.last.hbrp {
            return;
        }
        let (issued, index) = if self.last.pc == pc {
            (self.last.issue, self.index - 1)
        } else {
            (self.now, self.index)
        };
        self.hint = HintEntry {
            valid: true,
            branch: branch & 0x3_ffff,
            target: target & 0x3_ffff,
            issued,
            index,
        };
    }

    /// The instruction just issued at `pc` could not complete before cycle `until` because
    /// channel `channel` was empty (read) or full (write): it re-issues at `until`.
    pub fn channel_stall(&mut self, pc: u32, channel: u8, until: u64) {
        self.apply_deferred_writes();
        self.memo.chain_from = None;
        self.sync();
        if self.last.pc != pc || until <= self.last.issue {
            return;
        }
        // The total grows by `waited`; a dual-issued instruction also takes its own cycle now.
        let waited = until - self.last.issue;
        let stalled = waited - self.last.dual as u64;
        if self.last.dual {
            self.profile.undo_dual(pc);
            self.profile.add_cycles(pc, 1);
        }
        if stalled > 0 {
            self.profile
                .stall(pc, StallCause::Channel(channel), stalled);
            self.profile.channel(pc, channel, stalled);
        }
        if self.last.writes < 128 {
            self.ready[self.last.writes as usize] = until + self.last.latency as u64;
            self.max_ready = self.max_ready.max(until + self.last.latency as u64);
        }
        self.last.issue = until;
        self.last.dual = false;
        self.last.pairable = false;
        self.record.issue = until;
        self.record.dual = false;
        self.record.cause = Some(StallCause::Channel(channel));
        self.now = until + 1;
    }

    /// A DMA transfer occupies the local store for `bytes` starting at `cycle` (it has
    /// priority over loads, stores and instruction fetch): one 128-byte line access every
    /// 16 cycles (8 B/cycle), R9.
    pub fn dma_local_store(&mut self, cycle: u64, bytes: u32) {
        self.memo.chain_from = None;
        self.sync();
        self.memo.abort_recording(&mut self.profile);
        let lines = bytes.div_ceil(128).max(1) as u64;
        for k in 0..lines {
            let c = cycle + 16 * k;
            let pos = self.fetch.dma.partition_point(|&x| x < c);
            if self.fetch.dma.get(pos) != Some(&c) {
                self.fetch.dma.insert(pos, c);
            }
        }
        self.fetch.dma_min = self.fetch.dma.front().copied().unwrap_or(u64::MAX);
    }

    /// The current cycle: the issue cycle of the next instruction at the earliest.
    pub fn now(&self) -> u64 {
        self.now
    }

    /// Total cycles so far (the cycle after the last issue).
    pub fn cycles(&self) -> u64 {
        self.now
    }

    /// Lets time pass without issuing (e.g. while the SPU is stopped and restarted).
    pub fn advance_to(&mut self, cycle: u64) {
        self.memo.chain_from = None;
        self.sync();
        self.memo.abort_recording(&mut self.profile);
        if cycle > self.now {
            self.profile.totals.idle_cycles += cycle - self.now;
            self.now = cycle;
        }
    }

    /// Issue detail of the last instruction issued (exact when `memoize` is off).
    pub fn last_record(&self) -> IssueRecord {
        self.record
    }

    /// The counters, with the total cycle count filled in.
    pub fn finish_profile(&self) -> Profile {
        let mut p = self.profile.clone();
        p.log = None;
        self.memo.add_pending(&mut p, self.replay_done_counts());
        p.totals.cycles = self.now;
        p
    }

    /// Clears the counters (the pipeline state is kept).
    pub fn reset_profile(&mut self) {
        self.memo.chain_from = None;
        self.sync();
        self.memo.abort_recording(&mut self.profile);
        self.memo.clear_hits();
        self.profile = Profile::new();
    }

    /// Forgets register readiness, the hint and branch state: what `spu timing` does at the
    /// start of an analysed block.
    pub fn reset_pipeline(&mut self) {
        let mut profile = self.finish_profile();
        profile.totals.cycles = 0;
        let config = self.config.clone();
        *self = Timing::new(config);
        self.profile = profile;
    }
}

// ---- block memoization ------------------------------------------------------------------
//
// A basic block (up to its first branch) issued from the same relative pipeline state always
// times the same way. The first time a block starts at an address the model records, for
// each of its instructions, the state after it relative to the block's entry cycle and every
// counter change; when the block later starts in the same relative state (its signature),
// the recorded issue cycles are returned instead of recomputed, the state is set from the
// record at the end of the block, and the counter changes are counted once per replay and
// added when the profile is read. Anything unexpected in the middle of a replay (another
// address, a hook) first brings the state up to date at that point, so the result is exact.

mod memo {
    use super::*;
    use crate::profile::LogEntry;

    pub(super) const MAX_BLOCK: usize = 64;
    pub(super) const NEVER: u32 = u32::MAX;

    #[derive(Clone, Debug)]
    pub(super) struct Step {
        pub issue_rel: i64,
        pub write: u8,
        pub ready_rel: i64,
        pub producer: u32,
        pub unit: Unit,
        pub last: Last,
        pub last_issue_rel: i64,
        pub dp_rel: Option<i64>,
        pub hint: Option<(HintEntry, i64, u64)>,
        pub fetch: (u32, bool, i64, i64),
        pub record: IssueRecord,
        pub record_base_rel: i64,
        pub log_end: usize,
        pub totals: Totals,
    }

    #[derive(Clone, Debug)]
    pub(super) struct Memo {
        pub start: u32,
        pub words: Vec<u32>,
        pub live: Vec<u8>,
        pub branch_pc: u32,
        pub sig: Vec<i64>,
        pub steps: Vec<Step>,
        pub log: Vec<LogEntry>,
        pub hits: u64,
        /// The core's code epoch at which it last found local store holding `words`.
        pub verified: u64,
        /// The last write of each register the block writes (for the end of a replay).
        pub final_writes: Vec<FinalWrite>,
        /// The latest of those ready cycles, relative to the entry (0 without writes).
        pub max_ready_rel: u64,
        /// The registers in `final_writes`, one bit each.
        pub writes_mask: u128,
        /// Past every cycle the block's timing looks at in the local store (the fetch
        /// model's probes, the issue cycles), relative to the entry.
        pub dma_horizon_rel: u64,
        /// The block sets the hint entry (so after a replay it follows from the record).
        pub sets_hint: bool,
        /// Distinguishes this record from an earlier one in the same place.
        pub generation: u64,
        /// The blocks that followed a full replay, not taken and taken (see [`Chain`]).
        pub chain: [Chain; 2],
    }

    /// A register's state after a block, relative to the block's entry (a result is never
    /// ready before its block starts).
    #[derive(Clone, Copy, Debug)]
    pub(super) struct FinalWrite {
        pub ready_rel: u64,
        pub producer: u32,
        pub reg: u8,
        pub unit: Unit,
    }

    /// A block B that followed a full replay of block A once and matched its signature,
    /// in a state that A's record and the branch outcome decided entirely: the next time
    /// A replays fully with the same outcome to `pc`, B matches again without the check.
    #[derive(Clone, Copy, Debug)]
    pub(super) struct Chain {
        pub pc: u32,
        pub memo: u32,
        pub generation: u64,
        /// What B's signature saw of the hint entry (`Timing::hint_view`); the hint entry
        /// is the one part of B's entry state A's record may leave open, so it is compared.
        pub hint: [i64; 3],
        /// B's live registers that A does not write: they must have been ready before B's
        /// entry (as they were when the chain formed). Ended by 128; `UNLISTED` when
        /// there were too many to list (then every register must have been ready).
        pub open: [u8; OPEN_MAX],
    }

    pub(super) const OPEN_MAX: usize = 8;
    pub(super) const UNLISTED: u8 = 255;

    pub(super) const NO_CHAIN: Chain = Chain {
        pc: NEVER,
        memo: 0,
        generation: 0,
        hint: [0; 3],
        open: [UNLISTED; OPEN_MAX],
    };

    /// A full replay just ended, and what the next block's chain check needs of it.
    #[derive(Clone, Copy, Debug)]
    pub(super) struct ChainFrom {
        pub memo: usize,
        pub generation: u64,
        pub taken: bool,
        /// The instruction count after the block (nothing else may issue in between).
        pub index: u64,
        /// The latest ready cycle of any register at the block's entry.
        pub max_ready_at_entry: u64,
    }

    #[derive(Clone, Debug)]
    pub(super) struct Recording {
        pub start: u32,
        pub words: Vec<u32>,
        pub entry: Box<Entry>,
        pub dp_changed: bool,
        pub hint_changed: bool,
        pub steps: Vec<Step>,
    }

    /// The state a block's timing depends on, at its entry.
    #[derive(Clone, Debug)]
    pub(super) struct Entry {
        pub now: u64,
        pub index: u64,
        pub ready: [u64; 128],
        pub producer: [u32; 128],
        pub unit: [Unit; 128],
        pub last: Last,
        pub redirect: u64,
        pub miss_pc: u32,
        pub dp_until: u64,
        pub hint: HintEntry,
        pub fetch: (u32, bool, u64, u64),
        pub totals: Totals,
    }

    /// What the signature reads, borrowed from a live model or a recorded entry.
    pub(super) struct EntryRef<'a> {
        pub now: u64,
        pub index: u64,
        pub ready: &'a [u64; 128],
        pub producer: &'a [u32; 128],
        pub unit: &'a [Unit; 128],
        pub last: Last,
        pub redirect: u64,
        pub miss_pc: u32,
        pub dp_until: u64,
        pub hint: HintEntry,
        pub fetch: (u32, bool, u64, u64),
    }

    impl Entry {
        pub fn as_ref(&self) -> EntryRef<'_> {
            EntryRef {
                now: self.now,
                index: self.index,
                ready: &self.ready,
                producer: &self.producer,
                unit: &self.unit,
                last: self.last,
                redirect: self.redirect,
                miss_pc: self.miss_pc,
                dp_until: self.dp_until,
                hint: self.hint,
                fetch: self.fetch,
            }
        }
    }

    #[derive(Clone, Copy, Debug)]
    pub(super) struct Replay {
        pub memo: usize,
        pub k: usize,
        pub entry_now: u64,
        pub entry_index: u64,
        pub entry_max_ready: u64,
    }

    #[derive(Clone, Debug, Default)]
    pub(super) struct Memos {
        /// Per word address: 0 none, `NEVER`, or memo index + 1.
        pub slots: Vec<u32>,
        /// Per word address, a second record for the same start in another entry state
        /// (0 none, or memo index + 1): a block entered in two recurring states keeps both.
        pub second: Vec<u32>,
        pub fails: Vec<u8>,
        pub memos: Vec<Memo>,
        pub rec: Option<Box<Recording>>,
        pub replay: Option<Replay>,
        pub chain_from: Option<ChainFrom>,
        pub generations: u64,
    }

    impl Memos {
        #[inline]
        pub fn replaying(&self) -> bool {
            self.replay.is_some()
        }

        pub fn abort_recording(&mut self, profile: &mut Profile) {
            if self.rec.take().is_some() {
                profile.log = None;
            }
        }

        pub fn clear_hits(&mut self) {
            for m in &mut self.memos {
                m.hits = 0;
            }
        }

        /// Adds every replay's counters (and a replay in progress up to `partial`).
        pub fn add_pending(&self, p: &mut Profile, partial: Option<(usize, usize)>) {
            for m in &self.memos {
                if m.hits > 0 {
                    p.apply_log(&m.log, m.hits);
                    p.totals.add_scaled(&m.steps.last().unwrap().totals, m.hits);
                }
            }
            if let Some((id, k)) = partial {
                let m = &self.memos[id];
                let st = &m.steps[k - 1];
                p.apply_log(&m.log[..st.log_end], 1);
                p.totals.add_scaled(&st.totals, 1);
            }
        }

        /// Adds the counters of `id`'s replays to the profile and forgets them.
        pub fn flush(&mut self, id: usize, p: &mut Profile) {
            let m = &mut self.memos[id];
            if m.hits > 0 {
                p.apply_log(&m.log, m.hits);
                p.totals.add_scaled(&m.steps.last().unwrap().totals, m.hits);
                m.hits = 0;
            }
        }
    }

    /// Instructions that end a block before them and are never recorded: channel and SPR
    /// access (channel stalls), `hbr` (its target comes through a hook), halts, stops and
    /// syncs, unknown words.
    pub(super) fn is_terminator(inst: Inst) -> bool {
        use Op::*;
        match inst.op {
            Rdch | Wrch | Rchcnt | Mfspr | Mtspr | Stop | Stopd | Sync | Dsync | Heq | Hgt
            | Hlgt | Heqi | Hgti | Hlgti | Unknown => true,
            Hbr => !is_hbrp(inst),
            _ => false,
        }
    }
}

use memo::{ChainFrom, Entry, EntryRef, Memo, Recording, Replay, Step};

/// What the memo table says of a block start.
enum Lookup {
    /// Never memoized here (its state kept changing).
    Never,
    Absent,
    /// A memo whose recorded state (or words) differs from now.
    Differs(usize),
    Hit(usize),
}

/// Whether `inst` ends a memoized block (it needs the core around the pipeline: channels,
/// stops, halts, `sync`, register-target hints, undecodable words).
#[inline]
pub fn ends_block(inst: Inst) -> bool {
    memo::is_terminator(inst)
}

impl Timing {
    #[inline]
    fn slot_index(pc: u32) -> usize {
        ((pc & 0x3_ffff) >> 2) as usize
    }

    /// The signature of the current state for a block with live-in registers `live` and
    /// final branch `branch_pc`, into `out`.
    #[inline(always)]
    fn signature<F: FnMut(i64) -> bool>(
        &self,
        e: &EntryRef,
        live: &[u8],
        start: u32,
        branch_at: Option<(u32, u64)>,
        emit: &mut F,
    ) -> bool {
        let now = e.now as i64;
        for &r in live {
            let rel = (e.ready[r as usize] as i64 - now).max(-1);
            if !emit(rel) {
                return false;
            }
            if rel > 0 {
                if !emit(e.producer[r as usize] as i64) {
                    return false;
                }
                if !emit(e.unit[r as usize] as i64) {
                    return false;
                }
            }
        }
        let seq = e.last.pc.wrapping_add(4) == start;
        if !emit(seq as i64) {
            return false;
        }
        if seq && e.last.pairable {
            if !emit(1 + e.last.writes as i64) {
                return false;
            }
            if !emit(e.last.issue as i64 - now) {
                return false;
            }
        }
        let redirect = (e.redirect as i64 - now).max(0);
        if !emit(redirect) {
            return false;
        }
        if redirect > 0 {
            if !emit(e.miss_pc as i64) {
                return false;
            }
        }
        if !emit((e.dp_until as i64 - now).max(0)) {
            return false;
        }
        if let Some((bpc, k)) = branch_at {
            let [bits, window, target] = self.hint_view(&e.hint, e.index, e.now, bpc, k);
            if !emit(bits) {
                return false;
            }
            if bits == 3 {
                if !emit(window) {
                    return false;
                }
                if !emit(target) {
                    return false;
                }
            }
        }
        if self.config.model_fetch {
            let lat = self.config.fetch_latency as i64;
            if !emit(e.fetch.0 as i64) {
                return false;
            }
            if !emit(e.fetch.1 as i64) {
                return false;
            }
            if e.fetch.1 {
                if !emit((e.fetch.2 as i64 - now).max(-lat - 1)) {
                    return false;
                }
            } else {
                if !emit((e.fetch.3 as i64 - now).max(-1)) {
                    return false;
                }
            }
        }
        true
    }

    /// What a block whose branch is at `bpc`, `k` instructions after its start, sees of the
    /// hint entry `h` at its entry (instruction count `index`, cycle `now`): whether the
    /// entry names the branch and is far enough ahead (bits 0 and 1), and if both, how
    /// long its window still runs and its target (else 0).
    #[inline(always)]
    fn hint_view(&self, h: &HintEntry, index: u64, now: u64, bpc: u32, k: u64) -> [i64; 3] {
        let m = h.valid && h.branch == bpc;
        let close = index + k - h.index >= self.config.hint_min_distance as u64;
        if m && close {
            [
                3,
                (h.issued as i64 + self.config.hint_window as i64 - now as i64).max(-1),
                h.target as i64,
            ]
        } else {
            [m as i64 | (close as i64) << 1, 0, 0]
        }
    }

    /// [`Timing::hint_view`] of the current state for memo `id`'s branch.
    #[inline]
    fn hint_view_now(&self, id: usize) -> [i64; 3] {
        let m = &self.memo.memos[id];
        if m.branch_pc == NO_PC {
            return [0; 3];
        }
        self.hint_view(
            &self.hint,
            self.index,
            self.now,
            m.branch_pc,
            m.words.len() as u64 - 1,
        )
    }

    fn entry(&self) -> Entry {
        Entry {
            now: self.now,
            index: self.index,
            ready: self.ready,
            producer: self.producer,
            unit: self.producer_unit,
            last: self.last,
            redirect: self.redirect,
            miss_pc: self.miss_pc,
            dp_until: self.dp_until,
            hint: self.hint,
            fetch: (
                self.fetch.line,
                self.fetch.pending,
                self.fetch.probe,
                self.fetch.next_ready,
            ),
            totals: self.profile.totals.clone(),
        }
    }

    fn issue_memo(&mut self, pc: u32, inst: Inst) -> u64 {
        self.apply_deferred_writes();
        if let Some(rec) = &self.memo.rec {
            let k = rec.words.len();
            if pc != rec.start.wrapping_add(4 * k as u32)
                || memo::is_terminator(inst)
                || k >= memo::MAX_BLOCK
            {
                self.finish_recording();
            } else {
                let t = self.issue_slow(pc, inst);
                self.record_step(inst);
                if self.classes[inst.op as usize].flags & F_BRANCH != 0 {
                    self.finish_recording();
                }
                return t;
            }
        }
        if memo::is_terminator(inst) {
            return self.issue_slow(pc, inst);
        }
        let idx = Self::slot_index(pc);
        if idx >= self.memo.slots.len() {
            self.memo.slots.resize(0x1_0000, 0);
            self.memo.second.resize(0x1_0000, 0);
            self.memo.fails.resize(0x1_0000, 0);
        }
        // While DMA holds local-store cycles, blocks replay only clear of them and are not
        // recorded (a record must not depend on them).
        let dma = self.fetch.dma_min != u64::MAX;
        match self.chained_lookup(idx, pc, inst) {
            Lookup::Never => return self.issue_slow(pc, inst),
            Lookup::Hit(id) if self.clear_of_dma(id) => return self.begin_replay(id, pc, inst),
            Lookup::Hit(_) => return self.issue_slow(pc, inst),
            _ if dma => return self.issue_slow(pc, inst),
            Lookup::Differs(id) => {
                // A different state: record again (keeping what the old record counted).
                if self.memo.memos[id].hits < 2 {
                    self.memo.fails[idx] = self.memo.fails[idx].saturating_add(1);
                    if self.memo.fails[idx] >= 8 {
                        self.memo.flush(id, &mut self.profile);
                        if let Some(other) = self.second_memo(idx) {
                            self.memo.flush(other, &mut self.profile);
                        }
                        self.memo.slots[idx] = memo::NEVER;
                        return self.issue_slow(pc, inst);
                    }
                }
            }
            Lookup::Absent => {}
        }
        // Record this block.
        self.memo.rec = Some(Box::new(Recording {
            start: pc,
            words: Vec::new(),
            entry: Box::new(self.entry()),
            dp_changed: false,
            hint_changed: false,
            steps: Vec::new(),
        }));
        self.profile.log = Some(Vec::new());
        let t = self.issue_slow(pc, inst);
        self.record_step(inst);
        if self.classes[inst.op as usize].flags & F_BRANCH != 0 {
            self.finish_recording();
        }
        t
    }

    /// The memo for a block starting at `pc` with first instruction `inst` (slot `idx`),
    /// and whether the current state matches the one it was recorded in.
    #[inline]
    fn memo_lookup(&self, idx: usize, pc: u32, inst: Inst) -> Lookup {
        let slot = self.memo.slots[idx];
        if slot == memo::NEVER {
            return Lookup::Never;
        }
        if slot == 0 {
            return Lookup::Absent;
        }
        let first = (slot - 1) as usize;
        if self.entry_matches(first, pc, inst) {
            return Lookup::Hit(first);
        }
        match self.second_memo(idx) {
            Some(second) if self.entry_matches(second, pc, inst) => Lookup::Hit(second),
            // Record again over the one replayed less.
            Some(second) if self.memo.memos[second].hits <= self.memo.memos[first].hits => {
                Lookup::Differs(second)
            }
            _ => Lookup::Differs(first),
        }
    }

    /// The second record for word address `idx`, if any.
    #[inline]
    fn second_memo(&self, idx: usize) -> Option<usize> {
        match self.memo.second.get(idx) {
            Some(&s) if s != 0 => Some((s - 1) as usize),
            _ => None,
        }
    }

    /// Whether memo `id` is the block at `pc` starting with `inst` and the current state
    /// matches its signature.
    #[inline]
    fn entry_matches(&self, id: usize, pc: u32, inst: Inst) -> bool {
        let m = &self.memo.memos[id];
        if m.start != pc || m.words[0] != inst.word {
            return false;
        }
        let branch_at = (m.branch_pc != NO_PC).then(|| (m.branch_pc, m.words.len() as u64 - 1));
        let e = self.entry_ref();
        let mut pos = 0usize;
        let sig = &m.sig[..];
        self.signature(&e, &m.live, pc, branch_at, &mut |v| {
            let same = sig.get(pos) == Some(&v);
            pos += 1;
            same
        }) && pos == sig.len()
    }

    /// [`Timing::memo_lookup`], first through the chain of the block whose full replay
    /// just ended, and adding to that chain. A chain is followed only where the state at
    /// this block's entry follows from the previous block's record: every live register
    /// the previous block did not write was ready before now (as when the chain formed)
    /// and nothing issued in between; the rest of the signature (readiness of what the
    /// previous block wrote, the last issue, branch redirect, double-precision block,
    /// fetch) is set from that record and the branch outcome, and so is the hint entry
    /// where the previous block sets it; otherwise its view is compared.
    #[inline(always)]
    fn chained_lookup(&mut self, idx: usize, pc: u32, inst: Inst) -> Lookup {
        let from = self.memo.chain_from.take().filter(|f| {
            f.index == self.index && self.memo.memos[f.memo].generation == f.generation
        });
        if let Some(f) = from {
            let a = &self.memo.memos[f.memo];
            let c = &a.chain[f.taken as usize];
            if c.pc == pc {
                let b = &self.memo.memos[c.memo as usize];
                if b.generation == c.generation
                    && b.words[0] == inst.word
                    && self.open_registers_ready(f.max_ready_at_entry, &c.open)
                    && (a.sets_hint || self.hint_view_now(c.memo as usize) == c.hint)
                {
                    return Lookup::Hit(c.memo as usize);
                }
            }
        }
        self.apply_deferred_writes();
        let found = self.memo_lookup(idx, pc, inst);
        if let (Lookup::Hit(id), Some(f)) = (&found, from) {
            // B's live registers that A does not write (when few enough to list).
            let (a, b) = (&self.memo.memos[f.memo], &self.memo.memos[*id]);
            let mut listed = [128u8; memo::OPEN_MAX];
            let mut n = 0;
            for &r in &b.live {
                if a.writes_mask & (1u128 << (r & 127)) == 0 {
                    if n == memo::OPEN_MAX {
                        listed = [memo::UNLISTED; memo::OPEN_MAX];
                        break;
                    }
                    listed[n] = r;
                    n += 1;
                }
            }
            if self.open_registers_ready(f.max_ready_at_entry, &listed) {
                let chain = memo::Chain {
                    pc,
                    memo: *id as u32,
                    generation: b.generation,
                    hint: self.hint_view_now(*id),
                    open: listed,
                };
                self.memo.memos[f.memo].chain[f.taken as usize] = chain;
            }
        }
        found
    }

    /// Whether the registers a chain leaves open (`open`: a list ended by 128, or
    /// [`memo::UNLISTED`] for any register) were all ready before now: at once when every
    /// register was ready by the previous block's entry.
    #[inline(always)]
    fn open_registers_ready(&self, max_ready_at_entry: u64, open: &[u8; memo::OPEN_MAX]) -> bool {
        if max_ready_at_entry < self.now {
            return true;
        }
        if open[0] == memo::UNLISTED {
            return false;
        }
        open.iter()
            .take_while(|&&r| r < 128)
            .all(|&r| self.ready[r as usize] < self.now)
    }

    /// Starts replaying memo `id` with its first instruction (`pc`, `inst`); returns that
    /// instruction's issue cycle.
    fn begin_replay(&mut self, id: usize, pc: u32, inst: Inst) -> u64 {
        self.memo.replay = Some(Replay {
            memo: id,
            k: 0,
            entry_now: self.now,
            entry_index: self.index,
            entry_max_ready: self.max_ready,
        });
        self.replay_next(pc, inst)
            .expect("first replayed instruction")
    }

    /// For a core that runs whole memoized blocks: the memo (id and length) of the block
    /// starting at `pc` with `inst` when the state matches its record and nothing else is
    /// in progress; nothing changes. Follow with [`Timing::start_block_replay`].
    #[inline(always)]
    pub fn block_replay_candidate(&mut self, pc: u32, inst: Inst) -> Option<(usize, usize)> {
        if !self.config.memoize
            || self.memo.rec.is_some()
            || self.memo.replay.is_some()
            || memo::is_terminator(inst)
        {
            return None;
        }
        let idx = Self::slot_index(pc);
        if idx >= self.memo.slots.len() {
            return None;
        }
        match self.chained_lookup(idx, pc, inst) {
            Lookup::Hit(id) if self.clear_of_dma(id) => Some((id, self.memo.memos[id].words.len())),
            _ => None,
        }
    }

    /// Whether memo `id`'s block, starting now, ends its use of the local store before
    /// the first cycle a DMA holds: the model then asks of it exactly what it asked when
    /// the block was recorded (with no DMA), so the record holds.
    #[inline]
    fn clear_of_dma(&mut self, id: usize) -> bool {
        let horizon = self.now + self.memo.memos[id].dma_horizon_rel;
        if self.fetch.dma_min > horizon {
            return true;
        }
        self.drop_past_dma_cycles();
        self.fetch.dma_min > horizon
    }

    /// Forgets DMA cycles no fetch probe can reach any more: those before now and before
    /// a waiting prefetch's probe (probes only move forward, and `fetch_first_free` skips
    /// such cycles without counting them).
    #[cold]
    fn drop_past_dma_cycles(&mut self) {
        let bound = if self.fetch.pending {
            self.now.min(self.fetch.probe)
        } else {
            self.now
        };
        while self.fetch.dma.front().is_some_and(|&c| c < bound) {
            self.fetch.dma.pop_front();
        }
        self.fetch.dma_min = self.fetch.dma.front().copied().unwrap_or(u64::MAX);
    }

    /// The words memo `id` recorded, and the core's code epoch at which local store last
    /// held them.
    #[inline]
    pub fn memo_words(&self, id: usize) -> (&[u32], u64) {
        let m = &self.memo.memos[id];
        (&m.words, m.verified)
    }

    /// Notes that local store held memo `id`'s words at code epoch `epoch`.
    #[inline]
    pub fn set_memo_verified(&mut self, id: usize, epoch: u64) {
        self.memo.memos[id].verified = epoch;
    }

    /// The entry of a block replayed whole by the core: the replay `issue` started, or
    /// (for a [`Timing::block_replay_candidate`]) the current state.
    #[inline]
    fn block_entry(&mut self, id: usize) -> Replay {
        match self.memo.replay.take() {
            Some(rp) if rp.memo == id => rp,
            _ => Replay {
                memo: id,
                k: 0,
                entry_now: self.now,
                entry_index: self.index,
                entry_max_ready: self.max_ready,
            },
        }
    }

    /// The core ran memo `id`'s block whole (a [`Timing::block_replay_candidate`], or the
    /// replay `issue` started): the state and counters become what issuing each of its
    /// instructions would have made them, and `branch` (its last instruction's address,
    /// the instruction, whether it was taken and where to) resolves.
    #[inline(always)]
    pub fn block_replayed(&mut self, id: usize, branch: Option<(u32, Inst, bool, u32)>) {
        let mut rp = self.block_entry(id);
        let m = &mut self.memo.memos[id];
        m.hits += 1;
        rp.k = m.words.len();
        self.materialize(rp, false);
        self.chain_after(rp);
        if let Some((pc, inst, taken, target)) = branch {
            self.branch_resolved(pc, inst, taken, target);
        }
    }

    /// The core ran the first `k` instructions of memo `id`'s block and stopped (the rest
    /// go through `issue`).
    pub fn block_replayed_partly(&mut self, id: usize, k: usize) {
        let mut rp = self.block_entry(id);
        rp.k = k;
        self.memo.replay = Some(rp);
        self.sync();
    }

    /// The memo whose replay `issue` started.
    #[inline]
    pub fn replay_memo(&self) -> Option<usize> {
        self.memo.replay.map(|rp| rp.memo)
    }

    /// A view of the current state for the signature.
    fn entry_ref(&self) -> EntryRef<'_> {
        EntryRef {
            now: self.now,
            index: self.index,
            ready: &self.ready,
            producer: &self.producer,
            unit: &self.producer_unit,
            last: self.last,
            redirect: self.redirect,
            miss_pc: self.miss_pc,
            dp_until: self.dp_until,
            hint: self.hint,
            fetch: (
                self.fetch.line,
                self.fetch.pending,
                self.fetch.probe,
                self.fetch.next_ready,
            ),
        }
    }

    fn record_step(&mut self, inst: Inst) {
        self.apply_deferred_writes();
        let Some(rec) = self.memo.rec.as_mut() else {
            return;
        };
        let e = &rec.entry;
        let now = e.now as i64;
        let class = self.classes[inst.op as usize];
        if class.flags & F_FPD != 0 {
            rec.dp_changed = true;
        }
        if class.flags & F_HINT != 0 && !is_hbrp(inst) {
            rec.hint_changed = true;
        }
        let w = self.last.writes;
        let (ready_rel, producer, unit) = if w < 128 {
            (
                self.ready[w as usize] as i64 - now,
                self.producer[w as usize],
                self.producer_unit[w as usize],
            )
        } else {
            (0, NO_PC, Unit::NOP)
        };
        let step = Step {
            issue_rel: self.last.issue as i64 - now,
            write: w,
            ready_rel,
            producer,
            unit,
            last: self.last,
            last_issue_rel: self.last.issue as i64 - now,
            dp_rel: rec.dp_changed.then(|| self.dp_until as i64 - now),
            hint: rec.hint_changed.then(|| {
                (
                    self.hint,
                    self.hint.issued as i64 - now,
                    self.hint.index - e.index,
                )
            }),
            fetch: (
                self.fetch.line,
                self.fetch.pending,
                self.fetch.probe as i64 - now,
                self.fetch.next_ready as i64 - now,
            ),
            record: self.record,
            record_base_rel: self.record.base as i64 - now,
            log_end: self.profile.log.as_ref().map_or(0, |l| l.len()),
            totals: self.profile.totals.since(&e.totals),
        };
        rec.words.push(inst.word);
        rec.steps.push(step);
    }

    fn finish_recording(&mut self) {
        // The record may replace the deferred block's memo.
        self.apply_deferred_writes();
        let Some(rec) = self.memo.rec.take() else {
            return;
        };
        let log = self.profile.log.take().unwrap_or_default();
        if rec.steps.is_empty() {
            return;
        }
        // Live-in registers: read before the block writes them.
        let mut written = [false; 128];
        let mut live = Vec::new();
        let mut branch_pc = NO_PC;
        for (k, &word) in rec.words.iter().enumerate() {
            let inst = crate::codec::decode(word);
            let c = self.classes[inst.op as usize];
            let mut read = |r: u8| {
                let r = r & 127;
                if !written[r as usize] && !live.contains(&r) {
                    live.push(r);
                }
            };
            if c.regs & R_RA != 0 {
                read(inst.ra);
            }
            if c.regs & R_RB != 0 {
                read(inst.rb);
            }
            if c.regs & R_RC != 0 {
                read(inst.rc);
            }
            if c.regs & R_RT != 0 {
                read(inst.rt);
            }
            if c.regs & W_RT != 0 {
                written[(inst.rt & 127) as usize] = true;
            }
            if c.flags & F_BRANCH != 0 {
                branch_pc = rec.start.wrapping_add(4 * k as u32);
            }
        }
        let branch_at = (branch_pc != NO_PC).then(|| (branch_pc, rec.words.len() as u64 - 1));
        let mut sig = Vec::new();
        self.signature(
            &memo::Entry::as_ref(&rec.entry),
            &live,
            rec.start,
            branch_at,
            &mut |v| {
                sig.push(v);
                true
            },
        );
        let memo = Memo {
            start: rec.start,
            words: rec.words,
            live,
            branch_pc,
            sig,
            steps: rec.steps,
            log,
            hits: 0,
            verified: u64::MAX,
            final_writes: Vec::new(),
            max_ready_rel: 0,
            writes_mask: 0,
            dma_horizon_rel: 0,
            generation: self.memo.generations,
            sets_hint: rec.hint_changed,
            chain: [memo::NO_CHAIN; 2],
        };
        self.memo.generations += 1;
        let mut memo = memo;
        memo.dma_horizon_rel = memo
            .steps
            .iter()
            .map(|st| st.issue_rel.max(st.fetch.2).max(0) as u64)
            .max()
            .unwrap_or(0)
            + 2;
        for st in memo.steps.iter().rev() {
            if st.write < 128 && !memo.final_writes.iter().any(|w| w.reg == st.write) {
                let ready_rel = st.ready_rel.max(0) as u64;
                memo.final_writes.push(memo::FinalWrite {
                    ready_rel,
                    producer: st.producer,
                    reg: st.write,
                    unit: st.unit,
                });
                memo.max_ready_rel = memo.max_ready_rel.max(ready_rel);
                memo.writes_mask |= 1u128 << st.write;
            }
        }
        let idx = Self::slot_index(memo.start);
        let slot = self.memo.slots[idx];
        if slot == 0 || slot == memo::NEVER {
            self.memo.memos.push(memo);
            self.memo.slots[idx] = self.memo.memos.len() as u32;
            return;
        }
        let first = (slot - 1) as usize;
        // A block at the same start with other words (the code changed) replaces the first
        // record; another entry state takes the second place, or replaces the record
        // replayed less.
        let same_words = self.memo.memos[first].words == memo.words;
        let victim = match self.second_memo(idx) {
            None if same_words => {
                self.memo.memos.push(memo);
                self.memo.second[idx] = self.memo.memos.len() as u32;
                return;
            }
            Some(second)
                if same_words && self.memo.memos[second].hits <= self.memo.memos[first].hits =>
            {
                second
            }
            _ => first,
        };
        self.memo.flush(victim, &mut self.profile);
        self.memo.memos[victim] = memo;
    }

    /// Replays the next instruction of the block in progress, or brings the state up to
    /// date and returns `None` when `pc`/`inst` is not what the block recorded.
    #[inline]
    fn replay_next(&mut self, pc: u32, inst: Inst) -> Option<u64> {
        let rp = self.memo.replay.as_mut()?;
        let m = &mut self.memo.memos[rp.memo];
        let k = rp.k;
        if k < m.words.len() && pc == m.start.wrapping_add(4 * k as u32) && inst.word == m.words[k]
        {
            let issue = (rp.entry_now as i64 + m.steps[k].issue_rel) as u64;
            self.now = issue + 1;
            rp.k = k + 1;
            if rp.k == m.words.len() {
                m.hits += 1;
                let rp = *rp;
                self.memo.replay = None;
                self.materialize(rp, false);
                self.chain_after(rp);
            }
            Some(issue)
        } else {
            self.sync();
            None
        }
    }

    /// Applies the register writes of the block in `deferred_writes`.
    #[inline]
    fn apply_deferred_writes(&mut self) {
        if let Some((id, entry)) = self.deferred_writes.take() {
            for w in &self.memo.memos[id].final_writes {
                let r = (w.reg & 127) as usize;
                self.ready[r] = entry + w.ready_rel;
                self.producer[r] = w.producer;
                self.producer_unit[r] = w.unit;
            }
        }
    }

    /// Sets the state after `rp.k` replayed instructions; `eager`: also apply their
    /// counter changes now (a partial block).
    #[inline]
    fn materialize(&mut self, rp: Replay, eager: bool) {
        let k = rp.k;
        if k == self.memo.memos[rp.memo].steps.len() {
            // The registers wait in `deferred_writes`; the previous deferred block's are
            // applied first unless this block overwrites them all.
            if let Some((d, _)) = self.deferred_writes {
                let covered =
                    self.memo.memos[d].writes_mask & !self.memo.memos[rp.memo].writes_mask;
                if covered != 0 {
                    self.apply_deferred_writes();
                }
            }
            self.deferred_writes = Some((rp.memo, rp.entry_now));
            let m = &self.memo.memos[rp.memo];
            self.max_ready = self.max_ready.max(rp.entry_now + m.max_ready_rel);
        } else {
            self.apply_deferred_writes();
        }
        let m = &self.memo.memos[rp.memo];
        let base = rp.entry_now as i64;
        let at = |rel: i64| (base + rel).max(0) as u64;
        if k < m.steps.len() {
            for st in &m.steps[..k] {
                if st.write < 128 {
                    self.ready[st.write as usize] = at(st.ready_rel);
                    self.max_ready = self.max_ready.max(at(st.ready_rel));
                    self.producer[st.write as usize] = st.producer;
                    self.producer_unit[st.write as usize] = st.unit;
                }
            }
        }
        let st = &m.steps[k - 1];
        self.last = st.last;
        self.last.issue = at(st.last_issue_rel);
        self.now = self.last.issue + 1;
        if let Some(d) = st.dp_rel {
            self.dp_until = at(d);
        }
        if let Some((h, issued, index)) = st.hint {
            self.hint = h;
            self.hint.issued = at(issued);
            self.hint.index = rp.entry_index + index;
        }
        self.fetch.line = st.fetch.0;
        self.fetch.pending = st.fetch.1;
        self.fetch.probe = at(st.fetch.2);
        self.fetch.next_ready = at(st.fetch.3);
        self.record = st.record;
        self.record.issue = self.last.issue;
        self.record.base = at(st.record_base_rel);
        self.index = rp.entry_index + k as u64;
        if eager {
            let (log_end, totals) = (st.log_end, st.totals.clone());
            let log: Vec<_> = m.log[..log_end].to_vec();
            self.profile.apply_log(&log, 1);
            self.profile.totals.add_scaled(&totals, 1);
        }
    }

    /// Right after `issue` started replaying a memoized block with the block's first
    /// instruction: the block's length. The core may then execute the block's remaining
    /// instructions without calling `issue` and finish with [`Timing::block_replayed`]
    /// (or stop early with [`Timing::block_replayed_partly`]): the result is the same.
    #[inline]
    pub fn replay_started(&self) -> Option<usize> {
        let rp = self.memo.replay.as_ref()?;
        (rp.k == 1).then(|| self.memo.memos[rp.memo].words.len())
    }

    /// The words of the block being replayed (to check local store still holds them).
    #[inline]
    pub fn replay_words(&self) -> &[u32] {
        match &self.memo.replay {
            Some(rp) => &self.memo.memos[rp.memo].words,
            None => &[],
        }
    }

    /// The core's code epoch at which the replayed block's words were last checked.
    #[inline]
    pub fn replay_verified(&self) -> u64 {
        match &self.memo.replay {
            Some(rp) => self.memo.memos[rp.memo].verified,
            None => u64::MAX,
        }
    }

    /// Notes that local store held the replayed block's words at code epoch `epoch`.
    #[inline]
    pub fn set_replay_verified(&mut self, epoch: u64) {
        if let Some(rp) = &self.memo.replay {
            self.memo.memos[rp.memo].verified = epoch;
        }
    }

    /// After a full replay: what lets the next block skip its signature.
    fn chain_after(&mut self, rp: Replay) {
        self.memo.chain_from = Some(ChainFrom {
            memo: rp.memo,
            generation: self.memo.memos[rp.memo].generation,
            taken: false,
            index: self.index,
            max_ready_at_entry: rp.entry_max_ready,
        });
    }

    /// Brings a replay in progress up to date (before a hook or an unexpected address).
    fn sync(&mut self) {
        if let Some(rp) = self.memo.replay.take() {
            if rp.k > 0 {
                self.materialize(rp, true);
            }
        }
    }

    /// A `hint` hook call that repeats what a replayed hint instruction already recorded.
    fn replay_hint_matches(&self, pc: u32, branch: u32, target: u32) -> bool {
        let Some(rp) = &self.memo.replay else {
            return false;
        };
        let m = &self.memo.memos[rp.memo];
        if rp.k == 0 || pc != m.start.wrapping_add(4 * (rp.k as u32 - 1)) {
            return false;
        }
        matches!(m.steps[rp.k - 1].hint, Some((h, _, _)) if h.branch == branch & 0x3_ffff && h.target == target & 0x3_ffff)
    }

    fn replay_done_counts(&self) -> Option<(usize, usize)> {
        self.memo
            .replay
            .filter(|rp| rp.k > 0)
            .map(|rp| (rp.memo, rp.k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::{decode, encode};
    use crate::table::forms_named;

    fn w(m: &str, ops: &[i64], pc: u32) -> Inst {
        decode(encode(forms_named(m).next().unwrap(), ops, pc))
    }

    /// Runs straight-line code from address 0 (no fetch model); returns issue cycles.
    fn run(prog: &[(&str, &[i64])]) -> Vec<u64> {
        let mut t = Timing::new(TimingConfig {
            model_fetch: false,
            ..Default::default()
        });
        prog.iter()
            .enumerate()
            .map(|(i, (m, ops))| t.issue(i as u32 * 4, w(m, ops, i as u32 * 4)))
            .collect()
    }

    #[test]
    fn dependency_chains_of_each_class() {
        // Each dependent instruction issues `latency` cycles after its producer.
        // FX2: a $3 at 0, a $4,$3 at 2.
        assert_eq!(run(&[("a", &[3, 1, 2]), ("a", &[4, 3, 3])]), vec![0, 2]);
        // FX3: shli at 0, dependent at 4.
        assert_eq!(run(&[("shli", &[3, 1, 2]), ("a", &[4, 3, 3])]), vec![0, 4]);
        // FP6: fma at 0, dependent fma at 6.
        assert_eq!(
            run(&[("fma", &[3, 1, 2, 5]), ("fma", &[4, 3, 3, 3])]),
            vec![0, 6]
        );
        // FP7: mpy at 0, dependent at 7.
        assert_eq!(run(&[("mpy", &[3, 1, 2]), ("a", &[4, 3, 3])]), vec![0, 7]);
        // FPD: dfa at 0, dependent at 13.
        assert_eq!(
            run(&[("dfa", &[3, 1, 2]), ("dfa", &[4, 3, 3])]),
            vec![0, 13]
        );
        // LS: lqd at 0 (odd pipe in the even slot: alone), dependent a at 6.
        assert_eq!(run(&[("lqd", &[3, 0, 1]), ("a", &[4, 3, 3])]), vec![0, 6]);
        // SHUF: shufb at 0, dependent at 4.
        assert_eq!(
            run(&[("shufb", &[3, 1, 2, 5]), ("a", &[4, 3, 3])]),
            vec![0, 4]
        );
    }

    #[test]
    fn dual_issue_and_misalignment() {
        // even-pipe at 0 + odd-pipe at 4: one cycle.
        assert_eq!(run(&[("a", &[3, 1, 2]), ("lqd", &[4, 0, 1])]), vec![0, 0]);
        // odd first, even second: no pairing.
        assert_eq!(run(&[("lqd", &[4, 0, 1]), ("a", &[3, 1, 2])]), vec![0, 1]);
        // misaligned: the even-pipe one in the odd slot issues alone, the next pair pairs.
        assert_eq!(
            run(&[("lnop", &[]), ("a", &[3, 1, 2]), ("lqd", &[4, 0, 1])]),
            vec![0, 1, 2]
        );
        // The second reads the first's result: no dual issue.
        assert_eq!(run(&[("a", &[3, 1, 2]), ("lqd", &[4, 0, 3])]), vec![0, 2]);
    }

    #[test]
    fn double_precision_blocks_six_cycles() {
        // dfa at 0 blocks cycles 1..6; an independent add issues at 7, a lnop partner
        // does not dual-issue with the dfa.
        assert_eq!(
            run(&[("dfa", &[3, 1, 2]), ("lnop", &[]), ("a", &[5, 1, 2])]),
            vec![0, 7, 8]
        );
    }

    #[test]
    fn dma_helpers() {
        let c = TimingConfig::default();
        assert_eq!(c.dma_latency_cycles(), 240);
        assert_eq!(c.dma_completion(1000, 128), 1000 + 240 + 16);
        assert_eq!(TimingConfig::ps3().dma_latency_cycles(), 320);
        assert!((c.chip_bytes_per_cycle() - 25.6 / 2.4).abs() < 1e-12);
    }
}
impl Timing {
    /// Memoization statistics: (blocks recorded, replays, addresses given up on).
    pub fn memo_stats(&self) -> (usize, u64, usize) {
        let hits = self.memo.memos.iter().map(|m| m.hits).sum();
        let never = self
            .memo
            .slots
            .iter()
            .filter(|&&s| s == memo::NEVER)
            .count();
        (self.memo.memos.len(), hits, never)
    }
}
