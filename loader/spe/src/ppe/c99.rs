//! The C99 class (stop 0x2100): libspe2's `default_c99_handler` opcodes, stdio on the
//! PPE. Streams are small numbers on the SPU: 1, 2, 3 are stdin, stdout and stderr, and
//! `fopen` hands out 4..16 (libspe2's `SPE_FOPEN_MAX` of 17), each a host file the
//! sandbox allowed. Reads and writes go straight to the host (no buffering on either
//! side), so output interleaves in the order the program made it.

use super::format::{self, FormatError, VaList};
use super::{errno, io_errno, scan, Args, Fault, Host, Reply, Writes};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom, Write};

/// libspe2's C99 opcodes (`SPE_C99_*`), by number.
pub const OPCODES: &[&str] = &[
    "unused",
    "clearerr",
    "fclose",
    "feof",
    "ferror",
    "fflush",
    "fgetc",
    "fgetpos",
    "fgets",
    "fileno",
    "fopen",
    "fputc",
    "fputs",
    "fread",
    "freopen",
    "fseek",
    "fsetpos",
    "ftell",
    "fwrite",
    "getc",
    "getchar",
    "gets",
    "perror",
    "putc",
    "putchar",
    "puts",
    "remove",
    "rename",
    "rewind",
    "setbuf",
    "setvbuf",
    "system",
    "tmpfile",
    "tmpnam",
    "ungetc",
    "vfprintf",
    "vfscanf",
    "vprintf",
    "vscanf",
    "vsnprintf",
    "vsprintf",
    "vsscanf",
];

/// One past the largest stream number (`SPE_FOPEN_MAX`).
pub const FOPEN_MAX: u32 = 17;
/// The first stream `fopen` hands out.
const FOPEN_MIN: u32 = 4;

enum Kind {
    Stdin,
    Stdout,
    Stderr,
    File(File),
}

struct Stream {
    kind: Kind,
    eof: bool,
    error: bool,
    /// Bytes pushed back by `ungetc`, the next one last.
    unget: Vec<u8>,
}

impl Stream {
    fn new(kind: Kind) -> Stream {
        Stream {
            kind,
            eof: false,
            error: false,
            unget: Vec::new(),
        }
    }

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), i32> {
        let r = match &mut self.kind {
            Kind::Stdin => return Err(errno::EBADF),
            Kind::Stdout => std::io::stdout().write_all(bytes),
            Kind::Stderr => {
                let _ = std::io::stdout().flush();
                std::io::stderr().write_all(bytes)
            }
            Kind::File(f) => f.write_all(bytes),
        };
        r.map_err(|e| {
            self.error = true;
            io_errno(&e)
        })
    }

    /// Reads up to `buf.len()` bytes (fewer only at the end of the input).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, i32> {
        let mut n = 0;
        while n < buf.len() {
            if let Some(b) = self.unget.pop() {
                buf[n] = b;
                n += 1;
                continue;
            }
            let r = match &mut self.kind {
                Kind::Stdin => std::io::stdin().read(&mut buf[n..]),
                Kind::File(f) => f.read(&mut buf[n..]),
                _ => return Err(errno::EBADF),
            };
            match r {
                Ok(0) => {
                    self.eof = true;
                    break;
                }
                Ok(k) => n += k,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => {
                    self.error = true;
                    return Err(io_errno(&e));
                }
            }
        }
        Ok(n)
    }

    fn getc(&mut self) -> Result<Option<u8>, i32> {
        let mut b = [0u8];
        Ok((self.read(&mut b)? == 1).then_some(b[0]))
    }

    fn file(&mut self) -> Result<&mut File, i32> {
        match &mut self.kind {
            Kind::File(f) => Ok(f),
            _ => Err(errno::ESPIPE),
        }
    }
}

/// The streams a program has.
pub struct Streams {
    table: Vec<Option<Stream>>,
}

