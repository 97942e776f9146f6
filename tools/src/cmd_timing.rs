//! `spu timing`: static timing of assembly source per basic block, in the layout of IBM's
//! `spu_timing` (see `docs/timing.md`).

use crate::exit;
use crate::options;
use spu_isa::static_timing::{analyze_source, render_static, static_json, StaticTiming};
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
    check_operands(&args.file, &t)?;
    for (line, word) in t.unknown_statements() {
        eprintln!(
            "{}:{line}:{}: warning: `{word}` is not an SPU instruction; not timed",
            args.file.display(),
            word_column(&src, line, word)
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

/// The column (from 1) of statement `word` on line `line` of `src`, for a warning in the
/// assembler's `file:line:column` form: its first occurrence at the start of a word.
fn word_column(src: &str, line: usize, word: &str) -> usize {
    let text = src.lines().nth(line.saturating_sub(1)).unwrap_or("");
    let starts_word = |i: usize| {
        text[..i]
            .chars()
            .next_back()
            .is_none_or(|c| c.is_whitespace() || c == ':' || c == ';')
    };
    text.match_indices(word)
        .map(|(i, _)| i)
        .find(|&i| starts_word(i))
        .map_or(1, |i| text[..i].chars().count() + 1)
}

/// Refuses an instruction `spu as` refuses (a register past `$127`, an immediate out of
/// range, a bad operand), with the assembler's diagnostics, before timing anything: the
/// timing of an instruction that does not assemble describes no program. Statements the
/// timing does not time (reported as warnings) are left to the warnings.
fn check_operands(file: &std::path::Path, timing: &StaticTiming) -> exit::Result<()> {
    let Err(diagnostics) = spu_asm::assemble_object_file(file, &Default::default()) else {
        return Ok(());
    };
    let name = file.display().to_string();
    let timed = |line: usize| {
        line >= 1
            && timing
                .lines
                .get(line - 1)
                .is_some_and(|l| !l.insts.is_empty())
    };
    let refused: Vec<String> = diagnostics
        .iter()
        .filter(|d| {
            d.severity == spu_asm::Severity::Error
                && d.location.file == name
                && timed(d.location.line)
        })
        .map(|d| d.to_string())
        .collect();
    if refused.is_empty() {
        return Ok(());
    }
    Err(exit::Error::input(refused.join("\n")))
}
