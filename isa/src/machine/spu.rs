//! The SPU around its core: state, loading, the pre-decoded local store and the run loops
//! (the general per-instruction path, block replays with the timing model on, and the
//! timing-off fast loop) that drive it quantum by quantum.

use std::collections::VecDeque;

use super::apply_quantum;
use super::channels::ChannelOutcome;
use super::compiled::CompiledBlocks;
use super::memory::MainMemory;
use super::mfc::{DmaCommand, LoggedWrite};
use crate::codec::{decode, decode_ext, extension_of, Inst};
use crate::ext::Extensions;
use crate::jit::Engine;
use crate::machine::exec::{
    execute, execute_in, Core, Effect, Reg, TruncatingFloats, LS_MASK, LS_SIZE,
};
use crate::table::Op;
use crate::timing::{Timing, TimingConfig};

/// Why an SPU stopped running.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// `stop`/`stopd` with the 14-bit stop code.
    Stop(u16),
    /// A halt instruction's condition held.
    Halt {
        /// Local-store address of the halt instruction.
        pc: u32,
    },
    /// A word that decodes to no instruction was executed.
    IllegalInstruction {
        /// Local-store address of the word.
        pc: u32,
        /// The instruction word itself.
        word: u32,
    },
    /// An MFC command the hardware would reject: the command, the local-store address,
    /// effective address, size and tag it was issued with (for a list, those of the
    /// offending element), and why.
    DmaError {
        /// Local-store address of the channel instruction that issued the command.
        pc: u32,
        /// The MFC command opcode.
        cmd: u8,
        /// The local-store byte address.
        lsa: u32,
        /// The main-memory effective address.
        ea: u64,
        /// The transfer size in bytes.
        size: u32,
        /// The tag group.
        tag: u32,
        /// Why the command is rejected.
        reason: String,
    },
    /// A channel instruction named a channel the SPU does not have, or read a write
    /// channel or wrote a read channel (the hardware's "invalid channel" stop, SPU_Status
    /// bit IC).
    InvalidChannel {
        /// Local-store address of the channel instruction.
        pc: u32,
        /// The channel number it named.
        channel: u8,
    },
    /// Blocked on a channel nothing will ever make ready.
    Deadlock {
        /// Local-store address of the channel instruction.
        pc: u32,
        /// The channel it waits on.
        channel: u8,
    },
    /// Waiting on a channel only the host can serve (a mailbox or signal): resumable.
    Blocked {
        /// The channel it waits on.
        channel: u8,
    },
    /// The run reached the cycle limit it was given.
    CycleLimit,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Stop(code) => write!(f, "stop {code:#x}"),
            StopReason::Halt { pc } => write!(f, "halt at {pc:#x}"),
            StopReason::IllegalInstruction { pc, word } => {
                write!(f, "illegal instruction {word:#010x} at {pc:#x}")?;
                match extension_of(*word) {
                    Some(e) => write!(
                        f,
                        " (an instruction of the {0} extension, which is off: --ext {0})",
                        e.name()
                    ),
                    None => Ok(()),
                }
            }
            StopReason::DmaError {
                pc,
                cmd,
                lsa,
                ea,
                size,
                tag,
                reason,
            } => write!(
                f,
                "DMA error at {pc:#x}: {reason} (command {cmd:#x}, LS {lsa:#x}, EA {ea:#x}, size {size}, tag {tag})"
            ),
            StopReason::InvalidChannel { pc, channel } => {
                write!(f, "invalid channel {channel} at {pc:#x}")
            }
            StopReason::Deadlock { pc, channel } => {
                write!(f, "deadlock at {pc:#x} on channel {channel}")
            }
            StopReason::Blocked { channel } => write!(f, "blocked on channel {channel}"),
            StopReason::CycleLimit => write!(f, "cycle limit reached"),
        }
    }
}

