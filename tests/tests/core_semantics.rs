//! Per-instruction vectors for the simulated SPU core (`spu_isa::machine`), each checked by
//! hand from the SPU ISA 1.2 text (and `shared/isa/README.md` for the float rules). Every
//! case runs one instruction at address 0 followed by `stop`, on registers set by the host.

use spu_isa::encode;
use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_isa::table::forms_named;

type R = [u32; 4];

fn word(m: &str, ops: &[i64], pc: u32) -> u32 {
    let form = forms_named(m)
        .find(|f| f.operands.len() == ops.len())
        .unwrap_or_else(|| panic!("no form {m}/{}", ops.len()));
    encode(form, ops, pc)
}

/// Runs `prog` (mnemonic, operands) from address 0 with `regs` preset; the program must
/// end in a stop (one is appended).
fn run(prog: &[(&str, &[i64])], regs: &[(usize, R)]) -> (Spu, StopReason) {
    let mut image = Vec::new();
    for (i, (m, ops)) in prog.iter().enumerate() {
        image.extend(word(m, ops, 4 * i as u32).to_be_bytes());
    }
    image.extend(word("stop", &[0x3fff], 4 * prog.len() as u32).to_be_bytes());
    let mut spu = Spu::new(0);
    spu.load_image(&image);
    for (n, v) in regs {
        spu.set_reg(*n, *v);
    }
    let mut mem = MainMemory::zeroed(4096);
    let stop = spu.run(&mut mem, 10_000);
    (spu, stop)
}

/// One instruction writing $3 from $4, $5, $6 (and the old $3).
fn one(m: &str, ops: &[i64], regs: &[(usize, R)]) -> R {
    let (spu, stop) = run(&[(m, ops)], regs);
    assert_eq!(stop, StopReason::Stop(0x3fff), "{m}");
    spu.reg(3)
}

fn rr(m: &str, a: R, b: R) -> R {
    one(m, &[3, 4, 5], &[(4, a), (5, b)])
}
fn ri(m: &str, a: R, imm: i64) -> R {
    one(m, &[3, 4, imm], &[(4, a)])
}
fn r1(m: &str, a: R) -> R {
    one(m, &[3, 4], &[(4, a)])
}
fn rrr(m: &str, a: R, b: R, c: R) -> R {
    one(m, &[3, 4, 5, 6], &[(4, a), (5, b), (6, c)])
}
fn bytes(b: [u8; 16]) -> R {
    let w = |i: usize| u32::from_be_bytes([b[4 * i], b[4 * i + 1], b[4 * i + 2], b[4 * i + 3]]);
    [w(0), w(1), w(2), w(3)]
}
fn seq(start: u8) -> R {
    let mut b = [0u8; 16];
    for (i, x) in b.iter_mut().enumerate() {
        *x = start + i as u8;
    }
    bytes(b)
}
const F1: u32 = 0x3f80_0000; // 1.0f
const F2: u32 = 0x4000_0000; // 2.0f

#[test]
fn shufb_specials_and_selection() {
    // ra = 00..0f, rb = 10..1f. Control: 0x80 -> 00, 0xc0 -> ff, 0xe0 -> 80 (the three
    // 1x patterns take precedence over the index), otherwise byte (c & 0x1f) of ra:rb.
    let c = bytes([
        0x80, 0xbf, 0xc0, 0xdf, 0xe0, 0xff, 0x00, 0x0f, 0x10, 0x1f, 0x25, 0x3f, 0x63, 0x7c, 0x13,
        0x03,
    ]);
    assert_eq!(
        rrr("shufb", seq(0), seq(0x10), c),
        bytes([
            0x00, 0x00, 0xff, 0xff, 0x80, 0x80, 0x00, 0x0f, 0x10, 0x1f, 0x05, 0x1f, 0x03, 0x1c,
            0x13, 0x03
        ])
    );
}

#[test]
fn selb_takes_rb_where_mask_set() {
    let r = rrr(
        "selb",
        [0x1111_1111; 4],
        [0x2222_2222; 4],
        [0xffff_0000, 0, u32::MAX, 0x0f0f_0f0f],
    );
    assert_eq!(r, [0x2222_1111, 0x1111_1111, 0x2222_2222, 0x1212_1212]);
}

