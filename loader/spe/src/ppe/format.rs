//! The printf engine over local store: a format string and an SPU `va_list` (each argument
//! in a 16-byte slot, the value in the preferred slot; the list jumps over the caller's
//! 32-byte link area where the register save area ends) formatted as glibc formats them
//! for the PPE handler, plus the AltiVec-style vector conversions (`%vd`, `%,vhx`,
//! `%vlu`, `%vf`...) the SDK's printf accepted. `%n` is refused.

use super::{Fault, Ls};

/// The SPU ABI's `va_list`: the next argument's slot and where the caller's stack
/// begins.
#[derive(Clone, Copy, Debug)]
pub struct VaList {
    pub next: u32,
    pub caller_stack: u32,
}

/// No conversion may produce more than this (width and precision included): beyond it
/// the call fails with EOVERFLOW instead of filling the host's memory.
pub const MAX_FIELD: usize = 1 << 20;

pub enum FormatError {
    Fault(Fault),
    Overflow,
}

impl From<Fault> for FormatError {
    fn from(f: Fault) -> Self {
        FormatError::Fault(f)
    }
}

impl VaList {
    /// The next argument's 16-byte slot.
    fn slot(&mut self, ls: &Ls) -> Result<[u8; 16], Fault> {
        let q = ls.quad(self.next, "a printf argument")?;
        self.next = self.next.wrapping_add(16);
        if self.next == self.caller_stack {
            self.next = self.next.wrapping_add(32);
        }
        Ok(q)
    }
    fn int(&mut self, ls: &Ls) -> Result<u32, Fault> {
        let q = self.slot(ls)?;
        Ok(u32::from_be_bytes([q[0], q[1], q[2], q[3]]))
    }
    fn long_long(&mut self, ls: &Ls) -> Result<u64, Fault> {
        let q = self.slot(ls)?;
        Ok(u64::from_be_bytes(q[..8].try_into().unwrap()))
    }
}

#[derive(Default, Clone, Copy)]
struct Spec {
    minus: bool,
    plus: bool,
    space: bool,
    hash: bool,
    zero: bool,
    width: usize,
    precision: Option<usize>,
    /// 'h' count, 'l' count (j = 2; z, t = 1 are 32-bit on the SPU).
    h: u8,
    l: u8,
    vector: bool,
    separator: Option<u8>,
}