/// One SPU.
pub struct Spu {
    /// The SPU's number (0-based), which also places its signal-notification registers in the raw-SPU map.
    pub index: u32,
    pub(super) core: Core,
    pub(super) decoded: Box<[Inst; LS_SIZE / 4]>,
    /// Bumped whenever a store or DMA makes a decoded instruction stale.
    pub(super) code_epoch: u64,
    /// Per local-store quadword: nonzero where it may hold decoded (not stale) words, so
    /// a store there must mark them stale; compiled code reads it after each store.
    pub(super) code_quads: Box<[u8]>,
    pub(super) engine: Engine,
    /// Compiled blocks (made on first use with [`Engine::Jit`]).
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(super) compiled: Option<Box<CompiledBlocks>>,
    /// Instructions executed by compiled code.
    pub(super) compiled_instructions: u64,
    /// Passes of self-looping blocks run with the timing model on after a steady first
    /// pass (their timing record applied once for them all).
    pub(super) steady_passes: u64,
    /// The last block ran only in part (timing off, compiled engine).
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(super) block_cut: bool,
    pub(super) pc: u32,
    pub(super) instructions: u64,
    pub(super) cycle: u64,
    pub(super) timing: Option<Timing>,
    // channels
    pub(super) in_mbox: VecDeque<u32>,
    pub(super) out_mbox: Option<u32>,
    pub(super) out_intr_mbox: Option<u32>,
    pub(super) signal: [Option<u32>; 2],
    /// OR mode for each signal register (otherwise overwrite).
    pub signal_or_mode: [bool; 2],
    /// The host promises to feed the inbound mailbox/signals: a read on them blocks
    /// instead of deadlocking.
    pub host_feeds: bool,
    /// The cycle [`Spu::run`] stops at exactly (`u64::MAX` outside it): nothing issues at
    /// or after it and no stall runs past it.
    pub(super) limit: u64,
    pub(super) dec_value: u32,
    pub(super) dec_written_at: u64,
    /// When the decrementer goes from 0 to -1 (raising its event), if it will.
    pub(super) dec_event_at: Option<u64>,
    /// Cycles per decrementer tick (the timebase); 1 unless the host sets it.
    pub decrementer_cycles_per_tick: u64,
    pub(super) event_mask: u32,
    pub(super) event_status: u32,
    // MFC
    pub(super) tag_mask: u32,
    pub(super) tag_update: Option<u32>,
    pub(super) queue: Vec<DmaCommand>,
    pub(super) dma_free_at: u64,
    /// The memory interface is busy with earlier quanta's traffic until then (set at each
    /// boundary), and its EIB port in each direction (reads, writes); this quantum's
    /// commands, for the boundary to add.
    pub(super) bus_free_at: u64,
    pub(super) port_free_at: [u64; 2],
    pub(super) bus_log: Vec<super::memory::BusRequest>,
    /// Bytes moved per host-named main-memory region.
    pub(super) traffic: super::mfc::Traffic,
    pub(super) list_stall: u32,
    pub(super) stalled_list: Option<(u8, u8, u32, u32, u32, u32)>,
    pub(super) atomic_stat: Option<(u32, u64)>,
    pub(super) atomic_pending: bool,
    pub(super) reservation: Option<u32>,
    /// This quantum's main-memory writes, in the order logged (which breaks ties of cycle).
    pub(super) writes: Vec<LoggedWrite>,
    pub(super) timing_config: TimingConfig,
    /// The ISA extensions this SPU decodes and times ([`Spu::set_extensions`]).
    pub(super) extensions: Extensions,
    /// The command being issued, for a DmaError: (cmd, lsa, ea, size, tag).
    pub(super) dma_ctx: (u8, u32, u64, u32, u32),
    /// The event log, when on (see `events.rs`).
    pub(super) events: Option<Vec<super::events::SpuEvent>>,
}

/// The marker of a stale pre-decoded word: `Unknown` carrying a word that is not unknown
/// (`il $0,0`), so no real decoding result equals it.
/// How close to [`Spu::run`]'s limit the timing model is copied before each issue: past
/// the longest one instruction waits to issue (a branch miss, a fetch, a dependency).
pub(super) const LIMIT_REACH: u64 = 1024;

pub(super) const STALE: Inst = Inst {
    op: Op::Unknown,
    rt: 0,
    ra: 0,
    rb: 0,
    rc: 0,
    imm: 0,
    word: 0x4080_0000,
};

/// Whether this CPU runs code built for x86-64-v3 (the fast loops have such a build).
#[cfg(target_arch = "x86_64")]
#[inline]
fn host_has_x86_64_v3() -> bool {
    use std::sync::OnceLock;
    static HAS: OnceLock<bool> = OnceLock::new();
    *HAS.get_or_init(|| {
        std::is_x86_feature_detected!("avx2")
            && std::is_x86_feature_detected!("fma")
            && std::is_x86_feature_detected!("bmi1")
            && std::is_x86_feature_detected!("bmi2")
            && std::is_x86_feature_detected!("lzcnt")
            && std::is_x86_feature_detected!("popcnt")
            && std::is_x86_feature_detected!("sse4.2")
            && std::is_x86_feature_detected!("ssse3")
    })
}

