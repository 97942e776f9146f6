//! Timing configurations the tools refuse up front (an infinite, NaN or absurd clock or
//! latency) still leave the simulator's cycle arithmetic saturating: `max_cycles` stops a
//! run that waits on a DMA, instead of a wrapped cycle count running on forever.

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::timing::TimingConfig;

/// A 128-byte get on tag 1, then a wait for it.
const PROGRAM: &str = "
        .text
        .global _start
_start: ila     $70, 0x1000
        wrch    $MFC_LSA, $70
        il      $70, 0
        wrch    $MFC_EAH, $70
        wrch    $MFC_EAL, $70
        ila     $70, 128
        wrch    $MFC_Size, $70
        il      $70, 1
        wrch    $MFC_TagID, $70
        ila     $70, 0x40
        wrch    $MFC_Cmd, $70
        il      $70, 2
        wrch    $MFC_WrTagMask, $70
        wrch    $MFC_WrTagUpdate, $70
        rdch    $3, $MFC_RdTagStat
        stop    0x2000
";

fn run(config: TimingConfig, max_cycles: u64) -> (StopReason, u64) {
    let program = spu_asm::assemble(PROGRAM, "dma.s", &Default::default()).unwrap();
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    spu.enable_timing(config);
    let mut memory = MainMemory::zeroed(1 << 16);
    let stop = spu.run(&mut memory, max_cycles);
    (stop, spu.cycles())
}

#[test]
fn a_dma_that_never_completes_meets_the_cycle_limit() {
    for clock_ghz in [f64::INFINITY, 1e20, f64::MAX] {
        let config = TimingConfig {
            clock_ghz,
            ..Default::default()
        };
        let (stop, cycles) = run(config, 1_000_000);
        assert_eq!(stop, StopReason::CycleLimit, "clock {clock_ghz}");
        assert!(cycles >= 1_000_000, "clock {clock_ghz}: {cycles}");
    }
    let config = TimingConfig {
        dma_latency_ns: f64::INFINITY,
        ..Default::default()
    };
    assert_eq!(run(config, 1_000_000).0, StopReason::CycleLimit);
}

#[test]
fn nan_and_zero_latencies_complete() {
    for (clock_ghz, dma_latency_ns) in [(f64::NAN, 100.0), (2.4, f64::NAN), (2.4, 0.0)] {
        let config = TimingConfig {
            clock_ghz,
            dma_latency_ns,
            ..Default::default()
        };
        let (stop, cycles) = run(config, 1_000_000);
        assert_eq!(
            stop,
            StopReason::Stop(0x2000),
            "{clock_ghz} GHz, {dma_latency_ns} ns"
        );
        assert!(cycles < 1000, "{cycles}");
    }
}
