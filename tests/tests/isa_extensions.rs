//! The paper's ISA extensions (`docs/extensions.md`): the gather loads' semantics on both
//! engines, their cycles, the multi-entry branch target buffer, and every way an extension
//! that is off refuses its instructions (assembler, simulator, disassembler).

use spu_isa::codec::encode;
use spu_isa::disasm::{instruction_text, instruction_text_ext, SymbolTable};
use spu_isa::jit::Engine;
use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::profile::Profile;
use spu_isa::table::forms_named;
use spu_isa::timing::TimingConfig;
use spu_isa::Extensions;

/// Local-store addresses of the gather program's words: unaligned (+5 reads the word at
/// +4), wrapped (+0x40000 is the local store once round) and plain.
const GATHER: &str = "
        .spu_ext gather
        .text
        .global _start
_start: lqr     $6, addrs
        lqr     $8, base
        lgw     $7, $6
        lgwx    $9, $8, $6
        a       $10, $7, $9
        stop    0x2000
        .align  4
addrs:  .long   data, data+12, data+5, data+8
base:   .long   4, 4, 4, 0x40000
data:   .long   0x11111111, 0x22222222, 0x33333333, 0x44444444, 0x55555555
";

fn assemble(src: &str, options: &spu_asm::Options) -> spu_asm::Output {
    spu_asm::assemble(src, "ext.s", options).unwrap_or_else(|d| panic!("{d:?}"))
}

/// Runs `src` on one SPU with `ext`, timed with `timing` if given, to its stop.
fn run(
    src: &str,
    ext: Extensions,
    engine: Engine,
    timing: Option<TimingConfig>,
) -> (Spu, StopReason) {
    let program = assemble(src, &Default::default());
    let mut spu = Spu::new(0);
    spu.set_engine(engine);
    spu.set_extensions(ext);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    if let Some(config) = timing {
        spu.enable_timing(config);
    }
    let stop = spu.run(&mut MainMemory::zeroed(4096), 10_000_000);
    (spu, stop)
}

fn gather_on() -> Extensions {
    Extensions::parse("gather").unwrap()
}

#[test]
fn gathers_read_each_slots_word_as_the_spus_loads_address_it() {
    for engine in [Engine::Interp, Engine::host_default()] {
        let (spu, stop) = run(GATHER, gather_on(), engine, None);
        assert_eq!(stop, StopReason::Stop(0x2000));
        // data, data+12, data+5 (low bits ignored: data+4), data+8.
        assert_eq!(spu.reg(7), [0x11111111, 0x44444444, 0x22222222, 0x33333333]);
        // Four plus each: data+4, data+16, data+9 (data+8), data+8+256 KiB (wraps).
        assert_eq!(spu.reg(9), [0x22222222, 0x55555555, 0x33333333, 0x33333333]);
        assert_eq!(
            spu.reg(10),
            [0x33333333, 0x99999999, 0x55555555, 0x66666666]
        );
    }
}

#[test]
fn a_gather_with_its_extension_off_is_an_illegal_instruction_naming_it() {
    // Multi-hint on is not gather on.
    for ext in [Extensions::NONE, Extensions::parse("multihint=8").unwrap()] {
        let (spu, stop) = run(GATHER, ext, Engine::Interp, None);
        let lgw = encode(forms_named("lgw").next().unwrap(), &[7, 6], 0);
        assert_eq!(stop, StopReason::IllegalInstruction { pc: 8, word: lgw });
        assert_eq!(
            stop.to_string(),
            "illegal instruction 0x38a00307 at 0x8 (an instruction of the gather \
             extension, which is off: --ext gather)"
        );
        assert_eq!(spu.reg(7), [0; 4]);
    }
    // A word that is no extension's says nothing more.
    let stop = StopReason::IllegalInstruction {
        pc: 0,
        word: 0x00f00000,
    };
    assert_eq!(stop.to_string(), "illegal instruction 0x00f00000 at 0x0");
}