/// Formats `fmt` with arguments from `va`.
pub fn format(ls: &Ls, fmt: &[u8], va: &mut VaList) -> Result<Vec<u8>, FormatError> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < fmt.len() {
        let c = fmt[i];
        if c != b'%' {
            out.push(c);
            i += 1;
            continue;
        }
        let start = i;
        i += 1;
        let mut s = Spec::default();
        // Flags, with the vector flag and its separator among them.
        while let Some(&f) = fmt.get(i) {
            match f {
                b'-' => s.minus = true,
                b'+' => s.plus = true,
                b' ' => s.space = true,
                b'#' => s.hash = true,
                b'0' => s.zero = true,
                b'v' => s.vector = true,
                b',' | b';' | b':' | b'_' => s.separator = Some(f),
                _ => break,
            }
            i += 1;
        }
        let number = |i: &mut usize, va: &mut VaList| -> Result<Option<i64>, FormatError> {
            if fmt.get(*i) == Some(&b'*') {
                *i += 1;
                return Ok(Some(va.int(ls)? as i32 as i64));
            }
            let d = fmt[*i..].iter().take_while(|c| c.is_ascii_digit()).count();
            if d == 0 {
                return Ok(None);
            }
            let v = std::str::from_utf8(&fmt[*i..*i + d])
                .ok()
                .and_then(|t| t.parse::<i64>().ok())
                .unwrap_or(i64::MAX);
            *i += d;
            Ok(Some(v))
        };
        if let Some(w) = number(&mut i, va)? {
            if w < 0 {
                s.minus = true;
            }
            s.width = w.unsigned_abs().min(usize::MAX as u64) as usize;
        }
        if fmt.get(i) == Some(&b'.') {
            i += 1;
            let p = number(&mut i, va)?.unwrap_or(0);
            s.precision = (p >= 0).then_some(p as usize);
        }
        // Length modifiers (and `v` after them, as `%hvd`).
        while let Some(&m) = fmt.get(i) {
            match m {
                b'h' => s.h += 1,
                b'l' => s.l += 1,
                b'j' | b'q' => s.l = 2,
                b'L' => s.l = 2,
                b'z' | b't' => {}
                b'v' => s.vector = true,
                _ => break,
            }
            i += 1;
        }
        if s.width > MAX_FIELD || s.precision.unwrap_or(0) > MAX_FIELD {
            return Err(FormatError::Overflow);
        }
        let Some(&conv) = fmt.get(i) else {
            out.extend_from_slice(&fmt[start..]);
            break;
        };
        i += 1;
        match conv {
            b'%' => out.push(b'%'),
            b'n' => {
                return Err(FormatError::Fault(Fault(
                    "printf: %n (writing the count into the program's memory) is refused"
                        .to_string(),
                )))
            }
            _ if s.vector => vector(ls, va, &s, conv, &mut out)?,
            b'd' | b'i' | b'u' | b'o' | b'x' | b'X' | b'c' => {
                let v = if s.l >= 2 {
                    va.long_long(ls)?
                } else {
                    va.int(ls)? as u64
                };
                integer(&s, conv, v, if s.l >= 2 { 64 } else { 32 }, &mut out);
            }
            b'p' => {
                let v = va.int(ls)?;
                if v == 0 {
                    pad(&s, b"(nil)".to_vec(), &mut out);
                } else {
                    let mut t = s;
                    t.hash = true;
                    integer(&t, b'x', v as u64, 32, &mut out);
                }
            }
            b's' => {
                let p = va.int(ls)?;
                let text = if p == 0 {
                    match s.precision {
                        Some(n) if n < 6 => Vec::new(),
                        _ => b"(null)".to_vec(),
                    }
                } else {
                    ls.cstr_max(p, s.precision, "a printf %s string")?
                };
                pad(&s, text, &mut out);
            }
            b'f' | b'F' | b'e' | b'E' | b'g' | b'G' | b'a' | b'A' => {
                let q = va.slot(ls)?;
                let v = f64::from_be_bytes(q[..8].try_into().unwrap());
                float(&s, conv, v, &mut out);
            }
            _ => out.extend_from_slice(&fmt[start..i]),
        }
        if out.len() > 16 * MAX_FIELD {
            return Err(FormatError::Overflow);
        }
    }
    Ok(out)
}

/// A vector conversion: one 16-byte argument, each element formatted alike and joined by
/// the separator (a space, none for `%vc`).
fn vector(
    ls: &Ls,
    va: &mut VaList,
    s: &Spec,
    conv: u8,
    out: &mut Vec<u8>,
) -> Result<(), FormatError> {
    let q = va.slot(ls)?;
    let sep = s.separator.map(|c| vec![c]).unwrap_or_else(|| {
        if conv == b'c' {
            Vec::new()
        } else {
            vec![b' ']
        }
    });
    let mut elems: Vec<Vec<u8>> = Vec::new();
    let mut e = *s;
    e.vector = false;
    match conv {
        b'd' | b'i' | b'u' | b'o' | b'x' | b'X' | b'c' => {
            let size = if s.l >= 2 {
                8
            } else if s.l == 1 {
                4
            } else if s.h >= 1 {
                2
            } else {
                1
            };
            for chunk in q.chunks(size) {
                let mut v = 0u64;
                for b in chunk {
                    v = v << 8 | *b as u64;
                }
                let mut o = Vec::new();
                integer(&e, conv, v, size as u32 * 8, &mut o);
                elems.push(o);
            }
        }
        b'f' | b'F' | b'e' | b'E' | b'g' | b'G' | b'a' | b'A' => {
            if s.l >= 1 {
                for chunk in q.chunks(8) {
                    let mut o = Vec::new();
                    float(
                        &e,
                        conv,
                        f64::from_be_bytes(chunk.try_into().unwrap()),
                        &mut o,
                    );
                    elems.push(o);
                }
            } else {
                for chunk in q.chunks(4) {
                    let v = f32::from_be_bytes(chunk.try_into().unwrap()) as f64;
                    let mut o = Vec::new();
                    float(&e, conv, v, &mut o);
                    elems.push(o);
                }
            }
        }
        _ => return Ok(()),
    }
    out.extend_from_slice(&elems.join(&sep[..]));
    Ok(())
}

