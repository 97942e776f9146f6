//! `spu prof`: run a program with the timing model and print an annotated profile.
//!
//! The report side is ready (`spu_isa::profile::{annotated_listing, listing_json}` over a
//! `Timing::finish_profile()`); running needs the SPU core (`spu_isa::spu::Spu`), which is
//! being written. Until it exists this command says so.

use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Program: SPU assembly (.s), an SPU ELF or a flat image.
    file: PathBuf,
    /// Print JSON for tools.
    #[arg(long)]
    json: bool,
    /// Only the addresses from the first label up to (not including) the second.
    #[arg(long, value_name = "LABEL..LABEL")]
    range: Option<String>,
    /// Stop after this many cycles.
    #[arg(long = "max-cycles")]
    max_cycles: Option<u64>,
}

pub fn run(args: Args) -> Result<ExitCode, String> {
    let _ = (&args.json, &args.range, &args.max_cycles);
    Err(format!(
        "{}: `spu prof` needs the SPU core (spu_isa::spu::Spu), which is not available yet; \
         `spu timing` gives the static analysis meanwhile",
        args.file.display()
    ))
}
