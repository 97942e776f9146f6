//! Holder crate for the cross-crate tests in `tests/tests/`, and what several of them share:
//! random programs, and the one harness that runs a kernel module alone on the simulator
//! ([`ModuleHarness`]) and checks it against the register contract in its header
//! ([`RegisterContract`], [`check_register_contract`]).

use std::collections::HashMap;

use spu_isa::machine::{MainMemory, Spu, StopReason};

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

/// A kernel module's register contract: the `# Registers` block of its header comment,
/// which says what crosses the module's boundary:
///
/// ```text
/// # Registers of ENTRY (tests/src/lib.rs's module harness checks them):
/// #   in:       $0 $68 ZERO TTAGS
/// #   out:      $100
/// #   clobbers: $66..$127
/// ```
///
/// `of ENTRY` is left out where the module has one entry; registers are `$N`, ranges
/// `$A..$B`, or names of `layout.inc` and `modules/regs.inc`; `-` is none. A register
/// neither out nor clobbered is kept: the module leaves it as it found it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RegisterContract {
    pub inputs: Vec<usize>,
    pub outputs: Vec<usize>,
    pub clobbers: Vec<usize>,
}

/// The names kernel modules give registers and constants: `layout.inc` and
/// `modules/regs.inc` as the host provides them.
pub fn kernel_names() -> spu_asm::sched::Names {
    let mut names = spu_asm::sched::Names::default();
    for (file, text) in spu_loader::kernels::include_files() {
        if file == "layout.inc" || file == "modules/regs.inc" {
            names.collect(&text, &mut |_| None);
        }
    }
    names
}

impl RegisterContract {
    /// The contract of `entry` (or of the module's one entry, `None`) in the header of
    /// `text`, registers named through `names`.
    pub fn parse(
        text: &str,
        entry: Option<&str>,
        names: &spu_asm::sched::Names,
    ) -> Result<RegisterContract, String> {
        let lines: Vec<&str> = text.lines().collect();
        let start = lines
            .iter()
            .position(|l| {
                let Some(rest) = l.strip_prefix("# Registers") else {
                    return false;
                };
                match entry {
                    Some(e) => rest.strip_prefix(" of ").is_some_and(|r| {
                        r.split(|c: char| c.is_whitespace() || c == ':' || c == '(')
                            .next()
                            == Some(e)
                    }),
                    None => !rest.starts_with(" of "),
                }
            })
            .ok_or_else(|| format!("no `# Registers` block for {entry:?}"))?;
        let mut contract = RegisterContract::default();
        let mut seen = [false; 3];
        for line in &lines[start + 1..] {
            let Some(body) = line.strip_prefix('#') else {
                break;
            };
            let Some((key, list)) = body.split_once(':') else {
                break;
            };
            let (slot, k) = match key.trim() {
                "in" => (&mut contract.inputs, 0),
                "out" => (&mut contract.outputs, 1),
                "clobbers" => (&mut contract.clobbers, 2),
                _ => break,
            };
            seen[k] = true;
            for item in list.split_whitespace().filter(|&i| i != "-") {
                let reg = |t: &str| {
                    names
                        .register(t)
                        .map(usize::from)
                        .ok_or_else(|| format!("`{t}`: not a register"))
                };
                match item.split_once("..") {
                    Some((a, b)) => slot.extend(reg(a)?..=reg(b)?),
                    None => slot.push(reg(item)?),
                }
            }
        }
        if seen != [true; 3] {
            return Err(format!(
                "the `# Registers` block for {entry:?} needs in, out and clobbers lines"
            ));
        }
        Ok(contract)
    }

    /// The contract of `entry` in kernel module `file` (`modules/shade.s`).
    pub fn of_module(file: &str, entry: Option<&str>) -> RegisterContract {
        let text = spu_loader::kernels::MODULES
            .iter()
            .find(|(name, _)| *name == file)
            .unwrap_or_else(|| panic!("no module {file}"))
            .1;
        RegisterContract::parse(text, entry, &kernel_names())
            .unwrap_or_else(|e| panic!("{file}: {e}"))
    }

