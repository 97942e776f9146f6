//! A bad program never panics the host: random instruction streams (biased toward real
//! opcodes, with channel instructions and MFC commands carrying random operands) run on
//! the simulated SPU with and without the timing model, alone and as a pair sharing main
//! memory in quanta. Every run must end in a `StopReason`.

use spu_isa::machine::{apply_quantum, MainMemory, Spu, StopReason};
use spu_isa::table::Op;

use spu_tests::XorShift as Rng;

/// A random program: mostly random real opcodes with random fields, a good share of
/// `wrch`/`rdch`/`rchcnt` on the MFC and event channels, `il`/`ila` to make plausible
/// addresses, and some raw random words.
fn program(rng: &mut Rng, words: usize) -> Vec<u8> {
    let mut image = Vec::with_capacity(words * 4);
    for _ in 0..words {
        let r = rng.next();
        let word = match r % 8 {
            0 => rng.next() as u32,
            1 | 2 => {
                // A channel instruction on channels 0..31 with a register in 0..7.
                let op = [Op::Wrch, Op::Rdch, Op::Rchcnt][(r >> 8) as usize % 3];
                ((op.info().opcode11 as u32) << 21)
                    | (((r >> 16) as u32 % 32) << 7)
                    | ((r >> 24) as u32 % 8)
            }
            3 => {
                // il/ila into registers 0..7 with small values (sizes, tags, commands).
                let v = [
                    16u32, 128, 0x40, 0x20, 0x44, 0xd0, 0xb4, 0xb0, 8, 4, 0x1000, 0x7000, 2, 1, 0,
                    3,
                ][(r >> 8) as usize % 16];
                ((Op::Ila.info().opcode11 as u32) << 21) | (v << 7) | ((r >> 24) as u32 % 8)
            }
            _ => {
                let op = Op::ALL[(r >> 8) as usize % Op::ALL.len()];
                let info = op.info();
                let mask = (info.format.opcode_mask() as u32) << 21;
                ((info.opcode11 as u32) << 21) | (rng.next() as u32 & !mask)
            }
        };
        image.extend(word.to_be_bytes());
    }
    image
}

#[test]
fn random_programs_end_in_a_stop_reason() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut kinds = std::collections::BTreeMap::new();
    for seed in 0..std::env::var("CORE_FUZZ")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300u32)
    {
        let image = program(&mut rng, 2048);
        let mut spu = Spu::new(0);
        spu.load_image(&image);
        if seed % 3 == 0 {
            spu.enable_timing(Default::default());
        }
        if seed % 5 == 0 {
            spu.write_inbound_mailbox(seed);
            spu.write_signal(1, 7);
        }
        let mut mem = MainMemory::zeroed(64 * 1024);
        let stop = spu.run(&mut mem, 20_000);
        let kind = format!("{stop:?}");
        *kinds
            .entry(kind.split([' ', '(', '{']).next().unwrap().to_string())
            .or_insert(0) += 1;
    }
    // The random programs reach many kinds of stop.
    assert!(kinds.len() >= 4, "{kinds:?}");
}

#[test]
fn random_program_pairs_share_memory_in_quanta() {
    let mut rng = Rng(0xfeed_beef_0bad_f00d);
    for _ in 0..std::env::var("CORE_FUZZ")
        .ok()
        .and_then(|v| v.parse::<u32>().ok())
        .map_or(60, |n| n / 5)
    {
        let mut spus = [Spu::new(0), Spu::new(1)];
        for spu in &mut spus {
            spu.load_image(&program(&mut rng, 1024));
            spu.host_feeds = true;
        }
        let mut mem = MainMemory::zeroed(64 * 1024);
        let mut done = [false; 2];
        let mut until = 0;
        while until < 20_000 && !(done[0] && done[1]) {
            until += 1000;
            for (i, spu) in spus.iter_mut().enumerate() {
                if !done[i] {
                    match spu.run_quantum(&mem, until) {
                        None | Some(StopReason::Blocked { .. }) => {}
                        Some(_) => done[i] = true,
                    }
                }
            }
            apply_quantum(&mut spus, &mut mem);
        }
    }
}

/// A channel the SPU does not have, or one used in the wrong direction, stops the SPU with
/// the hardware's invalid-channel status at that instruction; `rchcnt` works on every
/// channel that exists in either direction.
#[test]
fn invalid_channels_stop_the_spu() {
    let run = |src: &str| {
        let program = spu_asm::assemble(
            &format!("\t.text\n\t.global _start\n_start:\n{src}\n\tstop 0x2000\n"),
            "ch.s",
            &Default::default(),
        )
        .expect("assembles");
        let mut spu = Spu::new(0);
        spu.load_image(&program.image);
        spu.set_pc(program.entry);
        let stop = spu.run(&mut MainMemory::zeroed(4096), 1_000_000);
        (stop, spu.reg(3)[0])
    };
    // rdch of an unimplemented channel (5), of a write channel (SPU_WrOutMbox, 28).
    assert_eq!(
        run("\tnop\n\trdch $3, $ch5").0,
        StopReason::InvalidChannel { pc: 4, channel: 5 }
    );
    assert_eq!(
        run("\trdch $3, $ch28").0,
        StopReason::InvalidChannel { pc: 0, channel: 28 }
    );
    // wrch of a read channel (SPU_RdEventStat, 0) and of channel 64.
    assert_eq!(
        run("\twrch $ch0, $3").0,
        StopReason::InvalidChannel { pc: 0, channel: 0 }
    );
    assert_eq!(
        run("\twrch $ch64, $3").0,
        StopReason::InvalidChannel { pc: 0, channel: 64 }
    );
    // rchcnt: a write channel with room (the outbound mailbox: 1), a missing channel.
    assert_eq!(run("\trchcnt $3, $ch28"), (StopReason::Stop(0x2000), 1));
    assert_eq!(
        run("\trchcnt $3, $ch31").0,
        StopReason::InvalidChannel { pc: 0, channel: 31 }
    );
    // The report names channel and address.
    assert_eq!(
        StopReason::InvalidChannel { pc: 8, channel: 5 }.to_string(),
        "invalid channel 5 at 0x8"
    );
}