/// Marks the four decoded words of the quadword a store wrote at `addr` stale (they are
/// decoded again when fetched); whether any held decoded code.
#[inline(always)]
pub(super) fn invalidate_quad(
    decoded: &mut [Inst; LS_SIZE / 4],
    code_quads: &mut [u8],
    addr: u32,
) -> bool {
    let s = (addr & LS_MASK & !15) as usize / 4;
    code_quads[s / 4] = 0;
    let quad = &mut decoded[s..s + 4];
    let touched = quad
        .iter()
        .any(|d| d.op != Op::Unknown || d.word != STALE.word);
    quad.fill(STALE);
    touched
}

impl Spu {
    /// SPU number `index`, reset: registers and local store zero, program counter 0, no timing model.
    pub fn new(index: u32) -> Spu {
        Spu {
            index,
            core: Core::new(),
            code_epoch: 0,
            code_quads: vec![1; LS_SIZE / 16].into_boxed_slice(),
            engine: Engine::default(),
            compiled: None,
            compiled_instructions: 0,
            steady_passes: 0,
            block_cut: false,
            decoded: vec![decode(0); LS_SIZE / 4]
                .into_boxed_slice()
                .try_into()
                .unwrap(),
            pc: 0,
            instructions: 0,
            cycle: 0,
            timing: None,
            in_mbox: VecDeque::new(),
            out_mbox: None,
            out_intr_mbox: None,
            signal: [None, None],
            signal_or_mode: [false, false],
            host_feeds: false,
            limit: u64::MAX,
            dec_value: 0,
            dec_written_at: 0,
            dec_event_at: None,
            decrementer_cycles_per_tick: 1,
            event_mask: 0,
            event_status: 0,
            tag_mask: 0,
            tag_update: None,
            queue: Vec::new(),
            dma_free_at: 0,
            bus_free_at: 0,
            port_free_at: [0; 2],
            bus_log: Vec::new(),
            traffic: Default::default(),
            list_stall: 0,
            stalled_list: None,
            atomic_stat: None,
            atomic_pending: false,
            reservation: None,
            writes: Vec::new(),
            timing_config: TimingConfig::default(),
            extensions: Extensions::NONE,
            dma_ctx: (0, 0, 0, 0, 0),
            events: None,
        }
    }

    /// Loads a flat image at local-store address 0.
    pub fn load_image(&mut self, image: &[u8]) {
        self.load_segments(&[(0, image)], 0);
    }

    /// Loads `(address, bytes)` segments and sets the entry point.
    pub fn load_segments(&mut self, segments: &[(u32, &[u8])], entry: u32) {
        for (addr, bytes) in segments {
            for (i, b) in bytes.iter().enumerate() {
                self.core.ls[(*addr as usize + i) & LS_MASK as usize] = *b;
            }
        }
        self.redecode(0, LS_SIZE as u32);
        self.pc = entry & LS_MASK & !3;
    }

    /// Marks the pre-decoded words covering `[addr, addr + len)` stale; they are decoded
    /// again when fetched (stores and DMA into local store cost no decoding unless the
    /// bytes are executed).
    pub(super) fn redecode(&mut self, addr: u32, len: u32) {
        let start = (addr & LS_MASK) as usize / 4;
        let words = (len as usize).div_ceil(4) + 1;
        let mut touched = false;
        for k in 0..words.min(LS_SIZE / 4) {
            let d = &mut self.decoded[(start + k) % (LS_SIZE / 4)];
            touched |= d.op != Op::Unknown || d.word != STALE.word;
            *d = STALE;
        }
        // Decoded code changed: memoized blocks must check their words again.
        self.code_epoch += touched as u64;
    }

    /// The decoded instruction at `pc`, decoding it first if a write made it stale.
    #[inline(always)]
    pub(super) fn fetch(&mut self, pc: u32) -> Inst {
        let w = (pc >> 2) as usize & (LS_SIZE / 4 - 1);
        let inst = self.decoded[w];
        if inst.op != Op::Unknown || inst.word != STALE.word {
            return inst;
        }
        let b = &self.core.ls[4 * w..4 * w + 4];
        let fresh = decode_ext(
            u32::from_be_bytes([b[0], b[1], b[2], b[3]]),
            self.extensions,
        );
        self.decoded[w] = fresh;
        self.code_quads[w / 4] = 1;
        fresh
    }

