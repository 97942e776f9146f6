//! Bit-exact semantics of every SPU operation, as one `match` over the decoded operation.

use crate::analysis::{is_mfc_param_write, MFC_PARAM_CHANNELS};
use crate::codec::Inst;
use crate::float;
use crate::table::Op;

/// One 128-bit SPU register or local-store quadword as four 32-bit words, word 0 first (the big-endian order; word 0 is the preferred slot).
pub type Reg = [u32; 4];

#[inline]
fn map(a: Reg, f: impl Fn(u32) -> u32) -> Reg {
    [f(a[0]), f(a[1]), f(a[2]), f(a[3])]
}
#[inline]
fn zip(a: Reg, b: Reg, f: impl Fn(u32, u32) -> u32) -> Reg {
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])]
}
#[inline]
fn zip3(a: Reg, b: Reg, c: Reg, f: impl Fn(u32, u32, u32) -> u32) -> Reg {
    [
        f(a[0], b[0], c[0]),
        f(a[1], b[1], c[1]),
        f(a[2], b[2], c[2]),
        f(a[3], b[3], c[3]),
    ]
}
#[inline]
fn halves(a: Reg, b: Reg, f: impl Fn(u16, u16) -> u16) -> Reg {
    zip(a, b, |x, y| {
        let hi = f((x >> 16) as u16, (y >> 16) as u16) as u32;
        let lo = f(x as u16, y as u16) as u32;
        (hi << 16) | lo
    })
}
#[inline]
fn bytes_of(a: Reg) -> [u8; 16] {
    let mut out = [0u8; 16];
    for i in 0..4 {
        out[4 * i..4 * i + 4].copy_from_slice(&a[i].to_be_bytes());
    }
    out
}
#[inline]
fn from_bytes(b: [u8; 16]) -> Reg {
    let w = |i: usize| u32::from_be_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    [w(0), w(1), w(2), w(3)]
}
#[inline]
fn bytewise(a: Reg, b: Reg, f: impl Fn(u8, u8) -> u8) -> Reg {
    let (x, y) = (bytes_of(a), bytes_of(b));
    let mut out = [0u8; 16];
    for i in 0..16 {
        out[i] = f(x[i], y[i]);
    }
    from_bytes(out)
}
#[inline]
fn to_u128(a: Reg) -> u128 {
    ((a[0] as u128) << 96) | ((a[1] as u128) << 64) | ((a[2] as u128) << 32) | a[3] as u128
}
#[inline]
fn from_u128(v: u128) -> Reg {
    [
        (v >> 96) as u32,
        (v >> 64) as u32,
        (v >> 32) as u32,
        v as u32,
    ]
}
fn dwords(a: Reg) -> [u64; 2] {
    [
        ((a[0] as u64) << 32) | a[1] as u64,
        ((a[2] as u64) << 32) | a[3] as u64,
    ]
}
fn from_dwords(d: [u64; 2]) -> Reg {
    [
        (d[0] >> 32) as u32,
        d[0] as u32,
        (d[1] >> 32) as u32,
        d[1] as u32,
    ]
}
fn mask(b: bool) -> u32 {
    if b {
        u32::MAX
    } else {
        0
    }
}
fn hmask(b: bool) -> u16 {
    if b {
        u16::MAX
    } else {
        0
    }
}
fn splat(v: u32) -> Reg {
    [v; 4]
}
fn splat_h(v: u16) -> Reg {
    splat(((v as u32) << 16) | v as u32)
}
fn splat_b(v: u8) -> Reg {
    splat(u32::from_ne_bytes([v; 4]))
}

/// The MFC command parameters, in the order of their channels (MFC_LSA 16, MFC_EAH 17,
/// MFC_EAL 18, MFC_Size 19, MFC_TagID 20). Writing one only latches a value that the next
/// command (MFC_Cmd) takes: it never waits and has no other effect, so the core does it
/// like a register move, and blocks hold such writes (compiled code stores the field).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct MfcParams {
    /// MFC_LSA: the local-store byte address.
    pub lsa: u32,
    /// MFC_EAH: the high 32 bits of the effective address.
    pub eah: u32,
    /// MFC_EAL: the low 32 bits of the effective address.
    pub eal: u32,
    /// MFC_Size: the transfer size in bytes.
    pub size: u32,
    /// MFC_TagID: the tag group (only the low 5 bits count).
    pub tag_id: u32,
}

impl MfcParams {
    /// Latches `v` into the parameter of `channel` ([`MFC_PARAM_CHANNELS`]).
    #[inline(always)]
    pub fn set(&mut self, channel: u8, v: u32) {
        match Self::index(channel) {
            0 => self.lsa = v,
            1 => self.eah = v,
            2 => self.eal = v,
            3 => self.size = v,
            _ => self.tag_id = v,
        }
    }

    /// Where in the parameters the one of `channel` lies (for compiled code): the fields
    /// follow the channels' order.
    #[cfg_attr(not(block_compiler), allow(dead_code))]
    pub(crate) const fn offset(channel: u8) -> usize {
        std::mem::offset_of!(MfcParams, lsa) + 4 * Self::index(channel)
    }

    const fn index(channel: u8) -> usize {
        (channel - *MFC_PARAM_CHANNELS.start()) as usize
    }
}

const _: () = assert!(
    MfcParams::offset(*MFC_PARAM_CHANNELS.end()) == std::mem::offset_of!(MfcParams, tag_id)
        && MfcParams::offset(19) == std::mem::offset_of!(MfcParams, size)
);

/// Architectural state the semantics act on (the channels and the MFC live outside, but
/// for the command parameters' latches).
pub struct Core {
    /// The 128 general-purpose registers.
    pub regs: [Reg; 128],
    /// The 256 KiB local store, indexed by local-store byte address.
    pub ls: Box<[u8; LS_SIZE]>,
    /// The floating-point status and control register.
    pub fpscr: float::Fpscr,
    /// Whether interrupts are enabled (set and cleared by the E and D bits of the indirect branches).
    pub interrupts_enabled: bool,
    /// SRR0: the local-store address `iret` returns to.
    pub srr0: u32,
    /// Whether SPU_RdEventStat has a count (for `bisled`), valid while
    /// `event_pending_known` is set by the SPU around that one instruction.
    pub event_pending: bool,
    /// Whether `event_pending` is valid (the SPU sets it around a `bisled`).
    pub event_pending_known: bool,
    /// The target of the last register-form hint (`hbr`) executed: blocks run whole hold
    /// such hints, and the timing model takes the hint entry's target from here.
    pub hint_target: u32,
    /// The latched MFC command parameters.
    pub mfc: MfcParams,
}

/// Local store size in bytes (256 KiB).
pub const LS_SIZE: usize = 256 * 1024;
/// Mask that wraps a byte address into the local store (`LS_SIZE - 1`).
pub const LS_MASK: u32 = (LS_SIZE as u32) - 1;

/// What executing one instruction did besides writing registers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    /// Nothing special: execution goes on at the next instruction.
    Next,
    /// A branch instruction: where it went when taken.
    Branch {
        /// Whether the branch was taken.
        taken: bool,
        /// The local-store address it went to when taken.
        target: u32,
    },
    /// A quadword store to this (aligned) local-store address.
    Store {
        /// The quadword's local-store byte address (a multiple of 16).
        addr: u32,
    },
    /// A branch hint (`hbr`, `hbra`, `hbrr`; not `hbrp`).
    Hint {
        /// Local-store address of the hinted branch.
        branch: u32,
        /// Local-store address the hint predicts the branch goes to.
        target: u32,
    },
    /// `stop`: the SPU stops with this 14-bit stop-and-signal code.
    Stop(u16),
    /// A halt instruction (`heq`, `hgt`, `hlgt` and their immediate forms) whose condition held.
    Halt,
    /// Channel instructions are carried out by the SPU, not here (but for the writes of
    /// the MFC command parameters, [`MfcParams`]).
    Channel,
    /// A word that decodes to no operation.
    Illegal,
}

impl Core {
    /// A core with every register and the whole local store zero, interrupts disabled.
    pub fn new() -> Core {
        Core {
            regs: [[0; 4]; 128],
            ls: vec![0; LS_SIZE].into_boxed_slice().try_into().unwrap(),
            fpscr: float::Fpscr::default(),
            interrupts_enabled: false,
            srr0: 0,
            event_pending: false,
            event_pending_known: false,
            hint_target: 0,
            mfc: MfcParams::default(),
        }
    }

    /// The word at local-store byte address `addr` (wrapped into the local store, low 2
    /// bits ignored), as the gather loads read each slot.
    #[inline(always)]
    pub fn load_word(&self, addr: u32) -> u32 {
        let a = (addr & LS_MASK & !3) as usize;
        u32::from_be_bytes(self.ls[a..a + 4].try_into().unwrap())
    }

