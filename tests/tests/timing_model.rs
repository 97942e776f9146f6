//! Pinned cycle counts of the timing model, fed instruction by instruction (no core), with
//! each expected number derived from the rules in `docs/timing.md` (R1..R10).

use spu_isa::codec::{decode, encode, Inst};
use spu_isa::table::forms_named;
use spu_isa::timing::{StallCause, Timing, TimingConfig};

fn inst(m: &str, ops: &[i64], pc: u32) -> Inst {
    let form = forms_named(m)
        .find(|f| f.operands.len() == ops.len())
        .unwrap_or_else(|| panic!("{m}"));
    decode(encode(form, ops, pc))
}

fn no_fetch() -> TimingConfig {
    TimingConfig {
        model_fetch: false,
        ..Default::default()
    }
}

/// A program laid out from address 0, one instruction per word.
struct Prog {
    insts: Vec<(String, Vec<i64>)>,
}

impl Prog {
    fn new(src: &[(&str, &[i64])]) -> Self {
        Prog {
            insts: src
                .iter()
                .map(|(m, o)| (m.to_string(), o.to_vec()))
                .collect(),
        }
    }
    fn at(&self, pc: u32) -> Inst {
        let (m, o) = &self.insts[(pc / 4) as usize];
        inst(m, o, pc)
    }
}

/// Issues straight-line code at consecutive addresses from `start`; returns issue cycles.
fn straight(t: &mut Timing, start: u32, src: &[(&str, &[i64])]) -> Vec<u64> {
    src.iter()
        .enumerate()
        .map(|(i, (m, o))| {
            let pc = start + 4 * i as u32;
            t.issue(pc, inst(m, o, pc))
        })
        .collect()
}

fn lnops(n: usize) -> Vec<(&'static str, &'static [i64])> {
    vec![("lnop", &[][..]); n]
}

// ---- R2: dependency chains of every class ------------------------------------------------

#[test]
fn dependency_chain_latencies() {
    // A chain of four dependent instructions of one class issues every `latency` cycles:
    // issue cycles 0, L, 2L, 3L; the profile charges 3(L-1) dependency stall cycles.
    let cases: [(&str, &[i64], i64); 7] = [
        ("a", &[3, 3, 3], 2),      // FX2
        ("shli", &[3, 3, 1], 4),   // FX3
        ("cntb", &[3, 3], 4),      // FXB
        ("fa", &[3, 3, 3], 6),     // FP6
        ("mpy", &[3, 3, 3], 7),    // FP7
        ("rotqby", &[3, 3, 3], 4), // SHUF
        ("lqx", &[3, 3, 3], 6),    // LS
    ];
    for (m, ops, lat) in cases {
        let mut t = Timing::new(no_fetch());
        let prog: Vec<(&str, &[i64])> = vec![(m, ops); 4];
        let got = straight(&mut t, 0, &prog);
        let l = lat as u64;
        assert_eq!(got, vec![0, l, 2 * l, 3 * l], "{m}");
        let p = t.finish_profile();
        assert_eq!(p.totals.cycles, 3 * l + 1, "{m}");
        assert_eq!(
            p.totals.stall[StallCause::Dependency.index()],
            3 * (l - 1),
            "{m}"
        );
        // The stall at the second instruction waited on the first.
        if l > 1 {
            assert_eq!(p.dependency_sources(4), vec![(0, l - 1)], "{m}");
        }
    }
}

#[test]
fn double_precision_latency_and_issue_block() {
    // dfa at 0; the dependent dfa waits for the 13-cycle result: issues at 13.
    let mut t = Timing::new(no_fetch());
    assert_eq!(
        straight(&mut t, 0, &[("dfa", &[3, 1, 2]), ("dfa", &[4, 3, 3])]),
        vec![0, 13]
    );
    // Independent instructions after a dfa at 0: nothing issues in cycles 1..6 (R3), so
    // the next issues at 7; the odd-pipe partner of the dfa does not dual-issue with it.
    let mut t = Timing::new(no_fetch());
    let got = straight(
        &mut t,
        0,
        &[
            ("dfa", &[3, 1, 2]),
            ("lnop", &[]),
            ("dfm", &[5, 1, 2]),
            ("a", &[6, 1, 2]),
            ("a", &[7, 1, 2]),
        ],
    );
    // dfa 0; lnop 7 (blocked 6); dfm 8; a at 12 is blocked by the dfm until 15; a 16.
    assert_eq!(got, vec![0, 7, 8, 15, 16]);
    let p = t.finish_profile();
    assert_eq!(p.totals.stall[StallCause::DoublePrecision.index()], 6 + 6);
    assert_eq!(p.totals.dual_cycles, 0);
    // A dependent chain: dfa (0) then fesd reading it waits 13 (the block is inside that).
    let mut t = Timing::new(no_fetch());
    assert_eq!(
        straight(&mut t, 0, &[("dfa", &[3, 1, 2]), ("fesd", &[4, 3])]),
        vec![0, 13]
    );
}

