//! The block compiler: hot basic blocks of local store translated to host code with
//! Cranelift (the code generator wasmtime uses), so that simulated SPUs run near host speed
//! with exactly the interpreter's results.
//!
//! A block is what the timing model's memo calls one: straight-line instructions up to and
//! including the first branch, ending before anything that needs the SPU around the core
//! (channels, stops, halts, `sync`, `bisled`, undecodable words); a register-form hint
//! (`hbr`) only leaves its target in the core for the timing model.
//! Registers live in the core's register file as 128-bit vectors; the common operations
//! (loads, stores, integer and logical word operations, compares, `selb`, `shufb`, constant
//! shifts and rotates, immediate loads, the simple branches) become host vector code, and
//! every other instruction is a call into the interpreter's own semantics for that one
//! instruction ([`crate::machine::exec`]), specialised per operation so the call does no
//! dispatch: the single-precision arithmetic keeps its one exact definition (the fast path
//! in host vector instructions where the result is an ordinary number, the exact code in
//! [`crate::float`] otherwise) and nothing is written twice.
//!
//! Stores check a per-quadword map of local store holding decoded code; a store there
//! calls back into the SPU, which marks the words stale and bumps the code epoch (compiled
//! blocks check their words again when the epoch moved), and ends the block early when it
//! wrote the block's own remaining instructions, as the interpreter's replay does.
//!
//! The SPU drives compiled blocks in `machine::compiled`; quanta, channels, DMA, timing
//! and multi-SPU determinism are the interpreter's, unchanged.

use std::fmt;
use std::str::FromStr;

#[cfg(block_compiler)]
mod compile;
#[cfg(block_compiler)]
mod helpers;

#[cfg(block_compiler)]
pub use compile::CodeCache;
#[cfg(block_compiler)]
pub(crate) use compile::{
    asked, Blocks, Ctx, Entry, Lookup, MAX_BLOCK, RESULT_PARTIAL, RESULT_TAKEN,
};

/// No block compiler on this host: nothing to share.
#[cfg(not(block_compiler))]
#[derive(Clone, Default)]
pub struct CodeCache;

#[cfg(not(block_compiler))]
impl CodeCache {
    /// An empty cache (there is nothing to put in it).
    pub fn new() -> CodeCache {
        CodeCache
    }

    /// An empty cache; how it would compile does not matter without a compiler.
    pub fn with(_compiling: Compiling) -> CodeCache {
        CodeCache
    }

    /// Compilations finished: always 0.
    pub fn completed(&self) -> u64 {
        0
    }

    /// Nothing is compiled; inline, as nothing waits.
    pub fn compiling(&self) -> Compiling {
        Compiling::Inline
    }

    /// The compiler's work: none.
    pub fn stats(&self) -> JitStats {
        JitStats::default()
    }
}

/// Which engine runs an SPU's instructions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Engine {
    /// The interpreter: every instruction through the semantics' `match` (the reference).
    Interp,
    /// Compiled blocks where the host has a code generator, the interpreter elsewhere.
    Jit,
}

impl Engine {
    /// Whether this host has the block compiler (x86_64 and aarch64, Cranelift's targets).
    pub const SUPPORTED: bool = cfg!(block_compiler);

    /// The compiler where the host has one, the interpreter elsewhere.
    pub const fn host_default() -> Engine {
        if Engine::SUPPORTED {
            Engine::Jit
        } else {
            Engine::Interp
        }
    }

    /// The engine's name as the command-line options spell it (`interp` or `jit`).
    pub const fn name(self) -> &'static str {
        match self {
            Engine::Interp => "interp",
            Engine::Jit => "jit",
        }
    }
}

impl Default for Engine {
    /// [`Engine::host_default`]: what a new SPU starts with until
    /// [`crate::machine::Spu::set_engine`] says otherwise.
    fn default() -> Self {
        Engine::host_default()
    }
}

impl fmt::Display for Engine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

impl FromStr for Engine {
    type Err = String;
    fn from_str(s: &str) -> Result<Engine, String> {
        match s {
            "interp" => Ok(Engine::Interp),
            "jit" => Ok(Engine::Jit),
            other => Err(format!("unknown engine `{other}` (interp or jit)")),
        }
    }
}

/// When a block that turned hot is compiled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Compiling {
    /// At once, by the SPU that found it hot, which waits: what runs compiled is the same
    /// at every run (the library's default, so tests can count it).
    Inline,
    /// By a host thread of the code cache's own while the SPUs go on interpreting it: no
    /// wait, but how much runs compiled depends on the host's timing (the `spu` commands'
    /// default). Results are the same either way.
    Background,
}

impl Compiling {
    /// The mode's name as the command-line options spell it (`inline` or `background`).
    pub const fn name(self) -> &'static str {
        match self {
            Compiling::Inline => "inline",
            Compiling::Background => "background",
        }
    }
}

impl Default for Compiling {
    /// Inline: what runs compiled is the same at every run.
    fn default() -> Self {
        Compiling::Inline
    }
}

impl fmt::Display for Compiling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.pad(self.name())
    }
}

impl FromStr for Compiling {
    type Err = String;
    fn from_str(s: &str) -> Result<Compiling, String> {
        match s {
            "inline" => Ok(Compiling::Inline),
            "background" => Ok(Compiling::Background),
            other => Err(format!(
                "unknown way of compiling `{other}` (inline or background)"
            )),
        }
    }
}

/// What the block compiler did for one SPU.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JitStats {
    /// Blocks compiled (including recompilations after code changed).
    pub blocks: u64,
    /// Instructions in those blocks.
    pub block_instructions: u64,
    /// Host seconds spent compiling.
    pub compile_seconds: f64,
    /// Simulated instructions executed by compiled code.
    pub compiled_instructions: u64,
    /// Passes of self-looping blocks that ran with the timing model on in a steady state,
    /// their timing record applied once for a whole run of passes (per SPU, like
    /// `compiled_instructions`).
    pub steady_passes: u64,
}