    #[inline(always)]
    /// The quadword at local-store byte address `addr` (wrapped into the local store, low 4 bits ignored).
    pub fn load_quad(&self, addr: u32) -> Reg {
        let a = (addr & LS_MASK & !15) as usize;
        let q: &[u8; 16] = self.ls[a..a + 16].try_into().unwrap();
        let w = |i: usize| u32::from_ne_bytes([q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]]);
        // Four native words, then a lane-wise byte swap (a vector operation).
        [w(0), w(1), w(2), w(3)].map(u32::from_be)
    }

    #[inline(always)]
    /// Stores `v` at local-store byte address `addr` (wrapped, low 4 bits ignored); returns the aligned address written.
    pub fn store_quad(&mut self, addr: u32, v: Reg) -> u32 {
        let a = (addr & LS_MASK & !15) as usize;
        let q: &mut [u8; 16] = (&mut self.ls[a..a + 16]).try_into().unwrap();
        let v = v.map(u32::to_be);
        for i in 0..4 {
            q[4 * i..4 * i + 4].copy_from_slice(&v[i].to_ne_bytes());
        }
        a as u32
    }
}

impl Default for Core {
    fn default() -> Self {
        Core::new()
    }
}

fn insertion_mask(t: u32, size: u32) -> Reg {
    let mut b = [0u8; 16];
    for (i, byte) in b.iter_mut().enumerate() {
        *byte = 0x10 + i as u8;
    }
    let start = (t & (16 - size)) as usize & 15;
    for k in 0..size as usize {
        b[start + k] = (if size == 1 {
            3
        } else if size == 2 {
            2
        } else {
            0
        } + k) as u8;
    }
    from_bytes(b)
}

/// `shufb`: each control byte picks a byte of the 32-byte concatenation RA:RB by its low 5
/// bits, or, when its top bit is set, a constant: 10xxxxxx → 0x00, 110xxxxx → 0xFF,
/// 111xxxxx → 0x80.
#[inline(always)]
fn shufb(a: Reg, b: Reg, c: Reg) -> Reg {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("ssse3") {
        // SAFETY: SSSE3 was just detected on this CPU.
        return unsafe { shufb_ssse3(a, b, c) };
    }
    shufb_scalar(a, b, c)
}

/// `shufb` with `pshufb`. A register's bytes sit in host memory order: big-endian byte
/// `k` of the quadword is at position `k ^ 3` of the little-endian words, so a control
/// byte's index is XORed with 3, bit 4 chooses RA or RB, and the special forms are blended
/// in where the control byte's top bit is set.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "ssse3")]
unsafe fn shufb_ssse3(a: Reg, b: Reg, c: Reg) -> Reg {
    use core::arch::x86_64::*;
    let va = _mm_loadu_si128(a.as_ptr() as *const __m128i);
    let vb = _mm_loadu_si128(b.as_ptr() as *const __m128i);
    let vc = _mm_loadu_si128(c.as_ptr() as *const __m128i);
    let high = _mm_set1_epi8(0x80u8 as i8);
    let idx = _mm_xor_si128(_mm_and_si128(vc, _mm_set1_epi8(0x1f)), _mm_set1_epi8(3));
    let from_b = _mm_cmpeq_epi8(_mm_and_si128(vc, _mm_set1_epi8(0x10)), _mm_set1_epi8(0x10));
    let ia = _mm_or_si128(idx, _mm_and_si128(from_b, high));
    let ib = _mm_or_si128(idx, _mm_andnot_si128(from_b, high));
    let picked = _mm_or_si128(_mm_shuffle_epi8(va, ia), _mm_shuffle_epi8(vb, ib));
    // 10xxxxxx -> 0x00, 110xxxxx -> 0xff, 111xxxxx -> 0x80.
    let special = _mm_cmplt_epi8(vc, _mm_setzero_si128());
    let top3 = _mm_and_si128(vc, _mm_set1_epi8(0xe0u8 as i8));
    let ff = _mm_cmpeq_epi8(top3, _mm_set1_epi8(0xc0u8 as i8));
    let x80 = _mm_and_si128(_mm_cmpeq_epi8(top3, _mm_set1_epi8(0xe0u8 as i8)), high);
    let constant = _mm_or_si128(ff, x80);
    let r = _mm_or_si128(
        _mm_andnot_si128(special, picked),
        _mm_and_si128(special, constant),
    );
    let mut out = [0u32; 4];
    _mm_storeu_si128(out.as_mut_ptr() as *mut __m128i, r);
    out
}

#[inline(always)]
fn shufb_scalar(a: Reg, b: Reg, c: Reg) -> Reg {
    let mut t = [0u8; 32];
    for i in 0..4 {
        t[4 * i..4 * i + 4].copy_from_slice(&a[i].to_be_bytes());
        t[16 + 4 * i..16 + 4 * i + 4].copy_from_slice(&b[i].to_be_bytes());
    }
    let special = (c[0] | c[1] | c[2] | c[3]) & 0x8080_8080 != 0;
    let mut out = [0u32; 4];
    for i in 0..4 {
        let cw = c[i];
        let mut w = 0u32;
        for k in 0..4 {
            let s = (cw >> (24 - 8 * k)) as u8;
            let v = if special && s & 0x80 != 0 {
                [0x00, 0x00, 0xff, 0x80][((s >> 5) & 3) as usize]
            } else {
                t[(s & 31) as usize]
            };
            w = (w << 8) | v as u32;
        }
        out[i] = w;
    }
    out
}

/// Writes register `rt` with one 16-byte store: operands are read with 16-byte loads, and
/// a load that finds its bytes in four narrower stores still in flight misses store
/// forwarding and stalls (a large cost in an interpreter that reads what it just wrote).
#[inline(always)]
pub fn put(regs: &mut [Reg; 128], rt: u8, v: Reg) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{__m128i, _mm_set_epi32, _mm_storeu_si128};
        let slot: *mut Reg = &mut regs[rt as usize & 127];
        // SAFETY: `slot` is a valid, exclusively borrowed 16-byte register; SSE2 is part of
        // the x86_64 baseline and the store is unaligned.
        unsafe {
            let x = _mm_set_epi32(v[3] as i32, v[2] as i32, v[1] as i32, v[0] as i32);
            _mm_storeu_si128(slot as *mut __m128i, x);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        regs[rt as usize & 127] = v;
    }
}

/// Executes `inst` at `pc` on `core`. Channel instructions return [`Effect::Channel`], but
/// for the writes of the MFC command parameters, which the core latches ([`MfcParams`]).
#[inline(always)]
pub fn execute(core: &mut Core, inst: Inst, pc: u32) -> Effect {
    execute_in::<false>(core, inst, pc)
}

