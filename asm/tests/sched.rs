//! The list scheduler (`spu_asm::sched`, the `.sched` blocks): exact output on small
//! blocks, each rule that moves an instruction, and the errors that name their line.

use spu_asm::sched::{parse_options, parse_registers, schedule, SchedError, SchedOptions};
use spu_asm::{assemble, Options};

fn no_names(_: &str) -> Option<u8> {
    None
}

fn pool(p: &str) -> SchedOptions {
    SchedOptions {
        pool: parse_registers(p).unwrap(),
        scratch: Vec::new(),
    }
}

fn run(block: &str, opts: &SchedOptions, start: Option<u32>) -> (Vec<String>, u32) {
    let lines: Vec<&str> = block.lines().collect();
    let s = schedule(&lines, opts, start, &no_names).unwrap_or_else(|e| panic!("{e:?}"));
    let text = s
        .lines
        .iter()
        .map(|(l, _)| l.split_whitespace().collect::<Vec<_>>().join(" "))
        .collect();
    (text, s.cycles)
}

fn fails(block: &str, opts: &SchedOptions) -> SchedError {
    let lines: Vec<&str> = block.lines().collect();
    schedule(&lines, opts, None, &no_names).unwrap_err()
}

#[test]
fn a_load_chain_pairs_with_independent_work() {
    // Critical path first: the load (6) feeds fa (6) feeds the store; the ai and the
    // shuffle fill the slots; %a and %b get the pool's registers in issue order.
    let (out, cycles) = run(
        "lqd %a, 0($3)\nfa %b, %a, $6\nai $4, $4, 1\nstqd %b, 0($5)\nshufb $7, $8, $8, $9",
        &pool("20-23"),
        None,
    );
    assert_eq!(
        out,
        [
            ".align 3",
            "ai $4, $4, 1",
            "lqd $20, 0($3)",
            "nop",
            "shufb $7, $8, $8, $9",
            "fa $21, $20, $6",
            "lnop",
            "nop",
            "stqd $21, 0($5)",
        ]
    );
    assert_eq!(cycles, 13);
}

#[test]
fn registers_are_reused_after_their_last_read() {
    // Two independent chains through a pool of two: a chain needs both registers (the
    // allocator takes a new one before freeing the last use), so they run one after
    // the other and the second takes the registers the first one freed.
    let (out, _) = run(
        "il %a, 1\nai %b, %a, 1\nstqd %b, 0($3)\nil %c, 2\nai %d, %c, 2\nstqd %d, 16($3)",
        &pool("30,31"),
        None,
    );
    let code: Vec<&String> = out.iter().filter(|l| !l.ends_with("nop")).collect();
    assert_eq!(
        code,
        [
            ".align 3",
            "il $30, 1",
            "ai $31, $30, 1",
            "stqd $31, 0($3)",
            "il $30, 2",
            "ai $31, $30, 2",
            "stqd $31, 16($3)",
        ]
    );
}

#[test]
fn barriers_stores_and_labels_keep_their_order() {
    let block = "\
start:
lqd $10, 0($3)
! wrch $MFC_LSA, $10
ai $11, $11, 1
stqd $12, 0($4)
~ stqd $13, 16($4)
lqd $14, 32($4)
mid:
br start";
    let (out, _) = run(block, &SchedOptions::default(), None);
    let code: Vec<&String> = out.iter().filter(|l| !l.ends_with("nop")).collect();
    let at = |s: &str| code.iter().position(|l| l.starts_with(s)).unwrap();
    assert_eq!(code[1], "start:");
    // Nothing moves above the channel write, which waits for the load.
    assert!(at("lqd $10") < at("wrch") && at("wrch") < at("ai $11"));
    assert!(at("wrch") < at("stqd $12") && at("wrch") < at("lqd $14"));
    // The label stays with the branch after everything else.
    assert_eq!(code[code.len() - 2], "mid:");
    assert_eq!(code[code.len() - 1], "br start");
}

