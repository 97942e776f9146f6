//! The block compiler against the interpreter (`--engine jit` against `--engine interp`):
//! random programs (integer, float, shifts and shuffles, loads and stores, branches,
//! hints, calls), programs with channels, DMA and self-modifying code, and a kernel frame
//! give the same registers, local store, main memory, instructions, cycles, counters,
//! profiles and images, with the timing model off and on.

use spu_isa::jit::{CodeCache, Compiling, Engine};
use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::timing::TimingConfig;
use spu_tests::{looping_program, LoopShape, XorShift as Rng};

/// What a run left behind, for comparing engines.
#[derive(Debug, PartialEq)]
struct Outcome {
    stop: StopReason,
    regs: Vec<[u32; 4]>,
    fpscr: String,
    instructions: u64,
    cycles: u64,
    totals: Option<String>,
    per_address: Option<Vec<String>>,
}

/// Runs `src` on one SPU with `engine`, the timing model on or off; main memory of
/// 64 KiB filled with a pattern.
fn run(src: &str, engine: Engine, timing: bool) -> (Outcome, Spu, MainMemory) {
    run_sharing(src, engine, timing, None)
}

/// [`run`] with the SPU compiling into `cache`, if given.
fn run_sharing(
    src: &str,
    engine: Engine,
    timing: bool,
    cache: Option<&CodeCache>,
) -> (Outcome, Spu, MainMemory) {
    let program = spu_asm::assemble(src, "engines.s", &Default::default())
        .unwrap_or_else(|d| panic!("{d:?}\n{src}"));
    let mut spu = Spu::new(0);
    spu.set_engine(engine);
    if let Some(cache) = cache {
        spu.share_code(cache);
    }
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    if timing {
        spu.enable_timing(TimingConfig::default());
    }
    let mut memory = MainMemory::zeroed(64 * 1024);
    for (i, b) in memory.bytes_mut().iter_mut().enumerate() {
        *b = (i * 7 + 3) as u8;
    }
    let stop = spu.run(&mut memory, 20_000_000);
    let profile = spu.timing().map(|t| t.finish_profile());
    let outcome = Outcome {
        stop,
        regs: (0..128).map(|r| spu.reg(r)).collect(),
        fpscr: format!("{:?}", spu.fpscr()),
        instructions: spu.instructions(),
        cycles: spu.cycles(),
        totals: profile.as_ref().map(|p| format!("{:?}", p.totals)),
        per_address: profile.as_ref().map(|p| {
            p.addresses()
                .map(|(pc, s)| format!("{pc:#x}: {s:?}"))
                .collect()
        }),
    };
    (outcome, spu, memory)
}

/// Runs `src` with both engines, timing off and on: everything the same. Returns the
/// compiled runs' SPUs (timing off, on).
fn same_with_both_engines(src: &str) -> [Spu; 2] {
    [false, true].map(|timing| {
        let (a, sa, ma) = run(src, Engine::Interp, timing);
        let (b, sb, mb) = run(src, Engine::Jit, timing);
        assert_eq!(a, b, "timing {timing}\n{src}");
        assert!(
            sa.ls() == sb.ls(),
            "local store differs, timing {timing}\n{src}"
        );
        assert!(
            ma.bytes() == mb.bytes(),
            "main memory differs, timing {timing}\n{src}"
        );
        sb
    })
}

/// `same_with_both_engines`, and more than half the instructions ran compiled.
fn same_and_mostly_compiled(src: &str) {
    let [off, _] = same_with_both_engines(src);
    let stats = off.jit_stats();
    assert!(
        stats.compiled_instructions > off.instructions() / 2,
        "{} of {} ran compiled",
        stats.compiled_instructions,
        off.instructions()
    );
}

