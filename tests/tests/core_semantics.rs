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
    // 35 & 31 = 3
    assert_eq!(rr("shlqby", a, s(35)), bytes(e));
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

    // 0.5 * 2^1 = 1; cfltu: negative -> 0, and 2^32 saturates.
    assert_eq!(ri("cflts", [0x3f00_0000; 4], 1)[0], 1);
    assert_eq!(ri("cfltu", [0xbf80_0000; 4], 0)[0], 0);
    assert_eq!(ri("cfltu", [0x4f80_0000; 4], 0)[0], u32::MAX);
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
    // 2^-53: half an ulp of 1.0
    let tiny = 0x3ca0_0000_0000_0000u64;
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

// ---------------------------------------------------------------------------------------
// Further vectors (second pass): every expected value below is derived from the SPU ISA 1.2
// RTL for the instruction, stated in the comment next to it.

const M: u32 = u32::MAX;

fn neg(x: i32) -> u32 {
    x as u32
}

/// The quadword as one big-endian 128-bit number (byte 0 = most significant), for the
/// quadword shift/rotate model below.
fn q(r: R) -> u128 {
    r.iter().fold(0u128, |acc, w| acc << 32 | *w as u128)
}
fn unq(v: u128) -> R {
    [
        (v >> 96) as u32,
        (v >> 64) as u32,
        (v >> 32) as u32,
        v as u32,
    ]
}

#[test]
fn add_and_subtract_wrap_and_extended_forms_use_only_bit_0() {
    // a: modulo 2^32 per word.
    assert_eq!(
        rr(
            "a",
            [M, 0x7fff_ffff, 1, 0x8000_0000],
            [1, 1, 2, 0x8000_0000]
        ),
        [0, 0x8000_0000, 3, 0]
    );
    // sf rt,ra,rb computes rb - ra (note the operand order).
    assert_eq!(
        rr("sf", [1, 0, 5, 0x8000_0000], [0, 0, 3, 0]),
        [M, 0, neg(-2), 0x8000_0000]
    );
    // ah/sfh: per halfword, carries do not cross into the upper halfword.
    assert_eq!(rr("ah", [0xffff_7fff; 4], [0x0001_0001; 4])[0], 0x0000_8000);
    assert_eq!(
        rr("sfh", [0x0001_0000; 4], [0x0000_0001; 4])[0],
        0xffff_0001
    );
    // addx: RT = RA + RB + RT(31) -- only the least significant bit of the old rt is the
    // carry in; rt = 2 (bit 0 clear) adds nothing, 0xffffffff adds one.
    let t = [2, 3, 0xffff_fffe, M];
    assert_eq!(
        one("addx", &[3, 4, 5], &[(3, t), (4, [1; 4]), (5, [1; 4])]),
        [2, 3, 2, 3]
    );
    // sfx: RT = RB + ~RA + RT(31), i.e. rb - ra - 1 + c.
    assert_eq!(
        one("sfx", &[3, 4, 5], &[(3, t), (4, [1; 4]), (5, [5, 5, 0, 0])]),
        [3, 4, neg(-2), M]
    );
    // cg: carry out of ra + rb (0 or 1 in each word).
    assert_eq!(
        rr(
            "cg",
            [M, M, 0x8000_0000, 0x7fff_ffff],
            [0, 1, 0x7fff_ffff, 0x8000_0001]
        ),
        [0, 1, 0, 1]
    );
    // cgx: carry out of ra + rb + rt(31).
    assert_eq!(
        one(
            "cgx",
            &[3, 4, 5],
            &[
                (3, [1, 0, 1, 0xffff_fffe]),
                (4, [M, M, 0x8000_0000, M]),
                (5, [0, 1, 0x7fff_ffff, 0])
            ]
        ),
        [1, 1, 1, 0]
    );
    // bg: 1 if rb >= ra unsigned (no borrow in rb - ra).
    assert_eq!(
        rr(
            "bg",
            [0, 1, 0x7fff_ffff, 0x8000_0000],
            [0, 0, 0x8000_0000, 0x7fff_ffff]
        ),
        [1, 0, 1, 0]
    );
    // bgx: 1 if rb > ra, or rb == ra and rt(31) = 1 (no borrow in rb - ra - !c).
    assert_eq!(
        one(
            "bgx",
            &[3, 4, 5],
            &[(3, [0, 1, 1, 0]), (4, [5, 5, 6, 0]), (5, [5, 5, 5, M])]
        ),
        [0, 1, 0, 1]
    );
}

#[test]
fn multiply_signs_at_the_halfword_extremes() {
    // mpy: signed 16 x 16 of the low halfwords; the upper halfwords are ignored.
    // 0x8000 * 0x8000 = (-32768)^2 = 2^30; 0x8000 * 0x7fff = -32768 * 32767.
    assert_eq!(
        rr(
            "mpy",
            [0x1234_8000, 0xffff_8000, 7, 0xffff],
            [0x0000_8000, 0x7fff, 0x5555_0003, 0xffff]
        ),
        [0x4000_0000, (-32768i32 * 32767) as u32, 21, 1]
    );
    // mpyu: unsigned low halfwords.
    assert_eq!(
        rr(
            "mpyu",
            [0xabcd_0002, 0xffff, 0x8000, 0],
            [0x1234_0003, 0xffff, 0x8000, 5]
        ),
        [6, 0xfffe_0001, 0x4000_0000, 0]
    );
    // mpyh: (ra upper * rb lower), low 16 bits of the product, shifted left 16.
    // -1 * 3 = 0xfffffffd -> 0xfffd0000; 0x1234 * 0x0100 = 0x123400 -> 0x34000000.
    assert_eq!(
        rr(
            "mpyh",
            [0xffff_0000, 0x1234_5678, 0, 0],
            [3, 0x9abc_0100, 0, 0]
        )[..2],
        [0xfffd_0000, 0x3400_0000]
    );
    // mpys: signed product shifted right 16, sign-extended.
    // 0x8000*0x8000 = 2^30 -> 0x4000; -32768*1 >> 16 = -1; (-1)*(-1) = 1 >> 16 = 0.
    assert_eq!(
        rr(
            "mpys",
            [0x8000, 0x8000, 0xffff, 0x7fff],
            [0x8000, 1, 0xffff, 0x7fff]
        ),
        [0x4000, M, 0, (32767 * 32767) >> 16]
    );
    // mpyhh: signed upper halfwords; mpyhhu unsigned.
    assert_eq!(
        rr(
            "mpyhh",
            [0x8000_1111, 0xffff_0000, 0, 0],
            [0x8000_2222, 0x7fff_0000, 0, 0]
        )[..2],
        [0x4000_0000, neg(-32767)]
    );
    assert_eq!(
        rr(
            "mpyhhu",
            [0x8000_1111, 0xffff_0000, 0, 0],
            [0x8000_2222, 0xffff_0000, 0, 0]
        )[..2],
        [0x4000_0000, 0xfffe_0001]
    );
    // mpya rt,ra,rb,rc: signed low-halfword product + rc, modulo 2^32.
    assert_eq!(
        rrr(
            "mpya",
            [0x8000, 0xffff, 0, 0],
            [0x7fff, 0xffff, 0, 0],
            [0x3fff_8000, M, 0, 0]
        )[..2],
        [0, 0] // -32768*32767 + 0x3fff8000 = 0; 1 + 0xffffffff wraps to 0
    );
    // mpyhha: rt += signed upper-halfword product (wrapping).
    assert_eq!(
        one(
            "mpyhha",
            &[3, 4, 5],
            &[
                (3, [0xc000_0000, 5, 0, 0]),
                (4, [0x8000_0000, 0xffff_0000, 0, 0]),
                (5, [0x8000_0000, 0x0005_0000, 0, 0])
            ]
        )[..2],
        [0, 0] // 0xc0000000 + 2^30 = 2^32 -> 0; 5 + (-5) = 0
    );
    // mpyi: signed low halfword * sign-extended I10.
    assert_eq!(
        ri("mpyi", [0x8000, 0, 0, 0], -512)[0],
        (-32768i32 * -512) as u32
    );
    assert_eq!(
        ri("mpyi", [0x0001_7fff, 0, 0, 0], 511)[0],
        (32767 * 511) as u32
    );
    // mpyui: low halfword * (I10 sign-extended to 16 bits), unsigned: -512 -> 0xfe00.
    assert_eq!(ri("mpyui", [0xffff, 0, 0, 0], -512)[0], 0xffffu32 * 0xfe00);
    assert_eq!(ri("mpyui", [0x1_0003, 0, 0, 0], 5)[0], 15);
}

