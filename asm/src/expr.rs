//! GNU as expressions: an iterative (shunting-yard) parser into postfix form, and a stack
//! evaluation, so that neither nesting nor length can exhaust the host stack.
//!
//! Precedence and results follow gas's `expr.c` (non-MRI): unary `- ~ ! +` bind tightest;
//! then `* / % << >>`; then `| ! ^ &` (binary `!` is or-not); then `+ -`; then the
//! comparisons `== != <> < <= > >=`, which give -1 for true and 0 for false; then `&&`;
//! then `||` (both give 1 or 0). `>>` is a logical (unsigned) shift, and division by zero
//! warns and divides by one. A value remembers whether it depends on an address (a label
//! or `.`): such "relocatable" operands of branches are made PC-relative, while plain
//! constants are taken as the offset itself, as gas does. It also remembers what a
//! relocation would be against (a section, or a global or undefined symbol), for objects.

use std::rc::Rc;

/// One element of an expression in postfix order; `usize` fields are byte offsets into
/// the parsed text (for errors).
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    Num(i64),
    Sym(String, usize),
    Dot,
    /// Numeric local label reference: `1b` (false) / `1f` (true).
    Local(u32, bool, usize),
    Unary(char),
    Bin(&'static str),
    /// A malformed number.
    BadNum(String, usize),
}

/// A parsed expression, in postfix order (no tree, so no recursion to build or drop it).
#[derive(Clone, Debug, PartialEq)]
pub struct Ast(pub Vec<Node>);

/// An expression's value: the number, whether it depends on an address, and what a
/// relocation for it would name.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct Val {
    pub v: i64,
    pub reloc: bool,
    /// The section (index of its definition) the value is an address in, if any.
    pub sect: Option<usize>,
    /// A global, weak or undefined symbol a relocation must name, with its value (the
    /// addend is `v - sym value`).
    pub sym: Option<(Rc<str>, i64)>,
    /// Depends on addresses in a way no relocation can express (a difference across
    /// sections): fine in an executable, an error in an object, unless `pcrel` says how.
    pub cross: bool,
    /// For a `cross` value, the pc-relative form a relocation can still carry when it
    /// sits in the section of the address subtracted (`x - y`, `-y`, `ext - .`).
    pub pcrel: Option<Rc<PcRel>>,
}

/// An address minus an address of another section, as write.c's `fixup_segment` keeps
/// it when the address subtracted is in the fixup's own section: a pc-relative
/// relocation (`R_SPU_REL32`) to the address added, its addend moved by the distance
/// from the subtracted address to the place.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PcRel {
    /// The section (definition index) of the address added, if a local one.
    pub sect: Option<usize>,
    /// The symbol a relocation must name for the address added, with its value.
    pub sym: Option<(Rc<str>, i64)>,
    /// The section of the address subtracted.
    pub minus: usize,
}

impl PcRel {
    /// `a - b` as a pc-relative relocation could carry it: `a` an address (or constant)
    /// that is not itself a difference, `b` an address defined in a section.
    fn of(a: &Val, b: &Val) -> Option<Rc<PcRel>> {
        let plain = |x: &Val| !x.cross && x.pcrel.is_none();
        (plain(a) && plain(b) && b.reloc).then_some(())?;
        Some(Rc::new(PcRel {
            sect: a.sect,
            sym: a.sym.clone(),
            minus: b.sect?,
        }))
    }
}

impl Val {
    pub fn abs(v: i64) -> Val {
        Val {
            v,
            ..Default::default()
        }
    }
}

/// What evaluation needs from the assembler.
pub trait Env {
    fn symbol(&self, name: &str) -> Option<Val>;
    fn dot(&self) -> Val;
    fn local(&self, n: u32, forward: bool) -> Option<Val>;
    /// Pass 1: unknown symbols read as 0 instead of failing.
    fn lenient(&self) -> bool;
    /// An unknown symbol is an external reference (relocatable objects) rather than an error.
    fn external(&self, _name: &str) -> Option<Val> {
        None
    }
}

