//! `spu run`: run a program on one simulated SPU and report how it stopped.

use crate::exit::{self, Error, Status};
use crate::options;
use spu_isa::disasm::{instruction_text_ext, SymbolTable};
use spu_isa::machine::{Spu, StopReason};
use spu_spe::{Channel, ContextConfig, ContextId, Outcome, Program, Start, State, System};
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
    /// Values for the inbound mailbox, in order (4 at a time: the rest as the program
    /// reads them).
    #[arg(long = "mbox-in")]
    mbox_in: Vec<String>,
    /// Run with the cycle-level timing model (otherwise one cycle per instruction).
    #[arg(long, conflicts_with = "trace")]
    timing: bool,
    /// Print every executed instruction: address, text and the registers it wrote (like
    /// IBM systemsim's instruction trace); on standard error with --json.
    #[arg(long)]
    trace: bool,
    /// Main memory in bytes.
    #[arg(long, default_value_t = 1 << 20)]
    memory: u64,
    /// Machine-readable output: one JSON document on standard output, with the
    /// --dump-ls ranges in it.
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

/// Reads FILE: a `.s` source is assembled; anything else must be an SPU ELF or a raw
/// image, checked before anything runs ([`Program::from_file`]: segments inside local
/// store and apart, no empty or text files).
pub fn load(file: &Path) -> Result<Program, String> {
    if file.extension().is_some_and(|e| e == "s") {
        let out = spu_asm::assemble_file(file, &Default::default()).map_err(|d| {
            d.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        })?;
        return Ok(Program {
            segments: vec![(0, out.image)],
            entry: out.entry,
            symbols: out.symbols,
            overlay_image: None,
        });
    }
    Program::from_file(file).map_err(|e| e.to_string())
}

/// How the run of the program's one context ended, as the SPU's stop: a wait the command
/// cannot serve (its mailbox values are spent) is a deadlock. `Err`: a PPE-assisted call
/// refused what the program asked (the `stop`'s address and why).
pub fn final_stop(
    system: &System,
    id: ContextId,
    outcome: &Outcome,
) -> Result<StopReason, (u32, String)> {
    match (outcome, system.state(id)) {
        (_, State::Faulted { pc, message }) => Err((*pc, message.clone())),
        (_, State::Stopped(stop)) => Ok(stop.clone()),
        (_, State::Waiting { channel, pc }) => Ok(StopReason::Deadlock {
            pc: *pc,
            channel: channel.number(),
        }),
        (_, State::Runnable) => Ok(StopReason::CycleLimit),
    }
}

/// Writes `--mbox-in` values into the inbound mailbox while it has room.
fn feed(system: &mut System, id: ContextId, values: &mut std::collections::VecDeque<u32>) {
    while system.in_mbox_len(id) < 4 {
        match values.pop_front() {
            Some(v) => {
                system.write_in_mbox(id, v);
            }
            None => break,
        }
    }
}

/// How the program starts: as `elfspe` ran it from a shell, or through the libspe2 API
/// with `--argp`/`--envp`.
fn start_mode(args: &Args) -> exit::Result<Start> {
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
    /// The `--dump-ls` ranges, in order.
    local_store: Vec<LsDump>,
}