/// Pads `body` to the width (spaces; on the right with `-`).
fn pad(s: &Spec, body: Vec<u8>, out: &mut Vec<u8>) {
    let fill = s.width.saturating_sub(body.len());
    if !s.minus {
        out.extend(std::iter::repeat_n(b' ', fill));
    }
    out.extend_from_slice(&body);
    if s.minus {
        out.extend(std::iter::repeat_n(b' ', fill));
    }
}

/// Sign or prefix, then digits, padded: zeros go between the two.
fn emit(s: &Spec, prefix: &[u8], digits: &[u8], zero_ok: bool, out: &mut Vec<u8>) {
    let len = prefix.len() + digits.len();
    let fill = s.width.saturating_sub(len);
    if s.minus {
        out.extend_from_slice(prefix);
        out.extend_from_slice(digits);
        out.extend(std::iter::repeat_n(b' ', fill));
    } else if s.zero && zero_ok {
        out.extend_from_slice(prefix);
        out.extend(std::iter::repeat_n(b'0', fill));
        out.extend_from_slice(digits);
    } else {
        out.extend(std::iter::repeat_n(b' ', fill));
        out.extend_from_slice(prefix);
        out.extend_from_slice(digits);
    }
}

/// An integer conversion of a `bits`-wide value.
fn integer(s: &Spec, conv: u8, raw: u64, bits: u32, out: &mut Vec<u8>) {
    let mut bits = bits;
    // hh and h narrow the value as C's conversions do.
    if s.h >= 2 && bits > 8 {
        bits = 8;
    } else if s.h == 1 && bits > 16 {
        bits = 16;
    }
    let mask = if bits >= 64 {
        u64::MAX
    } else {
        (1u64 << bits) - 1
    };
    let v = raw & mask;
    if conv == b'c' {
        pad(s, vec![v as u8], out);
        return;
    }
    let signed = matches!(conv, b'd' | b'i');
    let (neg, mag) = if signed {
        let shift = 64 - bits;
        let sv = ((v << shift) as i64) >> shift;
        (sv < 0, sv.unsigned_abs())
    } else {
        (false, v)
    };
    let mut digits = match conv {
        b'o' => format!("{mag:o}"),
        b'x' => format!("{mag:x}"),
        b'X' => format!("{mag:X}"),
        _ => format!("{mag}"),
    }
    .into_bytes();
    if let Some(p) = s.precision {
        if p == 0 && mag == 0 {
            digits.clear();
        }
        if digits.len() < p {
            let mut z = vec![b'0'; p - digits.len()];
            z.extend_from_slice(&digits);
            digits = z;
        }
    }
    let mut prefix: Vec<u8> = Vec::new();
    if signed {
        if neg {
            prefix.push(b'-');
        } else if s.plus {
            prefix.push(b'+');
        } else if s.space {
            prefix.push(b' ');
        }
    }
    if s.hash {
        match conv {
            b'o' if digits.first() != Some(&b'0') => digits.insert(0, b'0'),
            b'x' if mag != 0 => prefix.extend_from_slice(b"0x"),
            b'X' if mag != 0 => prefix.extend_from_slice(b"0X"),
            _ => {}
        }
    }
    emit(s, &prefix, &digits, s.precision.is_none(), out);
}

/// `d.ddde±XX` with `prec` digits after the point.
fn exp_form(v: f64, prec: usize, upper: bool, hash: bool) -> Vec<u8> {
    let t = format!("{v:.prec$e}");
    let (mant, exp) = t.split_once('e').unwrap();
    let exp: i32 = exp.parse().unwrap();
    let mut m = mant.to_string();
    if hash && prec == 0 {
        m.push('.');
    }
    let e = if upper { 'E' } else { 'e' };
    let sign = if exp < 0 { '-' } else { '+' };
    format!("{m}{e}{sign}{:02}", exp.abs()).into_bytes()
}

fn strip_zeros(t: &mut Vec<u8>) {
    if t.contains(&b'.') {
        while t.last() == Some(&b'0') {
            t.pop();
        }
        if t.last() == Some(&b'.') {
            t.pop();
        }
    }
}

