//! The core replays memoized blocks in one go (`Spu::run_block_replays`,
//! `Spu::replay_block`): for real programs run on the simulated SPU, that must give
//! exactly what timing every instruction does — the same registers, cycles, totals and
//! per-address counters.

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::profile::Profile;
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

/// Assembles `src` and runs it with the timing model, memoized or not, to `stop 0x2000`.
fn timed_run(src: &str, memoize: bool) -> (Spu, Profile) {
    let program = spu_asm::assemble(src, "memo.s", &Default::default())
        .unwrap_or_else(|d| panic!("{d:?}\n{src}"));
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    spu.enable_timing(TimingConfig {
        memoize,
        ..Default::default()
    });
    let mut memory = MainMemory::zeroed(4096);
    assert_eq!(
        spu.run(&mut memory, 10_000_000),
        StopReason::Stop(0x2000),
        "{src}"
    );
    let profile = spu.timing().expect("timing").finish_profile();
    (spu, profile)
}

/// Runs `src` without and with memoization: the same registers, instructions, cycles,
/// totals and per-address counters. Returns the memoized run.
fn same_both_ways(src: &str) -> (Spu, Profile) {
    let (a, pa) = timed_run(src, false);
    let (b, pb) = timed_run(src, true);
    for r in 0..128 {
        assert_eq!(a.reg(r), b.reg(r), "${r}\n{src}");
    }
    assert_eq!(
        (a.instructions(), a.cycles()),
        (b.instructions(), b.cycles()),
        "{src}"
    );
    assert_eq!(pa.totals, pb.totals, "{src}");
    let sa: Vec<_> = pa.addresses().map(|(pc, s)| (pc, *s)).collect();
    let sb: Vec<_> = pb.addresses().map(|(pc, s)| (pc, *s)).collect();
    assert_eq!(sa, sb, "{src}");
    (b, pb)
}

#[test]
fn replayed_blocks_match_the_per_instruction_model() {
    let (b, _) = same_both_ways(PROGRAM);
    // The patched instruction ran 40 times with the new word: $15 = 40 * 2.
    assert_eq!(b.reg(15)[0], 80);
    assert_eq!(b.reg(26)[0], 120);
}

/// Random programs with loops: blocks of random arithmetic, float, shuffle, load/store and
/// double-precision instructions, hints that are right, wrong or too close, and branches
/// that depend on the data, run with and without block memoization (replays, chains,
/// deferred register writes): the same registers, cycles, totals and per-address
/// counters, program after program.
#[test]
fn random_looping_programs_time_the_same_with_and_without_memoization() {
    use spu_tests::{looping_program, LoopShape, XorShift as Rng};
    let reg = |rng: &mut Rng| 10 + rng.below(12);
    let mut body_op = |rng: &mut Rng| -> String {
        let (t, a, b, c) = (reg(rng), reg(rng), reg(rng), reg(rng));
        match rng.below(16) {
            0 => format!("a ${t}, ${a}, ${b}"),
            1 => format!("ai ${t}, ${a}, {}", rng.below(64) as i64 - 32),
            2 => format!("fa ${t}, ${a}, ${b}"),
            3 => format!("fm ${t}, ${a}, ${b}"),
            4 => format!("fma ${t}, ${a}, ${b}, ${c}"),
            5 => format!("shufb ${t}, ${a}, ${b}, ${c}"),
            6 => format!("lqd ${t}, {}($3)", 16 * rng.below(8)),
            7 => format!("stqd ${t}, {}($3)", 16 * rng.below(8)),
            8 => format!("rotqby ${t}, ${a}, ${b}"),
            9 => format!("selb ${t}, ${a}, ${b}, ${c}"),
            10 => format!("dfa ${t}, ${a}, ${b}"),
            11 => "nop".into(),
            12 => "lnop".into(),
            13 => format!("ceq ${t}, ${a}, ${b}"),
            14 => format!("xor ${t}, ${a}, ${b}"),
            _ => format!("mpy ${t}, ${a}, ${b}"),
        }
    };
    let mut replays = 0;
    let shape = LoopShape {
        trips: 3000,
        prologue: "",
        before: 14,
        after: 6,
        conditions: &["brnz", "brz", "brhnz"],
        calls: false,
        raw_words: false,
    };
    for seed in 1..=24u64 {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed.wrapping_mul(0x1234_5678_9abc));
        let src = looping_program(&mut rng, &shape, &mut body_op);
        let (b, _) = same_both_ways(&src);
        replays += b.timing().expect("timing").memo_stats().1;
    }
    assert!(replays > 10_000, "only {replays} block replays");
}

