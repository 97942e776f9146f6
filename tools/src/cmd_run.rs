//! `spu run`: run a program on one simulated SPU and report how it stopped.

use crate::exit::{self, Error, Status};
use crate::options;
use spu_isa::disasm::{instruction_text_ext, SymbolTable};
use spu_isa::machine::{MainMemory, Spu, StopReason};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Engine: the block compiler (jit; the default where the host has one) or the
    /// interpreter (interp). Results are the same; only host speed differs.
    #[arg(long, default_value_t = spu_isa::jit::Engine::host_default())]
    engine: spu_isa::jit::Engine,
    #[command(flatten)]
    compile: crate::options::CompileOption,
    #[command(flatten)]
    ext: crate::options::ExtOption,
    /// An SPU ELF, a raw image loaded at 0, or an assembly source (.s).
    file: PathBuf,
    /// Stop after this many cycles.
    #[arg(long, default_value_t = 1_000_000_000)]
    max_cycles: u64,
    /// Print all 128 registers.
    #[arg(long)]
    dump_regs: bool,
    /// Print local store: ADDR:LEN (hex or decimal).
    #[arg(long)]
    dump_ls: Vec<String>,
    /// Values for the inbound mailbox, in order.
    #[arg(long = "mbox-in")]
    mbox_in: Vec<String>,
    /// Run with the cycle-level timing model (otherwise one cycle per instruction).
    #[arg(long, conflicts_with = "trace")]
    timing: bool,
    /// Print every executed instruction: address, text and the registers it wrote (like
    /// IBM systemsim's instruction trace).
    #[arg(long)]
    trace: bool,
    /// Main memory in bytes.
    #[arg(long, default_value_t = 1 << 20)]
    memory: u64,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
    /// Print nothing but what the program writes, as `elfspe` ran it (the exit status
    /// still tells how it ended).
    #[arg(short, long, conflicts_with_all = ["json", "dump_regs"])]
    quiet: bool,
    /// Print the registers and the argv region the program starts with
    /// (docs/running-programs.md).
    #[arg(long, conflicts_with = "json")]
    dump_entry: bool,
    /// Start as libspe2's `spe_context_run` does with these argp and envp (`$4`, `$5`;
    /// `$3` = speid) instead of as `elfspe` does with argc and argv.
    #[arg(long)]
    argp: Option<String>,
    #[arg(long, requires = "argp")]
    envp: Option<String>,
    /// The one host directory the program's file calls may reach (none without it; its
    /// standard streams are always the host's).
    #[arg(long)]
    root: Option<PathBuf>,
    /// Arguments for the program, after `--` (`argv[1]`...; `argv[0]` is FILE).
    #[arg(last = true)]
    program_args: Vec<std::ffi::OsString>,
}

fn number(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u64::from_str_radix(h, 16),
        None => t.parse(),
    };
    v.map_err(|_| format!("bad number `{text}`"))
}

/// Loads FILE into a fresh SPU.
pub fn load(file: &Path) -> Result<(Spu, Vec<(String, u32)>), String> {
    load_program(file).map(|(spu, symbols, _)| (spu, symbols))
}

/// A loaded program: the SPU, its symbols and where its code and data end.
type Loaded = (Spu, Vec<(String, u32)>, u32);

/// Loads FILE into a fresh SPU; also where its code and data end.
fn load_program(file: &std::path::Path) -> Result<Loaded, String> {
    let name = file.display();
    let mut spu = Spu::new(0);
    let mut symbols = Vec::new();
    let end;
    if file.extension().is_some_and(|e| e == "s" || e == "S") {
        let out = spu_asm::assemble_file(file, &Default::default()).map_err(|d| {
            d.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        })?;
        spu.load_image(&out.image);
        spu.set_pc(out.entry);
        symbols = out.symbols;
        end = out.image.len() as u32;
    } else {
        let bytes = options::read_input(file, options::MAX_PROGRAM_BYTES)?;
        if bytes.starts_with(b"\x7fELF") {
            let elf = spu_asm::elf::read_elf(&bytes).map_err(|e| format!("{name}: {e}"))?;
            let segments: Vec<(u32, &[u8])> = elf
                .segments
                .iter()
                .map(|(a, d)| (*a, d.as_slice()))
                .collect();
            spu.load_segments(&segments, elf.entry);
            end = elf
                .segments
                .iter()
                .map(|(a, d)| a + d.len() as u32)
                .max()
                .unwrap_or(0);
            symbols = elf.symbols;
        } else {
            if bytes.len() > 256 * 1024 {
                return Err(format!(
                    "{name}: {} bytes do not fit the 256 KiB local store",
                    bytes.len()
                ));
            }
            spu.load_image(&bytes);
            end = bytes.len() as u32;
        }
    }
    Ok((spu, symbols, end))
}