#[test]
fn immediate_word_and_halfword_shifts() {
    let a = [0x8000_0001; 4];
    // shli: count = I7 & 0x3f; 32..63 give zero; -1 (0x7f) is 63; -64 (0x40) is 0.
    assert_eq!(ri("shli", a, 31)[0], 0x8000_0000);
    assert_eq!(ri("shli", a, 32)[0], 0);
    assert_eq!(ri("shli", a, -1)[0], 0);
    assert_eq!(ri("shli", a, -64)[0], 0x8000_0001);
    // shlhi: count = I7 & 0x1f; 16..31 give zero; -32 (0x60) is 0.
    let h = [0x8001_8001; 4];
    assert_eq!(ri("shlhi", h, 15)[0], 0x8000_8000);
    assert_eq!(ri("shlhi", h, 16)[0], 0);
    assert_eq!(ri("shlhi", h, -16)[0], 0); // low 5 bits 16
    assert_eq!(ri("shlhi", h, -32)[0], 0x8001_8001);
    // shl with a count of exactly 32 (and 0x20 in the upper bits ignored beyond bit 5).
    assert_eq!(
        rr("shl", a, [0x40 | 1, 0x20, 0xffff_ffc0, 0x3f]),
        [2, 0, 0x8000_0001, 0]
    );
    // roti: count = I7 & 0x1f: 32 is 0, -31 is 1.
    assert_eq!(ri("roti", a, 32)[0], 0x8000_0001);
    assert_eq!(ri("roti", a, -31)[0], 3);
    // rothi: count = I7 & 0xf: 17 is 1.
    assert_eq!(ri("rothi", h, 17)[0], 0x0003_0003);
    // rotmi: count = (0 - I7) & 0x3f, logical right; positive immediates give counts of
    // 33..63 (zero result), 0 leaves the value.
    assert_eq!(ri("rotmi", a, 0)[0], 0x8000_0001);
    assert_eq!(ri("rotmi", a, 1)[0], 0); // count 63
    assert_eq!(ri("rotmi", a, -63)[0], 0);
    // rotmai $x,$y,-31: arithmetic right by 31 -> all sign bits.
    assert_eq!(
        one(
            "rotmai",
            &[3, 4, -31],
            &[(4, [0x8000_0001, 0x7fff_ffff, 0x4000_0000, M])]
        ),
        [M, 0, 0, M]
    );
    // rotmai: -1 halves with sign; -32 and beyond give the sign in every bit.
    assert_eq!(ri("rotmai", [0x8000_0000; 4], -1)[0], 0xc000_0000);
    assert_eq!(
        one(
            "rotmai",
            &[3, 4, -32],
            &[(4, [0x8000_0001, 0x7fff_ffff, 0, M])]
        ),
        [M, 0, 0, M]
    );
    // rothmi: (0 - I7) & 0x1f, logical per halfword: -15 leaves the top bit at bit 0.
    assert_eq!(ri("rothmi", h, -15)[0], 0x0001_0001);
    assert_eq!(ri("rothmi", h, -16)[0], 0);
    // rotmahi: arithmetic per halfword.
    assert_eq!(ri("rotmahi", [0x8001_7fff; 4], -15)[0], 0xffff_0000);
    assert_eq!(ri("rotmahi", [0x8001_7fff; 4], -16)[0], 0xffff_0000);
    assert_eq!(ri("rotmahi", [0x8001_7fff; 4], 0)[0], 0x8001_7fff);
    // rotma with a count register: -(count) & 0x3f; count = +1 means 63 -> sign.
    assert_eq!(
        rr("rotma", [0x8000_0000, 1, 0, 0], [1, 1, 0, 0])[..2],
        [M, 0]
    );
    // roth with count 16 (mod 16 = 0) and 15 (rotate left 15 = right 1).
    assert_eq!(rr("roth", h, [0x0010_000f; 4])[0], 0x8001_c000);
    // rothm: counts -(c) & 0x1f; c = 0 leaves the halfword; c = -17 gives 17 -> 0.
    assert_eq!(rr("rothm", h, [0x0000_ffef; 4])[0], 0x8001_0000);
}