/// [`execute`]; `TRUNCATING`: the caller holds a [`TruncatingFloats`], so the host's
/// floating-point unit already rounds toward zero.
#[inline(always)]
pub(crate) fn execute_in<const TRUNCATING: bool>(core: &mut Core, inst: Inst, pc: u32) -> Effect {
    use Op::*;
    // Operands are read where an operation uses them and each operation writes its own
    // result, so a result computed in vector registers is stored straight from them.
    macro_rules! ra {
        () => {
            core.regs[inst.ra as usize & 127]
        };
    }
    macro_rules! rb {
        () => {
            core.regs[inst.rb as usize & 127]
        };
    }
    macro_rules! rc {
        () => {
            core.regs[inst.rc as usize & 127]
        };
    }
    macro_rules! rt_old {
        () => {
            core.regs[inst.rt as usize & 127]
        };
    }
    macro_rules! w {
        ($e:expr $(,)?) => {{
            let v: Reg = $e;
            put(&mut core.regs, inst.rt, v)
        }};
    }
    let imm = inst.imm;
    let i10 = imm as u32;
    let next = pc.wrapping_add(4) & LS_MASK;
    let mut effect = Effect::Next;
    match inst.op {
        // ---- loads and stores
        Lqd => w!(core.load_quad(ra!()[0].wrapping_add((imm << 4) as u32))),
        Lqx => w!(core.load_quad(ra!()[0].wrapping_add(rb!()[0]))),
        // The gather extension (decoded only where it is on): each word slot's address.
        Lgw => w!(ra!().map(|a| core.load_word(a))),
        Lgwx => w!(zip(ra!(), rb!(), |a, b| core.load_word(a.wrapping_add(b)))),
        Lqa => w!(core.load_quad((imm << 2) as u32)),
        Lqr => w!(core.load_quad(pc.wrapping_add((imm << 2) as u32))),
        Stqd | Stqx | Stqa | Stqr => {
            let addr = match inst.op {
                Stqd => ra!()[0].wrapping_add((imm << 4) as u32),
                Stqx => ra!()[0].wrapping_add(rb!()[0]),
                Stqa => (imm << 2) as u32,
                _ => pc.wrapping_add((imm << 2) as u32),
            };
            let a = core.store_quad(addr, rt_old!());
            return Effect::Store { addr: a };
        }
        // ---- immediate loads
        Il => w!(splat(imm as u32)),
        Ilh => w!(splat_h(imm as u16)),
        Ilhu => w!(splat((imm as u32) << 16)),
        Ila => w!(splat(imm as u32 & 0x3ffff)),
        Iohl => w!(map(rt_old!(), |t| t | (imm as u32 & 0xffff))),
        Fsmbi => {
            let m = inst.u16();
            let mut b = [0u8; 16];
            for (i, byte) in b.iter_mut().enumerate() {
                *byte = if m & (0x8000 >> i) != 0 { 0xff } else { 0 };
            }
            w!(from_bytes(b))
        }
        // ---- integer arithmetic
        A => w!(zip(ra!(), rb!(), u32::wrapping_add)),
        Ah => w!(halves(ra!(), rb!(), u16::wrapping_add)),
        Ai => w!(map(ra!(), |a| a.wrapping_add(i10))),
        Ahi => w!(halves(ra!(), splat_h(imm as u16), u16::wrapping_add)),
        Sf => w!(zip(ra!(), rb!(), |a, b| b.wrapping_sub(a))),
        Sfh => w!(halves(ra!(), rb!(), |a, b| b.wrapping_sub(a))),
        Sfi => w!(map(ra!(), |a| i10.wrapping_sub(a))),
        Sfhi => w!(halves(ra!(), splat_h(imm as u16), |a, b| b.wrapping_sub(a))),
        Addx => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            a.wrapping_add(b).wrapping_add(t & 1)
        })),
        Sfx => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            b.wrapping_add(!a).wrapping_add(t & 1)
        })),
        Cg => w!(zip(ra!(), rb!(), |a, b| ((a as u64 + b as u64) >> 32) as u32)),
        Cgx => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            ((a as u64 + b as u64 + (t & 1) as u64) >> 32) as u32
        })),
        Bg => w!(zip(ra!(), rb!(), |a, b| (b >= a) as u32)),
        Bgx => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            if t & 1 != 0 {
                (b >= a) as u32
            } else {
                (b > a) as u32
            }
        })),
        Mpy => w!(zip(ra!(), rb!(), |a, b| {
            ((a as i16 as i32) * (b as i16 as i32)) as u32
        })),
        Mpyu => w!(zip(ra!(), rb!(), |a, b| (a & 0xffff) * (b & 0xffff))),
        Mpyi => w!(map(ra!(), |a| {
            ((a as i16 as i32) * (imm as i16 as i32)) as u32
        })),
        Mpyui => w!(map(ra!(), |a| (a & 0xffff) * (imm as u32 & 0xffff))),
        Mpya => w!(zip3(ra!(), rb!(), rc!(), |a, b, c| {
            ((a as i16 as i32) * (b as i16 as i32)).wrapping_add(c as i32) as u32
        })),
        Mpyh => w!(zip(ra!(), rb!(), |a, b| ((a >> 16) * (b & 0xffff)) << 16)),
        Mpys => w!(zip(ra!(), rb!(), |a, b| {
            (((a as i16 as i32) * (b as i16 as i32)) >> 16) as u32
        })),
        Mpyhh => w!(zip(ra!(), rb!(), |a, b| {
            (((a >> 16) as i16 as i32) * ((b >> 16) as i16 as i32)) as u32
        })),
        Mpyhha => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            (((a >> 16) as i16 as i32) * ((b >> 16) as i16 as i32)).wrapping_add(t as i32) as u32
        })),
        Mpyhhu => w!(zip(ra!(), rb!(), |a, b| (a >> 16) * (b >> 16))),
        Mpyhhau => w!(zip3(ra!(), rb!(), rt_old!(), |a, b, t| {
            ((a >> 16) * (b >> 16)).wrapping_add(t)
        })),
        Clz => w!(map(ra!(), u32::leading_zeros)),
        Cntb => w!(bytewise(ra!(), ra!(), |a, _| a.count_ones() as u8)),
        Absdb => w!(bytewise(ra!(), rb!(), |a, b| a.abs_diff(b))),
        Avgb => w!(bytewise(ra!(), rb!(), |a, b| {
            ((a as u16 + b as u16 + 1) >> 1) as u8
        })),
        Sumb => w!(zip(ra!(), rb!(), |a, b| {
            let s = |x: u32| x.to_be_bytes().iter().map(|v| *v as u32).sum::<u32>();
            (s(b) << 16) | s(a)
        })),
        Xsbh => w!(map(ra!(), |a| {
            let h = |x: u32| (x as u8 as i8 as i16 as u16) as u32;
            (h(a >> 16) << 16) | h(a)
        })),
        Xshw => w!(map(ra!(), |a| a as u16 as i16 as i32 as u32)),
        Xswd => {
            let d = dwords(ra!());
            w!(from_dwords(d.map(|x| x as u32 as i32 as i64 as u64)))
        }
        // ---- logical
        And => w!(zip(ra!(), rb!(), |a, b| a & b)),
        Andc => w!(zip(ra!(), rb!(), |a, b| a & !b)),
        Andi => w!(map(ra!(), |a| a & i10)),
        Andhi => w!(halves(ra!(), splat_h(imm as u16), |a, b| a & b)),
        Andbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| a & b)),
        Or => w!(zip(ra!(), rb!(), |a, b| a | b)),
        Orc => w!(zip(ra!(), rb!(), |a, b| a | !b)),
        Ori => w!(map(ra!(), |a| a | i10)),
        Orhi => w!(halves(ra!(), splat_h(imm as u16), |a, b| a | b)),
        Orbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| a | b)),
        Orx => w!([ra!()[0] | ra!()[1] | ra!()[2] | ra!()[3], 0, 0, 0]),
        Xor => w!(zip(ra!(), rb!(), |a, b| a ^ b)),
        Xori => w!(map(ra!(), |a| a ^ i10)),
        Xorhi => w!(halves(ra!(), splat_h(imm as u16), |a, b| a ^ b)),
        Xorbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| a ^ b)),
        Nand => w!(zip(ra!(), rb!(), |a, b| !(a & b))),
        Nor => w!(zip(ra!(), rb!(), |a, b| !(a | b))),
        Eqv => w!(zip(ra!(), rb!(), |a, b| !(a ^ b))),
        Selb => w!(zip3(ra!(), rb!(), rc!(), |a, b, c| (c & b) | (!c & a))),
        Shufb => w!(shufb(ra!(), rb!(), rc!())),
        // ---- compares
        Ceq => w!(zip(ra!(), rb!(), |a, b| mask(a == b))),
        Ceqh => w!(halves(ra!(), rb!(), |a, b| hmask(a == b))),
        Ceqb => w!(bytewise(ra!(), rb!(), |a, b| if a == b { 0xff } else { 0 })),
        Ceqi => w!(map(ra!(), |a| mask(a == i10))),
        Ceqhi => w!(halves(ra!(), splat_h(imm as u16), |a, b| hmask(a == b))),
        Ceqbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| {
            if a == b {
                0xff
            } else {
                0
            }
        })),
        Cgt => w!(zip(ra!(), rb!(), |a, b| mask((a as i32) > (b as i32)))),
        Cgth => w!(halves(ra!(), rb!(), |a, b| hmask((a as i16) > (b as i16)))),
        Cgtb => w!(bytewise(ra!(), rb!(), |a, b| {
            if (a as i8) > (b as i8) {
                0xff
            } else {
                0
            }
        })),
        Cgti => w!(map(ra!(), |a| mask((a as i32) > imm))),
        Cgthi => w!(halves(ra!(), splat_h(imm as u16), |a, b| {
            hmask((a as i16) > (b as i16))
        })),
        Cgtbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| {
            if (a as i8) > (b as i8) {
                0xff
            } else {
                0
            }
        })),
        Clgt => w!(zip(ra!(), rb!(), |a, b| mask(a > b))),
        Clgth => w!(halves(ra!(), rb!(), |a, b| hmask(a > b))),
        Clgtb => w!(bytewise(ra!(), rb!(), |a, b| if a > b { 0xff } else { 0 })),
        Clgti => w!(map(ra!(), |a| mask(a > i10))),
        Clgthi => w!(halves(ra!(), splat_h(imm as u16), |a, b| hmask(a > b))),
        Clgtbi => w!(bytewise(ra!(), splat_b(imm as u8), |a, b| {
            if a > b {
                0xff
            } else {
                0
            }
        })),
        // ---- word and halfword shifts and rotates
        Shl | Shli => {
            let cnt = if inst.op == Shl {
                rb!()
            } else {
                splat(imm as u32)
            };
            w!(zip(ra!(), cnt, |a, c| {
                let c = c & 0x3f;
                if c > 31 {
                    0
                } else {
                    a << c
                }
            }))
        }
        Shlh | Shlhi => {
            let cnt = if inst.op == Shlh {
                rb!()
            } else {
                splat_h(imm as u16)
            };
            w!(halves(ra!(), cnt, |a, c| {
                let c = c & 0x1f;
                if c > 15 {
                    0
                } else {
                    a << c
                }
            }))
        }
        Rot | Roti => {
            let cnt = if inst.op == Rot {
                rb!()
            } else {
                splat(imm as u32)
            };
            w!(zip(ra!(), cnt, |a, c| a.rotate_left(c & 0x1f)))
        }
        Roth | Rothi => {
            let cnt = if inst.op == Roth {
                rb!()
            } else {
                splat_h(imm as u16)
            };
            w!(halves(ra!(), cnt, |a, c| a.rotate_left((c & 0xf) as u32)))
        }
        Rotm | Rotmi => {
            let cnt = if inst.op == Rotm {
                rb!()
            } else {
                splat(imm as u32)
            };
            w!(zip(ra!(), cnt, |a, c| {
                let c = c.wrapping_neg() & 0x3f;
                if c > 31 {
                    0
                } else {
                    a >> c
                }
            }))
        }
        Rotma | Rotmai => {
            let cnt = if inst.op == Rotma {
                rb!()
            } else {
                splat(imm as u32)
            };
            w!(zip(ra!(), cnt, |a, c| {
                let c = c.wrapping_neg() & 0x3f;
                ((a as i32) >> c.min(31)) as u32
            }))
        }
        Rothm | Rothmi => {
            let cnt = if inst.op == Rothm {
                rb!()
            } else {
                splat_h(imm as u16)
            };
            w!(halves(ra!(), cnt, |a, c| {
                let c = c.wrapping_neg() & 0x1f;
                if c > 15 {
                    0
                } else {
                    a >> c
                }
            }))
        }
        Rotmah | Rotmahi => {
            let cnt = if inst.op == Rotmah {
                rb!()
            } else {
                splat_h(imm as u16)
            };
            w!(halves(ra!(), cnt, |a, c| {
                let c = c.wrapping_neg() & 0x1f;
                ((a as i16) >> c.min(15)) as u16
            }))
        }
        // ---- quadword shifts and rotates
        Shlqbi | Shlqbii => {
            let c = if inst.op == Shlqbi {
                rb!()[0]
            } else {
                imm as u32
            } & 7;
            w!(from_u128(to_u128(ra!()) << c))
        }
        Shlqby | Shlqbyi | Shlqbybi => {
            let c = match inst.op {
                Shlqby => rb!()[0] & 0x1f,
                Shlqbyi => imm as u32 & 0x1f,
                _ => (rb!()[0] >> 3) & 0x1f,
            };
            w!(if c > 15 {
                [0; 4]
            } else {
                from_u128(to_u128(ra!()) << (8 * c))
            })
        }
        Rotqbi | Rotqbii => {
            let c = if inst.op == Rotqbi {
                rb!()[0]
            } else {
                imm as u32
            } & 7;
            w!(from_u128(to_u128(ra!()).rotate_left(c)))
        }
        Rotqby | Rotqbyi | Rotqbybi => {
            let c = match inst.op {
                Rotqby => rb!()[0] & 0xf,
                Rotqbyi => imm as u32 & 0xf,
                _ => (rb!()[0] >> 3) & 0xf,
            };
            w!(from_u128(to_u128(ra!()).rotate_left(8 * c)))
        }
        Rotqmbi | Rotqmbii => {
            let c = if inst.op == Rotqmbi {
                rb!()[0]
            } else {
                imm as u32
            }
            .wrapping_neg()
                & 7;
            w!(from_u128(to_u128(ra!()) >> c))
        }
        Rotqmby | Rotqmbyi | Rotqmbybi => {
            let c = match inst.op {
                Rotqmby => rb!()[0].wrapping_neg() & 0x1f,
                Rotqmbyi => (imm as u32).wrapping_neg() & 0x1f,
                _ => ((rb!()[0] >> 3).wrapping_neg()) & 0x1f,
            };
            w!(if c > 15 {
                [0; 4]
            } else {
                from_u128(to_u128(ra!()) >> (8 * c))
            })
        }
        // ---- gather and form select masks
        Gb => w!([
            {
                let a = ra!();
                (0..4).fold(0, |m, i| m | ((a[i] & 1) << (3 - i)))
            },
            0,
            0,
            0
        ]),
        Gbh => {
            let mut m = 0;
            for i in 0..4 {
                m |= ((ra!()[i] >> 16) & 1) << (7 - 2 * i);
                m |= (ra!()[i] & 1) << (6 - 2 * i);
            }
            w!([m, 0, 0, 0])
        }
        Gbb => {
            let b = bytes_of(ra!());
            w!([
                (0..16).fold(0, |m, i| m | (((b[i] & 1) as u32) << (15 - i))),
                0,
                0,
                0,
            ])
        }
        Fsm => {
            let m = ra!()[0];
            w!([0, 1, 2, 3].map(|i| mask(m & (8 >> i) != 0)))
        }
        Fsmh => {
            let m = ra!()[0];
            w!([0, 1, 2, 3].map(|i| {
                let hi = if m & (0x80 >> (2 * i)) != 0 {
                    0xffff0000
                } else {
                    0
                };
                let lo = if m & (0x40 >> (2 * i)) != 0 {
                    0xffff
                } else {
                    0
                };
                hi | lo
            }))
        }
        Fsmb => {
            let m = ra!()[0];
            let mut b = [0u8; 16];
            for (i, byte) in b.iter_mut().enumerate() {
                *byte = if m & (0x8000 >> i) != 0 { 0xff } else { 0 };
            }
            w!(from_bytes(b))
        }
        Cbd | Chd | Cwd | Cdd | Cbx | Chx | Cwx | Cdx => {
            let t = match inst.op {
                Cbd | Chd | Cwd | Cdd => ra!()[0].wrapping_add(imm as u32),
                _ => ra!()[0].wrapping_add(rb!()[0]),
            };
            let size = match inst.op {
                Cbd | Cbx => 1,
                Chd | Chx => 2,
                Cwd | Cwx => 4,
                _ => 8,
            };
            w!(insertion_mask(t, size))
        }
        // ---- single precision
        Fa => {
            let (a, b) = (ra!(), rb!());
            w!(sp4v::<SP_FA, TRUNCATING>(a, b, b).unwrap_or_else(|| fl2(
                core,
                a,
                b,
                float::fa_flags
            )))
        }
        Fs => {
            let (a, b) = (ra!(), rb!());
            w!(sp4v::<SP_FS, TRUNCATING>(a, b, b).unwrap_or_else(|| fl2(
                core,
                a,
                b,
                float::fs_flags
            )))
        }
        Fm => {
            let (a, b) = (ra!(), rb!());
            w!(sp4v::<SP_FM, TRUNCATING>(a, b, b).unwrap_or_else(|| fl2(
                core,
                a,
                b,
                float::fm_flags
            )))
        }
        Fma => {
            let (a, b, c) = (ra!(), rb!(), rc!());
            w!(sp4v::<SP_FMA, TRUNCATING>(a, b, c).unwrap_or_else(|| fl3(
                core,
                a,
                b,
                c,
                float::fma_flags
            )))
        }
        Fms => {
            let (a, b, c) = (ra!(), rb!(), rc!());
            w!(sp4v::<SP_FMS, TRUNCATING>(a, b, c).unwrap_or_else(|| fl3(
                core,
                a,
                b,
                c,
                float::fms_flags
            )))
        }
        Fnms => {
            let (a, b, c) = (ra!(), rb!(), rc!());
            w!(sp4v::<SP_FNMS, TRUNCATING>(a, b, c).unwrap_or_else(|| fl3(
                core,
                a,
                b,
                c,
                float::fnms_flags
            )))
        }
        Fceq => w!(zip(ra!(), rb!(), |a, b| mask(float::fceq(a, b)))),
        Fcgt => w!(zip(ra!(), rb!(), |a, b| mask(float::fcgt(a, b)))),
        Fcmeq => w!(zip(ra!(), rb!(), |a, b| mask(float::fcmeq(a, b)))),
        Fcmgt => w!(zip(ra!(), rb!(), |a, b| mask(float::fcmgt(a, b)))),
        Frest => {
            let f = &mut core.fpscr;
            {
                let a = ra!();
                w!([0, 1, 2, 3].map(|i| float::frest_flags(a[i], f, i)))
            }
        }
        Frsqest => {
            let f = &mut core.fpscr;
            {
                let a = ra!();
                w!([0, 1, 2, 3].map(|i| float::frsqest_flags(a[i], f, i)))
            }
        }
        Fi => w!(zip(ra!(), rb!(), float::fi)),
        Cflts => w!(map(ra!(), |a| float::cflts(a, imm as u32))),
        Cfltu => w!(map(ra!(), |a| float::cfltu(a, imm as u32))),
        Csflt => {
            let f = &mut core.fpscr;
            {
                let a = ra!();
                w!([0, 1, 2, 3].map(|i| float::csflt_flags(a[i], imm as u32, f, i)))
            }
        }
        Cuflt => {
            let f = &mut core.fpscr;
            {
                let a = ra!();
                w!([0, 1, 2, 3].map(|i| float::cuflt_flags(a[i], imm as u32, f, i)))
            }
        }
        // ---- double precision
        Dfa | Dfs | Dfm => {
            let (a, b) = (dwords(ra!()), dwords(rb!()));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfa => float::dfa,
                Dfs => float::dfs,
                _ => float::dfm,
            };
            w!(from_dwords([op(a[0], b[0], f, 0), op(a[1], b[1], f, 1)]))
        }
        Dfma | Dfms | Dfnms | Dfnma => {
            let (a, b, t) = (dwords(ra!()), dwords(rb!()), dwords(rt_old!()));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfma => float::dfma,
                Dfms => float::dfms,
                Dfnms => float::dfnms,
                _ => float::dfnma,
            };
            w!(from_dwords([
                op(a[0], b[0], t[0], f, 0),
                op(a[1], b[1], t[1], f, 1),
            ]))
        }
        Fesd => {
            let f = &mut core.fpscr;
            w!(from_dwords([
                float::fesd(ra!()[0], f, 0),
                float::fesd(ra!()[2], f, 1),
            ]))
        }
        Frds => {
            let a = dwords(ra!());
            let f = &mut core.fpscr;
            w!([float::frds(a[0], f, 0), 0, float::frds(a[1], f, 1), 0])
        }
        Dfceq | Dfcmeq | Dfcgt | Dfcmgt => {
            let (a, b) = (dwords(ra!()), dwords(rb!()));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfceq => float::dfceq,
                Dfcmeq => float::dfcmeq,
                Dfcgt => float::dfcgt,
                _ => float::dfcmgt,
            };
            let m0 = op(a[0], b[0], f, 0);
            let m1 = op(a[1], b[1], f, 1);
            w!(from_dwords([
                if m0 { u64::MAX } else { 0 },
                if m1 { u64::MAX } else { 0 },
            ]))
        }
        Dftsv => {
            let a = dwords(ra!());
            let u = imm as u32 & 0x7f;
            w!(from_dwords(a.map(|x| {
                if float::dftsv(x, u) {
                    u64::MAX
                } else {
                    0
                }
            })))
        }
        Fscrrd => w!(core.fpscr.read()),
        Fscrwr => {
            core.fpscr.write(ra!());
        }
        // ---- branches
        Br | Bra | Brsl | Brasl => {
            let target = if matches!(inst.op, Br | Brsl) {
                pc.wrapping_add((imm << 2) as u32)
            } else {
                (imm << 2) as u32
            } & LS_MASK
                & !3;
            effect = Effect::Branch {
                taken: true,
                target,
            };
            if matches!(inst.op, Brsl | Brasl) {
                w!([next, 0, 0, 0])
            }
        }
        Brz | Brnz | Brhz | Brhnz => {
            let t = rt_old!()[0];
            let taken = match inst.op {
                Brz => t == 0,
                Brnz => t != 0,
                Brhz => t & 0xffff == 0,
                _ => t & 0xffff != 0,
            };
            effect = Effect::Branch {
                taken,
                target: pc.wrapping_add((imm << 2) as u32) & LS_MASK & !3,
            };
        }
        Bi | Bisl | Biz | Binz | Bihz | Bihnz | Iret | Bisled => {
            if inst.op == Bisled && !core.event_pending_known {
                // The event state lives in the SPU around the core: let it decide.
                return Effect::Channel;
            }
            let fb = inst.feature_bits();
            if fb & 0x20 != 0 {
                core.interrupts_enabled = false;
            } else if fb & 0x10 != 0 {
                core.interrupts_enabled = true;
            }
            let t = rt_old!()[0];
            let (taken, target) = match inst.op {
                Iret => (true, core.srr0),
                Bisled => (core.event_pending, ra!()[0]),
                Biz => (t == 0, ra!()[0]),
                Binz => (t != 0, ra!()[0]),
                Bihz => (t & 0xffff == 0, ra!()[0]),
                Bihnz => (t & 0xffff != 0, ra!()[0]),
                _ => (true, ra!()[0]),
            };
            effect = Effect::Branch {
                taken,
                target: target & LS_MASK & !3,
            };
            if matches!(inst.op, Bisl | Bisled) {
                w!([next, 0, 0, 0])
            }
        }
        Hbr | Hbra | Hbrr => {
            if inst.feature_bits() & 0x40 != 0 && inst.op == Hbr {
                return Effect::Next; // hbrp: an instruction-fetch request
            }
            let branch = pc.wrapping_add((inst.hint_offset() << 2) as u32) & LS_MASK;
            let target = match inst.op {
                Hbr => ra!()[0],
                Hbra => (imm << 2) as u32,
                _ => pc.wrapping_add((imm << 2) as u32),
            } & LS_MASK
                & !3;
            if inst.op == Hbr {
                core.hint_target = target;
            }
            return Effect::Hint { branch, target };
        }
        // ---- halts and stops
        Heq | Heqi | Hgt | Hgti | Hlgt | Hlgti => {
            let a = ra!()[0];
            let b = if matches!(inst.op, Heq | Hgt | Hlgt) {
                rb!()[0]
            } else {
                imm as u32
            };
            let halt = match inst.op {
                Heq | Heqi => a == b,
                Hgt | Hgti => (a as i32) > (b as i32),
                _ => a > b,
            };
            return if halt { Effect::Halt } else { Effect::Next };
        }
        Stop | Stopd => return Effect::Stop((inst.word & 0x3fff) as u16),
        Nop | Lnop | Sync | Dsync => {}
        Mfspr => w!([0; 4]),
        Mtspr => {}
        Wrch if is_mfc_param_write(inst) => core.mfc.set(inst.ra, rt_old!()[0]),
        Rdch | Wrch | Rchcnt => return Effect::Channel,
        Unknown => return Effect::Illegal,
    }
    effect
}

