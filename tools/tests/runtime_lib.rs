//! The runtime's library half (`kernels/runtime/`: malloc.s, divdi3.s, divsi3.s, clock.s)
//! run under `spu run` in programs written as spu-gcc writes them: the heap's reuse,
//! merging, growth and every out-of-memory path by exact output, and libgcc's division
//! helpers against Rust's integer arithmetic on edge cases and many pseudo-random values.

use std::fmt::Write;
use std::path::PathBuf;

fn dir(test: &str) -> PathBuf {
    crate::support::fresh_dir("rt", test)
}

use crate::support::spu_in as spu;

/// Builds `source` with the runtime and runs it: stdout and exit status.
fn run(test: &str, source: &str) -> (String, i32) {
    let d = dir(test);
    std::fs::write(d.join("prog.s"), source).unwrap();
    let (_, err, code) = spu(&["as", "--runtime", "prog.s", "-o", "prog.elf"], &d);
    assert_eq!(code, 0, "spu as --runtime: {err}");
    let (out, err, code) = spu(&["run", "-q", "prog.elf"], &d);
    assert!(err.is_empty(), "{err}");
    (out, code)
}

/// main: the heap. Each line of output is one claim about it.
const HEAP: &str = r#"
        .section .rodata
.Lfmt:  .string "%s %d\n"
.Lgrow: .string "heap grew, available stack fell by"
.Lfirst: .string "freed block reused (first fit)"
.Lmerge: .string "freed neighbours merged and reused"
.Lzero: .string "calloc zeroes a dirty block, sum"
.Lkeep: .string "realloc kept"
.Lsame: .string "realloc in place"
.Lbig:  .string "malloc(0x50000) is null, errno"
.Lover: .string "calloc(0x10000, 0x10001) is null, errno"
.Lfull: .string "heap exhausted below the stack reserve, errno"
.Lfree0: .string "free(0) is harmless"
.Lhello: .string "hello, heap"
.Lstr:  .string "%s: %s\n"
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $82, -48($sp)
        stqd    $83, -64($sp)
        stqd    $84, -80($sp)
        stqd    $sp, -128($sp)
        ai      $sp, $sp, -128
        rotqbyi $84, $sp, 4             # the available stack before
        il      $3, 100
        brsl    $lr, malloc
        ori     $80, $3, 0              # p1: a 128-byte block
        il      $3, 40
        brsl    $lr, malloc
        ori     $81, $3, 0              # p2: 64 bytes after it
        rotqbyi $4, $sp, 4
        sf      $4, $4, $84
        ila     $3, .Lfmt
        ila     $4, .Lgrow
        rotqbyi $5, $sp, 4
        sf      $5, $5, $84
        brsl    $lr, printf
        # free p1; malloc(50) takes its place.
        ori     $3, $80, 0
        brsl    $lr, free
        il      $3, 50
        brsl    $lr, malloc
        ceq     $5, $3, $80
        ila     $3, .Lfmt
        ila     $4, .Lfirst
        andi    $5, $5, 1
        brsl    $lr, printf
        # Dirty p1 (its 50 bytes), free p1 and p2: one 192-byte block again, which
        # malloc(170) fits exactly.
        ori     $3, $80, 0
        il      $4, 0x5a
        il      $5, 50
        brsl    $lr, memset
        ori     $3, $80, 0
        brsl    $lr, free
        ori     $3, $81, 0
        brsl    $lr, free
        il      $3, 170
        brsl    $lr, malloc
        ceq     $5, $3, $80
        ori     $82, $3, 0
        ila     $3, .Lfmt
        ila     $4, .Lmerge
        andi    $5, $5, 1
        brsl    $lr, printf
        # Freed again, calloc(25, 4) gets the dirty block back, zeroed.
        ori     $3, $82, 0
        brsl    $lr, free
        il      $3, 25
        il      $4, 4
        brsl    $lr, calloc
        ori     $82, $3, 0
        il      $83, 0                  # the sum of its 100 bytes
        il      $6, 0