/// How the program starts: as `elfspe` ran it from a shell, or through the libspe2 API
/// with `--argp`/`--envp`.
fn start_mode(args: &Args) -> exit::Result<spu_loader::ppe::start::Start> {
    use spu_loader::ppe::start::Start;
    if let Some(argp) = &args.argp {
        if !args.program_args.is_empty() {
            return Err(Error::input(
                "--argp starts the program through the libspe2 API: no arguments after --",
            ));
        }
        let argp = number(argp).map_err(|e| format!("--argp: {e}"))?;
        let envp = match &args.envp {
            Some(v) => number(v).map_err(|e| format!("--envp: {e}"))?,
            None => 0,
        };
        return Ok(Start::Api { argp, envp });
    }
    let mut argv = vec![args.file.as_os_str().as_encoded_bytes().to_vec()];
    argv.extend(
        args.program_args
            .iter()
            .map(|a| a.as_encoded_bytes().to_vec()),
    );
    Ok(Start::Shell { args: argv })
}

/// `spu run --json`: how the program stopped and the machine state.
#[derive(serde::Serialize)]
struct RunReport {
    stop: String,
    /// n for `stop 0x2000|n`, otherwise null.
    exit_code: Option<u8>,
    pc: u32,
    instructions: u64,
    cycles: u64,
    outbound_mailbox: Option<u32>,
    registers: Vec<[u32; 4]>,
}

/// A `--dump-ls ADDR:LEN` range, checked against the 256 KiB local store.
fn dump_range(spec: &str) -> exit::Result<std::ops::Range<usize>> {
    let (a, l) = spec
        .split_once(':')
        .ok_or_else(|| format!("--dump-ls {spec}: expected ADDR:LEN"))?;
    let (addr, len) = (number(a)?, number(l)?);
    let ls = 256 * 1024u64; // the local store
    if addr >= ls || len > ls - addr {
        return Err(Error::input(format!(
            "--dump-ls {spec}: outside the local store (0..{ls:#x})"
        )));
    }
    Ok(addr as usize..(addr + len) as usize)
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    options::max_cycles(args.max_cycles)?;
    let memory_bytes = options::memory(args.memory)?;
    let dumps = args
        .dump_ls
        .iter()
        .map(|s| dump_range(s))
        .collect::<exit::Result<Vec<_>>>()?;
    let mut mailbox = Vec::new();
    for v in &args.mbox_in {
        let value = number(v).map_err(|e| format!("--mbox-in: {e}"))?;
        let value =
            u32::try_from(value).map_err(|_| format!("--mbox-in {v}: does not fit in 32 bits"))?;
        mailbox.push(value);
    }
    let (mut spu, symbols, program_end) = load_program(&args.file)?;
    spu.set_extensions(args.ext.ext);
    spu.set_engine(args.engine);
    spu.share_code(&args.compile.cache());
    let start = start_mode(&args)?;
    let mut memory = MainMemory::zeroed(memory_bytes);
    let entry = spu_loader::ppe::start::prepare(&start, program_end, memory.len())
        .map_err(|e| format!("{}: {e}", args.file.display()))?;
    spu_loader::ppe::start::apply(&entry, &mut spu, &mut memory);
    if args.dump_entry {
        dump_entry(&entry)?;
    }
    for value in mailbox {
        if !spu.write_inbound_mailbox(value) {
            return Err(Error::input(
                "--mbox-in: the inbound mailbox holds 4 values",
            ));
        }
    }
    if args.timing {
        spu.enable_timing(Default::default());
    }
    let mut host = spu_loader::ppe::Host::new(args.root.as_deref())?;
    let symbols = SymbolTable::new(symbols.iter().map(|(n, a)| (*a, n.clone())).collect());
    // PPE-assisted calls (stop 0x2100..0x21ff) are served and the program resumed.
    let stop = loop {
        let stop = if args.trace {
            trace(&mut spu, &mut memory, args.max_cycles, &symbols)?
        } else {
            spu.run(&mut memory, args.max_cycles)
        };
        match stop {
            StopReason::Stop(code) if spu_loader::ppe::CALL_STOPS.contains(&code) => {
                if let Err(fault) = host.serve(&mut spu, code) {
                    eprintln!(
                        "spu: {}: the program stopped at {:#x}: {fault}",
                        args.file.display(),
                        spu.pc().wrapping_sub(4)
                    );
                    return Ok(Status::AbnormalStop.into());
                }
            }
            stop => break stop,
        }
    };
    let out_mbox = spu.read_outbound_mailbox();
    if args.json {
        let report = RunReport {
            stop: describe(&stop),
            exit_code: exit::program_exit_code(&stop),
            pc: spu.pc(),
            instructions: spu.instructions(),
            cycles: spu.cycles(),
            outbound_mailbox: out_mbox,
            registers: (0..128).map(|n| spu.reg(n)).collect(),
        };
        let json = serde_json::to_string(&report)
            .map_err(|e| exit::Error::failure(format!("JSON: {e}")))?;
        outln!("{json}");
    } else if !args.quiet {
        outln!("stopped: {}", describe(&stop));
        outln!("pc: {:#x}", spu.pc());
        outln!("instructions: {}", spu.instructions());
        outln!("cycles: {}", spu.cycles());
        if let Some(v) = out_mbox {
            outln!("outbound mailbox: {v:#x}");
        }
        if args.dump_regs {
            for n in 0..128 {
                let r = spu.reg(n);
                outln!("${n}: {:08x} {:08x} {:08x} {:08x}", r[0], r[1], r[2], r[3]);
            }
        }
    }
    let ls = spu.ls();
    for range in dumps {
        for row in range.clone().step_by(16) {
            let end = (row + 16).min(range.end);
            let hex: Vec<String> = ls[row..end].iter().map(|b| format!("{b:02x}")).collect();
            outln!("{row:05x}: {}", hex.join(" "));
        }
    }
    Ok(exit_status(&args.file, &stop))
}

