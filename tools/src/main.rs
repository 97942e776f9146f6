//! `spu`: assemble, disassemble, run, profile and render on simulated SPUs.
//!
//! Each subcommand lives in its own module so that the commands can grow independently.

mod cmd_dis;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "spu", version, about = "Cell BE SPU toolchain and cycle-level simulator")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Disassemble an SPU ELF or a raw image, in GNU objdump's format.
    Dis(cmd_dis::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Dis(args) => cmd_dis::run(args),
    };
    match result {
        Ok(code) => code,
        Err(message) => {
            eprintln!("spu: {message}");
            ExitCode::from(1)
        }
    }
}