#[test]
fn quadword_shifts_and_rotates_at_counts_0_7_15_16_31() {
    // a = bytes 10..1f (no zero bytes, so a byte moved anywhere is visible).
    let a = seq(0x10);
    let av = q(a);
    let s = |x: u32| [x, 0xdead_beef, 0xdead_beef, 0xdead_beef]; // only the preferred slot counts
    let shl = |n: u32| if n >= 128 { 0 } else { av << n };
    let shr = |n: u32| if n >= 128 { 0 } else { av >> n };
    let rotl = |n: u32| av.rotate_left(n);
    for c in [0u32, 7, 15, 16, 31] {
        // Byte forms: shlqby/shlqbyi count = c & 0x1f bytes (16..31 -> zero).
        assert_eq!(q(rr("shlqby", a, s(c))), shl(8 * (c & 0x1f)), "shlqby {c}");
        assert_eq!(
            q(ri("shlqbyi", a, c as i64)),
            shl(8 * (c & 0x1f)),
            "shlqbyi {c}"
        );
        // rotqby/rotqbyi: c & 0xf bytes.
        assert_eq!(q(rr("rotqby", a, s(c))), rotl(8 * (c & 0xf)), "rotqby {c}");
        assert_eq!(
            q(ri("rotqbyi", a, c as i64)),
            rotl(8 * (c & 0xf)),
            "rotqbyi {c}"
        );
        // Bit forms: shlqbi/shlqbii/rotqbi/rotqbii use c & 7 bits.
        assert_eq!(q(rr("shlqbi", a, s(c))), shl(c & 7), "shlqbi {c}");
        assert_eq!(q(ri("shlqbii", a, c as i64)), shl(c & 7), "shlqbii {c}");
        assert_eq!(q(rr("rotqbi", a, s(c))), rotl(c & 7), "rotqbi {c}");
        assert_eq!(q(ri("rotqbii", a, c as i64)), rotl(c & 7), "rotqbii {c}");
        // "bybi" forms take the byte count from bits 3..7: (c >> 3) & 0x1f (shl) or & 0xf
        // (rot): 0, 7 -> 0; 15 -> 1; 16 -> 2; 31 -> 3.
        assert_eq!(
            q(rr("shlqbybi", a, s(c))),
            shl(8 * ((c >> 3) & 0x1f)),
            "shlqbybi {c}"
        );
        assert_eq!(
            q(rr("rotqbybi", a, s(c))),
            rotl(8 * ((c >> 3) & 0xf)),
            "rotqbybi {c}"
        );
        // Right shifts take the negated count: rotqmby/rotqmbyi shift right by
        // (0 - count) & 0x1f bytes (16..31 -> zero); rotqmbi/rotqmbii by (0 - count) & 7 bits.
        let n = neg(-(c as i32));
        assert_eq!(
            q(rr("rotqmby", a, s(n))),
            shr(8 * (c & 0x1f)),
            "rotqmby -{c}"
        );
        assert_eq!(
            q(ri("rotqmbyi", a, -(c as i64))),
            shr(8 * (c & 0x1f)),
            "rotqmbyi -{c}"
        );
        assert_eq!(q(rr("rotqmbi", a, s(n))), shr(c & 7), "rotqmbi -{c}");
        assert_eq!(
            q(ri("rotqmbii", a, -(c as i64))),
            shr(c & 7),
            "rotqmbii -{c}"
        );
        // rotqmbybi: (0 - ((count >> 3) & 0x1f)) & 0x1f bytes: for count = -(8c) this is c.
        let n8 = neg(-8 * c as i32);
        assert_eq!(
            q(rr("rotqmbybi", a, s(n8))),
            shr(8 * (c & 0x1f)),
            "rotqmbybi -8*{c}"
        );
    }
    // Literal spot checks of the model: shlqbyi 7 and rotqmbyi -15.
    assert_eq!(
        ri("shlqbyi", a, 7),
        [0x1718_191a, 0x1b1c_1d1e, 0x1f00_0000, 0]
    );
    assert_eq!(ri("rotqmbyi", a, -15), [0, 0, 0, 0x10]);
    assert_eq!(ri("rotqbii", a, 7), unq(av.rotate_left(7)));
    // rotqmbybi with count -7: (0xfffffff9 >> 3) & 0x1f = 0x1f, 0 - 0x1f = 1 byte (the
    // count's low 3 bits are simply ignored, so this is not 0 bytes).
    assert_eq!(q(rr("rotqmbybi", a, s(neg(-7)))), shr(8));
    // Positive counts for rotqmby: (0 - 1) & 0x1f = 31 -> zero.
    assert_eq!(rr("rotqmby", a, s(1)), [0; 4]);
    // shlqby with 32: low 5 bits 0 -> unchanged.
    assert_eq!(rr("shlqby", a, s(32)), a);
}

#[test]
fn shufb_with_every_special_range_and_both_sources() {
    // ra = a0..af, rb = b0..bf. Bytes 0x00..0x0f pick ra, 0x10..0x1f pick rb, and bits 5..7
    // are ignored for indexing (0x2f = ra[15], 0x70 = rb[0]) unless the byte is 10xxxxxx
    // (-> 0x00), 110xxxxx (-> 0xff) or 111xxxxx (-> 0x80).
    let mut ra = [0u8; 16];
    let mut rb = [0u8; 16];
    for i in 0..16 {
        ra[i] = 0xa0 + i as u8;
        rb[i] = 0xb0 + i as u8;
    }
    let c = bytes([
        0x00, 0x10, 0x0f, 0x1f, 0x2f, 0x70, 0x80, 0x9f, 0xa5, 0xbf, 0xc0, 0xc7, 0xdf, 0xe0, 0xf3,
        0xff,
    ]);
    assert_eq!(
        rrr("shufb", bytes(ra), bytes(rb), c),
        bytes([
            0xa0, 0xb0, 0xaf, 0xbf, 0xaf, 0xb0, 0x00, 0x00, 0x00, 0x00, 0xff, 0xff, 0xff, 0x80,
            0x80, 0x80
        ])
    );
    // The same register as both sources and as control (shufb $3,$4,$4,$4).
    assert_eq!(
        one("shufb", &[3, 4, 4, 4], &[(4, seq(0))]),
        seq(0) // control byte i selects byte i of ra (i < 16)
    );
}

#[test]
fn gather_and_masks_use_only_their_bits() {
    // gb: bit 31 of each word (its least significant bit); other bits ignored.
    assert_eq!(r1("gb", [0xffff_fffe, 1, M, 0]), [0b0110, 0, 0, 0]);
    // gbh: low bit of each of the 8 halfwords, halfword 0 -> bit 7 of the result.
    assert_eq!(
        r1("gbh", [0xfffe_0001, 0, 0, 0x0001_0001]),
        [0b0100_0011, 0, 0, 0]
    );
    // gbb: low bit of each byte, byte 0 -> bit 15.
    assert_eq!(
        r1("gbb", [0x0100_0000, 0, 0, 0x0000_00ff]),
        [0x8001, 0, 0, 0]
    );
    // fsm uses bits 28..31 (the low 4) of the preferred slot, bit 28 -> word 0.
    assert_eq!(r1("fsm", [0x8, 7, 7, 7]), [M, 0, 0, 0]);
    // fsmb uses the low 16 bits: 0x10000 has none set.
    assert_eq!(r1("fsmb", [0x1_0000, M, M, M]), [0; 4]);
    assert_eq!(r1("fsmh", [0x100, 0, 0, 0]), [0; 4]);
    assert_eq!(
        r1("fsmh", [0x81, 0, 0, 0]),
        [0xffff_0000, 0, 0, 0x0000_ffff]
    );
    assert_eq!(one("fsmbi", &[3, 0], &[]), [0; 4]);
    assert_eq!(one("fsmbi", &[3, 0xffff], &[]), [M; 4]);
    assert_eq!(
        one("fsmbi", &[3, 0x8421], &[]),
        [0xff00_0000, 0x00ff_0000, 0x0000_ff00, 0x0000_00ff]
    );
}