/// `--dump-entry`: the registers that are not zero at entry and the argv region.
fn dump_entry(entry: &spu_loader::ppe::start::Entry) -> exit::Result<()> {
    outln!("entry registers (all others zero):");
    for (n, r) in &entry.regs {
        outln!("${n}: {:08x} {:08x} {:08x} {:08x}", r[0], r[1], r[2], r[3]);
    }
    if let Some(a) = &entry.argv {
        outln!(
            "argv region: {} bytes at local store {:#x}, main memory {:#x}",
            a.bytes.len(),
            a.ls,
            a.ea
        );
        for (i, row) in a.bytes.chunks(16).enumerate() {
            let hex: Vec<String> = row.iter().map(|b| format!("{b:02x}")).collect();
            outln!("{:05x}: {}", a.ls as usize + 16 * i, hex.join(" "));
        }
    }
    Ok(())
}

/// `stop 0x2000|n` exits with n, as `elfspe` does; any other end is reported on standard
/// error with its status.
fn exit_status(file: &std::path::Path, stop: &StopReason) -> ExitCode {
    if let Some(n) = exit::program_exit_code(stop) {
        return ExitCode::from(n);
    }
    let name = file.display();
    let status = match stop {
        StopReason::Stop(code) => {
            eprintln!("spu: {name}: stop {code:#x} is not an exit (0x2000..0x20ff)");
            Status::AbnormalStop
        }
        StopReason::CycleLimit => {
            eprintln!("spu: {name}: cycle limit reached (--max-cycles)");
            Status::CycleLimit
        }
        other => {
            eprintln!("spu: {name}: SPU stopped abnormally: {}", describe(other));
            Status::of_stop(other)
        }
    };
    status.into()
}

/// A channel's name (`SPU_RdInMbox`), with its number.
fn channel_name(channel: u8) -> String {
    match spu_asm::CHANNELS.iter().find(|c| c.1 == channel as u32) {
        Some((name, n)) => format!("{name} ({n})"),
        None => format!("{channel}"),
    }
}

/// How a program stopped, with channels named and what a stop code means to the Cell
/// SDK's loader (`stop 0x2000|n` is exit with status n).
pub fn describe(stop: &StopReason) -> String {
    match stop {
        StopReason::Stop(code) if (0x2000..=0x20ff).contains(code) => {
            format!("stop {code:#x} (exit status {})", code & 0xff)
        }
        StopReason::Stop(0x3fff) => "stop 0x3fff (debugger breakpoint)".to_string(),
        StopReason::InvalidChannel { pc, channel } => {
            format!("invalid channel {} at {pc:#x}", channel_name(*channel))
        }
        StopReason::Deadlock { pc, channel } => {
            format!("deadlock at {pc:#x} on channel {}", channel_name(*channel))
        }
        StopReason::Blocked { channel } => {
            format!("blocked on channel {}", channel_name(*channel))
        }
        other => other.to_string(),
    }
}

/// Runs one instruction at a time (no timing model: one cycle each), printing each one's
/// address, text and the registers it changed.
fn trace(
    spu: &mut Spu,
    memory: &mut MainMemory,
    max_cycles: u64,
    symbols: &SymbolTable,
) -> exit::Result<StopReason> {
    loop {
        if spu.cycles() >= max_cycles {
            return Ok(StopReason::CycleLimit);
        }
        let pc = spu.pc();
        let at = pc as usize & (256 * 1024 - 4);
        let ls = spu.ls();
        let word = u32::from_be_bytes([ls[at], ls[at + 1], ls[at + 2], ls[at + 3]]);
        let before: Vec<_> = (0..128).map(|n| spu.reg(n)).collect();
        let stop = spu.run(memory, spu.cycles() + 1);
        let mut line = format!(
            "{pc:05x}: {word:08x}  {}",
            instruction_text_ext(word, pc, symbols, spu.extensions())
        );
        for (n, old) in before.iter().enumerate() {
            let r = spu.reg(n);
            if r != *old {
                line.push_str(&format!(
                    "\t${n} <- {:08x} {:08x} {:08x} {:08x}",
                    r[0], r[1], r[2], r[3]
                ));
            }
        }
        outln!("{line}");
        if stop != StopReason::CycleLimit {
            return Ok(stop);
        }
    }
}