    /// The program counter: the local-store address of the next instruction.
    pub fn pc(&self) -> u32 {
        self.pc
    }

    /// Sets the program counter (wrapped into the local store and aligned to a word).
    pub fn set_pc(&mut self, pc: u32) {
        self.pc = pc & LS_MASK & !3;
    }

    /// Register `n` (taken modulo 128).
    pub fn reg(&self, n: usize) -> Reg {
        self.core.regs[n & 127]
    }

    /// Sets register `n` (taken modulo 128) to `value`.
    pub fn set_reg(&mut self, n: usize, value: Reg) {
        self.core.regs[n & 127] = value;
    }

    /// The whole 256 KiB local store, indexed by local-store byte address.
    pub fn ls(&self) -> &[u8] {
        &self.core.ls[..]
    }

    /// Counts the MFC's bytes per main-memory region from now on (see
    /// [`super::mfc::Traffic`]).
    pub fn count_traffic(&mut self, regions: Vec<(u64, u64)>) {
        self.traffic = super::mfc::Traffic::new(regions);
    }

    /// The bytes counted per region so far.
    pub fn traffic(&self) -> &super::mfc::Traffic {
        &self.traffic
    }

    /// Writes local store from the host (re-decoding what it covers).
    pub fn write_ls(&mut self, addr: u32, bytes: &[u8]) {
        for (i, b) in bytes.iter().enumerate() {
            self.core.ls[(addr as usize + i) & LS_MASK as usize] = *b;
        }
        self.redecode(addr, bytes.len() as u32);
    }

    /// Instructions executed so far.
    pub fn instructions(&self) -> u64 {
        self.instructions
    }

    /// The SPU's clock in cycles: the timing model's cycle when it is on, one per instruction otherwise.
    pub fn cycles(&self) -> u64 {
        self.cycle
    }

    /// The floating-point status and control register.
    pub fn fpscr(&self) -> &crate::float::Fpscr {
        &self.core.fpscr
    }

    /// The timing model, if [`Spu::enable_timing`] turned it on.
    pub fn timing(&self) -> Option<&Timing> {
        self.timing.as_ref()
    }

    /// The timing model, writable, if it is on.
    pub fn timing_mut(&mut self) -> Option<&mut Timing> {
        self.timing.as_mut()
    }

    /// Turns the cycle-level timing model on (with the branch target buffer of the SPU's
    /// extensions, whatever `config.hint_entries` says).
    pub fn enable_timing(&mut self, mut config: TimingConfig) {
        config.hint_entries = self.extensions.hint_entries;
        self.timing_config = config.clone();
        self.timing = Some(Timing::new(config));
    }

    /// Switches the ISA extensions (`docs/extensions.md`); call it before running. A word of
    /// an extension that is off stays an illegal instruction, whose stop names the extension.
    /// With the timing model on, it starts again (at cycle 0) with the new hint entries.
    pub fn set_extensions(&mut self, extensions: Extensions) {
        self.extensions = extensions;
        self.redecode(0, LS_SIZE as u32);
        if let Some(t) = &self.timing {
            let config = t.config.clone();
            self.enable_timing(config);
        }
    }

    /// The ISA extensions this SPU runs with.
    pub fn extensions(&self) -> Extensions {
        self.extensions
    }

    /// Runs until `max_cycles` or a stop; main memory writes apply immediately after.
    ///
    /// The stop at `max_cycles` is exact, with the timing model on or off and under either
    /// engine: no instruction issues at or after it (one that would is left unexecuted, the
    /// timing model as before it), a channel stall ends at it, and [`Spu::cycles`] is then
    /// `max_cycles`, never more. Running again goes on from there.
    pub fn run(&mut self, memory: &mut MainMemory, max_cycles: u64) -> StopReason {
        self.limit = max_cycles;
        let stop = self.run_to_limit(memory, max_cycles);
        self.limit = u64::MAX;
        stop
    }

    /// Makes [`Spu::run_quantum`] stop exactly at `limit`, as [`Spu::run`] does at its
    /// `max_cycles`: for hosts that run quanta themselves (a gang of SPUs) and have a cycle
    /// limit. `u64::MAX` (the default) sets none.
    pub fn set_cycle_limit(&mut self, limit: u64) {
        self.limit = limit;
    }

