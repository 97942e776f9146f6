//! The core replays a memoized block in one go (`Spu::replay_block`): for real programs run
//! on the simulated SPU, that must give exactly what timing every instruction does — the
//! same registers, cycles, totals and per-address counters.

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::timing::TimingConfig;

/// Loops with hints, loads, stores, shuffles, double precision, a data-dependent inner
/// trip count, a call, and a store that rewrites an instruction later in its own block
/// (the replay must hand the rest of that block back to the per-instruction path).
const PROGRAM: &str = "
        .text
        .global _start
_start: ila     $3, data
        il      $9, 40                  # outer iterations
        il      $20, 0
        ilhu    $21, 0x3f80
outer:  andi    $8, $9, 7
        ai      $8, $8, 1               # inner trip count 1..8
        hbrr    .Linner_br, inner
inner:  lqd     $5, 0($3)
        lqd     $6, 16($3)
        fma     $7, $5, $6, $7
        shufb   $10, $5, $6, $11
        a       $20, $20, $10
        dfa     $12, $12, $13
        stqd    $7, 32($3)
        ai      $8, $8, -1
.Linner_br:
        brnz    $8, inner
        brsl    $0, sub
        ila     $14, patch              # rewrite the `ai $15, $15, 1` below...
        lqd     $16, 0($14)
        ila     $17, newword
        lqd     $18, 0($17)
        stqd    $18, 0($14)             # ... with `ai $15, $15, 2`, in this very block
        .align  4
patch:  ai      $15, $15, 1
        lnop
        nop
        lnop
        stqd    $16, 0($14)             # and back
        br      1f                      # (a block of its own from here)
1:      ila     $24, patch2             # rewrite a later quadword of this block with
        lqd     $25, 0($24)             # what it already holds: the block replays up
        stqd    $25, 0($24)             # to here, then goes the long way
        .align  4
patch2: ai      $26, $26, 3
        lnop
        ai      $9, $9, -1
        brnz    $9, outer
        stop    0x2000
sub:    fa      $22, $22, $21
        fm      $23, $22, $21
        bi      $0
        .align  4
newword: ai     $15, $15, 2
        lnop
        nop
        lnop
        .data
        .align  4
data:   .float  1.5, 2.0, 0.5, 3.0, 0.25, 1.0, 2.0, 4.0
        .space  16
";

fn run(memoize: bool) -> (Spu, spu_isa::profile::Profile) {
    let program = spu_asm::assemble(PROGRAM, "memo.s", &Default::default()).expect("assembles");
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    spu.enable_timing(TimingConfig {
        memoize,
        ..Default::default()
    });
    let mut memory = MainMemory::zeroed(4096);
    assert_eq!(spu.run(&mut memory, 10_000_000), StopReason::Stop(0x2000));
    let profile = spu.timing().expect("timing").finish_profile();
    (spu, profile)
}

#[test]
fn replayed_blocks_match_the_per_instruction_model() {
    let (a, pa) = run(false);
    let (b, pb) = run(true);
    for r in 0..128 {
        assert_eq!(a.reg(r), b.reg(r), "${r}");
    }
    // The patched instruction ran 40 times with the new word: $15 = 40 * 2.
    assert_eq!(a.reg(15)[0], 80);
    assert_eq!(a.reg(26)[0], 120);
    assert_eq!(
        (a.instructions(), a.cycles()),
        (b.instructions(), b.cycles())
    );
    assert_eq!(pa.totals, pb.totals);
    let sa: Vec<_> = pa.addresses().map(|(pc, s)| (pc, *s)).collect();
    let sb: Vec<_> = pb.addresses().map(|(pc, s)| (pc, *s)).collect();
    assert_eq!(sa, sb);
}
