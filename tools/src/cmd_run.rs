//! `spu run`: run a program on one simulated SPU and report how it stopped.

use spu_isa::machine::{MainMemory, Spu, StopReason};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Engine: the block compiler (jit; the default where the host has one) or the
    /// interpreter (interp). Results are the same; only host speed differs.
    #[arg(long, default_value_t = spu_isa::jit::Engine::host_default())]
    engine: spu_isa::jit::Engine,
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
    #[arg(long)]
    timing: bool,
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
    spu_isa::jit::Engine::set_default(args.engine);
    let (mut spu, _) = load(&args.file)?;
    for v in &args.mbox_in {
        if !spu.write_inbound_mailbox(number(v)? as u32) {
            return Err("the inbound mailbox holds 4 values".into());
        }
    }
    if args.timing {
        spu.enable_timing(Default::default());
    }
    let mut memory = MainMemory::zeroed(args.memory);
    let stop = spu.run(&mut memory, args.max_cycles);
    let out_mbox = spu.read_outbound_mailbox();
    if args.json {
        let regs: Vec<String> = (0..128).map(|n| format!("{:?}", spu.reg(n))).collect();
        println!(
            "{{\"stop\": \"{}\", \"pc\": {}, \"instructions\": {}, \"cycles\": {}, \"outbound_mailbox\": {}, \"registers\": [{}]}}",
            stop,
            spu.pc(),
            spu.instructions(),
            spu.cycles(),
            out_mbox.map_or("null".to_string(), |v| v.to_string()),
            regs.join(", ")
        );
    } else {
        println!("stopped: {stop}");
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
