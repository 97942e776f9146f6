//! Exit statuses of `spu`: one scheme for every command (README, "Exit status"), and the
//! error type that carries a status and its message up to `main`, so that a script can tell
//! bad input from a failed write, a simulated SPU that stopped abnormally from one that ran
//! out of cycles, and a validation that found differences.

use spu_isa::machine::StopReason;
use std::fmt;
use std::io;
use std::path::Path;
use std::process::ExitCode;

/// The documented statuses (`spu run` also exits with a program's own exit code).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    Success = 0,
    /// An output could not be written, or another runtime failure.
    Failure = 1,
    /// Bad usage or bad input (clap's own usage errors are 2 as well).
    BadInput = 2,
    /// Validation found differences.
    Differences = 3,
    /// A cycle limit was reached (124, as `timeout` exits).
    CycleLimit = 124,
    /// A simulated SPU stopped abnormally: illegal instruction, DMA error, deadlock,
    /// invalid channel, halt (134, as a process killed by SIGABRT appears to a shell).
    AbnormalStop = 134,
    /// Interrupted (SIGINT, control-C) before the end: no output was left half-written
    /// (130, as a process killed by SIGINT appears to a shell).
    Interrupted = 130,
}

impl From<Status> for ExitCode {
    fn from(status: Status) -> ExitCode {
        ExitCode::from(status as u8)
    }
}

impl Status {
    /// How a simulated SPU's stop ends a command that does not pass a program's exit code
    /// on: any `stop` is a normal end.
    pub fn of_stop(stop: &StopReason) -> Status {
        match stop {
            StopReason::Stop(_) => Status::Success,
            StopReason::CycleLimit => Status::CycleLimit,
            _ => Status::AbnormalStop,
        }
    }
}

/// The exit code of a program that stopped with `stop 0x2000|n` (n < 256): n, as the Cell
/// SDK's `elfspe` exits; `None` for any other stop.
pub fn program_exit_code(stop: &StopReason) -> Option<u8> {
    match stop {
        StopReason::Stop(code) if code & 0xff00 == 0x2000 => Some((code & 0xff) as u8),
        _ => None,
    }
}

/// A command's failure: its exit status and what to say on standard error (`None`: end
/// quietly, as after a closed pipe).
#[derive(Debug)]
pub struct Error {
    pub status: Status,
    pub message: Option<String>,
}

pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    pub fn new(status: Status, message: impl Into<String>) -> Error {
        Error {
            status,
            message: Some(message.into()),
        }
    }

    /// Bad usage or bad input (status 2).
    pub fn input(message: impl Into<String>) -> Error {
        Error::new(Status::BadInput, message)
    }

    /// A runtime failure (status 1).
    pub fn failure(message: impl Into<String>) -> Error {
        Error::new(Status::Failure, message)
    }

    /// An output file whose writing failed part-way, a full device say (status 1). One
    /// that cannot be written at all is bad input found before the work starts (status 2,
    /// [`check_writable`]).
    pub fn output(path: &Path, err: impl fmt::Display) -> Error {
        Error::failure(format!("{}: {err}", path.display()))
    }

    /// A write to standard output that failed: quiet when the reader has gone (a closed
    /// pipe, as `spu dis x | head` leaves it), status 1 either way.
    pub fn stdout(err: io::Error) -> Error {
        if err.kind() == io::ErrorKind::BrokenPipe {
            Error {
                status: Status::Failure,
                message: None,
            }
        } else {
            Error::failure(format!("standard output: {err}"))
        }
    }
}

/// Plain messages are bad input: that is what most of the library's `Err(String)`s are
/// (unreadable or malformed files, rejected options). Failures of another kind say so with
/// the constructors above.
impl From<String> for Error {
    fn from(message: String) -> Error {
        Error::input(message)
    }
}

impl From<&str> for Error {
    fn from(message: &str) -> Error {
        Error::input(message)
    }
}

/// Writes to standard output, returning [`Error::stdout`] from the enclosing function if
/// the write fails (a closed pipe ends the command quietly instead of panicking as
/// `println!` does).
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*).map_err($crate::exit::Error::stdout)?
    }};
}

/// [`outln!`] without the newline.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*).map_err($crate::exit::Error::stdout)?
    }};
}

/// Writes `bytes` to `path` whole or not at all: into a temporary file in the same
/// directory, renamed over `path` once complete, so a failure never leaves a partial or
/// empty output behind. A symbolic link is written through, to the file it names, as
/// writing into it in place would.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    write_file_with(path, |file| {
        use std::io::Write as _;
        file.write_all(bytes)
    })
}

