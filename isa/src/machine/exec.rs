//! Bit-exact semantics of every SPU operation, as one `match` over the decoded operation.

use crate::codec::Inst;
use crate::float;
use crate::table::Op;

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

/// Architectural state the semantics act on (the channels and the MFC live outside).
pub struct Core {
    pub regs: [Reg; 128],
    pub ls: Vec<u8>,
    pub fpscr: float::Fpscr,
    pub interrupts_enabled: bool,
    pub srr0: u32,
    pub event_pending: bool,
}

/// Local store size and the mask that wraps addresses into it.
pub const LS_SIZE: usize = 256 * 1024;
pub const LS_MASK: u32 = (LS_SIZE as u32) - 1;

/// What executing one instruction did besides writing registers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Effect {
    Next,
    /// A branch instruction: where it went when taken.
    Branch {
        taken: bool,
        target: u32,
    },
    /// A quadword store to this (aligned) local-store address.
    Store {
        addr: u32,
    },
    Hint {
        branch: u32,
        target: u32,
    },
    Stop(u16),
    Halt,
    /// Channel instructions are carried out by the SPU, not here.
    Channel,
    Illegal,
}

impl Core {
    pub fn new() -> Core {
        Core {
            regs: [[0; 4]; 128],
            ls: vec![0; LS_SIZE],
            fpscr: float::Fpscr::default(),
            interrupts_enabled: false,
            srr0: 0,
            event_pending: false,
        }
    }

    #[inline]
    pub fn load_quad(&self, addr: u32) -> Reg {
        let a = (addr & LS_MASK & !15) as usize;
        let b = &self.ls[a..a + 16];
        let w = |i: usize| u32::from_be_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
        [w(0), w(1), w(2), w(3)]
    }