1:      a       $7, $82, $6
        lqd     $8, 0($7)
        ai      $9, $7, -3
        rotqby  $8, $8, $9
        andi    $8, $8, 0xff
        a       $83, $83, $8
        ai      $6, $6, 1
        ceqi    $9, $6, 100
        brz     $9, 1b
        ila     $3, .Lfmt
        ila     $4, .Lzero
        ori     $5, $83, 0
        brsl    $lr, printf
        # realloc: within the block it stays; past it the contents move.
        ori     $3, $82, 0
        il      $4, 112                 # what calloc's 128-byte block holds
        brsl    $lr, realloc
        ceq     $5, $3, $82
        ila     $3, .Lfmt
        ila     $4, .Lsame
        andi    $5, $5, 1
        brsl    $lr, printf
        ori     $3, $82, 0
        ila     $4, .Lhello
        brsl    $lr, strcpy
        ori     $3, $82, 0
        il      $4, 1000
        brsl    $lr, realloc
        ori     $5, $3, 0
        ila     $3, .Lstr
        ila     $4, .Lkeep
        brsl    $lr, printf
        # Out of memory: too large, an overflowing calloc, and the heap run into the stack.
        ilhu    $3, 5
        brsl    $lr, malloc
        ori     $80, $3, 0
        ila     $3, errno
        lqd     $5, 0($3)
        a       $5, $5, $80
        ila     $3, .Lfmt
        ila     $4, .Lbig
        brsl    $lr, printf
        ila     $3, errno
        il      $4, 0
        stqd    $4, 0($3)
        ilhu    $3, 1
        ilhu    $4, 1
        ori     $4, $4, 1
        brsl    $lr, calloc
        ori     $80, $3, 0
        ila     $3, errno
        lqd     $5, 0($3)
        a       $5, $5, $80
        ila     $3, .Lover
        ori     $4, $3, 0
        ila     $3, .Lfmt
        brsl    $lr, printf
        ila     $3, errno
        il      $4, 0
        stqd    $4, 0($3)
2:      il      $3, 0x4000
        brsl    $lr, malloc
        ori     $81, $80, 0
        ori     $80, $3, 0
        brnz    $3, 2b
        # The last block ends 4096 bytes or more below the stack; errno is ENOMEM.
        ila     $5, 0x4000 + 4096
        a       $4, $81, $5
        cgt     $4, $4, $sp             # -1 when past the reserve
        ila     $3, errno
        lqd     $5, 0($3)
        a       $5, $5, $4
        ila     $3, .Lfmt
        ila     $4, .Lfull
        brsl    $lr, printf
        il      $3, 0
        brsl    $lr, free
        ila     $3, .Lfmt
        ila     $4, .Lfree0
        il      $5, 1
        brsl    $lr, printf
        il      $3, 0
        ai      $sp, $sp, 128
        lqd     $84, -80($sp)
        lqd     $83, -64($sp)
        lqd     $82, -48($sp)
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
        .size   main, .-main
"#;

#[test]
fn the_heap_reuses_merges_grows_and_runs_out_cleanly() {
    let (out, code) = run("heap", HEAP);
    assert_eq!(
        out,
        "heap grew, available stack fell by 192\n\
         freed block reused (first fit) 1\n\
         freed neighbours merged and reused 1\n\
         calloc zeroes a dirty block, sum 0\n\
         realloc in place 1\n\
         realloc kept: hello, heap\n\
         malloc(0x50000) is null, errno 12\n\
         calloc(0x10000, 0x10001) is null, errno 12\n\
         heap exhausted below the stack reserve, errno 12\n\
         free(0) is harmless 1\n"
    );
    assert_eq!(code, 0);
}

/// A simple deterministic generator (xorshift64*), with the bit widths spread so that
/// small, mid-sized and full-width operands all occur.
fn values(n: usize, seed: u64) -> Vec<u64> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            let v = x.wrapping_mul(0x2545_f491_4f6c_dd1d);
            v >> (v % 64)
        })
        .collect()
}

