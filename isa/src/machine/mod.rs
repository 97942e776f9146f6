//! One simulated SPU: the core, its pre-decoded local store, channels and MFC, driven in
//! quanta of simulated cycles against a main memory shared by all SPUs.
//!
//! # Determinism across host threads
//! During a quantum an SPU only *reads* main memory (gets and `getllar` read the state left
//! by the previous boundary) and logs its writes (`put`, `putllc`, `putlluc`) with the cycle
//! they complete. At the boundary [`apply_quantum`] applies every SPU's log in (cycle, SPU
//! index, sequence) order. A `putllc` succeeds only if no write to its 128-byte line by
//! another SPU was ordered before it since its `getllar` (including writes made in the same
//! quantum, which its `getllar` could not see); its status becomes readable after the
//! boundary, so an SPU waiting on `MFC_RdAtomicStat` for it waits until then. The outcome
//! depends only on simulated time, never on which host thread ran which SPU.
//!
//! # Channels, events and interrupts
//! Reading an empty channel or writing a full one waits: until the next DMA completion or
//! decrementer event when one will make it ready, until the next quantum boundary for a
//! `putllc` outcome, otherwise the SPU stops with [`StopReason::Blocked`] (the host can
//! fill a mailbox or signal and run it again; [`Spu::run`] turns that into
//! [`StopReason::Deadlock`] unless [`Spu::host_feeds`] is set). Event bits are those of
//! the SDK's `spu_mfcio.h` ([`event`]); the decrementer counts down one tick every
//! [`Spu::decrementer_cycles_per_tick`] cycles and raises its event when it goes from 0
//! to -1. With interrupts enabled (the E forms of the indirect branches) an enabled
//! pending event interrupts before the next instruction: SRR0 gets its address,
//! interrupts are disabled and execution continues at 0; `iret` returns to SRR0.
//! `sndsig`/`sndsigb`/`sndsigf` write another SPU's signal-notification register (found at
//! [`signal_notify_ea`], the PlayStation 3's raw-SPU map), delivered at the boundary like a
//! put; `barrier`/`eieio`/`sync` are accepted and do nothing (commands complete in order
//! here, so fences and barriers are already honoured).
//!
//! # DMA timing
//! One DMA engine per SPU moves one command at a time: a command completes at
//! `max(issue + latency, previous completion) + bytes / bytes-per-cycle`, and no earlier
//! than the chip's memory interface, shared by all SPUs, can serve it behind the traffic of
//! earlier quanta (see `settle_memory_bus`). With the timing
//! model off the clock is the instruction count, so completion times stay deterministic.

pub mod exec;

use std::collections::VecDeque;

use crate::codec::{decode, Inst};
use crate::machine::exec::{
    execute, execute_in, Core, Effect, Reg, TruncatingFloats, LS_MASK, LS_SIZE,
};
use crate::table::Op;
use crate::timing::{StallCause, Timing, TimingConfig};

/// Main memory shared by all SPUs, big-endian bytes owned by the host, and the chip's
/// memory interface in front of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MainMemory {
    bytes: Vec<u8>,
    /// The cycle (fractional) at which the memory interface has moved every byte the SPUs'
    /// DMA commands asked for up to the last quantum boundary (see [`apply_quantum`]).
    bus_busy_until: f64,
}

impl MainMemory {
    pub fn new(bytes: Vec<u8>) -> Self {
        MainMemory {
            bytes,
            bus_busy_until: 0.0,
        }
    }
    pub fn zeroed(len: usize) -> Self {
        MainMemory::new(vec![0; len])
    }

