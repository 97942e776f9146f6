//! `spu as`: assemble GNU-as SPU assembly into an SPU ELF executable, a flat local-store
//! image, or (`-c`) a relocatable object; several sources are assembled and linked.

use crate::exit::{self, Error, Status};
use spu_asm::link::{link, resolve_inputs, Input, LinkOptions};
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
    /// Link with the built-in SPU runtime (crt0 calling `main(argc, argv, envp)` then
    /// `exit`, `printf` and the other PPE-assisted calls; docs/running-programs.md).
    #[arg(long, conflicts_with = "object")]
    runtime: bool,
    /// Line numbers of the assembly source in the object's `.debug_line` (GNU as `-g`),
    /// unless the source has `.file N`/`.loc` of its own.
    #[arg(short = 'g')]
    debug_lines: bool,
    /// GNU as `--alternate`: the alternate macro syntax from the first line (`.altmacro`).
    #[arg(long)]
    alternate: bool,
    #[command(flatten)]
    ext: crate::options::ExtOption,
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    if args.format != "elf" && args.format != "bin" {
        return Err(Error::input(format!(
            "--format {}: expected elf or bin",
            args.format
        )));
    }
    files(&args, &[]).check()?;
    let mut opts = Options {
        include_dirs: args.include.clone(),
        extensions: args.ext.ext,
        debug_lines: args.debug_lines,
        alternate: args.alternate,
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
    if args.object || args.runtime || args.input.len() > 1 {
        return objects(&args, &opts);
    }
    match assemble_file(&args.input[0], &opts) {
        Ok(out) => {
            for w in &out.warnings {
                eprintln!("{w}");
            }
            files(&args, &[(&args.input[0], &out.included)]).check()?;
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
        Err(diagnostics) => Ok(report(&diagnostics)),
    }
}

/// What the command reads and writes: the sources, the files each source's `.include` and
/// `.incbin` read (known once it is assembled, and checked again then, before anything is
/// written), and the outputs.
fn files(args: &Args, included: &[(&PathBuf, &Vec<PathBuf>)]) -> crate::outputs::Files {
    let mut files = crate::outputs::Files::new();
    for input in &args.input {
        files.input("the input", input);
    }
    for (source, paths) in included {
        for path in paths.iter() {
            files.input(format!("{}'s included file", source.display()), path);
        }
    }
    files.output("-o", &args.output);
    if let Some(path) = &args.listing {
        files.output("--listing", path);
    }
    files
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
    Status::BadInput.into()
}

/// `-c` (one object) or several sources (assembled to objects, then linked).
fn objects(args: &Args, opts: &Options) -> exit::Result<ExitCode> {
    if args.object && args.input.len() > 1 {
        return Err(Error::input("-c takes one source (one object per source)"));
    }
    if args.listing.is_some() {
        return Err(Error::input(
            "--listing is for one source assembled to an executable",
        ));
    }
    let mut objects = Vec::new();
    for input in &args.input {
        match assemble_object_file(input, opts) {
            Ok((obj, warnings)) => {
                for w in &warnings {
                    eprintln!("{w}");
                }
                objects.push(obj);
            }
            Err(d) => return Ok(report(&d)),
        }
    }
    let included: Vec<_> = args
        .input
        .iter()
        .zip(&objects)
        .map(|(input, obj)| (input, &obj.included))
        .collect();
    files(args, &included).check()?;
    if args.runtime {
        // As `spu ld --runtime`: crt0 first, the rest of the runtime searched after.
        let crt0 = spu_loader::ppe::runtime::start_file().map_err(Error::failure)?;
        let lib = spu_loader::ppe::runtime::library().map_err(Error::failure)?;
        let mut inputs = vec![Input::Object(crt0)];
        inputs.extend(objects.drain(..).map(Input::Object));
        inputs.push(Input::Archive("libspu.a".into(), lib));
        objects = resolve_inputs(inputs).map_err(Error::failure)?;
    }
    if args.object {
        let bytes = objects[0].to_elf().map_err(Error::failure)?;
        exit::write_file(&args.output, &bytes)?;
        return Ok(ExitCode::SUCCESS);
    }
    let opts = LinkOptions {
        output: Some(args.output.display().to_string()),
        ..Default::default()
    };
    let linked = match link(&objects, &opts) {
        Ok(l) => l,
        Err(errors) => {
            for e in &errors {
                eprintln!("spu ld: {e}");
            }
            return Ok(Status::BadInput.into());
        }
    };
    let bytes = if args.format == "bin" {
        &linked.image
    } else {
        &linked.elf
    };
    exit::write_file(&args.output, bytes)?;
    Ok(ExitCode::SUCCESS)
}
