//! GNU ld linker scripts (`spu ld -T`): the part of ld's script language that SPU
//! programs and binutils' `ld-spu` tests use (`SECTIONS` with output sections,
//! addresses, input section patterns, `KEEP`, `OVERLAY`, assignments, `PROVIDE`,
//! `ENTRY`, `INSERT AFTER/BEFORE`), parsed into statements the linker lays out.
//! Anything else is refused with its file:line:column, never skipped.

/// An expression of the script (addresses, assignments).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Expr {
    Number(u64),
    /// The location counter `.`.
    Dot,
    Symbol(String),
    /// `ALIGN(n)`: `.` rounded up to `n`; `ALIGN(e, n)`: `e` rounded up.
    Align(Option<Box<Expr>>, Box<Expr>),
    Binary(char, Box<Expr>, Box<Expr>),
}

impl Expr {
    /// The value with `.` at `dot` and `symbol` resolving names; `None` for a name not
    /// (yet) known.
    pub fn eval(&self, dot: u64, symbol: &dyn Fn(&str) -> Option<u64>) -> Result<u64, String> {
        Ok(match self {
            Expr::Number(n) => *n,
            Expr::Dot => dot,
            Expr::Symbol(s) => symbol(s).ok_or_else(|| format!("undefined symbol `{s}'"))?,
            Expr::Align(base, n) => {
                let base = match base {
                    Some(b) => b.eval(dot, symbol)?,
                    None => dot,
                };
                let n = n.eval(dot, symbol)?.max(1);
                base.div_ceil(n).saturating_mul(n)
            }
            Expr::Binary(op, a, b) => {
                let (a, b) = (a.eval(dot, symbol)?, b.eval(dot, symbol)?);
                match op {
                    '+' => a.wrapping_add(b),
                    '-' => a.wrapping_sub(b),
                    '*' => a.wrapping_mul(b),
                    '/' | '%' if b == 0 => return Err("division by zero".into()),
                    '/' => a / b,
                    '%' => a % b,
                    '&' => a & b,
                    '|' => a | b,
                    _ => unreachable!("the parser makes no other operator"),
                }
            }
        })
    }
}

/// One input section statement: `KEEP(file(section patterns))`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct InputSpec {
    pub keep: bool,
    /// A file-name pattern (`*` for any).
    pub file: String,
    /// Section-name patterns (`*`, `?` wildcards).
    pub sections: Vec<String>,
}

/// A statement inside an output section.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Item {
    Input(InputSpec),
    Assign(Assignment),
}

/// `name = expr;` (or `PROVIDE(name = expr);`, defined only where referenced and not
/// defined).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Assignment {
    pub name: String,
    pub expr: Expr,
    pub provide: bool,
}

/// `name [addr] : { items }`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputSection {
    pub name: String,
    pub addr: Option<Expr>,
    pub items: Vec<Item>,
}

/// A statement of `SECTIONS`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Statement {
    Assign(Assignment),
    Output(OutputSection),
    /// `OVERLAY addr : { sections }`: the sections share one address (an overlay
    /// region), loaded one after another.
    Overlay(Option<Expr>, Vec<OutputSection>),
}

/// A parsed script.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Script {
    pub entry: Option<String>,
    pub statements: Vec<Statement>,
    /// `INSERT AFTER name` (true) or `INSERT BEFORE name` (false).
    pub insert: Option<(bool, String)>,
}

impl Script {
    /// The names of the output sections, overlays' members included, in order.
    pub fn output_names(&self) -> Vec<&str> {
        let mut names = Vec::new();
        for s in &self.statements {
            match s {
                Statement::Output(o) => names.push(o.name.as_str()),
                Statement::Overlay(_, members) => {
                    names.extend(members.iter().map(|m| m.name.as_str()))
                }
                Statement::Assign(_) => {}
            }
        }
        names
    }

