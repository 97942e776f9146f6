//! GNU `as` compatible assembler for SPU: the same syntax, directives and encodings, with
//! diagnostics that name file:line:column. Output is a flat local-store image and an SPU
//! ELF executable, or a relocatable object; `link` joins objects into an executable.

//!
//! The house, bottom up: `lex`, `expr` and `expand` read gas syntax (shared with
//! `sched`, the list scheduler behind `.sched` and `spu sched`); `object`, `reloc` and
//! `executable` model ELF; `gas` (split as GNU as is: see its header) and `link` build on both
//! and not on each other.

pub mod archive;
pub mod disasm;
pub mod elf_check;
pub mod executable;
mod expand;
mod expr;
mod gas;
mod lex;
pub mod link;
mod link_debug;
mod link_groups;
pub mod link_overlay;
pub mod link_script;
pub mod object;
mod object_write;
pub mod reloc;
pub mod sched;

pub use gas::{
    assemble, assemble_object, Diagnostic, Location, Options, Output, Severity, CHANNELS,
    MAX_SOURCE,
};
pub use object::{Reloc, RelocTarget};

fn read_failure(path: &std::path::Path, e: String) -> Vec<Diagnostic> {
    vec![Diagnostic {
        severity: Severity::Error,
        location: Location {
            file: path.display().to_string(),
            line: 0,
            column: 0,
        },
        message: format!("can't read: {e}"),
        source_line: String::new(),
    }]
}

fn with_dir(path: &std::path::Path, opts: &Options) -> Options {
    let mut opts = opts.clone();
    if let Some(dir) = path.parent() {
        opts.include_dirs.push(dir.to_path_buf());
    }
    opts
}

/// Reads a source file (each byte one character, as gas reads it; at most `MAX_SOURCE`).
fn read(path: &std::path::Path) -> Result<String, Vec<Diagnostic>> {
    lex::read_source(path).map_err(|e| read_failure(path, e))
}

/// Assembles a file from disk, with its directory on the include path.
pub fn assemble_file(path: &std::path::Path, opts: &Options) -> Result<Output, Vec<Diagnostic>> {
    let source = read(path)?;
    gas::assemble_chars(&source, &path.display().to_string(), &with_dir(path, opts))
}

/// Assembles a file from disk into a relocatable object (and its warnings).
pub fn assemble_object_file(
    path: &std::path::Path,
    opts: &Options,
) -> Result<(object::Object, Vec<Diagnostic>), Vec<Diagnostic>> {
    let source = read(path)?;
    gas::assemble_object_chars(&source, &path.display().to_string(), &with_dir(path, opts))
}