#[test]
fn a_hint_goes_late_but_far_enough_from_the_branch() {
    let mut block = String::from("hbrr end, top\n");
    for r in 10..40 {
        block += &format!("ai ${r}, ${r}, 1\n");
    }
    block += "end:\nbr top";
    let (out, _) = run(&block, &SchedOptions::default(), None);
    let hint = out.iter().position(|l| l.starts_with("hbrr")).unwrap();
    let branch = out.iter().position(|l| l == "br top").unwrap();
    // One add per cycle: the latest odd slot 11 cycles before the branch, 22 instructions
    // ahead of it (the label is not one).
    let distance = out[hint + 1..=branch]
        .iter()
        .filter(|l| !l.ends_with(':'))
        .count();
    assert_eq!(distance, 22, "{out:?}");
}

#[test]
fn each_fetch_line_keeps_a_cycle_for_the_prefetch() {
    // 14 loads paired with 14 adds: at address 0 every pair would use the local store;
    // the scheduler leaves the odd slot of pair 8 to the instruction prefetch.
    let mut block = String::new();
    for k in 0..14 {
        block += &format!(
            "lqd ${}, {}($3)\nai ${}, ${}, 1\n",
            10 + k,
            16 * k,
            40 + k,
            40 + k
        );
    }
    let (at_line_start, _) = run(&block, &SchedOptions::default(), Some(0));
    assert_eq!(at_line_start[1 + 2 * 8 + 1], "lnop", "{at_line_start:?}");
    let (unknown, _) = run(&block, &SchedOptions::default(), None);
    assert!(!unknown.iter().any(|l| l == "lnop"), "{unknown:?}");
}

/// The instructions of a scheduled block, without the filler.
fn code(block: &str, opts: &SchedOptions) -> Vec<String> {
    let (out, _) = run(block, opts, None);
    out.into_iter().filter(|l| !l.ends_with("nop")).collect()
}

#[test]
fn irp_repeats_with_substitution() {
    assert_eq!(
        code(
            ".irp K, 0, 1\nil %v\\K, \\K\nstqd %v\\K, \\K*16($3)\n.endr",
            &pool("50-53")
        ),
        [
            ".align 3",
            "il $50, 0",
            "il $51, 1",
            "stqd $50, 0*16($3)",
            "stqd $51, 1*16($3)"
        ]
    );
    // `\()` ends a parameter's name, so a value can come before more text (gas's rule).
    assert_eq!(
        code(
            ".irp R, a, b\nil %\\R\\()0, 1\nil %\\R\\()1, 2\na $3, %\\R\\()0, %\\R\\()1\n.endr",
            &pool("50-53")
        ),
        [
            ".align 3",
            "il $50, 1",
            "il $51, 2",
            "il $52, 1",
            "a $3, $50, $51",
            "il $53, 2",
            "a $3, $52, $53"
        ]
    );
}

#[test]
fn bad_blocks_name_their_line() {
    let e = fails("il $3, 1\nfrob $3, $4", &SchedOptions::default());
    assert_eq!((e.line, e.column), (1, 1));
    assert!(e.message.contains("frob"), "{}", e.message);
    let e = fails("il $3, 1\nai $4, NOWHERE, 1", &SchedOptions::default());
    assert_eq!(e.line, 1);
    assert!(e.message.contains("NOWHERE"), "{}", e.message);
    let e = fails("il $3, 1\nover:", &SchedOptions::default());
    assert_eq!(e.line, 1);
    let e = fails(".irp K, 1\nil $3, \\K", &SchedOptions::default());
    assert!(e.message.contains(".endr"), "{}", e.message);
    let e = fails("il $3, 1\n.align 3", &SchedOptions::default());
    assert!(e.message.contains(".align"), "{}", e.message);
    let e = fails(
        "il %a, 1\nil %b, 2\nil %c, 3\nselb $3, %a, %b, %c",
        &pool("20,21"),
    );
    assert!(e.message.contains("pool"), "{}", e.message);
}