    /// The cycle at which the memory interface has drained the traffic published so far.
    pub fn bus_busy_until(&self) -> u64 {
        self.bus_busy_until.ceil() as u64
    }
    pub fn len(&self) -> usize {
        self.bytes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }
    pub fn read_u32(&self, addr: u32) -> u32 {
        let a = addr as usize;
        self.bytes
            .get(a..a + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(0)
    }
    pub fn write_u32(&mut self, addr: u32, value: u32) {
        let a = addr as usize;
        if let Some(b) = self.bytes.get_mut(a..a + 4) {
            b.copy_from_slice(&value.to_be_bytes());
        }
    }
    pub fn read_f32(&self, addr: u32) -> f32 {
        f32::from_bits(self.read_u32(addr))
    }
    pub fn write_f32(&mut self, addr: u32, value: f32) {
        self.write_u32(addr, value.to_bits())
    }
    /// `len` bytes from `addr`, or `None` if they are not all inside main memory.
    pub fn read_bytes(&self, addr: u64, len: usize) -> Option<&[u8]> {
        let end = addr.checked_add(len as u64)?;
        self.bytes.get(addr as usize..usize::try_from(end).ok()?)
    }
    /// Writes `data` at `addr`; false (and nothing written) if it does not fit.
    pub fn write_bytes(&mut self, addr: u64, data: &[u8]) -> bool {
        let Some(end) = addr.checked_add(data.len() as u64) else {
            return false;
        };
        match usize::try_from(end)
            .ok()
            .and_then(|end| self.bytes.get_mut(addr as usize..end))
        {
            Some(dst) => {
                dst.copy_from_slice(data);
                true
            }
            None => false,
        }
    }
    fn range(&self, ea: u64, size: u32) -> Option<std::ops::Range<usize>> {
        let end = ea.checked_add(size as u64)?;
        (end <= self.bytes.len() as u64).then_some(ea as usize..end as usize)
    }
}

/// Why an SPU stopped running.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// `stop`/`stopd` with the 14-bit stop code.
    Stop(u16),
    /// A halt instruction's condition held.
    Halt {
        pc: u32,
    },
    IllegalInstruction {
        pc: u32,
        word: u32,
    },
    /// An MFC command the hardware would reject: the command, the local-store address,
    /// effective address, size and tag it was issued with (for a list, those of the
    /// offending element), and why.
    DmaError {
        pc: u32,
        cmd: u8,
        lsa: u32,
        ea: u64,
        size: u32,
        tag: u32,
        reason: String,
    },
    /// A channel instruction named a channel the SPU does not have, or read a write
    /// channel or wrote a read channel (the hardware's "invalid channel" stop, SPU_Status
    /// bit IC).
    InvalidChannel {
        pc: u32,
        channel: u8,
    },
    /// Blocked on a channel nothing will ever make ready.
    Deadlock {
        pc: u32,
        channel: u8,
    },
    /// Waiting on a channel only the host can serve (a mailbox or signal): resumable.
    Blocked {
        channel: u8,
    },
    CycleLimit,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Stop(code) => write!(f, "stop {code:#x}"),
            StopReason::Halt { pc } => write!(f, "halt at {pc:#x}"),
            StopReason::IllegalInstruction { pc, word } => {
                write!(f, "illegal instruction {word:#010x} at {pc:#x}")
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

/// Channel numbers (SPU ISA / Cell BE Handbook).
pub mod ch {
    pub const RD_EVENT_STAT: u8 = 0;
    pub const WR_EVENT_MASK: u8 = 1;
    pub const WR_EVENT_ACK: u8 = 2;
    pub const RD_SIG_NOTIFY1: u8 = 3;
    pub const RD_SIG_NOTIFY2: u8 = 4;
    pub const WR_DEC: u8 = 7;
    pub const RD_DEC: u8 = 8;
    pub const WR_MS_SYNC_REQ: u8 = 9;
    pub const RD_EVENT_MASK: u8 = 11;
    pub const RD_TAG_MASK: u8 = 12;
    pub const RD_MACH_STAT: u8 = 13;
    pub const WR_SRR0: u8 = 14;
    pub const RD_SRR0: u8 = 15;
    pub const LSA: u8 = 16;
    pub const EAH: u8 = 17;
    pub const EAL: u8 = 18;
    pub const SIZE: u8 = 19;
    pub const TAG_ID: u8 = 20;
    pub const CMD: u8 = 21;
    pub const WR_TAG_MASK: u8 = 22;
    pub const WR_TAG_UPDATE: u8 = 23;
    pub const RD_TAG_STAT: u8 = 24;
    pub const RD_LIST_STALL_STAT: u8 = 25;
    pub const WR_LIST_STALL_ACK: u8 = 26;
    pub const RD_ATOMIC_STAT: u8 = 27;
    pub const WR_OUT_MBOX: u8 = 28;
    pub const RD_IN_MBOX: u8 = 29;
    pub const WR_OUT_INTR_MBOX: u8 = 30;
}

/// Event bits of SPU_RdEventStat, SPU_WrEventMask and SPU_WrEventAck (the values of the
/// SDK's `spu_mfcio.h`).
pub mod event {
    /// Multisource synchronisation (accepted in the mask, never raised here).
    pub const MULTI_SRC_SYNC: u32 = 0x1000;
    /// Privileged attention (never raised here).
    pub const PRIV_ATTN: u32 = 0x800;
    /// Lock-line reservation lost.
    pub const LR: u32 = 0x400;
    pub const SIGNAL1: u32 = 0x200;
    pub const SIGNAL2: u32 = 0x100;
    /// The outbound mailbox became available (the host read it).
    pub const OUT_MBOX: u32 = 0x80;
    /// The outbound interrupt mailbox became available.
    pub const OUT_INTR_MBOX: u32 = 0x40;
    /// The decrementer went from 0 to -1.
    pub const DECREMENTER: u32 = 0x20;
    /// The inbound mailbox holds a value.
    pub const IN_MBOX: u32 = 0x10;
    /// The MFC command queue has a free slot (never raised here: a full queue stalls).
    pub const QUEUE_VACANCY: u32 = 0x8;
    /// A DMA list element with stall-and-notify completed.
    pub const LIST_STALL: u32 = 0x2;
    /// A tag-status update request (any/all) is satisfied.
    pub const TAG_GROUP: u32 = 0x1;
}

#[derive(Clone, Debug)]
struct DmaCommand {
    tag: u8,
    complete: u64,
    /// Bytes to copy into local store at completion (gets).
    incoming: Vec<(u32, Vec<u8>)>,
}

#[derive(Clone, Debug)]
enum WriteKind {
    Put,
    Conditional,
    Unconditional,
    /// A `sndsig` to signal-notification register `which` (0 or 1) of the SPU whose
    /// index is `spu`.
    Signal {
        spu: u32,
        which: u8,
    },
}

/// Where `sndsig` finds the other SPUs' signal-notification registers: the PlayStation 3's
/// raw-SPU map (each SPU's problem-state area at `RAW_SPU_BASE + index * RAW_SPU_STRIDE +
/// PROBLEM_STATE_OFFSET`), with SPU_Sig_Notify_1 and _2 at their problem-state offsets
/// 0x1400C and 0x1C00C (Cell BE Handbook, problem-state register map).
pub const RAW_SPU_BASE: u32 = 0xE000_0000;
pub const RAW_SPU_STRIDE: u32 = 0x10_0000;
pub const PROBLEM_STATE_OFFSET: u32 = 0x4_0000;
pub const SIG_NOTIFY_OFFSETS: [u32; 2] = [0x1_400C, 0x1_C00C];

/// The effective address of signal-notification register `which` (0 or 1) of the SPU with
/// index `spu`, for `sndsig`.
pub fn signal_notify_ea(spu: u32, which: usize) -> u32 {
    RAW_SPU_BASE + spu * RAW_SPU_STRIDE + PROBLEM_STATE_OFFSET + SIG_NOTIFY_OFFSETS[which & 1]
}

/// The SPU index and register a `sndsig` effective address names, if it names one.
fn signal_target(ea: u64) -> Option<(u32, u8)> {
    let off = ea.checked_sub(RAW_SPU_BASE as u64)?;
    let (spu, within) = (off / RAW_SPU_STRIDE as u64, off % RAW_SPU_STRIDE as u64);
    let which = SIG_NOTIFY_OFFSETS
        .iter()
        .position(|&o| within == (PROBLEM_STATE_OFFSET + o) as u64)?;
    (spu < 256).then_some((spu as u32, which as u8))
}

#[derive(Clone, Debug)]
struct LoggedWrite {
    cycle: u64,
    seq: u64,
    ea: u32,
    data: Vec<u8>,
    kind: WriteKind,
}

/// One SPU.
pub struct Spu {
    pub index: u32,
    core: Core,
    decoded: Box<[Inst; LS_SIZE / 4]>,
    /// Bumped whenever a store or DMA makes a decoded instruction stale.
    code_epoch: u64,
    pc: u32,
    instructions: u64,
    cycle: u64,
    timing: Option<Timing>,
    // channels
    in_mbox: VecDeque<u32>,
    out_mbox: Option<u32>,
    out_intr_mbox: Option<u32>,
    signal: [Option<u32>; 2],
    /// OR mode for each signal register (otherwise overwrite).
    pub signal_or_mode: [bool; 2],
    /// The host promises to feed the inbound mailbox/signals: a read on them blocks
    /// instead of deadlocking.
    pub host_feeds: bool,
    dec_value: u32,
    dec_written_at: u64,
    /// When the decrementer goes from 0 to -1 (raising its event), if it will.
    dec_event_at: Option<u64>,
    /// Cycles per decrementer tick (the timebase); 1 unless the host sets it.
    pub decrementer_cycles_per_tick: u64,
    event_mask: u32,
    event_status: u32,
    // MFC
    lsa: u32,
    eah: u32,
    eal: u32,
    size: u32,
    tag_id: u32,
    tag_mask: u32,
    tag_update: Option<u32>,
    queue: Vec<DmaCommand>,
    dma_free_at: u64,
    /// The memory interface is busy with earlier quanta's traffic until then (set at each
    /// boundary); this quantum's commands, `(first cycle they may move data, bytes)`, for
    /// the boundary to add.
    bus_free_at: u64,
    bus_log: Vec<(u64, u32)>,
    list_stall: u32,
    stalled_list: Option<(u8, u8, u32, u32, u32, u32)>,
    atomic_stat: Option<(u32, u64)>,
    atomic_pending: bool,
    reservation: Option<u32>,
    writes: Vec<LoggedWrite>,
    seq: u64,
    timing_config: TimingConfig,
    /// The command being issued, for a DmaError: (cmd, lsa, ea, size, tag).
    dma_ctx: (u8, u32, u64, u32, u32),
}

/// The marker of a stale pre-decoded word: `Unknown` carrying a word that is not unknown
/// (`il $0,0`), so no real decoding result equals it.
const STALE: Inst = Inst {
    op: Op::Unknown,
    rt: 0,
    ra: 0,
    rb: 0,
    rc: 0,
    imm: 0,
    word: 0x4080_0000,
};

enum ChannelOutcome {
    Done,
    /// Not ready before this cycle; retry then.
    WaitUntil(u64),
    /// Ready only after the next quantum boundary.
    WaitBoundary,
    /// Only the host can make it ready.
    Host,
    Never,
    /// No such channel in that direction.
    Invalid,
    Error(String),
}

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
fn invalidate_quad(decoded: &mut [Inst; LS_SIZE / 4], addr: u32) -> bool {
    let s = (addr & LS_MASK & !15) as usize / 4;
    let quad = &mut decoded[s..s + 4];
    let touched = quad
        .iter()
        .any(|d| d.op != Op::Unknown || d.word != STALE.word);
    quad.fill(STALE);
    touched
}

impl Spu {
    pub fn new(index: u32) -> Spu {
        Spu {
            index,
            core: Core::new(),
            code_epoch: 0,
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
            dec_value: 0,
            dec_written_at: 0,
            dec_event_at: None,
            decrementer_cycles_per_tick: 1,
            event_mask: 0,
            event_status: 0,
            lsa: 0,
            eah: 0,
            eal: 0,
            size: 0,
            tag_id: 0,
            tag_mask: 0,
            tag_update: None,
            queue: Vec::new(),
            dma_free_at: 0,
            bus_free_at: 0,
            bus_log: Vec::new(),
            list_stall: 0,
            stalled_list: None,
            atomic_stat: None,
            atomic_pending: false,
            reservation: None,
            writes: Vec::new(),
            seq: 0,
            timing_config: TimingConfig::default(),
            dma_ctx: (0, 0, 0, 0, 0),
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
    fn redecode(&mut self, addr: u32, len: u32) {
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
    fn fetch(&mut self, pc: u32) -> Inst {
        let w = (pc >> 2) as usize & (LS_SIZE / 4 - 1);
        let inst = self.decoded[w];
        if inst.op != Op::Unknown || inst.word != STALE.word {
            return inst;
        }
        let b = &self.core.ls[4 * w..4 * w + 4];
        let fresh = decode(u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
        self.decoded[w] = fresh;
        fresh
    }

    pub fn pc(&self) -> u32 {
        self.pc
    }
    pub fn set_pc(&mut self, pc: u32) {
        self.pc = pc & LS_MASK & !3;
    }
    pub fn reg(&self, n: usize) -> Reg {
        self.core.regs[n & 127]
    }
    pub fn set_reg(&mut self, n: usize, value: Reg) {
        self.core.regs[n & 127] = value;
    }
    pub fn ls(&self) -> &[u8] {
        &self.core.ls[..]
    }
    /// Writes local store from the host (re-decoding what it covers).
    pub fn write_ls(&mut self, addr: u32, bytes: &[u8]) {
        for (i, b) in bytes.iter().enumerate() {
            self.core.ls[(addr as usize + i) & LS_MASK as usize] = *b;
        }
        self.redecode(addr, bytes.len() as u32);
    }
    pub fn instructions(&self) -> u64 {
        self.instructions
    }
    pub fn cycles(&self) -> u64 {
        self.cycle
    }
    pub fn fpscr(&self) -> &crate::float::Fpscr {
        &self.core.fpscr
    }
    pub fn timing(&self) -> Option<&Timing> {
        self.timing.as_ref()
    }
    pub fn timing_mut(&mut self) -> Option<&mut Timing> {
        self.timing.as_mut()
    }

    /// Turns the cycle-level timing model on.
    pub fn enable_timing(&mut self, config: TimingConfig) {
        self.timing_config = config.clone();
        self.timing = Some(Timing::new(config));
    }

    /// Host side of the inbound mailbox (4 deep): false when full.
    pub fn write_inbound_mailbox(&mut self, value: u32) -> bool {
        if self.in_mbox.len() >= 4 {
            return false;
        }
        self.in_mbox.push_back(value);
        self.event_status |= event::IN_MBOX;
        true
    }
    pub fn read_outbound_mailbox(&mut self) -> Option<u32> {
        let v = self.out_mbox.take();
        if v.is_some() {
            self.event_status |= event::OUT_MBOX;
        }
        v
    }
    pub fn read_outbound_interrupt_mailbox(&mut self) -> Option<u32> {
        let v = self.out_intr_mbox.take();
        if v.is_some() {
            self.event_status |= event::OUT_INTR_MBOX;
        }
        v
    }
    /// Entries waiting in the inbound mailbox (0..4).
    pub fn inbound_mailbox_len(&self) -> usize {
        self.in_mbox.len()
    }
    /// Pending events (SPU_RdEventStat before the mask).
    pub fn event_status(&self) -> u32 {
        self.event_status
    }
    /// The interrupt-enable bit (set by the E forms of the indirect branches, cleared by
    /// the D forms and when an interrupt is taken).
    pub fn interrupts_enabled(&self) -> bool {
        self.core.interrupts_enabled
    }
    /// SRR0: where `iret` returns to (SPU_WrSRR0 / SPU_RdSRR0; an interrupt sets it).
    pub fn srr0(&self) -> u32 {
        self.core.srr0
    }
    /// Host (or another SPU's `sndsig`) writes a signal-notification register (0 or 1).
    pub fn write_signal(&mut self, which: usize, value: u32) {
        let w = which & 1;
        self.signal[w] = Some(match (self.signal[w], self.signal_or_mode[w]) {
            (Some(old), true) => old | value,
            _ => value,
        });
        self.event_status |= if w == 0 {
            event::SIGNAL1
        } else {
            event::SIGNAL2
        };
    }

    fn dma_latency(&self) -> u64 {
        (self.timing_config.dma_latency_ns * self.timing_config.clock_ghz).round() as u64
    }

    /// Runs until `max_cycles` or a stop; main memory writes apply immediately after.
    pub fn run(&mut self, memory: &mut MainMemory, max_cycles: u64) -> StopReason {
        const QUANTUM: u64 = 4096;
        loop {
            let until = (self.cycle + QUANTUM).min(max_cycles);
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
        while self.cycle < until {
            if self.timing.is_none() {
                self.run_fast(until);
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
            let issue = match &mut self.timing {
                Some(t) => t.issue(pc, inst),
                None => self.cycle,
            };
            if !self.core.interrupts_enabled {
                if let Some(n) = self.timing.as_ref().and_then(|t| t.replay_started()) {
                    if self.replay_block(pc, n) {
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
                    ChannelOutcome::WaitUntil(when) => {
                        // Stall on the channel, then retry the instruction.
                        match &mut self.timing {
                            Some(t) => t.channel_stall(pc, inst.ra, when),
                            None => self.cycle = when,
                        }
                        if self.timing.is_some() {
                            self.cycle = self.timing.as_ref().unwrap().now();
                        }
                        continue;
                    }
                    ChannelOutcome::WaitBoundary => {
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
    fn block_in_store(&self, pc: u32, words: &[u32], verified: u64) -> bool {
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
    fn run_block_replays(&mut self, until: u64) {
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
    unsafe fn run_block_replays_v3(&mut self, until: u64) {
        self.run_block_replays_body(until)
    }

    #[inline(always)]
    fn run_block_replays_body(&mut self, until: u64) {
        let truncating = TruncatingFloats::hold();
        self.block_replays_loop(until);
        truncating.release();
    }

    #[inline(always)]
    fn block_replays_loop(&mut self, until: u64) {
        while self.cycle < until && !self.core.interrupts_enabled {
            let pc = self.pc;
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
            self.run_replayed_block(pc, n, id);
        }
    }

    /// Executes a memoized block whose replay `issue` has just started at `pc` (its first
    /// instruction issued, none executed): all `n` instructions in one go, leaving the
    /// timing model as the per-instruction path would. Declines (returns false, nothing
    /// done) unless local store still holds the recorded words, decoded, and none of them
    /// needs the core's event state (`bisled`).
    fn replay_block(&mut self, pc: u32, n: usize) -> bool {
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
        let epoch = self.code_epoch;
        if let Some(t) = self.timing.as_mut() {
            t.set_replay_verified(epoch);
        }
        let truncating = TruncatingFloats::hold();
        self.run_replayed_block(pc, n, id);
        truncating.release();
        true
    }

    /// The execution part of [`Spu::replay_block`]; the caller holds a
    /// [`TruncatingFloats`].
    #[inline(always)]
    fn run_replayed_block(&mut self, pc: u32, n: usize, id: usize) {
        let block_end = pc.wrapping_add(4 * n as u32);
        let core = &mut self.core;
        let decoded = &mut *self.decoded;
        let timing = self.timing.as_mut().expect("timing");
        // Blocks hold no `bisled`, the one reader of the pending-event flag.
        core.event_pending_known = false;
        let mut p = pc;
        let mut done = n;
        for k in 0..n {
            let inst = decoded[((p >> 2) as usize) & (LS_SIZE / 4 - 1)];
            match execute_in::<true>(core, inst, p) {
                Effect::Branch { taken, target } => {
                    // Blocks end at their first branch.
                    timing.block_replayed(id, Some((p, inst, taken, target)));
                    p = if taken { target } else { (p + 4) & LS_MASK };
                    done = k + 1;
                    break;
                }
                Effect::Store { addr } => {
                    self.code_epoch += invalidate_quad(decoded, addr) as u64;
                    p = (p + 4) & LS_MASK;
                    // A store into the rest of the block: the rest goes the long way.
                    let line = addr & LS_MASK & !15;
                    if k + 1 < n && line < block_end && line + 16 > p {
                        timing.block_replayed_partly(id, k + 1);
                        done = k + 1;
                        break;
                    }
                }
                // Hints name a static target here (register hints end blocks); the
                // replayed steps already hold what the hook would record.
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
    fn run_fast(&mut self, until: u64) {
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
    unsafe fn run_fast_v3(&mut self, until: u64) {
        self.run_fast_body(until)
    }

    #[inline(always)]
    fn run_fast_body(&mut self, until: u64) {
        if self.core.interrupts_enabled {
            return;
        }
        let truncating = TruncatingFloats::hold();
        let budget = until.saturating_sub(self.cycle);
        let mut pc = self.pc;
        let mut done = 0u64;
        let core = &mut self.core;
        let decoded = &mut *self.decoded;
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
                let fresh = decode(u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
                decoded[w] = fresh;
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
                    self.code_epoch += invalidate_quad(decoded, addr) as u64;
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

    fn finish(&mut self, issue: u64) {
        self.instructions += 1;
        self.cycle = issue + 1;
    }

    fn complete_dma(&mut self, now: u64) {
        let mut i = 0;
        while i < self.queue.len() {
            if self.queue[i].complete <= now {
                let cmd = self.queue.remove(i);
                for (lsa, bytes) in cmd.incoming {
                    for (k, b) in bytes.iter().enumerate() {
                        self.core.ls[(lsa as usize + k) & LS_MASK as usize] = *b;
                    }
                    self.redecode(lsa, bytes.len() as u32);
                }
            } else {
                i += 1;
            }
        }
        if let Some(mode) = self.tag_update {
            let done = self.tag_done_mask() & self.tag_mask;
            let satisfied = match mode {
                1 => done != 0 || self.tag_mask == 0,
                2 => done == self.tag_mask,
                _ => true,
            };
            if satisfied {
                self.event_status |= event::TAG_GROUP;
            }
        }
    }

    /// Brings time-driven state up to `now`: completed DMA (and the tag-group event) and
    /// the decrementer event.
    fn update_events(&mut self, now: u64) {
        self.complete_dma(now);
        if let Some(t) = self.dec_event_at {
            if t <= now {
                self.event_status |= event::DECREMENTER;
                self.dec_event_at = None;
            }
        }
    }

    fn busy_tags(&self) -> u32 {
        self.queue.iter().fold(0, |m, c| m | (1 << c.tag))
            | self.stalled_list.map_or(0, |s| 1 << s.0)
    }

    fn tag_done_mask(&self) -> u32 {
        !self.busy_tags()
    }

    /// The cycle when the commands of the tags in `mask` complete (all) or the first does.
    fn completion_of(&self, mask: u32, all: bool) -> Option<u64> {
        let times = self
            .queue
            .iter()
            .filter(|c| mask & (1 << c.tag) != 0)
            .map(|c| c.complete);
        if all {
            times.max()
        } else {
            times.min()
        }
    }

    fn read_channel(&mut self, channel: u8, now: u64) -> Result<u32, ChannelOutcome> {
        use ch::*;
        self.update_events(now);
        Ok(match channel {
            RD_EVENT_STAT => {
                let pending = self.event_status & self.event_mask;
                if pending == 0 {
                    let dec = self
                        .dec_event_at
                        .filter(|_| self.event_mask & event::DECREMENTER != 0);
                    let dma = self.queue.iter().map(|c| c.complete).min();
                    let next = match (dma, dec) {
                        (Some(a), Some(b)) => Some(a.min(b)),
                        (a, b) => a.or(b),
                    };
                    return Err(match next {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None if self.atomic_pending => ChannelOutcome::WaitBoundary,
                        None if self.host_feeds => ChannelOutcome::Host,
                        None => ChannelOutcome::Never,
                    });
                }
                pending
            }
            RD_SIG_NOTIFY1 | RD_SIG_NOTIFY2 => {
                let w = (channel - RD_SIG_NOTIFY1) as usize;
                match self.signal[w].take() {
                    Some(v) => v,
                    None => {
                        return Err(if self.host_feeds {
                            ChannelOutcome::Host
                        } else {
                            ChannelOutcome::Never
                        })
                    }
                }
            }
            RD_DEC => self.dec_value.wrapping_sub(
                (now.saturating_sub(self.dec_written_at) / self.decrementer_cycles_per_tick.max(1))
                    as u32,
            ),
            RD_EVENT_MASK => self.event_mask,
            RD_TAG_MASK => self.tag_mask,
            // Bit 0: interrupts enabled (not in isolation mode: bit 1 clear).
            RD_MACH_STAT => self.core.interrupts_enabled as u32,
            RD_SRR0 => self.core.srr0,
            RD_TAG_STAT => {
                let Some(mode) = self.tag_update.take() else {
                    return Err(ChannelOutcome::Never);
                };
                let done = self.tag_done_mask() & self.tag_mask;
                let ready = match mode {
                    1 => done != 0 || self.tag_mask == 0,
                    2 => done == self.tag_mask,
                    _ => true,
                };
                if !ready {
                    self.tag_update = Some(mode);
                    return Err(match self.completion_of(self.tag_mask, mode == 2) {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None if self.stalled_list.is_some() => ChannelOutcome::Never,
                        None => ChannelOutcome::Never,
                    });
                }
                done
            }
            RD_LIST_STALL_STAT => {
                if self.list_stall == 0 {
                    return Err(match self.queue.iter().map(|c| c.complete).min() {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None => ChannelOutcome::Never,
                    });
                }
                std::mem::take(&mut self.list_stall)
            }
            RD_ATOMIC_STAT => match self.atomic_stat {
                Some((value, ready)) if ready <= now => {
                    self.atomic_stat = None;
                    value
                }
                Some((_, ready)) => return Err(ChannelOutcome::WaitUntil(ready)),
                None if self.atomic_pending => return Err(ChannelOutcome::WaitBoundary),
                None => return Err(ChannelOutcome::Never),
            },
            RD_IN_MBOX => match self.in_mbox.pop_front() {
                Some(v) => v,
                None => {
                    return Err(if self.host_feeds {
                        ChannelOutcome::Host
                    } else {
                        ChannelOutcome::Never
                    })
                }
            },
            _ => 0,
        })
    }

    fn channel_count(&mut self, channel: u8, now: u64) -> u32 {
        use ch::*;
        self.update_events(now);
        match channel {
            RD_IN_MBOX => self.in_mbox.len() as u32,
            WR_OUT_MBOX => self.out_mbox.is_none() as u32,
            WR_OUT_INTR_MBOX => self.out_intr_mbox.is_none() as u32,
            RD_SIG_NOTIFY1 | RD_SIG_NOTIFY2 => {
                self.signal[(channel - RD_SIG_NOTIFY1) as usize].is_some() as u32
            }
            CMD => 16 - self.queue.len().min(16) as u32,
            RD_TAG_STAT => match self.tag_update {
                Some(2) => (self.tag_done_mask() & self.tag_mask == self.tag_mask) as u32,
                Some(1) => (self.tag_done_mask() & self.tag_mask != 0) as u32,
                Some(_) => 1,
                None => 0,
            },
            RD_ATOMIC_STAT => matches!(self.atomic_stat, Some((_, r)) if r <= now) as u32,
            RD_LIST_STALL_STAT => (self.list_stall != 0) as u32,
            RD_EVENT_STAT => (self.event_status & self.event_mask != 0) as u32,
            _ => 1,
        }
    }

    fn channel(&mut self, inst: Inst, now: u64, memory: &MainMemory) -> ChannelOutcome {
        let channel = inst.ra;
        // The SPU's channels and their directions (../shared/isa/README.md, "Channels").
        const READ: u128 = 1 << 0
            | 1 << 3
            | 1 << 4
            | 1 << 8
            | 1 << 11
            | 1 << 12
            | 1 << 13
            | 1 << 15
            | 1 << 24
            | 1 << 25
            | 1 << 27
            | 1 << 29;
        const WRITE: u128 =
            1 << 1 | 1 << 2 | 1 << 7 | 1 << 9 | 1 << 14 | 0xff << 16 | 1 << 26 | 1 << 28 | 1 << 30;
        let valid = match inst.op {
            Op::Rdch => READ,
            Op::Wrch => WRITE,
            _ => READ | WRITE,
        };
        if valid >> (channel & 127) & 1 == 0 {
            return ChannelOutcome::Invalid;
        }
        match inst.op {
            Op::Rdch => match self.read_channel(channel, now) {
                Ok(v) => {
                    self.core.regs[inst.rt as usize] = [v, 0, 0, 0];
                    ChannelOutcome::Done
                }
                Err(wait) => wait,
            },
            Op::Rchcnt => {
                let n = self.channel_count(channel, now);
                self.core.regs[inst.rt as usize] = [n, 0, 0, 0];
                ChannelOutcome::Done
            }
            _ => {
                let v = self.core.regs[inst.rt as usize][0];
                self.write_channel(channel, v, now, memory)
            }
        }
    }

    fn write_channel(
        &mut self,
        channel: u8,
        v: u32,
        now: u64,
        memory: &MainMemory,
    ) -> ChannelOutcome {
        use ch::*;
        self.update_events(now);
        match channel {
            WR_EVENT_MASK => self.event_mask = v,
            WR_EVENT_ACK => self.event_status &= !v,
            WR_DEC => {
                self.dec_value = v;
                self.dec_written_at = now;
                let tick = self.decrementer_cycles_per_tick.max(1);
                self.dec_event_at = Some(now + (v as u64 + 1) * tick);
            }
            WR_SRR0 => self.core.srr0 = v,
            LSA => self.lsa = v,
            EAH => self.eah = v,
            EAL => self.eal = v,
            SIZE => self.size = v,
            TAG_ID => self.tag_id = v,
            WR_TAG_MASK => self.tag_mask = v,
            WR_TAG_UPDATE => self.tag_update = Some(v & 3),
            WR_LIST_STALL_ACK => {
                if let Some((tag, cmd, lsa, list, remaining, eah)) = self.stalled_list.take() {
                    if tag as u32 == (v & 31) {
                        return self.run_list(cmd, tag, lsa, list, remaining, eah, now, memory);
                    }
                    self.stalled_list = Some((tag, cmd, lsa, list, remaining, eah));
                }
            }
            CMD => {
                if self.queue.len() >= 16 {
                    let earliest = self.queue.iter().map(|c| c.complete).min().unwrap_or(now);
                    return ChannelOutcome::WaitUntil(earliest);
                }
                return self.mfc_command(v & 0xff, now, memory);
            }
            WR_OUT_MBOX => {
                if self.out_mbox.is_some() {
                    return ChannelOutcome::Host;
                }
                self.out_mbox = Some(v);
            }
            WR_OUT_INTR_MBOX => {
                if self.out_intr_mbox.is_some() {
                    return ChannelOutcome::Host;
                }
                self.out_intr_mbox = Some(v);
            }
            _ => {}
        }
        ChannelOutcome::Done
    }

    fn schedule(&mut self, now: u64, bytes: u32) -> u64 {
        let earliest = now + self.dma_latency();
        let per_cycle = (self.timing_config.spu_bytes_per_cycle.max(1.0)) as u64;
        let own = earliest.max(self.dma_free_at) + (bytes as u64).div_ceil(per_cycle);
        // Behind the traffic the memory interface still has from earlier quanta.
        let chip = self.timing_config.chip_bytes_per_cycle();
        let shared = (earliest.max(self.bus_free_at) as f64 + bytes as f64 / chip).ceil() as u64;
        let done = own.max(shared);
        self.bus_log.push((earliest, bytes));
        self.dma_free_at = done;
        if let Some(t) = &mut self.timing {
            t.dma_local_store(done, bytes);
        }
        done
    }

    fn check_transfer(
        &self,
        lsa: u32,
        ea: u64,
        size: u32,
        memory: &MainMemory,
    ) -> Result<(), String> {
        let ok_size = matches!(size, 1 | 2 | 4 | 8) || (size % 16 == 0 && size <= 16384);
        if !ok_size {
            return Err(format!(
                "transfer size {size} is not 1, 2, 4, 8 or a multiple of 16 up to 16384"
            ));
        }
        if size == 0 {
            // A zero-length transfer moves nothing and completes its tag.
        } else if size < 16 {
            if lsa % size != 0 || ea % size as u64 != 0 {
                return Err(format!(
                    "{size}-byte transfer with LS {lsa:#x} / EA {ea:#x} not naturally aligned"
                ));
            }
            if (lsa ^ ea as u32) & 15 != 0 {
                return Err(format!(
                    "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits"
                ));
            }
        } else if (lsa as u64 ^ ea) & 15 != 0 {
            return Err(format!(
                "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits for a {size}-byte transfer"
            ));
        }
        if memory.range(ea, size).is_none() {
            return Err(format!(
                "EA {ea:#x}+{size} is outside main memory ({} bytes)",
                memory.len()
            ));
        }
        Ok(())
    }

    fn mfc_command(&mut self, cmd: u32, now: u64, memory: &MainMemory) -> ChannelOutcome {
        let tag = self.tag_id;
        self.dma_ctx = (
            cmd as u8,
            self.lsa,
            ((self.eah as u64) << 32) | self.eal as u64,
            self.size,
            tag,
        );
        if tag > 31 && !matches!(cmd, 0xd0 | 0xb4 | 0xb0 | 0xb8) {
            return ChannelOutcome::Error(format!("tag {tag} is out of range 0..31"));
        }
        let tag = (tag & 31) as u8;
        let lsa = self.lsa & LS_MASK;
        let ea = ((self.eah as u64) << 32) | self.eal as u64;
        match cmd {
            0x40..=0x42 | 0x20..=0x22 => {
                let size = self.size;
                if let Err(e) = self.check_transfer(lsa, ea, size, memory) {
                    return ChannelOutcome::Error(e);
                }
                let complete = self.schedule(now, size);
                let range = memory.range(ea, size).unwrap();
                if cmd & 0x40 != 0 {
                    let data = self.read_main(memory, range);
                    self.queue.push(DmaCommand {
                        tag,
                        complete,
                        incoming: vec![(lsa, data)],
                    });
                } else {
                    let data: Vec<u8> = (0..size)
                        .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                        .collect();
                    self.log_write(complete, ea as u32, data, WriteKind::Put);
                    self.queue.push(DmaCommand {
                        tag,
                        complete,
                        incoming: Vec::new(),
                    });
                }
                ChannelOutcome::Done
            }
            0x44..=0x46 | 0x24..=0x26 => {
                let list = self.eal & LS_MASK;
                if list & 7 != 0 {
                    return ChannelOutcome::Error(format!(
                        "DMA list address {list:#x} is not 8-byte aligned"
                    ));
                }
                if self.size % 8 != 0 || self.size / 8 > 2048 {
                    return ChannelOutcome::Error(format!(
                        "DMA list size {} is not a multiple of 8 up to 16384",
                        self.size
                    ));
                }
                self.run_list(
                    cmd as u8,
                    tag,
                    lsa,
                    list,
                    self.size / 8,
                    self.eah,
                    now,
                    memory,
                )
            }
            0xd0 => {
                let line = self.eal & !127;
                let ea = ((self.eah as u64) << 32) | line as u64;
                if lsa & 127 != 0 {
                    return ChannelOutcome::Error(format!(
                        "getllar LS {lsa:#x} not 128-byte aligned"
                    ));
                }
                let Some(range) = memory.range(ea, 128) else {
                    return ChannelOutcome::Error(format!(
                        "getllar EA {ea:#x} outside main memory"
                    ));
                };
                let data = self.read_main(memory, range);
                for (k, b) in data.iter().enumerate() {
                    self.core.ls[(lsa as usize + k) & LS_MASK as usize] = *b;
                }
                self.redecode(lsa, 128);
                self.reservation = Some(line);
                let ready = now + self.dma_latency();
                self.atomic_stat = Some((4, ready));
                ChannelOutcome::Done
            }
            0xb4 | 0xb0 | 0xb8 => {
                let line = self.eal & !127;
                if lsa & 127 != 0 {
                    return ChannelOutcome::Error(format!(
                        "putllc/putlluc LS {lsa:#x} not 128-byte aligned"
                    ));
                }
                if memory.range(line as u64, 128).is_none() {
                    return ChannelOutcome::Error(format!(
                        "atomic EA {line:#x} outside main memory"
                    ));
                }
                let data: Vec<u8> = (0..128)
                    .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                    .collect();
                let cycle = now + self.dma_latency();
                if cmd == 0xb4 {
                    if self.reservation != Some(line) {
                        self.atomic_stat = Some((1, cycle));
                    } else {
                        self.log_write(cycle, line, data, WriteKind::Conditional);
                        self.atomic_pending = true;
                        self.atomic_stat = None;
                    }
                } else {
                    self.log_write(cycle, line, data, WriteKind::Unconditional);
                    self.atomic_stat = Some((2, cycle));
                }
                ChannelOutcome::Done
            }
            0xa0..=0xa2 => {
                // sndsig, sndsigb, sndsigf: four bytes from local store into another SPU's
                // signal-notification register, delivered when the command completes
                // (at the quantum boundary that publishes it, like a put).
                let Some((spu, which)) = signal_target(ea) else {
                    return ChannelOutcome::Error(format!(
                        "sndsig to EA {ea:#x}, which is no SPU's signal-notification register"
                    ));
                };
                if self.size != 4 {
                    return ChannelOutcome::Error(format!(
                        "sndsig of {} bytes (a signal is 4 bytes)",
                        self.size
                    ));
                }
                if lsa & 15 != (ea as u32) & 15 {
                    return ChannelOutcome::Error(format!(
                        "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits"
                    ));
                }
                let complete = self.schedule(now, 4);
                let data: Vec<u8> = (0..4)
                    .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                    .collect();
                self.log_write(complete, ea as u32, data, WriteKind::Signal { spu, which });
                self.queue.push(DmaCommand {
                    tag,
                    complete,
                    incoming: Vec::new(),
                });
                ChannelOutcome::Done
            }
            0xc0 | 0xc8 | 0xcc => ChannelOutcome::Done,
            other => ChannelOutcome::Error(format!("unknown MFC command {other:#x}")),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn run_list(
        &mut self,
        cmd: u8,
        tag: u8,
        mut lsa: u32,
        mut list: u32,
        mut remaining: u32,
        eah: u32,
        now: u64,
        memory: &MainMemory,
    ) -> ChannelOutcome {
        let mut incoming = Vec::new();
        let mut last = now;
        while remaining > 0 {
            let e0 = u32::from_be_bytes(
                self.core.ls[list as usize..list as usize + 4]
                    .try_into()
                    .unwrap(),
            );
            let e1 = u32::from_be_bytes(
                self.core.ls[list as usize + 4..list as usize + 8]
                    .try_into()
                    .unwrap(),
            );
            let size = e0 & 0x7fff;
            let ea = ((eah as u64) << 32) | e1 as u64;
            self.dma_ctx = (cmd, lsa, ea, size, tag as u32);
            if let Err(e) = self.check_transfer(lsa, ea, size, memory) {
                return ChannelOutcome::Error(format!("list element at {list:#x}: {e}"));
            }
            last = self.schedule(now, size);
            let range = memory.range(ea, size).unwrap();
            if cmd & 0x40 != 0 {
                incoming.push((lsa, self.read_main(memory, range)));
            } else {
                let data: Vec<u8> = (0..size)
                    .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                    .collect();
                self.log_write(last, e1, data, WriteKind::Put);
            }
            lsa = (lsa + size.div_ceil(16) * 16) & LS_MASK;
            list = (list + 8) & LS_MASK;
            remaining -= 1;
            if e0 & 0x8000_0000 != 0 && remaining > 0 {
                self.stalled_list = Some((tag, cmd, lsa, list, remaining, eah));
                self.list_stall |= 1 << tag;
                self.event_status |= event::LIST_STALL;
                break;
            }
        }
        self.queue.push(DmaCommand {
            tag,
            complete: last,
            incoming,
        });
        ChannelOutcome::Done
    }

    /// Main memory as this SPU sees it: the state at the last boundary with its own
    /// logged writes (not yet applied) laid over it, in issue order. Conditional stores
    /// whose outcome the boundary has not decided yet are left out.
    fn read_main(&self, memory: &MainMemory, range: std::ops::Range<usize>) -> Vec<u8> {
        let mut data = memory.bytes()[range.clone()].to_vec();
        for w in &self.writes {
            if matches!(w.kind, WriteKind::Conditional) {
                continue;
            }
            let (ws, we) = (w.ea as usize, w.ea as usize + w.data.len());
            let (s, e) = (ws.max(range.start), we.min(range.end));
            if s < e {
                data[s - range.start..e - range.start].copy_from_slice(&w.data[s - ws..e - ws]);
            }
        }
        data
    }

    fn log_write(&mut self, cycle: u64, ea: u32, data: Vec<u8>, kind: WriteKind) {
        self.seq += 1;
        self.writes.push(LoggedWrite {
            cycle,
            seq: self.seq,
            ea,
            data,
            kind,
        });
    }
}

/// The chip's memory interface (25.6 GB/s at 2.4 GHz, 10.67 bytes per cycle) serves the
/// DMA commands of all SPUs first come, first served: at a boundary the commands of the
/// quantum just run, ordered by (first cycle they may move data, SPU index, order), are
/// queued behind the earlier traffic, and every SPU's later commands complete no earlier
/// than the interface can serve them behind it. Commands of one quantum do not delay each
/// other across SPUs (each SPU's own engine, 8 bytes per cycle, still does): sharing takes
/// effect one quantum late, and the outcome depends only on simulated time. One SPU alone
/// never waits for it (8 < 10.67).
fn settle_memory_bus(spus: &mut [Spu], memory: &mut MainMemory) {
    let mut traffic: Vec<(u64, usize, usize, u32)> = Vec::new();
    for (i, spu) in spus.iter_mut().enumerate() {
        for (k, (earliest, bytes)) in spu.bus_log.drain(..).enumerate() {
            traffic.push((earliest, i, k, bytes));
        }
    }
    let Some(first) = spus.first() else {
        return;
    };
    let chip = first.timing_config.chip_bytes_per_cycle();
    traffic.sort_unstable();
    let mut busy = memory.bus_busy_until;
    for (earliest, _, _, bytes) in traffic {
        busy = busy.max(earliest as f64) + bytes as f64 / chip;
    }
    memory.bus_busy_until = busy;
    for spu in spus.iter_mut() {
        spu.bus_free_at = busy.ceil() as u64;
    }
}

/// Applies every SPU's logged main-memory writes in (cycle, SPU index, sequence) order and
/// settles `putllc` outcomes and lost reservations (see the module docs).
pub fn apply_quantum(spus: &mut [Spu], memory: &mut MainMemory) {
    let mut all: Vec<(u64, usize, u64, LoggedWrite)> = Vec::new();
    for (i, spu) in spus.iter_mut().enumerate() {
        for w in spu.writes.drain(..) {
            all.push((w.cycle, i, w.seq, w));
        }
    }
    all.sort_by_key(|(c, i, s, _)| (*c, *i, *s));
    settle_memory_bus(spus, memory);
    for (_, i, _, w) in all {
        if let WriteKind::Signal { spu, which } = w.kind {
            // A signal for an SPU that is not running here goes nowhere.
            let value = u32::from_be_bytes([w.data[0], w.data[1], w.data[2], w.data[3]]);
            if let Some(target) = spus.iter_mut().find(|s| s.index == spu) {
                target.write_signal(which as usize, value);
            }
            continue;
        }
        let line = w.ea & !127;
        let apply = match w.kind {
            WriteKind::Conditional => {
                let ok = spus[i].reservation == Some(line);
                spus[i].reservation = None;
                spus[i].atomic_pending = false;
                spus[i].atomic_stat = Some((if ok { 0 } else { 1 }, 0));
                ok
            }
            _ => true,
        };
        if !apply {
            continue;
        }
        let start = w.ea as usize;
        if let Some(dst) = memory.bytes.get_mut(start..start + w.data.len()) {
            dst.copy_from_slice(&w.data);
        }
        let first_line = w.ea & !127;
        let last_line = (w.ea + w.data.len().max(1) as u32 - 1) & !127;
        for (j, other) in spus.iter_mut().enumerate() {
            if j == i {
                continue;
            }
            if let Some(r) = other.reservation {
                if r >= first_line && r <= last_line {
                    other.reservation = None;
                    other.event_status |= event::LR;
                }
            }
        }
    }
    let _ = StallCause::Dependency;
}