    /// The scripts of `-T` options combined as GNU ld combines them: the one script
    /// without `INSERT` replaces the default, and each `INSERT` script's statements go
    /// after (before) its named output section there.
    pub fn combine(scripts: Vec<(String, Script)>) -> Result<Script, String> {
        let (inserts, bases): (Vec<_>, Vec<_>) =
            scripts.into_iter().partition(|s| s.1.insert.is_some());
        let mut base = match bases.len() {
            0 => {
                return Err(format!(
                    "{}: INSERT into the default script is not supported: give a script \
                     with the whole SECTIONS too",
                    inserts[0].0
                ))
            }
            1 => bases.into_iter().next().unwrap().1,
            _ => return Err(format!("{}: a second SECTIONS script", bases[1].0)),
        };
        for (file, script) in inserts {
            let (after, name) = script.insert.clone().unwrap();
            let at = base
                .statements
                .iter()
                .position(|s| matches!(s, Statement::Output(o) if o.name == name))
                .ok_or_else(|| format!("{file}: INSERT: no output section {name}"))?;
            let at = if after { at + 1 } else { at };
            base.statements.splice(at..at, script.statements);
            if base.entry.is_none() {
                base.entry = script.entry;
            }
        }
        Ok(base)
    }
}

/// Whether `name` matches the glob `pattern` (`*`, `?`).
pub fn glob(pattern: &str, name: &str) -> bool {
    fn go(p: &[u8], n: &[u8]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some((b'*', rest)) => (0..=n.len()).any(|k| go(rest, &n[k..])),
            Some((b'?', rest)) => !n.is_empty() && go(rest, &n[1..]),
            Some((c, rest)) => n.first() == Some(c) && go(rest, &n[1..]),
        }
    }
    go(pattern.as_bytes(), name.as_bytes())
}

/// Parses the script `text` of `file`; an error names file:line:column.
pub fn parse(file: &str, text: &str) -> Result<Script, String> {
    let mut p = Parser {
        file,
        text: text.as_bytes(),
        at: 0,
        depth: 0,
    };
    p.script()
}

struct Parser<'a> {
    file: &'a str,
    text: &'a [u8],
    at: usize,
    /// How deep the expression being read nests (bounded: a script cannot exhaust the
    /// stack).
    depth: usize,
}

/// The deepest nesting of parentheses an expression may have.
const MAX_DEPTH: usize = 64;

/// Characters of a name or pattern (GNU ld's script names allow these).
fn name_char(c: u8) -> bool {
    c.is_ascii_alphanumeric() || b"_.$*?-/[]!~+:@".contains(&c)
}

