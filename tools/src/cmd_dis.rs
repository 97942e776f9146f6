//! `spu dis`: objdump-style disassembly of an SPU ELF (its code sections, with symbols) or
//! of a raw image loaded at address 0.

use spu_isa::disasm::{listing_ext, SymbolTable};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// An SPU ELF executable or a flat image loaded at address 0.
    file: PathBuf,
    /// Treat the file as a raw image even if it looks like an ELF.
    #[arg(long)]
    raw: bool,
    #[command(flatten)]
    ext: crate::options::ExtOption,
}

pub fn run(args: Args) -> crate::exit::Result<ExitCode> {
    let bytes = crate::options::read_input(&args.file, crate::options::MAX_PROGRAM_BYTES)?;
    let name = args.file.display();
    if !args.raw && bytes.starts_with(b"\x7fELF") {
        out!(
            "{}",
            spu_asm::disasm::objdump(&name.to_string(), &bytes, args.ext.ext)?
        );
    } else {
        out!("\n{name}:     file format binary\n\n\nDisassembly of section .data:\n\n00000000 <.data>:\n{}", listing_ext(&bytes, 0, &SymbolTable::default(), args.ext.ext));
    }
    Ok(ExitCode::SUCCESS)
}