// ---- R1: dual issue ---------------------------------------------------------------------

#[test]
fn dual_issue_pairs_and_misalignment() {
    // Four aligned even/odd pairs of independent instructions: 4 cycles for 8.
    let mut t = Timing::new(no_fetch());
    let pair: [(&str, &[i64]); 2] = [("a", &[10, 1, 2]), ("lqd", &[11, 0, 1])];
    let prog: Vec<_> = pair.iter().cycle().take(8).cloned().collect();
    assert_eq!(straight(&mut t, 0, &prog), vec![0, 0, 1, 1, 2, 2, 3, 3]);
    let p = t.finish_profile();
    assert_eq!(
        (
            p.totals.cycles,
            p.totals.dual_cycles,
            p.totals.single_cycles()
        ),
        (4, 4, 0)
    );
    assert_eq!(p.get(0).unwrap().dual, 1);

    // The same code one word later: every even-pipe instruction sits in an odd slot and
    // every odd-pipe one in an even slot, so nothing pairs: 8 cycles.
    let mut t = Timing::new(no_fetch());
    assert_eq!(straight(&mut t, 4, &prog), (0..8).collect::<Vec<u64>>());

    // Odd then even in one group: two cycles.
    let mut t = Timing::new(no_fetch());
    assert_eq!(
        straight(&mut t, 0, &[("lqd", &[11, 0, 1]), ("a", &[10, 1, 2])]),
        vec![0, 1]
    );

    // Even then odd where the odd one reads the even one's result (FX2, 2 cycles):
    // the pair splits and the second waits for the result.
    let mut t = Timing::new(no_fetch());
    assert_eq!(
        straight(
            &mut t,
            0,
            &[("a", &[10, 1, 2]), ("shufb", &[11, 10, 10, 10])]
        ),
        vec![0, 2]
    );
    assert_eq!(t.finish_profile().totals.pair_dependency, 1);

    // Even then odd where the odd one waits on an older load: the first issues alone
    // (it does not wait for its partner), the second issues when its operand is ready.
    let mut t = Timing::new(no_fetch());
    let got = straight(
        &mut t,
        0,
        &[
            ("lqd", &[20, 0, 1]),
            ("lnop", &[]),
            ("a", &[10, 1, 2]),
            ("shufb", &[11, 20, 20, 20]),
        ],
    );
    assert_eq!(got, vec![0, 1, 2, 6]);
}

// ---- R4/R5: branches and hints ----------------------------------------------------------

/// Runs `trace` (addresses in execution order) of `prog`, telling the model about branch
/// outcomes: a branch is taken when the next address is not pc + 4.
fn run_trace(t: &mut Timing, prog: &Prog, trace: &[u32]) -> Vec<u64> {
    let mut out = Vec::new();
    for (i, &pc) in trace.iter().enumerate() {
        let ins = prog.at(pc);
        out.push(t.issue(pc, ins));
        if spu_isa::analysis::is_branch(ins.op) {
            let next = trace.get(i + 1).copied().unwrap_or(pc + 4);
            t.branch_resolved(pc, ins, next != pc + 4, next);
        }
    }
    out
}

/// A program of `len` words of `lnop` (one issue per cycle, never paired) with the given
/// instructions placed at their addresses.
fn lnop_prog(len: usize, place: &[(u32, &str, &[i64])]) -> Prog {
    let mut p = Prog::new(&lnops(len));
    for (pc, m, o) in place {
        p.insts[(*pc / 4) as usize] = (m.to_string(), o.to_vec());
    }
    p
}