#[test]
fn the_assembler_refuses_an_extension_instruction_that_is_off() {
    let src = GATHER.replace(".spu_ext gather", "");
    let diags = spu_asm::assemble(&src, "ext.s", &Default::default()).unwrap_err();
    let text: Vec<String> = diags.iter().map(|d| d.to_string()).collect();
    assert_eq!(diags.len(), 2, "{text:?}");
    assert!(
        text[0].contains("'lgw' is an instruction of the gather extension, which is off")
            && text[0].contains("ext.s:7:9"),
        "{}",
        text[0]
    );
    assert!(
        text[1].contains("'lgwx'") && text[1].contains("ext.s:8:9"),
        "{}",
        text[1]
    );
    // `--ext gather` (the option) does what the directive does: the same words.
    let with_option = assemble(
        &src,
        &spu_asm::Options {
            extensions: gather_on(),
            ..Default::default()
        },
    );
    assert_eq!(
        with_option.image,
        assemble(GATHER, &Default::default()).image
    );
    // A bad list is an error at the directive.
    let bad = spu_asm::assemble(".spu_ext scatter\n", "bad.s", &Default::default()).unwrap_err();
    assert!(
        bad[0]
            .to_string()
            .contains(".spu_ext: unknown extension `scatter`")
            && bad[0].to_string().contains("bad.s:1:1"),
        "{}",
        bad[0]
    );
    let bad = spu_asm::assemble(".spu_ext multihint=16\n", "bad.s", &Default::default());
    assert!(bad.unwrap_err()[0].to_string().contains("1 to 8"));
}

#[test]
fn the_disassembler_knows_the_gathers_only_with_the_extension() {
    let lgwx = encode(forms_named("lgwx").next().unwrap(), &[9, 8, 6], 0);
    let symbols = SymbolTable::default();
    assert_eq!(instruction_text(lgwx, 0, &symbols), ".long 0x38c18409");
    assert_eq!(
        instruction_text_ext(lgwx, 0, &symbols, Extensions::NONE),
        ".long 0x38c18409"
    );
    assert_eq!(
        instruction_text_ext(lgwx, 0, &symbols, gather_on()),
        "lgwx\t$9,$8,$6"
    );
}

/// A gather issues on the odd pipe, holds the local store (and so issue) for its four
/// reads, and its result is ready 9 cycles after it issues; memoized or not, either engine.
#[test]
fn a_gather_costs_four_issue_cycles_and_nine_of_latency() {
    let mut cycles = Vec::new();
    for memoize in [false, true] {
        for engine in [Engine::Interp, Engine::host_default()] {
            let config = TimingConfig {
                memoize,
                model_fetch: false,
                ..Default::default()
            };
            let (spu, stop) = run(GATHER, gather_on(), engine, Some(config));
            assert_eq!(stop, StopReason::Stop(0x2000));
            let p = spu.timing().unwrap().finish_profile();
            cycles.push((p.totals.cycles, p.totals.stall));
        }
    }
    // lqr at 0, lqr 1, lgw 6 (its $6 is ready at 6: 4 dependency cycles), lgwx 10 (the
    // lgw holds issue through 9: 3 issue-block cycles, in the dp column), a 19 (the
    // lgwx's block to 14: 3 more; then its $9, ready at 10 + 9: 5 dependency cycles);
    // the stop ends the run: 20 cycles.
    assert_eq!(cycles[0].0, 20, "{cycles:?}");
    assert_eq!(cycles[0].1, [9, 0, 0, 6, 0, 0]);
    assert!(cycles.iter().all(|c| *c == cycles[0]), "{cycles:?}");
}

/// Two branches per pass, each hinted once before the loop: one entry holds only the
/// later hint, so the first branch misses every pass; two entries hold both.
const TWO_HINTS: &str = "
        .text
        .global _start
_start: il      $10, 50
        hbrr    b1, t1
        hbrr    b2, top
        nop
        lnop
        nop
        lnop
        nop
        lnop
        nop
        lnop
top:    ai      $10, $10, -1
        nop
        lnop
b1:     br      t1
        nop
t1:     nop
        lnop
b2:     brnz    $10, top
        stop    0x2000
";

fn timed(src: &str, ext: Extensions, memoize: bool) -> Profile {
    let config = TimingConfig {
        memoize,
        ..Default::default()
    };
    let (spu, stop) = run(src, ext, Engine::Interp, Some(config));
    assert_eq!(stop, StopReason::Stop(0x2000));
    spu.timing().unwrap().finish_profile()
}