/// A random instruction on registers $10..$21 ($3 points at the data, $5 holds a small
/// data offset).
fn random_op(rng: &mut Rng) -> String {
    let reg = |rng: &mut Rng| 10 + rng.below(12);
    let (t, a, b, c) = (reg(rng), reg(rng), reg(rng), reg(rng));
    let s10 = rng.below(1024) as i64 - 512;
    let u7 = rng.below(128);
    match rng.below(48) {
        0 => format!("a ${t}, ${a}, ${b}"),
        1 => format!("ai ${t}, ${a}, {s10}"),
        2 => format!("sf ${t}, ${a}, ${b}"),
        3 => format!("sfi ${t}, ${a}, {s10}"),
        4 => format!("and ${t}, ${a}, ${b}"),
        5 => format!("andc ${t}, ${a}, ${b}"),
        6 => format!("or ${t}, ${a}, ${b}"),
        7 => format!("orc ${t}, ${a}, ${b}"),
        8 => format!("xor ${t}, ${a}, ${b}"),
        9 => format!(
            "{} ${t}, ${a}, ${b}",
            ["nand", "nor", "eqv"][rng.below(3) as usize]
        ),
        10 => format!(
            "{} ${t}, ${a}, {s10}",
            ["andi", "ori", "xori"][rng.below(3) as usize]
        ),
        11 => format!(
            "{} ${t}, ${a}, ${b}",
            ["ceq", "cgt", "clgt"][rng.below(3) as usize]
        ),
        12 => format!(
            "{} ${t}, ${a}, {s10}",
            ["ceqi", "cgti", "clgti"][rng.below(3) as usize]
        ),
        13 => format!("il ${t}, {}", rng.below(65536) as i64 - 32768),
        14 => format!("ilhu ${t}, {}", rng.below(65536)),
        15 => format!("iohl ${t}, {}", rng.below(65536)),
        16 => format!("ila ${t}, {}", rng.below(1 << 18)),
        17 => format!("ilh ${t}, {}", rng.below(65536)),
        18 => format!("fsmbi ${t}, {}", rng.below(65536)),
        19 => format!("shli ${t}, ${a}, {u7}"),
        20 => format!("rotmi ${t}, ${a}, {}", -(rng.below(64) as i64)),
        21 => format!("rotmai ${t}, ${a}, {}", -(rng.below(64) as i64)),
        22 => format!("roti ${t}, ${a}, {}", rng.below(64) as i64 - 32),
        23 => format!("rotqbyi ${t}, ${a}, {}", rng.below(32)),
        24 => format!("shlqbyi ${t}, ${a}, {}", rng.below(32)),
        25 => format!("rotqmbyi ${t}, ${a}, {}", -(rng.below(32) as i64)),
        26 => format!("selb ${t}, ${a}, ${b}, ${c}"),
        27 | 28 => format!("shufb ${t}, ${a}, ${b}, ${c}"),
        29 => format!("fa ${t}, ${a}, ${b}"),
        30 => format!("fs ${t}, ${a}, ${b}"),
        31 => format!("fm ${t}, ${a}, ${b}"),
        32 => format!("fma ${t}, ${a}, ${b}, ${c}"),
        33 => format!("fnms ${t}, ${a}, ${b}, ${c}"),
        34 => format!("fms ${t}, ${a}, ${b}, ${c}"),
        35 => format!(
            "{} ${t}, ${a}, ${b}",
            ["fcgt", "fceq", "fcmgt", "fcmeq"][rng.below(4) as usize]
        ),
        36 => format!("{} ${t}, ${a}", ["frest", "frsqest"][rng.below(2) as usize]),
        37 => format!("fi ${t}, ${a}, ${b}"),
        38 => format!(
            "{} ${t}, ${a}, {}",
            ["cfltu", "cflts"][rng.below(2) as usize],
            rng.below(128)
        ),
        39 => format!("lqd ${t}, {}($3)", 16 * rng.below(8)),
        40 => format!("stqd ${t}, {}($3)", 16 * rng.below(8)),
        41 => format!("lqx ${t}, $3, $5"),
        42 => format!("stqx ${t}, $3, $5"),
        43 => format!(
            "{} ${t}, ${a}, ${b}",
            ["rotqby", "mpy", "ah"][rng.below(3) as usize]
        ),
        44 => format!(
            "{} ${t}, ${a}",
            ["gb", "clz", "cntb"][rng.below(3) as usize]
        ),
        45 => format!("dfa ${t}, ${a}, ${b}"),
        46 => "nop".into(),
        _ => "lnop".into(),
    }
}

