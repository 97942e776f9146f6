//! `spu run`: run a program on one simulated SPU and report how it stopped.

use spu_isa::disasm::{instruction_text, SymbolTable};
use spu_isa::machine::{MainMemory, Spu, StopReason};
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
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
    memory: usize,
    /// Machine-readable output.
    #[arg(long)]
    json: bool,
}

fn number(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let v = match t.strip_prefix("0x") {
        Some(h) => u64::from_str_radix(h, 16),
        None => t.parse(),
    };
    v.map_err(|_| format!("bad number `{text}`"))
}

/// Loads FILE into a fresh SPU.
pub fn load(file: &PathBuf) -> Result<(Spu, Vec<(String, u32)>), String> {
    let name = file.display();
    let mut spu = Spu::new(0);
    let mut symbols = Vec::new();
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
    } else {
        let bytes = std::fs::read(file).map_err(|e| format!("{name}: {e}"))?;
        if bytes.starts_with(b"\x7fELF") {
            let elf = spu_asm::elf::read_elf(&bytes).map_err(|e| format!("{name}: {e}"))?;
            let segments: Vec<(u32, &[u8])> = elf
                .segments
                .iter()
                .map(|(a, d)| (*a, d.as_slice()))
                .collect();
            spu.load_segments(&segments, elf.entry);
            symbols = elf.symbols;
        } else {
            if bytes.len() > 256 * 1024 {
                return Err(format!(
                    "{name}: {} bytes do not fit the 256 KiB local store",
                    bytes.len()
                ));
            }
            spu.load_image(&bytes);
        }
    }
    Ok((spu, symbols))
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let (mut spu, symbols) = load(&args.file)?;
    for v in &args.mbox_in {
        if !spu.write_inbound_mailbox(number(v)? as u32) {
            return Err("the inbound mailbox holds 4 values".into());
        }
    }
    if args.timing {
        spu.enable_timing(Default::default());
    }
    let mut memory = MainMemory::zeroed(args.memory);
    let stop = if args.trace {
        let symbols = SymbolTable::new(symbols.iter().map(|(n, a)| (*a, n.clone())).collect());
        trace(&mut spu, &mut memory, args.max_cycles, &symbols)
    } else {
        spu.run(&mut memory, args.max_cycles)
    };
    let out_mbox = spu.read_outbound_mailbox();
    if args.json {
        let regs: Vec<String> = (0..128).map(|n| format!("{:?}", spu.reg(n))).collect();
        println!(
            "{{\"stop\": \"{}\", \"pc\": {}, \"instructions\": {}, \"cycles\": {}, \"outbound_mailbox\": {}, \"registers\": [{}]}}",
            describe(&stop),
            spu.pc(),
            spu.instructions(),
            spu.cycles(),
            out_mbox.map_or("null".to_string(), |v| v.to_string()),
            regs.join(", ")
        );
    } else {
        println!("stopped: {}", describe(&stop));
        println!("pc: {:#x}", spu.pc());
        println!("instructions: {}", spu.instructions());
        println!("cycles: {}", spu.cycles());
        if let Some(v) = out_mbox {
            println!("outbound mailbox: {v:#x}");
        }
        if args.dump_regs {
            for n in 0..128 {
                let r = spu.reg(n);
                println!("${n}: {:08x} {:08x} {:08x} {:08x}", r[0], r[1], r[2], r[3]);
            }
        }
    }
    for spec in &args.dump_ls {
        let (a, l) = spec
            .split_once(':')
            .ok_or_else(|| format!("--dump-ls {spec}: expected ADDR:LEN"))?;
        let (addr, len) = (number(a)? as usize, number(l)? as usize);
        let ls = spu.ls();
        for row in (addr..(addr + len).min(ls.len())).step_by(16) {
            let end = (row + 16).min(addr + len).min(ls.len());
            let hex: Vec<String> = ls[row..end].iter().map(|b| format!("{b:02x}")).collect();
            println!("{row:05x}: {}", hex.join(" "));
        }
    }
    let ok = matches!(stop, StopReason::Stop(_));
    Ok(if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(2)
    })
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
) -> StopReason {
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    loop {
        if spu.cycles() >= max_cycles {
            return StopReason::CycleLimit;
        }
        let pc = spu.pc();
        let at = pc as usize & (256 * 1024 - 4);
        let ls = spu.ls();
        let word = u32::from_be_bytes([ls[at], ls[at + 1], ls[at + 2], ls[at + 3]]);
        let before: Vec<_> = (0..128).map(|n| spu.reg(n)).collect();
        let stop = spu.run(memory, spu.cycles() + 1);
        let mut line = format!(
            "{pc:05x}: {:08x}  {}",
            word,
            instruction_text(word, pc, symbols)
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
        // A closed pipe (`| head`) ends the trace quietly.
        if writeln!(out, "{line}").is_err() {
            return stop;
        }
        if stop != StopReason::CycleLimit {
            let _ = out.flush();
            return stop;
        }
    }
}