    /// Whether the module leaves register `r` as it found it.
    pub fn keeps(&self, r: usize) -> bool {
        !self.outputs.contains(&r) && !self.clobbers.contains(&r)
    }
}

/// What a register holds in run `k` of [`check_register_contract`] when the module is
/// not told anything of it: distinct in every register and word, and between runs.
pub fn poison(r: usize, k: usize) -> [u32; 4] {
    let base =
        (r as u32).wrapping_mul(0x0101_0101) ^ if k == 0 { 0x5a00_0000 } else { 0xa500_0000 };
    [base, base ^ 0x10, base ^ 0x200, !base]
}

/// Checks a module against its register contract: `run` prepares the module's state
/// (local store, main memory, its input registers), calls the given `poison` on the SPU
/// just before it runs the module, which sets every register outside the contract's
/// inputs to [`poison`]`(r, k)`, runs it and returns the SPU and what the test reads of
/// the outcome (local store, memory, the stop). It is run twice, with different poison:
/// the outcome and the declared outputs must be the same both times (the module reads
/// no register it does not declare), and every register the contract keeps must be as
/// it was (an input as set, another as poisoned). Returns the first run.
pub fn check_register_contract<T: PartialEq + std::fmt::Debug>(
    contract: &RegisterContract,
    mut run: impl FnMut(&dyn Fn(&mut Spu)) -> (Spu, T),
) -> (Spu, T) {
    let mut runs = Vec::new();
    for k in 0..2 {
        let before = std::cell::RefCell::new(Vec::new());
        let poison_registers = |spu: &mut Spu| {
            for r in (0..128).filter(|r| !contract.inputs.contains(r)) {
                spu.set_reg(r, poison(r, k));
            }
            *before.borrow_mut() = (0..128).map(|r| spu.reg(r)).collect();
        };
        let (spu, outcome) = run(&poison_registers);
        let before = before.into_inner();
        assert_eq!(before.len(), 128, "the run did not poison the registers");
        for r in (0..128).filter(|&r| contract.keeps(r)) {
            assert_eq!(spu.reg(r), before[r], "${r} is not kept (run {k})");
        }
        runs.push((spu, outcome));
    }
    let (second, first) = (runs.pop().unwrap(), runs.pop().unwrap());
    for &r in &contract.outputs {
        assert_eq!(
            first.0.reg(r),
            second.0.reg(r),
            "output ${r} depends on an undeclared register"
        );
    }
    // (not the outcomes themselves: local-store dumps are long)
    assert!(
        first.1 == second.1,
        "the outcome depends on an undeclared register"
    );
    first
}

/// A kernel module (or modules) assembled with a driver, alone on one simulated SPU: the
/// driver's source is assembled with `layout.inc` and the modules as the host provides
/// them; the host sets the registers and local store the module expects, runs it from a
/// label and reads what it leaves.
pub struct ModuleHarness {
    pub spu: Spu,
    pub memory: MainMemory,
    pub symbols: HashMap<String, u32>,
    pub entry: u32,
    /// The names of `layout.inc` and `modules/regs.inc`, for registers and constants.
    pub names: spu_asm::sched::Names,
    /// Stop codes of the stubs [`ModuleHarness::with_stubs`] made, by label.
    stubs: Vec<(String, u16)>,
}

impl ModuleHarness {
    /// Assembles the driver `src` (named `name` in diagnostics) and loads it.
    pub fn new(src: &str, name: &str, memory: MainMemory) -> Self {
        let out = assemble_with_kernels(src, name);
        let mut spu = Spu::new(0);
        spu.load_image(&out.image);
        ModuleHarness {
            spu,
            memory,
            symbols: out.symbols.into_iter().collect(),
            entry: out.entry,
            names: kernel_names(),
            stubs: Vec::new(),
        }
    }

