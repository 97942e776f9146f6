//! The memory model at the extremes (`docs/memory-model.md`): DMA latency fixed in
//! nanoseconds whatever the clock, one main-memory bandwidth per Cell shared by all its
//! SPEs, the EIB port's limit per direction, and the stream benchmark's exact cycles.

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::timing::TimingConfig;
use spu_loader::membench::{self, Direction, Measured, Setup};

fn stream(spes: usize, blocks: u32, direction: Direction, timing: TimingConfig) -> Measured {
    membench::run(&Setup {
        spes,
        blocks,
        direction,
        timing,
    })
    .unwrap()
}

/// Cycles of one SPU getting 128 bytes and waiting for them, with the timing model.
fn one_get(timing: TimingConfig) -> u64 {
    let src = "        .text\n        .global _start\n_start:\n\
        il $2, 0\n ila $3, 0x1000\n il $4, 128\n il $5, 0x40\n\
        wrch $MFC_LSA, $3\n wrch $MFC_EAH, $2\n wrch $MFC_EAL, $3\n wrch $MFC_Size, $4\n\
        wrch $MFC_TagID, $2\n wrch $MFC_Cmd, $5\n il $6, 1\n wrch $MFC_WrTagMask, $6\n\
        il $6, 2\n wrch $MFC_WrTagUpdate, $6\n rdch $7, $MFC_RdTagStat\n stop 0x100\n";
    let out = spu_asm::assemble(src, "t.s", &Default::default()).unwrap();
    let mut spu = Spu::new(0);
    spu.load_image(&out.image);
    spu.set_pc(out.entry);
    spu.enable_timing(timing);
    let stop = spu.run(&mut MainMemory::zeroed(64 * 1024), 1_000_000);
    assert_eq!(stop, StopReason::Stop(0x100));
    spu.cycles()
}

/// The latency is in nanoseconds: 100 ns is 240 cycles at 2.4 GHz, 320 at 3.2 and 640
/// at 6.4; the rest of the get (its bytes, the program around it) is the same in cycles.
#[test]
fn dma_latency_stays_fixed_in_nanoseconds_as_the_clock_rises() {
    for (clock, cycles) in [(2.4, 240), (3.2, 320), (5.2, 520), (6.4, 640)] {
        let at = |ns| {
            one_get(TimingConfig {
                clock_ghz: clock,
                dma_latency_ns: ns,
                ..Default::default()
            })
        };
        assert_eq!(at(100.0) - at(0.0), cycles, "{clock} GHz");
        assert_eq!(at(0.0), at(0.0));
    }
}

/// One SPE alone streams at its own 8 bytes per cycle where the chip allows it (2.4 and
/// 3.2 GHz), at the chip's 25.6 GB/s where it does not (6.4 GHz: 4 bytes per cycle).
#[test]
fn one_spe_streams_at_its_own_rate_or_the_chips() {
    let at = |clock| {
        stream(
            1,
            16,
            Direction::Read,
            TimingConfig {
                clock_ghz: clock,
                ..Default::default()
            },
        )
    };
    let own = 16 * 16384 / 8;
    let low = at(2.4);
    assert_eq!(low.cycles, 33_029);
    assert!(low.cycles > own && low.cycles < own + 800, "{low:?}");
    let high = at(6.4);
    assert_eq!(high.cycles, 66_197);
    assert!(high.cycles > 2 * own && high.cycles < 2 * own + 800);
}

/// The benchmark of docs/memory-model.md: 1, 2, 4, 8 and 16 SPEs each reading 1 MiB at
/// 2.4 GHz, exact cycles. The aggregate is held to the EIB port's 19.2 GB/s (16 bytes per
/// 1.2 GHz bus cycle) however many SPEs share it, and at 3.2 GHz to XDR's 25.6 GB/s, each
/// exceeded by at most 2%: the one quantum of unshared traffic at the start of the stream.
/// Writes queue on the port's other direction the same way.
#[test]
fn spes_share_one_memory_interface() {
    let mut got = Vec::new();
    for n in [1, 2, 4, 8, 16] {
        let read = stream(n, 64, Direction::Read, TimingConfig::default());
        got.push(read.cycles);
        if n == 16 {
            assert!((19.2..19.2 * 1.02).contains(&read.gbs), "{read:?}");
            let write = stream(n, 64, Direction::Write, TimingConfig::default());
            assert_eq!(read, write);
        }
    }
    assert_eq!(got, [131_333, 260_357, 518_405, 1_034_501, 2_066_693]);
    let ps3 = stream(16, 64, Direction::Read, TimingConfig::ps3());
    assert!((25.6..25.6 * 1.02).contains(&ps3.gbs), "{ps3:?}");
}

/// More memory bandwidth than the port carries changes nothing at 2.4 GHz (the port
/// binds); less makes 8 SPEs' stream slower in proportion.
#[test]
fn the_configured_bandwidth_is_what_the_spes_share() {
    let with = |gbs| {
        stream(
            8,
            16,
            Direction::Read,
            TimingConfig {
                memory_bandwidth_gbs: gbs,
                ..Default::default()
            },
        )
    };
    assert_eq!(with(25.6).cycles, with(100.0).cycles);
    let starved = with(6.4);
    assert!((6.4..8.0).contains(&starved.gbs), "{starved:?}");
}

/// Bad setups are refused, never run.
#[test]
fn the_benchmark_refuses_bad_setups() {
    for (spes, blocks) in [(0, 16), (65, 16), (1, 3), (1, 0), (1, 8192)] {
        let setup = Setup {
            spes,
            blocks,
            direction: Direction::Read,
            timing: TimingConfig::default(),
        };
        assert!(
            membench::run(&setup).is_err(),
            "{spes} SPEs, {blocks} blocks"
        );
    }
}