/// Characters past ASCII are name characters, as gas's lexer takes bytes 128-255
/// (UTF-8 names such as `he\u{202e}oll\u{202c}`).
pub fn is_ident_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_' || c == '.' || c == '$' || !c.is_ascii()
}
pub fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '$' || !c.is_ascii()
}

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

/// Rank of a prefix operator: above every binary operator.
const UNARY_RANK: u8 = 9;

enum Pending {
    /// An opening `(` or `[` (gas takes square brackets as parentheses on targets
    /// without an index operator, SPU among them).
    Open(char),
    Unary(char),
    Bin(&'static str, u8),
}

fn skip_ws(s: &str) -> &str {
    s.trim_start_matches([' ', '\t', '\n', '\r', '\x0b', '\x0c'])
}

/// An operand at the start of `i` (no operators): its node and the rest.
fn operand(i: &str, at: usize) -> Option<(Node, &str)> {
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
            None => return Some((Node::BadNum("'".into(), at), rest)),
        };
        let rest = &rest[used..];
        let rest = rest.strip_prefix('\'').unwrap_or(rest);
        return Some((Node::Num(v), rest));
    }
    if i.starts_with(|c: char| c.is_ascii_digit()) {
        let len = i
            .find(|c: char| !c.is_ascii_alphanumeric())
            .unwrap_or(i.len());
        return Some((number(&i[..len], at), &i[len..]));
    }
    if i.starts_with(is_ident_start) {
        let len = i.find(|c: char| !is_ident(c)).unwrap_or(i.len());
        let name = &i[..len];
        let node = if name == "." {
            Node::Dot
        } else {
            Node::Sym(name.to_string(), at)
        };
        return Some((node, &i[len..]));
    }
    None
}

/// Moves pending operators of rank at least `min` (stopping at an open parenthesis) to
/// the output.
fn reduce(ops: &mut Vec<Pending>, out: &mut Vec<Node>, min: u8) {
    while let Some(top) = ops.last() {
        match *top {
            Pending::Unary(c) if UNARY_RANK >= min => out.push(Node::Unary(c)),
            Pending::Bin(o, r) if r >= min => out.push(Node::Bin(o)),
            _ => break,
        }
        ops.pop();
    }
}

/// Parses one expression at the start of `text`; returns it and the unparsed rest
/// (which starts where the expression's last operand or parenthesis ended).
pub fn parse(text: &str) -> Option<(Ast, &str)> {
    let mut out = Vec::new();
    let mut ops: Vec<Pending> = Vec::new();
    let mut open = 0usize;
    let mut i = text;
    loop {
        // An operand, after any prefix operators and opening parentheses.
        loop {
            i = skip_ws(i);
            let at = text.len() - i.len();
            match i.chars().next() {
                Some(c @ ('-' | '~' | '!' | '+')) => {
                    ops.push(Pending::Unary(c));
                    i = &i[1..];
                }
                Some(c @ ('(' | '[')) => {
                    ops.push(Pending::Open(if c == '(' { ')' } else { ']' }));
                    open += 1;
                    i = &i[1..];
                }
                _ => {
                    let (node, rest) = operand(i, at)?;
                    out.push(node);
                    i = rest;
                    break;
                }
            }
        }
        // Closing parentheses, then a binary operator or the end.
        loop {
            let j = skip_ws(i);
            if open > 0 && j.starts_with([')', ']']) {
                reduce(&mut ops, &mut out, 0);
                match ops.pop() {
                    Some(Pending::Open(c)) if j.starts_with(c) => {}
                    _ => return None, // `(...]` or `[...)`
                }
                open -= 1;
                i = &j[1..];
                continue;
            }
            break;
        }
        let j = skip_ws(i);
        match OPS.iter().find(|(o, _)| j.starts_with(o)) {
            Some(&(op, rank)) => {
                reduce(&mut ops, &mut out, rank);
                ops.push(Pending::Bin(op, rank));
                i = &j[op.len()..];
            }
            None => {
                if open > 0 {
                    return None; // an unclosed parenthesis
                }
                reduce(&mut ops, &mut out, 0);
                return Some((Ast(out), i));
            }
        }
    }
}