    /// A channel wait (of the instruction at the pc, issued at `issue`) that reaches the
    /// limit: the clock stops there, and running again starts the instruction over, the
    /// model as before it where it was kept (within `LIMIT_REACH`), else stalled to the
    /// cycle before the limit (the instruction then retries, as after a quantum's boundary).
    fn stop_waiting_at_limit(&mut self, before: Option<Box<Timing>>, issue: u64, channel: u8) {
        let last = self.limit.saturating_sub(1);
        if self.events.is_some() {
            self.log_channel_wait(issue, last, channel);
        }
        match before {
            Some(model) => self.timing = Some(*model),
            None => {
                if let Some(t) = &mut self.timing {
                    t.channel_stall(self.pc, channel, last);
                }
            }
        }
        self.cycle = self.limit;
    }

    fn run_to_limit(&mut self, memory: &mut MainMemory, max_cycles: u64) -> StopReason {
        const QUANTUM: u64 = 4096;
        loop {
            let until = self.cycle.saturating_add(QUANTUM).min(max_cycles);
            let outcome = self.run_quantum(memory, until);
            apply_quantum(std::slice::from_mut(self), memory);
            match outcome {
                Some(StopReason::Blocked { channel }) if !self.host_feeds => {
                    return StopReason::Deadlock {
                        pc: self.pc,
                        channel,
                    }
                }
                Some(reason) => return reason,
                None if self.cycle >= max_cycles => return StopReason::CycleLimit,
                None => {}
            }
        }
    }

