//! `spu as`: assemble GNU-as SPU assembly into an SPU ELF executable, a flat local-store
//! image, or (`-c`) a relocatable object; several sources are assembled and linked.

use spu_asm::link::{link, LinkOptions};
use spu_asm::{assemble_file, assemble_object_file, Diagnostic, Options, Severity};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Assembly sources (several are assembled separately and linked).
    #[arg(required = true)]
    input: Vec<PathBuf>,
    /// Output file.
    #[arg(short = 'o', long, default_value = "a.out")]
    output: PathBuf,
    /// Write a relocatable object (ELF ET_REL) instead of an executable.
    #[arg(short = 'c')]
    object: bool,
    /// `elf` (an SPU ELF executable) or `bin` (the flat image loaded at address 0).
    #[arg(long, default_value = "elf")]
    format: String,
    /// Directories searched by `.include`.
    #[arg(short = 'I')]
    include: Vec<PathBuf>,
    /// Write a listing (address, words, source line).
    #[arg(long)]
    listing: Option<PathBuf>,
    /// Define a symbol: NAME=VALUE.
    #[arg(long = "defsym")]
    defsym: Vec<String>,
}

/// Prints diagnostics; the exit status for a failed assembly.
fn report(diagnostics: &[Diagnostic]) -> ExitCode {
    let errors = diagnostics
        .iter()
        .filter(|d| d.severity == Severity::Error)
        .count();
    for d in diagnostics {
        eprintln!("{d}");
    }
    eprintln!("{errors} error(s); nothing written");
    ExitCode::from(2)
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let mut opts = Options {
        include_dirs: args.include.clone(),
        ..Default::default()
    };
    for d in &args.defsym {
        let (name, value) = d
            .split_once('=')
            .ok_or_else(|| format!("--defsym {d}: expected NAME=VALUE"))?;
        let value = value.trim();
        let v = if let Some(h) = value.strip_prefix("0x") {
            i64::from_str_radix(h, 16)
        } else {
            value.parse()
        };
        opts.defines.push((
            name.trim().to_string(),
            v.map_err(|_| format!("--defsym {d}: bad value"))?,
        ));
    }
    if !matches!(args.format.as_str(), "elf" | "bin") {
        return Err(format!("--format {}: expected elf or bin", args.format));
    }
    let write = |bytes: &[u8]| {
        std::fs::write(&args.output, bytes).map_err(|e| format!("{}: {e}", args.output.display()))
    };
    if args.object || args.input.len() > 1 {
        if args.object && args.input.len() > 1 {
            return Err("-c takes one source (one object per source)".into());
        }
        if args.listing.is_some() {
            return Err("--listing is for one source assembled to an executable".into());
        }
        let mut objects = Vec::new();
        for input in &args.input {
            match assemble_object_file(input, &opts) {
                Ok((obj, warnings)) => {
                    for w in &warnings {
                        eprintln!("{w}");
                    }
                    objects.push(obj);
                }
                Err(d) => return Ok(report(&d)),
            }
        }
        if args.object {
            write(&objects[0].to_elf()?)?;
            return Ok(ExitCode::SUCCESS);
        }
        let linked = match link(&objects, &LinkOptions::default()) {
            Ok(l) => l,
            Err(errors) => {
                for e in &errors {
                    eprintln!("spu ld: {e}");
                }
                return Ok(ExitCode::from(2));
            }
        };
        write(if args.format == "bin" {
            &linked.image
        } else {
            &linked.elf
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    match assemble_file(&args.input[0], &opts) {
        Ok(out) => {
            for w in &out.warnings {
                eprintln!("{w}");
            }
            write(if args.format == "bin" {
                &out.image
            } else {
                &out.elf
            })?;
            if let Some(path) = &args.listing {
                std::fs::write(path, &out.listing)
                    .map_err(|e| format!("{}: {e}", path.display()))?;
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(diagnostics) => Ok(report(&diagnostics)),
    }
}