#[test]
fn several_hint_entries_keep_every_branch_hinted() {
    let one = timed(TWO_HINTS, Extensions::NONE, true);
    assert_eq!(one.totals, timed(TWO_HINTS, Extensions::NONE, false).totals);
    // One entry: b1 misses 50 times, b2's last pass falls through its hint.
    assert_eq!(one.totals.branch_misses, 51);
    assert_eq!(one.totals.hint_hits, 49);
    for n in [2u8, 4, 8] {
        let ext = Extensions {
            hint_entries: n,
            gather: false,
        };
        let many = timed(TWO_HINTS, ext, true);
        // The block memo keeps its records where the other entries play no part: the
        // same with it or without it, totals and per address, on either engine.
        assert_memo_exact(TWO_HINTS, ext);
        assert_eq!(many.totals.branch_misses, 1, "{n} entries");
        assert_eq!(many.totals.hint_hits, 99, "{n} entries");
        // Each of the 50 misses of b1 was 18 cycles of branch-miss stall.
        assert_eq!(
            one.totals.stall[1] - many.totals.stall[1],
            50 * 18,
            "{n} entries"
        );
        assert_eq!(
            one.totals.cycles - many.totals.cycles,
            50 * 18,
            "{n} entries"
        );
    }
}

/// Runs `src` with `ext` memoized (on both engines) and timing every instruction: the
/// same totals and per-address counters.
fn assert_memo_exact(src: &str, ext: Extensions) {
    let per = |p: &Profile| p.addresses().map(|(a, s)| (a, *s)).collect::<Vec<_>>();
    let plain = timed(src, ext, false);
    for engine in [Engine::Interp, Engine::host_default()] {
        let (spu, stop) = run(src, ext, engine, Some(TimingConfig::default()));
        assert_eq!(stop, StopReason::Stop(0x2000));
        let memo = spu.timing().unwrap().finish_profile();
        assert_eq!(memo.totals, plain.totals, "{ext:?} {engine:?}");
        assert_eq!(per(&memo), per(&plain), "{ext:?} {engine:?}");
    }
}

/// A full buffer replaces the entry filled longest ago; a new hint for a branch that has
/// an entry replaces that one.
#[test]
fn a_full_buffer_replaces_its_oldest_entry() {
    // Three hinted branches, two entries: the first hint is gone when the loop starts.
    let three = TWO_HINTS
        .replace(
            "        hbrr    b1, t1\n",
            "        hbrr    b1, t1\n        hbrr    b0, t0\n",
        )
        .replace(
            "top:    ai      $10, $10, -1\n        nop\n        lnop\n",
            "top:    ai      $10, $10, -1\nb0:     br      t0\n        nop\nt0:     lnop\n",
        );
    let two = Extensions {
        hint_entries: 2,
        gather: false,
    };
    let p = timed(&three, two, false);
    assert_eq!(p.totals.branch_misses, 51, "b1's entry was replaced");
    let p = timed(
        &three,
        Extensions {
            hint_entries: 3,
            gather: false,
        },
        false,
    );
    assert_eq!(p.totals.branch_misses, 1);
    // The memo's records with 2 to 8 entries, where the oldest entry is replaced (and a
    // hint set in the loop pushes another down), time it as the model does.
    let pushed = three.replace(
        "top:    ai      $10, $10, -1\n",
        "top:    ai      $10, $10, -1\n        hbrr    b9, t9\n",
    );
    let pushed = pushed.replace(
        "        stop    0x2000\n",
        "b9:     br      t9\nt9:     stop    0x2000\n",
    );
    for n in 2..=8 {
        let ext = Extensions {
            hint_entries: n,
            gather: false,
        };
        assert_memo_exact(&three, ext);
        assert_memo_exact(&pushed, ext);
    }
}

