//! Small programs through the simulated SPU: results, stops and DMA.

use spu_isa::encode;
use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::table::forms_named;

fn asm(lines: &[(&str, &[i64])]) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, (m, ops)) in lines.iter().enumerate() {
        let form = forms_named(m)
            .find(|f| f.operands.len() == ops.len())
            .unwrap_or_else(|| panic!("{m}"));
        out.extend(encode(form, ops, 4 * i as u32).to_be_bytes());
    }
    out
}

#[test]
fn loop_counts_down_and_stops() {
    // $3 = 10; loop: $3 -= 1; $4 += 2; brnz $3, loop; stop 0x1234
    let image = asm(&[
        ("il", &[3, 10]),
        ("il", &[4, 0]),
        ("ai", &[3, 3, -1]),
        ("ai", &[4, 4, 2]),
        ("brnz", &[3, 8]),
        ("stop", &[0x1234]),
    ]);
    let mut spu = Spu::new(0);
    spu.load_image(&image);
    let mut mem = MainMemory::zeroed(4096);
    assert_eq!(spu.run(&mut mem, 1_000_000), StopReason::Stop(0x1234));
    assert_eq!(spu.reg(3), [0, 0, 0, 0]);
    assert_eq!(spu.reg(4), [20; 4]);
    // 2 + 10 * 3 + 1 instructions.
    assert_eq!(spu.instructions(), 33);
}

#[test]
fn dma_get_and_put_round_trip() {
    // get 16 bytes from EA 0x100 to LS 0x400, wait, add 1 to each word, put to EA 0x200.
    let image = asm(&[
        ("ila", &[5, 0x400]),
        ("il", &[6, 0x100]),
        ("il", &[7, 16]),
        ("il", &[8, 0]),
        ("wrch", &[16, 5]),
        ("wrch", &[17, 8]),
        ("wrch", &[18, 6]),
        ("wrch", &[19, 7]),
        ("wrch", &[20, 8]),
        ("il", &[9, 0x40]),
        ("wrch", &[21, 9]),
        ("il", &[9, 1]),
        ("wrch", &[22, 9]),
        ("il", &[9, 2]),
        ("wrch", &[23, 9]),
        ("rdch", &[10, 24]),
        ("lqd", &[11, 0, 5]),
        ("ai", &[11, 11, 1]),
        ("stqd", &[11, 0, 5]),
        ("il", &[6, 0x200]),
        ("wrch", &[18, 6]),
        ("il", &[9, 0x20]),
        ("wrch", &[21, 9]),
        ("il", &[9, 2]),
        ("wrch", &[23, 9]), // each tag-status read consumes its update request
        ("rdch", &[10, 24]),
        ("stop", &[0]),
    ]);
    let mut spu = Spu::new(0);
    spu.load_image(&image);
    let mut mem = MainMemory::zeroed(4096);
    for i in 0..4 {
        mem.write_u32(0x100 + 4 * i, 100 + i);
    }
    assert_eq!(spu.run(&mut mem, 1_000_000), StopReason::Stop(0));
    for i in 0..4 {
        assert_eq!(mem.read_u32(0x200 + 4 * i), 101 + i);
    }
    // The wait took the DMA latency (240 cycles at 2.4 GHz) twice.
    assert!(spu.cycles() > 480, "{}", spu.cycles());
}

#[test]
fn bad_dma_stops_with_an_error() {
    let image = asm(&[
        ("il", &[6, 0x103]),
        ("il", &[7, 16]),
        ("wrch", &[18, 6]),
        ("wrch", &[19, 7]),
        ("il", &[9, 0x40]),
        ("wrch", &[21, 9]),
        ("stop", &[0]),
    ]);
    let mut spu = Spu::new(0);
    spu.load_image(&image);
    let mut mem = MainMemory::zeroed(4096);
    assert!(matches!(
        spu.run(&mut mem, 1_000_000),
        StopReason::DmaError { pc: 20, .. }
    ));
}