#[test]
fn word_shifts_at_and_beyond_width() {
    let a = [0x8000_0001; 4];
    // shl: count = low 6 bits; 32..63 give 0; 64 wraps to 0 (unchanged).
    assert_eq!(
        rr("shl", a, [1, 31, 32, 64]),
        [2, 0x8000_0000, 0, 0x8000_0001]
    );
    assert_eq!(rr("shl", a, [63, 33, 0, 65]), [0, 0, 0x8000_0001, 2]);
    // rotm uses the two's complement of the count: -1 shifts right by 1, -32 and beyond
    // (low 6 bits of -count >= 32) give 0, count 0 leaves the value.
    let n = |x: i32| x as u32;
    assert_eq!(
        rr("rotm", a, [n(-1), n(-31), n(-32), 0]),
        [0x4000_0000, 1, 0, 0x8000_0001]
    );
    // rotma: arithmetic; counts of 32..63 fill with the sign.
    assert_eq!(
        rr("rotma", a, [n(-1), n(-31), n(-32), n(-63)]),
        [0xc000_0000, 0xffff_ffff, 0xffff_ffff, 0xffff_ffff]
    );
    assert_eq!(ri("rotmai", [0x4000_0000; 4], -40)[0], 0);
    assert_eq!(ri("rotmi", a, -31)[0], 1);
    assert_eq!(ri("rotmi", a, -32)[0], 0);
    // rot: count modulo 32.
    assert_eq!(
        rr("rot", a, [1, 32, 33, 31]),
        [3, 0x8000_0001, 3, 0xc000_0000]
    );
    assert_eq!(ri("roti", a, -1)[0], 0xc000_0000);
}

#[test]
fn halfword_shifts_at_and_beyond_width() {
    let a = [0x8001_8001; 4];
    // shlh: low 5 bits of each halfword count; 16..31 give 0.
    assert_eq!(
        rr("shlh", a, [0x0001_000f, 0x0010_0020, 0x001f_0011, 0])[..3],
        [0x0002_8000, 0x0000_8001, 0x0000_0000]
    );
    // rothm: -count; -16 gives 0.
    assert_eq!(rr("rothm", a, [0xffff_fff0; 4])[0], 0x4000_0000);
    // rotmah: arithmetic; -1 on 0x8001 gives 0xc000.
    assert_eq!(rr("rotmah", a, [0xffff_ffff; 4])[0], 0xc000_c000);
    assert_eq!(rr("rotmah", a, [0xffe0_fff0; 4])[0], 0x8001_ffff);
    // roth: count modulo 16.
    assert_eq!(rr("roth", a, [0x0001_0011; 4])[0], 0x0003_0003);
}

#[test]
fn quadword_shifts_and_rotates() {
    let a = seq(0);
    let s = |x: u32| [x, 0, 0, 0];
    // shlqby: low 5 bits; 16..31 give zero.
    let mut e = [0u8; 16];
    e[..13].copy_from_slice(&[3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15]);
    assert_eq!(rr("shlqby", a, s(3)), bytes(e));
    assert_eq!(rr("shlqby", a, s(16)), [0; 4]);
    assert_eq!(rr("shlqby", a, s(35)), bytes(e)); // 35 & 31 = 3
                                                  // rotqby: low 4 bits.
    assert_eq!(rr("rotqby", a, s(17)), seq(1).map(|w| w & 0x0f0f_0f0f));
    // The "bi" forms take bits 0x78 of the count, i.e. count >> 3.
    assert_eq!(rr("shlqbybi", a, s(3 * 8 + 7)), bytes(e));
    assert_eq!(rr("rotqbybi", a, s(8 + 7)), seq(1).map(|w| w & 0x0f0f_0f0f));
    // shlqbi: low 3 bits of the count (bits, across word boundaries).
    assert_eq!(
        rr("shlqbi", [0x8000_0000, 0x8000_0000, 0, 1], s(9)),
        [1, 0, 0, 2] // word 1's top bit moves into word 0; word 0's is lost
    );
    assert_eq!(ri("rotqbii", [0x8000_0000, 0, 0, 1], 1), [0, 0, 0, 3]);
    // rotqmbyi: -count bytes right; -16 or beyond gives zero.
    assert_eq!(ri("rotqmbyi", a, -15), [0, 0, 0, 0]);
    assert_eq!(ri("rotqmbyi", a, -16), [0; 4]);
    assert_eq!(
        ri("rotqmbyi", a, -4),
        [0, 0x0001_0203, 0x0405_0607, 0x0809_0a0b]
    );
    // rotqmbi: -count bits right (low 3 bits).
    assert_eq!(ri("rotqmbii", [0, 0, 1, 0], -1), [0, 0, 0, 0x8000_0000]);
    // rotqmbybi: -(count >> 3) & 0x1f bytes.
    let n = |x: i32| x as u32;
    assert_eq!(
        rr("rotqmbybi", a, s(n(-32))),
        [0, 0x0001_0203, 0x0405_0607, 0x0809_0a0b]
    );
}