    /// Runs until the SPU's clock reaches `until` (returns `None`) or it stops. Main memory
    /// is only read; writes wait for [`apply_quantum`].
    pub fn run_quantum(&mut self, memory: &MainMemory, until: u64) -> Option<StopReason> {
        // Within reach of [`Spu::run`]'s limit, with the timing model on, each instruction
        // is timed on a copy of the model kept until it is known to issue before the limit
        // (memoized blocks that could reach it are not replayed: [`Spu::replay_fits`]).
        let near_limit =
            |spu: &Spu| spu.timing.is_some() && spu.cycle.saturating_add(LIMIT_REACH) >= spu.limit;
        while self.cycle < until {
            if self.timing.is_none() {
                if self.engine == Engine::Jit {
                    self.run_compiled(until);
                } else {
                    self.run_fast(until);
                }
            } else {
                self.run_block_replays(until);
            }
            if self.cycle >= until {
                break;
            }
            // One instruction the fast loop leaves to this general path (channels, stops,
            // halts, illegal words, `bisled`, anything while interrupts are enabled), or
            // any instruction with the timing model on.
            if self.core.interrupts_enabled {
                self.update_events(self.cycle);
                if self.event_status & self.event_mask != 0 {
                    // The SPU interrupt: SRR0 gets the next instruction's address,
                    // interrupts are disabled and execution continues at 0.
                    self.core.srr0 = self.pc;
                    self.core.interrupts_enabled = false;
                    self.pc = 0;
                }
            }
            let pc = self.pc;
            let inst = self.fetch(pc);
            if inst.op == Op::Bisled {
                self.update_events(self.cycle);
                self.core.event_pending = self.event_status & self.event_mask != 0;
                self.core.event_pending_known = true;
            }
            // Boxed: the model is large, and this is on every instruction's path.
            let before: Option<Box<Timing>> = if near_limit(self) {
                self.timing.as_ref().map(|t| Box::new(t.clone()))
            } else {
                None
            };
            let issue = match &mut self.timing {
                Some(t) => t.issue(pc, inst),
                None => self.cycle,
            };
            if issue >= self.limit {
                // It would issue at or after the limit: it does not run, and the clock
                // stops at the limit.
                if let Some(model) = before {
                    self.timing = Some(*model);
                }
                self.cycle = self.limit;
                return None;
            }
            if !self.core.interrupts_enabled {
                if let Some(n) = self.timing.as_ref().and_then(|t| t.replay_started()) {
                    if self.replay_block(pc, n, until) {
                        continue;
                    }
                }
            }
            let effect = execute(&mut self.core, inst, pc);
            self.core.event_pending_known = false;
            match effect {
                Effect::Next => self.pc = (pc + 4) & LS_MASK,
                Effect::Branch { taken, target } => {
                    if let Some(t) = &mut self.timing {
                        t.branch_resolved(pc, inst, taken, target);
                    }
                    self.pc = if taken { target } else { (pc + 4) & LS_MASK };
                }
                Effect::Store { addr } => {
                    self.redecode(addr, 16);
                    self.pc = (pc + 4) & LS_MASK;
                }
                Effect::Hint { branch, target } => {
                    if let Some(t) = &mut self.timing {
                        t.hint(pc, branch, target);
                    }
                    self.pc = (pc + 4) & LS_MASK;
                }
                Effect::Stop(code) => {
                    self.finish(issue);
                    self.pc = (pc + 4) & LS_MASK;
                    return Some(StopReason::Stop(code));
                }
                Effect::Halt => {
                    self.finish(issue);
                    return Some(StopReason::Halt { pc });
                }
                Effect::Illegal => {
                    self.finish(issue);
                    return Some(StopReason::IllegalInstruction {
                        pc,
                        word: inst.word,
                    });
                }
                Effect::Channel => match self.channel(inst, issue, memory) {
                    ChannelOutcome::Done => self.pc = (pc + 4) & LS_MASK,
                    ChannelOutcome::WaitUntil(when) if when >= self.limit => {
                        self.stop_waiting_at_limit(before, issue, inst.ra);
                        return None;
                    }
                    // A wait for the quantum's end where the quantum ends at the limit (a
                    // gang's last quantum): the same.
                    ChannelOutcome::WaitBoundary if until >= self.limit => {
                        self.stop_waiting_at_limit(before, issue, inst.ra);
                        return None;
                    }
                    ChannelOutcome::WaitUntil(when) => {
                        if self.events.is_some() {
                            self.log_channel_wait(issue, when, inst.ra);
                        }
                        // Stall on the channel, then retry the instruction.
                        match &mut self.timing {
                            Some(t) => t.channel_stall(pc, inst.ra, when),
                            None => self.cycle = when,
                        }
                        if let Some(t) = &self.timing {
                            self.cycle = t.now();
                        }
                        continue;
                    }
                    ChannelOutcome::WaitBoundary => {
                        if self.events.is_some() {
                            self.log_channel_wait(issue, until, inst.ra);
                        }
                        match &mut self.timing {
                            Some(t) => {
                                t.channel_stall(pc, inst.ra, until);
                                self.cycle = until.max(t.now());
                            }
                            None => self.cycle = until,
                        }
                        return None;
                    }
                    ChannelOutcome::Host => {
                        self.cycle = self.cycle.max(until);
                        return Some(StopReason::Blocked { channel: inst.ra });
                    }
                    ChannelOutcome::Never => {
                        self.finish(issue);
                        return Some(StopReason::Deadlock {
                            pc,
                            channel: inst.ra,
                        });
                    }
                    ChannelOutcome::Invalid => {
                        self.finish(issue);
                        return Some(StopReason::InvalidChannel {
                            pc,
                            channel: inst.ra,
                        });
                    }
                    ChannelOutcome::Error(reason) => {
                        self.finish(issue);
                        let (cmd, lsa, ea, size, tag) = self.dma_ctx;
                        return Some(StopReason::DmaError {
                            pc,
                            cmd,
                            lsa,
                            ea,
                            size,
                            tag,
                            reason,
                        });
                    }
                },
            }
            self.instructions += 1;
            self.cycle = match &self.timing {
                Some(t) => t.now(),
                None => self.cycle + 1,
            };
        }
        None
    }

    /// Whether local store still holds `words` at `pc`, decoded, with none that needs the
    /// core's event state (`bisled`) or ends a block; `verified`: the code epoch at which
    /// that was last found true.
    pub(super) fn block_in_store(&self, pc: u32, words: &[u32], verified: u64) -> bool {
        if verified == self.code_epoch {
            return true;
        }
        let first = (pc >> 2) as usize;
        words.iter().enumerate().all(|(k, &word)| {
            let d = self.decoded[(first + k) & (LS_SIZE / 4 - 1)];
            d.op != Op::Unknown
                && d.op != Op::Bisled
                && d.word == word
                && !crate::timing::ends_block(d)
        })
    }

    /// Timing on: runs memoized blocks back to back, each in one go, while the block at
    /// the program counter is memoized, its entry state matches its record and local
    /// store holds it. Returns at the first that is not (the general path takes it).
    #[inline(never)]
    pub(super) fn run_block_replays(&mut self, until: u64) {
        #[cfg(target_arch = "x86_64")]
        if host_has_x86_64_v3() {
            // SAFETY: the CPU has every feature the function is compiled for.
            return unsafe { self.run_block_replays_v3(until) };
        }
        self.run_block_replays_body(until)
    }