/// Random programs with loops: blocks of random instructions, hints right, wrong or
/// absent, data-dependent branches and a call.
#[test]
fn random_programs_run_the_same_compiled() {
    let mut compiled = 0;
    let shape = LoopShape {
        trips: 600,
        prologue: " il $5, 80\n",
        before: 16,
        after: 8,
        conditions: &["brnz", "brz", "brhnz", "brhz"],
        calls: true,
        raw_words: true,
    };
    for seed in 1..=16u64 {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d ^ seed.wrapping_mul(0x9e37_79b9));
        let src = looping_program(&mut rng, &shape, &mut random_op);
        let [off, _] = same_with_both_engines(&src);
        compiled += off.jit_stats().compiled_instructions;
    }
    assert!(
        compiled > 10_000,
        "only {compiled} instructions ran compiled"
    );
}

/// A code cache compiling on a thread of its own: while a block waits in its queue the
/// SPU interprets it, and the results are the same whatever ran compiled; once the
/// compiler finished, a program run again sharing the cache runs mostly compiled.
#[test]
fn a_background_compiler_gives_the_same_results() {
    if !Engine::SUPPORTED {
        return;
    }
    let shape = LoopShape {
        trips: 600,
        prologue: " il $5, 80\n",
        before: 16,
        after: 8,
        conditions: &["brnz", "brz"],
        calls: true,
        raw_words: false,
    };
    let mut rng = Rng(0x5eed_0b5e_55ed);
    let src = looping_program(&mut rng, &shape, &mut random_op);
    for timing in [false, true] {
        let (reference, _, memory) = run(&src, Engine::Interp, timing);
        let cache = CodeCache::with(Compiling::Background);
        let (first, _, first_memory) = run_sharing(&src, Engine::Jit, timing, Some(&cache));
        assert_eq!(reference, first, "timing {timing}");
        assert!(memory.bytes() == first_memory.bytes());
        // The blocks asked for are compiled by now, or soon.
        let asked = cache.stats();
        let started = std::time::Instant::now();
        while cache.completed() == 0 && started.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
        assert!(cache.completed() > 0, "nothing compiled ({asked:?})");
        let (again, spu, _) = run_sharing(&src, Engine::Jit, timing, Some(&cache));
        assert_eq!(reference, again, "timing {timing}");
        assert!(
            spu.jit_stats().compiled_instructions > 0,
            "timing {timing}: nothing ran compiled"
        );
    }
}

/// Stores that rewrite code: an instruction later in the same block (the block must end
/// and the new word run), a quadword of the block with what it already holds, and a
/// called routine rewritten between calls.
#[test]
fn self_modifying_code_runs_the_same_compiled() {
    let src = "
        .text
        .global _start
_start: il      $9, 40
        ila     $3, data
outer:  brsl    $0, sub
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
        br      1f
1:      ila     $24, patch2
        lqd     $25, 0($24)
        stqd    $25, 0($24)             # the same words again, later in this block
        .align  4
patch2: ai      $26, $26, 3
        lnop
        ila     $27, subbody            # the routine alternates between two bodies
        andi    $28, $9, 1
        shli    $28, $28, 4
        ila     $29, bodies
        lqx     $30, $29, $28
        stqd    $30, 0($27)
        ai      $9, $9, -1
        brnz    $9, outer
        stop    0x2000
        .align  4
sub:    nop
        lnop
        nop
        lnop
subbody: ai     $31, $31, 5
        lnop
        nop
        bi      $0
        .align  4
newword: ai     $15, $15, 2
        lnop
        nop
        lnop
bodies: ai      $31, $31, 7
        lnop
        nop
        bi      $0
        ai      $31, $31, 11
        lnop
        nop
        bi      $0
        .data
        .align  4
data:   .space  64
";
    let [off, on] = same_with_both_engines(src);
    // The patched instruction ran 40 times with the new word, the routine 40 times with
    // bodies chosen by the count's parity (the first call with its original body).
    for spu in [&off, &on] {
        assert_eq!(spu.reg(15)[0], 80);
        assert_eq!(spu.reg(26)[0], 120);
        assert_eq!(spu.reg(31)[0], 5 + 20 * 7 + 19 * 11);
    }
    assert!(off.jit_stats().compiled_instructions > 0);
}