impl Default for Streams {
    fn default() -> Self {
        Self::new()
    }
}

impl Streams {
    pub fn new() -> Streams {
        let mut table: Vec<Option<Stream>> = (0..FOPEN_MAX).map(|_| None).collect();
        table[1] = Some(Stream::new(Kind::Stdin));
        table[2] = Some(Stream::new(Kind::Stdout));
        table[3] = Some(Stream::new(Kind::Stderr));
        Streams { table }
    }

    fn get(&mut self, n: u32) -> Result<&mut Stream, i32> {
        self.table
            .get_mut(n as usize)
            .and_then(|s| s.as_mut())
            .ok_or(errno::EBADF)
    }

    /// How many streams `fopen` has handed out and not closed.
    pub fn open_files(&self) -> usize {
        self.table[FOPEN_MIN as usize..]
            .iter()
            .filter(|s| s.is_some())
            .count()
    }
}

/// `fopen`'s mode string as open options.
fn open_options(mode: &[u8]) -> Option<std::fs::OpenOptions> {
    let mut o = std::fs::OpenOptions::new();
    let plus = mode[1..].contains(&b'+');
    let excl = mode[1..].contains(&b'x');
    match mode.first()? {
        b'r' => o.read(true).write(plus),
        b'w' if excl => o.write(true).read(plus).create_new(true),
        b'w' => o.write(true).read(plus).create(true).truncate(true),
        b'a' => o.append(true).read(plus).create(true),
        _ => return None,
    };
    if mode[1..]
        .iter()
        .any(|c| !matches!(c, b'+' | b'b' | b'x' | b't'))
    {
        return None;
    }
    Some(o)
}

/// A Linux `strerror` text for errno `e`.
pub fn strerror(e: i32) -> String {
    let t = std::io::Error::from_raw_os_error(e).to_string();
    match t.rfind(" (os error") {
        Some(i) => t[..i].to_string(),
        None => t,
    }
}

fn eof() -> u32 {
    u32::MAX
}

/// Replies `rc` or, on an errno, `fail` with it.
fn reply<T>(r: Result<T, i32>, ok: impl FnOnce(T) -> u32, fail: u32) -> Reply {
    match r {
        Ok(v) => Reply::ok(ok(v)),
        Err(e) => Reply { rc: fail, errno: e },
    }
}

/// Formats for the printf family (`va` at argument quadword `va_at`).
fn printf(args: &Args, fmt_arg: u32, va_at: u32) -> Result<Result<Vec<u8>, i32>, Fault> {
    let fmt = args.ls.cstr(args.word(fmt_arg)?, "a printf format")?;
    let va_base = args.base + 16 * va_at;
    let w = |k: u32| -> Result<u32, Fault> {
        let q = args.ls.quad(va_base + 16 * k, "the call's va_list")?;
        Ok(u32::from_be_bytes([q[0], q[1], q[2], q[3]]))
    };
    let mut va = VaList {
        next: w(0)?,
        caller_stack: w(1)?,
    };
    match format::format(&args.ls, &fmt, &mut va) {
        Ok(t) => Ok(Ok(t)),
        Err(FormatError::Fault(f)) => Err(f),
        Err(FormatError::Overflow) => Ok(Err(errno::EOVERFLOW)),
    }
}

