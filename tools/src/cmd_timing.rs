//! `spu timing`: static timing of assembly source per basic block, in the layout of IBM's
//! `spu_timing` (see `docs/timing.md`).

use crate::exit;
use crate::options;
use spu_isa::static_timing::{analyze_source, render_static, static_json};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Assembly source (GNU as syntax, e.g. `spu-gcc -S` output).
    file: PathBuf,
    /// Analyse only the basic block starting at this label, from an idle pipeline.
    #[arg(long)]
    label: Option<String>,
    /// Print JSON: per instruction addr, text, pipe, issue, cycle, stall, dual, mark.
    #[arg(long)]
    json: bool,
    /// Start each instruction line with its issue cycle (spu_timing's -running-count).
    #[arg(long = "running-count")]
    running_count: bool,
    /// Write the listing here instead of standard output.
    #[arg(short = 'o', long)]
    output: Option<PathBuf>,
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    let mut files = crate::outputs::Files::new();
    files.input("the input", &args.file);
    if let Some(path) = &args.output {
        files.output("-o", path);
    }
    files.check()?;
    let bytes = options::read_input(&args.file, options::MAX_SOURCE_BYTES)?;
    let src =
        String::from_utf8(bytes).map_err(|_| format!("{}: not UTF-8 text", args.file.display()))?;
    let t = analyze_source(&src, args.label.as_deref())?;
    for (line, word) in t.unknown_statements() {
        eprintln!(
            "{}:{line}: warning: `{word}` is not an SPU instruction; not timed",
            args.file.display()
        );
    }
    let text = if args.json {
        static_json(&t)
    } else {
        render_static(&t, args.running_count)
    };
    match &args.output {
        Some(path) => exit::write_file(path, text.as_bytes())?,
        None => out!("{text}"),
    }
    Ok(ExitCode::SUCCESS)
}