// Four-lane fast path for the single-precision arithmetic. On x86_64 it is the host's
// arithmetic with rounding toward zero ([`sp4_truncating`]); elsewhere it computes in f64:
// with every operand normal (exponent 1..254), f64 holds each operand and each product
// exactly, and an error-free sum (TwoSum) gives the exact result as `s + err` with
// |err| <= ulp(s)/2. Truncating that toward zero to 24 bits is truncating `s`, except when
// `s` is itself a single-precision value and `err` points toward zero: then the result is
// the next single toward zero. A result outside the normal range (overflow, underflow,
// exponent 255) and any lane with a zero, denormal or exponent-255 operand send all four
// lanes to `float`'s exact per-lane functions, which also raise the flags; on the fast path
// no flag can arise.

#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn sp_normal(x: u32) -> bool {
    ((x >> 23) & 0xff).wrapping_sub(1) < 254
}
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn normal2(a: u32, b: u32, _: u32) -> bool {
    sp_normal(a) & sp_normal(b)
}
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn normal3(a: u32, b: u32, c: u32) -> bool {
    sp_normal(a) & sp_normal(b) & sp_normal(c)
}
/// Knuth's TwoSum: `s = fl(a + b)` and `err` with `s + err == a + b` exactly.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
#[inline(always)]
fn sp4(
    a: Reg,
    b: Reg,
    c: Reg,
    ok: impl Fn(u32, u32, u32) -> bool,
    f: impl Fn(f64, f64, f64) -> (f64, f64),
) -> Option<Reg> {
    let mut out = [0u32; 4];
    let mut good = true;
    for i in 0..4 {
        let x = f32::from_bits(a[i]) as f64;
        let y = f32::from_bits(b[i]) as f64;
        let z = f32::from_bits(c[i]) as f64;
        let (r, err) = f(x, y, z);
        let bits = r.to_bits();
        let e = ((bits >> 52) & 0x7ff) as i32 - 1023 + 127;
        let zero = r == 0.0;
        let v = ((bits >> 63) as u32) << 31
            | (e as u32 & 0xff) << 23
            | ((bits >> 29) as u32 & 0x7f_ffff);
        let on_grid = bits & 0x1fff_ffff == 0;
        let toward_zero = (err != 0.0) & ((err < 0.0) != (r < 0.0));
        let v = v.wrapping_sub((on_grid & toward_zero) as u32);
        good &= ok(a[i], b[i], c[i]) & (zero | ((((e - 1) as u32) < 254) & (v & 0x7f80_0000 != 0)));
        out[i] = if zero { 0 } else { v };
    }
    good.then_some(out)
}