#[test]
fn insertion_masks_for_every_size_and_both_address_forms() {
    let with = |at: usize, v: &[u8]| {
        let mut b = [0u8; 16];
        for (i, x) in b.iter_mut().enumerate() {
            *x = 0x10 + i as u8;
        }
        b[at..at + v.len()].copy_from_slice(v);
        bytes(b)
    };
    // c?d: t = (ra + I7) & 0xf, then rounded down to the element size.
    // chd: 0xf + 0 -> 0xe; cdd: 7 + 1 -> 8; cwd: 0xfffffffd + 4 -> 1 -> 0.
    assert_eq!(
        one("chd", &[3, 0, 4], &[(4, [0xf, 0, 0, 0])]),
        with(14, &[2, 3])
    );
    assert_eq!(
        one("cdd", &[3, 1, 4], &[(4, [7, 0, 0, 0])]),
        with(8, &[0, 1, 2, 3, 4, 5, 6, 7])
    );
    assert_eq!(
        one("cwd", &[3, 4, 4], &[(4, [neg(-3), 0, 0, 0])]),
        with(0, &[0, 1, 2, 3])
    );
    assert_eq!(
        one("cbd", &[3, 0x7f, 4], &[(4, [0, 0, 0, 0])]),
        with(15, &[3])
    );
    // c?x: t = (ra + rb) & 0xf.
    assert_eq!(
        one("cdx", &[3, 4, 5], &[(4, [3, 0, 0, 0]), (5, [4, 0, 0, 0])]),
        with(0, &[0, 1, 2, 3, 4, 5, 6, 7])
    );
    assert_eq!(
        one(
            "cdx",
            &[3, 4, 5],
            &[(4, [0x3fff8, 0, 0, 0]), (5, [0x10, 0, 0, 0])]
        ),
        with(8, &[0, 1, 2, 3, 4, 5, 6, 7])
    );
    assert_eq!(
        one("chx", &[3, 4, 5], &[(4, [1, 0, 0, 0]), (5, [2, 0, 0, 0])]),
        with(2, &[2, 3])
    );
    assert_eq!(
        one(
            "cbx",
            &[3, 4, 5],
            &[(4, [0x100, 0, 0, 0]), (5, [0xa, 0, 0, 0])]
        ),
        with(10, &[3])
    );
}

#[test]
fn compares_of_every_width_and_signedness() {
    let (w1, w2) = (
        [0x8000_0000, 0x7fff_ffff, 0, M],
        [0x7fff_ffff, 0x8000_0000, M, 0],
    );
    assert_eq!(rr("cgt", w1, w2), [0, M, M, 0]);
    assert_eq!(rr("clgt", w1, w2), [M, 0, 0, M]);
    assert_eq!(rr("ceq", [1, 2, 3, 4], [1, 0, 3, 0]), [M, 0, M, 0]);
    // Halfwords: 0x8000 is -32768 signed.
    assert_eq!(
        rr("cgth", [0x8000_7fff; 4], [0x7fff_8000; 4])[0],
        0x0000_ffff
    );
    assert_eq!(
        rr("clgth", [0x8000_7fff; 4], [0x7fff_8000; 4])[0],
        0xffff_0000
    );
    assert_eq!(
        rr("ceqh", [0x0001_0002; 4], [0x0001_0003; 4])[0],
        0xffff_0000
    );
    // Bytes.
    assert_eq!(
        rr("cgtb", [0x807f_00ff; 4], [0x7f80_ff00; 4])[0],
        0x00ff_ff00
    );
    assert_eq!(
        rr("clgtb", [0x807f_00ff; 4], [0x7f80_ff00; 4])[0],
        0xff00_00ff
    );
    assert_eq!(
        rr("ceqb", [0x0102_0304; 4], [0x0100_0300; 4])[0],
        0xff00_ff00
    );
    // Word immediates: I10 sign-extended to 32 bits; clgti compares unsigned with
    // 0xfffffe00 for -512.
    assert_eq!(
        ri("clgti", [0xffff_fe01, 0xffff_fe00, 0x7fff_ffff, M], -512),
        [M, 0, 0, M]
    );
    assert_eq!(ri("ceqi", [0xffff_fe00, 0x200, 0, 0], -512), [M, 0, 0, 0]);
    assert_eq!(
        ri("cgti", [0, M, 0x8000_0000, 0x7fff_ffff], -1),
        [M, 0, 0, M]
    );
    // Halfword immediates: I10 sign-extended to 16 bits.
    assert_eq!(ri("ceqhi", [0xffff_fffe; 4], -1)[0], 0xffff_0000);
    assert_eq!(ri("cgthi", [0x0000_8000; 4], -1)[0], 0xffff_0000);
    assert_eq!(ri("clgthi", [0xffff_0000; 4], -1)[0], 0); // nothing is > 0xffff
    assert_eq!(ri("clgthi", [0x0200_01ff; 4], 511)[0], 0xffff_0000);
    // Byte immediates: the low 8 bits of I10 (-128 -> 0x80, 127 -> 0x7f).
    assert_eq!(ri("cgtbi", [0x807f_00ff; 4], -128)[0], 0x00ff_ffff);
    assert_eq!(ri("clgtbi", [0x807f_00ff; 4], 0x7f)[0], 0xff00_00ff);
    assert_eq!(ri("ceqbi", [0x807f_00ff; 4], -128)[0], 0xff00_0000);
}

#[test]
fn immediate_load_extremes() {
    // il: I16 sign-extended into every word.
    assert_eq!(one("il", &[3, -32768], &[]), [0xffff_8000; 4]);
    assert_eq!(one("il", &[3, 32767], &[]), [0x7fff; 4]);
    // ilh: I16 into both halfwords; ilhu: into the upper halfword, lower zero.
    assert_eq!(one("ilh", &[3, 0xffff], &[]), [M; 4]);
    assert_eq!(one("ilhu", &[3, 0xffff], &[]), [0xffff_0000; 4]);
    // ila: I18 zero-extended.
    assert_eq!(one("ila", &[3, 0x20000], &[]), [0x20000; 4]);
    // ilhu + iohl build any word; iohl ORs the zero-extended I16 (no sign extension).
    let (spu, _) = run(&[("ilhu", &[3, 0x8765]), ("iohl", &[3, 0x8321])], &[]);
    assert_eq!(spu.reg(3), [0x8765_8321; 4]);
}

