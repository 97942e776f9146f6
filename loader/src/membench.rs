//! The memory-bandwidth benchmark: `kernels/bench/dma_stream.s` on 1 to 64 SPEs at once,
//! each streaming 16 KiB blocks from (or to) its own part of main memory with four gets in
//! flight, the way published SPE-to-memory measurements are made. It shows what the
//! simulated memory system gives beside those measurements (`docs/memory-model.md`), and
//! `spu paper` reports it.

use crate::render::{MAX_BANDWIDTH_GBS, MAX_SPES, MIN_BANDWIDTH_GBS};
use crate::runtime::{quantum_cycles, STOP_DONE};
use spu_isa::machine::{MainMemory, StopReason};
use spu_isa::timing::TimingConfig;
use spu_spe::{ContextConfig, Outcome, Quantum, State, System};

/// The stream program's source.
pub const SOURCE: &str = include_str!("../../kernels/bench/dma_stream.s");

/// Bytes of one DMA of the stream (the largest the MFC moves).
pub const BLOCK: u32 = 16 * 1024;

/// Which way the SPEs stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Direction {
    /// Gets: main memory into local store.
    Read,
    /// Puts: local store into main memory.
    Write,
}

/// One run of the benchmark.
#[derive(Clone, Debug)]
pub struct Setup {
    pub spes: usize,
    /// 16 KiB blocks each SPE moves (a multiple of 4).
    pub blocks: u32,
    pub direction: Direction,
    /// Clock, DMA latency and memory bandwidth (the rest as the timing model's defaults).
    pub timing: TimingConfig,
}

/// What a run measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Measured {
    /// Cycles until the last SPE had all its blocks.
    pub cycles: u64,
    /// Bytes all SPEs moved.
    pub bytes: u64,
    /// Their rate in GB/s at the configured clock.
    pub gbs: f64,
}

/// Runs `setup`: every SPE streams `blocks` blocks; the cycles of the slowest.
pub fn run(setup: &Setup) -> Result<Measured, String> {
    if !(1..=MAX_SPES).contains(&setup.spes) {
        return Err(format!("{} SPEs: must be 1 to {MAX_SPES}", setup.spes));
    }
    if setup.blocks < 4 || !setup.blocks.is_multiple_of(4) || setup.blocks > 4096 {
        return Err(format!(
            "{} blocks: must be a multiple of 4 from 4 to 4096",
            setup.blocks
        ));
    }
    let gbs = setup.timing.memory_bandwidth_gbs;
    if !(gbs.is_finite() && (MIN_BANDWIDTH_GBS..=MAX_BANDWIDTH_GBS).contains(&gbs)) {
        return Err(format!("memory bandwidth {gbs} GB/s is out of range"));
    }
    let program = crate::runtime::assemble_kernel(SOURCE, "bench/dma_stream.s")?;
    // Each SPE its own stream; they share only the memory interface.
    let stream = setup.blocks as usize * BLOCK as usize;
    let memory = MainMemory::zeroed(stream * setup.spes);
    let mut system = System::with_memory(memory);
    system.set_quantum(Quantum::Aligned(quantum_cycles(setup.spes)));
    let command = match setup.direction {
        Direction::Read => 0x40,
        Direction::Write => 0x20,
    };
    for i in 0..setup.spes {
        let id = system.create_context(ContextConfig {
            engine: spu_isa::jit::Engine::Interp,
            timing: Some(setup.timing.clone()),
            code: None,
            extensions: spu_isa::Extensions::NONE,
        });
        let spu = system.spu_mut(id);
        spu.load_image(&program.image);
        spu.set_pc(program.entry);
        spu.set_reg(3, [(i * stream) as u32, 0, 0, 0]);
        spu.set_reg(4, [setup.blocks, 0, 0, 0]);
        spu.set_reg(5, [command, 0, 0, 0]);
    }
    let outcome = system.run(1 << 40);
    let contexts: Vec<_> = system.contexts().collect();
    let mut cycles = 0;
    for &id in &contexts {
        match system.state(id) {
            State::Stopped(StopReason::Stop(STOP_DONE)) => {}
            other => return Err(format!("the stream ended {other:?} ({outcome:?})")),
        }
        cycles = cycles.max(system.spu(id).cycles());
    }
    if outcome != Outcome::Stopped {
        return Err(format!("the stream ended {outcome:?}"));
    }
    let bytes = stream as u64 * setup.spes as u64;
    Ok(Measured {
        cycles,
        bytes,
        gbs: bytes as f64 * setup.timing.clock_ghz / cycles.max(1) as f64,
    })
}