/// A block that branches back to its own start runs pass after pass inside its compiled
/// code; at pass 101 of 200 it stores a new first quadword over itself (`ai $15, $15, 1`
/// becomes `ai $15, $15, 2`), after which the next pass must run the new words.
#[test]
fn a_self_loop_that_rewrites_itself_runs_the_same_compiled() {
    let src = "
        .text
        .global _start
_start: il      $9, 200
        ila     $3, scratch
        ila     $4, loop
        ila     $5, newword
        lqd     $6, 0($5)
        .align  4
loop:   ai      $15, $15, 1
        ceqi    $20, $9, 100            # pass 101 (of 200, counting down)
        selb    $22, $3, $4, $20        # ... stores over `loop`, other passes elsewhere
        stqd    $6, 0($22)
        ai      $9, $9, -1
        brnz    $9, loop
        stop    0x2000
        .align  4
newword: ai     $15, $15, 2
        ceqi    $20, $9, 100
        selb    $22, $3, $4, $20
        stqd    $6, 0($22)
        .data
        .align  4
scratch: .space 16
";
    let [off, on] = same_with_both_engines(src);
    for spu in [&off, &on] {
        assert_eq!(spu.reg(15)[0], 101 + 2 * 99);
    }
    assert!(off.jit_stats().compiled_instructions > 100);
}

/// A program around `body` ($3 points at eight floats and a free quadword, $8 = 40,
/// $10 = 1.0, $11 a shuffle pattern, $30 = 3), ending with `stop 0x2000`.
fn steady_loop(body: &str) -> String {
    format!(
        "        .text\n        .global _start\n_start: ila $3, data\n il $8, 40\n\
         ilhu $10, 0x3f80\n ila $11, 0x10203\n il $30, 3\n{body}\n stop 0x2000\n\
         .data\n .align 4\ndata: .float 1.5, 2.0, 0.5, 3.0, 0.25, 1.0, 2.0, 4.0\n\
         .space 16\n"
    )
}

/// Self-loops with the timing model on: once a pass leaves the state its record was
/// made in, the compiled code runs pass after pass with the record applied once for them
/// all. Each program reaches such a steady state in another way (what the state settles
/// on: the loop's own hint, a hint's distance, a miss every pass, a result and a
/// double-precision block from before the loop, DMA cycles ahead); the runs must still be
/// the interpreter's to the cycle and counter, and most passes run steady.
#[test]
fn steady_self_loops_time_the_same_compiled() {
    let programs = [
        // The benchmark's loop: its own hint, loads, float runs and a store; 3000 passes
        // over many quanta.
        " il $9, 3000\n\
         loop: hbrr .Lback, loop\n lqd $5, 0($3)\n lqd $6, 16($3)\n\
         fma $7, $5, $6, $7\n fma $8, $6, $10, $8\n shufb $12, $5, $6, $11\n\
         a $4, $4, $12\n ai $9, $9, -1\n fa $13, $7, $8\n stqd $13, 32($3)\n\
         .Lback: brnz $9, loop",
        // A hint issued before the loop (its window long past after the first pass).
        "outer: hbrr .Lin, inner\n il $9, 12\n il $24, 1\n il $25, 2\n il $26, 3\n\
         il $27, 4\n il $28, 5\ninner: ai $9, $9, -1\n.Lin: brnz $9, inner\n\
         a $21, $21, $9\n ai $8, $8, -1\n brnz $8, outer",
        // No hint at all: every pass a miss.
        "outer: il $9, 30\ninner: ai $9, $9, -1\n a $22, $22, $9\n brnz $9, inner\n\
         ai $8, $8, -1\n brnz $8, outer",
        // A long-latency result from before the loop that the loop reads and does not
        // write, a double-precision block before it, and one inside a second loop.
        "outer: il $9, 20\n dfa $40, $41, $42\n mpy $20, $30, $8\n hbrr .La, ina\n\
         ina: a $21, $21, $20\n fm $22, $22, $10\n ai $9, $9, -1\n.La: brnz $9, ina\n\
         il $9, 15\n hbrr .Lb, inb\ninb: dfa $44, $45, $46\n ai $9, $9, -1\n\
         a $23, $23, $44\n.Lb: brnz $9, inb\n ai $8, $8, -1\n brnz $8, outer",
        // A DMA moving 2 KiB into local store while a loop that loads runs: passes
        // replay only clear of its local-store cycles.
        "outer: ila $70, 0x8000\n wrch $MFC_LSA, $70\n il $70, 0\n wrch $MFC_EAH, $70\n\
         wrch $MFC_EAL, $70\n il $70, 2048\n wrch $MFC_Size, $70\n il $70, 1\n\
         wrch $MFC_TagID, $70\n il $70, 0x40\n wrch $MFC_Cmd, $70\n il $9, 300\n\
         hbrr .Ld, ind\nind: lqd $22, 0($3)\n a $21, $21, $22\n ai $9, $9, -1\n a $23, $23, $9\n\
         .Ld: brnz $9, ind\n il $70, 2\n wrch $MFC_WrTagMask, $70\n\
         wrch $MFC_WrTagUpdate, $70\n rdch $22, $MFC_RdTagStat\n ai $8, $8, -1\n\
         brnz $8, outer",
    ];
    for body in programs {
        let src = steady_loop(body);
        let [_, on] = same_with_both_engines(&src);
        assert_eq!(on.reg(9)[0], 0, "{src}");
        let steady = on.jit_stats().steady_passes;
        assert!(steady > 100, "{steady} steady passes\n{src}");
    }
}