#[test]
fn taken_unhinted_branch_costs_18() {
    // 0: br 0x40 (taken, no hint): it issues at 0; its target at 0 + 1 + 18 = 19.
    let prog = lnop_prog(32, &[(0, "br", &[0x40])]);
    let mut t = Timing::new(no_fetch());
    assert_eq!(run_trace(&mut t, &prog, &[0, 0x40, 0x44]), vec![0, 19, 20]);
    let p = t.finish_profile();
    assert_eq!(p.totals.stall[StallCause::BranchMiss.index()], 18);
    // The miss is charged to the branch.
    assert_eq!(p.get(0).unwrap().stall[StallCause::BranchMiss.index()], 18);
    assert_eq!(
        (
            p.totals.branches_taken,
            p.totals.branch_misses,
            p.totals.cycles
        ),
        (1, 1, 21)
    );
}

#[test]
fn not_taken_unhinted_branch_is_free() {
    // 0: brz $5,0x40 not taken: the next instruction issues the next cycle.
    let prog = lnop_prog(32, &[(0, "brz", &[5, 0x40])]);
    let mut t = Timing::new(no_fetch());
    assert_eq!(run_trace(&mut t, &prog, &[0, 4, 8]), vec![0, 1, 2]);
    let p = t.finish_profile();
    assert_eq!(
        (p.totals.branches_not_taken, p.totals.branch_misses),
        (1, 0)
    );
}

#[test]
fn correctly_hinted_branch_is_free() {
    // 0: hbrr 0x2c,0x80; lnops at 4..0x28 issue at 1..10; the branch at 0x2c is 11
    // instructions after the hint (>= 8) and issues at 11 = hint + 11 (no hint stall);
    // taken to the hinted target, which issues at 12 with no penalty.
    let prog = lnop_prog(64, &[(0, "hbrr", &[0x2c, 0x80]), (0x2c, "br", &[0x80])]);
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..=0x2c).step_by(4).collect();
    trace.push(0x80);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[11..], [11, 12]);
    let p = t.finish_profile();
    assert_eq!(
        (p.totals.hints, p.totals.hint_hits, p.totals.branch_misses),
        (1, 1, 0)
    );
    assert_eq!(p.totals.stall_cycles(), 0);
}

#[test]
fn late_hint_stalls_the_branch_until_11_cycles() {
    // 0: hbrr 0x20,0x80 at cycle 0; seven lnops at 4..0x1c issue at 1..7; the branch at
    // 0x20 is 8 instructions after the hint (just enough) and could issue at 8, but
    // waits until 0 + 11 = 11 (3 hint-stall cycles); its target then issues at 12.
    let prog = lnop_prog(64, &[(0, "hbrr", &[0x20, 0x80]), (0x20, "br", &[0x80])]);
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..=0x20).step_by(4).collect();
    trace.push(0x80);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[7..], [7, 11, 12]);
    let p = t.finish_profile();
    assert_eq!(p.totals.stall[StallCause::Hint.index()], 3);
    assert_eq!(p.get(0x20).unwrap().stall[StallCause::Hint.index()], 3);
    assert_eq!(p.totals.hint_hits, 1);
}

#[test]
fn too_close_hint_is_ignored() {
    // 0: hbrr 0x1c,0x80; the branch at 0x1c is only 7 instructions after the hint, so
    // the hint is ignored: the taken branch (cycle 7) misses and its target issues at
    // 7 + 1 + 18 = 26. No hint stall is charged.
    let prog = lnop_prog(64, &[(0, "hbrr", &[0x1c, 0x80]), (0x1c, "br", &[0x80])]);
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..=0x1c).step_by(4).collect();
    trace.push(0x80);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[7..], [7, 26]);
    let p = t.finish_profile();
    assert_eq!((p.totals.hint_hits, p.totals.branch_misses), (0, 1));
    assert_eq!(p.totals.stall[StallCause::Hint.index()], 0);
}

#[test]
fn wrongly_hinted_branches_miss() {
    // Hint names target 0x100 but the branch (bi, register target) goes to 0x80: the
    // branch issues at 11 and its target at 11 + 1 + 18 = 30.
    let prog = lnop_prog(128, &[(0, "hbrr", &[0x2c, 0x100]), (0x2c, "bi", &[9])]);
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..=0x2c).step_by(4).collect();
    trace.push(0x80);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[11..], [11, 30]);
    assert_eq!(t.finish_profile().totals.branch_misses, 1);

    // A hinted conditional branch that falls through also costs the miss: 11, then 30.
    let prog = lnop_prog(
        128,
        &[(0, "hbrr", &[0x2c, 0x80]), (0x2c, "brnz", &[5, 0x80])],
    );
    let mut t = Timing::new(no_fetch());
    let trace: Vec<u32> = (0..=0x30).step_by(4).collect();
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[11..], [11, 30]);
    let p = t.finish_profile();
    assert_eq!(
        (p.totals.branches_not_taken, p.totals.branch_misses),
        (1, 1)
    );
}