/// [`write_file`] for a writer that produces the contents itself.
pub fn write_file_with(
    path: &Path,
    produce: impl FnOnce(&mut std::fs::File) -> io::Result<()>,
) -> Result<()> {
    use std::io::Write as _;
    if is_special(path) {
        // A device or a pipe (`-o /dev/stdout`): written in place, never replaced.
        let result = std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .and_then(|mut file| produce(&mut file).and_then(|_| file.flush()));
        return result.map_err(|e| Error::output(path, e));
    }
    let target = crate::outputs::resolve_links(path);
    let tmp = temp_path(&target);
    let result = (|| {
        let mut file = create_temporary(&tmp)?;
        produce(&mut file)?;
        file.flush()?;
        drop(file);
        std::fs::rename(&tmp, &target)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    forget_temporary(&tmp);
    result.map_err(|e| Error::output(path, e))
}

/// The temporary files being written ([`write_file_with`], [`check_writable`]): what an
/// interrupt removes before the command ends.
static TEMPORARIES: std::sync::Mutex<Vec<std::path::PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Creates the temporary file `tmp` and notes it, both under the lock an interrupt takes,
/// so that an interrupt either comes before the file exists or finds it noted.
fn create_temporary(tmp: &Path) -> io::Result<std::fs::File> {
    let mut temporaries = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
    let file = std::fs::File::create(tmp)?;
    temporaries.push(tmp.to_path_buf());
    Ok(file)
}

/// `tmp` is gone (renamed into place or removed): no more an interrupt's to remove.
fn forget_temporary(tmp: &Path) {
    let mut temporaries = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
    temporaries.retain(|noted| noted != tmp);
}

/// Removes the temporary files being written, and keeps the lock (returned) so that no
/// other is created until the process ends.
fn remove_temporaries() -> std::sync::MutexGuard<'static, Vec<std::path::PathBuf>> {
    let temporaries = TEMPORARIES.lock().unwrap_or_else(|e| e.into_inner());
    remove_each(&temporaries);
    temporaries
}

fn remove_each(temporaries: &[std::path::PathBuf]) {
    for tmp in temporaries {
        let _ = std::fs::remove_file(tmp);
    }
}

/// Makes SIGINT (control-C) end the command with [`Status::Interrupted`] after removing
/// the temporary files of outputs being written: an interrupted command leaves each output
/// as it was before, never half-written. Outputs are only ever written whole through a
/// temporary file and a rename, so this is the only file an interrupt could leave behind.
pub fn on_interrupt_remove_temporaries() {
    // Without the handler (a host that refuses one) SIGINT ends the process as before.
    let _ = ctrlc::set_handler(|| {
        let _held = remove_temporaries();
        eprintln!("spu: interrupted");
        std::process::exit(Status::Interrupted as i32);
    });
}

/// Checks before the work starts that `path` can be written: its directory exists and
/// accepts a new file, and `path` is not a directory.
pub fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::input(format!("{}: is a directory", path.display())));
    }
    if is_special(path) {
        return Ok(());
    }
    let tmp = temp_path(&crate::outputs::resolve_links(path));
    match create_temporary(&tmp) {
        Ok(_) => {
            let _ = std::fs::remove_file(&tmp);
            forget_temporary(&tmp);
            Ok(())
        }
        Err(e) => Err(Error::input(format!(
            "{}: cannot write: {e}",
            path.display()
        ))),
    }
}

/// An existing path that is not a regular file (a device, a pipe).
fn is_special(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

fn temp_path(path: &Path) -> std::path::PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interrupt_removes_the_temporary_files_being_written() {
        let dir = std::env::temp_dir().join(format!("spu-exit-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (writing, written) = (dir.join("writing.png"), dir.join("written.png"));
        let writing_tmp = temp_path(&writing);
        let file = create_temporary(&writing_tmp).unwrap();
        write_file(&written, b"whole").unwrap();
        assert!(writing_tmp.is_file());
        // the handler removes every noted file; other tests write too, so only this
        // test's are removed here
        let noted: Vec<_> = TEMPORARIES
            .lock()
            .unwrap()
            .iter()
            .filter(|p| p.starts_with(&dir))
            .cloned()
            .collect();
        assert_eq!(
            noted,
            vec![writing_tmp.clone()],
            "the written one is forgotten"
        );
        remove_each(&noted);
        drop(file);
        assert!(
            !writing_tmp.exists(),
            "the temporary being written is removed"
        );
        assert_eq!(
            std::fs::read(&written).unwrap(),
            b"whole",
            "a finished output stays"
        );
        let left: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(left, vec![std::ffi::OsString::from("written.png")]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