/// main: for each pair in the table, calls the four helpers named and prints their results.
fn division_program(pairs: &[(u64, u64)], wide: bool) -> String {
    let mut table = String::new();
    for (a, b) in pairs {
        if wide {
            writeln!(
                table,
                "\t.long\t{:#x}, {:#x}, {:#x}, {:#x}",
                a >> 32,
                a & 0xffff_ffff,
                b >> 32,
                b & 0xffff_ffff
            )
            .unwrap();
        } else {
            writeln!(
                table,
                "\t.long\t{:#x}, {:#x}, 0, 0",
                a & 0xffff_ffff,
                b & 0xffff_ffff
            )
            .unwrap();
        }
    }
    let (fmt, helpers, second) = if wide {
        (
            "%llx %llx %llx %llx\\n",
            ["__udivdi3", "__umoddi3", "__divdi3", "__moddi3"],
            "shlqbyi $4, $3, 8",
        )
    } else {
        (
            "%x %x %x %x\\n",
            ["__udivsi3", "__umodsi3", "__divsi3", "__modsi3"],
            "rotqbyi $4, $3, 4",
        )
    };
    let mut calls = String::new();
    for (k, h) in helpers.iter().enumerate() {
        writeln!(
            calls,
            "\tlqd\t$3, 0($80)\n\t{second}\n\tbrsl\t$lr, {h}\n\tori\t${}, $3, 0",
            82 + k
        )
        .unwrap();
    }
    table_loop_program(fmt, &table, pairs.len(), &calls)
}

/// The pairs: every combination of the edge cases, then pseudo-random ones.
fn pairs(edges: &[u64], random: usize, seed: u64) -> Vec<(u64, u64)> {
    let mut p: Vec<(u64, u64)> = edges
        .iter()
        .flat_map(|&a| edges.iter().map(move |&b| (a, b)))
        .collect();
    let v = values(2 * random, seed);
    p.extend(v.chunks(2).map(|c| (c[0], c[1])));
    p
}

#[test]
fn the_64_bit_division_helpers_match_rust() {
    let edges = [
        0,
        1,
        2,
        3,
        7,
        u64::MAX,
        u64::MAX - 1,
        1 << 63,
        (1 << 63) - 1,
        1 << 32,
        0xffff_ffff,
        10,
    ];
    let pairs = pairs(&edges, 120, 0x9e37_79b9_7f4a_7c15);
    let (out, code) = run("div64", &division_program(&pairs, true));
    let mut want = String::new();
    for &(a, b) in &pairs {
        let (sa, sb) = (a as i64, b as i64);
        // By zero: the quotient all ones, the remainder the dividend, then the signs.
        let (uq, ur) = (
            a.checked_div(b).unwrap_or(u64::MAX),
            a.checked_rem(b).unwrap_or(a),
        );
        let (sq, sr) = if b == 0 {
            (if sa < 0 { 1 } else { -1 }, sa)
        } else {
            (sa.wrapping_div(sb), sa.wrapping_rem(sb))
        };
        writeln!(want, "{uq:x} {ur:x} {:x} {:x}", sq as u64, sr as u64).unwrap();
    }
    assert_eq!(out, want);
    assert_eq!(code, 0);
}

#[test]
fn the_32_bit_division_helpers_match_rust() {
    let edges = [
        0,
        1,
        2,
        3,
        7,
        0xffff_ffff,
        0xffff_fffe,
        0x8000_0000,
        0x7fff_ffff,
        0x10000,
        10,
    ];
    let pairs: Vec<(u64, u64)> = pairs(&edges, 200, 0x2545_f491)
        .into_iter()
        .map(|(a, b)| (a & 0xffff_ffff, b & 0xffff_ffff))
        .collect();
    let (out, code) = run("div32", &division_program(&pairs, false));
    let mut want = String::new();
    for &(a, b) in &pairs {
        let (a, b) = (a as u32, b as u32);
        let (sa, sb) = (a as i32, b as i32);
        let (uq, ur) = (
            a.checked_div(b).unwrap_or(u32::MAX),
            a.checked_rem(b).unwrap_or(a),
        );
        let (sq, sr) = if b == 0 {
            (if sa < 0 { 1 } else { -1 }, sa)
        } else {
            (sa.wrapping_div(sb), sa.wrapping_rem(sb))
        };
        writeln!(want, "{uq:x} {ur:x} {:x} {:x}", sq as u32, sr as u32).unwrap();
    }
    assert_eq!(out, want);
    assert_eq!(code, 0);
}