/// A floating-point conversion of a double.
fn float(s: &Spec, conv: u8, v: f64, out: &mut Vec<u8>) {
    let upper = conv.is_ascii_uppercase();
    let neg = v.is_sign_negative();
    let a = v.abs();
    let mut prefix: Vec<u8> = Vec::new();
    if neg {
        prefix.push(b'-');
    } else if s.plus {
        prefix.push(b'+');
    } else if s.space {
        prefix.push(b' ');
    }
    if !a.is_finite() {
        let t = match (a.is_nan(), upper) {
            (true, false) => "nan",
            (true, true) => "NAN",
            (false, false) => "inf",
            (false, true) => "INF",
        };
        emit(s, &prefix, t.as_bytes(), false, out);
        return;
    }
    let body: Vec<u8> = match conv {
        b'f' | b'F' => {
            let p = s.precision.unwrap_or(6);
            let mut t = format!("{a:.p$}").into_bytes();
            if s.hash && p == 0 {
                t.push(b'.');
            }
            t
        }
        b'e' | b'E' => exp_form(a, s.precision.unwrap_or(6), upper, s.hash),
        b'g' | b'G' => {
            let p = match s.precision.unwrap_or(6) {
                0 => 1,
                p => p,
            };
            let t = format!("{a:.*e}", p - 1);
            let x: i32 = t.split_once('e').unwrap().1.parse().unwrap();
            let mut t = if (x as i64) < p as i64 && x >= -4 {
                let f = (p as i64 - 1 - x as i64) as usize;
                format!("{a:.f$}").into_bytes()
            } else {
                exp_form(a, p - 1, upper, false)
            };
            if !s.hash {
                if let Some(e) = t.iter().position(|c| *c == b'e' || *c == b'E') {
                    let mut m = t[..e].to_vec();
                    strip_zeros(&mut m);
                    m.extend_from_slice(&t[e..]);
                    t = m;
                } else {
                    strip_zeros(&mut t);
                }
            }
            t
        }
        _ => hex_float(a, s.precision, upper),
    };
    emit(s, &prefix, &body, true, out);
}