/// Operation selectors of [`sp4v`].
const SP_FA: u8 = 0;
const SP_FS: u8 = 1;
const SP_FM: u8 = 2;
const SP_FMA: u8 = 3;
const SP_FMS: u8 = 4;
const SP_FNMS: u8 = 5;

/// MXCSR with every exception masked and rounding toward zero, the SPU's truncation (and
/// no flush-to-zero or denormals-are-zero: the fast path's range checks see denormals).
#[cfg(target_arch = "x86_64")]
static MXCSR_TRUNCATE: u32 = 0x7f80;

/// While held, the host's floating-point unit truncates (MXCSR as [`MXCSR_TRUNCATE`]), so
/// the single-precision fast path ([`execute_in`] with `TRUNCATING`) needs no MXCSR writes
/// of its own; the previous MXCSR comes back with [`TruncatingFloats::release`]. Only code whose host
/// floating point is exact or inline assembly runs while it is held: the core's fast
/// loops, between channel instructions (the float unit's other paths compute in f64 only
/// where the result is exact, and in integers otherwise).
pub(crate) struct TruncatingFloats {
    #[cfg(target_arch = "x86_64")]
    saved: u32,
}

impl TruncatingFloats {
    #[inline(always)]
    pub(crate) fn hold() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            let mut saved = 0u32;
            // SAFETY: stores MXCSR to a local and loads a constant into it; the only
            // effect is the rounding mode and exception masks this guard exists to set.
            unsafe {
                core::arch::asm!(
                    "stmxcsr [{s}]",
                    "ldmxcsr [{t}]",
                    s = in(reg) &mut saved as *mut u32,
                    t = in(reg) &MXCSR_TRUNCATE as *const u32,
                    options(nostack, preserves_flags),
                );
            }
            TruncatingFloats { saved }
        }
        #[cfg(not(target_arch = "x86_64"))]
        TruncatingFloats {}
    }
}