/// clock() counts the simulated cycles: it grows, and never past the run's total.
#[test]
fn clock_counts_decrementer_ticks() {
    let source = r#"
        .section .rodata
.Lfmt:  .string "%u %u\n"
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $sp, -48($sp)
        ai      $sp, $sp, -48
        brsl    $lr, clock
        ori     $80, $3, 0
        il      $5, 1000
1:      ai      $5, $5, -1
        brnz    $5, 1b
        brsl    $lr, clock
        ori     $5, $3, 0
        ori     $4, $80, 0
        ila     $3, .Lfmt
        brsl    $lr, printf
        il      $3, 0
        ai      $sp, $sp, 48
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
"#;
    let d = dir("clock");
    std::fs::write(d.join("prog.s"), source).unwrap();
    let (_, err, code) = spu(&["as", "--runtime", "prog.s", "-o", "prog.elf"], &d);
    assert_eq!(code, 0, "{err}");
    let (out, _, code) = spu(&["run", "prog.elf"], &d);
    assert_eq!(code, 0, "{out}");
    let mut lines = out.lines();
    let first: Vec<u64> = lines
        .next()
        .unwrap()
        .split(' ')
        .map(|v| v.parse().unwrap())
        .collect();
    let cycles: u64 = out
        .lines()
        .find_map(|l| l.strip_prefix("cycles: "))
        .unwrap()
        .parse()
        .unwrap();
    // The 1000-iteration loop alone is 2000 instructions.
    assert!(first[0] > 0 && first[1] >= first[0] + 2000, "{out}");
    assert!(first[1] < cycles, "{out}");
    // Deterministic: the same figures again.
    let (again, _, _) = spu(&["run", "prog.elf"], &d);
    assert_eq!(again, out);
}

/// `spu prof` starts the program as `spu run` does (argc, argv, the stack) and serves its
/// PPE-assisted calls: the program's output comes first, then the profile of its run.
#[test]
fn prof_starts_and_serves_the_program_as_run_does() {
    let source = r#"
        .section .rodata
.Lfmt:  .string "argc=%d argv[0]=%s\n"
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $sp, -32($sp)
        ai      $sp, $sp, -32
        lqd     $5, 0($4)
        rotqby  $5, $5, $4
        ori     $4, $3, 0
        ila     $3, .Lfmt
        brsl    $lr, printf
        il      $3, 0
        ai      $sp, $sp, 32
        lqd     $lr, 16($sp)
        bi      $lr
        .size   main, .-main
"#;
    let d = dir("prof");
    std::fs::write(d.join("prog.s"), source).unwrap();
    let (_, err, code) = spu(&["as", "--runtime", "prog.s", "-o", "prog.elf"], &d);
    assert_eq!(code, 0, "{err}");
    let (run, _, _) = spu(&["run", "-q", "prog.elf"], &d);
    assert_eq!(run, "argc=1 argv[0]=prog.elf\n");
    let (out, err, code) = spu(&["prof", "prog.elf"], &d);
    assert_eq!((code, err.as_str()), (0, ""));
    assert!(
        out.starts_with("argc=1 argv[0]=prog.elf\nprog.elf: stopped with stop 0x2000\n"),
        "{out}"
    );
    assert!(out.contains("<main>") || out.contains("main:"), "{out}");
}

/// main: for each entry {double, int} of the table, the four conversions, printed as bits.
fn conversion_program(cases: &[(u64, u32)]) -> String {
    let mut table = String::new();
    for (d, i) in cases {
        writeln!(
            table,
            "\t.long\t{:#x}, {:#x}, {i:#x}, 0",
            d >> 32,
            d & 0xffff_ffff
        )
        .unwrap();
    }
    conversion_program_calling(
        &table,
        cases.len(),
        [
            "__fixdfsi",
            "__fixunsdfsi",
            "__floatsidf",
            "__float_unssidf",
        ],
        "%x %x %llx %llx",
    )
}

