//! The state a program starts in, as the Cell SDK's loader left it, so that compiled code's
//! first use of the stack through `$1` lands at the top of local store instead of on
//! address 0, and `main` finds its arguments where `elfspe` put them.
//!
//! libspe2's `spe_context_run` clears all 128 registers, sets `$1` word 0 to the top
//! quadword of local store (0x3fff0) and `$2` (the stack size; 0 = the default) to 0, and
//! passes `$3`, `$4`, `$5` = speid, argp, envp as 64-bit values in words 0-1 (`$6` holds
//! the effective address local store is mapped at). `elfspe`, the shell's way to run an
//! SPU program, instead passes its own three registers (`SPE_RUN_USER_REGS`): `$3` =
//! argc, `$4` = {LS address of the argv region, its effective address high and low, its
//! size}, `$5` = 0; the argv region (argc+1 local-store pointers, then the strings, padded
//! to 16 bytes, at most 4096 = `SPE_ARG_MAX`) sits in main memory for `crt0` to copy to
//! the top of local store. Here the region is placed in main memory as `elfspe` placed it
//! *and* already at its local-store address, and `$1` starts below it with the ABI's
//! available-stack count in word 1, so that code without a `crt0` runs as well; a `crt0`
//! that copies the region and sets `$1` again finds the same values. The layout is
//! documented in `docs/running-programs.md`.

use spu_isa::machine::{MainMemory, Spu};

/// The local store's size.
pub const LS_SIZE: u32 = 0x40000;
/// The largest argv region `elfspe` passes (its `SPE_ARG_MAX` default).
pub const ARG_MAX: usize = 4096;
/// The speid `$3` carries when a program is started through the libspe2 API
/// ([`Start::Api`]): on the Cell this was the PPE address of the context; here it is a
/// fixed, recognisable value.
pub const SPEID: u64 = 0x0000_0000_5350_4530;

/// How the program is started.
#[derive(Clone, Debug)]
pub enum Start {
    /// From a shell through `elfspe`: `main(argc, argv)`; `args[0]` is the program's name.
    Shell {
        /// The arguments, the program's name first.
        args: Vec<Vec<u8>>,
    },
    /// Through `spe_context_run(ctx, &entry, 0, argp, envp, ...)`: `main(speid, argp,
    /// envp)`.
    Api {
        /// `$4`: the argument pointer (an effective address, as a rule).
        argp: u64,
        /// `$5`: the environment pointer.
        envp: u64,
    },
}

/// The argv region `elfspe` builds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ArgvRegion {
    /// Where `crt0` copies it to: the top of local store.
    pub ls: u32,
    /// Where it lies in main memory.
    pub ea: u64,
    /// The pointers and strings.
    pub bytes: Vec<u8>,
}

/// Registers and memory at entry.
#[derive(Clone, Debug)]
pub struct Entry {
    /// Every register that is not zero at entry, in order.
    pub regs: Vec<(usize, [u32; 4])>,
    /// The argv region of a [`Start::Shell`] start.
    pub argv: Option<ArgvRegion>,
}

fn split(v: u64) -> [u32; 4] {
    [(v >> 32) as u32, v as u32, 0, 0]
}

/// Builds `elfspe`'s argv region for local-store address `LS_SIZE - size`: the pointers
/// (argc of them and a null), then each string with its NUL, zero-padded to 16 bytes.
pub fn argv_region(args: &[Vec<u8>]) -> Result<(u32, Vec<u8>), String> {
    let table = (args.len() + 1) * 4;
    let strings: usize = args.iter().map(|a| a.len() + 1).sum();
    let size = (table + strings).next_multiple_of(16);
    if size > ARG_MAX {
        return Err(format!(
            "the program's arguments take {size} bytes; elfspe passes at most {ARG_MAX} \
             (SPE_ARG_MAX)"
        ));
    }
    if let Some(a) = args.iter().find(|a| a.contains(&0)) {
        return Err(format!(
            "argument `{}` contains a NUL byte",
            String::from_utf8_lossy(a)
        ));
    }
    let ls = LS_SIZE - size as u32;
    let mut bytes = vec![0u8; size];
    let mut at = table;
    for (i, a) in args.iter().enumerate() {
        bytes[i * 4..i * 4 + 4].copy_from_slice(&(ls + at as u32).to_be_bytes());
        bytes[at..at + a.len()].copy_from_slice(a);
        at += a.len() + 1;
    }
    Ok((ls, bytes))
}