#[test]
fn unknown_word_is_illegal_and_empty_mailbox_deadlocks() {
    let mut spu = Spu::new(0);
    spu.load_image(&0x00f0_0000u32.to_be_bytes());
    let mut mem = MainMemory::zeroed(16);
    assert_eq!(
        spu.run(&mut mem, 100),
        StopReason::IllegalInstruction {
            pc: 0,
            word: 0x00f0_0000
        }
    );
    let mut spu = Spu::new(0);
    spu.load_image(&asm(&[("rdch", &[3, 29])]));
    assert_eq!(
        spu.run(&mut mem, 100),
        StopReason::Deadlock { pc: 0, channel: 29 }
    );
}

/// `run(max_cycles)` stops exactly there, timing model on or off, either engine: the clock
/// reads `max_cycles` (never more), and running on from there ends exactly as one
/// uninterrupted run does, to the cycle (so nothing issued at or after the limit ran, and
/// no stall ran past it: a branch miss, a dependency, a fetch, a DMA wait, a memoized
/// block).
#[test]
fn cycle_limits_stop_exactly_and_resume_seamlessly() {
    // A DMA get waited on, then a loop of dependent multiplies ending in a backward branch.
    let image = asm(&[
        ("ila", &[5, 0x400]),
        ("il", &[6, 0x100]),
        ("il", &[7, 16]),
        ("il", &[8, 0]),
        ("wrch", &[16, 5]),
        ("wrch", &[17, 8]),
        ("wrch", &[18, 6]),
        ("wrch", &[19, 7]),
        ("wrch", &[20, 8]),
        ("il", &[9, 0x40]),
        ("wrch", &[21, 9]),
        ("il", &[9, 1]),
        ("wrch", &[22, 9]),
        ("il", &[9, 2]),
        ("wrch", &[23, 9]),
        ("rdch", &[10, 24]),
        ("il", &[3, 12]),
        ("lqd", &[11, 0, 5]),
        ("fm", &[12, 11, 11]),
        ("fm", &[12, 12, 12]),
        ("ai", &[3, 3, -1]),
        ("fa", &[13, 12, 13]),
        ("brnz", &[3, 4 * 17]),
        ("stop", &[0x2000]),
    ]);
    let fresh = |engine, timing: bool| {
        let mut spu = Spu::new(0);
        spu.set_engine(engine);
        if timing {
            spu.enable_timing(Default::default());
        }
        spu.load_image(&image);
        spu
    };
    let state = |spu: &Spu| {
        (
            spu.pc(),
            spu.instructions(),
            spu.cycles(),
            (0..16).map(|r| spu.reg(r)).collect::<Vec<_>>(),
            spu.timing()
                .map(|t| (t.cycles(), t.finish_profile().totals)),
        )
    };
    for engine in [spu_isa::jit::Engine::Interp, spu_isa::jit::Engine::Jit] {
        for timing in [false, true] {
            let mut whole = fresh(engine, timing);
            let mut mem = MainMemory::zeroed(4096);
            assert_eq!(whole.run(&mut mem, 1_000_000), StopReason::Stop(0x2000));
            let end = state(&whole);
            let total = whole.cycles();
            assert!(total > 100, "{engine:?} timing {timing}: {total}");
            let mut last_instructions = 0;
            for limit in (1..total).step_by(if timing { 1 } else { 3 }) {
                let mut spu = fresh(engine, timing);
                let mut mem = MainMemory::zeroed(4096);
                let what = format!("{engine:?}, timing {timing}, limit {limit}");
                assert_eq!(spu.run(&mut mem, limit), StopReason::CycleLimit, "{what}");
                assert_eq!(spu.cycles(), limit, "{what}");
                if let Some(t) = spu.timing() {
                    assert!(t.cycles() <= limit, "{what}: model at {}", t.cycles());
                }
                assert!(spu.instructions() >= last_instructions, "{what}");
                last_instructions = spu.instructions();
                assert_eq!(
                    spu.run(&mut mem, 1_000_000),
                    StopReason::Stop(0x2000),
                    "{what}"
                );
                assert_eq!(state(&spu), end, "{what}");
            }
        }
    }
}
