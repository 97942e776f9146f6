//! `spu timing`: the static listing in `spu_timing`'s layout.

use spu_isa::static_timing::{analyze_source, render_static, static_json};

const EULER: &str = include_str!("data/timing_euler.s");

/// The Euler particle-system inner loop listed with `spu_timing` in the Cell SDK 3.0
/// Programmer's Guide ("Static analysis of SPE threads"). There the loop starts at cycle
/// 47; relative to its first instruction the published issue cycles are these (read off
/// the listing's digit columns), with 'D' dual-issue marks on a/lqx, ila/lqx, ai/lqa and
/// ai/brnz and 'd' on the fma/stqx pair that a dependency splits.
#[test]
fn euler_loop_matches_the_published_listing() {
    let t = analyze_source(EULER, Some(".L19")).unwrap();
    let issue: Vec<u64> = t.rows.iter().map(|r| r.issue).collect();
    assert_eq!(
        issue,
        [0, 0, 1, 1, 2, 7, 13, 14, 15, 15, 16, 20, 24, 28, 34, 40, 41, 41]
    );
    let marks: String = t.rows.iter().map(|r| r.mark).collect();
    assert_eq!(marks, "DDDD    DD    ddDD");
    let stall: Vec<u64> = t.rows.iter().map(|r| r.stall).collect();
    assert_eq!(
        stall,
        [0, 0, 0, 0, 0, 4, 5, 0, 0, 0, 0, 3, 3, 3, 5, 5, 0, 0]
    );
    assert_eq!(t.blocks.len(), 1);
    assert_eq!(
        (
            t.blocks[0].instructions,
            t.blocks[0].cycles,
            t.blocks[0].dual
        ),
        (18, 42, 4)
    );
}

#[test]
fn euler_listing_snapshot() {
    let t = analyze_source(EULER, None).unwrap();
    insta::assert_snapshot!(render_static(&t, false));
}

#[test]
fn euler_json_snapshot() {
    let t = analyze_source(EULER, Some(".L19")).unwrap();
    insta::assert_snapshot!(static_json(&t));
}

/// Blocks end at branches and start at labels; the timeline runs on across them.
#[test]
fn blocks_and_running_count() {
    let src = "\
f:\n\
\tila\t$3,1\n\
\tfa\t$4,$3,$3\n\
\tfm\t$5,$4,$4\n\
\tbrz\t$5,f\n\
\tdfa\t$6,$7,$8\n\
\tlnop\n\
.L2:\n\
\tdfa\t$6,$6,$6\n\
\tstqd\t$6,0($1)\n";
    let t = analyze_source(src, None).unwrap();
    // ila 0; fa waits for ila (FX2 2) -> 2; fm waits 6 -> 8; brz waits 6 -> 14;
    // dfa 15 (its own block after the branch); lnop blocked 6 cycles -> 22;
    // .L2: dfa reads $6 (13) -> 28; stqd (odd slot, dfa never pairs) waits 13 -> 41.
    let cycles: Vec<u64> = t.rows.iter().map(|r| r.cycle).collect();
    assert_eq!(cycles, [0, 2, 8, 14, 15, 22, 28, 41]);
    let blocks: Vec<(Option<&str>, u64, u64)> = t
        .blocks
        .iter()
        .map(|b| (b.label.as_deref(), b.instructions, b.cycles))
        .collect();
    assert_eq!(
        blocks,
        [(Some("f"), 4, 15), (None, 2, 8), (Some(".L2"), 2, 14)]
    );
    insta::assert_snapshot!(render_static(&t, true));
}

/// `--label` finds a block by any label at its address, not only the first one.
#[test]
fn label_shared_with_another_finds_the_block() {
    let src = "\
\tila\t$3,1\n\
\tbrz\t$3,.L18\n\
.L18:\n\
.L19:\tfa\t$4,$3,$3\n\
\tfm\t$5,$4,$4\n";
    let by_first = analyze_source(src, Some(".L18")).unwrap();
    let by_second = analyze_source(src, Some(".L19")).unwrap();
    assert_eq!(by_first.rows.len(), 2);
    let cycles = |t: &spu_isa::static_timing::StaticTiming| {
        t.rows.iter().map(|r| r.cycle).collect::<Vec<_>>()
    };
    assert_eq!(cycles(&by_first), cycles(&by_second));
    assert!(analyze_source(src, Some(".L20"))
        .unwrap_err()
        .contains("no block starts at label `.L20`"));
}