#[test]
fn register_hint_through_the_hook() {
    // hbr takes its target from a register: the core reports it through `hint`. Same
    // layout as the correctly hinted case: no penalty.
    let prog = lnop_prog(64, &[(0, "hbr", &[0x2c, 9]), (0x2c, "bi", &[9])]);
    let mut t = Timing::new(no_fetch());
    let mut out = Vec::new();
    for pc in (0..=0x2c).step_by(4) {
        let ins = prog.at(pc);
        out.push(t.issue(pc, ins));
        if pc == 0 {
            t.hint(0, 0x2c, 0x80);
        }
        if pc == 0x2c {
            t.branch_resolved(pc, ins, true, 0x80);
        }
    }
    out.push(t.issue(0x80, prog.at(0x80)));
    assert_eq!(out[11..], [11, 12]);
    assert_eq!(t.finish_profile().totals.hint_hits, 1);
}

#[test]
fn a_newer_hint_replaces_the_older() {
    // Two hints for two branches: only the newer (for 0x30) is kept, so the branch at
    // 0x2c named by the first one misses.
    let prog = lnop_prog(
        128,
        &[
            (0, "hbrr", &[0x2c, 0x80]),
            (4, "hbrr", &[0x30, 0x90]),
            (0x2c, "br", &[0x80]),
        ],
    );
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..=0x2c).step_by(4).collect();
    trace.push(0x80);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[11..], [11, 30]);
}

#[test]
fn hinted_loop_runs_without_misses() {
    // A 4-instruction loop hinted once before it: hbrr at 0 names the loop branch at
    // 0x2c; 0x20..0x2c is the body (a; lnop; ai; brnz $6) executed 3 times.
    //   hbrr 0, lnops 0x4..0x1c at 1..7; iteration 1: a + lnop pair at 8, ai 9; brnz is
    //   11 instructions after the hint (>= 8) but only 9 cycles: it cannot join ai at 9,
    //   and waits to 0 + 11 = 11 (1 hint-stall cycle). Iterations 2 and 3 are hinted hits
    //   with ai + brnz dual-issuing: 12 12 13 13, 14 14 15 15. The exit falls through
    //   although the hint says taken: a miss, 15 + 1 + 18 = 34.
    let prog = lnop_prog(
        64,
        &[
            (0, "hbrr", &[0x2c, 0x20]),
            (0x20, "a", &[10, 1, 2]),
            (0x28, "ai", &[5, 5, -1]),
            (0x2c, "brnz", &[6, 0x20]),
        ],
    );
    let mut t = Timing::new(no_fetch());
    let mut trace: Vec<u32> = (0..0x20).step_by(4).collect();
    for _ in 0..3 {
        trace.extend([0x20, 0x24, 0x28, 0x2c]);
    }
    trace.push(0x30);
    let got = run_trace(&mut t, &prog, &trace);
    assert_eq!(got[8..], [8, 8, 9, 11, 12, 12, 13, 13, 14, 14, 15, 15, 34]);
    let p = t.finish_profile();
    assert_eq!((p.totals.hint_hits, p.totals.branch_misses), (2, 1));
    assert_eq!(p.totals.stall[StallCause::Hint.index()], 1);
    assert_eq!(p.totals.dual_cycles, 3 + 2);
}

// ---- R6: channels ----------------------------------------------------------------------

