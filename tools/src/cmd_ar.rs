//! `spu ar`: build and list static libraries of SPU objects, GNU ar's `rcs` and `t`, so
//! that users and tests can make the archives `spu ld -l` links.

use crate::exit::{self, Error, Status};
use spu_asm::archive::{Archive, Member};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// Operation and modifiers as GNU ar takes them: `r` (insert, replacing members of the
    /// same name) with `c` (create quietly) and `s` (write the symbol index), or `t` (list
    /// the members).
    operation: String,
    /// The archive.
    archive: PathBuf,
    /// Objects to insert (`r`).
    members: Vec<PathBuf>,
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    let op = args.operation.trim_start_matches('-');
    if op.is_empty() || !op.chars().all(|c| "rcstuD".contains(c)) {
        return Err(Error::input(format!(
            "{}: expected r with c and s, or t",
            args.operation
        )));
    }
    let (insert, list) = (op.contains('r'), op.contains('t'));
    if insert == list {
        return Err(Error::input(format!(
            "{}: give one of r (insert) or t (list)",
            args.operation
        )));
    }
    let name = args.archive.display().to_string();
    let existing = if args.archive.exists() {
        let bytes = crate::options::read_input(&args.archive, 256 << 20)?;
        match Archive::read(&name, &bytes) {
            Ok(a) => Some(a),
            Err(e) => {
                eprintln!("spu ar: {e}");
                return Ok(Status::BadInput.into());
            }
        }
    } else {
        None
    };
    if list {
        let archive = existing.ok_or_else(|| Error::input(format!("{name}: no such file")))?;
        for m in &archive.members {
            println!("{}", m.name);
        }
        return Ok(ExitCode::SUCCESS);
    }
    if args.members.is_empty() {
        return Err(Error::input("r: expected objects to insert"));
    }
    if args.members.contains(&args.archive) {
        return Err(Error::input(format!(
            "{name}: the archive is also a member"
        )));
    }
    if existing.is_none() && !op.contains('c') {
        eprintln!("spu ar: creating {name}");
    }
    let mut archive = existing.unwrap_or_default();
    for path in &args.members {
        let data = crate::options::read_input(path, 64 << 20)?;
        let file = path
            .file_name()
            .map(|f| f.to_string_lossy().into_owned())
            .ok_or_else(|| Error::input(format!("{}: not a file name", path.display())))?;
        archive.replace(Member { name: file, data });
    }
    // GNU ar writes the index unless told `S`; `s` is the usual spelling of asking for it.
    archive.rebuild_index();
    exit::write_file(&args.archive, &archive.write())?;
    Ok(ExitCode::SUCCESS)
}