    /// Assembles `modules` (include names under `kernels/`) with the frame's register map
    /// and local-store data (`modules/regs.inc`, `modules/data.s`) and a `stop` stub for
    /// each of `exits`, the labels outside them the modules branch to; `extra` is more
    /// driver source. The timing model is on and main memory is 1 MiB of zeros.
    pub fn with_stubs(modules: &[&str], exits: &[&str], extra: &str) -> Self {
        let mut src = String::from(
            "        .include \"layout.inc\"\n        .include \"modules/regs.inc\"\n        .include \"modules/data.s\"\n        .text\n        .global _start\n_start: stop 0x2100\n",
        );
        for m in modules {
            src += &format!("        .include \"{m}\"\n");
        }
        let mut stubs = Vec::new();
        for (k, label) in exits.iter().enumerate() {
            let code = 0x2101 + k as u16;
            src += &format!("{label}: stop {code:#x}\n");
            stubs.push((label.to_string(), code));
        }
        src += extra;
        let mut h = ModuleHarness::new(&src, "driver.s", MainMemory::zeroed(1 << 20));
        h.spu.enable_timing(Default::default());
        h.stubs = stubs;
        h
    }

    pub fn sym(&self, name: &str) -> u32 {
        *self
            .symbols
            .get(name)
            .unwrap_or_else(|| panic!("no symbol {name}"))
    }

    pub fn reg_number(&self, name: &str) -> usize {
        self.names
            .register(name)
            .unwrap_or_else(|| panic!("no register {name}")) as usize
    }

    /// A constant of the register map or `layout.inc` (`CTX_RAY_T`, `V_PFMISS`, ...).
    pub fn value(&self, name: &str) -> u32 {
        self.names
            .value_of(name)
            .unwrap_or_else(|| panic!("no constant {name}")) as u32
    }

    pub fn set(&mut self, name: &str, value: [u32; 4]) {
        let r = self.reg_number(name);
        self.spu.set_reg(r, value);
    }

    pub fn splat(&mut self, name: &str, value: u32) {
        self.set(name, [value; 4]);
    }

    pub fn reg(&self, name: &str) -> [u32; 4] {
        self.spu.reg(self.reg_number(name))
    }

    pub fn word(&self, addr: u32) -> u32 {
        let a = addr as usize;
        u32::from_be_bytes(self.spu.ls()[a..a + 4].try_into().unwrap())
    }

    pub fn f(&self, addr: u32) -> f32 {
        f32::from_bits(self.word(addr))
    }

    pub fn quad(&self, addr: u32) -> [u32; 4] {
        std::array::from_fn(|i| self.word(addr + 4 * i as u32))
    }

    /// Local-store bytes `len` from `addr`.
    pub fn bytes(&self, addr: u32, len: u32) -> Vec<u8> {
        self.spu.ls()[addr as usize..(addr + len) as usize].to_vec()
    }

    pub fn write_words<W: std::borrow::Borrow<u32>>(
        &mut self,
        addr: u32,
        words: impl IntoIterator<Item = W>,
    ) {
        let bytes: Vec<u8> = words
            .into_iter()
            .flat_map(|w| w.borrow().to_be_bytes())
            .collect();
        self.spu.write_ls(addr, &bytes);
    }

    /// Runs from `pc` until the program stops, at most `limit` cycles.
    pub fn run_at(&mut self, pc: u32, limit: u64) -> StopReason {
        self.spu.set_pc(pc);
        self.spu.run(&mut self.memory, limit)
    }

    /// Runs from `label` until a stub stops it: the stub's label.
    pub fn run_from(&mut self, label: &str) -> String {
        match self.run_at(self.sym(label), 10_000_000) {
            StopReason::Stop(code) => self
                .stubs
                .iter()
                .find(|s| s.1 == code)
                .map_or(format!("stop {code:#x}"), |s| s.0.clone()),
            other => panic!("the module stopped abnormally: {other}"),
        }
    }
}