#[test]
fn carries_and_borrows() {
    let m = u32::MAX;
    assert_eq!(
        rr("cg", [m, 1, 0x8000_0000, 0], [1, 1, 0x8000_0000, 0]),
        [1, 0, 1, 0]
    );
    // bg: 1 when rb >= ra (no borrow in rb - ra).
    assert_eq!(rr("bg", [1, 2, 0, m], [1, 1, m, 0]), [1, 0, 1, 0]);
    // addx: ra + rb + (rt & 1); sfx: rb - ra - !(rt & 1).
    let t = [1, 0, 1, 0];
    assert_eq!(
        one(
            "addx",
            &[3, 4, 5],
            &[(3, t), (4, [m, 5, 5, 5]), (5, [0, 6, 6, 6])]
        ),
        [0, 11, 12, 11]
    );
    assert_eq!(
        one(
            "sfx",
            &[3, 4, 5],
            &[(3, t), (4, [1, 1, 0, 0]), (5, [1, 1, 0, 0])]
        ),
        [0, m, 0, m]
    );
    // cgx: carry of ra + rb + c; bgx: borrow of rb - ra - !c.
    assert_eq!(
        one(
            "cgx",
            &[3, 4, 5],
            &[(3, t), (4, [m, m, 0, 0]), (5, [0, 0, 0, 0])]
        ),
        [1, 0, 0, 0]
    );
    assert_eq!(
        one(
            "bgx",
            &[3, 4, 5],
            &[(3, t), (4, [5, 5, 4, 4]), (5, [5, 5, 5, 5])]
        ),
        [1, 0, 1, 1]
    );
}

#[test]
fn multiplies_and_their_signs() {
    // mpy: signed low halfwords; 0xffff is -1.
    assert_eq!(
        rr("mpy", [0x1234_ffff; 4], [0x0000_0002; 4])[0],
        0xffff_fffe
    );
    assert_eq!(
        rr("mpyu", [0x1234_ffff; 4], [0x0000_ffff; 4])[0],
        0xfffe_0001
    );
    // mpyh: (ra high * rb low) << 16.
    assert_eq!(
        rr("mpyh", [0x0003_0000; 4], [0xffff_0005; 4])[0],
        0x000f_0000
    );
    // mpys: signed product >> 16, sign-extended.
    assert_eq!(rr("mpys", [0x4000; 4], [0x4000; 4])[0], 0x1000);
    assert_eq!(rr("mpys", [0xffff; 4], [0x0001; 4])[0], 0xffff_ffff);
    assert_eq!(
        rr("mpyhh", [0xfffe_0000; 4], [0x0003_0000; 4])[0],
        (-6i32) as u32
    );
    assert_eq!(rr("mpyhhu", [0xfffe_0000; 4], [0x0003_0000; 4])[0], 0x2fffa);
    assert_eq!(
        rrr("mpya", [0xffff; 4], [0x0003; 4], [10; 4])[0],
        7 // -1 * 3 + 10
    );
    assert_eq!(
        one(
            "mpyhha",
            &[3, 4, 5],
            &[(3, [100; 4]), (4, [0xffff_0000; 4]), (5, [0x0002_0000; 4])]
        )[0],
        98
    );
    assert_eq!(
        one(
            "mpyhhau",
            &[3, 4, 5],
            &[(3, [1; 4]), (4, [0xffff_0000; 4]), (5, [0x0002_0000; 4])]
        )[0],
        0x1fffe + 1
    );
    // mpyi: signed immediate; mpyui: the 10-bit immediate sign-extended to 16 bits, then
    // unsigned (-1 -> 0xffff).
    assert_eq!(ri("mpyi", [0xfffe; 4], -3)[0], 6);
    assert_eq!(ri("mpyui", [2; 4], -1)[0], 0x1fffe);
}