/// One `--dump-ls` range in `spu run --json`.
#[derive(serde::Serialize)]
struct LsDump {
    address: usize,
    /// The bytes as lowercase hex, two digits each.
    bytes: String,
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
    let mut mailbox = std::collections::VecDeque::new();
    for v in &args.mbox_in {
        let value = number(v).map_err(|e| format!("--mbox-in: {e}"))?;
        let value =
            u32::try_from(value).map_err(|_| format!("--mbox-in {v}: does not fit in 32 bits"))?;
        mailbox.push_back(value);
    }
    let program = load(&args.file)?;
    let start = start_mode(&args)?;
    let mut system = System::new(memory_bytes);
    let id = system.create_context(ContextConfig {
        engine: args.engine,
        timing: args.timing.then(Default::default),
        code: Some(args.compile.cache()),
        extensions: args.ext.ext,
    });
    let entry = system
        .load(id, &program, &start)
        .map_err(|e| format!("{}: {e}", args.file.display()))?;
    if args.dump_entry {
        dump_entry(&entry)?;
    }
    feed(&mut system, id, &mut mailbox);
    system.set_root(args.root.as_deref())?;
    let symbols = SymbolTable::new(
        program
            .symbols
            .iter()
            .map(|(n, a)| (*a, n.clone()))
            .collect(),
    );
    // PPE-assisted calls (stop 0x2100..0x21ff) are served and the program resumed.
    // The mailbox holds 4 values: the rest go in as the program waits for them.
    let outcome = loop {
        let outcome = if args.trace {
            trace(&mut system, id, args.max_cycles, &symbols, args.json)?
        } else {
            system.run(args.max_cycles)
        };
        match &outcome {
            Outcome::Waiting(waits)
                if !mailbox.is_empty() && waits.iter().any(|w| w.channel == Channel::InMbox) =>
            {
                feed(&mut system, id, &mut mailbox)
            }
            _ => break outcome,
        }
    };
    let stop = match final_stop(&system, id, &outcome) {
        Ok(stop) => stop,
        Err((pc, fault)) => {
            eprintln!(
                "spu: {}: the program stopped at {pc:#x}: {fault}",
                args.file.display(),
            );
            return Ok(Status::AbnormalStop.into());
        }
    };
    let spu = system.spu_mut(id);
    let out_mbox = spu.read_outbound_mailbox();
    if args.json {
        json_report(spu, &stop, out_mbox, &dumps)?;
    } else {
        if !args.quiet {
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
        text_dumps(spu.ls(), &dumps)?;
    }
    Ok(exit_status(&args.file, &stop))
}

/// `spu run --json`: one document on standard output, the local-store dumps in it.
fn json_report(
    spu: &Spu,
    stop: &StopReason,
    out_mbox: Option<u32>,
    dumps: &[std::ops::Range<usize>],
) -> exit::Result<()> {
    let report = RunReport {
        stop: describe(stop),
        exit_code: exit::program_exit_code(stop),
        pc: spu.pc(),
        instructions: spu.instructions(),
        cycles: spu.cycles(),
        outbound_mailbox: out_mbox,
        registers: (0..128).map(|n| spu.reg(n)).collect(),
        local_store: dumps
            .iter()
            .map(|range| LsDump {
                address: range.start,
                bytes: spu.ls()[range.clone()]
                    .iter()
                    .map(|b| format!("{b:02x}"))
                    .collect(),
            })
            .collect(),
    };
    let json =
        serde_json::to_string(&report).map_err(|e| exit::Error::failure(format!("JSON: {e}")))?;
    outln!("{json}");
    Ok(())
}

/// `--dump-ls` as text: 16 bytes a row, each row with its address.
fn text_dumps(ls: &[u8], dumps: &[std::ops::Range<usize>]) -> exit::Result<()> {
    for range in dumps {
        for row in range.clone().step_by(16) {
            let end = (row + 16).min(range.end);
            let hex: Vec<String> = ls[row..end].iter().map(|b| format!("{b:02x}")).collect();
            outln!("{row:05x}: {}", hex.join(" "));
        }
    }
    Ok(())
}

/// `--dump-entry`: the registers that are not zero at entry and the argv region.
fn dump_entry(entry: &spu_spe::ppe::start::Entry) -> exit::Result<()> {
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
/// address, text and the registers it changed: on standard error under `--json`, whose
/// standard output is the one JSON document (a trace is too long to hold in it).
fn trace(
    system: &mut System,
    id: ContextId,
    max_cycles: u64,
    symbols: &SymbolTable,
    json: bool,
) -> exit::Result<Outcome> {
    loop {
        let spu = system.spu(id);
        if spu.cycles() >= max_cycles {
            return Ok(Outcome::CycleLimit);
        }
        let pc = spu.pc();
        let at = pc as usize & (256 * 1024 - 4);
        let ls = spu.ls();
        let word = u32::from_be_bytes([ls[at], ls[at + 1], ls[at + 2], ls[at + 3]]);
        let before: Vec<_> = (0..128).map(|n| spu.reg(n)).collect();
        let outcome = system.run(spu.cycles() + 1);
        let spu = system.spu(id);
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
        if json {
            eprintln!("{line}");
        } else {
            outln!("{line}");
        }
        if outcome != Outcome::CycleLimit {
            return Ok(outcome);
        }
    }
}