/// Singles of every kind: zeros of both signs, denormals, ordinary values, exponent 255
/// (an ordinary number on the SPU), values that saturate or vanish when scaled.
const SPECIALS: [u32; 16] = [
    0x0000_0000,
    0x8000_0000,
    0x0000_0001,
    0x807f_ffff,
    0x3f80_0000,
    0xbf80_0000,
    0x4f00_0000,
    0xcf00_0001,
    0x7f80_0000,
    0xffff_ffff,
    0x7fff_ffff,
    0x0080_0000,
    0x4f80_0000,
    0x3eff_ffff,
    0xc2c8_0000,
    0x4b00_0001,
];

/// The single-precision compares, `fi` and the conversions to integers, which compiled
/// code does in host vector instructions, on operands of every kind: zeros of both
/// signs, denormals, ordinary values, exponent 255 (an ordinary number on the SPU) and
/// values that saturate or vanish at every scale. Everything the same as interpreted,
/// and the loop ran compiled.
#[test]
fn float_compares_and_conversions_run_the_same_compiled() {
    let mut rng = Rng(0x5eed_f10a7);
    let mut src = String::from(
        "        .text\n        .global _start\n_start: ila $3, data\n il $9, 64\n il $5, 0\n",
    );
    src += "loop: andi $6, $5, 0x1f0\n lqx $10, $3, $6\n ai $7, $6, 48\n andi $7, $7, 0x1f0\n\
            lqx $11, $3, $7\n frest $12, $10\n";
    // Each result is summed into an accumulator of its own ($40 up), rotated each pass.
    let mut acc = 40;
    let mut push = |src: &mut String, line: String| {
        *src += &format!(" {line}\n a ${acc}, ${acc}, $30\n roti ${acc}, ${acc}, 3\n");
        acc += 1;
    };
    for op in ["fcgt", "fceq", "fcmgt", "fcmeq"] {
        push(&mut src, format!("{op} $30, $10, $11"));
        push(&mut src, format!("{op} $30, $11, $10"));
        push(&mut src, format!("{op} $30, $10, $10"));
    }
    // The estimates and the divide-by-zero flags they raise, and gathered bits.
    for op in ["frest", "frsqest", "gb"] {
        push(&mut src, format!("{op} $30, $10"));
        push(&mut src, format!("{op} $30, $11"));
    }
    push(&mut src, "fscrrd $30".into());
    push(&mut src, "fi $30, $10, $12".into());
    push(&mut src, "fi $30, $11, $12".into());
    for scale in [0, 1, 20, 31, 32, 100, 127] {
        push(&mut src, format!("cflts $30, $10, {scale}"));
        push(&mut src, format!("cfltu $30, $11, {scale}"));
    }
    src += " ai $5, $5, 16\n ai $9, $9, -1\n brnz $9, loop\n stop 0x2000\n";
    src += "        .data\n        .align 4\ndata:\n";
    for k in 0..32 {
        let w = if k % 2 == 0 {
            SPECIALS[(k / 2) % 16]
        } else {
            rng.next() as u32
        };
        src += &format!(
            " .long {w}, {}, {}, {}\n",
            SPECIALS[(k + 5) % 16],
            rng.next() as u32,
            SPECIALS[(3 * k + 1) % 16]
        );
    }
    same_and_mostly_compiled(&src);
}

