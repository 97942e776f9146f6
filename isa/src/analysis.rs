//! Which registers each instruction reads and writes, and what kind of instruction it is.
//!
//! Derived from the table's operand list, with the few operations whose destination field
//! is also (or only) a source written out by name: stores and conditional branches read
//! RT, the carry/borrow and accumulate forms read their old RT, halts and `nop` write
//! nothing. The timing model and the profilers use this to find dependencies.

use crate::codec::Inst;
use crate::table::{Op, OperandKind};

/// Whether `inst` writes one of the MFC command parameters (`wrch` of channels 16 to 20:
/// MFC_LSA, MFC_EAH, MFC_EAL, MFC_Size, MFC_TagID): a latch that never waits, which the
/// core does itself (`machine::exec::MfcParams`), unlike the other channel instructions.
#[inline(always)]
pub fn is_mfc_param_write(inst: Inst) -> bool {
    inst.op == Op::Wrch && MFC_PARAM_CHANNELS.contains(&inst.ra)
}

/// The channels of the MFC command parameters, in the order `machine::exec::MfcParams`
/// holds them.
pub const MFC_PARAM_CHANNELS: std::ops::RangeInclusive<u8> = 16..=20;

/// Register usage of one operation's fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegUse {
    /// The operation reads register `rt` (stores, `selb`-like forms and branches on `rt`).
    pub reads_rt: bool,
    /// The operation writes its result to register `rt`.
    pub writes_rt: bool,
    /// The operation reads register `ra`.
    pub reads_ra: bool,
    /// The operation reads register `rb`.
    pub reads_rb: bool,
    /// The operation reads register `rc`.
    pub reads_rc: bool,
}

/// The register usage of an operation (independent of the operand values).
pub fn regs(op: Op) -> RegUse {
    let mut u = RegUse {
        reads_rt: false,
        writes_rt: false,
        reads_ra: false,
        reads_rb: false,
        reads_rc: false,
    };
    let Some(form) = crate::table::primary_form(op) else {
        return u;
    };
    for kind in form.operands {
        match kind {
            OperandKind::Rt => u.writes_rt = true,
            OperandKind::Ra | OperandKind::ParenRa => u.reads_ra = true,
            OperandKind::Rb => u.reads_rb = true,
            OperandKind::Rc => u.reads_rc = true,
            _ => {}
        }
    }
    use Op::*;
    match op {
        // RT is a source: stores, conditional branches, channel/SPR writes.
        Stqd | Stqx | Stqa | Stqr | Brz | Brnz | Brhz | Brhnz | Biz | Binz | Bihz | Bihnz
        | Wrch | Mtspr => {
            u.reads_rt = true;
            u.writes_rt = false;
        }
        // RT is both source and destination.
        Iohl | Addx | Sfx | Cgx | Bgx | Mpyhha | Mpyhhau | Dfma | Dfms | Dfnms | Dfnma => {
            u.reads_rt = true;
        }
        // No destination at all.
        Heq | Hgt | Hlgt | Heqi | Hgti | Hlgti | Nop | Stopd | Fscrwr => u.writes_rt = false,
        _ => {}
    }
    u
}

/// The registers an instruction reads (up to four) and the one it writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Operands {
    /// Register numbers (0 to 127) read, in the order `ra`, `rb`, `rc`, `rt`; `None` where that field is not read.
    pub reads: [Option<u8>; 4],
    /// The register number written, if the instruction writes one.
    pub writes: Option<u8>,
}

/// The registers `inst` reads and writes, from its operation's [`RegUse`] and its register fields.
pub fn operands(inst: Inst) -> Operands {
    let u = regs(inst.op);
    let reads = [
        u.reads_ra.then_some(inst.ra),
        u.reads_rb.then_some(inst.rb),
        u.reads_rc.then_some(inst.rc),
        u.reads_rt.then_some(inst.rt),
    ];
    Operands {
        reads,
        writes: u.writes_rt.then_some(inst.rt),
    }
}

/// Broad classes the timing model and statistics care about.
pub fn is_branch(op: Op) -> bool {
    use Op::*;
    matches!(
        op,
        Br | Brsl
            | Bra
            | Brasl
            | Brz
            | Brnz
            | Brhz
            | Brhnz
            | Bi
            | Bisl
            | Iret
            | Bisled
            | Biz
            | Binz
            | Bihz
            | Bihnz
    )
}

/// Whether `op` is a branch hint (`hbr`, `hbra`, `hbrr`).
pub fn is_hint(op: Op) -> bool {
    matches!(op, Op::Hbr | Op::Hbra | Op::Hbrr)
}

/// Whether `op` is a load from local store (`lqd`, `lqx`, `lqa`, `lqr`, and the gather
/// extension's `lgw`, `lgwx`).
pub fn is_load(op: Op) -> bool {
    matches!(
        op,
        Op::Lqd | Op::Lqx | Op::Lqa | Op::Lqr | Op::Lgw | Op::Lgwx
    )
}

/// Whether `op` is a quadword store to local store (`stqd`, `stqx`, `stqa`, `stqr`).
pub fn is_store(op: Op) -> bool {
    matches!(op, Op::Stqd | Op::Stqx | Op::Stqa | Op::Stqr)
}

/// Whether `op` is a no-op of either pipeline (`nop`, `lnop`).
pub fn is_nop(op: Op) -> bool {
    matches!(op, Op::Nop | Op::Lnop)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codec::decode;

    #[test]
    fn register_usage() {
        // fma $7,$6,$5,$4 reads 6,5,4 and writes 7.
        let o = operands(decode(0xe0e14304));
        assert_eq!(o.reads, [Some(6), Some(5), Some(4), None]);
        assert_eq!(o.writes, Some(7));
        // stqd $5,32($1) reads 1 and 5, writes nothing.
        let o = operands(decode(0x24008085));
        assert_eq!(o.reads, [Some(1), None, None, Some(5)]);
        assert_eq!(o.writes, None);
        assert!(regs(Op::Dfma).reads_rt && regs(Op::Dfma).writes_rt);
        assert!(!regs(Op::Heq).writes_rt);
    }
}