#[test]
fn options_are_checked() {
    assert_eq!(
        parse_options("pool=78-80,$83 scratch=66").unwrap(),
        SchedOptions {
            pool: vec![78, 79, 80, 83],
            scratch: vec![66]
        }
    );
    for bad in [
        "pool=5-3", "pool=128", "pool=1,1", "colour=3", "pool", "pool=x",
    ] {
        assert!(parse_options(bad).is_err(), "{bad}");
    }
}

fn asm(src: &str) -> Result<Vec<u8>, Vec<String>> {
    assemble(src, "t.s", &Options::default())
        .map(|o| o.image)
        .map_err(|d| d.iter().map(|d| d.to_string()).collect())
}

#[test]
fn the_assembler_assembles_the_schedule() {
    // A .sched block with register names assembles to the schedule written out.
    let block = "\
        .set BASE, 3
        il $9, 0
        .sched pool=20-23
        lqd %a, 0(BASE)
        fa %b, %a, $6
        ai $4, $4, 1
        stqd %b, 0($5)
        shufb $7, $8, $8, $9
        .endsched
        stop
";
    let written = "\
        .set BASE, 3
        il $9, 0
        .align 3
        ai $4, $4, 1
        lqd $20, 0(BASE)
        nop
        shufb $7, $8, $8, $9
        fa $21, $20, $6
        lnop
        nop
        stqd $21, 0($5)
        stop
";
    assert_eq!(asm(block).unwrap(), asm(written).unwrap());
}

#[test]
fn the_assembler_reports_sched_errors_at_their_line() {
    let e = asm("il $3, 0\n.sched\nil $4, 1\n").unwrap_err();
    assert!(
        e[0].contains("t.s:2:") && e[0].contains("missing .endsched"),
        "{e:?}"
    );
    let e = asm("il $3, 0\n.endsched\n").unwrap_err();
    assert!(
        e[0].contains("t.s:2:") && e[0].contains(".endsched"),
        "{e:?}"
    );
    let e = asm(".sched\nil $3, 0\nai $4, %q, 1\n.endsched\n").unwrap_err();
    assert!(e[0].contains("t.s:3:"), "{e:?}");
    let e = asm(".sched pool=9-1\n.endsched\n").unwrap_err();
    assert!(e[0].contains("t.s:1:"), "{e:?}");
}

#[test]
fn a_macro_called_in_a_sched_block_is_scheduled_with_it() {
    // The macro's lines join the block (its virtual registers, its arguments substituted)
    // and are scheduled with the rest: the same image as the block written out.
    let with_macro = "\
        .macro SCALE out, in
        fm %s, \\in, $6
        fa \\out, %s, $7
        .endm
        .sched pool=20-23
        lqd %a, 0($3)
        SCALE %b, %a
        stqd %b, 0($5)
        .endsched
        stop
";
    let written = "\
        .sched pool=20-23
        lqd %a, 0($3)
        fm %s, %a, $6
        fa %b, %s, $7
        stqd %b, 0($5)
        .endsched
        stop
";
    assert_eq!(asm(with_macro).unwrap(), asm(written).unwrap());
    // Without the expansion the block would not assemble at all.
    assert!(asm(&with_macro.replace("SCALE %b, %a", "SCALE2 %b, %a")).is_err());
}