/// Gathers in a loop: the block memo replays their issue blocks and latencies exactly
/// (the same cycles, totals and per-address counters as the model timing every
/// instruction), with the fetch model on and either engine.
#[test]
fn memoized_gather_loops_time_exactly() {
    let src = GATHER.replace(
        "        stop    0x2000\n",
        "        il      $11, 40
loop:   lgw     $7, $6
        ai      $11, $11, -1
        lgwx    $9, $8, $6
        a       $10, $7, $9
        hbrr    back, loop
        fa      $12, $12, $12
        lgw     $13, $6
        nop
        lnop
        nop
        lnop
        a       $14, $13, $10
back:   brnz    $11, loop
        stop    0x2000\n",
    );
    let per = |p: &Profile| p.addresses().map(|(a, s)| (a, *s)).collect::<Vec<_>>();
    let plain = {
        let config = TimingConfig {
            memoize: false,
            ..Default::default()
        };
        let (spu, stop) = run(&src, gather_on(), Engine::Interp, Some(config));
        assert_eq!(stop, StopReason::Stop(0x2000));
        (spu.reg(14), spu.timing().unwrap().finish_profile())
    };
    assert!(plain.1.totals.stall[3] >= 40 * 6, "{:?}", plain.1.totals);
    for engine in [Engine::Interp, Engine::host_default()] {
        let (spu, stop) = run(&src, gather_on(), engine, Some(TimingConfig::default()));
        assert_eq!(stop, StopReason::Stop(0x2000));
        let memo = spu.timing().unwrap().finish_profile();
        assert_eq!(spu.reg(14), plain.0);
        assert_eq!(memo.totals, plain.1.totals, "{engine:?}");
        assert_eq!(per(&memo), per(&plain.1), "{engine:?}");
    }
}

/// `spu timing` times a gather as the model does: odd pipe, 9 cycles to its result, and
/// the next instruction held three cycles behind it.
#[test]
fn the_static_listing_times_gathers() {
    let t = spu_isa::static_timing::analyze_source(GATHER, None).unwrap();
    let texts: Vec<&str> = t.rows.iter().map(|r| r.text.as_str()).collect();
    let row = |mnemonic: &str| {
        let r = t
            .rows
            .iter()
            .find(|r| r.text.starts_with(mnemonic))
            .unwrap_or_else(|| panic!("{mnemonic}: {texts:?}"));
        (r.pipe, r.issue, r.stall, r.latency)
    };
    assert_eq!(row("lgw\t"), (1, 6, 4, 9));
    assert_eq!(row("lgwx"), (1, 10, 3, 9));
    assert_eq!(row("a\t"), (0, 19, 8, 2));
}

/// The kernel for several hint entries (`KernelVariant::PrimaryMultihint`, chosen by
/// `kernel_with` when multihint is on) renders the baseline's image, which the host
/// reference validates, with fewer branch-miss stall cycles in traversal; on the real SPU's
/// one entry the baseline kernel runs.
#[test]
fn the_multihint_kernel_renders_the_same_frame_with_fewer_traversal_misses() {
    use spu_isa::jit::CodeCache;
    use spu_loader::kernels::KernelVariant;
    use spu_loader::render::{prepare, render, validate, RenderConfig};
    use spu_loader::shading::ShadeMode;
    let four = Extensions::parse("multihint=4").unwrap();
    assert_eq!(
        RenderConfig::kernel_with(false, ShadeMode::None, four),
        KernelVariant::PrimaryMultihint
    );
    assert_eq!(
        RenderConfig::kernel_with(false, ShadeMode::None, gather_on()),
        KernelVariant::Primary
    );
    assert_eq!(
        RenderConfig::kernel_with(false, ShadeMode::Simple, four),
        KernelVariant::Shaded
    );
    let room = prepare("room").unwrap();
    let frame = |kernel: KernelVariant, extensions: Extensions| {
        let config = RenderConfig {
            width: 128,
            height: 128,
            threads: 1,
            kernel,
            extensions,
            ..RenderConfig::new("room")
        };
        let frame = render(&room, &config, &CodeCache::default()).unwrap();
        let v = validate(&room, &config, &frame).unwrap();
        assert!(v.passed(), "{kernel:?}: {:?}", v.messages);
        let stats = frame.stats(&config, None);
        let branch = stats.traversal.as_ref().unwrap().stalls.branch;
        (frame.run.frame_buffer, branch, stats.frame_cycles)
    };
    let base = frame(KernelVariant::Primary, Extensions::NONE);
    let multi = frame(KernelVariant::PrimaryMultihint, four);
    assert_eq!(multi.0, base.0);
    // (traversal's branch-miss stall cycles, frame cycles): the step's early exits as one
    // hinted `bi`, the slow path's second search hinted on entry and its skips by masks
    // (docs/extensions.md, Multihint): 2,950 misses of 18 cycles fewer here, at most half
    // of the baseline's (issue #33), in fewer cycles (with the leaf's cull per group of 16
    // rays: 2,085,730 against 2,134,000 with the packet's; four triangles a cull pass, one
    // per lane, and the prefetch pass that hints its misses: 2,081,157; the test loop's
    // last pass stepping over the triangles the cull culls: 2,073,825).
    assert_eq!((base.1, base.2), (83_052, 2_197_047));
    assert_eq!((multi.1, multi.2), (29_952, 2_073_825));
    assert_eq!(base.1 - multi.1, 2_950 * 18);
    assert!(2 * multi.1 <= base.1 && multi.2 < base.2);
}

