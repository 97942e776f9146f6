//! Bad input never panics the assembler: mutated kernels and random fragments either
//! assemble or come back as diagnostics.

const SOURCES: &[&str] = &[
    include_str!("../../kernels/modules/frame.s"),
    include_str!("../../kernels/modules/raygen.s"),
    include_str!("../../kernels/modules/traverse.s"),
    include_str!("../../kernels/modules/triangle.s"),
    include_str!("../../kernels/modules/output.s"),
    include_str!("../../kernels/fill.s"),
];

const FRAGMENTS: &[&str] = &[
    "(",
    ")",
    "$",
    "$ch",
    "$sp9",
    ",",
    ":",
    "::",
    "1b",
    "9f",
    ".irp",
    ".endr",
    ".macro m",
    ".endm",
    ".if",
    ".endif",
    ".else",
    "@h",
    "@l",
    "\\",
    "\"",
    "/*",
    "*/",
    "#",
    ";",
    "0x",
    "-",
    "~",
    "!",
    "<<",
    ">>",
    "%",
    "/0",
    "lqd $3,",
    "($1)",
    "99999999999999999999",
    "\t",
    ".align 40",
    ".space -1",
    ".fill 3,9,1",
    ".rept 3",
    ".include \"nope\"",
    "stop",
    "bi",
];

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> usize {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 33) as usize
    }
}

#[test]
fn mutated_sources_never_panic() {
    let mut rng = Lcg(42);
    let opts = spu_asm::Options {
        virtual_files: vec![
            (
                "layout.inc".into(),
                ".set TRI_N_U, 0\n.set TRI_B_NU, 16\n.set TRI_C_NU, 32\n".into(),
            ),
            (
                "modules/regs.inc".into(),
                include_str!("../../kernels/modules/regs.inc").into(),
            ),
        ],
        ..Default::default()
    };
    for round in 0..300 {
        let base = SOURCES[round % SOURCES.len()];
        let mut lines: Vec<String> = base.lines().map(str::to_string).collect();
        for _ in 0..1 + rng.next() % 8 {
            let i = rng.next() % lines.len();
            let line = &mut lines[i];
            let pos = if line.is_empty() {
                0
            } else {
                rng.next() % line.len()
            };
            let pos = (0..=pos)
                .rev()
                .find(|p| line.is_char_boundary(*p))
                .unwrap_or(0);
            match rng.next() % 3 {
                0 => line.insert_str(pos, FRAGMENTS[rng.next() % FRAGMENTS.len()]),
                1 => line.truncate(pos),
                _ => {
                    let j = rng.next() % lines.len();
                    lines.swap(i, j);
                }
            }
        }
        let source = lines.join("\n");
        let _ = spu_asm::assemble(&source, "mutated.s", &opts);
        // The same source as a relocatable object, written, read back and linked.
        if let Ok((obj, _)) = spu_asm::assemble_object(&source, "mutated.s", &opts) {
            let elf = obj.to_elf().expect("an assembled object writes");
            let back = spu_asm::object::Object::from_elf("mutated.o", &elf).expect("reads back");
            let _ = spu_asm::link::link(&[back], &Default::default());
        }
    }
}

#[test]
fn random_fragments_never_panic() {
    let mut rng = Lcg(7);
    for _ in 0..1500 {
        let mut s = String::new();
        for _ in 0..rng.next() % 12 {
            s.push_str(FRAGMENTS[rng.next() % FRAGMENTS.len()]);
            if rng.next().is_multiple_of(3) {
                s.push(' ');
            }
            if rng.next().is_multiple_of(5) {
                s.push('\n');
            }
        }
        let _ = spu_asm::assemble(&s, "random.s", &spu_asm::Options::default());
    }
}

/// Inputs the fuzzer found (fuzz/ with cargo-fuzz), kept as regression tests.
#[test]
fn fuzzer_findings_stay_fixed() {
    for input in [
        "\n\" #\n\")),z\x0b='\r",
        "x='",
        "a='b",
        ".long '",
        ",z\x0b='\u{d8}cn",
        "x = '\u{e9}\u{e9}",
    ] {
        let _ = spu_asm::assemble(input, "fuzz.s", &spu_asm::Options::default());
    }
}
