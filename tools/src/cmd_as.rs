//! `spu as`: assemble GNU-as SPU assembly into an SPU ELF or a flat local-store image.

use crate::exit::{self, Error, Status};
use spu_asm::{assemble_file, Options, Severity};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Assembly source.
    input: PathBuf,
    /// Output file.
    #[arg(short = 'o', long, default_value = "a.out")]
    output: PathBuf,
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

pub fn run(args: Args) -> exit::Result<ExitCode> {
    if args.format != "elf" && args.format != "bin" {
        return Err(Error::input(format!(
            "--format {}: expected elf or bin",
            args.format
        )));
    }
    exit::check_writable(&args.output)?;
    if let Some(path) = &args.listing {
        exit::check_writable(path)?;
    }
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
    match assemble_file(&args.input, &opts) {
        Ok(out) => {
            for w in &out.warnings {
                eprintln!("{w}");
            }
            let bytes = if args.format == "bin" {
                &out.image
            } else {
                &out.elf
            };
            exit::write_file(&args.output, bytes)?;
            if let Some(path) = &args.listing {
                exit::write_file(path, out.listing.as_bytes())?;
            }
            Ok(ExitCode::SUCCESS)
        }
        Err(diagnostics) => {
            let errors = diagnostics
                .iter()
                .filter(|d| d.severity == Severity::Error)
                .count();
            for d in &diagnostics {
                eprintln!("{d}");
            }
            eprintln!("{errors} error(s); nothing written");
            Ok(Status::BadInput.into())
        }
    }
}