    #[inline]
    pub fn store_quad(&mut self, addr: u32, v: Reg) -> u32 {
        let a = (addr & LS_MASK & !15) as usize;
        for i in 0..4 {
            self.ls[a + 4 * i..a + 4 * i + 4].copy_from_slice(&v[i].to_be_bytes());
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

fn shufb(a: Reg, b: Reg, c: Reg) -> Reg {
    let (x, y, z) = (bytes_of(a), bytes_of(b), bytes_of(c));
    let mut out = [0u8; 16];
    for i in 0..16 {
        let s = z[i];
        out[i] = if s >= 0xe0 {
            0x80
        } else if s >= 0xc0 {
            0xff
        } else if s >= 0x80 {
            0
        } else {
            let k = (s & 0x1f) as usize;
            if k < 16 {
                x[k]
            } else {
                y[k - 16]
            }
        };
    }
    from_bytes(out)
}

/// Executes `inst` at `pc` on `core`. Channel instructions return [`Effect::Channel`].
#[inline]
pub fn execute(core: &mut Core, inst: Inst, pc: u32) -> Effect {
    use Op::*;
    let r = &core.regs;
    let ra = r[inst.ra as usize];
    let rb = r[inst.rb as usize];
    let rt_old = r[inst.rt as usize];
    let rc = r[inst.rc as usize];
    let imm = inst.imm;
    let i10 = imm as u32;
    let next = pc.wrapping_add(4) & LS_MASK;
    let mut effect = Effect::Next;
    let result: Option<Reg> = match inst.op {
        // ---- loads and stores
        Lqd => Some(core.load_quad(ra[0].wrapping_add((imm << 4) as u32))),
        Lqx => Some(core.load_quad(ra[0].wrapping_add(rb[0]))),
        Lqa => Some(core.load_quad((imm << 2) as u32)),
        Lqr => Some(core.load_quad(pc.wrapping_add((imm << 2) as u32))),
        Stqd | Stqx | Stqa | Stqr => {
            let addr = match inst.op {
                Stqd => ra[0].wrapping_add((imm << 4) as u32),
                Stqx => ra[0].wrapping_add(rb[0]),
                Stqa => (imm << 2) as u32,
                _ => pc.wrapping_add((imm << 2) as u32),
            };
            let a = core.store_quad(addr, rt_old);
            return Effect::Store { addr: a };
        }
        // ---- immediate loads
        Il => Some(splat(imm as u32)),
        Ilh => Some(splat_h(imm as u16)),
        Ilhu => Some(splat((imm as u32) << 16)),
        Ila => Some(splat(imm as u32 & 0x3ffff)),
        Iohl => Some(map(rt_old, |t| t | (imm as u32 & 0xffff))),
        Fsmbi => {
            let m = inst.u16();
            let mut b = [0u8; 16];
            for (i, byte) in b.iter_mut().enumerate() {
                *byte = if m & (0x8000 >> i) != 0 { 0xff } else { 0 };
            }
            Some(from_bytes(b))
        }
        // ---- integer arithmetic
        A => Some(zip(ra, rb, u32::wrapping_add)),
        Ah => Some(halves(ra, rb, u16::wrapping_add)),
        Ai => Some(map(ra, |a| a.wrapping_add(i10))),
        Ahi => Some(halves(ra, splat_h(imm as u16), u16::wrapping_add)),
        Sf => Some(zip(ra, rb, |a, b| b.wrapping_sub(a))),
        Sfh => Some(halves(ra, rb, |a, b| b.wrapping_sub(a))),
        Sfi => Some(map(ra, |a| i10.wrapping_sub(a))),
        Sfhi => Some(halves(ra, splat_h(imm as u16), |a, b| b.wrapping_sub(a))),
        Addx => Some(zip3(ra, rb, rt_old, |a, b, t| {
            a.wrapping_add(b).wrapping_add(t & 1)
        })),
        Sfx => Some(zip3(ra, rb, rt_old, |a, b, t| {
            b.wrapping_add(!a).wrapping_add(t & 1)
        })),
        Cg => Some(zip(ra, rb, |a, b| ((a as u64 + b as u64) >> 32) as u32)),
        Cgx => Some(zip3(ra, rb, rt_old, |a, b, t| {
            ((a as u64 + b as u64 + (t & 1) as u64) >> 32) as u32
        })),
        Bg => Some(zip(ra, rb, |a, b| (b >= a) as u32)),
        Bgx => Some(zip3(ra, rb, rt_old, |a, b, t| {
            if t & 1 != 0 {
                (b >= a) as u32
            } else {
                (b > a) as u32
            }
        })),
        Mpy => Some(zip(ra, rb, |a, b| {
            ((a as i16 as i32) * (b as i16 as i32)) as u32
        })),
        Mpyu => Some(zip(ra, rb, |a, b| (a & 0xffff) * (b & 0xffff))),
        Mpyi => Some(map(ra, |a| {
            ((a as i16 as i32) * (imm as i16 as i32)) as u32
        })),
        Mpyui => Some(map(ra, |a| (a & 0xffff) * (imm as u32 & 0xffff))),
        Mpya => Some(zip3(ra, rb, rc, |a, b, c| {
            ((a as i16 as i32) * (b as i16 as i32)).wrapping_add(c as i32) as u32
        })),
        Mpyh => Some(zip(ra, rb, |a, b| ((a >> 16) * (b & 0xffff)) << 16)),
        Mpys => Some(zip(ra, rb, |a, b| {
            (((a as i16 as i32) * (b as i16 as i32)) >> 16) as u32
        })),
        Mpyhh => Some(zip(ra, rb, |a, b| {
            (((a >> 16) as i16 as i32) * ((b >> 16) as i16 as i32)) as u32
        })),
        Mpyhha => Some(zip3(ra, rb, rt_old, |a, b, t| {
            (((a >> 16) as i16 as i32) * ((b >> 16) as i16 as i32)).wrapping_add(t as i32) as u32
        })),
        Mpyhhu => Some(zip(ra, rb, |a, b| (a >> 16) * (b >> 16))),
        Mpyhhau => Some(zip3(ra, rb, rt_old, |a, b, t| {
            ((a >> 16) * (b >> 16)).wrapping_add(t)
        })),
        Clz => Some(map(ra, u32::leading_zeros)),
        Cntb => Some(bytewise(ra, ra, |a, _| a.count_ones() as u8)),
        Absdb => Some(bytewise(ra, rb, |a, b| a.abs_diff(b))),
        Avgb => Some(bytewise(ra, rb, |a, b| {
            ((a as u16 + b as u16 + 1) >> 1) as u8
        })),
        Sumb => Some(zip(ra, rb, |a, b| {
            let s = |x: u32| x.to_be_bytes().iter().map(|v| *v as u32).sum::<u32>();
            (s(b) << 16) | s(a)
        })),
        Xsbh => Some(map(ra, |a| {
            let h = |x: u32| (x as u8 as i8 as i16 as u16) as u32;
            (h(a >> 16) << 16) | h(a)
        })),
        Xshw => Some(map(ra, |a| a as u16 as i16 as i32 as u32)),
        Xswd => {
            let d = dwords(ra);
            Some(from_dwords(d.map(|x| x as u32 as i32 as i64 as u64)))
        }
        // ---- logical
        And => Some(zip(ra, rb, |a, b| a & b)),
        Andc => Some(zip(ra, rb, |a, b| a & !b)),
        Andi => Some(map(ra, |a| a & i10)),
        Andhi => Some(halves(ra, splat_h(imm as u16), |a, b| a & b)),
        Andbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| a & b)),
        Or => Some(zip(ra, rb, |a, b| a | b)),
        Orc => Some(zip(ra, rb, |a, b| a | !b)),
        Ori => Some(map(ra, |a| a | i10)),
        Orhi => Some(halves(ra, splat_h(imm as u16), |a, b| a | b)),
        Orbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| a | b)),
        Orx => Some([ra[0] | ra[1] | ra[2] | ra[3], 0, 0, 0]),
        Xor => Some(zip(ra, rb, |a, b| a ^ b)),
        Xori => Some(map(ra, |a| a ^ i10)),
        Xorhi => Some(halves(ra, splat_h(imm as u16), |a, b| a ^ b)),
        Xorbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| a ^ b)),
        Nand => Some(zip(ra, rb, |a, b| !(a & b))),
        Nor => Some(zip(ra, rb, |a, b| !(a | b))),
        Eqv => Some(zip(ra, rb, |a, b| !(a ^ b))),
        Selb => Some(zip3(ra, rb, rc, |a, b, c| (c & b) | (!c & a))),
        Shufb => Some(shufb(ra, rb, rc)),
        // ---- compares
        Ceq => Some(zip(ra, rb, |a, b| mask(a == b))),
        Ceqh => Some(halves(ra, rb, |a, b| hmask(a == b))),
        Ceqb => Some(bytewise(ra, rb, |a, b| if a == b { 0xff } else { 0 })),
        Ceqi => Some(map(ra, |a| mask(a == i10))),
        Ceqhi => Some(halves(ra, splat_h(imm as u16), |a, b| hmask(a == b))),
        Ceqbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| {
            if a == b {
                0xff
            } else {
                0
            }
        })),
        Cgt => Some(zip(ra, rb, |a, b| mask((a as i32) > (b as i32)))),
        Cgth => Some(halves(ra, rb, |a, b| hmask((a as i16) > (b as i16)))),
        Cgtb => Some(bytewise(ra, rb, |a, b| {
            if (a as i8) > (b as i8) {
                0xff
            } else {
                0
            }
        })),
        Cgti => Some(map(ra, |a| mask((a as i32) > imm))),
        Cgthi => Some(halves(ra, splat_h(imm as u16), |a, b| {
            hmask((a as i16) > (b as i16))
        })),
        Cgtbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| {
            if (a as i8) > (b as i8) {
                0xff
            } else {
                0
            }
        })),
        Clgt => Some(zip(ra, rb, |a, b| mask(a > b))),
        Clgth => Some(halves(ra, rb, |a, b| hmask(a > b))),
        Clgtb => Some(bytewise(ra, rb, |a, b| if a > b { 0xff } else { 0 })),
        Clgti => Some(map(ra, |a| mask(a > i10))),
        Clgthi => Some(halves(ra, splat_h(imm as u16), |a, b| hmask(a > b))),
        Clgtbi => Some(bytewise(ra, splat_b(imm as u8), |a, b| {
            if a > b {
                0xff
            } else {
                0
            }
        })),
        // ---- word and halfword shifts and rotates
        Shl | Shli => {
            let cnt = if inst.op == Shl {
                rb
            } else {
                splat(imm as u32)
            };
            Some(zip(ra, cnt, |a, c| {
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
                rb
            } else {
                splat_h(imm as u16)
            };
            Some(halves(ra, cnt, |a, c| {
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
                rb
            } else {
                splat(imm as u32)
            };
            Some(zip(ra, cnt, |a, c| a.rotate_left(c & 0x1f)))
        }
        Roth | Rothi => {
            let cnt = if inst.op == Roth {
                rb
            } else {
                splat_h(imm as u16)
            };
            Some(halves(ra, cnt, |a, c| a.rotate_left((c & 0xf) as u32)))
        }
        Rotm | Rotmi => {
            let cnt = if inst.op == Rotm {
                rb
            } else {
                splat(imm as u32)
            };
            Some(zip(ra, cnt, |a, c| {
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
                rb
            } else {
                splat(imm as u32)
            };
            Some(zip(ra, cnt, |a, c| {
                let c = c.wrapping_neg() & 0x3f;
                ((a as i32) >> c.min(31)) as u32
            }))
        }
        Rothm | Rothmi => {
            let cnt = if inst.op == Rothm {
                rb
            } else {
                splat_h(imm as u16)
            };
            Some(halves(ra, cnt, |a, c| {
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
                rb
            } else {
                splat_h(imm as u16)
            };
            Some(halves(ra, cnt, |a, c| {
                let c = c.wrapping_neg() & 0x1f;
                ((a as i16) >> c.min(15)) as u16
            }))
        }
        // ---- quadword shifts and rotates
        Shlqbi | Shlqbii => {
            let c = if inst.op == Shlqbi { rb[0] } else { imm as u32 } & 7;
            Some(from_u128(to_u128(ra) << c))
        }
        Shlqby | Shlqbyi | Shlqbybi => {
            let c = match inst.op {
                Shlqby => rb[0] & 0x1f,
                Shlqbyi => imm as u32 & 0x1f,
                _ => (rb[0] >> 3) & 0x1f,
            };
            Some(if c > 15 {
                [0; 4]
            } else {
                from_u128(to_u128(ra) << (8 * c))
            })
        }
        Rotqbi | Rotqbii => {
            let c = if inst.op == Rotqbi { rb[0] } else { imm as u32 } & 7;
            Some(from_u128(to_u128(ra).rotate_left(c)))
        }
        Rotqby | Rotqbyi | Rotqbybi => {
            let c = match inst.op {
                Rotqby => rb[0] & 0xf,
                Rotqbyi => imm as u32 & 0xf,
                _ => (rb[0] >> 3) & 0xf,
            };
            Some(from_u128(to_u128(ra).rotate_left(8 * c)))
        }
        Rotqmbi | Rotqmbii => {
            let c = if inst.op == Rotqmbi {
                rb[0]
            } else {
                imm as u32
            }
            .wrapping_neg()
                & 7;
            Some(from_u128(to_u128(ra) >> c))
        }
        Rotqmby | Rotqmbyi | Rotqmbybi => {
            let c = match inst.op {
                Rotqmby => rb[0].wrapping_neg() & 0x1f,
                Rotqmbyi => (imm as u32).wrapping_neg() & 0x1f,
                _ => ((rb[0] >> 3).wrapping_neg()) & 0x1f,
            };
            Some(if c > 15 {
                [0; 4]
            } else {
                from_u128(to_u128(ra) >> (8 * c))
            })
        }
        // ---- gather and form select masks
        Gb => Some([(0..4).fold(0, |m, i| m | ((ra[i] & 1) << (3 - i))), 0, 0, 0]),
        Gbh => {
            let mut m = 0;
            for i in 0..4 {
                m |= ((ra[i] >> 16) & 1) << (7 - 2 * i);
                m |= (ra[i] & 1) << (6 - 2 * i);
            }
            Some([m, 0, 0, 0])
        }
        Gbb => {
            let b = bytes_of(ra);
            Some([
                (0..16).fold(0, |m, i| m | (((b[i] & 1) as u32) << (15 - i))),
                0,
                0,
                0,
            ])
        }
        Fsm => Some([0, 1, 2, 3].map(|i| mask(ra[0] & (8 >> i) != 0))),
        Fsmh => {
            let m = ra[0];
            Some([0, 1, 2, 3].map(|i| {
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
            let m = ra[0];
            let mut b = [0u8; 16];
            for (i, byte) in b.iter_mut().enumerate() {
                *byte = if m & (0x8000 >> i) != 0 { 0xff } else { 0 };
            }
            Some(from_bytes(b))
        }
        Cbd | Chd | Cwd | Cdd | Cbx | Chx | Cwx | Cdx => {
            let t = match inst.op {
                Cbd | Chd | Cwd | Cdd => ra[0].wrapping_add(imm as u32),
                _ => ra[0].wrapping_add(rb[0]),
            };
            let size = match inst.op {
                Cbd | Cbx => 1,
                Chd | Chx => 2,
                Cwd | Cwx => 4,
                _ => 8,
            };
            Some(insertion_mask(t, size))
        }
        // ---- single precision
        Fa => Some(fl2(core, ra, rb, float::fa_flags)),
        Fs => Some(fl2(core, ra, rb, float::fs_flags)),
        Fm => Some(fl2(core, ra, rb, float::fm_flags)),
        Fma => Some(fl3(core, ra, rb, rc, float::fma_flags)),
        Fms => Some(fl3(core, ra, rb, rc, float::fms_flags)),
        Fnms => Some(fl3(core, ra, rb, rc, float::fnms_flags)),
        Fceq => Some(zip(ra, rb, |a, b| mask(float::fceq(a, b)))),
        Fcgt => Some(zip(ra, rb, |a, b| mask(float::fcgt(a, b)))),
        Fcmeq => Some(zip(ra, rb, |a, b| mask(float::fcmeq(a, b)))),
        Fcmgt => Some(zip(ra, rb, |a, b| mask(float::fcmgt(a, b)))),
        Frest => {
            let f = &mut core.fpscr;
            Some([0, 1, 2, 3].map(|i| float::frest_flags(ra[i], f, i)))
        }
        Frsqest => {
            let f = &mut core.fpscr;
            Some([0, 1, 2, 3].map(|i| float::frsqest_flags(ra[i], f, i)))
        }
        Fi => Some(zip(ra, rb, float::fi)),
        Cflts => Some(map(ra, |a| float::cflts(a, imm as u32))),
        Cfltu => Some(map(ra, |a| float::cfltu(a, imm as u32))),
        Csflt => {
            let f = &mut core.fpscr;
            Some([0, 1, 2, 3].map(|i| float::csflt_flags(ra[i], imm as u32, f, i)))
        }
        Cuflt => {
            let f = &mut core.fpscr;
            Some([0, 1, 2, 3].map(|i| float::cuflt_flags(ra[i], imm as u32, f, i)))
        }
        // ---- double precision
        Dfa | Dfs | Dfm => {
            let (a, b) = (dwords(ra), dwords(rb));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfa => float::dfa,
                Dfs => float::dfs,
                _ => float::dfm,
            };
            Some(from_dwords([op(a[0], b[0], f, 0), op(a[1], b[1], f, 1)]))
        }
        Dfma | Dfms | Dfnms | Dfnma => {
            let (a, b, t) = (dwords(ra), dwords(rb), dwords(rt_old));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfma => float::dfma,
                Dfms => float::dfms,
                Dfnms => float::dfnms,
                _ => float::dfnma,
            };
            Some(from_dwords([
                op(a[0], b[0], t[0], f, 0),
                op(a[1], b[1], t[1], f, 1),
            ]))
        }
        Fesd => {
            let f = &mut core.fpscr;
            Some(from_dwords([
                float::fesd(ra[0], f, 0),
                float::fesd(ra[2], f, 1),
            ]))
        }
        Frds => {
            let a = dwords(ra);
            let f = &mut core.fpscr;
            Some([float::frds(a[0], f, 0), 0, float::frds(a[1], f, 1), 0])
        }
        Dfceq | Dfcmeq | Dfcgt | Dfcmgt => {
            let (a, b) = (dwords(ra), dwords(rb));
            let f = &mut core.fpscr;
            let op = match inst.op {
                Dfceq => float::dfceq,
                Dfcmeq => float::dfcmeq,
                Dfcgt => float::dfcgt,
                _ => float::dfcmgt,
            };
            let m0 = op(a[0], b[0], f, 0);
            let m1 = op(a[1], b[1], f, 1);
            Some(from_dwords([
                if m0 { u64::MAX } else { 0 },
                if m1 { u64::MAX } else { 0 },
            ]))
        }
        Dftsv => {
            let a = dwords(ra);
            let u = imm as u32 & 0x7f;
            Some(from_dwords(a.map(|x| {
                if float::dftsv(x, u) {
                    u64::MAX
                } else {
                    0
                }
            })))
        }
        Fscrrd => Some(core.fpscr.read()),
        Fscrwr => {
            core.fpscr.write(ra);
            None
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
                Some([next, 0, 0, 0])
            } else {
                None
            }
        }
        Brz | Brnz | Brhz | Brhnz => {
            let t = rt_old[0];
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
            None
        }
        Bi | Bisl | Biz | Binz | Bihz | Bihnz | Iret | Bisled => {
            let fb = inst.feature_bits();
            if fb & 0x20 != 0 {
                core.interrupts_enabled = false;
            } else if fb & 0x10 != 0 {
                core.interrupts_enabled = true;
            }
            let t = rt_old[0];
            let (taken, target) = match inst.op {
                Iret => (true, core.srr0),
                Bisled => (core.event_pending, ra[0]),
                Biz => (t == 0, ra[0]),
                Binz => (t != 0, ra[0]),
                Bihz => (t & 0xffff == 0, ra[0]),
                Bihnz => (t & 0xffff != 0, ra[0]),
                _ => (true, ra[0]),
            };
            effect = Effect::Branch {
                taken,
                target: target & LS_MASK & !3,
            };
            if matches!(inst.op, Bisl | Bisled) {
                Some([next, 0, 0, 0])
            } else {
                None
            }
        }
        Hbr | Hbra | Hbrr => {
            if inst.feature_bits() & 0x40 != 0 && inst.op == Hbr {
                return Effect::Next; // hbrp: an instruction-fetch request
            }
            let branch = pc.wrapping_add((inst.hint_offset() << 2) as u32) & LS_MASK;
            let target = match inst.op {
                Hbr => ra[0],
                Hbra => (imm << 2) as u32,
                _ => pc.wrapping_add((imm << 2) as u32),
            } & LS_MASK
                & !3;
            return Effect::Hint { branch, target };
        }
        // ---- halts and stops
        Heq | Heqi | Hgt | Hgti | Hlgt | Hlgti => {
            let a = ra[0];
            let b = if matches!(inst.op, Heq | Hgt | Hlgt) {
                rb[0]
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
        Nop | Lnop | Sync | Dsync => None,
        Mfspr => Some([0; 4]),
        Mtspr => None,
        Rdch | Wrch | Rchcnt => return Effect::Channel,
        Unknown => return Effect::Illegal,
    };
    if let Some(v) = result {
        core.regs[inst.rt as usize] = v;
    }
    effect
}

fn fl2(core: &mut Core, a: Reg, b: Reg, f: fn(u32, u32, &mut float::Fpscr, usize) -> u32) -> Reg {
    let s = &mut core.fpscr;
    [
        f(a[0], b[0], s, 0),
        f(a[1], b[1], s, 1),
        f(a[2], b[2], s, 2),
        f(a[3], b[3], s, 3),
    ]
}

fn fl3(
    core: &mut Core,
    a: Reg,
    b: Reg,
    c: Reg,
    f: fn(u32, u32, u32, &mut float::Fpscr, usize) -> u32,
) -> Reg {
    let s = &mut core.fpscr;
    [
        f(a[0], b[0], c[0], s, 0),
        f(a[1], b[1], c[1], s, 1),
        f(a[2], b[2], c[2], s, 2),
        f(a[3], b[3], c[3], s, 3),
    ]
}