/// Runs of single-precision arithmetic with register-only instructions between them,
/// which compiled code checks once for the whole run: operands of every kind (zeros,
/// denormals, exponent 255, values whose products overflow or vanish) mixed with ordinary
/// quadwords, so that some passes take the fast path and others redo the whole run
/// exactly, including a run whose last operation overwrites its first one's operand.
/// Registers (the status register read back too), local store and cycles the same.
#[test]
fn float_runs_run_the_same_compiled() {
    let mut rng = Rng(0xf1_0a75);
    let mut src = String::from(
        "        .text\n        .global _start\n_start: ila $3, data\n il $9, 96\n il $5, 0\n\
         ila $13, 0x10203\n",
    );
    src += "loop: andi $6, $5, 0x1f0\n lqx $10, $3, $6\n ai $7, $6, 48\n andi $7, $7, 0x1f0\n\
            lqx $11, $3, $7\n ai $7, $6, 112\n andi $7, $7, 0x1f0\n lqx $12, $3, $7\n\
            fma $20, $10, $11, $12\n fm $21, $11, $12\n lnop\n shufb $22, $20, $21, $13\n\
            a $40, $40, $22\n fnms $23, $20, $10, $21\n fs $24, $23, $12\n roti $41, $24, 5\n\
            fms $25, $21, $11, $20\n xor $42, $42, $41\n fa $10, $25, $10\n\
            stqd $10, 1024($3)\n a $43, $43, $10\n fa $26, $11, $12\n fm $27, $26, $26\n\
            a $44, $44, $27\n ai $5, $5, 16\n ai $9, $9, -1\n brnz $9, loop\n\
            fscrrd $50\n stop 0x2000\n";
    src += "        .data\n        .align 4\ndata:\n";
    for k in 0..32 {
        let mut word = |j: usize| {
            if k % 3 == 0 && j == k % 4 {
                SPECIALS[(k + 2) % 16]
            } else {
                // An ordinary single between 2^-8 and 2^8, either sign.
                let r = rng.next() as u32;
                (r & 0x8000_0000) | (0x3b80_0000 + (r & 0x07ff_ffff))
            }
        };
        let w: Vec<u32> = (0..4).map(&mut word).collect();
        src += &format!(" .long {}, {}, {}, {}\n", w[0], w[1], w[2], w[3]);
    }
    src += " .space 1040\n";
    same_and_mostly_compiled(&src);
}

/// DMA gets and puts inside a loop of computation, tag waits, the decrementer read
/// between blocks (its value depends on the cycle), and an outbound mailbox write at the
/// end: the same registers, local store, main memory and cycles.
#[test]
fn channels_and_dma_run_the_same_compiled() {
    let mut src = String::from(
        "        .text\n        .global _start\n_start: il $9, 24\n ila $3, 0x8000\n\
         il $70, -1\n wrch $SPU_WrDec, $70\n",
    );
    src += "loop:\n";
    // get 256 bytes from EA 0x1000 + 256 * (count & 7) into 0x8000, wait.
    src += " andi $20, $9, 7\n shli $20, $20, 8\n ai $21, $20, 0x100\n shli $21, $21, 4\n";
    src += " ila $70, 0x8000\n wrch $MFC_LSA, $70\n il $70, 0\n wrch $MFC_EAH, $70\n";
    src += " wrch $MFC_EAL, $21\n il $70, 256\n wrch $MFC_Size, $70\n il $70, 1\n";
    src += " wrch $MFC_TagID, $70\n il $70, 0x40\n wrch $MFC_Cmd, $70\n";
    src += " il $70, 2\n wrch $MFC_WrTagMask, $70\n il $70, 2\n wrch $MFC_WrTagUpdate, $70\n";
    src += " rdch $22, $MFC_RdTagStat\n";
    // Compute on what arrived while nothing is in flight, then put it back elsewhere.
    src += " lqd $10, 0($3)\n lqd $11, 16($3)\n lqd $12, 32($3)\n";
    for k in 0..6 {
        src += &format!(
            " a $13, $10, $11\n xor $14, $13, $12\n shufb $15, $14, $10, $11\n\
             stqd $15, {}($3)\n rotqbyi $10, $15, {}\n",
            48 + 16 * k,
            k + 1
        );
    }
    src += " rdch $23, $SPU_RdDec\n a $24, $24, $23\n";
    src += " ila $70, 0x8000\n wrch $MFC_LSA, $70\n il $70, 0\n wrch $MFC_EAH, $70\n";
    src += " ila $25, 0x4000\n a $21, $21, $25\n wrch $MFC_EAL, $21\n il $70, 256\n wrch $MFC_Size, $70\n";
    src += " il $70, 2\n wrch $MFC_TagID, $70\n il $70, 0x20\n wrch $MFC_Cmd, $70\n";
    src += " il $70, 4\n wrch $MFC_WrTagMask, $70\n il $70, 2\n wrch $MFC_WrTagUpdate, $70\n";
    src += " rdch $22, $MFC_RdTagStat\n";
    src += " ai $9, $9, -1\n brnz $9, loop\n wrch $SPU_WrOutMbox, $24\n stop 0x2000\n";
    let [off, on] = same_with_both_engines(&src);
    for spu in [&off, &on] {
        assert_eq!(spu.reg(9)[0], 0);
        assert_eq!(spu.reg(22)[0], 4);
    }
}