    /// [`Spu::run_block_replays`] compiled for x86-64-v3 (AVX2, FMA, BMI, LZCNT), so
    /// that byte swaps, shuffles and bit counts inline as single instructions.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,sse4.2,ssse3")]
    pub(super) unsafe fn run_block_replays_v3(&mut self, until: u64) {
        self.run_block_replays_body(until)
    }

    #[inline(always)]
    pub(super) fn run_block_replays_body(&mut self, until: u64) {
        let truncating = TruncatingFloats::hold();
        self.block_replays_loop(until);
        truncating.release();
    }

    #[inline(always)]
    pub(super) fn block_replays_loop(&mut self, until: u64) {
        while self.cycle < until && !self.core.interrupts_enabled {
            let pc = self.pc;
            let epoch = self.code_epoch;
            if let Some((id, n)) = self
                .timing
                .as_mut()
                .and_then(|t| t.chained_replay_candidate(pc, epoch))
            {
                if !self.replay_fits(id) {
                    return;
                }
                self.run_replayed_block(pc, n, id, until);
                continue;
            }
            let inst = self.decoded[((pc >> 2) as usize) & (LS_SIZE / 4 - 1)];
            if inst.op == Op::Unknown || inst.op == Op::Bisled {
                return;
            }
            let Some(t) = self.timing.as_mut() else {
                return;
            };
            let Some((id, n)) = t.block_replay_candidate(pc, inst) else {
                return;
            };
            let t = self.timing.as_ref().expect("timing");
            let (words, verified) = t.memo_words(id);
            if verified != self.code_epoch {
                if words.len() != n || !self.block_in_store(pc, words, verified) {
                    return;
                }
                let epoch = self.code_epoch;
                let t = self.timing.as_mut().expect("timing");
                t.set_memo_verified(id, epoch);
            }
            if !self.replay_fits(id) {
                return;
            }
            self.run_replayed_block(pc, n, id, until);
        }
    }

    /// Whether memo `id`, replayed whole from about now, issues nothing at or after
    /// [`Spu::run`]'s limit (its entry may wait up to [`LIMIT_REACH`] cycles more).
    #[inline(always)]
    fn replay_fits(&self, id: usize) -> bool {
        self.limit == u64::MAX
            || self.timing.as_ref().is_some_and(|t| {
                self.cycle
                    .saturating_add(t.memo_span(id))
                    .saturating_add(LIMIT_REACH)
                    < self.limit
            })
    }

    /// Executes a memoized block whose replay `issue` has just started at `pc` (its first
    /// instruction issued, none executed): all `n` instructions in one go, leaving the
    /// timing model as the per-instruction path would. Declines (returns false, nothing
    /// done) unless local store still holds the recorded words, decoded, and none of them
    /// needs the core's event state (`bisled`).
    pub(super) fn replay_block(&mut self, pc: u32, n: usize, until: u64) -> bool {
        let Some(t) = self.timing.as_ref() else {
            return false;
        };
        let words = t.replay_words();
        if words.len() != n || !self.block_in_store(pc, words, t.replay_verified()) {
            return false;
        }
        let Some(id) = t.replay_memo() else {
            return false;
        };
        if !self.replay_fits(id) {
            return false;
        }
        let epoch = self.code_epoch;
        if let Some(t) = self.timing.as_mut() {
            t.set_replay_verified(epoch);
        }
        let truncating = TruncatingFloats::hold();
        self.run_replayed_block(pc, n, id, until);
        truncating.release();
        true
    }

