//! `spu dis`: objdump-style disassembly of a raw image (loaded at 0) or an SPU ELF.

use spu_isa::disasm::{listing, SymbolTable};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// An SPU ELF executable or a flat image loaded at address 0.
    file: PathBuf,
    /// Treat the file as a raw image even if it looks like an ELF.
    #[arg(long)]
    raw: bool,
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let bytes = std::fs::read(&args.file).map_err(|e| format!("{}: {e}", args.file.display()))?;
    let text = listing(&bytes, 0, &SymbolTable::default());
    print!("{}:     file format binary\n\n\nDisassembly of section .data:\n\n00000000 <.data>:\n{text}", args.file.display());
    Ok(ExitCode::SUCCESS)
}