impl Parser<'_> {
    fn error(&self, at: usize, what: &str) -> String {
        let before = &self.text[..at.min(self.text.len())];
        let line = before.iter().filter(|&&c| c == b'\n').count() + 1;
        let column = at
            - before
                .iter()
                .rposition(|&c| c == b'\n')
                .map_or(0, |p| p + 1)
            + 1;
        format!("{}:{line}:{column}: {what}", self.file)
    }

    fn skip(&mut self) -> Result<(), String> {
        loop {
            while self.at < self.text.len() && self.text[self.at].is_ascii_whitespace() {
                self.at += 1;
            }
            if self.text[self.at..].starts_with(b"/*") {
                let start = self.at;
                match self.text[self.at + 2..].windows(2).position(|w| w == b"*/") {
                    Some(p) => self.at += p + 4,
                    None => return Err(self.error(start, "unterminated comment")),
                }
            } else {
                return Ok(());
            }
        }
    }

    fn peek(&mut self) -> Result<Option<u8>, String> {
        self.skip()?;
        Ok(self.text.get(self.at).copied())
    }

    fn eat(&mut self, c: u8) -> Result<bool, String> {
        if self.peek()? == Some(c) {
            self.at += 1;
            return Ok(true);
        }
        Ok(false)
    }

    fn expect(&mut self, c: u8) -> Result<(), String> {
        if !self.eat(c)? {
            let found = self.describe();
            return Err(self.error(self.at, &format!("expected `{}', found {found}", c as char)));
        }
        Ok(())
    }

    fn describe(&self) -> String {
        match self.text.get(self.at) {
            None => "the end of the script".into(),
            Some(_) => {
                let end = (self.at..self.text.len())
                    .find(|&k| self.text[k].is_ascii_whitespace())
                    .unwrap_or(self.text.len())
                    .min(self.at + 20);
                format!("`{}'", String::from_utf8_lossy(&self.text[self.at..end]))
            }
        }
    }

    /// A name or pattern; `stop` characters end it even where names allow them.
    fn name_until(&mut self, stop: &[u8]) -> Result<Option<String>, String> {
        self.skip()?;
        let start = self.at;
        while self.at < self.text.len()
            && name_char(self.text[self.at])
            && !stop.contains(&self.text[self.at])
        {
            self.at += 1;
        }
        Ok((self.at > start)
            .then(|| String::from_utf8_lossy(&self.text[start..self.at]).into_owned()))
    }

    fn name(&mut self) -> Result<String, String> {
        let at = self.at;
        self.name_until(b":")?.ok_or_else(|| {
            let found = self.describe();
            self.error(at.max(self.at), &format!("expected a name, found {found}"))
        })
    }

    fn script(&mut self) -> Result<Script, String> {
        let mut script = Script::default();
        while self.peek()?.is_some() {
            let at = self.at;
            let word = self.name()?;
            match word.as_str() {
                "SECTIONS" => {
                    self.expect(b'{')?;
                    while !self.eat(b'}')? {
                        let s = self.statement()?;
                        script.statements.push(s);
                    }
                }
                "ENTRY" => {
                    self.expect(b'(')?;
                    script.entry = Some(self.name()?);
                    self.expect(b')')?;
                    self.eat(b';')?;
                }
                "INSERT" => {
                    let at = self.at;
                    let after = match self.name()?.as_str() {
                        "AFTER" => true,
                        "BEFORE" => false,
                        w => {
                            return Err(self
                                .error(at + 1, &format!("expected AFTER or BEFORE, found `{w}'")))
                        }
                    };
                    script.insert = Some((after, self.name()?));
                    self.eat(b';')?;
                }
                _ => {
                    if self.peek()? == Some(b'=') {
                        return Err(
                            self.error(at, "an assignment outside SECTIONS is not supported")
                        );
                    }
                    return Err(self.error(
                        at,
                        &format!(
                            "`{word}' is not supported (spu ld takes SECTIONS, ENTRY, INSERT)"
                        ),
                    ));
                }
            }
        }
        Ok(script)
    }

    fn statement(&mut self) -> Result<Statement, String> {
        self.skip()?;
        let at = self.at;
        let word = self.name()?;
        if word == "OVERLAY" {
            let addr = if self.peek()? == Some(b':') {
                None
            } else {
                Some(self.expr()?)
            };
            self.expect(b':')?;
            let save = self.at;
            if let Some(w) = self.name_until(b":")? {
                if w != "NOCROSSREFS" {
                    return Err(
                        self.error(save + 1, &format!("`{w}' after OVERLAY is not supported"))
                    );
                }
            }
            self.expect(b'{')?;
            let mut members = Vec::new();
            while !self.eat(b'}')? {
                let name = self.name()?;
                self.expect(b'{')?;
                let items = self.items()?;
                members.push(OutputSection {
                    name,
                    addr: None,
                    items,
                });
            }
            return Ok(Statement::Overlay(addr, members));
        }
        if word == "PROVIDE" || word == "PROVIDE_HIDDEN" {
            return Ok(Statement::Assign(self.provide()?));
        }
        if self.peek()? == Some(b'=') {
            return Ok(Statement::Assign(self.assignment(word)?));
        }
        if word == "/DISCARD/" {
            return Err(self.error(at, "/DISCARD/ is not supported"));
        }
        // An output section: NAME [addr] : { items }
        let addr = if self.peek()? == Some(b':') {
            None
        } else {
            Some(self.expr()?)
        };
        self.expect(b':')?;
        self.expect(b'{')?;
        let items = self.items()?;
        if self.peek()? == Some(b'>') || self.peek()? == Some(b'=') {
            return Err(self.error(self.at, "memory regions and fill values are not supported"));
        }
        Ok(Statement::Output(OutputSection {
            name: word,
            addr,
            items,
        }))
    }

    fn provide(&mut self) -> Result<Assignment, String> {
        self.expect(b'(')?;
        let name = self.name()?;
        let mut a = self.assignment_body(name)?;
        a.provide = true;
        self.expect(b')')?;
        self.eat(b';')?;
        Ok(a)
    }

    fn assignment_body(&mut self, name: String) -> Result<Assignment, String> {
        self.expect(b'=')?;
        let expr = self.expr()?;
        Ok(Assignment {
            name,
            expr,
            provide: false,
        })
    }

    fn assignment(&mut self, name: String) -> Result<Assignment, String> {
        let a = self.assignment_body(name)?;
        self.expect(b';')?;
        Ok(a)
    }

    /// The statements of an output section, up to its `}`.
    fn items(&mut self) -> Result<Vec<Item>, String> {
        let mut items = Vec::new();
        while !self.eat(b'}')? {
            self.skip()?;
            let at = self.at;
            let word = self.name_until(b"(")?.ok_or_else(|| {
                let found = self.describe();
                self.error(
                    at,
                    &format!("expected an input section or assignment, found {found}"),
                )
            })?;
            match word.as_str() {
                "KEEP" => {
                    self.expect(b'(')?;
                    self.skip()?;
                    let at = self.at;
                    let file = self
                        .name_until(b"(")?
                        .ok_or_else(|| self.error(at, "expected a file pattern"))?;
                    let mut spec = self.input(file)?;
                    spec.keep = true;
                    self.expect(b')')?;
                    items.push(Item::Input(spec));
                }
                "PROVIDE" | "PROVIDE_HIDDEN" => items.push(Item::Assign(self.provide()?)),
                _ if self.peek()? == Some(b'=') => items.push(Item::Assign(self.assignment(word)?)),
                _ if self.peek()? == Some(b'(') => items.push(Item::Input(self.input(word)?)),
                _ => {
                    return Err(self.error(
                        at,
                        &format!("`{word}': expected FILE(SECTIONS), KEEP(...) or an assignment"),
                    ))
                }
            }
        }
        Ok(items)
    }

    fn input(&mut self, file: String) -> Result<InputSpec, String> {
        self.expect(b'(')?;
        let mut sections = Vec::new();
        loop {
            self.skip()?;
            let at = self.at;
            match self.name_until(b"")? {
                Some(s) if s == "EXCLUDE_FILE" || s.starts_with("SORT") => {
                    return Err(self.error(at, &format!("{s} is not supported")))
                }
                Some(s) => sections.push(s),
                None => break,
            }
        }
        if sections.is_empty() {
            let found = self.describe();
            return Err(self.error(
                self.at,
                &format!("expected a section pattern, found {found}"),
            ));
        }
        self.expect(b')')?;
        Ok(InputSpec {
            keep: false,
            file,
            sections,
        })
    }

    fn expr(&mut self) -> Result<Expr, String> {
        let mut left = self.term()?;
        loop {
            let op = match self.peek()? {
                Some(c @ (b'+' | b'-' | b'&' | b'|')) => c as char,
                _ => return Ok(left),
            };
            self.at += 1;
            let right = self.term()?;
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
    }

    fn term(&mut self) -> Result<Expr, String> {
        let mut left = self.atom()?;
        loop {
            let op = match self.peek()? {
                Some(c @ (b'*' | b'/' | b'%')) => c as char,
                _ => return Ok(left),
            };
            self.at += 1;
            let right = self.atom()?;
            left = Expr::Binary(op, Box::new(left), Box::new(right));
        }
    }

    fn atom(&mut self) -> Result<Expr, String> {
        self.skip()?;
        let at = self.at;
        match self.peek()? {
            Some(b'(') => {
                if self.depth >= MAX_DEPTH {
                    return Err(self.error(at, "expression nested too deeply"));
                }
                self.at += 1;
                self.depth += 1;
                let e = self.expr();
                self.depth -= 1;
                let e = e?;
                self.expect(b')')?;
                return Ok(e);
            }
            Some(c) if c.is_ascii_digit() => {
                let start = self.at;
                while self.at < self.text.len() && self.text[self.at].is_ascii_alphanumeric() {
                    self.at += 1;
                }
                let s = String::from_utf8_lossy(&self.text[start..self.at]).to_lowercase();
                let (digits, scale) = match s.strip_suffix('k') {
                    Some(d) if !d.starts_with("0x") => (d.to_string(), 1024),
                    _ => match s.strip_suffix('m') {
                        Some(d) => (d.to_string(), 1 << 20),
                        None => (s.clone(), 1),
                    },
                };
                let v = match digits.strip_prefix("0x") {
                    Some(h) => u64::from_str_radix(h, 16),
                    None => digits.parse(),
                }
                .map_err(|_| self.error(start, &format!("bad number `{s}'")))?;
                return Ok(Expr::Number(v * scale));
            }
            _ => {}
        }
        let name = self.name_until(b"+-*/%&|:")?.ok_or_else(|| {
            let found = self.describe();
            self.error(
                at.max(self.at),
                &format!("expected an expression, found {found}"),
            )
        })?;
        if name == "." {
            return Ok(Expr::Dot);
        }
        if name == "ALIGN" {
            self.expect(b'(')?;
            let first = self.expr()?;
            if self.eat(b',')? {
                let n = self.expr()?;
                self.expect(b')')?;
                return Ok(Expr::Align(Some(Box::new(first)), Box::new(n)));
            }
            self.expect(b')')?;
            return Ok(Expr::Align(None, Box::new(first)));
        }
        if self.peek()? == Some(b'(') {
            return Err(self.error(at, &format!("the function `{name}' is not supported")));
        }
        Ok(Expr::Symbol(name))
    }
}