#[test]
fn channel_wait_on_dma() {
    // A 16 KiB get issued at cycle 10 completes at 10 + 240 (100 ns at 2.4 GHz) + 2048
    // (16384 B at 8 B/cycle) = 2298. `rdch $3,$ch24` (MFC_RdTagStat) issues at 11 and
    // waits until then; the shufb using $3 waits for the channel's 6-cycle result.
    let mut t = Timing::new(no_fetch());
    let cfg = t.config.clone();
    let done = cfg.dma_completion(10, 16384);
    assert_eq!(done, 2298);
    for pc in (0..40).step_by(4) {
        t.issue(pc, inst("lnop", &[], pc));
    }
    assert_eq!(t.issue(40, inst("lnop", &[], 40)), 10);
    assert_eq!(t.issue(44, inst("rdch", &[3, 24], 44)), 11);
    t.channel_stall(44, 24, done);
    assert_eq!(t.now(), done + 1);
    assert_eq!(t.issue(48, inst("shufb", &[4, 3, 3, 3], 48)), done + 6);
    let p = t.finish_profile();
    assert_eq!(p.totals.stall[StallCause::Channel(24).index()], done - 11);
    assert_eq!(p.channel_stalls(44), vec![(24, done - 11)]);
    assert_eq!(p.totals.cycles, done + 7);
    // The cycles charged to each address add up to the total.
    let sum: u64 = p.addresses().map(|(_, s)| s.cycles).sum();
    assert_eq!(sum, p.totals.cycles);
}

#[test]
fn channel_wait_of_a_dual_issued_instruction() {
    // `a` at 0 and `rdch` at 4 dual-issue at 0; the channel holds the rdch until 20: it
    // no longer counts as dual-issued, and the total is 21 cycles.
    let mut t = Timing::new(no_fetch());
    t.issue(0, inst("a", &[5, 1, 2], 0));
    assert_eq!(t.issue(4, inst("rdch", &[3, 29], 4)), 0);
    t.channel_stall(4, 29, 20);
    let p = t.finish_profile();
    assert_eq!((p.totals.cycles, p.totals.dual_cycles), (21, 0));
    let sum: u64 = p.addresses().map(|(_, s)| s.cycles).sum();
    assert_eq!(sum, 21);
}

// ---- R8: instruction fetch ---------------------------------------------------------------

#[test]
fn loads_and_stores_starve_fetch() {
    // 64 loads (odd pipe, one per cycle, never paired): line 0 (0x00..0x7c) issues at
    // 0..31 and takes the local store in every one of those cycles, so the prefetch of
    // line 1 requested at cycle 0 gets no slot until 32, and line 1's first load issues at
    // 32 + 6 = 38 (6 fetch stall cycles). Line 2 is then requested at 38 and starved the
    // same way.
    let mut t = Timing::new(TimingConfig::default());
    let loads: Vec<(&str, &[i64])> = vec![("lqd", &[3, 0, 1]); 64];
    let got = straight(&mut t, 0, &loads);
    assert_eq!(got[31], 31);
    assert_eq!(got[32], 38);
    assert_eq!(got[63], 69);
    let p = t.finish_profile();
    assert_eq!(p.totals.stall[StallCause::Fetch.index()], 6);
    assert_eq!(p.get(0x80).unwrap().stall[StallCause::Fetch.index()], 6);
    // Every load took the cycle the waiting prefetch wanted: 32 for line 1, 32 for line 2.
    assert_eq!(p.totals.ls_contention, 64);
}

#[test]
fn hbrp_feeds_fetch_in_a_run_of_loads() {
    // The same run with `hbrp` at 0x40: it takes its own local-store cycle (16) for the
    // inline prefetch, so line 1 is ready at 16 + 6 = 22, well before it is needed.
    let mut t = Timing::new(TimingConfig::default());
    let mut loads: Vec<(&str, &[i64])> = vec![("lqd", &[3, 0, 1]); 64];
    loads[16] = ("hbrp", &[]);
    let got = straight(&mut t, 0, &loads);
    assert_eq!(got[16], 16);
    assert_eq!(got[32], 32);
    assert_eq!(
        t.finish_profile().totals.stall[StallCause::Fetch.index()],
        0
    );
}

#[test]
fn one_free_cycle_is_enough_for_fetch() {
    // Loads with a single lnop in line 0: the lnop's cycle leaves the local store free,
    // the prefetch takes it, and line 1 continues without a stall.
    let mut t = Timing::new(TimingConfig::default());
    let mut loads: Vec<(&str, &[i64])> = vec![("lqd", &[3, 0, 1]); 64];
    loads[20] = ("lnop", &[]);
    let got = straight(&mut t, 0, &loads);
    assert_eq!(got[32], 32);
    assert_eq!(
        t.finish_profile().totals.stall[StallCause::Fetch.index()],
        0
    );
}