#[test]
fn a_conditional_in_a_sched_block_picks_its_lines_before_scheduling() {
    // `.ifdef` / `.else` / `.endif` inside a block (nested too): only the taken branch's
    // lines are scheduled, the same image as the block written out with them alone.
    let block = |defined: bool| {
        format!(
            "{}        .sched pool=20-23
        lqd %a, 0($3)
        .ifdef WIDE
        fm %b, %a, $6
        .if 2 > 1
        fa %b2, %b, $7
        .else
        fs %b2, %b, $7
        .endif
        stqd %b2, 0($5)
        .else
        stqd %a, 0($5)
        .endif
        .endsched
        stop
",
            if defined {
                "        .set WIDE, 1\n"
            } else {
                ""
            }
        )
    };
    let wide = "\
        .set WIDE, 1
        .sched pool=20-23
        lqd %a, 0($3)
        fm %b, %a, $6
        fa %b2, %b, $7
        stqd %b2, 0($5)
        .endsched
        stop
";
    let narrow = "\
        .sched pool=20-23
        lqd %a, 0($3)
        stqd %a, 0($5)
        .endsched
        stop
";
    assert_eq!(asm(&block(true)).unwrap(), asm(wide).unwrap());
    assert_eq!(asm(&block(false)).unwrap(), asm(narrow).unwrap());
    assert_ne!(asm(wide).unwrap(), asm(narrow).unwrap());
    // An unclosed conditional in a block is an error.
    assert!(
        asm(&block(true).replace("        .endif\n        .endsched", "        .endsched"))
            .is_err()
    );
}

/// Eight independent chains (a load, a reciprocal and its Newton step, two stores) through a
/// pool of 12: ranked by critical path alone, every chain's load goes first, the loaded
/// values fill the pool and the chains then wait on it; the program-order and pressure
/// ranks overlap fewer chains at once and finish sooner, and the scheduler keeps the
/// fewest-cycle schedule.
#[test]
fn many_chains_through_a_small_pool_take_the_fewest_cycle_rank() {
    let mut block = String::new();
    for k in 0..8 {
        let o = 16 * k;
        block.push_str(&format!(
            "lqd %d{k}, {o}($3)\nfrest %y{k}, %d{k}\nfi %z{k}, %d{k}, %y{k}\n\
             fnms %e{k}, %d{k}, %z{k}, $5\nfma %r{k}, %e{k}, %z{k}, %z{k}\n\
             fcgt %m{k}, %r{k}, $6\nselb $6, $6, %r{k}, %m{k}\n\
             stqd %r{k}, {o}($4)\nstqd %d{k}, {o}($7)\n"
        ));
    }
    let (_, cycles) = run(&block, &pool("20-31"), None);
    assert_eq!(cycles, 129); // the critical path's rank alone: 154
}

#[test]
fn a_register_named_after_the_block_is_scheduled_with_its_value() {
    // The layout passes schedule each block again; the first pass reads the not yet
    // defined BASE as 0, so there the load does not wait for the `ai` on $3 and could go
    // first. The assembled block must be the one scheduled with BASE = 3, as if BASE
    // were set before it.
    let block = |set_before: bool| {
        let set = ".set BASE, 3\n";
        format!(
            "{}        .sched pool=20-23\n        ai $3, $3, 16\n        lqd %a, 0(BASE)\n\
             fa %b, %a, $6\n        stqd %b, 0($5)\n        .endsched\n        stop\n{}",
            if set_before { set } else { "" },
            if set_before { "" } else { set },
        )
    };
    let (after, before) = (asm(&block(false)).unwrap(), asm(&block(true)).unwrap());
    assert_eq!(after, before);
    // And with BASE = 0 from the start the load does go first: the two schedules differ.
    let zero = asm(&block(true).replace(".set BASE, 3", ".set BASE, 0")).unwrap();
    assert_ne!(zero[..8], before[..8]);
}

#[test]
fn a_gather_holds_issue_for_its_four_reads() {
    // lgw (the gather extension, docs/extensions.md): 9 cycles to its result, and nothing
    // issues in the 3 cycles after it, so the independent lqd waits to cycle 4 and the fa
    // to the gather's result at 9.
    let (out, cycles) = run(
        "lgw %a, $3\nai $4, $4, 1\nfa %b, %a, $6\nlqd $7, 0($8)\nstqd %b, 0($5)",
        &pool("20-23"),
        None,
    );
    assert_eq!(
        out,
        [
            ".align 3",
            "ai $4, $4, 1",
            "lgw $20, $3",
            "nop",
            "lqd $7, 0($8)",
            "fa $21, $20, $6",
            "lnop",
            "nop",
            "stqd $21, 0($5)",
        ]
    );
    assert_eq!(cycles, 16);
}
