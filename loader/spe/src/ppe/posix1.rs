//! The POSIX.1 class (stop 0x2101): libspe2's `default_posix1_handler` opcodes, file
//! descriptors on the PPE. Descriptors are the host's own table, not host descriptors: 0,
//! 1, 2 are the host's standard streams, and `open` hands out the lowest free number up
//! to [`MAX_FDS`], each a host file the sandbox allowed. Flags and errno values are
//! Linux's, as newlib's SPU stubs pass them.

use super::{errno, io_errno, Args, Fault, Host, Reply, Writes};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};

/// libspe2's POSIX.1 opcodes (`SPE_POSIX1_*`), by number.
pub const OPCODES: &[&str] = &[
    "unused",
    "adjtimex",
    "close",
    "creat",
    "fstat",
    "ftok",
    "getpagesize",
    "gettimeofday",
    "kill",
    "lseek",
    "lstat",
    "mmap",
    "mremap",
    "msync",
    "munmap",
    "open",
    "read",
    "shmat",
    "shmctl",
    "shmdt",
    "shmget",
    "shm_open",
    "shm_unlink",
    "stat",
    "unlink",
    "wait",
    "waitpid",
    "write",
    "ftruncate",
    "access",
    "dup",
    "time",
    "nanosleep",
    "chdir",
    "fchdir",
    "mkdir",
    "mknod",
    "rmdir",
    "chmod",
    "fchmod",
    "chown",
    "fchown",
    "lchown",
    "getcwd",
    "link",
    "symlink",
    "readlink",
    "sync",
    "fsync",
    "fdatasync",
    "dup2",
    "lockf",
    "truncate",
    "mkstemp",
    "mktemp",
    "opendir",
    "closedir",
    "readdir",
    "rewinddir",
    "seekdir",
    "telldir",
    "sched_yield",
    "umask",
    "utime",
    "utimes",
    "pread",
    "pwrite",
    "readv",
    "writev",
];

/// The most descriptors a program holds at once (`open` fails with EMFILE beyond).
pub const MAX_FDS: u32 = 256;

/// Linux's open flags, as the SPU passes them.
const O_ACCMODE: u32 = 3;
const O_CREAT: u32 = 0o100;
const O_EXCL: u32 = 0o200;
const O_TRUNC: u32 = 0o1000;
const O_APPEND: u32 = 0o2000;

enum Fd {
    Stdin,
    Stdout,
    Stderr,
    File(File),
}

/// A program's descriptors.
pub struct Fds {
    table: BTreeMap<u32, Fd>,
}

impl Default for Fds {
    fn default() -> Self {
        Self::new()
    }
}

impl Fds {
    pub fn new() -> Fds {
        let mut table = BTreeMap::new();
        table.insert(0, Fd::Stdin);
        table.insert(1, Fd::Stdout);
        table.insert(2, Fd::Stderr);
        Fds { table }
    }

    fn lowest_free(&self) -> Result<u32, i32> {
        (0..MAX_FDS)
            .find(|n| !self.table.contains_key(n))
            .ok_or(errno::EMFILE)
    }

    fn get(&mut self, fd: u32) -> Result<&mut Fd, i32> {
        self.table.get_mut(&fd).ok_or(errno::EBADF)
    }

    fn dup_of(&mut self, fd: u32) -> Result<Fd, i32> {
        Ok(match self.get(fd)? {
            Fd::Stdin => Fd::Stdin,
            Fd::Stdout => Fd::Stdout,
            Fd::Stderr => Fd::Stderr,
            Fd::File(f) => Fd::File(f.try_clone().map_err(|e| io_errno(&e))?),
        })
    }

    /// How many descriptors are open.
    pub fn open_count(&self) -> usize {
        self.table.len()
    }
}

/// `struct stat` as the SPU's newlib receives it: 13 big-endian words.
fn stat_bytes(m: &std::fs::Metadata) -> Vec<u8> {
    let words = [
        m.dev() as u32,
        m.ino() as u32,
        m.mode(),
        m.nlink() as u32,
        m.uid(),
        m.gid(),
        m.rdev() as u32,
        m.size() as u32,
        m.blksize() as u32,
        m.blocks() as u32,
        m.atime() as u32,
        m.mtime() as u32,
        m.ctime() as u32,
    ];
    words.iter().flat_map(|w| w.to_be_bytes()).collect()
}

/// The metadata of a standard stream: a character device, as a terminal or pipe shows.
fn std_stat() -> Vec<u8> {
    let mut words = [0u32; 13];
    words[2] = 0o20620;
    words[3] = 1;
    words[8] = 1024;
    words.iter().flat_map(|w| w.to_be_bytes()).collect()
}