/// `%a`: `0x1.hhhp±d` (glibc's form; subnormals as `0x0.hhh`), rounded to the precision.
fn hex_float(a: f64, precision: Option<usize>, upper: bool) -> Vec<u8> {
    let bits = a.to_bits();
    let exp_bits = ((bits >> 52) & 0x7ff) as i64;
    let mut mant = bits & ((1u64 << 52) - 1);
    let (mut lead, exp) = if exp_bits == 0 {
        if mant == 0 {
            (0u64, 0i64)
        } else {
            (0, -1022)
        }
    } else {
        (1, exp_bits - 1023)
    };
    let mut digits = 13usize;
    if let Some(p) = precision {
        if p < 13 {
            let drop = (13 - p) * 4;
            let half = 1u64 << (drop - 1);
            let rest = mant & ((1u64 << drop) - 1);
            mant >>= drop;
            if rest > half || (rest == half && mant & 1 == 1) {
                mant += 1;
                if mant >> (p * 4) != 0 {
                    mant &= (1u64 << (p * 4)) - 1;
                    lead += 1;
                }
            }
            digits = p;
        }
    }
    let mut hex = if digits == 0 {
        String::new()
    } else {
        format!("{mant:0digits$x}")
    };
    if precision.is_none() {
        while hex.ends_with('0') {
            hex.pop();
        }
    }
    let extra = precision.map_or(0, |p| p.saturating_sub(13));
    hex.extend(std::iter::repeat_n('0', extra));
    let point = if hex.is_empty() { "" } else { "." };
    let t = format!("0x{lead}{point}{hex}p{exp:+}");
    if upper {
        t.to_uppercase().into_bytes()
    } else {
        t.into_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Local store with the format at 0x1000 and one 16-byte slot per argument from
    /// 0x2000, jumping 32 bytes at 0x2000 + 16 * `regs` (where the register save area
    /// ends and the caller's stack begins).
    fn run(fmt: &str, args: &[[u8; 16]], regs: usize) -> Result<String, String> {
        let mut ls = vec![0u8; 0x40000];
        ls[0x1000..0x1000 + fmt.len()].copy_from_slice(fmt.as_bytes());
        ls[0x3000..0x3006].copy_from_slice(b"hello\0");
        let mut at = 0x2000;
        for (i, a) in args.iter().enumerate() {
            if i == regs {
                at += 32;
            }
            ls[at..at + 16].copy_from_slice(a);
            at += 16;
        }
        let ls = Ls::new(&ls);
        let fmt = ls.cstr(0x1000, "fmt").unwrap();
        let mut va = VaList {
            next: 0x2000,
            caller_stack: 0x2000 + 16 * regs as u32,
        };
        match format(&ls, &fmt, &mut va) {
            Ok(t) => Ok(String::from_utf8(t).unwrap()),
            Err(FormatError::Fault(f)) => Err(f.0),
            Err(FormatError::Overflow) => Err("overflow".into()),
        }
    }

    fn int(v: i32) -> [u8; 16] {
        let mut q = [0u8; 16];
        q[..4].copy_from_slice(&v.to_be_bytes());
        q
    }

    fn dbl(v: f64) -> [u8; 16] {
        let mut q = [0u8; 16];
        q[..8].copy_from_slice(&v.to_be_bytes());
        q
    }

    #[test]
    fn the_list_skips_the_callers_link_area() {
        let args = [int(1), int(2), int(3), int(4)];
        assert_eq!(run("%d %d %d %d", &args, 2).unwrap(), "1 2 3 4");
        assert_eq!(
            run(
                "%*d|%-*d|%.*f",
                &[int(4), int(7), int(3), int(8), int(1), dbl(2.25)],
                3
            )
            .unwrap(),
            "   7|8  |2.2"
        );
    }

    #[test]
    fn conversions_as_glibc_prints_them() {
        let cases: &[(&str, [u8; 16], &str)] = &[
            ("%g", dbl(100000.0), "100000"),
            ("%g", dbl(1e6), "1e+06"),
            ("%g", dbl(0.0001), "0.0001"),
            ("%#g", dbl(1.0), "1.00000"),
            ("%.0f", dbl(2.5), "2"),
            ("%.0f", dbl(3.5), "4"),
            ("%e", dbl(0.0), "0.000000e+00"),
            ("%f", dbl(-0.0), "-0.000000"),
            ("%+.2e", dbl(12345.678), "+1.23e+04"),
            ("%a", dbl(0.0), "0x0p+0"),
            ("%a", dbl(0.5), "0x1p-1"),
            ("%.1a", dbl(1.96875), "0x2.0p+0"),
            ("%A", dbl(10.0), "0X1.4P+3"),
            ("%f", dbl(f64::INFINITY), "inf"),
            ("%5.1F", dbl(f64::NAN), "  NAN"),
            ("%08.3x", int(0x1f), "     01f"),
            ("%-05d|", int(-3), "-3   |"),
            ("% d", int(5), " 5"),
            ("%hd", int(0x12345), "9029"),
            ("%#o", int(8), "010"),
            ("%#x", int(0), "0"),
            ("%.0d|", int(0), "|"),
            ("%lu", int(-1), "4294967295"),
            ("%10s|", int(0x3000), "     hello|"),
            ("%-7.3s|", int(0x3000), "hel    |"),
            ("%p", int(0), "(nil)"),
            ("%y", int(0), "%y"),
        ];
        for (fmt, arg, want) in cases {
            assert_eq!(run(fmt, &[*arg], 72).unwrap(), *want, "{fmt}");
        }
    }

    #[test]
    fn vector_conversions() {
        let mut q = [0u8; 16];
        for (i, b) in q.iter_mut().enumerate() {
            *b = i as u8 * 17;
        }
        assert_eq!(
            run("%vx", &[q], 72).unwrap(),
            "0 11 22 33 44 55 66 77 88 99 aa bb cc dd ee ff"
        );
        assert_eq!(
            run("%;vhd", &[q], 72).unwrap(),
            "17;8755;17493;26231;-30567;-21829;-13091;-4353"
        );
        assert_eq!(
            run("%_vllx", &[q], 72).unwrap(),
            "11223344556677_8899aabbccddeeff"
        );
        let mut d = [0u8; 16];
        d[..8].copy_from_slice(&1.5f64.to_be_bytes());
        d[8..].copy_from_slice(&(-2.0f64).to_be_bytes());
        assert_eq!(run("%vlf", &[d], 72).unwrap(), "1.500000 -2.000000");
        let mut c = [b'a'; 16];
        c[15] = b'z';
        assert_eq!(run("%vc", &[c], 72).unwrap(), "aaaaaaaaaaaaaaaz");
    }

    #[test]
    fn refusals() {
        assert!(run("%n", &[int(0x3000)], 72).unwrap_err().contains("%n"));
        assert_eq!(run("%2000000d", &[int(1)], 72).unwrap_err(), "overflow");
        let e = run("%s", &[int(0x40000)], 72).unwrap_err();
        assert!(e.contains("outside local store"), "{e}");
    }
}
