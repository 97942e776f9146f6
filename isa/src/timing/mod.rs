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

mod memo;

pub use crate::stall::{StallCause, STALL_CLASSES};
pub use memo::ends_block;
#[cfg_attr(not(block_compiler), allow(unused_imports))]
pub(crate) use memo::{may_fall_through, MAX_BLOCK};

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
    /// Bytes per core cycle the memory interface's EIB port moves in each direction: 16
    /// bytes per bus cycle at half the core clock (Kistler et al. 2006), so 8, whatever
    /// the clock (`docs/memory-model.md`).
    pub eib_port_bytes_per_cycle: f64,
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
    /// With `hint_entries > 1` a block is memoized where only the newest hint entry plays
    /// a part in its timing (`memo::others_quiet`); elsewhere it is timed per instruction.
    pub memoize: bool,
    /// Entries of the branch target buffer: 1 is the real SPU's one hint; more is the
    /// `multihint` extension (`docs/extensions.md`).
    pub hint_entries: u8,
}

impl Default for TimingConfig {
    fn default() -> Self {
        TimingConfig {
            clock_ghz: 2.4,
            dma_latency_ns: 100.0,
            memory_bandwidth_gbs: 25.6,
            spu_bytes_per_cycle: 8.0,
            eib_port_bytes_per_cycle: 8.0,
            branch_miss_penalty: 18,
            hint_window: 11,
            hint_min_distance: 8,
            dp_issue_block: 6,
            model_fetch: true,
            fetch_latency: 6,
            memoize: true,
            hint_entries: 1,
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
/// A gather load: it takes the local store for [`crate::ext::GATHER_LS_CYCLES`] cycles,
/// during which nothing else issues (counted with the double-precision issue block).
pub(crate) const F_GATHER: u16 = 128;

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
            if info.ext == Some(crate::ext::Extension::Gather) {
                flags |= F_GATHER;
            }
            if analysis::is_nop(op) {
                flags |= F_NOP;
            }
            OpClass {
                regs,
                flags,
                latency: info.latency() as u8,
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
        Op::Hbra => Some((inst.u16() << 2) & 0x3_ffff),
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

impl Last {
    /// The target a hint predicted for this branch, if one applied when it issued.
    #[inline]
    fn hinted(&self) -> Option<u32> {
        match self.branch_hint {
            Some(NO_PC) | None => None,
            Some(t) => Some(t),
        }
    }
}

/// Per-issue detail of one instruction, for the static `spu timing` listing and tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IssueRecord {
    /// Local-store address of the instruction.
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
    /// The latencies and rules this model was built with.
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
    /// A fully replayed block (memo, entry cycle, `max_ready` at its entry) whose final
    /// register writes are not in `ready`, `producer` and `producer_unit` yet: they are
    /// applied when something reads or writes those ([`Timing::apply_deferred_writes`]),
    /// or dropped when the next replayed block writes all the same registers. Every other
    /// register is up to date.
    deferred_writes: Option<(usize, u64, u64)>,
    /// The target of the last `hbr` the core ran ([`Timing::note_hint_target`]).
    hint_target: u32,
    producer: [u32; 128],
    producer_unit: [Unit; 128],
    /// Nothing issues before this cycle after a branch miss (R4), charged to `miss_pc`.
    redirect: u64,
    miss_pc: u32,
    /// Nothing issues before this cycle after a double-precision instruction (R3).
    dp_until: u64,
    hint: HintEntry,
    /// The other entries of a `multihint` branch target buffer (`hint_entries - 1` at most,
    /// newest first; `hint` is the newest of all). Always empty with one entry.
    more_hints: Vec<HintEntry>,
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
    /// A model at cycle 0 with every register ready, using `config`.
    pub fn new(mut config: TimingConfig) -> Self {
        config.hint_entries = config.hint_entries.clamp(1, crate::ext::MAX_HINT_ENTRIES);
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
            hint_target: 0,
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
            more_hints: Vec::new(),
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
            // With several entries, the one naming this branch (at most one does); each
            // entry has its own distance and window.
            let h = if self.hint.branch == pc {
                Some(&self.hint)
            } else {
                self.more_hints.iter().find(|h| h.branch == pc)
            };
            if let Some(h) = h
                .filter(|h| h.valid && self.index - h.index >= self.config.hint_min_distance as u64)
            {
                hinted = Some(h.target);
                hint_ready = h.issued + self.config.hint_window as u64;
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
            } else if flags & F_GATHER != 0 {
                // A gather's four reads take the cycles from its issue on.
                let end = issue + crate::ext::GATHER_LS_CYCLES as u64;
                if (issue..end).contains(&self.fetch.probe) {
                    self.profile.totals.ls_contention += end - self.fetch.probe;
                    self.fetch.probe = end;
                }
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
        if flags & F_GATHER != 0 {
            // The local store is busy with the gather's reads: nothing issues meanwhile.
            self.dp_until = issue + crate::ext::GATHER_LS_CYCLES as u64;
        }
        let hbrp = is_hbrp(inst);
        if flags & F_HINT != 0 && !hbrp {
            // hbra/hbrr name their target; hbr's comes through the `hint` hook.
            self.set_hint(HintEntry {
                valid: true,
                branch: hint_branch_address(pc, inst),
                target: hint_static_target(pc, inst).unwrap_or(UNKNOWN_TARGET),
                issued: issue,
                index: self.index,
            });
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
        if let Some(rec) = self.memo.rec.as_deref_mut() {
            rec.probes.push(from);
        }
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
                // A block's record must not depend on DMA: a recording ends before this.
                self.cut_recording();
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
        self.resolve_branch(pc, taken, target);
    }

    /// [`Timing::branch_resolved`] (which needs no more than the branch's address).
    #[inline]
    fn resolve_branch(&mut self, pc: u32, taken: bool, target: u32) {
        if (self.memo.replay.is_some() || self.memo.rec.is_some())
            && self.inner_branch_resolved(pc, taken)
        {
            return;
        }
        self.sync();
        if self.last.pc != pc {
            self.memo.chain_from = None;
            return;
        }
        if let Some(from) = &mut self.memo.chain_from {
            from.taken = taken;
        }
        let hinted = self.last.hinted();
        let target = target & 0x3_ffff;
        if self.count_branch(hinted, taken, target, 1) {
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

    /// Counts `times` resolutions of a branch predicted `hinted` (the hint's target, if
    /// any), `taken` or not to `target`; returns whether it was a miss (R4).
    #[inline]
    fn count_branch(&mut self, hinted: Option<u32>, taken: bool, target: u32, times: u64) -> bool {
        let miss = match (taken, hinted) {
            (true, Some(t)) => t != target,
            (true, None) => true,
            (false, Some(_)) => true,
            (false, None) => false,
        };
        let t = &mut self.profile.totals;
        if taken {
            t.branches_taken += times;
        } else {
            t.branches_not_taken += times;
        }
        if taken && hinted == Some(target) {
            t.hint_hits += times;
        }
        if miss {
            t.branch_misses += times;
        }
        miss
    }

    /// The target of the last `hbr` the core ran in a block it reports whole (or in part)
    /// without the `hint` hook (`Core::hint_target`): a replayed record whose hint entry
    /// an `hbr` set last takes it as the entry's target.
    #[inline(always)]
    pub(crate) fn note_hint_target(&mut self, target: u32) {
        self.hint_target = target & 0x3_ffff;
    }

    /// After a hint executed: the branch address it names and the target it predicts
    /// (for `hbr` the target comes from a register, so the core supplies it).
    pub fn hint(&mut self, pc: u32, branch: u32, target: u32) {
        self.hint_target = target & 0x3_ffff;
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
        self.set_hint(HintEntry {
            valid: true,
            branch: branch & 0x3_ffff,
            target: target & 0x3_ffff,
            issued,
            index,
        });
    }

    /// Fills a hint entry: the real SPU's one entry is replaced; a `multihint` buffer
    /// replaces the entry of the same branch, or else its oldest-filled one once full.
    #[inline]
    fn set_hint(&mut self, new: HintEntry) {
        let others = self.config.hint_entries as usize - 1;
        if others == 0 {
            self.hint = new;
            return;
        }
        let old = std::mem::replace(&mut self.hint, new);
        self.more_hints.retain(|h| h.branch != new.branch);
        if old.valid && old.branch != new.branch {
            self.more_hints.insert(0, old);
            self.more_hints.truncate(others);
        }
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
    pub(crate) fn last_record(&self) -> IssueRecord {
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

    /// Wherever `steady_passes` says a self-loop is steady, applying its record for those
    /// passes at once (`steady_replayed`) gives what timing them one by one gives: the
    /// cycle, the totals and every per-address counter. The loop (`ai`, `brnz` at 0x08)
    /// follows a hint issued just before it, so its first passes miss and the later ones
    /// are hinted.
    #[test]
    fn steady_passes_time_as_passes_one_by_one() {
        let hbrr = w("hbrr", &[0x0c, 0x08], 0x00);
        let il = w("il", &[9, 10], 0x04);
        let ai = w("ai", &[9, 9, -1], 0x08);
        let brnz = w("brnz", &[9, 0x08], 0x0c);
        let (ai8, brnz8) = (w("ai", &[8, 8, -1], 0x10), w("brnz", &[8, 0x00], 0x14));
        let mut t = Timing::new(TimingConfig::default());
        let pass = |t: &mut Timing, taken: bool| {
            t.issue(0x08, ai);
            t.issue(0x0c, brnz);
            t.branch_resolved(0x0c, brnz, taken, 0x08);
        };
        let mut steady = 0;
        for outer in 0..8 {
            t.issue(0x00, hbrr);
            t.hint(0x00, 0x0c, 0x08);
            t.issue(0x04, il);
            for p in 0..10 {
                if let Some(f) = t.memo.chain_from.filter(|f| f.taken && p > 0) {
                    let mut bulk = t.clone();
                    let passes = bulk.steady_passes(f.memo, 0x08, ai, bulk.now + 200);
                    if passes >= 2 {
                        steady += 1;
                        let mut one_by_one = bulk.clone();
                        bulk.steady_replayed(f.memo, passes, (0x0c, true, 0x08));
                        for _ in 0..passes {
                            pass(&mut one_by_one, true);
                        }
                        let (a, b) = (bulk.finish_profile(), one_by_one.finish_profile());
                        assert_eq!(bulk.now, one_by_one.now, "outer {outer} pass {p}");
                        assert_eq!(a.totals, b.totals, "outer {outer} pass {p}");
                        let per =
                            |p: &Profile| p.addresses().map(|(a, s)| (a, *s)).collect::<Vec<_>>();
                        assert_eq!(per(&a), per(&b), "outer {outer} pass {p}");
                    }
                }
                pass(&mut t, p < 9);
            }
            t.issue(0x10, ai8);
            t.issue(0x14, brnz8);
            t.branch_resolved(0x14, brnz8, true, 0x00);
        }
        assert!(steady > 8, "{steady} steady states");
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