/// A kernel frame (the room, 64x64, two SPUs with the timing model): the same image,
/// cycles, per-SPU counts and profile with either engine; compiled on one host thread or
/// two, the same instructions run compiled on each SPU.
#[test]
fn a_kernel_frame_is_the_same_compiled() {
    use spu_loader::render::{render, Prepared, RenderConfig};
    let room = Prepared::from_scene("room", spu_loader::procedural::room()).unwrap();
    let frame = |engine: Engine, threads: usize| {
        let config = RenderConfig {
            width: 64,
            height: 64,
            spes: 2,
            threads,
            sht: 1,
            engine,
            max_cycles: 50_000_000_000,
            ..RenderConfig::new("room")
        };
        render(&room, &config, &CodeCache::default()).unwrap().run
    };
    let a = frame(Engine::Interp, 1);
    let b = frame(Engine::Jit, 1);
    // The SPUs share one code cache; which of them compiles a block first depends on the
    // host threads, what each runs compiled does not.
    let c = frame(Engine::Jit, 2);
    let compiled = |run: &spu_loader::runtime::FrameRun| -> Vec<u64> {
        run.spus.iter().map(|s| s.compiled_instructions).collect()
    };
    assert_eq!(compiled(&a), [0, 0]);
    assert!(compiled(&b).iter().all(|&n| n > 0), "{:?}", compiled(&b));
    assert_eq!(compiled(&b), compiled(&c));
    assert_eq!(
        b.jit.compiled_instructions,
        compiled(&b).iter().sum::<u64>()
    );
    assert_eq!(
        (b.jit.blocks, b.jit.block_instructions),
        (c.jit.blocks, c.jit.block_instructions)
    );
    assert!(b.frame_buffer == c.frame_buffer && b.frame_cycles == c.frame_cycles);
    assert!(a.frame_buffer == b.frame_buffer, "images differ");
    assert_eq!(a.frame_cycles, b.frame_cycles);
    for (x, y) in a.spus.iter().zip(&b.spus) {
        assert_eq!(
            (x.cycles, x.instructions, x.tiles),
            (y.cycles, y.instructions, y.tiles)
        );
    }
    let (pa, pb) = (a.profile.unwrap(), b.profile.unwrap());
    assert_eq!(pa.totals, pb.totals);
    let per = |p: &spu_isa::profile::Profile| -> Vec<String> {
        p.addresses()
            .map(|(pc, s)| format!("{pc:#x}: {s:?}"))
            .collect()
    };
    assert_eq!(per(&pa), per(&pb));
}

/// Blocks that go on past untaken conditional branches, compiled with an exit at each
/// ([`spu_tests::UNTAKEN_BRANCHES`]: inner branches taken now and then, one named by a
/// hint on some passes, a self-loop left by an inner branch every 16th pass).
/// Everything the same as interpreted, with the timing model on and off.
#[test]
fn blocks_past_untaken_branches_run_the_same_compiled() {
    let src = spu_tests::UNTAKEN_BRANCHES;
    let [off, on] = same_with_both_engines(src);
    assert_eq!(on.reg(27)[0], 200);
    assert_eq!(
        [on.reg(31)[0], on.reg(6)[0]],
        [18, 37],
        "indirect inner branches taken"
    );
    assert!(off.jit_stats().compiled_instructions > off.instructions() / 2);
    assert!(on.jit_stats().compiled_instructions > on.instructions() / 2);
}