#[test]
fn loads_and_stores_wrap_at_256k_and_mask_the_low_4_bits() {
    let v = [0x1111_1111, 0x2222_2222, 0x3333_3333, 0x4444_4444];
    // stqd $5,-32($4) with $4 = 0x10 -> 0x10 - 0x20 = -0x10 -> 0x3fff0 (mod 256 KiB);
    // lqa 0x3fff0, lqx 0x3fff4 + 0x40000 (wraps, low 4 bits dropped), lqd 16(0x3ffef) and
    // lqr all read the same quadword back.
    let (spu, stop) = run(
        &[
            ("stqd", &[5, -32, 4]),
            ("lqa", &[6, 0x3fff0]),
            ("lqx", &[7, 8, 9]),
            ("lqd", &[10, 16, 11]),
            ("lqr", &[12, 0x3fff0]),
        ],
        &[
            (4, [0x10, 0xdead, 0xbeef, 0]),
            (5, v),
            (8, [0x3fff4, 0, 0, 0]),
            (9, [0x4_0000, 0, 0, 0]), // 0x3fff4 + 0x40000 = 0x7fff4 -> 0x3fff4 -> 0x3fff0
            (11, [0x3ffef, 0, 0, 0]), // 0x3ffef + 16 = 0x3ffff -> 0x3fff0
        ],
    );
    assert_eq!(stop, StopReason::Stop(0x3fff));
    assert_eq!(&spu.ls()[0x3fff0..0x3fff4], &[0x11; 4]);
    for r in [6, 7, 10, 12] {
        assert_eq!(spu.reg(r), v, "${r}");
    }
    // lqr is PC-relative: at pc 0, target -16 wraps to 0x3fff0 too (encoded as pc + imm).
    let mut image = Vec::new();
    let lqr = forms_named("lqr").next().unwrap();
    // I16 = -4 words: 0 - 16 -> 0x3fff0.
    image.extend((spu_isa::encode(lqr, &[3, 0], 0) | ((0xfffc & 0xffff) << 7)).to_be_bytes());
    image.extend(word("stop", &[1], 4).to_be_bytes());
    let mut s = Spu::new(0);
    s.load_image(&image);
    s.write_ls(0x3fff0, &[0xab; 16]);
    assert_eq!(
        s.run(&mut MainMemory::zeroed(16), 1000),
        StopReason::Stop(1)
    );
    assert_eq!(s.reg(3), [0xabab_abab; 4]);
    // stqx: the address is (ra + rb) & 0x3fff0 -- low 4 bits dropped.
    let (spu, _) = run(
        &[("stqx", &[5, 4, 6])],
        &[(4, [0x2005, 0, 0, 0]), (5, v), (6, [0x0a, 0, 0, 0])],
    );
    assert_eq!(&spu.ls()[0x2000..0x2004], &[0x11; 4]);
    assert_eq!(&spu.ls()[0x200c..0x2010], &[0x44; 4]);
}