impl Script {
    /// The output section and the statement (1-based, in its section) that take input
    /// section `section` of file `file`: the first that matches, in the script's order.
    pub fn assign(&self, file: &str, section: &str) -> Option<(String, u32)> {
        let base = file.rsplit('/').next().unwrap_or(file);
        let takes = |o: &OutputSection| {
            o.items.iter().enumerate().find_map(|(r, item)| match item {
                Item::Input(spec)
                    if (glob(&spec.file, file) || glob(&spec.file, base))
                        && spec.sections.iter().any(|p| glob(p, section)) =>
                {
                    Some((o.name.clone(), r as u32 + 1))
                }
                _ => None,
            })
        };
        self.statements.iter().find_map(|s| match s {
            Statement::Output(o) => takes(o),
            Statement::Overlay(_, members) => members.iter().find_map(takes),
            Statement::Assign(_) => None,
        })
    }

    /// The members of each `OVERLAY` statement, in order.
    pub fn overlay_regions(&self) -> Vec<Vec<String>> {
        self.statements
            .iter()
            .filter_map(|s| match s {
                Statement::Overlay(_, m) => Some(m.iter().map(|o| o.name.clone()).collect()),
                _ => None,
            })
            .collect()
    }
}

/// An output section as the layout sees it.
pub(crate) struct Placed {
    pub name: String,
    pub size: u64,
    pub align: u64,
    /// Its kind for orphan placement: 0 code, 1 read-only data, 2 data, 3 bss; 5 for
    /// what the caller places after everything (notes, `._ea`).
    pub class: u8,
    /// Takes an address but no room (`.tbss`).
    pub tbss: bool,
    /// The end of its contents after each of its script statements (by statement).
    pub item_ends: Vec<u64>,
}