fn reply<T>(r: Result<T, i32>, ok: impl FnOnce(T) -> u32) -> Reply {
    match r {
        Ok(v) => Reply::ok(ok(v)),
        Err(e) => Reply::err(e),
    }
}

/// The simulated clock's rate: the Cell's SPU clock, 3.2 GHz.
pub const CLOCK_HZ: u64 = 3_200_000_000;

/// The simulated wall clock a program sees through `time` and `gettimeofday`: 1970-01-01
/// 00:00:00 UTC (the Unix epoch, time 0) when the program was loaded, plus the SPU's
/// elapsed cycles at [`CLOCK_HZ`]. Never the host's clock, so a program's output is the
/// same on every run and every engine. Returns (seconds, microseconds).
pub fn simulated_time(cycles: u64) -> (u32, u32) {
    let secs = cycles / CLOCK_HZ;
    let micros = (cycles % CLOCK_HZ) / (CLOCK_HZ / 1_000_000);
    (secs as u32, micros as u32)
}

/// Serves POSIX.1 opcode `op`.
pub fn call(host: &mut Host, op: u32, a: &Args, w: &mut Writes) -> Result<Option<Reply>, Fault> {
    let fds = &mut host.posix1;
    let name = OPCODES.get(op as usize).copied().unwrap_or("unknown");
    let r = match op {
        // close
        2 => reply(fds.get(a.word(0)?).map(|_| ()), |_| 0).and_then_remove(fds, a.word(0)?),
        // creat(path, mode), open(path, flags, mode)
        3 | 15 => {
            let path = a.ls.cstr(a.word(0)?, "the path to open")?;
            let (flags, mode) = if op == 3 {
                (O_CREAT | 1 | O_TRUNC, a.word(1)?)
            } else {
                (a.word(1)?, a.word(2)?)
            };
            let r = fds.lowest_free().and_then(|fd| {
                let p = host.sandbox.resolve(&path)?;
                let mut o = std::fs::OpenOptions::new();
                match flags & O_ACCMODE {
                    0 => o.read(true),
                    1 => o.write(true),
                    2 => o.read(true).write(true),
                    _ => return Err(errno::EINVAL),
                };
                if flags & O_APPEND != 0 {
                    o.append(true);
                }
                if flags & O_CREAT != 0 {
                    if flags & O_EXCL != 0 {
                        o.create_new(true);
                    } else {
                        o.create(true);
                    }
                }
                if flags & O_TRUNC != 0 {
                    o.truncate(true);
                }
                o.mode(mode & 0o777);
                let f = o.open(p).map_err(|e| io_errno(&e))?;
                fds.table.insert(fd, Fd::File(f));
                Ok(fd)
            });
            reply(r, |fd| fd)
        }
        // fstat(fd, buf)
        4 => {
            let buf = a.word(1)?;
            super::check(buf, 52, "fstat's buffer")?;
            let r = fds.get(a.word(0)?).and_then(|fd| match fd {
                Fd::File(f) => f
                    .metadata()
                    .map(|m| stat_bytes(&m))
                    .map_err(|e| io_errno(&e)),
                _ => Ok(std_stat()),
            });
            reply(r.map(|b| w.push((buf, b))), |_| 0)
        }
        // gettimeofday(tv, tz)
        7 => {
            let tv = a.word(0)?;
            if tv != 0 {
                super::check(tv, 8, "gettimeofday's timeval")?;
                let (secs, micros) = simulated_time(a.cycles);
                let mut b = secs.to_be_bytes().to_vec();
                b.extend_from_slice(&micros.to_be_bytes());
                w.push((tv, b));
            }
            Reply::ok(0)
        }
        // lseek(fd, offset, whence)
        9 => {
            let (off, whence) = (a.word(1)? as i32 as i64, a.word(2)?);
            let r = fds.get(a.word(0)?).and_then(|fd| {
                let Fd::File(f) = fd else {
                    return Err(errno::ESPIPE);
                };
                let pos = match whence {
                    0 if off >= 0 => SeekFrom::Start(off as u64),
                    1 => SeekFrom::Current(off),
                    2 => SeekFrom::End(off),
                    _ => return Err(errno::EINVAL),
                };
                let p = f.seek(pos).map_err(|e| io_errno(&e))?;
                u32::try_from(p)
                    .ok()
                    .filter(|p| *p <= i32::MAX as u32)
                    .ok_or(errno::EOVERFLOW)
            });
            reply(r, |p| p)
        }
        // lstat, stat(path, buf)
        10 | 23 => {
            let path = a.ls.cstr(a.word(0)?, "the path to stat")?;
            let buf = a.word(1)?;
            super::check(buf, 52, "stat's buffer")?;
            let r = host.sandbox.resolve(&path).and_then(|p| {
                std::fs::metadata(p)
                    .map(|m| stat_bytes(&m))
                    .map_err(|e| io_errno(&e))
            });
            reply(r.map(|b| w.push((buf, b))), |_| 0)
        }
        // read(fd, buf, count), write(fd, buf, count)
        16 | 27 => {
            let (buf, count) = (a.word(1)?, a.word(2)?);
            let what = if op == 16 {
                "read's buffer"
            } else {
                "write's buffer"
            };
            super::check(buf, count as u64, what)?;
            let r = fds.get(a.word(0)?).and_then(|fd| {
                if op == 16 {
                    let mut data = vec![0u8; count as usize];
                    let n = match fd {
                        Fd::Stdin => std::io::stdin().read(&mut data),
                        Fd::File(f) => f.read(&mut data),
                        _ => return Err(errno::EBADF),
                    }
                    .map_err(|e| io_errno(&e))?;
                    data.truncate(n);
                    w.push((buf, data));
                    Ok(n as u32)
                } else {
                    let data =
                        a.ls.slice(buf, count as u64, what)
                            .map_err(|_| errno::EINVAL)?;
                    match fd {
                        Fd::Stdout => std::io::stdout().write_all(data),
                        Fd::Stderr => {
                            let _ = std::io::stdout().flush();
                            std::io::stderr().write_all(data)
                        }
                        Fd::File(f) => f.write_all(data),
                        Fd::Stdin => return Err(errno::EBADF),
                    }
                    .map_err(|e| io_errno(&e))?;
                    Ok(count)
                }
            });
            reply(r, |n| n)
        }
        // unlink
        24 => {
            let path = a.ls.cstr(a.word(0)?, "the path to unlink")?;
            let r = host
                .sandbox
                .resolve(&path)
                .and_then(|p| std::fs::remove_file(p).map_err(|e| io_errno(&e)));
            reply(r, |_| 0)
        }
        // ftruncate(fd, length)
        28 => {
            let len = a.word(1)? as i32;
            let r = fds.get(a.word(0)?).and_then(|fd| match fd {
                Fd::File(f) if len >= 0 => f.set_len(len as u64).map_err(|e| io_errno(&e)),
                Fd::File(_) => Err(errno::EINVAL),
                _ => Err(errno::EINVAL),
            });
            reply(r, |_| 0)
        }
        // access(path, mode): whether it exists inside the sandbox.
        29 => {
            let path = a.ls.cstr(a.word(0)?, "the path to access")?;
            let r = host
                .sandbox
                .resolve(&path)
                .and_then(|p| std::fs::metadata(p).map(|_| ()).map_err(|e| io_errno(&e)));
            reply(r, |_| 0)
        }
        // dup(fd)
        30 => {
            let old = a.word(0)?;
            let r = fds.lowest_free().and_then(|n| {
                let d = fds.dup_of(old)?;
                fds.table.insert(n, d);
                Ok(n)
            });
            reply(r, |n| n)
        }
        // time(t)
        31 => {
            let t = a.word(0)?;
            let secs = simulated_time(a.cycles).0;
            if t != 0 {
                super::check(t, 4, "time's result")?;
                w.push((t, secs.to_be_bytes().to_vec()));
            }
            Reply::ok(secs)
        }
        // dup2(old, new)
        50 => {
            let (old, new) = (a.word(0)?, a.word(1)?);
            let r = if new >= MAX_FDS {
                Err(errno::EBADF)
            } else if old == new {
                fds.get(old).map(|_| new)
            } else {
                fds.dup_of(old).map(|d| {
                    fds.table.insert(new, d);
                    new
                })
            };
            reply(r, |n| n)
        }
        _ => {
            return Err(Fault(format!(
                "stop 0x2101: POSIX.1 opcode {op} ({name}) is not served by this host"
            )))
        }
    };
    Ok(Some(r))
}

trait CloseExt {
    fn and_then_remove(self, fds: &mut Fds, fd: u32) -> Reply;
}

impl CloseExt for Reply {
    /// `close`: the descriptor goes once it was found.
    fn and_then_remove(self, fds: &mut Fds, fd: u32) -> Reply {
        if self.errno == 0 {
            fds.table.remove(&fd);
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_simulated_clock_counts_cycles_at_3_2_ghz_from_the_epoch() {
        assert_eq!(simulated_time(0), (0, 0));
        assert_eq!(simulated_time(3199), (0, 0));
        assert_eq!(simulated_time(3200), (0, 1));
        assert_eq!(simulated_time(5 * CLOCK_HZ + 7 * 3200 + 3199), (5, 7));
        assert_eq!(simulated_time(2 * CLOCK_HZ - 1), (1, 999_999));
    }
}
