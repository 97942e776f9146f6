//! The SPU timing model (under construction: this is the agreed interface with a trivial
//! one-cycle-per-instruction body; the real model replaces the bodies, not the signatures).
//!
//! The core calls these hooks in program order for every executed instruction when timing
//! is enabled. The model owns the notion of "now" (the current cycle), which the MFC uses
//! to time DMA completion.

use crate::codec::Inst;

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

/// Settings of the timing model.
#[derive(Clone, Debug)]
pub struct TimingConfig {
    /// Core clock in GHz (2.4 for the paper's blade, 3.2 for a PlayStation 3).
    pub clock_ghz: f64,
    /// Latency of a DMA command in nanoseconds before its bytes start to move.
    pub dma_latency_ns: f64,
    /// Main-memory bandwidth of the chip in GB/s, shared by all SPUs.
    pub memory_bandwidth_gbs: f64,
}

impl Default for TimingConfig {
    fn default() -> Self {
        TimingConfig { clock_ghz: 2.4, dma_latency_ns: 100.0, memory_bandwidth_gbs: 25.6 }
    }
}

/// The per-SPU pipeline model.
#[derive(Clone, Debug)]
pub struct Timing {
    pub config: TimingConfig,
    now: u64,
}

impl Timing {
    pub fn new(config: TimingConfig) -> Self {
        Timing { config, now: 0 }
    }

    /// Issues `inst` at `pc` (call in program order, before executing it); returns the
    /// cycle at which it issues.
    pub fn issue(&mut self, _pc: u32, _inst: Inst) -> u64 {
        self.now += 1;
        self.now - 1
    }

    /// After a branch instruction executed: whether it was taken and where it went.
    pub fn branch_resolved(&mut self, _pc: u32, _inst: Inst, _taken: bool, _target: u32) {}

    /// After a hint executed: the branch address it names and the target it predicts
    /// (for `hbr` the target comes from a register, so the core supplies it).
    pub fn hint(&mut self, _pc: u32, _branch: u32, _target: u32) {}

    /// The instruction just issued at `pc` could not complete before cycle `until` because
    /// channel `channel` was empty (read) or full (write): it re-issues at `until`.
    pub fn channel_stall(&mut self, _pc: u32, _channel: u8, until: u64) {
        self.now = self.now.max(until + 1);
    }

    /// A DMA transfer occupies the local store for `bytes` starting at `cycle` (it has
    /// priority over loads, stores and instruction fetch).
    pub fn dma_local_store(&mut self, _cycle: u64, _bytes: u32) {}

    /// The current cycle: the issue cycle of the next instruction at the earliest.
    pub fn now(&self) -> u64 {
        self.now
    }
}
