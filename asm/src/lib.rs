//! GNU `as` compatible assembler for SPU: the same syntax, directives and encodings, with
//! diagnostics that name file:line:column. Output is a flat local-store image and an SPU ELF.

pub mod elf;
mod expr;
mod gas;
pub mod sched;

pub use gas::{assemble, Diagnostic, Location, Options, Output, Severity};

/// Assembles a file from disk, with its directory on the include path.
pub fn assemble_file(path: &std::path::Path, opts: &Options) -> Result<Output, Vec<Diagnostic>> {
    let source = std::fs::read_to_string(path).map_err(|e| {
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
    })?;
    let mut opts = opts.clone();
    if let Some(dir) = path.parent() {
        opts.include_dirs.push(dir.to_path_buf());
    }
    assemble(&source, &path.display().to_string(), &opts)
}