/// Deferred register writes at the core's block replays: block X ends with a 6-cycle `fm`
/// into $20 and a hinted branch to B, block Y ends with an `ai` elsewhere and a hinted
/// branch to B; B writes neither and C reads $20 at once, stalling only after X. The
/// rounds take X four times, then Y four times, and so on, so X, Y, B and C all replay;
/// X's write waits in the deferred writes across B's replay until C needs it.
#[test]
fn deferred_writes_survive_a_replayed_block_that_writes_other_registers() {
    let mut src = String::from(
        "        .text\n        .global _start\n_start: il $4, 32\n il $9, 1\n\
         ilhu $21, 0x3f80\nloop: andi $10, $4, 4\n brz $10, y\n\
         x: hbrr .Lx, b\n",
    );
    // Twelve cycles of filler: the hints' 11-cycle window has run out by the branches.
    src += &" il $30, 1\n".repeat(12);
    src += " fm $20, $21, $21\n.Lx: br b\ny: hbrr .Ly, b\n";
    src += &" il $30, 1\n".repeat(12);
    src += " ai $23, $23, 1\n.Ly: br b\n";
    src += "b: ai $7, $7, 1\n brz $9, end\n";
    src += "c: fa $22, $20, $20\n ai $4, $4, -1\n brnz $4, loop\nend: stop 0x2000\n";
    let (b, pb) = same_both_ways(&src);
    // C's `fa` (after 5 + 1 + 12 + 2 + 1 + 12 + 2 + 2 words) stalls 3 cycles after X
    // (16 rounds), none after Y.
    let fa = pb.get(4 * 37).expect("C was run");
    assert_eq!((fa.executions, fa.stall_total()), (32, 16 * 3), "{fa:?}");
    // (The count covers the records still in place; C's are replaced at each switch.)
    let replays = b.timing().expect("timing").memo_stats().1;
    assert!(replays > 0, "{replays} replays");
}