fn number(text: &str, at: usize) -> Node {
    let lower = text.to_ascii_lowercase();
    // Numeric local label references: 1b, 12f (but 0b1 is binary).
    if let Some(stem) = lower.strip_suffix('b').or_else(|| lower.strip_suffix('f')) {
        if !stem.is_empty() && stem.bytes().all(|b| b.is_ascii_digit()) {
            if let Ok(n) = stem.parse::<u32>() {
                return Node::Local(n, lower.ends_with('f'), at);
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
        Some(v) => Node::Num(v as i64),
        None => Node::BadNum(text.to_string(), at),
    }
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
    fn leaf(&mut self, node: &Node) -> Result<Val, EvalErr> {
        let unknown = Val {
            v: 0,
            reloc: true,
            ..Default::default()
        };
        Ok(match node {
            Node::Num(v) => Val::abs(*v),
            Node::BadNum(t, at) => return Err((*at, format!("bad number `{t}`"))),
            Node::Dot => self.env.dot(),
            Node::Sym(name, at) => match self.env.symbol(name) {
                Some(v) => v,
                None if self.env.lenient() => {
                    self.undefined = true;
                    unknown
                }
                None => match self.env.external(name) {
                    Some(v) => v,
                    None => return Err((*at, format!("undefined symbol `{name}`"))),
                },
            },
            Node::Local(n, fwd, at) => match self.env.local(*n, *fwd) {
                Some(v) => v,
                None if self.env.lenient() => {
                    self.undefined = true;
                    unknown
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
            Node::Unary(_) | Node::Bin(_) => unreachable!("operators are not leaves"),
        })
    }

    pub fn eval(&mut self, e: &Ast) -> Result<Val, EvalErr> {
        let mut stack: Vec<Val> = Vec::new();
        for node in &e.0 {
            match node {
                Node::Unary(op) => {
                    let a = stack.pop().unwrap_or_default();
                    if *op == '~' && a.reloc && !self.env.lenient() {
                        // expr.c: no relocation can carry the complement of an address.
                        return Err((0, "invalid operand (an address) for `~'".into()));
                    }
                    let v = match op {
                        '-' => a.v.wrapping_neg(),
                        '~' => !a.v,
                        '!' => (a.v == 0) as i64,
                        _ => a.v,
                    };
                    stack.push(match op {
                        '+' => a,
                        // `-x`: `0 - x`, which a relocation carries only pc-relative.
                        '-' if a.reloc || a.cross => Val {
                            v,
                            cross: true,
                            pcrel: PcRel::of(&Val::abs(0), &a),
                            ..Default::default()
                        },
                        _ => Val::abs(v),
                    });
                }
                Node::Bin(op) => {
                    let b = stack.pop().unwrap_or_default();
                    let a = stack.pop().unwrap_or_default();
                    let v = self.binary(op, &a, &b);
                    stack.push(v);
                }
                leaf => {
                    let v = self.leaf(leaf)?;
                    stack.push(v);
                }
            }
        }
        Ok(stack.pop().unwrap_or_default())
    }

    fn binary(&mut self, op: &str, a: &Val, b: &Val) -> Val {
        let (x, y) = (a.v, b.v);
        let t = |b: bool| if b { -1 } else { 0 };
        let v = match op {
            "||" => ((x != 0) || (y != 0)) as i64,
            "&&" => ((x != 0) && (y != 0)) as i64,
            "==" => t(x == y),
            "!=" | "<>" => t(x != y),
            "<" => t(x < y),
            "<=" => t(x <= y),
            ">" => t(x > y),
            ">=" => t(x >= y),
            "<<" | ">>" if !(0..64).contains(&y) => {
                self.warnings.push(format!(
                    "shift count out of range ({y} is not between 0 and 63)"
                ));
                0
            }
            "<<" => x.wrapping_shl(y as u32),
            ">>" => ((x as u64) >> y) as i64,
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
                if op == "/" {
                    x.wrapping_div(y)
                } else {
                    x.wrapping_rem(y)
                }
            }
            _ => 0,
        };
        let cross = a.cross || b.cross;
        let constant = |c: &Val| !c.reloc && !c.cross;
        match op {
            // A pending pc-relative difference plus or minus a constant stays one.
            "+" | "-" if a.pcrel.is_some() && constant(b) => Val { v, ..a.clone() },
            "+" if b.pcrel.is_some() && constant(a) => Val { v, ..b.clone() },
            // An address plus or minus a constant stays an address in its section.
            "+" if a.reloc != b.reloc => {
                let r = if a.reloc { a } else { b };
                Val {
                    v,
                    cross,
                    ..r.clone()
                }
            }
            "-" if a.reloc && !b.reloc => Val {
                v,
                cross,
                ..a.clone()
            },
            // The difference of two addresses is a constant; a relocation can express it
            // only when both are in one section (or are one symbol).
            "-" if a.reloc && b.reloc => {
                let same = (a.sect.is_some() && a.sect == b.sect)
                    || (a.sym.is_some()
                        && a.sym.as_ref().map(|s| &s.0) == b.sym.as_ref().map(|s| &s.0));
                Val {
                    v,
                    cross: cross || !same,
                    pcrel: if same { None } else { PcRel::of(a, b) },
                    ..Default::default()
                }
            }
            // A constant minus an address: as the negation.
            "-" if constant(a) && b.reloc => Val {
                v,
                cross: true,
                pcrel: PcRel::of(a, b),
                ..Default::default()
            },
            // expr.c resolves (in)equality of addresses at once: equal only at the same
            // place of the same section (an undefined symbol equals nothing known).
            "==" | "!=" | "<>"
                if (a.reloc || b.reloc) && !cross && a.sym.is_none() && b.sym.is_none() =>
            {
                let same = a.sect == b.sect && a.reloc == b.reloc && x == y;
                Val::abs(t(same == (op == "==")))
            }
            // Anything else that involves an address can only be resolved once addresses
            // are known (an executable), not by a relocation.
            _ => Val {
                v,
                reloc: a.reloc || b.reloc,
                cross,
                ..Default::default()
            },
        }
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
                sect: Some(0),
                ..Default::default()
            })
        }
        fn dot(&self) -> Val {
            Val {
                v: 8,
                reloc: true,
                sect: Some(0),
                ..Default::default()
            }
        }
        fn local(&self, _: u32, _: bool) -> Option<Val> {
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

    #[test]
    fn long_and_deep_expressions_do_not_use_the_host_stack() {
        let n = 100_000;
        let flat = vec!["1"; n].join("+");
        assert_eq!(ev(&flat).0, n as i64);
        let nested = format!("{}1{}", "(".repeat(n), ")".repeat(n));
        assert_eq!(ev(&nested).0, 1);
        let unary = format!("{}5", "-".repeat(n + 1));
        assert_eq!(ev(&unary).0, -5);
        assert!(parse(&"(".repeat(n)).is_none());
    }

    #[test]
    fn square_brackets_group_like_parentheses() {
        assert_eq!(ev("[1+2]*3").0, 9);
        assert_eq!(ev("([1+2]*[3])").0, 9);
        assert!(parse("(1+2]").is_none());
    }

    #[test]
    fn parenthesised_operands_end_where_gas_stops() {
        assert_eq!(ev("(1+2)*3").0, 9);
        assert_eq!(ev("4 ( $3)"), (4, false, " ( $3)".to_string()));
        assert!(parse("(1+").is_none());
        assert!(parse("1 +").is_none());
    }
}