/// Serves C99 opcode `op`; `None`: a `void` function, nothing written back.
pub fn call(host: &mut Host, op: u32, a: &Args, w: &mut Writes) -> Result<Option<Reply>, Fault> {
    let s = &mut host.c99;
    let name = OPCODES.get(op as usize).copied().unwrap_or("unknown");
    let r = match op {
        // clearerr, rewind: void.
        1 | 28 => {
            if let Ok(st) = s.get(a.word(0)?) {
                st.eof = false;
                st.error = false;
                if op == 28 {
                    st.unget.clear();
                    if let Ok(f) = st.file() {
                        let _ = f.seek(SeekFrom::Start(0));
                    }
                }
            }
            return Ok(None);
        }
        // fclose
        2 => {
            let n = a.word(0)?;
            match s.get(n) {
                Ok(_) => {
                    s.table[n as usize] = None;
                    Reply::ok(0)
                }
                Err(e) => Reply {
                    rc: eof(),
                    errno: e,
                },
            }
        }
        3 => reply(s.get(a.word(0)?).map(|st| st.eof as u32), |v| v, 0),
        4 => reply(s.get(a.word(0)?).map(|st| st.error as u32), |v| v, 0),
        // fflush: output is never held back.
        5 => {
            let n = a.word(0)?;
            let r = if n == 0 { Ok(()) } else { s.get(n).map(|_| ()) };
            let _ = std::io::stdout().flush();
            reply(r, |_| 0, eof())
        }
        // fgetc, getc, getchar
        6 | 19 | 20 => {
            let n = if op == 20 { 1 } else { a.word(0)? };
            let r = s.get(n).and_then(|st| st.getc());
            reply(r, |c| c.map_or(eof(), |c| c as u32), eof())
        }
        // fgets
        8 => {
            let (buf, size, n) = (a.word(0)?, a.word(1)? as i32, a.word(2)?);
            if size <= 0 {
                return Ok(Some(Reply {
                    rc: 0,
                    errno: errno::EINVAL,
                }));
            }
            super::check(buf, size as u64, "fgets's buffer")?;
            let r = s.get(n).and_then(|st| {
                let mut line = Vec::new();
                while line.len() < size as usize - 1 {
                    match st.getc()? {
                        Some(c) => {
                            line.push(c);
                            if c == b'\n' {
                                break;
                            }
                        }
                        None => break,
                    }
                }
                Ok(line)
            });
            match r {
                Ok(line) if line.is_empty() => Reply::ok(0),
                Ok(mut line) => {
                    line.push(0);
                    w.push((buf, line));
                    Reply::ok(buf)
                }
                Err(e) => Reply { rc: 0, errno: e },
            }
        }
        // fileno: the standard streams' descriptors; a file's is not shared with POSIX.1.
        9 => match a.word(0)? {
            n @ 1..=3 if s.get(n).is_ok() => Reply::ok(n - 1),
            _ => Reply::err(errno::EBADF),
        },
        // fopen
        10 => {
            let path = a.ls.cstr(a.word(0)?, "fopen's path")?;
            let mode = a.ls.cstr(a.word(1)?, "fopen's mode")?;
            let Some(slot) = (FOPEN_MIN..FOPEN_MAX).find(|&i| s.table[i as usize].is_none()) else {
                return Ok(Some(Reply {
                    rc: 0,
                    errno: errno::EMFILE,
                }));
            };
            let Some(opts) = open_options(&mode) else {
                return Ok(Some(Reply {
                    rc: 0,
                    errno: errno::EINVAL,
                }));
            };
            match host.sandbox.resolve(&path) {
                Err(e) => Reply { rc: 0, errno: e },
                Ok(p) => match opts.open(p) {
                    Ok(f) => {
                        s.table[slot as usize] = Some(Stream::new(Kind::File(f)));
                        Reply::ok(slot)
                    }
                    Err(e) => Reply {
                        rc: 0,
                        errno: io_errno(&e),
                    },
                },
            }
        }
        // fputc, putc, putchar
        11 | 23 | 24 => {
            let c = a.word(0)? as u8;
            let n = if op == 24 { 2 } else { a.word(1)? };
            reply(
                s.get(n).and_then(|st| st.write_all(&[c])),
                |_| c as u32,
                eof(),
            )
        }
        // fputs, puts
        12 | 25 => {
            let mut text = a.ls.cstr(a.word(0)?, "the string to put")?;
            let n = if op == 25 { 2 } else { a.word(1)? };
            if op == 25 {
                text.push(b'\n');
            }
            let len = text.len() as u32;
            let r = s.get(n).and_then(|st| st.write_all(&text));
            reply(r, |_| if op == 25 { len } else { 1 }, eof())
        }
        // fread, fwrite
        13 | 18 => {
            let (buf, size, nmemb, n) = (a.word(0)?, a.word(1)?, a.word(2)?, a.word(3)?);
            let total = size as u64 * nmemb as u64;
            let what = if op == 13 {
                "fread's buffer"
            } else {
                "fwrite's buffer"
            };
            super::check(buf, total, what)?;
            if total == 0 {
                return Ok(Some(Reply::ok(0)));
            }
            let r = s.get(n).and_then(|st| {
                if op == 13 {
                    let mut data = vec![0u8; total as usize];
                    let got = st.read(&mut data)?;
                    data.truncate(got);
                    let items = got as u32 / size;
                    w.push((buf, data));
                    Ok(items)
                } else {
                    let data = a.ls.slice(buf, total, what).map_err(|_| errno::EINVAL)?;
                    st.write_all(data)?;
                    Ok(nmemb)
                }
            });
            reply(r, |v| v, 0)
        }
        // fseek
        15 => {
            let (n, off, whence) = (a.word(0)?, a.word(1)? as i32 as i64, a.word(2)?);
            let r = s.get(n).and_then(|st| {
                let held = st.unget.len() as i64;
                let f = st.file()?;
                let pos = match whence {
                    0 if off >= 0 => SeekFrom::Start(off as u64),
                    1 => SeekFrom::Current(off - held),
                    2 => SeekFrom::End(off),
                    _ => return Err(errno::EINVAL),
                };
                f.seek(pos).map_err(|e| io_errno(&e))?;
                st.unget.clear();
                st.eof = false;
                Ok(())
            });
            reply(r, |_| 0, u32::MAX)
        }
        // ftell
        17 => {
            let r = s.get(a.word(0)?).and_then(|st| {
                let held = st.unget.len() as u64;
                let pos = st.file()?.stream_position().map_err(|e| io_errno(&e))?;
                let pos = pos.saturating_sub(held);
                u32::try_from(pos)
                    .ok()
                    .filter(|p| *p <= i32::MAX as u32)
                    .ok_or(errno::EOVERFLOW)
            });
            reply(r, |p| p, u32::MAX)
        }
        // perror(s, errno)
        22 => {
            let p = a.word(0)?;
            let e = a.word(1)? as i32;
            let prefix = if p == 0 {
                Vec::new()
            } else {
                a.ls.cstr(p, "perror's string")?
            };
            let mut text = prefix;
            if !text.is_empty() {
                text.extend_from_slice(b": ");
            }
            text.extend_from_slice(strerror(e).as_bytes());
            text.push(b'\n');
            if let Ok(st) = s.get(3) {
                let _ = st.write_all(&text);
            }
            return Ok(None);
        }
        // remove
        26 => {
            let path = a.ls.cstr(a.word(0)?, "remove's path")?;
            let r = host.sandbox.resolve(&path).and_then(|p| {
                let r = if p.is_dir() {
                    std::fs::remove_dir(&p)
                } else {
                    std::fs::remove_file(&p)
                };
                r.map_err(|e| io_errno(&e))
            });
            reply(r, |_| 0, u32::MAX)
        }
        // rename
        27 => {
            let from = a.ls.cstr(a.word(0)?, "rename's old name")?;
            let to = a.ls.cstr(a.word(1)?, "rename's new name")?;
            let r = host.sandbox.resolve(&from).and_then(|f| {
                let t = host.sandbox.resolve(&to)?;
                std::fs::rename(f, t).map_err(|e| io_errno(&e))
            });
            reply(r, |_| 0, u32::MAX)
        }
        // setbuf: void; setvbuf: 0. Nothing is buffered here.
        29 => return Ok(None),
        30 => Reply::ok(0),
        // ungetc
        34 => {
            let c = a.word(0)? as i32;
            let r = s.get(a.word(1)?).and_then(|st| {
                if c == -1 {
                    return Err(0);
                }
                st.unget.push(c as u8);
                st.eof = false;
                Ok(c as u8 as u32)
            });
            match r {
                Ok(v) => Reply::ok(v),
                Err(e) => Reply {
                    rc: eof(),
                    errno: e,
                },
            }
        }
        // vfprintf(stream, fmt, va), vprintf(fmt, va)
        35 | 37 => {
            let (n, fmt, va) = if op == 35 {
                (a.word(0)?, 1, 2)
            } else {
                (2, 0, 1)
            };
            let text = printf(a, fmt, va)?;
            let r = text.and_then(|t| {
                let st = s.get(n)?;
                st.write_all(&t)?;
                Ok(t.len() as u32)
            });
            reply(r, |v| v, u32::MAX)
        }
        // vsnprintf(str, size, fmt, va), vsprintf(str, fmt, va)
        39 | 40 => {
            let buf = a.word(0)?;
            let (size, fmt, va) = if op == 39 {
                (Some(a.word(1)?), 2, 3)
            } else {
                (None, 1, 2)
            };
            match printf(a, fmt, va)? {
                Ok(mut t) => {
                    let len = t.len() as u32;
                    let keep = match size {
                        Some(0) => None,
                        Some(n) => Some((n as usize - 1).min(t.len())),
                        None => Some(t.len()),
                    };
                    if let Some(k) = keep {
                        t.truncate(k);
                        t.push(0);
                        super::check(buf, t.len() as u64, "the sprintf buffer")?;
                        w.push((buf, t));
                    }
                    Reply::ok(len)
                }
                Err(e) => Reply::err(e),
            }
        }
        // vfscanf(stream, fmt, va), vscanf(fmt, va), vsscanf(str, fmt, va)
        36 | 38 | 41 => {
            let (fmt_arg, va_at) = if op == 38 { (0, 1) } else { (1, 2) };
            let fmt = a.ls.cstr(a.word(fmt_arg)?, "a scanf format")?;
            let va_base = a.base + 16 * va_at;
            let word = |k: u32| -> Result<u32, Fault> {
                let q = a.ls.quad(va_base + 16 * k, "the call's va_list")?;
                Ok(u32::from_be_bytes([q[0], q[1], q[2], q[3]]))
            };
            let mut va = VaList {
                next: word(0)?,
                caller_stack: word(1)?,
            };
            if op == 41 {
                let text = a.ls.cstr(a.word(0)?, "sscanf's string")?;
                let mut bytes = text.into_iter();
                let mut next = move || bytes.next();
                let mut input = scan::Input::new(&mut next);
                let n = scan::scan(&a.ls, &fmt, &mut va, &mut input, w)?;
                Reply::ok(n as u32)
            } else {
                let n = if op == 38 { 1 } else { a.word(0)? };
                let st = match s.get(n) {
                    Ok(st) => st,
                    Err(e) => {
                        return Ok(Some(Reply {
                            rc: eof(),
                            errno: e,
                        }))
                    }
                };
                let mut failed = None;
                let (n, left) = {
                    let mut next = || match st.getc() {
                        Ok(c) => c,
                        Err(e) => {
                            failed = Some(e);
                            None
                        }
                    };
                    let mut input = scan::Input::new(&mut next);
                    let n = scan::scan(&a.ls, &fmt, &mut va, &mut input, w)?;
                    (n, input.left_over())
                };
                if let Some(c) = left {
                    st.unget.push(c);
                    st.eof = false;
                }
                Reply {
                    rc: n as u32,
                    errno: failed.unwrap_or(0),
                }
            }
        }
        _ => {
            return Err(Fault(format!(
                "stop 0x2100: C99 opcode {op} ({name}) is not served by this host"
            )))
        }
    };
    Ok(Some(r))
}
