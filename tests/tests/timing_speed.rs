//! Speed of the timing model with all counters on, on a mixed loop (loads, multiply-adds,
//! shuffles, adds, a hinted branch). Run with
//! `cargo test --release -p spu-tests --test all timing_speed -- --ignored --nocapture`.

use spu_isa::codec::{decode, encode, Inst};
use spu_isa::table::forms_named;
use spu_isa::timing::{Timing, TimingConfig};
use std::time::Instant;

fn inst(m: &str, ops: &[i64], pc: u32) -> Inst {
    let form = forms_named(m)
        .find(|f| f.operands.len() == ops.len())
        .unwrap();
    decode(encode(form, ops, pc))
}

pub fn mixed_loop() -> Vec<(u32, Inst)> {
    let body: [(&str, &[i64]); 16] = [
        ("hbrr", &[0x3c, 0x0]),
        ("lqd", &[10, 0, 1]),
        ("fma", &[20, 21, 22, 20]),
        ("lqd", &[11, 16, 1]),
        ("fma", &[23, 24, 25, 23]),
        ("shufb", &[12, 10, 11, 13]),
        ("a", &[30, 30, 31]),
        ("lqd", &[14, 32, 1]),
        ("fma", &[26, 27, 28, 26]),
        ("shufb", &[15, 14, 12, 13]),
        ("ai", &[1, 1, 48]),
        ("stqd", &[15, 48, 2]),
        ("fm", &[29, 27, 28]),
        ("lnop", &[]),
        ("ai", &[5, 5, -1]),
        ("brnz", &[5, 0x0]),
    ];
    body.iter()
        .enumerate()
        .map(|(i, (m, o))| (i as u32 * 4, inst(m, o, i as u32 * 4)))
        .collect()
}

#[test]
#[ignore]
fn timing_model_speed() {
    let body = mixed_loop();
    let iterations = 5_000_000u64;
    let mut t = Timing::new(TimingConfig::default());
    let start = Instant::now();
    for i in 0..iterations {
        for &(pc, ins) in &body {
            t.issue(pc, ins);
        }
        let (pc, ins) = body[15];
        t.branch_resolved(
            pc,
            ins,
            i + 1 < iterations,
            if i + 1 < iterations { 0 } else { 0x40 },
        );
    }
    let secs = start.elapsed().as_secs_f64();
    let n = iterations * body.len() as u64;
    let p = t.finish_profile();
    println!(
        "{} instructions in {:.3} s: {:.1} M instructions/s; {} cycles, CPI {:.3}",
        n,
        secs,
        n as f64 / secs / 1e6,
        p.totals.cycles,
        p.totals.cpi()
    );
    println!("{}", p.totals.report());
    println!("memo {:?}", t.memo_stats());
}
