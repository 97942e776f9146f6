//! The block memo of the timing model.
//!
//! A basic block (up to its first branch) issued from the same relative pipeline state always
//! times the same way. The first time a block starts at an address the model records, for
//! each of its instructions, the state after it relative to the block's entry cycle and every
//! counter change; when the block later starts in the same relative state (its signature),
//! the recorded issue cycles are returned instead of recomputed, the state is set from the
//! record at the end of the block, and the counter changes are counted once per replay and
//! added when the profile is read. Anything unexpected in the middle of a replay (another
//! address, a hook) first brings the state up to date at that point, so the result is exact.

use super::*;
use crate::profile::{LogEntry, COUNTERS, STALL_COUNTERS_AT};

/// The longest block recorded (and compiled).
pub(crate) const MAX_BLOCK: usize = 256;
pub(super) const NEVER: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
pub(super) struct Step {
    pub issue_rel: i64,
    pub write: StepWrite,
    pub exit: Exit,
    pub log_end: usize,
    /// The profile's counters since the block's entry ([`Totals::counters`]), in 32 bits:
    /// a record holds one such step per instruction.
    pub totals: [u32; COUNTERS],
}

/// The state after a step that is not in the registers' readiness (times relative to the
/// block's entry): what a replay that ends after the step sets. A record keeps its last
/// step's apart ([`Memo::exit`]), next to the rest a full replay reads, so that a replay
/// does not reach into its steps.
#[derive(Clone, Copy, Debug)]
pub(super) struct Exit {
    pub last: Last,
    pub last_issue_rel: i64,
    pub dp_rel: Option<i64>,
    /// The hint entry once the block set it (issue and instruction count relative to the
    /// entry), and whether an `hbr` set it last: its target is then the one the core
    /// last noted ([`Timing::note_hint_target`]), not the recorded one.
    pub hint: Option<(HintEntry, i64, u64, bool)>,
    pub fetch: (u32, bool, i64, i64),
    pub record: IssueRecord,
    pub record_base_rel: i64,
}

#[derive(Clone, Debug)]
pub(super) struct Memo {
    pub start: u32,
    pub words: Vec<u32>,
    pub live: Vec<u8>,
    /// The live registers ready before the entry when the block was recorded (their part
    /// of the signature: each ready before now), and the others, whose part is in `sig`.
    pub live_past: Vec<u8>,
    pub live_exact: Vec<u8>,
    pub branch_pc: u32,
    /// The conditional branches inside the block (before its last instruction): the
    /// record went on past each, untaken and named by no hint. A replay that finds one
    /// taken stops there.
    pub inner: Vec<u32>,
    /// The signature of the state the block was recorded in, but for `live_past`.
    pub sig: Vec<i64>,
    pub steps: Vec<Step>,
    /// The last step's [`Exit`].
    pub exit: Exit,
    /// Each step's register write (the steps', packed): a partial replay applies those
    /// of its steps without reaching into them.
    pub step_writes: Vec<StepWrite>,
    pub log: Vec<LogEntry>,
    pub hits: u64,
    /// Replays that stopped after step `k` (an inner branch taken, a hook), by `k`:
    /// their counters are added with the full replays' (empty until the first).
    pub partial_hits: Vec<u64>,
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
    /// The cycles, relative to the entry and from it on, at which the fetch model looked
    /// for a local-store cycle free of DMA (sorted): a DMA cycle elsewhere changes
    /// nothing the block's timing depends on.
    pub probes: Vec<u32>,
    /// The block sets the hint entry (so after a replay it follows from the record).
    pub sets_hint: bool,
    /// Cycles its first instruction waits for a branch miss just before the block (R4),
    /// charged to that branch, whichever it was: so the record leaves them out and each
    /// replay charges them to the branch of its own entry.
    pub entry_miss_stall: u64,
    /// Distinguishes this record from an earlier one in the same place.
    pub generation: u64,
    /// The blocks that followed a full replay, not taken and taken (see [`Chain`]).
    pub chain: [Chain; 2],
    /// What the core keeps with the record (its compiled code), zeros for nothing.
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub code: [u64; 3],
    /// The next record for the same start (another entry state): memo index + 1, 0 none.
    pub next: u32,
}

/// Records kept for one block start, each for another recurring entry state.
pub(super) const MEMO_WAYS: usize = 8;

/// A step's register write (`reg` 128: none).
#[derive(Clone, Copy, Debug)]
pub(super) struct StepWrite {
    pub ready_rel: i64,
    pub producer: u32,
    pub reg: u8,
    pub unit: Unit,
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
    /// The last hint recorded was an `hbr`.
    pub hint_dynamic: bool,
    /// Hints the block set (a record with several hint entries keeps at most one).
    pub hints_set: u8,
    /// With several hint entries, the entries but the newest at the entry (else empty).
    pub entry_more_hints: Vec<HintEntry>,
    pub steps: Vec<Step>,
    /// The cycles the fetch model probed for a free local-store cycle (absolute).
    pub probes: Vec<u64>,
    /// How many of them the recorded steps made (the rest are the current one's).
    pub probes_done: usize,
    /// Where the record stands after its last step, when that is a conditional branch.
    pub after_branch: AfterBranch,
    /// A counter since the entry outgrew a step's 32 bits: the record is not kept.
    pub overflowed: bool,
}

/// A recording whose last step is a conditional branch: it goes on past the branch
/// only when the branch resolved untaken and no hint named it (then its timing is the
/// record's whatever the branch reads), else the block ends with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum AfterBranch {
    NoBranch,
    Unresolved,
    GoesOn,
    Ends,
}