/// main: for each quadword of `table` ({double, integer}), calls the four helpers named
/// (two taking the double, two the integer) and prints their results with `format`.
fn conversion_program_calling(table: &str, n: usize, calls: [&str; 4], format: &str) -> String {
    let mut text = String::new();
    for (k, f) in calls.iter().enumerate() {
        // the integer is the quadword's second doubleword
        let integer = if k >= 2 { "\trotqbyi\t$3, $3, 8\n" } else { "" };
        writeln!(
            text,
            "\tlqd\t$3, 0($80)\n{integer}\tbrsl\t$lr, {f}\n\tori\t${}, $3, 0",
            82 + k
        )
        .unwrap();
    }
    table_loop_program(&format!("{format}\\n"), table, n, &text)
}

/// main: for each of the `n` quadwords of `table` (at `.Ltable`, walked in `$80`), runs
/// `calls` (which leave four results in `$82`..`$85`) and prints them with `printf(fmt)`.
fn table_loop_program(fmt: &str, table: &str, n: usize, calls: &str) -> String {
    format!(
        r#"
        .section .rodata
.Lfmt:  .string "{fmt}"
        .align  4
.Ltable:
{table}
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $82, -48($sp)
        stqd    $83, -64($sp)
        stqd    $84, -80($sp)
        stqd    $85, -96($sp)
        stqd    $sp, -128($sp)
        ai      $sp, $sp, -128
        ila     $80, .Ltable
        il      $81, {n}
1:      brz     $81, 2f
{calls}
        ila     $3, .Lfmt
        ori     $4, $82, 0
        ori     $5, $83, 0
        ori     $6, $84, 0
        ori     $7, $85, 0
        brsl    $lr, printf
        ai      $80, $80, 16
        ai      $81, $81, -1
        br      1b
2:      il      $3, 0
        ai      $sp, $sp, 128
        lqd     $85, -96($sp)
        lqd     $84, -80($sp)
        lqd     $83, -64($sp)
        lqd     $82, -48($sp)
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
        .size   main, .-main
"#
    )
}

/// libgcc2's __fixunsdfsi: from 2^31 up, x - 2^31 converted and 2^31 added back; below,
/// __fixdfsi's result (Rust's `as i32`: truncation, saturation, NaN 0) as unsigned.
fn fixunsdfsi(x: f64) -> u32 {
    if x >= 2147483648.0 {
        ((x - 2147483648.0) as i32 as u32).wrapping_add(0x8000_0000)
    } else {
        x as i32 as u32
    }
}

#[test]
fn the_conversion_helpers_match_rust() {
    let mut doubles: Vec<f64> = vec![
        0.0,
        -0.0,
        0.5,
        -0.5,
        0.999_999,
        1.0,
        -1.0,
        1.5,
        -1.5,
        2.5,
        -2.5,
        1e9,
        -1e9,
        2147483647.0,
        2147483647.5,
        2147483648.0,
        -2147483648.0,
        -2147483648.5,
        -2147483649.0,
        4294967295.0,
        4294967295.9,
        4294967296.0,
        3e9,
        -3e9,
        1e20,
        -1e20,
        f64::MAX,
        f64::MIN,
        f64::MIN_POSITIVE,
        5e-324,
        -5e-324,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        -f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        f64::EPSILON,
        123456.789,
    ];
    let ints: Vec<u32> = values(200, 0x1234_5678).iter().map(|v| *v as u32).collect();
    doubles.extend(values(160, 0xdead_beef).iter().map(|v| {
        // Integers-sized values with fractions, both signs, and raw bit patterns.
        let x = (*v as i64 as f64) / 1024.0;
        if v % 3 == 0 {
            f64::from_bits(*v)
        } else {
            x
        }
    }));
    let edge_ints = [
        0u32,
        1,
        2,
        0x7fff_ffff,
        0x8000_0000,
        0x8000_0001,
        0xffff_ffff,
        0xffff_fffe,
        1 << 20,
        (1 << 21) - 1,
    ];
    let cases: Vec<(u64, u32)> = doubles
        .iter()
        .enumerate()
        .map(|(k, d)| {
            (
                d.to_bits(),
                if k < edge_ints.len() {
                    edge_ints[k]
                } else {
                    ints[k % ints.len()]
                },
            )
        })
        .collect();
    let (out, code) = run("conv", &conversion_program(&cases));
    let mut want = String::new();
    for &(d, i) in &cases {
        let x = f64::from_bits(d);
        writeln!(
            want,
            "{:x} {:x} {:x} {:x}",
            x as i32 as u32,
            fixunsdfsi(x),
            (i as i32 as f64).to_bits(),
            (i as f64).to_bits()
        )
        .unwrap();
    }
    let got: Vec<&str> = out.lines().collect();
    for (k, (g, w)) in got.iter().zip(want.lines()).enumerate() {
        assert_eq!(g, &w, "case {k}: {:?}", f64::from_bits(cases[k].0));
    }
    assert_eq!(out, want);
    assert_eq!(code, 0);
}