/// The entry state for a program whose code and data end at `program_end` (the stack
/// must not reach below it), run with `memory_len` bytes of main memory.
pub fn prepare(start: &Start, program_end: u32, memory_len: usize) -> Result<Entry, String> {
    let program_end = program_end.next_multiple_of(16);
    let (top, mut regs, argv) = match start {
        Start::Shell { args } => {
            let (ls, bytes) = argv_region(args)?;
            let size = bytes.len();
            if memory_len < size {
                return Err(format!(
                    "the program's arguments ({size} bytes) do not fit main memory \
                     ({memory_len} bytes)"
                ));
            }
            let ea = ((memory_len - size) & !127) as u64;
            let regs = vec![
                (3, [args.len() as u32, 0, 0, 0]),
                (4, [ls, (ea >> 32) as u32, ea as u32, size as u32]),
            ];
            (ls, regs, Some(ArgvRegion { ls, ea, bytes }))
        }
        Start::Api { argp, envp } => {
            let regs = vec![(3, split(SPEID)), (4, split(*argp)), (5, split(*envp))];
            (LS_SIZE, regs, None)
        }
    };
    let sp = top - 16;
    // The stack frame crt0 makes (32 bytes) must fit above the program.
    if sp < program_end + 32 {
        return Err(format!(
            "the program's arguments reach below {top:#x}, into the program (which ends at \
             {program_end:#x}): no room for a stack"
        ));
    }
    regs.insert(0, (1, [sp, sp - program_end, 0, 0]));
    regs.retain(|(_, r)| *r != [0; 4]);
    regs.sort_by_key(|(n, _)| *n);
    Ok(Entry { regs, argv })
}

/// Puts the entry state into a loaded SPU and its main memory.
pub fn apply(entry: &Entry, spu: &mut Spu, memory: &mut MainMemory) {
    for n in 0..128 {
        spu.set_reg(n, [0; 4]);
    }
    for (n, r) in &entry.regs {
        spu.set_reg(*n, *r);
    }
    // The back chain at $1: zero, the end of the chain.
    let sp = entry
        .regs
        .iter()
        .find(|(n, _)| *n == 1)
        .map_or(0, |(_, r)| r[0]);
    spu.write_ls(sp, &[0; 16]);
    if let Some(a) = &entry.argv {
        spu.write_ls(a.ls, &a.bytes);
        memory.write_bytes(a.ea, &a.bytes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn argv_region_is_elfspe_s_layout() {
        let (ls, bytes) = argv_region(&[b"prog".to_vec(), b"ab".to_vec()]).unwrap();
        // 3 pointers (12 bytes) + "prog\0" + "ab\0" = 20, padded to 32.
        assert_eq!(ls, 0x3ffe0);
        assert_eq!(bytes.len(), 32);
        assert_eq!(&bytes[0..4], &0x3ffecu32.to_be_bytes());
        assert_eq!(&bytes[4..8], &0x3fff1u32.to_be_bytes());
        assert_eq!(&bytes[8..12], &[0; 4]);
        assert_eq!(&bytes[12..20], b"prog\0ab\0");
        assert_eq!(&bytes[20..], &[0; 12]);
    }

    #[test]
    fn shell_start_registers() {
        let e = prepare(
            &Start::Shell {
                args: vec![b"p".to_vec()],
            },
            0x100,
            1 << 20,
        )
        .unwrap();
        // "p\0" + 2 pointers = 10 -> 16 bytes at 0x3fff0; $1 below it.
        assert_eq!(
            e.regs,
            vec![
                (1, [0x3ffe0, 0x3fee0, 0, 0]),
                (3, [1, 0, 0, 0]),
                (4, [0x3fff0, 0, 0xffff0 & !127, 16]),
            ]
        );
    }

    #[test]
    fn api_start_registers() {
        let e = prepare(
            &Start::Api {
                argp: 0x1_0000_0020,
                envp: 0,
            },
            0x1000,
            1 << 20,
        )
        .unwrap();
        assert_eq!(
            e.regs,
            vec![
                (1, [0x3fff0, 0x3eff0, 0, 0]),
                (3, [0, SPEID as u32, 0, 0]),
                (4, [1, 0x20, 0, 0]),
            ]
        );
        assert!(e.argv.is_none());
    }

    #[test]
    fn too_many_arguments_are_refused() {
        let args = vec![vec![b'x'; 5000]];
        let err = prepare(&Start::Shell { args }, 0, 1 << 20).unwrap_err();
        assert!(err.contains("SPE_ARG_MAX"), "{err}");
        let args = vec![vec![b'x'; 2000]];
        let err = prepare(&Start::Shell { args }, 0x3f800, 1 << 20).unwrap_err();
        assert!(err.contains("no room for a stack"), "{err}");
    }
}
