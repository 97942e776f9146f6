//! The PPE side of a single SPU program run from the command line, as libspe2 and the
//! SDK's `elfspe` were on the Cell: the state a program starts in ([`start`]) and, when it
//! stops with a code in 0x2100..0x21ff, the PPE-assisted library calls it asks for.
//!
//! The protocol is libspe2's: the stop code's low byte names the class (0 = C99 stdio,
//! `c99.rs`; 1 = POSIX.1, `posix1.rs`); the word after the `stop` holds the opcode in its top
//! byte and the local-store address of the argument block in its low 24 bits. The block
//! holds one argument per 16-byte quadword (the value in the preferred slot); the host
//! writes the result over the first quadword as {return value, 0, 0, errno} and resumes
//! the SPU after the data word. Every pointer and length a program hands over is checked
//! against local store first: a bad one, an unknown class or opcode, or `%n` stops the
//! program with a [`Fault`] (`spu run` exits 134).

pub(crate) mod c99;
pub mod errno;
pub(crate) mod format;
pub(crate) mod posix1;
pub(crate) mod sandbox;
pub(crate) mod scan;
pub mod start;

use spu_isa::machine::Spu;
use start::LS_SIZE;
use std::io::Write;
use std::path::Path;

/// The stop codes of PPE-assisted calls (`SPE_PROGRAM_LIBRARY_CALL`).
pub const CALL_STOPS: std::ops::RangeInclusive<u16> = 0x2100..=0x21ff;
/// The C99 class's stop code (`SPE_C99_CLASS`).
pub const C99_CLASS: u16 = 0x2100;
/// The POSIX.1 class's stop code (`SPE_POSIX1_CLASS`).
pub const POSIX1_CLASS: u16 = 0x2101;

/// Why a call stopped the program instead of returning to it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fault(pub String);

impl std::fmt::Display for Fault {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// Local store as a call's handler reads it: every access checked.
pub(crate) struct Ls<'a> {
    bytes: &'a [u8],
}

impl<'a> Ls<'a> {
    pub fn new(bytes: &'a [u8]) -> Ls<'a> {
        Ls { bytes }
    }

    /// `len` bytes at `addr`, which must lie inside local store.
    pub fn slice(&self, addr: u32, len: u64, what: &str) -> Result<&'a [u8], Fault> {
        check(addr, len, what)?;
        Ok(&self.bytes[addr as usize..addr as usize + len as usize])
    }

    pub fn quad(&self, addr: u32, what: &str) -> Result<[u8; 16], Fault> {
        Ok(self.slice(addr, 16, what)?.try_into().unwrap())
    }

    /// The NUL-terminated string at `addr` (without the NUL).
    pub fn cstr(&self, addr: u32, what: &str) -> Result<Vec<u8>, Fault> {
        self.cstr_max(addr, None, what)
    }

    /// The string at `addr`, at most `max` bytes of it (then no NUL is needed).
    pub fn cstr_max(&self, addr: u32, max: Option<usize>, what: &str) -> Result<Vec<u8>, Fault> {
        if addr == 0 {
            return Err(Fault(format!("{what}: a null pointer")));
        }
        check(addr, 1, what)?;
        let rest = &self.bytes[addr as usize..];
        let limit = max.unwrap_or(usize::MAX);
        match rest.iter().take(limit).position(|&b| b == 0) {
            Some(n) => Ok(rest[..n].to_vec()),
            None if rest.len() >= limit => Ok(rest[..limit].to_vec()),
            None => Err(Fault(format!(
                "{what} at {addr:#x} runs past the end of local store without a NUL"
            ))),
        }
    }
}

/// Checks that `[addr, addr + len)` lies inside local store.
pub(crate) fn check(addr: u32, len: u64, what: &str) -> Result<(), Fault> {
    if addr as u64 + len > LS_SIZE as u64 {
        return Err(Fault(format!(
            "{what}: {len} bytes at {addr:#x} lie outside local store (0..{LS_SIZE:#x})"
        )));
    }
    Ok(())
}

/// One call's arguments: quadword `n` of the block at `base`.
pub(crate) struct Args<'a> {
    pub ls: Ls<'a>,
    pub base: u32,
    /// The SPU's clock when it stopped (the simulated time `time` and friends answer).
    pub cycles: u64,
}

impl Args<'_> {
    /// Argument `n`'s preferred-slot word.
    pub fn word(&self, n: u32) -> Result<u32, Fault> {
        let q = self
            .ls
            .quad(self.base + 16 * n, "the call's argument block")?;
        Ok(u32::from_be_bytes([q[0], q[1], q[2], q[3]]))
    }
}

/// A call's outcome: the return value and errno written back to the program.
pub(crate) struct Reply {
    pub rc: u32,
    pub errno: i32,
}

impl Reply {
    pub fn ok(rc: u32) -> Reply {
        Reply { rc, errno: 0 }
    }
    /// -1 with `errno`.
    pub fn err(errno: i32) -> Reply {
        Reply {
            rc: u32::MAX,
            errno,
        }
    }
}

/// A local-store write a handler asks for (made after the handler returns).
pub(crate) type Writes = Vec<(u32, Vec<u8>)>;

/// The host's side of every call: the sandbox and the open streams and descriptors.
pub(crate) struct Host {
    pub sandbox: sandbox::Sandbox,
    pub c99: c99::Streams,
    pub posix1: posix1::Fds,
}

impl Host {
    /// A host whose programs may open files only under `root`.
    pub fn new(root: Option<&Path>) -> Result<Host, String> {
        Ok(Host {
            sandbox: sandbox::Sandbox::new(root)?,
            c99: c99::Streams::new(),
            posix1: posix1::Fds::new(),
        })
    }

    /// Serves the call an SPU stopped on with `code` (in [`CALL_STOPS`]; its pc at the
    /// data word) and sets it to resume after the data word.
    pub fn serve(&mut self, spu: &mut Spu, code: u16) -> Result<(), Fault> {
        let pc = spu.pc();
        let ls = Ls::new(spu.ls());
        let data = ls.slice(pc, 4, "the call's data word")?;
        let data = u32::from_be_bytes(data.try_into().unwrap());
        let op = data >> 24;
        let base = data & 0xff_ffff;
        let args = Args {
            ls,
            base,
            cycles: spu.cycles(),
        };
        let mut writes = Writes::new();
        let reply = match code {
            C99_CLASS => c99::call(self, op, &args, &mut writes)?,
            POSIX1_CLASS => posix1::call(self, op, &args, &mut writes)?,
            _ => {
                return Err(Fault(format!(
                    "stop {code:#x}: PPE-assisted call class {} (opcode {op}) is not one this \
                     host serves (0 = C99, 1 = POSIX.1)",
                    code & 0xff
                )))
            }
        };
        // Flushed after each call, so the program's output and the host's interleave as
        // they were made.
        let _ = std::io::stdout().flush();
        for (addr, bytes) in writes {
            spu.write_ls(addr, &bytes);
        }
        if let Some(reply) = reply {
            let mut q = [0u8; 16];
            q[..4].copy_from_slice(&reply.rc.to_be_bytes());
            q[12..].copy_from_slice(&(reply.errno as u32).to_be_bytes());
            check(base, 16, "the call's argument block")?;
            spu.write_ls(base, &q);
        }
        spu.set_pc(pc + 4);
        Ok(())
    }
}

/// The errno of a host I/O error, as the SPU's newlib numbers it (Linux's numbers).
pub(crate) fn io_errno(e: &std::io::Error) -> i32 {
    e.raw_os_error().unwrap_or(errno::EIO)
}