/// main: for each entry {double, long long} of the table, the four 64-bit conversions,
/// printed as bits.
fn wide_conversion_program(cases: &[(u64, u64)]) -> String {
    let mut table = String::new();
    for (d, i) in cases {
        writeln!(
            table,
            "\t.long\t{:#x}, {:#x}, {:#x}, {:#x}",
            d >> 32,
            d & 0xffff_ffff,
            i >> 32,
            i & 0xffff_ffff
        )
        .unwrap();
    }
    conversion_program_calling(
        &table,
        cases.len(),
        [
            "__fixdfdi",
            "__fixunsdfdi",
            "__floatdidf",
            "__float_unsdidf",
        ],
        "%llx %llx %llx %llx",
    )
}

/// The 64-bit conversions' expected results: truncation with Rust's saturation (NaN 0)
/// and conversion rounded to nearest even, as Rust's `as` does both.
fn wide_conversions(d: u64, i: u64) -> String {
    let x = f64::from_bits(d);
    format!(
        "{:x} {:x} {:x} {:x}",
        x as i64 as u64,
        x as u64,
        (i as i64 as f64).to_bits(),
        (i as f64).to_bits()
    )
}

#[test]
fn the_64_bit_conversion_helpers_match_rust() {
    let p63 = 9223372036854775808.0f64;
    let mut doubles: Vec<f64> = vec![
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.0,
        -1.0,
        -1.5,
        4294967295.5,
        4294967296.0,
        -4294967296.5,
        9007199254740993.0,
        p63,
        -p63,
        p63 - 1024.0,
        -(p63 - 1024.0),
        p63 * 2.0,
        p63 * 2.0 - 2048.0,
        p63 * 4.0,
        -p63 * 2.0,
        1e300,
        -1e300,
        f64::MAX,
        f64::MIN_POSITIVE,
        -5e-324,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        -f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        123456789.987,
    ];
    let edge_ints = [
        0u64,
        1,
        u64::MAX,
        i64::MAX as u64,
        i64::MIN as u64,
        i64::MIN as u64 + 1,
        (1 << 53) + 1,
        (1 << 53) - 1,
        (1 << 54) + 2,
        (1 << 54) + 6,
        0xffff_ffff,
        0x1_0000_0000,
        0x8000_0000,
        0xffff_ffff_0000_0000,
        u64::MAX - 1023,
        u64::MAX - 1024,
        0x0020_0000_0000_0401,
        0x0020_0000_0000_0c01,
    ];
    doubles.extend(values(200, 0xfeed_f00d).iter().map(|v| {
        // Values across the whole 64-bit range, with fractions, both signs, and raw bits.
        let x = (*v as i64 as f64) / if v % 5 == 0 { 1024.0 } else { 1.0 };
        if v % 3 == 0 {
            f64::from_bits(*v)
        } else {
            x
        }
    }));
    let ints = values(300, 0x0bad_cafe);
    let cases: Vec<(u64, u64)> = doubles
        .iter()
        .enumerate()
        .map(|(k, d)| (d.to_bits(), edge_ints.get(k).copied().unwrap_or(ints[k])))
        .collect();
    let (out, code) = run("conv64", &wide_conversion_program(&cases));
    for (k, (g, &(d, i))) in out.lines().zip(&cases).enumerate() {
        assert_eq!(
            g,
            wide_conversions(d, i),
            "case {k}: {:?} {i:#x}",
            f64::from_bits(d)
        );
    }
    assert_eq!(out.lines().count(), cases.len(), "{out}");
    assert_eq!(code, 0);
}