    /// The execution part of [`Spu::replay_block`]; the caller holds a
    /// [`TruncatingFloats`].
    #[inline(always)]
    pub(super) fn run_replayed_block(&mut self, pc: u32, n: usize, id: usize, until: u64) {
        let block_end = pc.wrapping_add(4 * n as u32);
        if self.engine == Engine::Jit && self.replay_compiled(pc, n, id, until) {
            return;
        }
        let core = &mut self.core;
        let decoded = &mut *self.decoded;
        let code_quads = &mut *self.code_quads;
        let timing = self.timing.as_mut().expect("timing");
        // Blocks hold no `bisled`, the one reader of the pending-event flag.
        core.event_pending_known = false;
        let mut p = pc;
        let mut done = n;
        for k in 0..n {
            let inst = decoded[((p >> 2) as usize) & (LS_SIZE / 4 - 1)];
            match execute_in::<true>(core, inst, p) {
                // An inner branch not taken: the record goes on past it.
                Effect::Branch { taken: false, .. } if k + 1 < n => p = (p + 4) & LS_MASK,
                Effect::Branch { taken, target } if k + 1 < n => {
                    debug_assert!(taken);
                    timing.block_left_at_branch(id, k + 1, p, target);
                    p = target;
                    done = k + 1;
                    break;
                }
                Effect::Branch { taken, target } => {
                    timing.block_replayed(id, Some((p, taken, target)));
                    p = if taken { target } else { (p + 4) & LS_MASK };
                    done = k + 1;
                    break;
                }
                Effect::Store { addr } => {
                    self.code_epoch += invalidate_quad(decoded, code_quads, addr) as u64;
                    p = (p + 4) & LS_MASK;
                    // A store into the rest of the block: the rest goes the long way.
                    let line = addr & LS_MASK & !15;
                    if k + 1 < n && line < block_end && line + 16 > p {
                        timing.block_replayed_partly(id, k + 1);
                        done = k + 1;
                        break;
                    }
                }
                // The replayed steps hold what the hook would record, but for an
                // `hbr`'s target.
                Effect::Hint { target, .. } => {
                    timing.note_hint_target(target);
                    p = (p + 4) & LS_MASK;
                }
                _ => p = (p + 4) & LS_MASK,
            }
            if k + 1 == n {
                timing.block_replayed(id, None);
            }
        }
        self.pc = p;
        self.instructions += done as u64;
        self.cycle = timing.now();
    }

    /// The timing-off inner loop: one cycle per instruction, pre-decoded words, no
    /// per-instruction bookkeeping beyond the program counter. It runs until `until` or
    /// the first instruction that needs the SPU around the core (a channel, stop, halt or
    /// illegal word), which it leaves unexecuted for the general path; those have no
    /// effect on the core before that point.
    #[inline(never)]
    pub(super) fn run_fast(&mut self, until: u64) {
        #[cfg(target_arch = "x86_64")]
        if host_has_x86_64_v3() {
            // SAFETY: the CPU has every feature the function is compiled for.
            return unsafe { self.run_fast_v3(until) };
        }
        self.run_fast_body(until)
    }

    /// [`Spu::run_fast`] compiled for x86-64-v3 (see [`Spu::run_block_replays_v3`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,sse4.2,ssse3")]
    pub(super) unsafe fn run_fast_v3(&mut self, until: u64) {
        self.run_fast_body(until)
    }

    #[inline(always)]
    pub(super) fn run_fast_body(&mut self, until: u64) {
        if self.core.interrupts_enabled {
            return;
        }
        let truncating = TruncatingFloats::hold();
        let budget = until.saturating_sub(self.cycle);
        let mut pc = self.pc;
        let mut done = 0u64;
        let core = &mut self.core;
        let decoded = &mut *self.decoded;
        let code_quads = &mut *self.code_quads;
        let extensions = self.extensions;
        while done < budget {
            let w = (pc >> 2) as usize & (LS_SIZE / 4 - 1);
            let inst = decoded[w];
            if inst.op == Op::Unknown {
                if inst.word != STALE.word {
                    break;
                }
                // Decode the stale word and take it again from the array (one path
                // into the dispatch keeps the instruction in registers).
                let b = &core.ls[4 * w..4 * w + 4];
                let fresh = decode_ext(u32::from_be_bytes([b[0], b[1], b[2], b[3]]), extensions);
                decoded[w] = fresh;
                code_quads[w / 4] = 1;
                if fresh.op == Op::Unknown {
                    break;
                }
                continue;
            }
            match execute_in::<true>(core, inst, pc) {
                Effect::Next | Effect::Hint { .. } => pc = (pc + 4) & LS_MASK,
                Effect::Branch { taken, target } => {
                    pc = if taken { target } else { (pc + 4) & LS_MASK };
                    if core.interrupts_enabled {
                        done += 1;
                        break;
                    }
                }
                Effect::Store { addr } => {
                    self.code_epoch += invalidate_quad(decoded, code_quads, addr) as u64;
                    pc = (pc + 4) & LS_MASK;
                }
                _ => break,
            }
            done += 1;
        }
        truncating.release();
        self.pc = pc;
        self.instructions += done;
        self.cycle += done;
    }

    pub(super) fn finish(&mut self, issue: u64) {
        self.instructions += 1;
        self.cycle = issue + 1;
    }
}