#[test]
fn byte_operations() {
    let a = bytes([
        0xff, 0x01, 0x80, 0x00, 0x0f, 0xf0, 0x03, 0x07, 0, 0, 0, 0, 0, 0, 0, 255,
    ]);
    assert_eq!(r1("cntb", a)[..2], [0x0801_0100, 0x0404_0203]);
    let b = bytes([0x01, 0xff, 0x80, 0x10, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    // absdb: |a - b| unsigned; avgb: (a + b + 1) >> 1.
    assert_eq!(rr("absdb", a, b)[0], 0xfefe_0010);
    assert_eq!(rr("avgb", a, b)[0], 0x8080_8008);
    // sumb: high halfword = sum of rb's bytes, low = sum of ra's bytes.
    assert_eq!(
        rr("sumb", a, b)[0],
        ((1 + 255 + 128 + 16) << 16) | (255 + 1 + 128)
    );
    assert_eq!(r1("clz", [0, 1, 0x8000_0000, 0x0001_0000]), [32, 31, 0, 15]);
    assert_eq!(r1("xsbh", [0x1280_007f; 4])[0], 0xff80_007f);
    assert_eq!(r1("xshw", [0x1234_8000; 4])[0], 0xffff_8000);
    assert_eq!(
        r1("xswd", [7, 0x8000_0000, 9, 1]),
        [0xffff_ffff, 0x8000_0000, 0, 1]
    );
}

#[test]
fn gather_and_form_select_masks() {
    assert_eq!(r1("gb", [1, 0, 3, 2]), [0b1010, 0, 0, 0]);
    assert_eq!(
        r1("gbh", [0x0001_0000, 1, 0x0001_0001, 0]),
        [0b1001_1100, 0, 0, 0]
    );
    assert_eq!(r1("gbb", seq(0)), [0x5555, 0, 0, 0]);
    // Low 4 bits 0101: word 0 takes bit 3.
    assert_eq!(r1("fsm", [0xfff5, 0, 0, 0]), [0, u32::MAX, 0, u32::MAX]);
    assert_eq!(
        r1("fsmh", [0x1a6, 0, 0, 0]), // low 8 bits 10 10 01 10
        [0xffff_0000, 0xffff_0000, 0x0000_ffff, 0xffff_0000]
    );
    assert_eq!(
        r1("fsmb", [0xf_8001, 0, 0, 0]),
        [0xff00_0000, 0, 0, 0x0000_00ff]
    );
    assert_eq!(
        one("fsmbi", &[3, 0xc003], &[]),
        [0xffff_0000, 0, 0, 0x0000_ffff]
    );
}

#[test]
fn insertion_masks() {
    // Default bytes 10..1f; the element at (address & (16 - size)) gets 00.. (cbd: 03,
    // chd: 02 03, cwd: 00..03, cdd: 00..07).
    let base = seq(0x10);
    let with = |at: usize, v: &[u8]| {
        let mut b = [0u8; 16];
        for (i, x) in b.iter_mut().enumerate() {
            *x = 0x10 + i as u8;
        }
        b[at..at + v.len()].copy_from_slice(v);
        bytes(b)
    };
    let _ = base;
    assert_eq!(
        one("cbd", &[3, 5, 4], &[(4, [0x1000, 0, 0, 0])]),
        with(5, &[3])
    );
    assert_eq!(
        one("chd", &[3, 7, 4], &[(4, [0, 0, 0, 0])]),
        with(6, &[2, 3])
    );
    assert_eq!(
        one("cwd", &[3, 4, 4], &[(4, [0xb, 0, 0, 0])]),
        with(12, &[0, 1, 2, 3])
    );
    assert_eq!(
        one("cdd", &[3, 0, 4], &[(4, [0x9, 0, 0, 0])]),
        with(8, &[0, 1, 2, 3, 4, 5, 6, 7])
    );
    assert_eq!(
        one(
            "cwx",
            &[3, 4, 5],
            &[(4, [0x100, 0, 0, 0]), (5, [4, 0, 0, 0])]
        ),
        with(4, &[0, 1, 2, 3])
    );
    assert_eq!(
        one("cbx", &[3, 4, 5], &[(4, [0xf, 0, 0, 0]), (5, [1, 0, 0, 0])]),
        with(0, &[3])
    );
}

#[test]
fn immediate_loads() {
    assert_eq!(one("il", &[3, -2], &[]), [0xffff_fffe; 4]);
    assert_eq!(one("ilh", &[3, 0x8001], &[]), [0x8001_8001; 4]);
    assert_eq!(one("ilhu", &[3, 0x8001], &[]), [0x8001_0000; 4]);
    assert_eq!(one("ila", &[3, 0x3ffff], &[]), [0x3ffff; 4]);
    assert_eq!(
        one("iohl", &[3, 0xbeef], &[(3, [0xdead_0000, 1, 2, 3])]),
        [0xdead_beef, 0xbeef, 0xbeef, 0xbeef]
    );
    // Immediate logical and arithmetic forms: I10 sign-extended, truncated per element.
    assert_eq!(ri("andbi", [0x1234_5678; 4], 0x0f)[0], 0x0204_0608);
    assert_eq!(ri("orhi", [0x0001_0000; 4], -512)[0], 0xfe01_fe00);
    assert_eq!(ri("ahi", [0x0001_ffff; 4], 1)[0], 0x0002_0000);
    assert_eq!(ri("sfi", [5; 4], 3)[0], (-2i32) as u32);
    assert_eq!(ri("clgti", [0xffff_fffe; 4], -1)[0], 0); // 0xfffffffe > 0xffffffff? no
    assert_eq!(ri("cgti", [0xffff_fffe; 4], -3)[0], u32::MAX);
    assert_eq!(ri("ceqbi", [0x00ff_01ff; 4], -1)[0], 0x00ff_00ff);
    assert_eq!(ri("cgtbi", [0x80_7f_01_00; 4], 0)[0], 0x00ff_ff00);
    assert_eq!(ri("clgtbi", [0x80_7f_01_00; 4], 0)[0], 0xffff_ff00);
    assert_eq!(r1("orx", [1, 2, 4, 0x8000_0000]), [0x8000_0007, 0, 0, 0]);
}

#[test]
fn single_precision_rules() {
    // Truncation: 1 + 0.75 ulp is 1.0 (IEEE would round up to 0x3f800001).
    assert_eq!(rr("fa", [F1; 4], [0x33c0_0000; 4])[0], F1);
    // Negative results truncate toward zero too.
    assert_eq!(rr("fs", [0xbf80_0000; 4], [0x33c0_0000; 4])[0], 0xbf80_0000);
    // Exponent 255 is an ordinary number: 2^128 + 0 = 2^128; doubling it saturates.
    assert_eq!(rr("fa", [0x7f80_0000; 4], [0; 4])[0], 0x7f80_0000);
    assert_eq!(rr("fa", [0x7f80_0000; 4], [0x7f80_0000; 4])[0], 0x7fff_ffff);
    assert_eq!(rr("fm", [0xff00_0000; 4], [0x7f00_0000; 4])[0], 0xffff_ffff);
    // Denormal operands read as zero; zero results are +0; underflow gives +0.
    assert_eq!(rr("fa", [0x0000_0001; 4], [0; 4])[0], 0);
    assert_eq!(rr("fm", [0x8080_0000; 4], [0x3f00_0000; 4])[0], 0);
    assert_eq!(rr("fs", [F1; 4], [F1; 4])[0], 0);
    // fma truncates once: 1 * (1 + 2^-23) + (-1) = 2^-23 exactly.
    assert_eq!(
        rrr("fma", [F1; 4], [0x3f80_0001; 4], [0xbf80_0000; 4])[0],
        0x3400_0000
    );
    // fms: a*b - c; fnms: c - a*b.
    assert_eq!(rrr("fms", [F2; 4], [F2; 4], [F1; 4])[0], 0x4040_0000);
    assert_eq!(rrr("fnms", [F2; 4], [F2; 4], [F1; 4])[0], 0xc040_0000);
    // Compares: magnitude forms ignore the sign; -0 == +0, denormals equal zero.
    assert_eq!(
        rr("fceq", [0x8000_0000, 1, F1, F1], [0, 0, F1, F2]),
        [u32::MAX, u32::MAX, u32::MAX, 0]
    );
    assert_eq!(
        rr("fcgt", [F1, 0xbf80_0000, F2, 0], [0xbf80_0000, F1, F1, 0]),
        [u32::MAX, 0, u32::MAX, 0]
    );
    assert_eq!(rr("fcmgt", [0xc000_0000; 4], [F1; 4])[0], u32::MAX);
    assert_eq!(rr("fcmeq", [0xbf80_0000; 4], [F1; 4])[0], u32::MAX);
}

#[test]
fn conversions_scale_and_saturate() {
    // cflts rt, ra, scale: truncate toward zero, saturate to the int range.
    assert_eq!(ri("cflts", [0xbfc0_0000; 4], 0)[0], (-1i32) as u32); // -1.5
    assert_eq!(ri("cflts", [0x4f00_0000; 4], 0)[0], 0x7fff_ffff); // 2^31
    assert_eq!(ri("cflts", [0xdf00_0000; 4], 0)[0], 0x8000_0000); // -2^63
    assert_eq!(ri("cflts", [0x3f00_0000; 4], 1)[0], 1); // 0.5 * 2^1
    assert_eq!(ri("cfltu", [0xbf80_0000; 4], 0)[0], 0); // negative -> 0
    assert_eq!(ri("cfltu", [0x4f80_0000; 4], 0)[0], u32::MAX); // 2^32
                                                               // csflt/cuflt rt, ra, scale: int to float, divided by 2^scale.
    assert_eq!(ri("csflt", [(-2i32) as u32; 4], 0)[0], 0xc000_0000);
    assert_eq!(ri("csflt", [1; 4], 1)[0], 0x3f00_0000);
    assert_eq!(ri("cuflt", [u32::MAX; 4], 0)[0], 0x4f7f_ffff); // truncated, not 2^32
}

fn dw(v: u64) -> R {
    [(v >> 32) as u32, v as u32, (v >> 32) as u32, v as u32]
}

#[test]
fn double_precision_rounding_modes_and_flags() {
    let one_ = 0x3ff0_0000_0000_0000u64;
    let tiny = 0x3ca0_0000_0000_0000u64; // 2^-53: half an ulp of 1.0
                                         // Nearest even: 1 + 2^-53 -> 1.0, and the inexact flag is raised.
    let (spu, _) = run(
        &[("dfa", &[3, 4, 5]), ("fscrrd", &[7])],
        &[(4, dw(one_)), (5, dw(tiny))],
    );
    assert_eq!(spu.reg(3), dw(one_));
    assert_ne!(
        spu.reg(7)[1] | spu.reg(7)[2],
        0,
        "DP flags after an inexact add"
    );
    // Slot 0 toward +inf (mode 2 at bits 11:10), slot 1 toward zero (mode 1 at 9:8).
    let (spu, _) = run(
        &[("fscrwr", &[0, 8]), ("dfa", &[3, 4, 5])],
        &[(8, [0x0000_0900, 0, 0, 0]), (4, dw(one_)), (5, dw(tiny))],
    );
    assert_eq!(spu.reg(3), [0x3ff0_0000, 1, 0x3ff0_0000, 0]);
    // dfma rt = ra*rb + rt: 3 * 0.5 + 1 = 2.5.
    let (spu, _) = run(
        &[("dfma", &[3, 4, 5])],
        &[
            (3, dw(one_)),
            (4, dw(0x4008_0000_0000_0000)),
            (5, dw(0x3fe0_0000_0000_0000)),
        ],
    );
    assert_eq!(spu.reg(3), dw(0x4004_0000_0000_0000));
    // frds: the single in word 0 of each doubleword, others zero; fesd back.
    let (spu, _) = run(
        &[("frds", &[3, 4]), ("fesd", &[6, 3])],
        &[(4, dw(0x3ff8_0000_0000_0000))],
    );
    assert_eq!(spu.reg(3), [0x3fc0_0000, 0, 0x3fc0_0000, 0]);
    assert_eq!(spu.reg(6), dw(0x3ff8_0000_0000_0000));
}

#[test]
fn branches_links_and_conditions() {
    // brsl: link = PC + 4 in word 0, others zero.
    let (spu, stop) = run(
        &[("brsl", &[3, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(3, [9; 4])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    assert_eq!(spu.reg(3), [4, 0, 0, 0]);
    // bi: target = preferred slot & 0x3fffc (low bits and high bits dropped).
    let (_, stop) = run(
        &[("bi", &[4]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0x0004_0009, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    // brhz looks at the low halfword of word 0 only.
    let (_, stop) = run(
        &[("brhz", &[4, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0x1234_0000, 1, 1, 1])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    let (_, stop) = run(
        &[("brz", &[4, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0x1234_0000, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(1));
    // binz with a link-free indirect target.
    let (_, stop) = run(
        &[("binz", &[4, 5]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [1, 0, 0, 0]), (5, [8, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(2));
}

#[test]
fn stops_halts_and_illegal() {
    let (spu, stop) = run(&[("stop", &[0x1234])], &[]);
    assert_eq!(stop, StopReason::Stop(0x1234));
    assert_eq!(spu.instructions(), 1);
    let (_, stop) = run(&[("heqi", &[4, 5]), ("stop", &[1])], &[(4, [5, 0, 0, 0])]);
    assert_eq!(stop, StopReason::Halt { pc: 0 });
    let (_, stop) = run(&[("hgti", &[4, 5]), ("stop", &[1])], &[(4, [5, 0, 0, 0])]);
    assert_eq!(stop, StopReason::Stop(1));
    // hlgt is unsigned: 0xffffffff > 1.
    let (_, stop) = run(
        &[("lnop", &[]), ("hlgt", &[4, 5]), ("stop", &[1])],
        &[(4, [u32::MAX, 0, 0, 0]), (5, [1, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Halt { pc: 4 });
    // A zero word is `stop 0`; a word whose opcode matches nothing is illegal.
    let mut spu = Spu::new(0);
    spu.load_image(&[0, 0, 0, 0]);
    assert_eq!(
        spu.run(&mut MainMemory::zeroed(16), 100),
        StopReason::Stop(0)
    );
    let bad = (0..2048u32)
        .map(|top| top << 21 | 0x1234)
        .find(|&w| spu_isa::decode(w).op == spu_isa::Op::Unknown)
        .expect("an unassigned opcode");
    let mut spu = Spu::new(0);
    spu.load_image(&bad.to_be_bytes());
    let stop = spu.run(&mut MainMemory::zeroed(16), 100);
    assert_eq!(stop, StopReason::IllegalInstruction { pc: 0, word: bad });
}

#[test]
fn loads_and_stores_ignore_low_bits_and_wrap() {
    // stqd at 0x3fff0 + 0x1f (low 4 bits ignored) -> 0x40000 wraps to 0: writes over code?
    // Use 0x1000 + 0xf instead; then lqx reads it back from 0x100c.
    let (spu, stop) = run(
        &[("stqd", &[5, 0, 4]), ("lqx", &[3, 6, 7])],
        &[
            (4, [0x100f, 0, 0, 0]),
            (5, [1, 2, 3, 4]),
            (6, [0x1000, 0, 0, 0]),
            (7, [0xc, 0, 0, 0]),
        ],
    );
    assert_eq!(stop, StopReason::Stop(0x3fff));
    assert_eq!(spu.reg(3), [1, 2, 3, 4]);
    // Addresses wrap at 256 KiB: 0x41000 is 0x1000.
    let (spu, _) = run(
        &[("stqd", &[5, 0, 4]), ("lqd", &[3, 0, 6])],
        &[
            (4, [0x41000, 0, 0, 0]),
            (5, [9, 8, 7, 6]),
            (6, [0x1000, 0, 0, 0]),
        ],
    );
    assert_eq!(spu.reg(3), [9, 8, 7, 6]);
}

#[test]
fn self_modifying_code_is_seen() {
    // Store a `stop 0x77` word over the next instruction: the new word must execute.
    let stop77 = word("stop", &[0x77], 0);
    let (_, stop) = run(
        &[
            ("stqd", &[5, 0, 4]),
            ("lnop", &[]),
            ("lnop", &[]),
            ("lnop", &[]),
            ("stop", &[1]),
        ],
        &[(4, [0x10, 0, 0, 0]), (5, [stop77, stop77, stop77, stop77])],
    );
    assert_eq!(stop, StopReason::Stop(0x77));
}
