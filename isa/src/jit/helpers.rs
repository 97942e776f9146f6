//! The calls compiled blocks make into the interpreter: one instruction's semantics, with
//! the operation fixed at compile time for the frequent ones (so the call does no
//! dispatch), and the encoding of what the instruction did.

use crate::codec::Inst;
use crate::machine::exec::{execute_in, Core, Effect};
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