#[test]
fn dma_takes_the_local_store_before_fetch() {
    // A 128-byte DMA into the local store at cycle 20 takes that cycle. The lnop at 20 in
    // a line of loads would have let the prefetch in; the DMA takes it first, so the
    // prefetch waits for the end of the loads as in the starved case.
    let mut t = Timing::new(TimingConfig::default());
    t.dma_local_store(20, 128);
    let mut loads: Vec<(&str, &[i64])> = vec![("lqd", &[3, 0, 1]); 64];
    loads[20] = ("lnop", &[]);
    let got = straight(&mut t, 0, &loads);
    assert_eq!(got[32], 38);
    let p = t.finish_profile();
    assert_eq!(p.totals.dma_contention, 1);
}

// ---- merging ----------------------------------------------------------------------------

#[test]
fn profiles_of_several_spus_merge() {
    let mut a = Timing::new(no_fetch());
    straight(&mut a, 0, &[("a", &[3, 3, 3]), ("a", &[3, 3, 3])]);
    let mut b = Timing::new(no_fetch());
    straight(
        &mut b,
        0,
        &[("a", &[3, 3, 3]), ("a", &[3, 3, 3]), ("a", &[3, 3, 3])],
    );
    let mut p = a.finish_profile();
    p.merge(&b.finish_profile());
    assert_eq!(p.totals.spus, 2);
    assert_eq!(p.totals.instructions, 5);
    assert_eq!(p.totals.cycles, 3 + 5);
    assert_eq!(p.get(4).unwrap().executions, 2);
    assert_eq!(p.get(8).unwrap().executions, 1);
    assert_eq!(p.dependency_sources(4), vec![(0, 2)]);
}

// ---- memoization is exact -----------------------------------------------------------------

/// A loop nest with hints, loads, stores, double precision and a data-dependent exit,
/// executed with and without block memoization: every issue cycle and counter agrees.
#[test]
fn memoized_replay_is_exact() {
    let body: Vec<(&str, Vec<i64>)> = vec![
        ("hbrr", vec![0x3c, 0x0]),
        ("lqd", vec![10, 0, 1]),
        ("fma", vec![20, 21, 22, 20]),
        ("lqd", vec![11, 16, 1]),
        ("fma", vec![23, 24, 25, 23]),
        ("shufb", vec![12, 10, 11, 13]),
        ("a", vec![30, 30, 31]),
        ("lqd", vec![14, 32, 1]),
        ("dfa", vec![26, 27, 28]),
        ("shufb", vec![15, 14, 12, 13]),
        ("ai", vec![1, 1, 48]),
        ("stqd", vec![15, 48, 2]),
        ("fm", vec![29, 26, 28]),
        ("hbrp", vec![]),
        ("ai", vec![5, 5, -1]),
        ("brnz", vec![5, 0x0]),
        // 0x40: a second block reached by fall-through, then back to 0 via br.
        ("a", vec![40, 29, 29]),
        ("lnop", vec![]),
        ("br", vec![0x0]),
    ];
    let insts: Vec<Inst> = body
        .iter()
        .enumerate()
        .map(|(i, (m, o))| inst(m, o, 4 * i as u32))
        .collect();
    // Trace: inner loop counts 1..=6 iterations alternately, then the outer block.
    let mut trace: Vec<u32> = Vec::new();
    for outer in 0..40 {
        let n = 1 + outer % 6;
        for _ in 0..n {
            trace.extend((0..16).map(|i| 4 * i));
        }
        trace.extend([0x40, 0x44, 0x48]);
    }
    let run = |memoize: bool, fetch: bool| {
        let mut t = Timing::new(TimingConfig {
            memoize,
            model_fetch: fetch,
            ..Default::default()
        });
        let mut cycles = Vec::new();
        for (i, &pc) in trace.iter().enumerate() {
            let ins = insts[(pc / 4) as usize];
            cycles.push(t.issue(pc, ins));
            if spu_isa::analysis::is_branch(ins.op) {
                let next = trace.get(i + 1).copied().unwrap_or(pc + 4);
                t.branch_resolved(pc, ins, next != pc + 4, next);
            }
            if i == trace.len() / 2 {
                // A DMA and a channel wait in the middle.
                t.dma_local_store(t.now() + 3, 256);
            }
        }
        (cycles, t.finish_profile())
    };
    for fetch in [false, true] {
        let (c0, p0) = run(false, fetch);
        let (c1, p1) = run(true, fetch);
        assert_eq!(c0, c1);
        assert_eq!(p0.totals, p1.totals);
        let a0: Vec<_> = p0.addresses().map(|(a, s)| (a, *s)).collect();
        let a1: Vec<_> = p1.addresses().map(|(a, s)| (a, *s)).collect();
        assert_eq!(a0, a1);
        for pc in (0..0x4c).step_by(4) {
            assert_eq!(
                p0.dependency_sources(pc),
                p1.dependency_sources(pc),
                "{pc:x}"
            );
        }
    }
}

