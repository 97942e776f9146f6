//! The calls compiled blocks make into the interpreter: one instruction's semantics, with
//! the operation fixed at compile time for the frequent ones (so the call does no
//! dispatch), and the encoding of what the instruction did.

use crate::codec::Inst;
use crate::machine::exec::{execute_in, Core, Effect, LS_MASK};
use crate::table::Op;

/// A call into the interpreter for one instruction: the core, the decoded instruction
/// (kept alive by its block), its address; returns [`effect_code`] of the effect.
pub(crate) type Helper = unsafe extern "C" fn(*mut Core, *const Inst, u32) -> u64;

/// Bit 33: the instruction was a branch; bit 32: taken; bits 0..31: its target.
pub(crate) const BRANCH: u64 = 1 << 33;
pub(crate) const TAKEN: u64 = 1 << 32;

#[inline(always)]
fn effect_code(effect: Effect) -> u64 {
    match effect {
        Effect::Branch { taken, target } => BRANCH | (taken as u64) << 32 | target as u64,
        // Blocks hold no stores through here, no stops, halts, channels or illegal words
        // (they end blocks), and hints do nothing outside the timing model.
        _ => 0,
    }
}

/// Any operation: the interpreter's full dispatch.
unsafe extern "C" fn any_op(core: *mut Core, inst: *const Inst, pc: u32) -> u64 {
    // SAFETY: the block passes its SPU's core, exclusively borrowed for the call, and an
    // instruction its block owns.
    unsafe { effect_code(execute_in::<true>(&mut *core, *inst, pc)) }
}

macro_rules! specialised {
    ($($op:ident),* $(,)?) => {
        /// The helper for `op`: specialised for the frequent operations.
        pub(crate) fn helper_for(op: Op) -> Helper {
            match op {
                $(Op::$op => {
                    unsafe extern "C" fn h(core: *mut Core, inst: *const Inst, pc: u32) -> u64 {
                        // SAFETY: as in `any_op`; with the operation a constant the
                        // interpreter's `match` folds to this one arm.
                        unsafe {
                            effect_code(execute_in::<true>(
                                &mut *core,
                                Inst { op: Op::$op, ..*inst },
                                pc,
                            ))
                        }
                    }
                    h as Helper
                })*
                _ => any_op as Helper,
            }
        }
    };
}

specialised!(
    Fa, Fs, Fm, Fma, Fms, Fnms, Frest, Frsqest, Csflt, Cuflt, Gb, Gbh, Gbb, Fsm, Fsmh, Fsmb,
    Rotqby, Rotqbybi, Shlqby, Shlqbybi, Rotqmby, Rotqmbybi, Rotqbi, Rotqbii, Shlqbi, Shlqbii,
    Rotqmbi, Rotqmbii, Mpy, Mpyu, Mpyi, Mpyui, Mpya, Mpyh, Mpyhh, Mpys, Ah, Ahi, Sfh, Sfhi, Ceqb,
    Ceqbi, Ceqh, Ceqhi, Cgtb, Cgth, Clgtb, Clgth, Andbi, Andhi, Orbi, Orhi, Xorbi, Xorhi, Cwd, Cbd,
    Chd, Cdd, Cwx, Cbx, Chx, Cdx, Clz, Xsbh, Xshw, Xswd, Shl, Rot, Rotm, Rotma, Shlh, Shlhi, Roth,
    Rothi, Rothm, Rothmi, Rotmah, Rotmahi, Cntb, Avgb, Absdb, Sumb, Addx, Sfx, Cg, Cgx, Bg, Bgx,
    Dfa, Dfs, Dfm, Dfma, Dfms, Dfnms, Dfnma, Fesd, Frds, Orx,
);