impl TruncatingFloats {
    /// Sets MXCSR back (explicitly, not in `Drop`: a cleanup path for unwinding would cost
    /// the fast loops registers; a panic in them ends the simulation anyway).
    #[inline(always)]
    pub(crate) fn release(self) {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: restores the MXCSR value saved by `hold`.
        unsafe {
            core::arch::asm!(
                "ldmxcsr [{s}]",
                s = in(reg) &self.saved as *const u32,
                options(nostack, preserves_flags, readonly),
            );
        }
    }
}

/// [`sp4`] for operation `K` on x86_64: the host's own single-precision arithmetic with
/// rounding toward zero is the SPU's truncation whenever operands and result are normal,
/// so the operation runs in one instruction (an FMA3 fused multiply-add where the CPU has
/// one; otherwise the exact product in double precision, then the sum truncated twice,
/// which truncates once) with MXCSR set to truncate: by the fast loops for as long as
/// they run (`TRUNCATING`), else around the operation. The arithmetic is inline assembly
/// so the compiler never moves or folds it under an assumed rounding mode. Lanes are declined
/// as in [`sp4`], and also a result of the largest magnitude (it may be a truncated
/// overflow) and a zero from the multiplying forms (it may be an underflow).
#[inline(always)]
fn sp4v<const K: u8, const TRUNCATING: bool>(a: Reg, b: Reg, c: Reg) -> Option<Reg> {
    #[cfg(target_arch = "x86_64")]
    {
        // SAFETY: SSE2 is part of the x86_64 baseline; the FMA3 form runs only where the
        // CPU reports FMA.
        unsafe { sp4_truncating::<K, TRUNCATING>(a, b, c, std::is_x86_feature_detected!("fma")) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        match K {
            SP_FA => sp4(a, b, c, normal2, |x, y, _| two_sum(x, y)),
            SP_FS => sp4(a, b, c, normal2, |x, y, _| two_sum(x, -y)),
            SP_FM => sp4(a, b, c, normal2, |x, y, _| (x * y, 0.0)),
            SP_FMA => sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, z)),
            SP_FMS => sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, -z)),
            _ => sp4(a, b, c, normal3, |x, y, z| two_sum(z, -(x * y))),
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn sp4_truncating<const K: u8, const TRUNCATING: bool>(
    a: Reg,
    b: Reg,
    c: Reg,
    fma3: bool,
) -> Option<Reg> {
    use core::arch::asm;
    use core::arch::x86_64::*;
    let va = _mm_loadu_si128(a.as_ptr() as *const __m128i);
    let vb = _mm_loadu_si128(b.as_ptr() as *const __m128i);
    let vc = _mm_loadu_si128(c.as_ptr() as *const __m128i);
    // Exponent field 1..254: (bits & exponent) + one exponent step lies in
    // 0x0100_0000..=0x7f80_0000, signed-greater than 0x00ff_ffff (255 wraps negative).
    let normal = |v: __m128i| {
        let t = _mm_add_epi32(
            _mm_and_si128(v, _mm_set1_epi32(0x7f80_0000)),
            _mm_set1_epi32(0x0080_0000),
        );
        _mm_cmpgt_epi32(t, _mm_set1_epi32(0x00ff_ffff))
    };
    // A zero operand (±0, not a denormal, which raises a flag) is an operand as well.
    let zero = |v: __m128i| {
        _mm_cmpeq_epi32(
            _mm_and_si128(v, _mm_set1_epi32(0x7fff_ffff)),
            _mm_setzero_si128(),
        )
    };
    let (zero_a, zero_b) = (zero(va), zero(vb));
    let mut ok = _mm_and_si128(
        _mm_or_si128(normal(va), zero_a),
        _mm_or_si128(normal(vb), zero_b),
    );
    if K >= SP_FMA {
        ok = _mm_and_si128(ok, _mm_or_si128(normal(vc), zero(vc)));
    }
    if _mm_movemask_ps(_mm_castsi128_ps(ok)) != 0xf {
        return None;
    }
    let (fa, fb, fc) = (
        _mm_castsi128_ps(va),
        _mm_castsi128_ps(vb),
        _mm_castsi128_ps(vc),
    );
    // Outside the fast loops, MXCSR is set to truncate around the operation.
    let held = (!TRUNCATING).then(TruncatingFloats::hold);
    macro_rules! binary {
        ($template:expr) => {{
            let mut x = fa;
            asm!(
                $template,
                x = inout(xmm_reg) x,
                y = in(xmm_reg) fb,
                options(nostack, preserves_flags, nomem),
            );
            x
        }};
    }
    // With FMA3 (and so AVX) the VEX forms: a legacy SSE instruction inside code that uses
    // the upper halves of the vector registers costs a state transition.
    macro_rules! one {
        ($op:literal, $vex:literal) => {
            if fma3 {
                binary!(concat!($vex, " {x}, {x}, {y}"))
            } else {
                binary!(concat!($op, " {x}, {y}"))
            }
        };
    }
    macro_rules! fused {
        ($op:literal) => {{
            let mut x = fa;
            asm!(
                concat!($op, " {x}, {y}, {z}"),
                x = inout(xmm_reg) x,
                y = in(xmm_reg) fb,
                z = in(xmm_reg) fc,
                options(nostack, preserves_flags, nomem),
            );
            x
        }};
    }
    // Products of singles are exact in double precision; the sum is truncated to double
    // and then to single, which is truncating once.
    macro_rules! via_double {
        ($sum:literal) => {{
            let mut lo = fa;
            asm!(
                "pshufd {hi}, {lo}, 0xee",
                "cvtps2pd {lo}, {lo}",
                "cvtps2pd {hi}, {hi}",
                "cvtps2pd {p}, {y}",
                "mulpd {lo}, {p}",
                "pshufd {p}, {y}, 0xee",
                "cvtps2pd {p}, {p}",
                "mulpd {hi}, {p}",
                "cvtps2pd {p}, {z}",
                "pshufd {q}, {z}, 0xee",
                "cvtps2pd {q}, {q}",
                $sum,
                "cvtpd2ps {lo}, {lo}",
                "cvtpd2ps {hi}, {hi}",
                "movlhps {lo}, {hi}",
                lo = inout(xmm_reg) lo,
                hi = out(xmm_reg) _,
                p = out(xmm_reg) _,
                q = out(xmm_reg) _,
                y = in(xmm_reg) fb,
                z = in(xmm_reg) fc,
                options(nostack, preserves_flags, nomem),
            );
            lo
        }};
    }
    let r: __m128 = match K {
        SP_FA => one!("addps", "vaddps"),
        SP_FS => one!("subps", "vsubps"),
        SP_FM => one!("mulps", "vmulps"),
        SP_FMA if fma3 => fused!("vfmadd213ps"),
        SP_FMS if fma3 => fused!("vfmsub213ps"),
        SP_FNMS if fma3 => fused!("vfnmadd213ps"),
        SP_FMA => via_double!("addpd {lo}, {p}\n addpd {hi}, {q}"),
        SP_FMS => via_double!("subpd {lo}, {p}\n subpd {hi}, {q}"),
        _ => via_double!("subpd {p}, {lo}\n subpd {q}, {hi}\n movapd {lo}, {p}\n movapd {hi}, {q}"),
    };
    if let Some(held) = held {
        held.release();
    }
    let v = _mm_castps_si128(r);
    // A normal single other than the largest magnitude; or a zero, which the SPU gives as
    // +0, where it cannot be an underflow: from an addition (only an exact cancellation
    // or zero operands give one) or from a product with a zero factor.
    let mag = _mm_and_si128(v, _mm_set1_epi32(0x7fff_ffff));
    let result_zero = _mm_cmpeq_epi32(mag, _mm_setzero_si128());
    let zero_ok = if K <= SP_FS {
        _mm_set1_epi32(-1)
    } else {
        _mm_or_si128(zero_a, zero_b)
    };
    let good = _mm_or_si128(
        _mm_and_si128(
            _mm_cmpgt_epi32(mag, _mm_set1_epi32(0x007f_ffff)),
            _mm_cmplt_epi32(mag, _mm_set1_epi32(0x7f7f_ffff)),
        ),
        _mm_and_si128(result_zero, zero_ok),
    );
    if _mm_movemask_ps(_mm_castsi128_ps(good)) != 0xf {
        return None;
    }
    let mut out = [0u32; 4];
    _mm_storeu_si128(
        out.as_mut_ptr() as *mut __m128i,
        _mm_andnot_si128(result_zero, v),
    );
    Some(out)
}

