//! `spu ld`: link relocatable SPU objects (from `spu as -c` or GNU as) into an executable.

use crate::exit::{self, Status};
use spu_asm::link::{link, LinkOptions};
use spu_asm::object::Object;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Relocatable objects.
    #[arg(required = true)]
    input: Vec<PathBuf>,
    /// Output executable.
    #[arg(short = 'o', long, default_value = "a.out")]
    output: PathBuf,
    /// Address of the code (the first section), as GNU ld's -Ttext.
    #[arg(long = "Ttext", value_parser = parse_address)]
    text: Option<u32>,
    /// Entry symbol (default `_start`).
    #[arg(short = 'e', long = "entry")]
    entry: Option<String>,
}

fn parse_address(s: &str) -> Result<u32, String> {
    let v = match s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        Some(h) => u32::from_str_radix(h, 16),
        None => s.parse(),
    }
    .map_err(|_| format!("{s}: expected an address"))?;
    if v >= 256 * 1024 {
        return Err(format!("{s}: outside the 256 KiB local store"));
    }
    Ok(v)
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    let mut files = crate::outputs::Files::new();
    for input in &args.input {
        files.input("the input", input);
    }
    files.output("-o", &args.output).check()?;
    let mut objects = Vec::new();
    for path in &args.input {
        let name = path.display().to_string();
        let bytes = crate::options::read_input(path, 64 << 20)?;
        match Object::from_elf(&name, &bytes) {
            Ok(o) => objects.push(o),
            Err(e) => {
                eprintln!("spu ld: {e}");
                return Ok(Status::BadInput.into());
            }
        }
    }
    let opts = LinkOptions {
        text_addr: args.text.unwrap_or(0),
        entry: args.entry.clone(),
    };
    match link(&objects, &opts) {
        Ok(linked) => {
            exit::write_file(&args.output, &linked.elf)?;
            Ok(ExitCode::SUCCESS)
        }
        Err(errors) => {
            for e in &errors {
                eprintln!("spu ld: {e}");
            }
            Ok(Status::BadInput.into())
        }
    }
}