/// DMA moving 2 KiB into local store (a local-store cycle every 16) before each of six
/// loops whose blocks cross instruction lines (fetch probes) and start in several states
/// (a data-dependent trip count, a double-precision block before the first loop on every
/// other pass): blocks are recorded while DMA cycles are pending, and some of their
/// probes meet one (the record then ends before that instruction); blocks replay with
/// DMA cycles ahead that miss every probe, or go the long way when one meets a probe.
#[test]
fn blocks_record_and_replay_around_dma_cycles_exactly() {
    const OPS: [&str; 9] = [
        "a $20, $20, $10",
        "lqd $5, 0($3)",
        "fma $7, $5, $6, $7",
        "shufb $10, $5, $6, $11",
        "lqd $6, 16($3)",
        "fa $22, $22, $21",
        "stqd $7, 32($3)",
        "xor $23, $23, $20",
        "mpy $24, $20, $9",
    ];
    let mut src = String::from(
        "        .text\n        .global _start\n_start: ila $3, data\n il $9, 48\n\
         ilhu $21, 0x3f80\n ila $11, 0x10203\nouter: andi $30, $9, 1\n brz $30, 1f\n\
         dfa $40, $41, $42\n1:\n",
    );
    for k in 0..6 {
        src += " il $70, 0x4000\n wrch $MFC_LSA, $70\n il $70, 0\n wrch $MFC_EAH, $70\n\
                wrch $MFC_EAL, $70\n il $70, 2048\n wrch $MFC_Size, $70\n il $70, 1\n\
                wrch $MFC_TagID, $70\n il $70, 0x40\n wrch $MFC_Cmd, $70\n\
                andi $8, $9, 7\n ai $8, $8, 6\n";
        src += &format!("inner{k}:\n");
        for j in 0..36 + 3 * k {
            src += &format!(" {}\n", OPS[(j * 5 + k) % OPS.len()]);
        }
        src += &format!(" ai $8, $8, -1\n brnz $8, inner{k}\n");
        src += " il $70, 2\n wrch $MFC_WrTagMask, $70\n wrch $MFC_WrTagUpdate, $70\n\
                rdch $31, $MFC_RdTagStat\n";
    }
    src += " ai $9, $9, -1\n brnz $9, outer\n stop 0x2000\n .data\n .align 4\n\
            data: .float 1.5, 2.0, 0.5, 3.0, 0.25, 1.0, 2.0, 4.0\n .space 16\n";
    let (b, p) = same_both_ways(&src);
    assert_eq!(b.reg(9)[0], 0);
    assert!(p.totals.dma_contention > 0, "{:?}", p.totals);
}

/// A loop like the ray tracer's: a register-form hint (`hbr`) predicts a computed branch
/// (`bi`) to one of four entries, a different one each pass, whose unhinted branches all
/// miss into one joining block, entered after each of them with other registers still in
/// flight. The block holding the `hbr` must replay although the hint names another target
/// each time (the target only decides whether the branch resolving after it was
/// predicted, and a replay takes it from the core), and so must the joining block
/// although the branch-miss wait at its entry goes to another branch each time (and it
/// starts in more states than two): the same registers, cycles and counters as timing
/// every instruction, and every block start keeps its records.
#[test]
fn computed_hinted_branches_and_their_misses_replay_exactly() {
    let src = "
        .text
        .global _start
_start: ila     $11, e0
        il      $9, 400
        ilhu    $21, 0x3f80
loop:   andi    $8, $9, 3
        shli    $8, $8, 4
        a       $10, $11, $8
        hbr     jump, $10
        a       $20, $20, $9
        xor     $23, $23, $20
        fa      $22, $22, $21
        ai      $25, $25, 3
        mpy     $26, $20, $9
        fm      $27, $22, $21
        ai      $28, $28, 1
jump:   bi      $10
        .align  4
e0:     ai      $30, $30, 1
        br      join
        nop
        lnop
e1:     fm      $24, $22, $21
        br      join
        nop
        lnop
e2:     mpy     $31, $9, $9
        br      join
        nop
        lnop
e3:     ai      $32, $32, 2
        br      join
        nop
        lnop
join:   fa      $24, $24, $21
        a       $33, $33, $31
        ai      $9, $9, -1
        brnz    $9, loop
        stop    0x2000
";
    let (b, p) = same_both_ways(src);
    assert_eq!(b.reg(30)[0], 100);
    assert_eq!(b.reg(32)[0], 200);
    // The four entries' branches miss into `join` every pass and so does the unhinted
    // branch back to `loop`; the computed branch is predicted every time.
    assert_eq!(p.totals.branch_misses, 400 + 399, "{:?}", p.totals);
    assert_eq!(p.totals.hint_hits, 400, "{:?}", p.totals);
    let (_, replays, given_up) = b.timing().expect("timing").memo_stats();
    assert_eq!(given_up, 0, "no block start given up on");
    // Three blocks a pass: the loop with its hint, an entry, the joining block.
    assert!(replays > 3 * 350, "{replays} replays");
}