/// A chained block skips its signature only where the block before it decided its entry
/// state. Here block A (0x108) replays from the same state every time, but what comes
/// before it varies: the tail at 0xf0 has a 6-cycle `fm` or a 2-cycle `ai`, and a hint for
/// block B's branch, for another branch or none. With the `ai`, P's load into $20 is still
/// in flight when B (0x114) reads it (B stalls); with the `fm` it is not; after
/// the first hint B's branch is predicted, after the second not. A chain A -> B formed
/// after one tail must not be followed after another: every issue cycle and counter
/// agrees with the unmemoized model.
#[test]
fn chained_blocks_check_what_the_previous_block_did_not_decide() {
    let at = |pc: u32, m: &str, ops: &[i64]| (pc, inst(m, ops, pc));
    let tails = [
        [at(0xf0, "nop", &[]), at(0xf4, "fm", &[24, 26, 26])],
        [at(0xf0, "nop", &[]), at(0xf4, "ai", &[24, 24, 1])],
        [
            at(0xf0, "hbrr", &[0x118, 0xf0]),
            at(0xf4, "fm", &[24, 26, 26]),
        ],
        [
            at(0xf0, "hbrr", &[0x300, 0xf0]),
            at(0xf4, "fm", &[24, 26, 26]),
        ],
    ];
    let hinted_branch = [0, 0, 0x118, 0x300];
    let rest = [
        at(0xf8, "brz", &[9, 0x200]), // not taken
        at(0xfc, "lqd", &[20, 0, 3]), // P
        at(0x100, "ai", &[25, 24, 1]),
        at(0x104, "brz", &[9, 0x200]), // not taken
        at(0x108, "ai", &[21, 21, 1]), // A
        at(0x10c, "ai", &[27, 27, 1]),
        at(0x110, "brz", &[9, 0x200]), // not taken
        at(0x114, "a", &[22, 20, 20]), // B
        at(0x118, "brnz", &[9, 0xf0]), // taken, back to the tail
    ];
    // Each tail four times (so that A replays and the chain A -> B forms), then another.
    let pairs = [
        (0, 1),
        (1, 0),
        (0, 2),
        (2, 0),
        (1, 2),
        (2, 1),
        (2, 3),
        (3, 2),
    ];
    let order: Vec<usize> = pairs.iter().flat_map(|&(x, y)| [x, x, x, x, y]).collect();
    let run = |memoize: bool| {
        let mut t = Timing::new(TimingConfig {
            memoize,
            model_fetch: false,
            ..Default::default()
        });
        let mut cycles = Vec::new();
        for _ in 0..4 {
            for &v in &order {
                for &(pc, ins) in tails[v].iter().chain(&rest) {
                    cycles.push(t.issue(pc, ins));
                    if ins.op == spu_isa::table::Op::Hbrr {
                        t.hint(pc, hinted_branch[v], 0xf0);
                    }
                    if spu_isa::analysis::is_branch(ins.op) {
                        let taken = pc == 0x118;
                        t.branch_resolved(pc, ins, taken, if taken { 0xf0 } else { pc + 4 });
                    }
                }
            }
        }
        (cycles, t.finish_profile())
    };
    let (c0, p0) = run(false);
    let (c1, p1) = run(true);
    assert_eq!(c0, c1);
    assert_eq!(p0.totals, p1.totals);
    let a0: Vec<_> = p0.addresses().map(|(a, s)| (a, *s)).collect();
    let a1: Vec<_> = p1.addresses().map(|(a, s)| (a, *s)).collect();
    assert_eq!(a0, a1);
    // B's load-use stall happens after some tails and not after others.
    let b = p0.get(0x114).unwrap();
    assert!(
        b.stall_total() > 0 && b.stall_total() < b.executions,
        "{b:?}"
    );
    assert!(p0.totals.hint_hits > 0);
}
