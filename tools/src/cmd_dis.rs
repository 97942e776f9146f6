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
        let elf = spu_spe::elf::read_elf(&bytes).map_err(|e| format!("{name}: {e}"))?;
        // objdump names an address after a symbol of its section: a function or object
        // before a bare global (the linker's `__bss_start`), a global before local labels;
        // absolute symbols name nothing.
        let symbols = SymbolTable::ranked(
            elf.symbol_kinds
                .iter()
                .filter(|s| !s.absolute)
                .map(|s| (s.addr, s.name.clone(), 2 * !s.global as u8 + !s.typed as u8))
                .collect(),
        );
        out!("\n{name}:     file format elf32-spu\n\n");
        for (section, addr, data, code) in &elf.sections {
            if *code {
                out!(
                    "\nDisassembly of section {section}:\n{}",
                    listing_ext(data, *addr, &symbols, args.ext.ext)
                );
            }
        }
    } else {
        out!("\n{name}:     file format binary\n\n\nDisassembly of section .data:\n\n00000000 <.data>:\n{}", listing_ext(&bytes, 0, &SymbolTable::default(), args.ext.ext));
    }
    Ok(ExitCode::SUCCESS)
}