#[test]
fn branch_targets_links_and_conditions() {
    // bisl: link = pc + 4 in the preferred slot (rest zero), target = ra & 0x3fffc.
    let (spu, stop) = run(
        &[
            ("bisl", &[3, 4]),
            ("stop", &[1]),
            ("stop", &[2]),
            ("stop", &[3]),
        ],
        &[(4, [0x4000b, 5, 5, 5])],
    );
    assert_eq!(stop, StopReason::Stop(2)); // 0x4000b & 0x3fffc = 8, the second stop
    assert_eq!(spu.reg(3), [4, 0, 0, 0]);
    // biz rt,ra: branch to ra if rt (preferred slot) is zero; other words ignored.
    let (_, stop) = run(
        &[("biz", &[4, 5]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0, 1, 1, 1]), (5, [8, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    let (_, stop) = run(
        &[("biz", &[4, 5]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0x10000, 0, 0, 0]), (5, [8, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(1));
    // brhz/brhnz test bits 16..31 of the preferred slot only.
    let (_, stop) = run(
        &[("brhnz", &[4, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0xffff_0000, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(1));
    let (_, stop) = run(
        &[("brhnz", &[4, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0x0000_0100, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    // brnz looks at the whole preferred slot, not the other words.
    let (_, stop) = run(
        &[("brnz", &[4, 8]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [0, M, M, M])],
    );
    assert_eq!(stop, StopReason::Stop(1));
    // bra (absolute) and brasl (absolute, linked).
    let (spu, stop) = run(
        &[
            ("brasl", &[3, 12]),
            ("stop", &[1]),
            ("stop", &[2]),
            ("stop", &[3]),
        ],
        &[],
    );
    assert_eq!((stop, spu.reg(3)), (StopReason::Stop(3), [4, 0, 0, 0]));
    // D and E bits: bie enables interrupts, bid disables them, as the branch is taken.
    let (spu, stop) = run(
        &[("bie", &[4]), ("stop", &[1]), ("stop", &[2])],
        &[(4, [8, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(2));
    assert!(spu.interrupts_enabled(), "bie sets the interrupt enable");
    let (spu, stop) = run(
        &[
            ("bie", &[4]),
            ("stop", &[1]),
            ("bid", &[5]),
            ("stop", &[3]),
            ("stop", &[4]),
        ],
        &[(4, [8, 0, 0, 0]), (5, [16, 0, 0, 0])],
    );
    assert_eq!(stop, StopReason::Stop(4));
    assert!(!spu.interrupts_enabled(), "bid clears it");
    // The D/E bits are bits 19/18 of the word: bie $4 = bi $4 | 0x10 << 14.
    assert_eq!(word("bie", &[4], 0), word("bi", &[4], 0) | 0x10 << 14);
    assert_eq!(word("bid", &[3], 0), 0x3508_0180);
}

#[test]
fn halts_on_register_compares() {
    // heq ra,rb halts if the preferred slots are equal; hgt signed; hlgt unsigned.
    let h = |m: &str, a: u32, b: u32| {
        run(
            &[(m, &[4, 5]), ("stop", &[1])],
            &[(4, [a, 9, 9, 9]), (5, [b, 0, 0, 0])],
        )
        .1
    };
    let halt = StopReason::Halt { pc: 0 };
    assert_eq!(h("heq", 7, 7), halt);
    assert_eq!(h("heq", 7, 8), StopReason::Stop(1));
    assert_eq!(h("hgt", 1, M), halt); // 1 > -1
    assert_eq!(h("hgt", M, 1), StopReason::Stop(1));
    assert_eq!(h("hlgt", M, 1), halt);
    assert_eq!(h("hlgt", 1, M), StopReason::Stop(1));
    assert_eq!(h("hlgt", 5, 5), StopReason::Stop(1));
    // Immediate forms: heqi/hgti sign-extend I10; hlgti compares unsigned with it.
    let hi = |m: &str, a: u32, i: i64| run(&[(m, &[4, i]), ("stop", &[1])], &[(4, [a, 0, 0, 0])]).1;
    assert_eq!(hi("heqi", neg(-512), -512), halt);
    assert_eq!(hi("hgti", 0, -1), halt);
    assert_eq!(hi("hlgti", 0, -1), StopReason::Stop(1)); // 0 > 0xffffffff is false
    assert_eq!(hi("hlgti", M, -2), halt);
    // stop codes: the low 14 bits of the word.
    for code in [0, 1, 0x2000, 0x3fff] {
        assert_eq!(
            run(&[("stop", &[code])], &[]).1,
            StopReason::Stop(code as u16)
        );
    }
}

#[test]
fn single_precision_saturation_denormals_truncation_and_fused_rounding() {
    // fm: 2^127 * 4 = 2^129 exceeds (2 - 2^-23) * 2^128: saturates to 0x7fffffff.
    assert_eq!(rr("fm", [0x7f00_0000; 4], [0x4080_0000; 4])[0], 0x7fff_ffff);
    // 2^127 * 2 = 2^128 is an ordinary number with exponent 255 (not infinity).
    assert_eq!(rr("fm", [0x7f00_0000; 4], [F2; 4])[0], 0x7f80_0000);
    // Denormal input (exponent 0) reads as zero even times the largest number.
    assert_eq!(rr("fm", [0x0040_0000; 4], [0x7fff_ffff; 4])[0], 0);
    assert_eq!(rr("fa", [0x8000_0001; 4], [F1; 4])[0], F1);
    // Truncation: 1.5 * (1 + 2^-23) = 1.5 + 2^-23 + 2^-24 -> 0x3fc00001 (IEEE nearest-even
    // would give 0x3fc00002 on this tie).
    assert_eq!(rr("fm", [0x3fc0_0000; 4], [0x3f80_0001; 4])[0], 0x3fc0_0001);
    // Negative products truncate toward zero as well.
    assert_eq!(rr("fm", [0xbfc0_0000; 4], [0x3f80_0001; 4])[0], 0xbfc0_0001);
    // fma single rounding: (1 + 2^-23)^2 - (1 + 2^-22) = 2^-46 exactly (0x28800000); with
    // the product rounded first it would be 0.
    assert_eq!(
        rrr("fma", [0x3f80_0001; 4], [0x3f80_0001; 4], [0xbf80_0002; 4])[0],
        0x2880_0000
    );
    // fnms: c - a*b, single truncation: 1 + 2^-22 - (1+2^-23)^2 = -2^-46.
    assert_eq!(
        rrr("fnms", [0x3f80_0001; 4], [0x3f80_0001; 4], [0x3f80_0002; 4])[0],
        0xa880_0000
    );
    // Results below the smallest normal (2^-126) are +0: 2^-64 * 2^-64.
    assert_eq!(rr("fm", [0x1f80_0000; 4], [0x9f80_0000; 4])[0], 0);
}

#[test]
fn conversion_saturation_and_scales() {
    // cflts: x * 2^scale truncated toward zero, saturated to [-2^31, 2^31 - 1].
    assert_eq!(ri("cflts", [0x4eff_ffff; 4], 0)[0], 0x7fff_ff80); // 2^31 - 128
    assert_eq!(ri("cflts", [0xcf00_0000; 4], 0)[0], 0x8000_0000); // -2^31 exactly
    assert_eq!(ri("cflts", [0xcf80_0000; 4], 0)[0], 0x8000_0000); // -2^32 saturates
    assert_eq!(ri("cflts", [0x7fff_ffff; 4], 0)[0], 0x7fff_ffff); // largest SPU float

    // 1.5 * 2 = 3; 2^127 saturates; a denormal is zero.
    assert_eq!(ri("cflts", [0x3fc0_0000; 4], 1)[0], 3);
    assert_eq!(ri("cflts", [F1; 4], 127)[0], 0x7fff_ffff);
    assert_eq!(ri("cflts", [0x0040_0000; 4], 127)[0], 0);
    // cfltu: negatives give 0, 2^32 and beyond give 0xffffffff.
    assert_eq!(ri("cfltu", [0x4f7f_ffff; 4], 0)[0], 0xffff_ff00);
    assert_eq!(ri("cfltu", [0xbf00_0000; 4], 0)[0], 0);
    assert_eq!(ri("cfltu", [0xcf00_0000; 4], 0)[0], 0);
    assert_eq!(ri("cfltu", [F1; 4], 32)[0], M);
    assert_eq!(ri("cfltu", [0x3f00_0000; 4], 31)[0], 0x4000_0000);
    // csflt: int -> float, truncated, then divided by 2^scale.
    assert_eq!(ri("csflt", [0x8000_0000; 4], 31)[0], 0xbf80_0000); // -2^31 / 2^31
    assert_eq!(ri("csflt", [3; 4], 1)[0], 0x3fc0_0000);
    assert_eq!(ri("csflt", [0x7fff_ffff; 4], 0)[0], 0x4eff_ffff); // truncated, not 2^31
    assert_eq!(ri("csflt", [0; 4], 5)[0], 0);
    // cuflt: (2^32 - 1) / 2^32 truncated = 1 - 2^-24 -> 0x3f7fffff.
    assert_eq!(ri("cuflt", [M; 4], 32)[0], 0x3f7f_ffff);
}

#[test]
fn reciprocal_estimate_refined_by_fi() {
    // frest alone is a table base/step encoding, only roughly 1/x; `frest` then `fi`
    // (spu_re in the SDK) is documented as accurate to 12 bits; one Newton-Raphson step in
    // the core, e = 1 - x*y (fnms), y' = y + e*y (fma), then gets within a few ulps (each
    // operation truncates). Checked for several magnitudes and both signs.
    for x in [2.0f32, 3.0, 0.1, 7.5, -1.0e30, 1.0e-20, -0.3333] {
        let xb = x.to_bits();
        let (spu, stop) = run(
            &[
                ("frest", &[5, 4]),
                ("fi", &[6, 4, 5]),
                ("fnms", &[7, 4, 6, 9]),
                ("fma", &[8, 7, 6, 6]),
            ],
            &[(4, [xb; 4]), (9, [F1; 4])],
        );
        assert_eq!(stop, StopReason::Stop(0x3fff));
        let est = f32::from_bits(spu.reg(5)[0]) as f64;
        let fi = f32::from_bits(spu.reg(6)[0]) as f64;
        let nr = f32::from_bits(spu.reg(8)[0]) as f64;
        let exact = 1.0 / x as f64;
        let rel = |v: f64| ((v - exact) / exact).abs();
        // The raw estimate carries the interpolation step in its low fraction bits: only its
        // sign and exponent are meaningful on their own.
        assert!(rel(est) < 1.0 / 16.0, "frest {x}: {est}");
        assert!(rel(fi) < 1.0 / 4096.0, "fi {x}: {fi}");
        assert!(rel(nr) < 4.0 / (1u64 << 23) as f64, "newton {x}: {nr}");
        assert_eq!(fi.is_sign_negative(), x < 0.0);
        // Every slot gets the same answer.
        assert_eq!(spu.reg(6), [spu.reg(6)[0]; 4]);
    }
}

#[test]
fn double_precision_rounding_modes_flags_and_overflow() {
    let a = 0x3ff0_0000_0000_0001u64; // 1 + 2^-52
    let na = a | 1 << 63;
    // a * a = 1 + 2^-51 + 2^-104: nearest and toward-zero give 1 + 2^-51 (...002),
    // toward +inf ...003; for -(a) * a, toward -inf gives -(...003).
    let fpscr = |m0: u32, m1: u32| [(m0 << 10) | (m1 << 8), 0, 0, 0];
    let both = |x: u64, y: u64| [(x >> 32) as u32, x as u32, (y >> 32) as u32, y as u32];
    let dfm = |m0: u32, m1: u32, x: R, y: R| {
        run(
            &[("fscrwr", &[0, 8]), ("dfm", &[3, 4, 5]), ("fscrrd", &[7])],
            &[(8, fpscr(m0, m1)), (4, x), (5, y)],
        )
        .0
    };
    let s = dfm(0, 1, both(a, a), both(a, a));
    assert_eq!(s.reg(3), both(0x3ff0_0000_0000_0002, 0x3ff0_0000_0000_0002));
    // INX is bit 11 of word 1 (slot 0) and word 2 (slot 1); the modes read back.
    assert_eq!(s.reg(7), [0x100, 0x800, 0x800, 0]);
    let s = dfm(2, 3, both(a, na), both(a, a));
    assert_eq!(s.reg(3), both(0x3ff0_0000_0000_0003, 0xbff0_0000_0000_0003));
    let s = dfm(3, 2, both(a, na), both(a, a));
    assert_eq!(s.reg(3), both(0x3ff0_0000_0000_0002, 0xbff0_0000_0000_0002));
    // An exact product raises nothing.
    let s = dfm(
        0,
        0,
        both(0x4000_0000_0000_0000, 0x4008_0000_0000_0000),
        both(0x3fe0_0000_0000_0000, 0x4000_0000_0000_0000),
    );
    assert_eq!(s.reg(3), both(0x3ff0_0000_0000_0000, 0x4018_0000_0000_0000));
    assert_eq!(s.reg(7), [0; 4]);
    // Overflow: 2^1000 * 2^100. Nearest -> +inf, toward zero -> the largest finite; both
    // raise OVF (bit 13) and INX (bit 11).
    let big = 0x7e70_0000_0000_0000u64; // 2^1000
    let hundred = 0x4630_0000_0000_0000u64; // 2^100
    let s = dfm(0, 1, both(big, big), both(hundred, hundred));
    assert_eq!(s.reg(3), both(0x7ff0_0000_0000_0000, 0x7fef_ffff_ffff_ffff));
    assert_eq!(s.reg(7)[1..3], [0x2800, 0x2800]);
    // dfa in mode toward -inf: 1 + (-1) = -0 (IEEE: exact zero sum of opposite signs is -0
    // only when rounding toward -inf).
    let s = run(
        &[("fscrwr", &[0, 8]), ("dfa", &[3, 4, 5])],
        &[
            (8, fpscr(3, 0)),
            (4, both(0x3ff0_0000_0000_0000, 0x3ff0_0000_0000_0000)),
            (5, both(0xbff0_0000_0000_0000, 0xbff0_0000_0000_0000)),
        ],
    )
    .0;
    assert_eq!(s.reg(3), both(0x8000_0000_0000_0000, 0));
    // The flags are sticky: a later exact operation does not clear them; fscrwr does.
    let s = run(
        &[
            ("dfm", &[3, 4, 4]),
            ("dfa", &[6, 9, 9]),
            ("fscrrd", &[7]),
            ("fscrwr", &[0, 8]),
            ("fscrrd", &[10]),
        ],
        &[(4, both(a, a)), (9, both(0, 0)), (8, [0; 4])],
    )
    .0;
    assert_eq!(s.reg(7)[1..3], [0x800, 0x800]);
    assert_eq!(s.reg(10), [0; 4]);
}

/// Formats all 128 registers as `$N: w0 w1 w2 w3`.
fn register_dump(spu: &Spu) -> String {
    (0..128)
        .map(|n| {
            let r = spu.reg(n);
            format!(
                "${n}: {:08x} {:08x} {:08x} {:08x}\n",
                r[0], r[1], r[2], r[3]
            )
        })
        .collect()
}

#[test]
fn register_dump_after_a_small_mixed_program() {
    // Expected (checked by hand against the accepted snapshot):
    //  $3  il -1                          ffffffff x4
    //  $4  ilhu 0x1234; iohl 0x5678       12345678 x4
    //  $5  ila 0x3ffff                    0003ffff x4
    //  $6  a $4,$5                        12385677 x4
    //  $7  fsmbi 0xf00f                   ffffffff 00000000 00000000 ffffffff
    //  $8  selb $4,$3,$7                  ffffffff 12345678 12345678 ffffffff
    //  $9  shlqbyi $4,2                   56781234 56781234 56781234 56780000
    //  $10 rotqbyi $8,4                   12345678 12345678 ffffffff ffffffff
    //  $11 cwd 8($0)                      10111213 14151617 00010203 1c1d1e1f
    //  $12 shufb $4,$5,$11                0003ffff 0003ffff 12345678 0003ffff
    //  $13 mpyu $4,$4 = 0x5678^2          1d34d840 x4
    //  $14 clz $5 (18 significant bits)   0000000e x4
    //  $15 clgt $3,$4                     ffffffff x4
    //  $16 xsbh $4 (0x34, 0x78 positive)  00340078 x4
    //  $17 brsl at 0x3c to 0x40           00000040 00000000 00000000 00000000
    //  $18 sf $4,$5 = 0x3ffff - 0x12345678 edcfa987 x4
    // and every other register zero.
    let (spu, stop) = run(
        &[
            ("il", &[3, -1]),
            ("ilhu", &[4, 0x1234]),
            ("iohl", &[4, 0x5678]),
            ("ila", &[5, 0x3ffff]),
            ("a", &[6, 4, 5]),
            ("fsmbi", &[7, 0xf00f]),
            ("selb", &[8, 4, 3, 7]),
            ("shlqbyi", &[9, 4, 2]),
            ("rotqbyi", &[10, 8, 4]),
            ("cwd", &[11, 8, 0]),
            ("shufb", &[12, 4, 5, 11]),
            ("mpyu", &[13, 4, 4]),
            ("clz", &[14, 5]),
            ("clgt", &[15, 3, 4]),
            ("xsbh", &[16, 4]),
            ("brsl", &[17, 0x40]),
            ("sf", &[18, 4, 5]),
        ],
        &[],
    );
    assert_eq!(stop, StopReason::Stop(0x3fff));
    insta::assert_snapshot!(register_dump(&spu));
}

#[test]
fn logical_operations_bitwise() {
    // a = ff00ff00, b = 0ff00ff0: every combination of bit pairs appears.
    let (a, b) = ([0xff00_ff00; 4], [0x0ff0_0ff0; 4]);
    assert_eq!(rr("and", a, b)[0], 0x0f00_0f00);
    assert_eq!(rr("or", a, b)[0], 0xfff0_fff0);
    assert_eq!(rr("xor", a, b)[0], 0xf0f0_f0f0);
    assert_eq!(rr("nand", a, b)[0], 0xf0ff_f0ff);
    assert_eq!(rr("nor", a, b)[0], 0x000f_000f);
    // andc is a & !b, orc a | !b
    assert_eq!(rr("andc", a, b)[0], 0xf000_f000);
    assert_eq!(rr("orc", a, b)[0], 0xff0f_ff0f);
    // eqv is !(a ^ b).
    assert_eq!(rr("eqv", a, b)[0], 0x0f0f_0f0f);
    // Immediate forms: andi/ori/xori sign-extend I10 to 32 bits; xorhi to 16; xorbi uses
    // the low 8 bits.
    assert_eq!(ri("andi", a, -256)[0], 0xff00_ff00);
    assert_eq!(ri("xori", a, -1)[0], 0x00ff_00ff);
    assert_eq!(ri("xorhi", a, 0x1ff)[0], 0xfeff_feff); // each ff00 ^ 01ff = feff
    assert_eq!(ri("xorbi", a, 0x0f)[0], 0xf00f_f00f);
}

#[test]
fn indirect_halfword_branches_test_the_low_halfword() {
    // bihz rt,ra / bihnz rt,ra: condition on bits 16..31 of rt's preferred slot.
    let go = |m: &str, t: u32| {
        run(
            &[(m, &[4, 5]), ("stop", &[1]), ("stop", &[2])],
            &[(4, [t, 0, 0, 0]), (5, [8, 0, 0, 0])],
        )
        .1
    };
    assert_eq!(go("bihz", 0xffff_0000), StopReason::Stop(2));
    assert_eq!(go("bihz", 0x0000_0001), StopReason::Stop(1));
    assert_eq!(go("bihnz", 0xffff_0000), StopReason::Stop(1));
    assert_eq!(go("bihnz", 0x0000_8000), StopReason::Stop(2));
    assert_eq!(go("binz", 0xffff_0000), StopReason::Stop(2));
}

#[test]
fn float_compares_with_extended_range_and_zero() {
    // Exponent 255 numbers are ordinary: 0x7fffffff > 0x7f800000; -0 is not below +0;
    // a denormal compares equal to (not greater than) zero.
    assert_eq!(
        rr(
            "fcgt",
            [0x7fff_ffff, 0, 0x0000_0001, 0xff80_0000],
            [0x7f80_0000, 0x8000_0000, 0, 0xffff_ffff]
        ),
        [M, 0, 0, M]
    );
    assert_eq!(rr("fcmgt", [0xffff_ffff; 4], [0x7f80_0000; 4])[0], M);
}

#[test]
fn double_precision_nan_and_invalid() {
    let both = |x: u64| [(x >> 32) as u32, x as u32, (x >> 32) as u32, x as u32];
    // A quiet NaN operand gives the default QNaN and sets NAN (bit 9) in word 1 and 2;
    // a signalling NaN also sets INV (bit 10); inf - inf is invalid.
    let (spu, _) = run(
        &[("dfa", &[3, 4, 5]), ("fscrrd", &[7])],
        &[
            (4, both(0x7ff8_0000_0000_1234)),
            (5, both(0x3ff0_0000_0000_0000)),
        ],
    );
    assert_eq!(spu.reg(3), both(0x7ff8_0000_0000_0000));
    assert_eq!(spu.reg(7)[1] & 0x0600, 0x0200);
    let (spu, _) = run(
        &[("dfm", &[3, 4, 5]), ("fscrrd", &[7])],
        &[
            (4, both(0x7ff0_0000_0000_0001)),
            (5, both(0x3ff0_0000_0000_0000)),
        ],
    );
    assert_eq!(spu.reg(3), both(0x7ff8_0000_0000_0000));
    assert_eq!(spu.reg(7)[1] & 0x0600, 0x0600);
    let (spu, _) = run(
        &[("dfs", &[3, 4, 4]), ("fscrrd", &[7])],
        &[(4, both(0x7ff0_0000_0000_0000))],
    );
    assert_eq!(spu.reg(3), both(0x7ff8_0000_0000_0000));
    assert_ne!(spu.reg(7)[2] & 0x0400, 0);
}

/// The core truncates with the host's own float unit while it runs (the fast loops hold
/// MXCSR at round-toward-zero); afterwards the host rounds to nearest again: 1 + 2^-24 *
/// (2 - 2^-23) is just over half an ulp of 1.0, so it rounds up on the host but truncates
/// to 1.0 on the SPU.
#[test]
fn the_host_rounds_to_nearest_again_after_the_spu_truncates() {
    use std::hint::black_box;
    let (one_f, tiny) = (1.0f32, f32::from_bits(0x33ff_ffff));
    let on_spu = rr("fa", [one_f.to_bits(); 4], [tiny.to_bits(); 4]);
    assert_eq!(on_spu, [0x3f80_0000; 4]);
    let on_host = black_box(one_f) + black_box(tiny);
    assert_eq!(on_host.to_bits(), 0x3f80_0001);
}
