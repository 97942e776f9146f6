//! GNU as expressions: a nom grammar that builds a small tree, and its evaluation.
//!
//! Precedence and results follow gas's `expr.c` (non-MRI): unary `- ~ ! +` bind tightest;
//! then `* / % << >>`; then `| ! ^ &` (binary `!` is or-not); then `+ -`; then the
//! comparisons `== != <> < <= > >=`, which give -1 for true and 0 for false; then `&&`;
//! then `||` (both give 1 or 0). `>>` is a logical (unsigned) shift, and division by zero
//! warns and divides by one. A value remembers whether it depends on an address (a label
//! or `.`): such "relocatable" operands of branches are made PC-relative, while plain
//! constants are taken as the offset itself, as gas does.

use nom::branch::alt;
use nom::bytes::complete::{tag, take_while, take_while1};
use nom::character::complete::{char as ch, multispace0};
use nom::combinator::recognize;
use nom::sequence::{delimited, pair, preceded};
use nom::{IResult, Parser};

/// An expression tree; `usize` fields are byte offsets into the parsed text (for errors).
#[derive(Clone, Debug, PartialEq)]
pub enum Ast {
    Num(i64),
    Sym(String, usize),
    Dot,
    /// Numeric local label reference: `1b` (false) / `1f` (true).
    Local(u32, bool, usize),
    Unary(char, Box<Ast>),
    Bin(&'static str, Box<Ast>, Box<Ast>),
    /// A malformed number.
    BadNum(String, usize),
}

/// An expression's value: the number and whether it depends on an address.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Val {
    pub v: i64,
    pub reloc: bool,
}

/// What evaluation needs from the assembler.
pub trait Env {
    fn symbol(&self, name: &str) -> Option<Val>;
    fn dot(&self) -> i64;
    fn local(&self, n: u32, forward: bool) -> Option<i64>;
    /// Pass 1: unknown symbols read as 0 instead of failing.
    fn lenient(&self) -> bool;
}

pub fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_' || c == '.' || c == '$'
}
pub fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '$'
}

type R<'a, T> = IResult<&'a str, T>;

/// Offset of `rest` within `all` (both slices of one string).
fn off(all: &str, rest: &str) -> usize {
    all.len() - rest.len()
}

struct P<'s> {
    all: &'s str,
}

