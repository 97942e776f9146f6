//! Two SPUs play ping-pong through the host: each reads a word from its inbound mailbox,
//! adds one and mails it back, ten times; the host passes each word to the other SPU. At
//! the end each SPU DMAs its last word into a main-memory region the host owns.
//!
//! `cargo run --release -p spu-spe --example ping_pong` (`cargo test` runs it too).

use spu_spe::{Channel, ContextConfig, Outcome, Start, System};

/// Each SPU: ten rounds of mailbox in, add one, mailbox out; then the last word to main
/// memory at argp (`$4`, a 64-bit address: its low word moved to the preferred slot) with a
/// `put`, and exit.
const PLAYER: &str = "
_start: il      $10, 10
        shlqbyi $20, $4, 4
round:  rdch    $5, $SPU_RdInMbox
        ai      $5, $5, 1
        wrch    $SPU_WrOutMbox, $5
        ai      $10, $10, -1
        brnz    $10, round
        stqa    $5, 0x2000
        il      $6, 0x2000
        wrch    $MFC_LSA, $6
        il      $7, 0
        wrch    $MFC_EAH, $7
        wrch    $MFC_EAL, $20
        il      $8, 16
        wrch    $MFC_Size, $8
        wrch    $MFC_TagID, $7
        il      $9, 0x20
        wrch    $MFC_Cmd, $9
        il      $11, 1
        wrch    $MFC_WrTagMask, $11
        il      $12, 2
        wrch    $MFC_WrTagUpdate, $12
        rdch    $13, $MFC_RdTagStat
        stop    0x2000
";

fn main() {
    let elf = spu_asm::assemble(PLAYER, "player.s", &Default::default())
        .expect("the player assembles")
        .elf;
    let mut system = System::new(4096);
    let players: Vec<_> = (0..2)
        .map(|i| {
            let spu = system.create_context(ContextConfig::default());
            let start = Start::Api {
                argp: 0x100 + 0x10 * i,
                envp: 0,
            };
            system.load_elf(spu, &elf, &start).expect("loads");
            spu
        })
        .collect();
    system.set_threads(2);
    assert!(system.write_in_mbox(players[0], 0));
    loop {
        match system.run(1_000_000) {
            Outcome::Waiting(waits) => {
                for wait in waits {
                    let me = wait.context;
                    let other = players[1 - me.0];
                    if wait.channel == Channel::OutMbox || system.in_mbox_len(other) == 0 {
                        if let Some(word) = system.read_out_mbox(me) {
                            assert!(system.write_in_mbox(other, word));
                        }
                    }
                }
            }
            Outcome::Stopped => break,
            other => panic!("the game stopped: {other:?}"),
        }
        // Words the SPUs mailed without waiting go across too.
        for &me in &players {
            if let Some(word) = system.read_out_mbox(me) {
                assert!(system.write_in_mbox(players[1 - me.0], word));
            }
        }
    }
    let word = |at: u64| {
        let b = system.memory().read_bytes(at, 4).expect("in main memory");
        u32::from_be_bytes([b[0], b[1], b[2], b[3]])
    };
    // The ball went 0, 1, 2, ... 19, 20: SPU 0 sent the odd words, SPU 1 the even ones.
    println!(
        "SPU 0's last word: {}, SPU 1's: {}",
        word(0x100),
        word(0x110)
    );
    assert_eq!((word(0x100), word(0x110)), (19, 20));
}

#[test]
fn the_game_ends_with_19_and_20() {
    main();
}