/// The exact path of a float run: its `n` instructions from `insts` on (at `pc`,
/// `pc + 4`, ...) one by one by the interpreter's semantics, results and flags in the core
/// (a run holds register-only instructions: no branch, store or channel).
unsafe extern "C" fn exact_run(core: *mut Core, insts: *const Inst, pc: u32, n: u32) {
    // SAFETY: the block passes its SPU's core, exclusively borrowed for the call, and
    // `n` instructions its block owns.
    let (core, insts) = unsafe { (&mut *core, std::slice::from_raw_parts(insts, n as usize)) };
    for (k, inst) in insts.iter().enumerate() {
        let _ = execute_in::<true>(core, *inst, pc.wrapping_add(4 * k as u32) & LS_MASK);
    }
}

/// How a compiled block calls [`exact_run`]: the address to call and whether the callee
/// keeps every register (Cranelift's `preserve_all` convention, through
/// `spu_jit_exact_run_preserving`), so that the values a block holds in registers need not
/// be saved around a path that is seldom taken.
pub(crate) fn exact_run_entry() -> (usize, bool) {
    #[cfg(target_arch = "x86_64")]
    {
        extern "C" {
            fn spu_jit_exact_run_preserving();
        }
        (spu_jit_exact_run_preserving as *const () as usize, true)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        (exact_run as *const () as usize, false)
    }
}

// [`exact_run`] keeping every general and vector register the System V convention lets a
// callee change (the arguments arrive as for it). 9 pushes after rbp leave rsp 8 below a
// 16-byte boundary; 264 bytes more hold xmm0-15 and realign it for the call.
#[cfg(target_arch = "x86_64")]
std::arch::global_asm!(
    ".pushsection .text.spu_jit_exact_run_preserving,\"ax\",@progbits",
    ".p2align 4",
    ".globl spu_jit_exact_run_preserving",
    ".hidden spu_jit_exact_run_preserving",
    "spu_jit_exact_run_preserving:",
    "push rbp",
    "mov rbp, rsp",
    "push rax",
    "push rcx",
    "push rdx",
    "push rsi",
    "push rdi",
    "push r8",
    "push r9",
    "push r10",
    "push r11",
    "sub rsp, 264",
    "movdqu [rsp], xmm0",
    "movdqu [rsp + 16], xmm1",
    "movdqu [rsp + 32], xmm2",
    "movdqu [rsp + 48], xmm3",
    "movdqu [rsp + 64], xmm4",
    "movdqu [rsp + 80], xmm5",
    "movdqu [rsp + 96], xmm6",
    "movdqu [rsp + 112], xmm7",
    "movdqu [rsp + 128], xmm8",
    "movdqu [rsp + 144], xmm9",
    "movdqu [rsp + 160], xmm10",
    "movdqu [rsp + 176], xmm11",
    "movdqu [rsp + 192], xmm12",
    "movdqu [rsp + 208], xmm13",
    "movdqu [rsp + 224], xmm14",
    "movdqu [rsp + 240], xmm15",
    "call {run}",
    "movdqu xmm0, [rsp]",
    "movdqu xmm1, [rsp + 16]",
    "movdqu xmm2, [rsp + 32]",
    "movdqu xmm3, [rsp + 48]",
    "movdqu xmm4, [rsp + 64]",
    "movdqu xmm5, [rsp + 80]",
    "movdqu xmm6, [rsp + 96]",
    "movdqu xmm7, [rsp + 112]",
    "movdqu xmm8, [rsp + 128]",
    "movdqu xmm9, [rsp + 144]",
    "movdqu xmm10, [rsp + 160]",
    "movdqu xmm11, [rsp + 176]",
    "movdqu xmm12, [rsp + 192]",
    "movdqu xmm13, [rsp + 208]",
    "movdqu xmm14, [rsp + 224]",
    "movdqu xmm15, [rsp + 240]",
    "add rsp, 264",
    "pop r11",
    "pop r10",
    "pop r9",
    "pop r8",
    "pop rdi",
    "pop rsi",
    "pop rdx",
    "pop rcx",
    "pop rax",
    "pop rbp",
    "ret",
    ".popsection",
    run = sym exact_run,
);