#[cold]
#[inline(never)]
fn fl2(
    core: &mut Core,
    a: Reg,
    b: Reg,
    f: impl Fn(u32, u32, &mut float::Fpscr, usize) -> u32,
) -> Reg {
    let s = &mut core.fpscr;
    [
        f(a[0], b[0], s, 0),
        f(a[1], b[1], s, 1),
        f(a[2], b[2], s, 2),
        f(a[3], b[3], s, 3),
    ]
}

#[cold]
#[inline(never)]
fn fl3(
    core: &mut Core,
    a: Reg,
    b: Reg,
    c: Reg,
    f: impl Fn(u32, u32, u32, &mut float::Fpscr, usize) -> u32,
) -> Reg {
    let s = &mut core.fpscr;
    [
        f(a[0], b[0], c[0], s, 0),
        f(a[1], b[1], c[1], s, 1),
        f(a[2], b[2], c[2], s, 2),
        f(a[3], b[3], c[3], s, 3),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(x: f32) -> u32 {
        x.to_bits()
    }

    /// Fast-path cases checked by hand (all operands normal, results normal).
    fn hand_cases() -> [(u32, u32, u32); 6] {
        let p60 = f(2f32.powi(-30));
        [
            // 1 - 2^-60: f64 rounds to 1.0 (a single), the error points toward zero, so
            // truncation gives the single just below 1.0 (0x3f7fffff).
            (p60, p60 | 0x8000_0000, f(1.0)),
            // 1 + 2^-60 truncates to 1.0.
            (p60, p60, f(1.0)),
            // -1 + 2^-60 truncates toward zero: -0x3f7fffff.
            (p60, p60, f(-1.0)),
            // An exact zero: +0.
            (f(1.5), f(2.0), f(-3.0)),
            (f(3.0e30), f(2.5e7), f(-1.0)),
            (0x3fffffff, 0x3fffffff, 0x3f800001),
        ]
    }

    /// Random single-precision operands for the fast-path tests: a wide exponent spread
    /// (from `low`, `span` values), short and full mantissas, and some zeros, denormals and
    /// exponent-255 and exponent-254 values.
    struct Singles {
        state: u64,
        low: u32,
        span: u64,
    }

    impl Singles {
        fn new(seed: u64, low: u32, span: u64) -> Self {
            Singles {
                state: seed,
                low,
                span,
            }
        }

        fn next(&mut self) -> u64 {
            let x = &mut self.state;
            *x ^= *x << 13;
            *x ^= *x >> 7;
            *x ^= *x << 17;
            *x
        }

        fn single(&mut self) -> u32 {
            let r = self.next();
            let sign = (r as u32) & 0x8000_0000;
            let exp = match (r >> 40) % 16 {
                0 => 0,
                1 => 255,
                2 => 1,
                3 => 254,
                4 => return sign, // ±0
                _ => self.low + ((r >> 8) % self.span) as u32,
            };
            let mant = ((r >> 16) as u32 & 0x7f_ffff) & (0x7f_ffff << ((r >> 48) % 24));
            sign | exp << 23 | mant
        }

        fn reg(&mut self) -> Reg {
            [0; 4].map(|_| self.single())
        }
    }

    /// The fast path must take these cases (all operands normal, result normal) and agree
    /// with the float unit's exact functions bit for bit.
    #[test]
    fn four_lane_fast_path_matches_the_exact_functions() {
        let p60 = f(2f32.powi(-30));
        for (a, b, c) in hand_cases() {
            let ra = [a; 4];
            let rb = [b; 4];
            let rc = [c; 4];
            let fma = sp4(ra, rb, rc, normal3, |x, y, z| two_sum(x * y, z)).expect("fast");
            assert_eq!(fma[0], float::fma(a, b, c), "fma {a:#x} {b:#x} {c:#x}");
            let fms = sp4(ra, rb, rc, normal3, |x, y, z| two_sum(x * y, -z)).expect("fast");
            assert_eq!(fms[0], float::fms(a, b, c), "fms {a:#x} {b:#x} {c:#x}");
            let fnms = sp4(ra, rb, rc, normal3, |x, y, z| two_sum(z, -(x * y))).expect("fast");
            assert_eq!(fnms[0], float::fnms(a, b, c), "fnms {a:#x} {b:#x} {c:#x}");
            let fa = sp4(ra, rc, rc, normal2, |x, y, _| two_sum(x, y)).expect("fast");
            assert_eq!(fa[0], float::fa(a, c), "fa {a:#x} {c:#x}");
            let fs = sp4(ra, rc, rc, normal2, |x, y, _| two_sum(x, -y)).expect("fast");
            assert_eq!(fs[0], float::fs(a, c), "fs {a:#x} {c:#x}");
        }
        assert_eq!(
            sp4(
                [p60; 4],
                [p60 | 0x8000_0000; 4],
                [f(1.0); 4],
                normal3,
                |x, y, z| { two_sum(x * y, z) }
            )
            .unwrap()[0],
            0x3f7f_ffff
        );
    }

    #[test]
    fn four_lane_fast_path_declines_what_it_cannot_do_exactly() {
        // A zero or denormal operand, an exponent-255 operand, a result below the normal
        // range, a result that rounds up to exponent 255.
        let min = 0x0080_0000; // 2^-126
        let declined = [
            (0u32, f(1.0)),
            (0x0000_0001, f(1.0)),
            (0x7f80_0000, f(1.0)),
            (min, f(0.5)),
            (0x7f7f_ffff, f(2.0)),
        ];
        for (a, b) in declined {
            assert!(
                sp4([a; 4], [b; 4], [b; 4], normal2, |x, y, _| (x * y, 0.0)).is_none(),
                "{a:#x} * {b:#x}"
            );
        }
        // Subtracting down to exactly the smallest normal stays on the fast path; one step
        // further (a decrement below it) does not.
        let just_above = min + 1;
        assert_eq!(
            sp4([just_above; 4], [min; 4], [0; 4], normal2, |x, y, _| {
                two_sum(x, -y)
            }),
            None,
            "the difference 2^-149 is far below the normal range"
        );
    }

    /// 200k random operand triples (wide exponent spread, short and full mantissas, some
    /// zeros, denormals and exponent-255 values): whatever the fast path returns equals
    /// the float unit's exact functions.
    #[test]
    fn four_lane_fast_path_agrees_on_random_operands() {
        let mut singles = Singles::new(0x2545_f491_4f6c_dd1d, 90, 76);
        let mut fast = 0;
        for _ in 0..50_000 {
            let a: Reg = singles.reg();
            let b: Reg = singles.reg();
            let c: Reg = singles.reg();
            type Exact = fn(u32, u32, u32) -> u32;
            let ops: [(Option<Reg>, Exact); 6] = [
                (sp4(a, b, c, normal2, |x, y, _| two_sum(x, y)), |a, b, _| {
                    float::fa(a, b)
                }),
                (
                    sp4(a, b, c, normal2, |x, y, _| two_sum(x, -y)),
                    |a, b, _| float::fs(a, b),
                ),
                (sp4(a, b, c, normal2, |x, y, _| (x * y, 0.0)), |a, b, _| {
                    float::fm(a, b)
                }),
                (
                    sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, z)),
                    float::fma,
                ),
                (
                    sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, -z)),
                    float::fms,
                ),
                (
                    sp4(a, b, c, normal3, |x, y, z| two_sum(z, -(x * y))),
                    float::fnms,
                ),
            ];
            for (k, (got, exact)) in ops.iter().enumerate() {
                if let Some(r) = got {
                    fast += 1;
                    for i in 0..4 {
                        assert_eq!(
                            r[i],
                            exact(a[i], b[i], c[i]),
                            "op {k} lane {i}: {a:x?} {b:x?} {c:x?}"
                        );
                    }
                }
            }
        }
        assert!(fast > 20_000, "the fast path ran {fast} times");
    }

    /// The x86_64 path (host arithmetic between MXCSR writes), in both its fused
    /// (FMA3) and its double-precision forms, on the hand cases above and 200k random
    /// triples: whatever it returns equals the float unit's exact functions, and it takes
    /// the cases a real kernel has.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn truncating_host_path_agrees_with_the_exact_functions() {
        let mut singles = Singles::new(0x2545_f491_4f6c_dd1d, 90, 76);
        let p60 = f(2f32.powi(-30));
        let mut triples: Vec<(Reg, Reg, Reg)> = hand_cases()
            .iter()
            .map(|&(a, b, c)| ([a; 4], [b; 4], [c; 4]))
            .collect();
        for _ in 0..50_000 {
            let a: Reg = singles.reg();
            let b: Reg = singles.reg();
            let c: Reg = singles.reg();
            triples.push((a, b, c));
        }
        type Exact = fn(u32, u32, u32) -> u32;
        let fused = [false, std::is_x86_feature_detected!("fma")];
        let mut fast = [0usize; 6];
        for &(a, b, c) in &triples {
            for fma3 in fused {
                // SAFETY: the FMA3 form only where the CPU has it.
                let ops: [(Option<Reg>, Exact); 6] = unsafe {
                    [
                        (sp4_truncating::<SP_FA, false>(a, b, c, fma3), |a, b, _| {
                            float::fa(a, b)
                        }),
                        (sp4_truncating::<SP_FS, false>(a, b, c, fma3), |a, b, _| {
                            float::fs(a, b)
                        }),
                        (sp4_truncating::<SP_FM, false>(a, b, c, fma3), |a, b, _| {
                            float::fm(a, b)
                        }),
                        (sp4_truncating::<SP_FMA, false>(a, b, c, fma3), float::fma),
                        (sp4_truncating::<SP_FMS, false>(a, b, c, fma3), float::fms),
                        (sp4_truncating::<SP_FNMS, false>(a, b, c, fma3), float::fnms),
                    ]
                };
                // The same under a held truncating MXCSR (the fast loops' form).
                let held: [Option<Reg>; 6] = {
                    let truncating = TruncatingFloats::hold();
                    // SAFETY: as above.
                    let held = unsafe {
                        [
                            sp4_truncating::<SP_FA, true>(a, b, c, fma3),
                            sp4_truncating::<SP_FS, true>(a, b, c, fma3),
                            sp4_truncating::<SP_FM, true>(a, b, c, fma3),
                            sp4_truncating::<SP_FMA, true>(a, b, c, fma3),
                            sp4_truncating::<SP_FMS, true>(a, b, c, fma3),
                            sp4_truncating::<SP_FNMS, true>(a, b, c, fma3),
                        ]
                    };
                    truncating.release();
                    held
                };
                for (k, h) in held.iter().enumerate() {
                    assert_eq!(*h, ops[k].0, "op {k} held, fma3 {fma3}");
                }
                for (k, (got, exact)) in ops.iter().enumerate() {
                    if let Some(r) = got {
                        fast[k] += 1;
                        for i in 0..4 {
                            assert_eq!(
                                r[i],
                                exact(a[i], b[i], c[i]),
                                "op {k} fma3 {fma3} lane {i}: {a:x?} {b:x?} {c:x?}"
                            );
                        }
                    }
                }
            }
        }
        // About a third of the random quadwords have four normal operands.
        assert!(
            fast.iter().all(|&n| n > 10_000),
            "fast path counts {fast:?}"
        );
        // The hand cases the fast path must take (all normal, results normal, not zero
        // for the multiplying forms): 1 - 2^-60 truncates to just below 1.0.
        // SAFETY: SSE2 only.
        let r = unsafe {
            sp4_truncating::<SP_FMA, false>([p60; 4], [p60 | 0x8000_0000; 4], [f(1.0); 4], false)
        };
        assert_eq!(r, Some([0x3f7f_ffff; 4]));
        // A cancellation to zero in an addition is +0 on the fast path; a product that
        // truncates to the largest magnitude is declined (it may be an overflow).
        let r = unsafe { sp4_truncating::<SP_FS, false>([f(1.5); 4], [f(1.5); 4], [0; 4], false) };
        assert_eq!(r, Some([0; 4]));
        let r =
            unsafe { sp4_truncating::<SP_FM, false>([0x7f7f_ffff; 4], [f(2.0); 4], [0; 4], false) };
        assert_eq!(r, None);
    }

    #[test]
    fn shufb_paths_agree() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u32
        };
        for _ in 0..20_000 {
            let a = [next(), next(), next(), next()];
            let b = [next(), next(), next(), next()];
            let c = [next(), next(), next(), next()];
            assert_eq!(
                shufb(a, b, c),
                shufb_scalar(a, b, c),
                "{a:x?} {b:x?} {c:x?}"
            );
        }
        // Identity and the specials, by hand: control bytes 0x00..0x0f give RA, 0x10..0x1f
        // RB; 0x80, 0xc0, 0xe0 give 0x00, 0xff, 0x80.
        let a = [0x0001_0203, 0x0405_0607, 0x0809_0a0b, 0x0c0d_0e0f];
        let b = [0x1011_1213, 0x1415_1617, 0x1819_1a1b, 0x1c1d_1e1f];
        assert_eq!(shufb(a, b, a), a);
        assert_eq!(shufb(a, b, b), b);
        assert_eq!(
            shufb(a, b, [0x80c0_e01f, 0x9fdf_ff00, 0x0302_0100, 0x1312_1110]),
            [0x00ff_801f, 0x00ff_8000, 0x0302_0100, 0x1312_1110]
        );
    }

    /// The SSE2 path declines and computes exactly what the scalar path does.
    #[test]
    fn vector_and_scalar_fast_paths_agree() {
        let mut singles = Singles::new(0x0123_4567_89ab_cdef, 60, 136);
        let (mut agree, mut declined_more) = (0, 0);
        for i in 0..100_000 {
            // Mostly all-normal registers, so that the result checks are exercised.
            let pick = |v: u32| {
                if i % 4 == 0 {
                    v
                } else {
                    (v & 0x807f_ffff) | (((v >> 23) & 0xff).clamp(40, 200) << 23)
                }
            };
            let a: Reg = singles.reg().map(pick);
            let b: Reg = singles.reg().map(pick);
            let c: Reg = singles.reg().map(pick);
            let pairs = [
                (
                    sp4v::<SP_FA, false>(a, b, c),
                    sp4(a, b, c, normal2, |x, y, _| two_sum(x, y)),
                ),
                (
                    sp4v::<SP_FS, false>(a, b, c),
                    sp4(a, b, c, normal2, |x, y, _| two_sum(x, -y)),
                ),
                (
                    sp4v::<SP_FM, false>(a, b, c),
                    sp4(a, b, c, normal2, |x, y, _| (x * y, 0.0)),
                ),
                (
                    sp4v::<SP_FMA, false>(a, b, c),
                    sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, z)),
                ),
                (
                    sp4v::<SP_FMS, false>(a, b, c),
                    sp4(a, b, c, normal3, |x, y, z| two_sum(x * y, -z)),
                ),
                (
                    sp4v::<SP_FNMS, false>(a, b, c),
                    sp4(a, b, c, normal3, |x, y, z| two_sum(z, -(x * y))),
                ),
            ];
            for (k, (v, s)) in pairs.iter().enumerate() {
                // The host path may decline more (a largest-magnitude result, a zero from
                // a multiplying form) and take more (zero operands), never differ.
                if v.is_some() && s.is_some() {
                    assert_eq!(v, s, "op {k}: {a:x?} {b:x?} {c:x?}");
                    agree += 1;
                } else if s.is_some() {
                    declined_more += 1;
                }
            }
        }
        assert!(agree > 100_000, "{agree}");
        assert!(declined_more < 100, "{declined_more}");
    }
}