/// Conditional branches a block (its record, its compiled code) may go on past into
/// the next instruction, whose taken way leaves the block: the relative ones, and the
/// indirect ones that leave the interrupt enable alone (an untaken branch that no hint
/// names times the same wherever its register points; one that enables or disables
/// interrupts changes what the run loops may do after it).
#[inline]
pub(crate) fn may_fall_through(inst: Inst) -> bool {
    match inst.op {
        Op::Brz | Op::Brnz | Op::Brhz | Op::Brhnz => true,
        Op::Biz | Op::Binz | Op::Bihz | Op::Bihnz => inst.feature_bits() & 0x30 == 0,
        _ => false,
    }
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
    pub fails: Vec<u8>,
    pub memos: Vec<Memo>,
    pub rec: Option<Box<Recording>>,
    pub replay: Option<Replay>,
    pub chain_from: Option<ChainFrom>,
    /// A [`Timing::block_replay_candidate`] at this address and instruction count found
    /// this record, not clear of DMA: `issue` right after it issues the instruction alone
    /// without looking the record up again.
    pub dma_blocked: Option<(u32, u64)>,
    pub generations: u64,
    /// The buffer the next recording's steps go into: room for the longest block, kept
    /// from recording to recording (each record keeps a copy of its own size).
    pub spare_steps: Vec<Step>,
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
            m.partial_hits.clear();
        }
    }

    /// Adds every replay's counters (and a replay in progress up to `partial`).
    pub fn add_pending(&self, p: &mut Profile, partial: Option<(usize, usize)>) {
        for m in &self.memos {
            if m.hits > 0 {
                p.apply_log(&m.log, m.hits);
                p.totals
                    .add_counters(&m.steps.last().unwrap().totals, m.hits);
            }
            add_partial_hits(m, p);
        }
        if let Some((id, k)) = partial {
            let m = &self.memos[id];
            let st = &m.steps[k - 1];
            p.apply_log(&m.log[..st.log_end], 1);
            p.totals.add_counters(&st.totals, 1);
        }
    }

    /// Adds the counters of `id`'s replays to the profile and forgets them.
    pub fn flush(&mut self, id: usize, p: &mut Profile) {
        let m = &mut self.memos[id];
        if m.hits > 0 {
            p.apply_log(&m.log, m.hits);
            p.totals
                .add_counters(&m.steps.last().unwrap().totals, m.hits);
            m.hits = 0;
        }
        add_partial_hits(m, p);
        m.partial_hits.clear();
    }
}

/// Instructions that end a block before them and are never recorded: channel and SPR
/// access (channel stalls; not the MFC command parameters' latches, which never wait),
/// halts, stops and syncs, unknown words. A register-form hint
/// (`hbr`) does not: its target, different from pass to pass, is no part of a record
/// (see [`Timing::note_hint_target`]).
pub(super) fn is_terminator(inst: Inst) -> bool {
    use Op::*;
    if analysis::is_mfc_param_write(inst) {
        return false;
    }
    matches!(
        inst.op,
        Rdch | Wrch
            | Rchcnt
            | Mfspr
            | Mtspr
            | Stop
            | Stopd
            | Sync
            | Dsync
            | Heq
            | Hgt
            | Hlgt
            | Heqi
            | Hgti
            | Hlgti
            | Unknown
    )
}

/// Takes out of a block's record the branch-miss wait of its first instruction (the
/// profile's stall and cycles at the missed branch `miss_pc`, the first two notes of that
/// cause in the first step's log) and returns its cycles.
fn take_entry_miss_stall(steps: &mut [Step], log: &mut Vec<LogEntry>, miss_pc: u32) -> u64 {
    let field = 3 + StallCause::BranchMiss.index() as u8;
    let end = steps[0].log_end.min(log.len());
    let Some(at) = log[..end]
        .iter()
        .position(|e| e.field == field && e.pc == miss_pc)
    else {
        return 0;
    };
    let n = log[at].n;
    let cycles = log
        .get(at + 1)
        .filter(|e| e.field == 1 && e.pc == miss_pc && e.n == n);
    if at + 1 >= end || cycles.is_none() {
        return 0;
    }
    log.drain(at..at + 2);
    for st in steps.iter_mut() {
        st.log_end -= 2;
        st.totals[STALL_COUNTERS_AT + StallCause::BranchMiss.index()] -= n as u32;
    }
    n
}

/// Adds the counters of memo `m`'s replays that stopped inside the block.
fn add_partial_hits(m: &Memo, p: &mut Profile) {
    for (st, &n) in m.steps.iter().zip(&m.partial_hits) {
        if n > 0 {
            p.apply_log(&m.log[..st.log_end], n);
            p.totals.add_counters(&st.totals, n);
        }
    }
}

/// Whether hint entry `h` names one of the branches `inner`.
#[inline]
fn names_inner(h: &HintEntry, inner: &[u32]) -> bool {
    h.valid && inner.contains(&h.branch)
}

