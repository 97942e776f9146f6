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

/// Most host threads a command takes (`--threads`).
pub const MAX_THREADS: usize = 1024;

/// `--threads` of `spu render` and `spu paper`: the host threads to use and what to say
/// about them on standard error, checked before any work. `None` takes the host's `cores`.
/// 0 or more than [`MAX_THREADS`] is bad input. More than the `units` of work that can run
/// at once (`unit`: singular and plural, ("SPE", "SPEs") or ("run", "runs")) is allowed: the extra threads would idle, and the note
/// says how many do the work. More than the host's `cores` is allowed too (results never
/// depend on threads), with a note that it is likely slower than `cores`.
pub fn threads(
    requested: Option<usize>,
    units: usize,
    unit: (&str, &str),
    cores: usize,
) -> exit::Result<(usize, Vec<String>)> {
    let Some(threads) = requested else {
        return Ok((cores.max(1), Vec::new()));
    };
    if threads == 0 {
        return Err(Error::input("--threads 0: must be at least 1"));
    }
    count("--threads", threads, 1..=MAX_THREADS)?;
    let mut notes = Vec::new();
    if threads > units {
        let (unit, threads_run) = if units == 1 {
            (unit.0, "host thread runs it")
        } else {
            (unit.1, "host threads run them")
        };
        notes.push(format!(
            "--threads {threads}: only {units} {unit} to run at once, so {units} {threads_run}"
        ));
    }
    if threads > cores {
        notes.push(format!(
            "--threads {threads}: more than this host's {cores} cores; the results are the same, the run likely slower than with --threads {cores}"
        ));
    }
    Ok((threads, notes))
}

/// The host's cores (1 where it cannot tell).
pub fn host_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    const SPES: (&str, &str) = ("SPE", "SPEs");
    const RUNS: (&str, &str) = ("run", "runs");

    #[test]
    fn threads_zero_and_too_many_are_bad_input_and_extra_threads_are_said() {
        let error = threads(Some(0), 4, SPES, 2).unwrap_err();
        assert_eq!(error.status, Status::BadInput);
        assert_eq!(
            error.message.as_deref(),
            Some("--threads 0: must be at least 1")
        );
        let error = threads(Some(1025), 4, SPES, 2).unwrap_err();
        assert_eq!(
            error.message.as_deref(),
            Some("--threads 1025: must be 1 to 1024")
        );
        assert_eq!(threads(None, 4, SPES, 2).unwrap(), (2, vec![]));
        assert_eq!(threads(Some(2), 4, SPES, 2).unwrap(), (2, vec![]));
        assert_eq!(
            threads(Some(4), 1, SPES, 8).unwrap(),
            (
                4,
                vec![
                    "--threads 4: only 1 SPE to run at once, so 1 host thread runs it".to_string()
                ]
            )
        );
        assert_eq!(
            threads(Some(3), 2, RUNS, 2).unwrap(),
            (
                3,
                vec![
                    "--threads 3: only 2 runs to run at once, so 2 host threads run them".to_string(),
                    "--threads 3: more than this host's 2 cores; the results are the same, the run likely slower than with --threads 2".to_string()
                ]
            )
        );
    }
}
