//! Snapshots of the simulated SPU's register file and a local-store digest after small
//! programs, so any change in the core's behaviour shows up as a snapshot diff.

use spu_isa::machine::{MainMemory, Spu};

fn run(src: &str) -> String {
    let src = format!("        .text\n        .global _start\n_start:\n{src}\n        stop 0x2a\n");
    let out = spu_asm::assemble(&src, "snap.s", &Default::default()).expect("assembles");
    let mut spu = Spu::new(0);
    spu.load_image(&out.image);
    spu.set_pc(out.entry);
    let mut mem = MainMemory::zeroed(4096);
    let stop = spu.run(&mut mem, 1_000_000);
    let mut text = format!(
        "stop: {stop}\ninstructions: {}\ncycles: {}\n",
        spu.instructions(),
        spu.cycles()
    );
    for n in 0..128 {
        let r = spu.reg(n);
        if r != [0; 4] {
            text += &format!(
                "${n}: {:08x} {:08x} {:08x} {:08x}\n",
                r[0], r[1], r[2], r[3]
            );
        }
    }
    // FNV-1a over the whole local store.
    let digest = spu.ls().iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ *b as u64).wrapping_mul(0x100_0000_01b3)
    });
    text += &format!("ls fnv1a: {digest:016x}\n");
    text
}

#[test]
fn integer_and_shuffle_program() {
    insta::assert_snapshot!(run("
        il      $3, -7
        ilhu    $4, 0x1234
        iohl    $4, 0x5678
        a       $5, $3, $4
        sf      $6, $3, $4
        mpy     $7, $3, $4
        mpyhh   $8, $4, $4
        clz     $9, $4
        cntb    $10, $4
        rotqbyi $11, $4, 3
        shlqbyi $12, $4, 5
        rotmi   $13, $4, -4
        rotmai  $14, $3, -1
        ila     $15, 0x10203
        shufb   $16, $4, $3, $15
        fsmbi   $17, 0xa5f0
        selb    $18, $3, $4, $17
        gbb     $19, $17
        cwd     $20, 4($1)
        xswd    $21, $3
        sumb    $22, $4, $3
        cg      $23, $3, $4
        bg      $24, $3, $4
        ila     $25, 0x1000
        stqd    $16, 0($25)
        stqd    $18, 16($25)
        lqd     $26, 16($25)
        brsl    $27, sub
        ai      $28, $28, 1
        br      done
sub:    il      $28, 100
        bi      $27
done:   nop
"));
}

#[test]
fn float_program() {
    insta::assert_snapshot!(run("
        ilhu    $3, 0x3f80
        ilhu    $4, 0x4040
        fa      $5, $3, $4
        fs      $6, $3, $4
        fm      $7, $4, $4
        fma     $8, $4, $4, $3
        fnms    $9, $4, $4, $3
        frest   $10, $4
        fi      $11, $4, $10
        frsqest $12, $4
        cflts   $13, $7, 4
        csflt   $14, $13, 4
        fcgt    $15, $4, $3
        ilhu    $16, 0x7f80
        fa      $17, $16, $16
        fesd    $18, $4
        dfm     $19, $18, $18
        dfa     $20, $19, $18
        frds    $21, $20
        fscrrd  $22
"));
}
