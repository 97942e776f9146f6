//! Checks of numeric options and inputs made before any work starts, shared by the
//! commands, so that every limit is stated once and every message says what is allowed.

use crate::exit::{self, Error};
use std::io::Read;
use std::path::Path;

/// Largest program file `spu run`/`spu prof`/`spu dis` read (an ELF with symbols and debug
/// sections can be far larger than the 256 KiB it loads).
pub const MAX_PROGRAM_BYTES: u64 = 64 << 20;

/// Largest assembly source `spu timing` reads.
pub const MAX_SOURCE_BYTES: u64 = 64 << 20;

/// Largest simulated main memory: 4 GiB, more than any Cell blade gave one process.
pub const MAX_MEMORY_BYTES: u64 = 4 << 30;

/// Reads a whole input file, refusing one larger than `limit` bytes (checked while reading
/// too, so that a file that grows or a device that never ends cannot exhaust memory).
pub fn read_input(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let name = path.display();
    let file = std::fs::File::open(path).map_err(|e| format!("{name}: {e}"))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("{name}: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "{name}: larger than the {limit}-byte limit for this input"
        ));
    }
    Ok(bytes)
}

/// `--ext`, for the commands that assemble, disassemble or run SPU code.
#[derive(clap::Args, Clone, Copy, Debug)]
pub struct ExtOption {
    /// ISA extensions the paper proposes (docs/extensions.md), comma-separated:
    /// multihint[=N] (a branch target buffer of N hint entries, 1 to 8; 4 without N),
    /// gather (the gather loads lgw, lgwx), none.
    #[arg(long = "ext", value_name = "LIST", default_value = "none", value_parser = extensions)]
    pub ext: spu_isa::Extensions,
}

fn extensions(text: &str) -> Result<spu_isa::Extensions, String> {
    spu_isa::Extensions::parse(text)
}

/// `--compile`, for the commands that run SPUs.
#[derive(clap::Args)]
pub struct CompileOption {
    /// When the block compiler compiles a block that turned hot: on a host thread of its
    /// own while the SPU goes on interpreting the block (background) or at once while the
    /// SPU waits (inline: the share of instructions run compiled is then the same at
    /// every run). Results are the same either way.
    #[arg(long, default_value_t = spu_isa::jit::Compiling::Background)]
    pub compile: spu_isa::jit::Compiling,
}

impl CompileOption {
    /// A code cache compiling this way, for the SPUs of one command to share.
    pub fn cache(&self) -> spu_isa::jit::CodeCache {
        spu_isa::jit::CodeCache::with(self.compile)
    }
}

/// `--max-cycles`: at least 1.
pub fn max_cycles(cycles: u64) -> exit::Result<()> {
    if cycles == 0 {
        return Err(Error::input("--max-cycles 0: must be at least 1"));
    }
    Ok(())
}

/// `--memory`: 16 bytes to 4 GiB, a multiple of 16 (DMA moves quadwords); returned as the
/// host size.
pub fn memory(bytes: u64) -> exit::Result<usize> {
    if !(16..=MAX_MEMORY_BYTES).contains(&bytes) || !bytes.is_multiple_of(16) {
        return Err(Error::input(format!(
            "--memory {bytes}: must be a multiple of 16 from 16 to {MAX_MEMORY_BYTES} (4 GiB)"
        )));
    }
    usize::try_from(bytes)
        .map_err(|_| Error::input(format!("--memory {bytes}: too large for this host")))
}

/// `--clock` in GHz: finite, 0.01 to 100 (the Cell ran at 2.4 to 3.2).
pub fn clock_ghz(ghz: f64) -> exit::Result<()> {
    if !(ghz.is_finite() && (0.01..=100.0).contains(&ghz)) {
        return Err(Error::input(format!(
            "--clock {ghz}: must be a number of GHz from 0.01 to 100"
        )));
    }
    Ok(())
}

/// A count option that must lie in `range`.
pub fn count<T: PartialOrd + std::fmt::Display + Copy>(
    name: &str,
    value: T,
    range: std::ops::RangeInclusive<T>,
) -> exit::Result<()> {
    if !range.contains(&value) {
        return Err(Error::input(format!(
            "{name} {value}: must be {} to {}",
            range.start(),
            range.end()
        )));
    }
    Ok(())
}
