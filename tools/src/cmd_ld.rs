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
    /// Objects and archives, in link order (an archive is searched where it stands, for
    /// the symbols still undefined there).
    #[arg(required_unless_present = "library")]
    input: Vec<PathBuf>,
    /// A library `libNAME.a` from the `-L` directories, searched where it stands among
    /// the inputs.
    #[arg(short = 'l')]
    library: Vec<String>,
    /// Output executable.
    #[arg(short = 'o', long, default_value = "a.out")]
    output: PathBuf,
    /// A directory searched for `-lNAME` (`libNAME.a`), in the order given.
    #[arg(short = 'L')]
    library_path: Vec<PathBuf>,
    /// Address of the code (the first section), as GNU ld's -Ttext.
    #[arg(long = "Ttext", value_parser = parse_address)]
    text: Option<u32>,
    /// A linker script (GNU ld's language: SECTIONS, OVERLAY, INSERT AFTER/BEFORE,
    /// KEEP, PROVIDE, ENTRY; docs/linker.md): its layout replaces the default one; a
    /// script with INSERT goes into the one without.
    #[arg(short = 'T', value_name = "SCRIPT")]
    script: Vec<PathBuf>,
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

/// The inputs and `-l` libraries in command-line order, as GNU ld takes them: clap
/// keeps each list apart, so their positions come from parsing the command line again.
fn in_order(args: &Args) -> Vec<Result<PathBuf, String>> {
    let raw: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let indices = raw.iter().position(|a| a == "ld").and_then(|at| {
        let cmd = <Args as clap::Args>::augment_args(clap::Command::new("ld"));
        let m = cmd.try_get_matches_from(&raw[at..]).ok()?;
        let of = |id: &str| m.indices_of(id).map(|i| i.collect()).unwrap_or_default();
        let (inputs, libs): (Vec<usize>, Vec<usize>) = (of("input"), of("library"));
        (inputs.len() == args.input.len() && libs.len() == args.library.len())
            .then_some((inputs, libs))
    });
    // Without positions (not run from the command line): the objects, then the libraries.
    let (inputs, libs) = indices.unwrap_or_else(|| {
        let n = args.input.len();
        ((0..n).collect(), (n..n + args.library.len()).collect())
    });
    let mut items: Vec<(usize, Result<PathBuf, String>)> = inputs
        .into_iter()
        .zip(&args.input)
        .map(|(i, p)| (i, Ok(p.clone())))
        .collect();
    items.extend(
        libs.into_iter()
            .zip(&args.library)
            .map(|(i, l)| (i, Err(l.clone()))),
    );
    items.sort_by_key(|x| x.0);
    items.into_iter().map(|x| x.1).collect()
}

/// The files named by the inputs, `-lNAME` found as GNU ld finds `libNAME.a` (the first
/// `-L` directory holding it).
fn input_paths(args: &Args) -> exit::Result<Vec<PathBuf>> {
    let mut paths = Vec::new();
    for item in in_order(args) {
        match item {
            Ok(path) => paths.push(path),
            Err(name) => {
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
        }
    }
    Ok(paths)
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    let paths = input_paths(&args)?;
    let mut files = crate::outputs::Files::new();
    for input in &paths {
        files.input("the input", input);
    }
    for script in &args.script {
        files.input("-T", script);
    }
    files.output("-o", &args.output).check()?;
    let mut scripts = Vec::new();
    for path in &args.script {
        let name = path.display().to_string();
        let bytes = crate::options::read_input(path, 1 << 20)?;
        let parsed = String::from_utf8(bytes)
            .map_err(|_| format!("{name}: not a text file"))
            .and_then(|text| spu_asm::link_script::parse(&name, &text));
        match parsed {
            Ok(s) => scripts.push((name, s)),
            Err(e) => {
                eprintln!("spu ld: {e}");
                return Ok(Status::BadInput.into());
            }
        }
    }
    let script = if scripts.is_empty() {
        None
    } else {
        match spu_asm::link_script::Script::combine(scripts) {
            Ok(s) => Some(s),
            Err(e) => {
                eprintln!("spu ld: {e}");
                return Ok(Status::BadInput.into());
            }
        }
    };
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
        output: Some(args.output.display().to_string()),
        script,
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
