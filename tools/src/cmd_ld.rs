//! `spu ld`: link relocatable SPU objects (from `spu as -c` or GNU as) and libraries
//! (`.a`, `-lNAME` searched in the `-L` directories) into an executable, as GNU ld does.

use crate::exit::{self, Error, Status};
use spu_asm::archive::{is_archive, Archive};
use spu_asm::link::{link, resolve_inputs, Input, LinkOptions};
use spu_asm::object::Object;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Objects, archives and `-lNAME` libraries, in link order (an archive is searched
    /// where it stands, for the symbols still undefined there).
    #[arg(required = true, allow_hyphen_values = true)]
    input: Vec<String>,
    /// Output executable.
    #[arg(short = 'o', long, default_value = "a.out")]
    output: PathBuf,
    /// A directory searched for `-lNAME` (`libNAME.a`), in the order given.
    #[arg(short = 'L')]
    library_path: Vec<PathBuf>,
    /// Address of the code (the first section), as GNU ld's -Ttext.
    #[arg(long = "Ttext", value_parser = parse_address)]
    text: Option<u32>,
    /// Entry symbol (default `_start`).
    #[arg(short = 'e', long = "entry")]
    entry: Option<String>,
    /// Link with the built-in SPU runtime, as spu-gcc's driver did: its `crt0` first, the
    /// rest searched as a library after the inputs (docs/running-programs.md).
    #[arg(long)]
    runtime: bool,
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

/// The files named by the inputs, `-lNAME` found as GNU ld finds `libNAME.a` (the first
/// `-L` directory holding it), `-l NAME` too.
fn input_paths(args: &Args) -> exit::Result<Vec<PathBuf>> {
    let mut paths = Vec::new();
    let mut items = args.input.iter();
    while let Some(item) = items.next() {
        let lib = match item.strip_prefix("-l") {
            Some("") => Some(
                items
                    .next()
                    .ok_or_else(|| Error::input("-l: expected a library name"))?
                    .as_str(),
            ),
            Some(name) => Some(name),
            None if item.starts_with('-') && item.len() > 1 => {
                return Err(Error::input(format!("{item}: unknown option")));
            }
            None => None,
        };
        match lib {
            Some(name) => {
                let file = format!("lib{name}.a");
                let found = args
                    .library_path
                    .iter()
                    .map(|d| d.join(&file))
                    .find(|p| p.is_file())
                    .ok_or_else(|| {
                        Error::input(format!("cannot find -l{name} ({file} in no -L directory)"))
                    })?;
                paths.push(found);
            }
            None => paths.push(PathBuf::from(item)),
        }
    }
    Ok(paths)
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    exit::check_writable(&args.output)?;
    let paths = input_paths(&args)?;
    let mut inputs = Vec::new();
    if args.runtime {
        let crt0 = spu_loader::ppe::runtime::start_file().map_err(Error::failure)?;
        inputs.push(Input::Object(crt0));
    }
    for path in &paths {
        let name = path.display().to_string();
        let bytes = crate::options::read_input(path, 64 << 20)?;
        let input = if is_archive(&bytes) {
            Archive::read(&name, &bytes).map(|a| Input::Archive(name, a))
        } else {
            Object::from_elf(&name, &bytes).map(Input::Object)
        };
        match input {
            Ok(i) => inputs.push(i),
            Err(e) => {
                eprintln!("spu ld: {e}");
                return Ok(Status::BadInput.into());
            }
        }
    }
    if args.runtime {
        let lib = spu_loader::ppe::runtime::library().map_err(Error::failure)?;
        inputs.push(Input::Archive("libspu.a".into(), lib));
    }
    let objects = match resolve_inputs(inputs) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("spu ld: {e}");
            return Ok(Status::BadInput.into());
        }
    };
    let opts = LinkOptions {
        text_addr: args.text.unwrap_or(0),
        entry: args.entry.clone(),
    };
    match link(&objects, &opts) {
        Ok(linked) => {
            for w in &linked.warnings {
                eprintln!("spu ld: warning: {w}");
            }
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