/// The shading kernel for SPUs with the gather load (`KernelVariant::ShadedGather`, chosen
/// by `kernel_with` when gather is on and a shading mode is) renders the baseline's image,
/// which the host reference validates, in fewer shading cycles (at this size the room's
/// too; at 1024x1024, where its groups are nearly all on one triangle, it takes 0.7% more:
/// docs/extensions.md); without the extension the frame is refused before it runs.
#[test]
fn the_gather_kernel_shades_the_same_frame_in_fewer_cycles() {
    use spu_isa::jit::CodeCache;
    use spu_loader::kernels::KernelVariant;
    use spu_loader::render::{prepare, render, validate, RenderConfig};
    use spu_loader::shading::ShadeMode;
    assert_eq!(
        RenderConfig::kernel_with(false, ShadeMode::Simple, gather_on()),
        KernelVariant::ShadedGather
    );
    assert_eq!(
        RenderConfig::kernel_with(false, ShadeMode::None, gather_on()),
        KernelVariant::Primary
    );
    let mut shaded = Vec::new();
    for scene in ["room", "conference"] {
        let prepared = prepare(scene).unwrap();
        let frame = |kernel: KernelVariant, extensions: Extensions| {
            let mut config = RenderConfig {
                width: 128,
                height: 128,
                threads: 1,
                kernel,
                extensions,
                ..RenderConfig::new(scene)
            };
            config.shading.mode = ShadeMode::Shadows;
            let frame = render(&prepared, &config, &CodeCache::default()).unwrap();
            let v = validate(&prepared, &config, &frame).unwrap();
            assert!(v.passed(), "{scene} {kernel:?}: {:?}", v.messages);
            let stats = frame.stats(&config, None);
            let cycles = stats.shading.as_ref().unwrap().cycles;
            assert!(frame.run.colour_buffer.is_some());
            ((frame.run.frame_buffer, frame.run.colour_buffer), cycles)
        };
        let base = frame(KernelVariant::Shaded, Extensions::NONE);
        let gather = frame(KernelVariant::ShadedGather, gather_on());
        assert_eq!(gather.0, base.0, "{scene}");
        shaded.push((scene, base.1, gather.1));
    }
    // (scene, the shading module's cycles: baseline, gather)
    assert_eq!(
        shaded,
        [
            ("room", 1_243_345, 1_035_714),
            ("conference", 3_614_585, 1_716_310)
        ]
    );
    let refused = RenderConfig {
        kernel: KernelVariant::ShadedGather,
        ..RenderConfig::new("room")
    };
    let mut refused = refused;
    refused.shading.mode = ShadeMode::Simple;
    let e = refused.check().unwrap_err();
    assert!(e.contains("--ext gather"), "{e}");
}

/// The multihint kernel (several hints in flight in one block: the step's exit and its
/// loop, the slow path's searches, the resumed leaf's slots) is timed by the block memo
/// exactly as by the per-instruction model, with 2 and 4 entries: the same frame, cycles
/// and counters, total and per address. A small conference frame with small caches and
/// SHT 4, so that BVH and triangle misses, suspensions and every traversal case occur.
#[test]
fn the_multihint_kernel_times_the_same_with_and_without_block_memoization() {
    use spu_loader::kernels::KernelVariant;
    use spu_loader::render::{prepare, RenderConfig};
    let conference = prepare("conference").unwrap();
    for ext in ["multihint=2", "multihint=4"] {
        let extensions = Extensions::parse(ext).unwrap();
        let config = RenderConfig {
            width: 48,
            height: 32,
            threads: 1,
            bvh_cache: 128,
            tri_cache: 128,
            kernel: KernelVariant::PrimaryMultihint,
            extensions,
            ..RenderConfig::new("conference")
        };
        let pp = crate::runtime_frames::assert_memo_times_the_same(&conference, &config, ext);
        assert!(
            pp.totals.branch_misses > 0 && pp.totals.hint_hits > 1_000,
            "{ext}"
        );
    }
}