/// Blocks that go on past untaken conditional branches (`brz`, `brnz`, `brhz`,
/// `brhnz`): in a loop, inner branches taken now and then (the replay stops there and
/// the branch resolves taken), one of them named by a hint on some passes (that entry
/// state must not replay the longer record), and a self-loop whose inner branch leaves
/// it every 16th pass. The same registers, cycles and counters as timing every
/// instruction.
#[test]
fn blocks_past_untaken_branches_time_exactly() {
    let (b, p) = same_both_ways(spu_tests::UNTAKEN_BRANCHES);
    assert_eq!(b.reg(24)[0], 38, "side1 passes");
    assert_eq!(b.reg(31)[0], 18, "side3 passes (biz)");
    assert_eq!(b.reg(6)[0], 37, "side4 passes (bihnz)");
    assert_eq!(b.reg(27)[0], 200);
    assert_eq!(b.reg(29)[0], 12, "tick passes");
    assert!(p.totals.branches_not_taken > 800, "{:?}", p.totals);
}

/// An indirect conditional branch (`biz`) that stays untaken until the last pass does not
/// end its block: each pass of the loop replays as one record (two blocks a pass would
/// double the replays), exactly as timing every instruction; one that enables interrupts
/// (`bize`) still ends its block.
#[test]
fn untaken_indirect_branches_stay_inside_their_block() {
    let src = "
        .text
        .global _start
_start: il      $9, 100
        ila     $17, done
loop:   ai      $9, $9, -1
        a       $20, $20, $9
        biz     $9, $17
        a       $21, $21, $9
        br      loop
done:   stop    0x2000
";
    let (b, _) = same_both_ways(src);
    assert_eq!([b.reg(20)[0], b.reg(21)[0]], [4950, 4950]);
    let (records, replays, _) = b.timing().expect("timing").memo_stats();
    assert!(
        (95..=100).contains(&replays),
        "{records} records, {replays} replays"
    );
    let with_e = src.replace("biz     $9, $17", "bizd    $9, $17");
    let (b, _) = same_both_ways(&with_e);
    let (_, replays, _) = b.timing().expect("timing").memo_stats();
    assert!(replays > 150, "{replays} replays: a `bizd` ends its block");
}

/// The writes of an MFC command's parameters (MFC_LSA to MFC_TagID) are latches the core
/// does itself: they do not end a block, so a DMA loop's set-up is one record with the
/// code around it (six blocks a pass otherwise), and the transfers and the timing are
/// exactly those of timing every instruction.
#[test]
fn mfc_parameter_writes_stay_inside_their_block() {
    let src = "
        .text
        .global _start
_start: il      $9, 40
        ila     $3, 0x8000
loop:   ai      $9, $9, -1
        andi    $20, $9, 3
        shli    $20, $20, 7
        ai      $21, $20, 0x100
        wrch    $MFC_LSA, $3
        il      $70, 0
        wrch    $MFC_EAH, $70
        wrch    $MFC_EAL, $21
        il      $70, 128
        wrch    $MFC_Size, $70
        il      $70, 1
        wrch    $MFC_TagID, $70
        a       $24, $24, $21
        il      $70, 0x40
        wrch    $MFC_Cmd, $70
        il      $70, 2
        wrch    $MFC_WrTagMask, $70
        il      $70, 2
        wrch    $MFC_WrTagUpdate, $70
        rdch    $22, $MFC_RdTagStat
        lqd     $10, 0($3)
        a       $25, $25, $10
        brnz    $9, loop
        stop    0x2000
";
    let (b, _) = same_both_ways(src);
    assert_eq!(b.reg(22)[0], 2);
    // EAL 0x100 + 128 * (count & 3) over 40 passes.
    assert_eq!(b.reg(24)[0], 40 * 0x100 + 10 * 128 * (1 + 2 + 3));
    let (_, replays, _) = b.timing().expect("timing").memo_stats();
    // A pass: the set-up to MFC_Cmd, then one instruction between each of the three
    // channel instructions, then the tail: five records, not ten.
    assert!(replays < 6 * 40, "{replays} replays");
}