impl<'s> P<'s> {
    fn ws(&self, i: &'s str) -> &'s str {
        multispace0::<&str, nom::error::Error<&str>>(i)
            .map(|r| r.0)
            .unwrap_or(i)
    }

    fn primary(&self, i: &'s str) -> R<'s, Ast> {
        let i = self.ws(i);
        let at = off(self.all, i);
        // Unary operators bind to the operand that follows.
        if let Ok((rest, op)) = alt((
            ch::<&str, nom::error::Error<&str>>('-'),
            ch('~'),
            ch('!'),
            ch('+'),
        ))
        .parse(i)
        {
            let (rest, e) = self.primary(rest)?;
            return Ok((rest, Ast::Unary(op, Box::new(e))));
        }
        if let Ok((rest, e)) =
            delimited(ch('('), |x| self.expr(x, 0), preceded(multispace0, ch(')'))).parse(i)
        {
            return Ok((rest, e));
        }
        // Character constant: 'c (an optional closing quote is tolerated), with escapes.
        if let Some(rest) = i.strip_prefix('\'') {
            let mut chars = rest.chars();
            let (v, used) = match chars.next() {
                Some('\\') => match chars.next() {
                    Some('n') => (10, 2),
                    Some('t') => (9, 2),
                    Some('r') => (13, 2),
                    Some('0') => (0, 2),
                    Some(c) => (c as i64, 1 + c.len_utf8()),
                    None => (b'\\' as i64, 1),
                },
                Some(c) => (c as i64, c.len_utf8()),
                None => return Ok((rest, Ast::BadNum("'".into(), at))),
            };
            let rest = &rest[used..];
            let rest = rest.strip_prefix('\'').unwrap_or(rest);
            return Ok((rest, Ast::Num(v)));
        }
        if i.starts_with(|c: char| c.is_ascii_digit()) {
            let (rest, text) = take_while1(|c: char| c.is_ascii_alphanumeric()).parse(i)?;
            return Ok((rest, number(text, at)));
        }
        if let Ok((rest, name)) = recognize(pair(
            take_while1::<_, &str, nom::error::Error<&str>>(is_ident_start),
            take_while(is_ident),
        ))
        .parse(i)
        {
            if name == "." {
                return Ok((rest, Ast::Dot));
            }
            return Ok((rest, Ast::Sym(name.to_string(), at)));
        }
        Err(nom::Err::Error(nom::error::Error::new(
            i,
            nom::error::ErrorKind::Alt,
        )))
    }

    fn binop(&self, i: &'s str) -> Option<(&'s str, &'static str, u8)> {
        let i = self.ws(i);
        const OPS: &[(&str, u8)] = &[
            ("||", 2),
            ("&&", 3),
            ("==", 4),
            ("!=", 4),
            ("<>", 4),
            ("<=", 4),
            (">=", 4),
            ("<<", 8),
            (">>", 8),
            ("<", 4),
            (">", 4),
            ("+", 5),
            ("-", 5),
            ("|", 7),
            ("!", 7),
            ("^", 7),
            ("&", 7),
            ("*", 8),
            ("/", 8),
            ("%", 8),
        ];
        OPS.iter().find_map(|(o, p)| {
            tag::<&str, &str, nom::error::Error<&str>>(*o)
                .parse(i)
                .ok()
                .map(|(rest, _)| (rest, *o, *p))
        })
    }

    /// Precedence climbing: operators of rank above `min` (left associative).
    fn expr(&self, i: &'s str, min: u8) -> R<'s, Ast> {
        let (mut rest, mut lhs) = self.primary(i)?;
        while let Some((after, op, rank)) = self.binop(rest) {
            if rank <= min {
                break;
            }
            let (r, rhs) = self.expr(after, rank)?;
            lhs = Ast::Bin(op, Box::new(lhs), Box::new(rhs));
            rest = r;
        }
        Ok((rest, lhs))
    }
}

fn number(text: &str, at: usize) -> Ast {
    let lower = text.to_ascii_lowercase();
    // Numeric local label references: 1b, 12f (but 0b1 is binary).
    if let Some(stem) = lower.strip_suffix('b').or_else(|| lower.strip_suffix('f')) {
        if !stem.is_empty() && stem.bytes().all(|b| b.is_ascii_digit()) {
            if let Ok(n) = stem.parse::<u32>() {
                return Ast::Local(n, lower.ends_with('f'), at);
            }
        }
    }
    let parsed = if let Some(h) = lower.strip_prefix("0x") {
        u64::from_str_radix(h, 16).ok()
    } else if let Some(b) = lower.strip_prefix("0b") {
        u64::from_str_radix(b, 2).ok()
    } else if lower.len() > 1 && lower.starts_with('0') {
        u64::from_str_radix(&lower[1..], 8).ok()
    } else {
        lower.parse::<u64>().ok()
    };
    match parsed {
        Some(v) => Ast::Num(v as i64),
        None => Ast::BadNum(text.to_string(), at),
    }
}

/// Parses one expression at the start of `text`; returns it and the unparsed rest.
pub fn parse(text: &str) -> Option<(Ast, &str)> {
    let p = P { all: text };
    let (rest, ast) = p.expr(text, 0).ok()?;
    Some((ast, rest))
}

/// Evaluation failure: byte offset in the expression text and message.
pub type EvalErr = (usize, String);

pub struct Eval<'e> {
    pub env: &'e dyn Env,
    pub warnings: Vec<String>,
    /// Set when an unknown symbol was read as 0 (pass 1).
    pub undefined: bool,
}

impl Eval<'_> {
    pub fn eval(&mut self, e: &Ast) -> Result<Val, EvalErr> {
        let c = |v: i64| Val { v, reloc: false };
        Ok(match e {
            Ast::Num(v) => c(*v),
            Ast::BadNum(t, at) => return Err((*at, format!("bad number `{t}`"))),
            Ast::Dot => Val {
                v: self.env.dot(),
                reloc: true,
            },
            Ast::Sym(name, at) => match self.env.symbol(name) {
                Some(v) => v,
                None if self.env.lenient() => {
                    self.undefined = true;
                    Val { v: 0, reloc: true }
                }
                None => return Err((*at, format!("undefined symbol `{name}`"))),
            },
            Ast::Local(n, fwd, at) => match self.env.local(*n, *fwd) {
                Some(v) => Val { v, reloc: true },
                None if self.env.lenient() => {
                    self.undefined = true;
                    Val { v: 0, reloc: true }
                }
                None => {
                    return Err((
                        *at,
                        format!(
                            "undefined local label `{n}{}`",
                            if *fwd { 'f' } else { 'b' }
                        ),
                    ))
                }
            },
            Ast::Unary(op, a) => {
                let a = self.eval(a)?;
                let v = match op {
                    '-' => a.v.wrapping_neg(),
                    '~' => !a.v,
                    '!' => (a.v == 0) as i64,
                    _ => a.v,
                };
                Val {
                    v,
                    reloc: a.reloc && *op == '+',
                }
            }
            Ast::Bin(op, a, b) => {
                let a = self.eval(a)?;
                let b = self.eval(b)?;
                let (x, y) = (a.v, b.v);
                let t = |b: bool| if b { -1 } else { 0 };
                let v = match *op {
                    "||" => ((x != 0) || (y != 0)) as i64,
                    "&&" => ((x != 0) && (y != 0)) as i64,
                    "==" => t(x == y),
                    "!=" | "<>" => t(x != y),
                    "<" => t(x < y),
                    "<=" => t(x <= y),
                    ">" => t(x > y),
                    ">=" => t(x >= y),
                    "<<" => {
                        if !(0..64).contains(&y) {
                            self.warnings.push(format!(
                                "shift count out of range ({y} is not between 0 and 63)"
                            ));
                            0
                        } else {
                            x.wrapping_shl(y as u32)
                        }
                    }
                    ">>" => {
                        if !(0..64).contains(&y) {
                            self.warnings.push(format!(
                                "shift count out of range ({y} is not between 0 and 63)"
                            ));
                            0
                        } else {
                            ((x as u64) >> y) as i64
                        }
                    }
                    "|" => x | y,
                    "!" => x | !y,
                    "^" => x ^ y,
                    "&" => x & y,
                    "+" => x.wrapping_add(y),
                    "-" => x.wrapping_sub(y),
                    "*" => x.wrapping_mul(y),
                    "/" | "%" => {
                        let y = if y == 0 {
                            self.warnings.push("division by zero".into());
                            1
                        } else {
                            y
                        };
                        if *op == "/" {
                            x.wrapping_div(y)
                        } else {
                            x.wrapping_rem(y)
                        }
                    }
                    _ => 0,
                };
                let reloc = match *op {
                    "-" => a.reloc != b.reloc && a.reloc,
                    "+" => a.reloc || b.reloc,
                    _ => a.reloc || b.reloc,
                };
                Val { v, reloc }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct NoEnv;
    impl Env for NoEnv {
        fn symbol(&self, name: &str) -> Option<Val> {
            (name == "L").then_some(Val {
                v: 0x40,
                reloc: true,
            })
        }
        fn dot(&self) -> i64 {
            8
        }
        fn local(&self, _: u32, _: bool) -> Option<i64> {
            None
        }
        fn lenient(&self) -> bool {
            false
        }
    }

    fn ev(s: &str) -> (i64, bool, String) {
        let (ast, rest) = parse(s).unwrap();
        let v = Eval {
            env: &NoEnv,
            warnings: vec![],
            undefined: false,
        }
        .eval(&ast)
        .unwrap();
        (v.v, v.reloc, rest.to_string())
    }

    #[test]
    fn gas_precedence() {
        assert_eq!(ev("1 + 2 & 3").0, 3); // & binds tighter than +
        assert_eq!(ev("1 << 2 + 1").0, 5);
        assert_eq!(ev("2 * 3 - 1").0, 5);
        assert_eq!(ev("1 == 1").0, -1);
        assert_eq!(ev("1 < 2 && 3").0, 1);
        assert_eq!(ev("-2 * 3").0, -6);
        assert_eq!(ev("0 ! 0").0, -1);
        assert_eq!(ev("-16 >> 60").0, 15);
        assert_eq!(ev("010 + 0x10 + 0b11").0, 27);
        assert_eq!(ev("'a").0, 97);
        assert_eq!(ev("7 / 0").0, 7);
    }

    #[test]
    fn relocatable_values() {
        assert_eq!(ev("L + 4"), (0x44, true, String::new()));
        assert_eq!(ev("L - ."), (0x38, false, String::new()));
        assert_eq!(ev("16($3)"), (16, false, "($3)".to_string()));
        assert_eq!(ev("L@h"), (0x40, true, "@h".to_string()));
    }
}
