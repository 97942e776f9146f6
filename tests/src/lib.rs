//! Holder crate for the cross-crate tests in `tests/tests/`, and what several of them share.

/// A xorshift64 generator: the random programs and operands of the tests, reproducible
/// from a seed.
pub struct XorShift(pub u64);

impl XorShift {
    // Not an Iterator: it never ends, and the tests call it for one value at a time.
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }

    /// A value in `0..n`.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

/// The shape of a random looping program ([`looping_program`]).
pub struct LoopShape {
    /// Passes through the blocks before the program stops (the countdown in `$4`).
    pub trips: u32,
    /// Lines after the prologue's `ila $3, data` and `il $4, trips`.
    pub prologue: &'static str,
    /// A block holds up to this many random instructions less one before its countdown,
    /// and up to `after` less one after it.
    pub before: u64,
    pub after: u64,
    /// The conditional branches that end the blocks.
    pub conditions: &'static [&'static str],
    /// One block in four calls a routine of random instructions (`brsl $0, sub`).
    pub calls: bool,
    /// Every fourth data word is raw (zeros, denormals, huge values, any sign) rather
    /// than an ordinary float.
    pub raw_words: bool,
}

/// A random looping program: 3 to 7 blocks of `op`'s instructions on `$10..$21` (loaded
/// from `data`, which `$3` points at), each with a hint (`hbrr`, or `hbr` through `$22`)
/// that is right, wrong or absent, a
/// countdown that stops the program after `trips` passes, and a data-dependent branch to
/// a random block; `stop 0x2000` at the end.
pub fn looping_program(
    rng: &mut XorShift,
    shape: &LoopShape,
    op: &mut dyn FnMut(&mut XorShift) -> String,
) -> String {
    let blocks = 3 + rng.below(5) as usize;
    let mut src = format!(
        "        .text\n        .global _start\n_start: ila $3, data\n il $4, {}\n{}",
        shape.trips, shape.prologue
    );
    for r in 10..22 {
        src += &format!(" lqd ${r}, {}($3)\n", 16 * (r % 8));
    }
    for i in 0..blocks {
        let target = rng.below(blocks as u64);
        src += &format!("b{i}:\n");
        match rng.below(5) {
            0 => src += &format!(" hbrr .Lbr{i}, b{target}\n"),
            1 => src += &format!(" hbrr .Lbr{i}, b{}\n", (target + 1) % blocks as u64),
            // Register-form hints, right or wrong: their target is no part of a record.
            2 => src += &format!(" ila $22, b{target}\n hbr .Lbr{i}, $22\n"),
            3 => {
                src += &format!(
                    " ila $22, b{}\n hbr .Lbr{i}, $22\n",
                    (target + 1) % blocks as u64
                )
            }
            _ => {}
        }
        for _ in 0..rng.below(shape.before) {
            src += &format!(" {}\n", op(rng));
        }
        if shape.calls && rng.below(4) == 0 {
            src += " brsl $0, sub\n";
        }
        src += " ai $4, $4, -1\n brz $4, end\n";
        for _ in 0..rng.below(shape.after) {
            src += &format!(" {}\n", op(rng));
        }
        let cond = shape.conditions[rng.below(shape.conditions.len() as u64) as usize];
        src += &format!(".Lbr{i}: {cond} ${}, b{target}\n", 10 + rng.below(12));
    }
    src += " br b0\n";
    if shape.calls {
        src += "sub:\n";
        for _ in 0..rng.below(6) {
            src += &format!(" {}\n", op(rng));
        }
        src += " bi $0\n";
    }
    src += "end: stop 0x2000\n        .data\n        .align 4\ndata:\n";
    for k in 0..32 {
        let w = rng.next() as u32;
        let w = if shape.raw_words && k % 4 == 3 {
            w
        } else {
            w & 0xc3ff_ffff | 0x0800_0000
        };
        src += &format!(" .long {w}\n");
    }
    src
}

/// Assembles `src` (named `name` in diagnostics) with the kernel modules and `layout.inc`
/// the host provides in memory, as the frame programs are; panics with every diagnostic.
pub fn assemble_with_kernels(src: &str, name: &str) -> spu_asm::Output {
    let opts = spu_asm::Options {
        virtual_files: spu_loader::kernels::include_files(),
        ..Default::default()
    };
    spu_asm::assemble(src, name, &opts).unwrap_or_else(|diags| {
        let text: Vec<String> = diags.iter().map(|d| d.to_string()).collect();
        panic!("{name} does not assemble:\n{}", text.join("\n"))
    })
}

/// A program whose blocks go on past untaken conditional branches (`brz`, `brnz`,
/// `brhz`, `brhnz`, and the indirect `biz`, `bihnz`): a loop of 300 passes whose inner
/// branches are taken now and then (`$24` counts one of them: 38 passes; `$31` the
/// `biz`: 18; `$6` the `bihnz`: 37), two of them named by a hint on some passes, then a
/// self-loop of 200 passes (`$27`) whose inner branch leaves it every 16th pass (`$29`:
/// 12 times). Ends with `stop 0x2000`.
pub const UNTAKEN_BRANCHES: &str = "
        .text
        .global _start
_start: ila     $3, data
        il      $9, 300
        ilhu    $10, 0x3f80
loop:   andi    $8, $9, 7
        ceqi    $12, $8, 3
        a       $20, $20, $9
.Lin1:  brnz    $12, side1
        fa      $21, $21, $10
        ceqi    $13, $8, 5
        xor     $22, $22, $20
        brhnz   $13, side2
        andi    $18, $9, 15
        ila     $17, side3
.Lin3:  biz     $18, $17
        ceqi    $19, $8, 6
        ila     $11, side4
        bihnz   $19, $11
        andi    $14, $9, 1
        mpy     $23, $20, $9
        lqd     $5, 0($3)
        brz     $14, even
back:   ai      $9, $9, -1
        brnz    $9, loop
        il      $27, 0
        hbrr    .Lt, tight
tight:  ai      $27, $27, 1
        andi    $15, $27, 15
        brz     $15, tick
        a       $28, $28, $27
        ceqi    $16, $27, 200
.Lt:    brz     $16, tight
        stop    0x2000
tick:   ai      $29, $29, 1
        br      tight
side1:  ai      $24, $24, 1
        br      back
side2:  ai      $25, $25, 1
        hbrr    .Lin1, side1
        br      back
side3:  ai      $31, $31, 1
        br      back
side4:  ai      $6, $6, 1
        hbr     .Lin3, $17
        br      back
even:   ai      $26, $26, 1
        fm      $30, $21, $10
        brhz    $26, back
        br      back
        .data
        .align  4
data:   .float  1.5, 2.0, 0.5, 3.0
";
