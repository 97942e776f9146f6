//! The scanf engine: a format string from local store read against an input (a string in
//! local store or a stream), each converted value stored through a pointer argument from
//! the SPU `va_list` (checked against local store), as glibc's scanf converts them with
//! the SPU's sizes (`long` 32 bits, `float` 4 bytes, `double` and `long double` 8).
//! `%n` is refused, as in printf.

use super::format::VaList;
use super::{check, Fault, Ls, Writes};

/// Bytes of input, one at a time, with one byte of look-ahead.
pub struct Input<'a> {
    next: &'a mut dyn FnMut() -> Option<u8>,
    peeked: Option<Option<u8>>,
}

impl<'a> Input<'a> {
    pub fn new(next: &'a mut dyn FnMut() -> Option<u8>) -> Input<'a> {
        Input { next, peeked: None }
    }
    fn peek(&mut self) -> Option<u8> {
        if self.peeked.is_none() {
            self.peeked = Some((self.next)());
        }
        self.peeked.unwrap()
    }
    fn bump(&mut self) {
        self.peek();
        self.peeked = None;
    }
    /// The byte looked at and not consumed, to be pushed back into a stream.
    pub fn left_over(&self) -> Option<u8> {
        self.peeked.flatten()
    }
    fn skip_space(&mut self) {
        while self.peek().is_some_and(|c| c.is_ascii_whitespace()) {
            self.bump();
        }
    }
}

/// Reads `fmt` against `input`: the number of values assigned, or -1 (EOF) when the
/// input ended before the first conversion; the stores go to `writes`.
pub fn scan(
    ls: &Ls,
    fmt: &[u8],
    va: &mut VaList,
    input: &mut Input,
    writes: &mut Writes,
) -> Result<i32, Fault> {
    let mut assigned = 0;
    let mut converted_any = false;
    let mut i = 0;
    let eof = |converted: bool, assigned: i32| if converted { assigned } else { -1 };
    while i < fmt.len() {
        let c = fmt[i];
        if c.is_ascii_whitespace() {
            input.skip_space();
            i += 1;
            continue;
        }
        if c != b'%' {
            match input.peek() {
                Some(x) if x == c => input.bump(),
                Some(_) => return Ok(assigned),
                None => return Ok(eof(converted_any, assigned)),
            }
            i += 1;
            continue;
        }
        i += 1;
        let suppress = fmt.get(i) == Some(&b'*');
        if suppress {
            i += 1;
        }
        let digits = fmt[i..].iter().take_while(|c| c.is_ascii_digit()).count();
        let width = std::str::from_utf8(&fmt[i..i + digits])
            .ok()
            .and_then(|t| t.parse::<usize>().ok())
            .filter(|w| *w > 0);
        i += digits;
        let (mut h, mut l) = (0, 0);
        while let Some(&m) = fmt.get(i) {
            match m {
                b'h' => h += 1,
                b'l' => l += 1,
                b'j' | b'q' | b'L' => l = 2,
                b'z' | b't' => {}
                _ => break,
            }
            i += 1;
        }
        let Some(&conv) = fmt.get(i) else {
            break;
        };
        i += 1;
        if conv == b'n' {
            return Err(Fault(
                "scanf: %n (writing the count into the program's memory) is refused".into(),
            ));
        }
        if !matches!(conv, b'[' | b'c') {
            input.skip_space();
        }
        if input.peek().is_none() && conv != b'%' {
            return Ok(eof(converted_any, assigned));
        }
        let max = width.unwrap_or(usize::MAX);
        let stored: Option<Vec<u8>> = match conv {
            b'%' => {
                match input.peek() {
                    Some(b'%') => input.bump(),
                    Some(_) => return Ok(assigned),
                    None => return Ok(eof(converted_any, assigned)),
                }
                continue;
            }
            b'd' | b'i' | b'u' | b'o' | b'x' | b'X' | b'p' => {
                let base = match conv {
                    b'o' => 8,
                    b'x' | b'X' | b'p' => 16,
                    b'i' => 0,
                    _ => 10,
                };
                let Some(v) = integer(input, base, max) else {
                    return Ok(assigned);
                };
                let size = if conv == b'p' {
                    4
                } else if l >= 2 {
                    8
                } else if h >= 2 {
                    1
                } else if h == 1 {
                    2
                } else {
                    4
                };
                Some(v.to_be_bytes()[8 - size..].to_vec())
            }
            b'f' | b'F' | b'e' | b'E' | b'g' | b'G' | b'a' | b'A' => {
                let Some(v) = float(input, max) else {
                    return Ok(assigned);
                };
                Some(if l >= 1 {
                    v.to_be_bytes().to_vec()
                } else {
                    (v as f32).to_be_bytes().to_vec()
                })
            }
            b's' => {
                let mut t = Vec::new();
                while t.len() < max {
                    match input.peek() {
                        Some(c) if !c.is_ascii_whitespace() => {
                            t.push(c);
                            input.bump();
                        }
                        _ => break,
                    }
                }
                t.push(0);
                Some(t)
            }
            b'c' => {
                let n = width.unwrap_or(1);
                let mut t = Vec::new();
                while t.len() < n {
                    match input.peek() {
                        Some(c) => {
                            t.push(c);
                            input.bump();
                        }
                        None => break,
                    }
                }
                if t.len() < n {
                    return Ok(eof(converted_any || !t.is_empty(), assigned));
                }
                Some(t)
            }
            b'[' => {
                let (set, end) = char_set(&fmt[i..]);
                i += end;
                let mut t = Vec::new();
                while t.len() < max {
                    match input.peek() {
                        Some(c) if set[c as usize] => {
                            t.push(c);
                            input.bump();
                        }
                        _ => break,
                    }
                }
                if t.is_empty() {
                    return Ok(assigned);
                }
                t.push(0);
                Some(t)
            }
            _ => return Ok(assigned),
        };
        converted_any = true;
        if let (false, Some(bytes)) = (suppress, stored) {
            let p = va_ptr(ls, va)?;
            if p == 0 {
                return Err(Fault("scanf: a null pointer argument".into()));
            }
            check(p, bytes.len() as u64, "a scanf result")?;
            writes.push((p, bytes));
            assigned += 1;
        }
    }
    Ok(assigned)
}

fn va_ptr(ls: &Ls, va: &mut VaList) -> Result<u32, Fault> {
    let q = ls.quad(va.next, "a scanf argument")?;
    va.next = va.next.wrapping_add(16);
    if va.next == va.caller_stack {
        va.next = va.next.wrapping_add(32);
    }
    Ok(u32::from_be_bytes([q[0], q[1], q[2], q[3]]))
}

/// `%[...]`: the set (which bytes match) and how far the format goes past the `]`.
fn char_set(f: &[u8]) -> ([bool; 256], usize) {
    let mut i = 0;
    let negate = f.first() == Some(&b'^');
    if negate {
        i += 1;
    }
    let mut set = [false; 256];
    let mut first = true;
    while i < f.len() && (f[i] != b']' || first) {
        if i + 2 < f.len() && f[i + 1] == b'-' && f[i + 2] != b']' {
            for c in f[i]..=f[i + 2] {
                set[c as usize] = true;
            }
            i += 3;
        } else {
            set[f[i] as usize] = true;
            i += 1;
        }
        first = false;
    }
    if negate {
        for s in set.iter_mut() {
            *s = !*s;
        }
    }
    (set, (i + 1).min(f.len()))
}

/// An integer in `base` (0: C's prefixes) of at most `max` characters, as strtol reads it
/// (wrapping to 64 bits).
fn integer(input: &mut Input, base: u32, max: usize) -> Option<u64> {
    let mut n = 0;
    let mut neg = false;
    if let Some(c @ (b'+' | b'-')) = input.peek() {
        neg = c == b'-';
        input.bump();
        n += 1;
    }
    let mut base = base;
    let mut digits = 0;
    let mut v: u64 = 0;
    if (base == 0 || base == 16) && n < max && input.peek() == Some(b'0') {
        input.bump();
        n += 1;
        digits = 1;
        if n < max && matches!(input.peek(), Some(b'x' | b'X')) {
            input.bump();
            n += 1;
            base = 16;
            digits = 0;
        } else if base == 0 {
            base = 8;
        }
    }
    if base == 0 {
        base = 10;
    }
    while n < max {
        let Some(d) = input.peek().and_then(|c| (c as char).to_digit(base)) else {
            break;
        };
        v = v.wrapping_mul(base as u64).wrapping_add(d as u64);
        input.bump();
        n += 1;
        digits += 1;
    }
    (digits > 0).then_some(if neg { v.wrapping_neg() } else { v })
}

/// A floating-point number of at most `max` characters.
fn float(input: &mut Input, max: usize) -> Option<f64> {
    let mut t = String::new();
    let take = |input: &mut Input, t: &mut String, ok: &dyn Fn(u8) -> bool| -> bool {
        match input.peek() {
            Some(c) if t.len() < max && ok(c) => {
                t.push(c as char);
                input.bump();
                true
            }
            _ => false,
        }
    };
    take(input, &mut t, &|c| c == b'+' || c == b'-');
    let word = |input: &mut Input, t: &mut String, w: &str| {
        let mut ok = true;
        for ch in w.bytes() {
            ok &= take(input, t, &|c| c.eq_ignore_ascii_case(&ch));
        }
        ok
    };
    if matches!(input.peek(), Some(b'i' | b'I')) {
        return word(input, &mut t, "inf")
            .then(|| t.parse::<f64>().ok())
            .flatten();
    }
    if matches!(input.peek(), Some(b'n' | b'N')) {
        return word(input, &mut t, "nan")
            .then(|| t.parse::<f64>().ok())
            .flatten();
    }
    let mut digits = 0;
    while take(input, &mut t, &|c| c.is_ascii_digit()) {
        digits += 1;
    }
    if take(input, &mut t, &|c| c == b'.') {
        while take(input, &mut t, &|c| c.is_ascii_digit()) {
            digits += 1;
        }
    }
    if digits == 0 {
        return None;
    }
    if take(input, &mut t, &|c| c == b'e' || c == b'E') {
        take(input, &mut t, &|c| c == b'+' || c == b'-');
        let mut e = 0;
        while take(input, &mut t, &|c| c.is_ascii_digit()) {
            e += 1;
        }
        if e == 0 {
            t.push('0');
        }
    }
    t.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(text: &str, fmt: &str, nargs: usize) -> (i32, Writes) {
        let mut ls = vec![0u8; 0x40000];
        ls[0x1000..0x1000 + fmt.len()].copy_from_slice(fmt.as_bytes());
        for k in 0..nargs {
            let p = 0x3000 + 0x40 * k as u32;
            ls[0x2000 + 16 * k..0x2004 + 16 * k].copy_from_slice(&p.to_be_bytes());
        }
        let ls = Ls::new(&ls);
        let mut va = VaList {
            next: 0x2000,
            caller_stack: 0x2000 + 16 * 72,
        };
        let mut bytes = text.bytes();
        let mut next = move || bytes.next();
        let mut input = Input::new(&mut next);
        let mut w = Writes::new();
        let fmt = ls.cstr(0x1000, "fmt").unwrap();
        let n = scan(&ls, &fmt, &mut va, &mut input, &mut w).unwrap();
        (n, w)
    }

    #[test]
    fn conversions() {
        let (n, w) = run(
            "  42 -0x1f 017 abc 2.5 xyzzy,Q 7",
            "%d %i %i %s %lf %[a-z],%c %hhd",
            8,
        );
        assert_eq!(n, 8);
        assert_eq!(
            w,
            vec![
                (0x3000, 42u32.to_be_bytes().to_vec()),
                (0x3040, (-31i32).to_be_bytes().to_vec()),
                (0x3080, 15u32.to_be_bytes().to_vec()),
                (0x30c0, b"abc\0".to_vec()),
                (0x3100, 2.5f64.to_be_bytes().to_vec()),
                (0x3140, b"xyzzy\0".to_vec()),
                (0x3180, b"Q".to_vec()),
                (0x31c0, vec![7]),
            ]
        );
    }

    #[test]
    fn failures_and_end_of_input() {
        assert_eq!(run("12 x", "%d %d", 2).0, 1);
        assert_eq!(run("", "%d", 1).0, -1);
        assert_eq!(run("   ", "%s", 1).0, -1);
        let (n, w) = run("5 6", "%*d %3f", 1);
        assert_eq!((n, w), (1, vec![(0x3000, 6f32.to_be_bytes().to_vec())]));
    }
}
