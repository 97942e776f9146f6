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

mod channels;
mod compiled;
mod events;
pub mod exec;
mod memory;
mod mfc;
mod spu;

pub use channels::{ch, event};
pub use events::SpuEvent;
pub use memory::{apply_quantum, MainMemory};
pub use mfc::{
    signal_notify_ea, Traffic, PROBLEM_STATE_OFFSET, RAW_SPU_BASE, RAW_SPU_STRIDE,
    SIG_NOTIFY_OFFSETS,
};
pub use spu::{Spu, StopReason};