/// With several hint entries (`multihint`), whether a block whose final branch is at
/// `branch_pc`, with inner branches `inner`, that sets a hint for branch `sets` (at most
/// one), times the same as with the newest entry `newest` alone, so that its record (or
/// its replay) holds: no other entry `more` names one of its branches, and the newest
/// names none but the one the block hints itself (which then replaces it). Otherwise the
/// newest entry, pushed down by the block's hint, would still hint a branch after it.
#[inline]
fn others_quiet(
    newest: &HintEntry,
    more: &[HintEntry],
    branch_pc: u32,
    inner: &[u32],
    sets: Option<u32>,
) -> bool {
    let names = |h: &HintEntry| h.valid && (h.branch == branch_pc || inner.contains(&h.branch));
    !more.iter().any(names)
        && match sets {
            Some(b) => newest.branch == b || !names(newest),
            None => true,
        }
}

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
/// stops, halts, `sync`, undecodable words).
#[inline]
pub fn ends_block(inst: Inst) -> bool {
    is_terminator(inst)
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
        inner: &[u32],
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
        if !emit((e.dp_until as i64 - now).max(0)) {
            return false;
        }
        if !inner.is_empty() && !emit(names_inner(&e.hint, inner) as i64) {
            return false;
        }
        if let Some((bpc, k)) = branch_at {
            let [bits, window] = self.hint_view(&e.hint, e.index, e.now, bpc, k);
            if !emit(bits) {
                return false;
            }
            if bits == 3 && !emit(window) {
                return false;
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
    /// long its window still runs (else 0). Not its target: that only decides whether the
    /// branch, resolving after the block, was predicted, and a replay takes it from the
    /// entry as it is then (see [`Timing::materialize`]), so a register-target hint
    /// (`hbr`) naming a different target each time still replays the block.
    #[inline(always)]
    fn hint_view(&self, h: &HintEntry, index: u64, now: u64, bpc: u32, k: u64) -> [i64; 2] {
        let m = h.valid && h.branch == bpc;
        let close = index + k - h.index >= self.config.hint_min_distance as u64;
        if m && close {
            [
                3,
                (h.issued as i64 + self.config.hint_window as i64 - now as i64).max(-1),
            ]
        } else {
            [m as i64 | (close as i64) << 1, 0]
        }
    }

    /// [`Timing::hint_view`] of the current state for memo `id`'s branch, and whether
    /// the hint entry names one of its inner branches.
    #[inline]
    fn hint_view_now(&self, id: usize) -> [i64; 3] {
        let m = &self.memo.memos[id];
        let inner = names_inner(&self.hint, &m.inner) as i64;
        if m.branch_pc == NO_PC {
            return [0, 0, inner];
        }
        let [bits, window] = self.hint_view(
            &self.hint,
            self.index,
            self.now,
            m.branch_pc,
            m.words.len() as u64 - 1,
        );
        [bits, window, inner]
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
            totals: self.profile.totals,
        }
    }

    pub(super) fn issue_memo(&mut self, pc: u32, inst: Inst) -> u64 {
        self.apply_deferred_writes();
        if let Some(rec) = &self.memo.rec {
            let k = rec.words.len();
            let after = rec.after_branch;
            if pc != rec.start.wrapping_add(4 * k as u32)
                || is_terminator(inst)
                || k >= MAX_BLOCK
                || !matches!(after, AfterBranch::NoBranch | AfterBranch::GoesOn)
            {
                self.finish_recording();
            } else {
                return self.issue_recorded(pc, inst);
            }
        }
        if is_terminator(inst) {
            return self.issue_slow(pc, inst);
        }
        // The lookup just made for this instruction found its record blocked by DMA.
        if self.memo.dma_blocked.take() == Some((pc, self.index)) {
            return self.issue_slow(pc, inst);
        }
        let idx = Self::slot_index(pc);
        if idx >= self.memo.slots.len() {
            self.memo.slots.resize(0x1_0000, 0);
            self.memo.fails.resize(0x1_0000, 0);
        }
        // While DMA holds local-store cycles, blocks replay only clear of them, and a
        // recording ends before an instruction whose fetch meets one (a record must not
        // depend on them).
        match self.chained_lookup(idx, pc, inst) {
            Lookup::Never => return self.issue_slow(pc, inst),
            Lookup::Hit(id) if self.clear_of_dma(id) => return self.begin_replay(id, pc, inst),
            Lookup::Hit(_) => return self.issue_slow(pc, inst),
            Lookup::Differs(id) => {
                // A different state: record again (keeping what the old record counted).
                if self.memo.memos[id].hits < 2 {
                    self.memo.fails[idx] = self.memo.fails[idx].saturating_add(1);
                    if self.memo.fails[idx] >= 8 {
                        let mut at = self.memo.slots[idx];
                        while at != 0 {
                            let id = (at - 1) as usize;
                            self.memo.flush(id, &mut self.profile);
                            at = self.memo.memos[id].next;
                        }
                        self.memo.slots[idx] = NEVER;
                        return self.issue_slow(pc, inst);
                    }
                }
            }
            Lookup::Absent => {}
        }
        // Record this block.
        self.memo.rec = Some(Box::new(Recording {
            start: pc,
            words: Vec::with_capacity(MAX_BLOCK),
            entry: Box::new(self.entry()),
            dp_changed: false,
            hint_changed: false,
            hint_dynamic: false,
            hints_set: 0,
            entry_more_hints: self.more_hints.clone(),
            steps: {
                // Empty: a recording hands its buffer back cleared.
                let mut steps = std::mem::take(&mut self.memo.spare_steps);
                steps.reserve(MAX_BLOCK);
                steps
            },
            probes: Vec::new(),
            probes_done: 0,
            after_branch: AfterBranch::NoBranch,
            overflowed: false,
        }));
        self.profile.log = Some(Vec::with_capacity(MAX_BLOCK));
        self.issue_recorded(pc, inst)
    }

    /// Issues `inst` at `pc` as the next step of the recording: a branch ends it, unless
    /// the record may go on past it (then it waits for how the branch resolves).
    fn issue_recorded(&mut self, pc: u32, inst: Inst) -> u64 {
        let t = self.issue_slow(pc, inst);
        self.record_step(inst);
        let branch = self.classes[inst.op as usize].flags & F_BRANCH != 0;
        if branch && !may_fall_through(inst) {
            self.finish_recording();
        } else if let Some(rec) = self.memo.rec.as_deref_mut() {
            rec.after_branch = if branch {
                AfterBranch::Unresolved
            } else {
                AfterBranch::NoBranch
            };
        }
        t
    }

    /// A branch at `pc` resolved (`taken` or not) while a block is recorded or replayed
    /// per instruction. Returns true when that is all: an untaken inner branch of the
    /// block being replayed (the record holds what it did).
    #[inline]
    pub(super) fn inner_branch_resolved(&mut self, pc: u32, taken: bool) -> bool {
        if let Some(rp) = &self.memo.replay {
            let m = &self.memo.memos[rp.memo];
            return !taken
                && rp.k > 0
                && rp.k < m.words.len()
                && pc == m.start.wrapping_add(4 * (rp.k as u32 - 1));
        }
        if let Some(rec) = self.memo.rec.as_deref_mut() {
            if rec.after_branch == AfterBranch::Unresolved && self.last.pc == pc {
                let named = self.hint.valid && self.hint.branch == pc & 0x3_ffff;
                rec.after_branch = if taken || named {
                    AfterBranch::Ends
                } else {
                    AfterBranch::GoesOn
                };
            }
        }
        false
    }

    /// The memo for a block starting at `pc` with first instruction `inst` (slot `idx`),
    /// and whether the current state matches the one it was recorded in.
    #[inline]
    fn memo_lookup(&self, idx: usize, pc: u32, inst: Inst) -> Lookup {
        let slot = self.memo.slots[idx];
        if slot == NEVER {
            return Lookup::Never;
        }
        if slot == 0 {
            return Lookup::Absent;
        }
        // The records for this start, each for another entry state; when they are all
        // taken, a new one replaces the one replayed least.
        let (mut at, mut ways, mut victim) = (slot, 0, (slot - 1) as usize);
        while at != 0 {
            let id = (at - 1) as usize;
            if self.entry_matches(id, pc, inst) {
                return Lookup::Hit(id);
            }
            if self.memo.memos[id].hits < self.memo.memos[victim].hits {
                victim = id;
            }
            ways += 1;
            at = self.memo.memos[id].next;
        }
        if ways < MEMO_WAYS && self.memo.memos[victim].words[0] == inst.word {
            Lookup::Absent
        } else {
            Lookup::Differs(victim)
        }
    }

    /// Whether memo `id` is the block at `pc` starting with `inst` and the current state
    /// matches its signature.
    #[inline]
    fn entry_matches(&self, id: usize, pc: u32, inst: Inst) -> bool {
        let m = &self.memo.memos[id];
        if m.start != pc || m.words[0] != inst.word || !self.others_quiet_now(id) {
            return false;
        }
        let branch_at = (m.branch_pc != NO_PC).then(|| (m.branch_pc, m.words.len() as u64 - 1));
        // Branch-free: these registers are many, and all ready long ago as a rule.
        let now = self.now;
        let past = m
            .live_past
            .iter()
            .fold(true, |all, &r| all & (self.ready[(r & 127) as usize] < now));
        if !past {
            return false;
        }
        let e = self.entry_ref();
        let mut pos = 0usize;
        let sig = &m.sig[..];
        self.signature(&e, &m.live_exact, pc, branch_at, &m.inner, &mut |v| {
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
        let from = self
            .memo
            .chain_from
            .take()
            .filter(|f| self.chain_current(f));
        if let Some(id) = from.and_then(|f| self.chained_memo(f, pc)) {
            if self.memo.memos[id].words[0] == inst.word {
                return Lookup::Hit(id);
            }
        }
        self.apply_deferred_writes();
        let found = self.memo_lookup(idx, pc, inst);
        if let (Lookup::Hit(id), Some(f)) = (&found, from) {
            // B's live registers that A does not write (when few enough to list).
            let (a, b) = (&self.memo.memos[f.memo], &self.memo.memos[*id]);
            let mut listed = [128u8; OPEN_MAX];
            let mut n = 0;
            for &r in &b.live {
                if a.writes_mask & (1u128 << (r & 127)) == 0 {
                    if n == OPEN_MAX {
                        listed = [UNLISTED; OPEN_MAX];
                        break;
                    }
                    listed[n] = r;
                    n += 1;
                }
            }
            if self.open_registers_ready(f.max_ready_at_entry, &listed) {
                let chain = Chain {
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

    /// Whether chain `f` is still that of the block whose full replay just ended: the same
    /// slot index, its record not replaced since.
    #[inline(always)]
    fn chain_current(&self, f: &ChainFrom) -> bool {
        f.index == self.index && self.memo.memos[f.memo].generation == f.generation
    }

    /// The memo that chain `f` (the block whose full replay just ended, still current)
    /// names for a block at `pc`, when its entry state follows from that block's: the
    /// chained record is still the one the chain saw, the registers the chain leaves open
    /// are ready and the hint reads the same. The caller checks the block's words.
    #[inline(always)]
    fn chained_memo(&self, f: ChainFrom, pc: u32) -> Option<usize> {
        let a = &self.memo.memos[f.memo];
        let c = &a.chain[f.taken as usize];
        let id = c.memo as usize;
        let ok = c.pc == pc
            && self.memo.memos[id].generation == c.generation
            && self.open_registers_ready(f.max_ready_at_entry, &c.open)
            && (a.sets_hint || self.hint_view_now(id) == c.hint)
            && self.others_quiet_now(id);
        ok.then_some(id)
    }

    /// [`others_quiet`] for memo `id` in the current state (at once with one entry).
    #[inline(always)]
    fn others_quiet_now(&self, id: usize) -> bool {
        if self.config.hint_entries == 1 {
            return true;
        }
        let m = &self.memo.memos[id];
        others_quiet(
            &self.hint,
            &self.more_hints,
            m.branch_pc,
            &m.inner,
            m.exit.hint.map(|h| h.0.branch),
        )
    }

    /// Whether the registers a chain leaves open (`open`: a list ended by 128, or
    /// [`UNLISTED`] for any register) were all ready before now: at once when every
    /// register was ready by the previous block's entry.
    #[inline(always)]
    fn open_registers_ready(&self, max_ready_at_entry: u64, open: &[u8; OPEN_MAX]) -> bool {
        if max_ready_at_entry < self.now {
            return true;
        }
        if open[0] == UNLISTED {
            return false;
        }
        open.iter()
            .take_while(|&&r| r < 128)
            .all(|&r| self.ready[r as usize] < self.now)
    }

    /// Starts replaying memo `id` with its first instruction (`pc`, `inst`); returns that
    /// instruction's issue cycle.
    fn begin_replay(&mut self, id: usize, pc: u32, inst: Inst) -> u64 {
        self.charge_entry_miss(id);
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
    /// in progress; nothing changes. Once the core ran it whole, [`Timing::block_replayed`].
    #[inline(always)]
    pub(crate) fn block_replay_candidate(&mut self, pc: u32, inst: Inst) -> Option<(usize, usize)> {
        if !self.memo_between_blocks() || is_terminator(inst) {
            return None;
        }
        let idx = Self::slot_index(pc);
        if idx >= self.memo.slots.len() {
            return None;
        }
        match self.chained_lookup(idx, pc, inst) {
            Lookup::Hit(id) if self.clear_of_dma(id) => Some((id, self.memo.memos[id].words.len())),
            Lookup::Hit(_) => {
                self.memo.dma_blocked = Some((pc, self.index));
                None
            }
            _ => None,
        }
    }

    /// Memoization is on and neither a recording nor a replay is under way: a block may
    /// start here as a replay.
    #[inline(always)]
    fn memo_between_blocks(&self) -> bool {
        self.config.memoize && self.memo.rec.is_none() && self.memo.replay.is_none()
    }

    /// [`Timing::block_replay_candidate`] through the chain of the block whose full replay
    /// just ended only, for a block whose words the core last found in local store at
    /// code epoch `epoch` (the current one): the record's own check then stands for
    /// reading its first word. The memo and its length, or `None` with nothing changed
    /// (then ask [`Timing::block_replay_candidate`]).
    #[inline(always)]
    pub(crate) fn chained_replay_candidate(
        &mut self,
        pc: u32,
        epoch: u64,
    ) -> Option<(usize, usize)> {
        if !self.memo_between_blocks() {
            return None;
        }
        let f = self.memo.chain_from.filter(|f| self.chain_current(f))?;
        let id = self.chained_memo(f, pc)?;
        let b = &self.memo.memos[id];
        if b.verified != epoch || b.start != pc || !self.clear_of_dma(id) {
            return None;
        }
        self.memo.chain_from = None;
        Some((id, self.memo.memos[id].words.len()))
    }

    /// Whether memo `id`'s block, starting now, is clear of the cycles DMA holds in the
    /// local store: it ends its use of the local store before the first of them, or none
    /// of them before that end is now or later than now and a cycle its fetch model
    /// probed (DMA reaches the timing only through those probes). The model then asks of
    /// it exactly what it asked when the block was recorded (with no DMA), so the record
    /// holds.
    #[inline]
    fn clear_of_dma(&mut self, id: usize) -> bool {
        let horizon = self.now + self.memo.memos[id].dma_horizon_rel;
        if self.fetch.dma_min > horizon {
            return true;
        }
        self.drop_past_dma_cycles();
        self.fetch.dma_min > horizon || self.probes_miss_dma(id, horizon)
    }

    /// Whether every DMA cycle up to `horizon` is now or later and none is one of memo
    /// `id`'s probes (relative to now).
    #[cold]
    fn probes_miss_dma(&self, id: usize, horizon: u64) -> bool {
        let probes = &self.memo.memos[id].probes;
        let now = self.now;
        self.fetch
            .dma
            .iter()
            .take_while(|&&c| c <= horizon)
            .all(|&c| c >= now && probes.binary_search(&((c - now) as u32)).is_err())
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
    pub(crate) fn memo_words(&self, id: usize) -> (&[u32], u64) {
        let m = &self.memo.memos[id];
        (&m.words, m.verified)
    }

    /// Past every cycle memo `id`'s replay issues at, relative to its entry: a replay
    /// entered at cycle `c` issues nothing at or after `c + memo_span(id)`.
    #[inline]
    pub fn memo_span(&self, id: usize) -> u64 {
        self.memo.memos[id].dma_horizon_rel
    }

    /// What the core kept with memo `id` ([`Timing::set_memo_code`]); zeros for nothing.
    #[inline]
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(crate) fn memo_code(&self, id: usize) -> [u64; 3] {
        self.memo.memos[id].code
    }

    /// Keeps `code` with memo `id` (the core's compiled code for the record's words), until
    /// the record is replaced.
    #[inline]
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(crate) fn set_memo_code(&mut self, id: usize, code: [u64; 3]) {
        self.memo.memos[id].code = code;
    }

    /// Notes that local store held memo `id`'s words at code epoch `epoch`.
    #[inline]
    pub(crate) fn set_memo_verified(&mut self, id: usize, epoch: u64) {
        self.memo.memos[id].verified = epoch;
    }

    /// The entry of a block replayed whole by the core: the replay `issue` started, or
    /// (for a [`Timing::block_replay_candidate`]) the current state.
    #[inline]
    fn block_entry(&mut self, id: usize) -> Replay {
        match self.memo.replay.take() {
            Some(rp) if rp.memo == id => rp,
            _ => {
                self.charge_entry_miss(id);
                Replay {
                    memo: id,
                    k: 0,
                    entry_now: self.now,
                    entry_index: self.index,
                    entry_max_ready: self.max_ready,
                }
            }
        }
    }

    /// A replay of memo `id` starts: the branch-miss wait of its first instruction goes
    /// to the branch that missed, as issuing it would have charged it.
    #[inline(always)]
    fn charge_entry_miss(&mut self, id: usize) {
        let n = self.memo.memos[id].entry_miss_stall;
        if n > 0 {
            self.profile.stall(self.miss_pc, StallCause::BranchMiss, n);
        }
    }

    /// The core ran memo `id`'s block whole (a [`Timing::block_replay_candidate`], or the
    /// replay `issue` started): the state and counters become what issuing each of its
    /// instructions would have made them, and `branch` (its last instruction's address,
    /// whether it was taken and where to) resolves.
    #[inline(always)]
    pub(crate) fn block_replayed(&mut self, id: usize, branch: Option<(u32, bool, u32)>) {
        let mut rp = self.block_entry(id);
        let m = &mut self.memo.memos[id];
        m.hits += 1;
        rp.k = m.words.len();
        self.materialize(rp, false);
        self.chain_after(rp);
        if let Some((pc, taken, target)) = branch {
            self.resolve_branch(pc, taken, target);
        }
    }

    /// The core ran the first `k` instructions of memo `id`'s block, the last of them an
    /// inner branch at `pc`, which was taken (to `target`).
    pub(crate) fn block_left_at_branch(&mut self, id: usize, k: usize, pc: u32, target: u32) {
        self.block_replayed_partly(id, k);
        self.resolve_branch(pc, true, target);
    }

    /// The core ran the first `k` instructions of memo `id`'s block and stopped (the rest
    /// go through `issue`).
    pub(crate) fn block_replayed_partly(&mut self, id: usize, k: usize) {
        let mut rp = self.block_entry(id);
        rp.k = k;
        self.memo.replay = Some(rp);
        self.sync();
    }

    /// Right after a full replay of memo `id` (entered in its recorded state) whose final
    /// branch went back to the block's own start `pc` (first instruction `inst`): how many
    /// passes from now, one after the other while the branch keeps going back, are sure to
    /// replay exactly as the one just done, each starting before cycle `until` and clear
    /// of DMA; 0 when the state is not steady (yet).
    ///
    /// Steady: the state now matches the record again. Then every later pass does too.
    /// Each part of the signature is either set by the block's record and the branch
    /// outcome (the same after every pass, relative to the next entry), or left alone by
    /// the block, and then it moved by the pass's length between two entries that both
    /// matched: a readiness, a redirect, a double-precision block or a hint window that
    /// moves and still reads the same has reached its floor (already past) and stays
    /// there. The one part that does not settle that way, whether a hint the block does
    /// not set itself is far enough ahead of the branch, only grows from false to true,
    /// so it is required true.
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(crate) fn steady_passes(&mut self, id: usize, pc: u32, inst: Inst, until: u64) -> u64 {
        if !self.memo_between_blocks() {
            return 0;
        }
        match self.memo.chain_from {
            Some(f) if f.memo == id && f.taken && f.index == self.index => {}
            _ => return 0,
        }
        self.apply_deferred_writes();
        if !self.entry_matches(id, pc, inst) {
            return 0;
        }
        let m = &self.memo.memos[id];
        if !m.sets_hint && self.hint_view_now(id)[0] & 2 == 0 {
            return 0;
        }
        let delta = m.exit.last_issue_rel as u64 + 1;
        // Passes start at now + k * delta, each before `until` ...
        let mut last_start = until.saturating_sub(1);
        // ... and with its use of the local store ending before the first DMA cycle.
        if self.fetch.dma_min != u64::MAX {
            last_start = last_start.min(self.fetch.dma_min.saturating_sub(m.dma_horizon_rel + 1));
        }
        if last_start < self.now {
            return 0;
        }
        ((last_start - self.now) / delta + 1).min(1 << 32)
    }

    /// The core ran `passes` passes of memo `id`'s block in the steady state
    /// [`Timing::steady_passes`] found, each a full replay whose final branch (at
    /// `branch.0`) went back to the block's start `branch.2`: the state and counters
    /// become what replaying them one by one would have made them.
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(crate) fn steady_replayed(&mut self, id: usize, passes: u64, branch: (u32, bool, u32)) {
        if passes == 0 {
            return;
        }
        let skip = passes - 1;
        if skip > 0 {
            self.memo.memos[id].hits += skip;
            let m = &self.memo.memos[id];
            let delta = m.exit.last_issue_rel as u64 + 1;
            let hinted = self.entry_hinted(id, m.exit.last);
            let max_ready_rel = m.max_ready_rel;
            let len = m.words.len() as u64;
            let entry = self.now;
            // The state at the last pass's entry: every pass sets the same parts (the
            // last pass sets them again), the rest is left alone.
            self.max_ready = self
                .max_ready
                .max(entry + (skip - 1) * delta + max_ready_rel);
            self.index += skip * len;
            self.now = entry + skip * delta;
            self.count_branch(hinted, true, branch.2 & 0x3_ffff, skip);
            // Each pass but the last (charged by its replay below) after the miss of
            // the same branch.
            let n = self.memo.memos[id].entry_miss_stall;
            if n > 0 {
                self.profile
                    .stall(self.miss_pc, StallCause::BranchMiss, n * skip);
            }
        }
        self.block_replayed(id, Some(branch));
    }

    /// The memo whose replay `issue` started.
    #[inline]
    pub(crate) fn replay_memo(&self) -> Option<usize> {
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
        rec.probes_done = rec.probes.len();
        let totals = self.profile.totals.counters_since(&rec.entry.totals);
        rec.overflowed |= totals.is_none();
        let e = &rec.entry;
        let now = e.now as i64;
        let class = self.classes[inst.op as usize];
        if class.flags & (F_FPD | F_GATHER) != 0 {
            rec.dp_changed = true;
        }
        if class.flags & F_HINT != 0 && !is_hbrp(inst) {
            rec.hint_changed = true;
            rec.hint_dynamic = inst.op == Op::Hbr;
            rec.hints_set = rec.hints_set.saturating_add(1);
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
            write: StepWrite {
                ready_rel,
                producer,
                reg: w,
                unit,
            },
            exit: Exit {
                last: self.last,
                last_issue_rel: self.last.issue as i64 - now,
                dp_rel: rec.dp_changed.then(|| self.dp_until as i64 - now),
                hint: rec.hint_changed.then(|| {
                    (
                        self.hint,
                        self.hint.issued as i64 - now,
                        self.hint.index - e.index,
                        rec.hint_dynamic,
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
            },
            log_end: self.profile.log.as_ref().map_or(0, |l| l.len()),
            totals: totals.unwrap_or([0; COUNTERS]),
        };
        rec.words.push(inst.word);
        rec.steps.push(step);
    }

    /// The fetch model of the instruction being recorded met a local-store cycle DMA
    /// holds: the record must not depend on DMA, so it ends with the instructions before
    /// (whose probes all found their cycles free), and this one issues unrecorded.
    pub(super) fn cut_recording(&mut self) {
        let Some(rec) = self.memo.rec.as_deref_mut() else {
            return;
        };
        rec.probes.truncate(rec.probes_done);
        let log_end = rec.steps.last().map_or(0, |st| st.log_end);
        if let Some(log) = self.profile.log.as_mut() {
            log.truncate(log_end);
        }
        self.finish_recording();
    }

    fn finish_recording(&mut self) {
        // The record may replace the deferred block's memo.
        self.apply_deferred_writes();
        let Some(rec) = self.memo.rec.take() else {
            return;
        };
        let mut log = self.profile.log.take().unwrap_or_default();
        let mut rec = rec;
        if rec.steps.is_empty() || rec.overflowed {
            rec.steps.clear();
            self.memo.spare_steps = std::mem::take(&mut rec.steps);
            return;
        }
        // Recorded into room for the longest block, kept at their size.
        let steps = rec.steps.to_vec();
        rec.steps.clear();
        self.memo.spare_steps = std::mem::replace(&mut rec.steps, steps);
        rec.words.shrink_to_fit();
        log.shrink_to_fit();
        let entry_miss_stall = take_entry_miss_stall(&mut rec.steps, &mut log, rec.entry.miss_pc);
        // Live-in registers: read before the block writes them.
        let mut written = [false; 128];
        let mut live = Vec::new();
        let mut branch_pc = NO_PC;
        let mut inner = Vec::new();
        for (k, &word) in rec.words.iter().enumerate() {
            // A recorded block ran: its extension words were on.
            let inst = crate::codec::decode_ext(word, crate::ext::Extensions::ALL);
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
                let at = rec.start.wrapping_add(4 * k as u32) & 0x3_ffff;
                if k + 1 == rec.words.len() {
                    branch_pc = at;
                } else {
                    inner.push(at);
                }
            }
        }
        let exit = rec.steps.last().expect("a step").exit;
        if self.config.hint_entries > 1
            && (rec.hints_set > 1
                || !others_quiet(
                    &rec.entry.hint,
                    &rec.entry_more_hints,
                    branch_pc,
                    &inner,
                    exit.hint.map(|h| h.0.branch),
                ))
        {
            // Timed by more than the newest hint entry: not kept (the block is timed
            // per instruction where it runs again in such a state). A start that has
            // no record and keeps failing so is not recorded again.
            rec.steps.clear();
            self.memo.spare_steps = std::mem::take(&mut rec.steps);
            let idx = Self::slot_index(rec.start);
            if self.memo.slots.get(idx) == Some(&0) {
                self.memo.fails[idx] = self.memo.fails[idx].saturating_add(1);
                if self.memo.fails[idx] >= 8 {
                    self.memo.slots[idx] = NEVER;
                }
            }
            return;
        }
        let branch_at = (branch_pc != NO_PC).then(|| (branch_pc, rec.words.len() as u64 - 1));
        let (live_past, live_exact): (Vec<u8>, Vec<u8>) = live
            .iter()
            .partition(|&&r| rec.entry.ready[r as usize] < rec.entry.now);
        let mut sig = Vec::new();
        self.signature(
            &Entry::as_ref(&rec.entry),
            &live_exact,
            rec.start,
            branch_at,
            &inner,
            &mut |v| {
                sig.push(v);
                true
            },
        );
        let memo = Memo {
            start: rec.start,
            words: rec.words,
            live,
            live_past,
            live_exact,
            branch_pc,
            inner,
            sig,
            exit,
            step_writes: rec.steps.iter().map(|st| st.write).collect(),
            steps: rec.steps,
            log,
            hits: 0,
            partial_hits: Vec::new(),
            verified: u64::MAX,
            final_writes: Vec::new(),
            max_ready_rel: 0,
            writes_mask: 0,
            dma_horizon_rel: 0,
            probes: Vec::new(),
            generation: self.memo.generations,
            sets_hint: rec.hint_changed,
            entry_miss_stall,
            chain: [NO_CHAIN; 2],
            code: [0; 3],
            next: 0,
        };
        self.memo.generations += 1;
        let mut memo = memo;
        memo.dma_horizon_rel = memo
            .steps
            .iter()
            .map(|st| st.issue_rel.max(st.exit.fetch.2).max(0) as u64)
            .max()
            .unwrap_or(0)
            + 2;
        let entry_now = rec.entry.now;
        memo.probes = rec
            .probes
            .iter()
            .filter(|&&c| c >= entry_now)
            .map(|&c| (c - entry_now) as u32)
            .collect();
        memo.probes.sort_unstable();
        memo.probes.dedup();
        for w in memo.step_writes.iter().rev() {
            if w.reg < 128 && !memo.final_writes.iter().any(|f| f.reg == w.reg) {
                let ready_rel = w.ready_rel.max(0) as u64;
                memo.final_writes.push(FinalWrite {
                    ready_rel,
                    producer: w.producer,
                    reg: w.reg,
                    unit: w.unit,
                });
                memo.max_ready_rel = memo.max_ready_rel.max(ready_rel);
                memo.writes_mask |= 1u128 << w.reg;
            }
        }
        // Latest first: applying them stops at the first already past (see
        // `apply_deferred_writes`).
        memo.final_writes
            .sort_by_key(|w| std::cmp::Reverse(w.ready_rel));
        let idx = Self::slot_index(memo.start);
        let slot = self.memo.slots[idx];
        if slot == 0 || slot == NEVER {
            self.memo.memos.push(memo);
            self.memo.slots[idx] = self.memo.memos.len() as u32;
            return;
        }
        // A block at the same start with other words (the code changed) replaces the
        // records there; another entry state takes a place of its own, or replaces the
        // record replayed least.
        let first = (slot - 1) as usize;
        if self.memo.memos[first].words != memo.words {
            let mut at = self.memo.memos[first].next;
            while at != 0 {
                let id = (at - 1) as usize;
                self.memo.flush(id, &mut self.profile);
                at = self.memo.memos[id].next;
            }
            self.memo.flush(first, &mut self.profile);
            self.memo.memos[first] = memo;
            return;
        }
        let (mut last, mut ways, mut victim) = (first, 1, first);
        while self.memo.memos[last].next != 0 {
            last = (self.memo.memos[last].next - 1) as usize;
            ways += 1;
            if self.memo.memos[last].hits < self.memo.memos[victim].hits {
                victim = last;
            }
        }
        if ways < MEMO_WAYS {
            self.memo.memos.push(memo);
            self.memo.memos[last].next = self.memo.memos.len() as u32;
            return;
        }
        memo.next = self.memo.memos[victim].next;
        self.memo.flush(victim, &mut self.profile);
        self.memo.memos[victim] = memo;
    }

    /// Replays the next instruction of the block in progress, or brings the state up to
    /// date and returns `None` when `pc`/`inst` is not what the block recorded.
    #[inline]
    pub(super) fn replay_next(&mut self, pc: u32, inst: Inst) -> Option<u64> {
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

    /// Applies the register writes of the block in `deferred_writes`, latest first. A
    /// register ready at or before both the last issue and the cycle before now acts the
    /// same however long ago that was (no stall, dual issue allowed, a signature of -1,
    /// a chain's open register ready), and those only grow: once every register was
    /// ready that long ago at the block's entry, the writes that are past too are left
    /// out.
    #[inline]
    pub(super) fn apply_deferred_writes(&mut self) {
        if let Some((id, entry, entry_max_ready)) = self.deferred_writes.take() {
            let past = self.last.issue.min(self.now.saturating_sub(1));
            let all_past = entry_max_ready <= past;
            for w in &self.memo.memos[id].final_writes {
                let ready = entry + w.ready_rel;
                if all_past && ready <= past {
                    break;
                }
                let r = (w.reg & 127) as usize;
                self.ready[r] = ready;
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
            if let Some((d, _, _)) = self.deferred_writes {
                let covered =
                    self.memo.memos[d].writes_mask & !self.memo.memos[rp.memo].writes_mask;
                if covered != 0 {
                    self.apply_deferred_writes();
                }
            }
            self.deferred_writes = Some((rp.memo, rp.entry_now, rp.entry_max_ready));
            let m = &self.memo.memos[rp.memo];
            self.max_ready = self.max_ready.max(rp.entry_now + m.max_ready_rel);
        } else {
            self.apply_deferred_writes();
        }
        let m = &self.memo.memos[rp.memo];
        let base = rp.entry_now as i64;
        let at = |rel: i64| (base + rel).max(0) as u64;
        if k < m.steps.len() {
            for w in &m.step_writes[..k] {
                if w.reg < 128 {
                    self.ready[w.reg as usize] = at(w.ready_rel);
                    self.max_ready = self.max_ready.max(at(w.ready_rel));
                    self.producer[w.reg as usize] = w.producer;
                    self.producer_unit[w.reg as usize] = w.unit;
                }
            }
        }
        let st = if k == m.steps.len() {
            m.exit
        } else {
            m.steps[k - 1].exit
        };
        let sets_hint = m.sets_hint;
        self.last = st.last;
        self.last.issue = at(st.last_issue_rel);
        self.now = self.last.issue + 1;
        if let Some(d) = st.dp_rel {
            self.dp_until = at(d);
        }
        let mut dynamic = false;
        if let Some((mut h, issued, index, from_hbr)) = st.hint {
            h.issued = at(issued);
            h.index = rp.entry_index + index;
            if from_hbr {
                h.target = self.hint_target;
                dynamic = true;
            }
            // As the block's one hint filled it (with several entries, the newest moves
            // down unless it names the same branch; again after a partial replay's
            // materialize, nothing changes).
            self.set_hint(h);
        }
        // The final branch was predicted to the hint entry's target as it is now, when
        // that is not the record's own.
        if (!sets_hint || dynamic) && st.last.hinted().is_some() {
            self.last.branch_hint = Some(self.hint.target);
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
            let m = &mut self.memo.memos[rp.memo];
            if m.partial_hits.is_empty() {
                m.partial_hits = vec![0; m.steps.len()];
            }
            m.partial_hits[k - 1] += 1;
        }
    }

    /// Right after `issue` started replaying a memoized block with the block's first
    /// instruction: the block's length. The core may then execute the block's remaining
    /// instructions without calling `issue` and finish with [`Timing::block_replayed`]
    /// (or stop early with [`Timing::block_replayed_partly`]): the result is the same.
    #[inline]
    pub(crate) fn replay_started(&self) -> Option<usize> {
        let rp = self.memo.replay.as_ref()?;
        (rp.k == 1).then(|| self.memo.memos[rp.memo].words.len())
    }

    /// The words of the block being replayed (to check local store still holds them).
    #[inline]
    pub(crate) fn replay_words(&self) -> &[u32] {
        match &self.memo.replay {
            Some(rp) => &self.memo.memos[rp.memo].words,
            None => &[],
        }
    }

    /// The core's code epoch at which the replayed block's words were last checked.
    #[inline]
    pub(crate) fn replay_verified(&self) -> u64 {
        match &self.memo.replay {
            Some(rp) => self.memo.memos[rp.memo].verified,
            None => u64::MAX,
        }
    }

    /// Notes that local store held the replayed block's words at code epoch `epoch`.
    #[inline]
    pub(crate) fn set_replay_verified(&mut self, epoch: u64) {
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
    pub(super) fn sync(&mut self) {
        if let Some(rp) = self.memo.replay.take() {
            if rp.k > 0 {
                self.materialize(rp, true);
            }
        }
    }

    /// A `hint` hook call that repeats what a replayed hint instruction already recorded.
    pub(super) fn replay_hint_matches(&self, pc: u32, branch: u32, target: u32) -> bool {
        let Some(rp) = &self.memo.replay else {
            return false;
        };
        let m = &self.memo.memos[rp.memo];
        if rp.k == 0 || pc != m.start.wrapping_add(4 * (rp.k as u32 - 1)) {
            return false;
        }
        matches!(m.steps[rp.k - 1].exit.hint, Some((h, _, _, from_hbr)) if h.branch == branch & 0x3_ffff && (from_hbr || h.target == target & 0x3_ffff))
    }

    pub(super) fn replay_done_counts(&self) -> Option<(usize, usize)> {
        self.memo
            .replay
            .filter(|rp| rp.k > 0)
            .map(|rp| (rp.memo, rp.k))
    }
}

impl Timing {
    /// The target a replayed block's final branch (recorded as `last`) was predicted to:
    /// the hint entry's as it is now when the block does not set the entry itself.
    #[inline]
    fn entry_hinted(&self, id: usize, last: Last) -> Option<u32> {
        match last.hinted() {
            Some(_) if !self.memo.memos[id].sets_hint => Some(self.hint.target),
            h => h,
        }
    }

    /// Memoization statistics: (blocks recorded, replays, addresses given up on).
    pub fn memo_stats(&self) -> (usize, u64, usize) {
        let hits = self.memo.memos.iter().map(|m| m.hits).sum();
        let never = self.memo.slots.iter().filter(|&&s| s == NEVER).count();
        (self.memo.memos.len(), hits, never)
    }
}