#[test]
fn memcmp_orders_bytes_as_unsigned_chars() {
    let source = r#"
        .section .rodata
.Lfmt:  .string "%d %d %d %d\n"
.La:    .string "abc\x80x"
.Lb:    .string "abd\x01x"
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $82, -48($sp)
        stqd    $sp, -80($sp)
        ai      $sp, $sp, -80
        ila     $3, .La
        ila     $4, .Lb
        il      $5, 2
        brsl    $lr, memcmp
        ori     $80, $3, 0
        ila     $3, .La
        ila     $4, .Lb
        il      $5, 5
        brsl    $lr, memcmp
        ori     $81, $3, 0
        ila     $3, .La
        ai      $3, $3, 3
        ila     $4, .Lb
        ai      $4, $4, 3
        il      $5, 1
        brsl    $lr, memcmp
        ori     $82, $3, 0
        ila     $3, .La
        ila     $4, .Lb
        il      $5, 0
        brsl    $lr, memcmp
        ori     $7, $3, 0
        ori     $4, $80, 0
        ori     $5, $81, 0
        ori     $6, $82, 0
        ila     $3, .Lfmt
        brsl    $lr, printf
        il      $3, 0
        ai      $sp, $sp, 80
        lqd     $82, -48($sp)
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
"#;
    // 'c' - 'd' = -1; 0x80 - 0x01 = 127 (unsigned chars).
    assert_eq!(run("memcmp", source), ("0 -1 127 0\n".to_string(), 0));
}

/// The runtime is a library: a program links only the members it calls (GNU ld's archive
/// search), both through `spu as --runtime` and `spu as -c` + `spu ld --runtime`.
#[test]
fn a_program_links_only_the_runtime_members_it_calls() {
    let source = "\t.section .rodata\n.LC0:\t.string \"hi\"\n\t.text\n\t.global main\n\t.type main, @function\nmain:\tstqd\t$lr, 16($sp)\n\tstqd\t$sp, -32($sp)\n\tai\t$sp, $sp, -32\n\tila\t$3, .LC0\n\tbrsl\t$lr, puts\n\til\t$3, 5\n\tai\t$sp, $sp, 32\n\tlqd\t$lr, 16($sp)\n\tbi\t$lr\n";
    let d = dir("members");
    std::fs::write(d.join("prog.s"), source).unwrap();
    let (_, err, code) = spu(&["as", "-c", "prog.s", "-o", "prog.o"], &d);
    assert_eq!(code, 0, "{err}");
    // One output name for both: the executable's `.note.spu_name` records it.
    let (_, err, code) = spu(&["ld", "--runtime", "prog.o", "-o", "one.elf"], &d);
    assert_eq!((code, err.as_str()), (0, ""));
    let linked = std::fs::read(d.join("one.elf")).unwrap();
    let (_, err, code) = spu(&["as", "--runtime", "prog.s", "-o", "one.elf"], &d);
    assert_eq!(code, 0, "{err}");
    assert_eq!(std::fs::read(d.join("one.elf")).unwrap(), linked);
    let (dis, _, _) = spu(&["dis", "one.elf"], &d);
    for wanted in [
        "<_start>:",
        "<main>:",
        "<puts>:",
        "<__send_to_ppe>:",
        "exit>:",
    ] {
        assert!(dis.contains(wanted), "{wanted} missing:\n{dis}");
    }
    for unwanted in [
        "<malloc>:",
        "<__udivdi3>:",
        "<memcpy>:",
        "<clock>:",
        "<__fixdfsi>:",
    ] {
        assert!(!dis.contains(unwanted), "{unwanted} linked:\n{dis}");
    }
    let (out, _, code) = spu(&["run", "-q", "one.elf"], &d);
    assert_eq!((out.as_str(), code), ("hi\n", 5));
}

