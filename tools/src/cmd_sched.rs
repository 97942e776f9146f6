//! `spu sched`: list-schedule straight-line SPU code into dual-issue pairs (the assembler's
//! `.sched` blocks, shown as source), so a block written in logical order with virtual
//! registers can be read, timed and pasted as the assembler would lay it out.

use crate::exit;
use spu_asm::sched::{find_blocks, parse_options, parse_registers, schedule, Names, SchedOptions};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Source: either a file with `.sched` ... `.endsched` blocks (each is replaced by its
    /// schedule) or, without any, one block in logical order.
    input: PathBuf,
    /// Registers for the `%name` virtual registers of a whole-file block: `78-111,113`.
    #[arg(long)]
    pool: Option<String>,
    /// Registers besides the pool whose writes may move above a branch (whole-file block).
    #[arg(long)]
    scratch: Option<String>,
    /// A file whose `.set` definitions name the registers (repeatable).
    #[arg(long)]
    names: Vec<PathBuf>,
    /// Directories searched by `.include` for register names.
    #[arg(short = 'I')]
    include: Vec<PathBuf>,
    /// The address the block(s) will be assembled at, for the instruction-fetch lines
    /// (the assembler knows it; without it fetch is not modelled).
    #[arg(long, value_parser = parse_address)]
    address: Option<u32>,
    /// Output file (default: standard output).
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
}

/// Exit status 0, 1 when writing the output fails part-way, 2 for bad input (an unreadable
/// source, a block that does not schedule, bad options, an output that cannot be written or
/// would overwrite an input).
pub fn run(args: Args) -> exit::Result<ExitCode> {
    let mut files = crate::outputs::Files::new();
    files.input("the input", &args.input);
    for path in &args.names {
        files.input("--names", path);
    }
    if let Some(path) = &args.output {
        files.output("-o", path);
    }
    files.check()?;
    let read =
        |p: &PathBuf| std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()));
    let source = read(&args.input)?;
    let mut dirs: Vec<PathBuf> = args.input.parent().map(PathBuf::from).into_iter().collect();
    dirs.extend(args.include.iter().cloned());
    let mut include = |name: &str| {
        dirs.iter()
            .find_map(|d| std::fs::read_to_string(d.join(name)).ok())
    };
    let mut names = Names::default();
    for path in &args.names {
        names.collect(&read(path)?, &mut include);
    }
    names.collect(&source, &mut include);
    let resolve = |text: &str| names.register(text);
    let file = args.input.display().to_string();
    let lines: Vec<&str> = source.lines().collect();
    let blocks =
        find_blocks(&lines).map_err(|e| format!("{file}:{}: {}", e.line + 1, e.message))?;
    let mut out = String::new();
    let report = |first: usize, s: &spu_asm::sched::Scheduled| {
        eprintln!(
            "{file}:{}: {} instructions in {} cycles (scheduler's model)",
            first + 1,
            s.instructions,
            s.cycles
        );
    };
    if blocks.is_empty() {
        let opts = SchedOptions {
            pool: parse_registers(args.pool.as_deref().unwrap_or(""))
                .map_err(|e| format!("--pool: {e}"))?,
            scratch: parse_registers(args.scratch.as_deref().unwrap_or(""))
                .map_err(|e| format!("--scratch: {e}"))?,
        };
        let s = schedule(&lines, &opts, args.address, &resolve)
            .map_err(|e| located(&file, 0, &lines, &e))?;
        report(0, &s);
        for (text, _) in &s.lines {
            out.push_str(text);
            out.push('\n');
        }
    } else {
        if args.pool.is_some() || args.scratch.is_some() {
            return Err(
                "--pool and --scratch are for a file without .sched blocks; a block \
                        names its own (.sched pool=... scratch=...)"
                    .into(),
            );
        }
        let mut next = 0;
        for (start, end) in blocks {
            for line in &lines[next..start] {
                out.push_str(line);
                out.push('\n');
            }
            let directive = lines[start].trim();
            let opts =
                parse_options(&directive[6..]).map_err(|e| format!("{file}:{}: {e}", start + 1))?;
            let body = &lines[start + 1..end];
            let s = schedule(body, &opts, args.address, &resolve)
                .map_err(|e| located(&file, start + 1, &lines, &e))?;
            report(start, &s);
            out.push_str(&format!(
                "# {directive}: {} instructions in {} cycles (scheduler's model)\n",
                s.instructions, s.cycles
            ));
            for (text, _) in &s.lines {
                out.push_str(text);
                out.push('\n');
            }
            next = end + 1;
        }
        for line in &lines[next..] {
            out.push_str(line);
            out.push('\n');
        }
    }
    match &args.output {
        Some(path) => exit::write_file(path, out.as_bytes())?,
        None => crate::out!("{out}"),
    }
    Ok(ExitCode::SUCCESS)
}

fn located(file: &str, offset: usize, lines: &[&str], e: &spu_asm::sched::SchedError) -> String {
    let line = offset + e.line;
    format!(
        "{file}:{}:{}: {}\n    {}",
        line + 1,
        e.column.max(1),
        e.message,
        lines.get(line).map_or("", |l| l.trim_end())
    )
}

fn parse_address(text: &str) -> Result<u32, String> {
    let parsed = match text.strip_prefix("0x") {
        Some(hex) => u32::from_str_radix(hex, 16),
        None => text.parse(),
    };
    parsed
        .ok()
        .filter(|a| a % 8 == 0 && *a < 256 * 1024)
        .ok_or_else(|| format!("`{text}`: expected an 8-byte aligned local-store address"))
}
