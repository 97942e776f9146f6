//! `spu prof`: run a program with the timing model and print an annotated profile: per
//! instruction its executions, cycles and stall cycles by cause, a dual-issue mark, then a
//! summary per label and the totals IBM's simulator reported.

use crate::exit::{self, Status};
use crate::options;
use spu_isa::profile::{annotated_listing, executed_lines, listing_json, ListingOptions};
use spu_spe::{ContextConfig, Start, System};
use std::path::PathBuf;
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
    /// Program: SPU assembly (.s), an SPU ELF or a flat image.
    file: PathBuf,
    /// Print JSON for tools.
    #[arg(long)]
    json: bool,
    /// Only the addresses from the first label up to (not including) the second.
    #[arg(long, value_name = "LABEL..LABEL")]
    range: Option<String>,
    /// Stop after this many cycles.
    #[arg(long = "max-cycles", default_value_t = 1_000_000_000)]
    max_cycles: u64,
    /// Main memory in bytes.
    #[arg(long, default_value_t = 1 << 20)]
    memory: u64,
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    options::max_cycles(args.max_cycles)?;
    let memory_bytes = options::memory(args.memory)?;
    let program = crate::cmd_run::load(&args.file)?;
    let symbols = &program.symbols;
    let address_of = |name: &str| symbols.iter().find(|(n, _)| n == name).map(|(_, a)| *a);
    let range = match &args.range {
        Some(r) => {
            let (a, b) = r
                .split_once("..")
                .ok_or_else(|| format!("--range {r}: expected LABEL..LABEL"))?;
            let start = address_of(a).ok_or_else(|| format!("--range: no label `{a}`"))?;
            let end = address_of(b).ok_or_else(|| format!("--range: no label `{b}`"))?;
            if end <= start {
                return Err(exit::Error::input(format!(
                    "--range {r}: `{b}` ({end:#x}) does not come after `{a}` ({start:#x})"
                )));
            }
            Some((start, end))
        }
        None => None,
    };
    // Started as `spu run` starts it, its PPE-assisted calls served.
    let mut system = System::new(memory_bytes);
    let id = system.create_context(ContextConfig {
        engine: args.engine,
        timing: Some(Default::default()),
        code: Some(args.compile.cache()),
        extensions: args.ext.ext,
    });
    let start = Start::Shell {
        args: vec![args.file.as_os_str().as_encoded_bytes().to_vec()],
    };
    system
        .load(id, &program, &start)
        .map_err(|e| format!("{}: {e}", args.file.display()))?;
    let outcome = system.run(args.max_cycles);
    let stop = match crate::cmd_run::final_stop(&system, id, &outcome) {
        Ok(stop) => stop,
        Err((pc, fault)) => {
            eprintln!(
                "spu: {}: the program stopped at {pc:#x}: {fault}",
                args.file.display()
            );
            return Ok(Status::AbnormalStop.into());
        }
    };
    let spu = system.spu(id);
    let profile = spu
        .timing()
        .map(|t| t.finish_profile())
        .ok_or_else(|| exit::Error::failure("timing was not enabled"))?;
    // Every executed address, with its labels and disassembly, in address order.
    let lines = executed_lines(&profile, spu.ls(), symbols);
    let opts = ListingOptions {
        range,
        executed_only: true,
    };
    if args.json {
        outln!("{}", listing_json(&profile, &lines, &opts));
    } else {
        outln!("{}: stopped with {stop}", args.file.display());
        out!("{}", annotated_listing(&profile, &lines, &opts));
    }
    // The profile is printed whatever the end; the status says how the program ended.
    let status = Status::of_stop(&stop);
    if status != Status::Success {
        eprintln!("spu: {}: {stop}", args.file.display());
    }
    Ok(status.into())
}