/// The SPU double unit's division as `docs/running-programs.md` gives it: denormal
/// operands are zeros, NaN results the default NaN, results below 2^-1022 (rounded with an
/// unbounded exponent) zeros of their sign, the rest IEEE round-to-nearest-even.
fn spu_divide(a: f64, b: f64) -> u64 {
    let flush = |x: f64| {
        if x.is_subnormal() {
            0.0f64.copysign(x)
        } else {
            x
        }
    };
    let (a, b) = (flush(a), flush(b));
    let q = a / b;
    if q.is_nan() {
        return 0x7ff8_0000_0000_0000;
    }
    if q != 0.0 && q.abs() < f64::MIN_POSITIVE || q == 0.0 && a != 0.0 && b.is_finite() {
        // Near or below 2^-1022: the quotient again with a scaled (exact) dividend, whose
        // rounding is that of an unbounded exponent.
        let scaled = (a * 2f64.powi(200)) / b;
        return if scaled.abs() < 2f64.powi(-822) {
            0.0f64.copysign(q).to_bits()
        } else {
            (scaled * 2f64.powi(-200)).to_bits()
        };
    }
    q.to_bits()
}

#[test]
fn double_division_matches_the_double_unit() {
    let specials = [
        0.0,
        -0.0,
        1.0,
        -1.0,
        3.0,
        0.1,
        7.0,
        1e308,
        -1e308,
        f64::MAX,
        f64::MIN_POSITIVE,
        f64::MIN_POSITIVE * 1.5,
        5e-324,
        -2.5e-310,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
        f64::from_bits(0x7ff0_0000_0000_0001),
        1.0 + f64::EPSILON,
        2.0 - f64::EPSILON,
    ];
    let mut pairs: Vec<(u64, u64)> = specials
        .iter()
        .flat_map(|&a| {
            specials
                .iter()
                .map(move |&b| (f64::to_bits(a), f64::to_bits(b)))
        })
        .collect();
    let v = values(400, 0x0bad_cafe);
    pairs.extend(v.chunks(2).map(|c| {
        // Random signs and exponents around 1, and raw bit patterns (any exponent).
        let near =
            |x: u64| f64::from_bits((x & 0x800f_ffff_ffff_ffff) | ((1023 + (x % 41) - 20) << 52));
        if c[0] % 4 == 0 {
            (c[0], c[1] ^ (c[1] << 7))
        } else {
            (near(c[0]).to_bits(), near(c[1].rotate_left(17)).to_bits())
        }
    }));
    // Quotients that land at the underflow threshold and at overflow.
    pairs.push((f64::MIN_POSITIVE.to_bits(), (1.0 + f64::EPSILON).to_bits()));
    pairs.push(((f64::MIN_POSITIVE * 2.0).to_bits(), 2.0f64.to_bits()));
    pairs.push((f64::MAX.to_bits(), 0.5f64.to_bits()));
    pairs.push((1.0f64.to_bits(), 3.0f64.to_bits()));
    let mut table = String::new();
    for (a, b) in &pairs {
        writeln!(
            table,
            "\t.long\t{:#x}, {:#x}, {:#x}, {:#x}",
            a >> 32,
            a & 0xffff_ffff,
            b >> 32,
            b & 0xffff_ffff
        )
        .unwrap();
    }
    let source = format!(
        r#"
        .section .rodata
.Lfmt:  .string "%llx\n"
        .align  4
.Lpairs:
{table}
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $sp, -64($sp)
        ai      $sp, $sp, -64
        ila     $80, .Lpairs
        il      $81, {n}
1:      brz     $81, 2f
        lqd     $3, 0($80)
        shlqbyi $4, $3, 8
        brsl    $lr, __divdf3
        ori     $4, $3, 0
        ila     $3, .Lfmt
        brsl    $lr, printf
        ai      $80, $80, 16
        ai      $81, $81, -1
        br      1b
2:      il      $3, 0
        ai      $sp, $sp, 64
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
"#,
        n = pairs.len()
    );
    let (out, code) = run("divdf", &source);
    let got: Vec<&str> = out.lines().collect();
    assert_eq!(got.len(), pairs.len(), "{out}");
    for (k, &(a, b)) in pairs.iter().enumerate() {
        let (x, y) = (f64::from_bits(a), f64::from_bits(b));
        assert_eq!(
            got[k],
            format!("{:x}", spu_divide(x, y)),
            "case {k}: {x:e} / {y:e} ({a:#x} / {b:#x})"
        );
    }
    assert_eq!(code, 0);
}
