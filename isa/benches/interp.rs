//! Simulated SPU instructions per host second on mixed loops (loads, float multiply-adds,
//! shuffles, adds, a store, a hinted branch), timing model off and on:
//! `cargo bench -p spu-isa`.
//!
//! `accumulating` is the loop of `spu bench` (its fma chain grows without bound, so after
//! the first iterations every fma takes the float unit's exact path); `bounded` does the
//! same work on values that stay in range, the common case in real kernels; `integer`
//! replaces the float operations with `selb` and `xor`. Each runs with the interpreter
//! and the block compiler (`interp` or `jit` as an argument picks one).

use spu_isa::encode;
use spu_isa::jit::Engine;
use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::table::forms_named;
use std::time::Instant;

fn asm(lines: &[(&str, &[i64])]) -> Vec<u8> {
    let mut out = Vec::new();
    for (i, (m, ops)) in lines.iter().enumerate() {
        let form = forms_named(m)
            .find(|f| f.operands.len() == ops.len())
            .unwrap_or_else(|| panic!("{m}"));
        out.extend(encode(form, ops, 4 * i as u32).to_be_bytes());
    }
    out
}

/// The loop body starts at 24 (word 6); data at 0x1000.
fn program(iterations: u32, kind: &str) -> Vec<u8> {
    let (acc7, acc8) = if kind == "accumulating" {
        (7, 8)
    } else {
        (10, 10)
    };
    let (fma, fa) = if kind == "integer" {
        ("selb", "xor")
    } else {
        ("fma", "fa")
    };
    let mut image = asm(&[
        ("ila", &[3, 0x1000]),
        ("il", &[4, 0]),
        ("ilhu", &[10, 0x3f80]),
        ("ilhu", &[9, (iterations >> 16) as i64]),
        ("iohl", &[9, (iterations & 0xffff) as i64]),
        ("ila", &[11, 0x10203]),
        // loop (24):
        ("hbrr", &[24 + 36, 24]),
        ("lqd", &[5, 0, 3]),
        ("lqd", &[6, 16, 3]),
        (fma, &[7, 5, 6, acc7]),
        (fma, &[8, 6, 10, acc8]),
        ("shufb", &[12, 5, 6, 11]),
        ("a", &[4, 4, 12]),
        ("ai", &[9, 9, -1]),
        (fa, &[13, 7, 8]),
        ("stqd", &[13, 32, 3]),
        ("brnz", &[9, 24]),
        ("stop", &[0x2000]),
    ]);
    image.resize(0x1000, 0);
    for f in [1.5f32, 2.0, 0.5, 3.0, 0.25, 1.0, 2.0, 4.0] {
        image.extend(f.to_bits().to_be_bytes());
    }
    image.resize(0x1030, 0);
    image
}

fn measure(name: &str, iterations: u32, timing: bool, engine: Engine) {
    let image = program(iterations, name);
    let mut best = f64::MAX;
    let mut n = 0;
    for _ in 0..3 {
        let mut spu = Spu::new(0);
        spu.set_engine(engine);
        spu.load_image(&image);
        if timing {
            spu.enable_timing(Default::default());
        }
        let mut memory = MainMemory::zeroed(4096);
        let t = Instant::now();
        let stop = spu.run(&mut memory, u64::MAX);
        let s = t.elapsed().as_secs_f64();
        assert_eq!(stop, StopReason::Stop(0x2000), "{name}");
        n = spu.instructions();
        best = best.min(s);
    }
    println!(
        "{name:>12} {engine:6}: {n} instructions in {best:.3} s = {:7.1} M simulated instructions per host second (timing {}, best of 3)",
        n as f64 / best / 1e6,
        if timing { "on" } else { "off" }
    );
}

/// Arguments: an iteration count, the names of the loops to run, `on` or `off` for the
/// timing model, `interp` or `jit` for the engine (both when neither is given).
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let iterations = args
        .iter()
        .find_map(|a| a.parse().ok())
        .unwrap_or(10_000_000);
    const LOOPS: [&str; 3] = ["bounded", "accumulating", "integer"];
    let named = args.iter().any(|a| LOOPS.contains(&a.as_str()));
    let modes: Vec<bool> = [false, true]
        .into_iter()
        .filter(|&on| {
            let word = if on { "on" } else { "off" };
            !args.iter().any(|a| a == "on" || a == "off") || args.iter().any(|a| a == word)
        })
        .collect();
    let engines: Vec<Engine> = [Engine::Interp, Engine::Jit]
        .into_iter()
        .filter(|e| {
            !args.iter().any(|a| a == "interp" || a == "jit") || args.iter().any(|a| *a == e.name())
        })
        .collect();
    for name in LOOPS {
        if !named || args.iter().any(|a| a == name) {
            for &timing in &modes {
                for &engine in &engines {
                    measure(name, iterations, timing, engine);
                }
            }
        }
    }
}