/// Addresses (VMA and LMA) of the output sections and the script's symbols.
pub(crate) struct Layout {
    pub addr: Vec<u64>,
    pub lma: Vec<u64>,
    /// (name, value, only if referenced and undefined)
    pub symbols: Vec<(String, u64, bool)>,
    /// The location counter at the end.
    pub end: u64,
}

enum Step<'a> {
    Assign(&'a Assignment),
    Out(Option<usize>, &'a OutputSection),
    Orphan(usize),
    Overlay(Option<&'a Expr>, Vec<(Option<usize>, &'a OutputSection)>),
}

/// Lays `outs` out as GNU ld runs `script`: `.` from 0, each output section at its
/// address or at `.` aligned to its inputs, an `OVERLAY`'s members all at its start and
/// loaded one after another (their LMAs consecutive, the sections after them keeping
/// the last one's LMA offset), sections the script does not name placed as orphans
/// after the last named section of their kind.
pub(crate) fn lay_out(script: &Script, outs: &[Placed]) -> Result<Layout, String> {
    let find = |name: &str| outs.iter().position(|o| o.name == name && o.size > 0);
    let mut steps: Vec<Step> = Vec::new();
    let named = script.output_names();
    for s in &script.statements {
        steps.push(match s {
            Statement::Assign(a) => Step::Assign(a),
            Statement::Output(o) => Step::Out(find(&o.name), o),
            Statement::Overlay(addr, m) => Step::Overlay(
                addr.as_ref(),
                m.iter().map(|o| (find(&o.name), o)).collect(),
            ),
        });
    }
    for (k, o) in outs.iter().enumerate() {
        if named.contains(&o.name.as_str()) || o.class == 5 || o.size == 0 {
            continue;
        }
        let class_of = |s: &Step| match s {
            Step::Out(Some(j), _) | Step::Orphan(j) => Some(outs[*j].class),
            _ => None,
        };
        let at = steps
            .iter()
            .rposition(|s| class_of(s).is_some_and(|c| c <= o.class))
            .map_or(steps.len(), |p| p + 1);
        steps.insert(at, Step::Orphan(k));
    }
    let mut layout = Layout {
        addr: vec![0; outs.len()],
        lma: vec![0; outs.len()],
        symbols: Vec::new(),
        end: 0,
    };
    let mut dot = 0u64;
    let mut lma_delta = 0u64;
    let mut known: std::collections::HashMap<String, u64> = Default::default();
    let assign = |a: &Assignment,
                  dot: &mut u64,
                  known: &mut std::collections::HashMap<String, u64>,
                  layout: &mut Layout,
                  in_section: bool|
     -> Result<(), String> {
        let v = a.expr.eval(*dot, &|n| known.get(n).copied())?;
        if a.name == "." {
            if in_section {
                return Err("`. =' inside an output section is not supported".into());
            }
            if v > u32::MAX as u64 {
                return Err(format!("`. = {v:#x}': outside the 32-bit address space"));
            }
            *dot = v;
        } else {
            known.insert(a.name.clone(), v);
            layout.symbols.push((a.name.clone(), v, a.provide));
        }
        Ok(())
    };
    let items = |k: Option<usize>,
                 o: &OutputSection,
                 start: u64,
                 known: &mut std::collections::HashMap<String, u64>,
                 layout: &mut Layout|
     -> Result<(), String> {
        for (r, item) in o.items.iter().enumerate() {
            if let Item::Assign(a) = item {
                let end = k.map_or(0, |k| outs[k].item_ends.get(r).copied().unwrap_or(0));
                let mut at = start + end;
                assign(a, &mut at, known, layout, true)?;
            }
        }
        Ok(())
    };
    for step in &steps {
        match step {
            Step::Assign(a) => assign(a, &mut dot, &mut known, &mut layout, false)?,
            Step::Out(k, o) => {
                let explicit = match &o.addr {
                    Some(e) => Some(e.eval(dot, &|n| known.get(n).copied())?),
                    None => None,
                };
                let Some(k) = *k else {
                    items(None, o, explicit.unwrap_or(dot), &mut known, &mut layout)?;
                    continue;
                };
                dot = match explicit {
                    Some(a) => {
                        lma_delta = 0;
                        a
                    }
                    None => dot.next_multiple_of(outs[k].align.max(1)),
                };
                layout.addr[k] = dot;
                layout.lma[k] = dot.wrapping_add(lma_delta);
                items(Some(k), o, dot, &mut known, &mut layout)?;
                if !outs[k].tbss {
                    dot += outs[k].size;
                }
            }
            Step::Orphan(k) => {
                dot = dot.next_multiple_of(outs[*k].align.max(1));
                layout.addr[*k] = dot;
                layout.lma[*k] = dot.wrapping_add(lma_delta);
                if !outs[*k].tbss {
                    dot += outs[*k].size;
                }
            }
            Step::Overlay(addr, members) => {
                let base = match addr {
                    Some(e) => e.eval(dot, &|n| known.get(n).copied())?,
                    None => dot,
                };
                let mut lma = base;
                let mut end = base;
                for (k, o) in members {
                    items(*k, o, base, &mut known, &mut layout)?;
                    let Some(k) = *k else { continue };
                    layout.addr[k] = base;
                    layout.lma[k] = lma;
                    lma_delta = lma - base;
                    lma += outs[k].size;
                    end = end.max(base + outs[k].size);
                }
                dot = end;
            }
        }
    }
    layout.end = dot;
    Ok(layout)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_an_overlay_script_and_inserts_it() {
        let base = parse(
            "ovl.lnk",
            "SECTIONS\n{\n  . = 0x100;\n  .text : { *(.text) *(.stub) }\n  .data : { *(.data) *(.ovtab) }\n  .bss : { *(.bss) }\n}\n",
        )
        .unwrap();
        let ovl = parse(
            "ovl1.lnk",
            "SECTIONS\n{\n  OVERLAY 0x400 :\n  {\n    .ov_a1 { *(.ov_a1) }\n    .ov_a2 { *(.ov_a2) }\n  }\n}\nINSERT AFTER .text;\n",
        )
        .unwrap();
        assert_eq!(ovl.insert, Some((true, ".text".into())));
        let all =
            Script::combine(vec![("ovl1.lnk".into(), ovl), ("ovl.lnk".into(), base)]).unwrap();
        assert_eq!(
            all.output_names(),
            [".text", ".ov_a1", ".ov_a2", ".data", ".bss"]
        );
        assert_eq!(
            all.statements[0],
            Statement::Assign(Assignment {
                name: ".".into(),
                expr: Expr::Number(0x100),
                provide: false
            })
        );
        let Statement::Output(text) = &all.statements[1] else {
            panic!("{:?}", all.statements[1])
        };
        assert_eq!(
            text.items,
            [
                Item::Input(InputSpec {
                    keep: false,
                    file: "*".into(),
                    sections: vec![".text".into()]
                }),
                Item::Input(InputSpec {
                    keep: false,
                    file: "*".into(),
                    sections: vec![".stub".into()]
                })
            ]
        );
    }

    #[test]
    fn reads_addresses_keep_provide_and_entry() {
        let s = parse(
            "a.ld",
            "ENTRY(main) /* c */ SECTIONS { .text 0x200 : { KEEP(crt0.o(.init)) *(.text .text.*) x = . ; } \
             . = ALIGN(0x80) + 4*2; PROVIDE(__stack = 0x3fff0); }",
        )
        .unwrap();
        assert_eq!(s.entry.as_deref(), Some("main"));
        let Statement::Output(o) = &s.statements[0] else {
            panic!()
        };
        assert_eq!(o.addr, Some(Expr::Number(0x200)));
        assert_eq!(
            o.items[0],
            Item::Input(InputSpec {
                keep: true,
                file: "crt0.o".into(),
                sections: vec![".init".into()]
            })
        );
        let Statement::Assign(a) = &s.statements[1] else {
            panic!()
        };
        assert_eq!(a.expr.eval(0x101, &|_| None), Ok(0x188));
        let Statement::Assign(p) = &s.statements[2] else {
            panic!()
        };
        assert!(p.provide && p.name == "__stack");
    }

    #[test]
    fn errors_name_file_line_and_column() {
        let e = parse("x.ld", "SECTIONS\n{\n  .text : { *(.text) }\n  MEMORY\n}\n").unwrap_err();
        assert_eq!(e, "x.ld:5:1: expected an expression, found `}'");
        let e = parse("x.ld", "OUTPUT_FORMAT(elf32-spu)\n").unwrap_err();
        assert_eq!(
            e,
            "x.ld:1:1: `OUTPUT_FORMAT' is not supported (spu ld takes SECTIONS, ENTRY, INSERT)"
        );
        let e = parse("x.ld", "SECTIONS { .t : { *(.text) } > ram }").unwrap_err();
        assert_eq!(
            e,
            "x.ld:1:30: memory regions and fill values are not supported"
        );
        let e = parse("x.ld", "SECTIONS { /* open").unwrap_err();
        assert_eq!(e, "x.ld:1:12: unterminated comment");
        let deep = format!(
            "SECTIONS {{ . = {}1{}; }}",
            "(".repeat(100_000),
            ")".repeat(100_000)
        );
        let e = parse("x.ld", &deep).unwrap_err();
        assert_eq!(e, "x.ld:1:80: expression nested too deeply");
        let e = parse("x.ld", "SECTIONS { . = SIZEOF(.text); }").unwrap_err();
        assert_eq!(e, "x.ld:1:16: the function `SIZEOF' is not supported");
    }

    #[test]
    fn globs_match_as_ld_matches() {
        assert!(glob("*", "a.o"));
        assert!(glob("empty.o?", "empty.o1"));
        assert!(!glob("empty.o?", "empty.o"));
        assert!(glob(".text.*", ".text.hot"));
        assert!(!glob(".text.*", ".text"));
    }
}
