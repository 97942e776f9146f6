//! Symbols (gas's `symbols.c` and the symbol side of `expr.c`): what a name stands for
//! (a `.set` value, a label in a chunk, a common block), numeric local labels, labels and
//! `.set` as statements define them, and expressions evaluated against them
//! (`crate::expr` parses and evaluates; this is its environment).

use super::{Assembler, Res, Sect, Severity};
use crate::expr::{Env, Eval, Val};
use crate::lex::Line;

/// What a symbol is: a value, a place in a chunk, or a common block.
#[derive(Clone, Debug)]
pub(super) enum SymVal {
    /// A value from `.set`/`=` (which may be an address).
    Abs(Val),
    Label(Sect, u32),
    /// `.comm name, size, align` in an object: allocated by the linker.
    Common(u32, u32),
}

/// One link of gas's symbol chain: the order symbols are made in (first mention, by
/// reference or definition), which is the order of an object's symbol table.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Link {
    Symbol(String),
    /// A section's own symbol, made with the section by a section directive.
    Section(usize),
    /// `.file "NAME"`: the first goes to the head of the chain.
    File(String),
}

/// The symbol chain of the final walk.
#[derive(Clone, Debug, Default)]
pub(super) struct Chain {
    pub(super) links: Vec<Link>,
    names: std::collections::HashSet<String>,
    sections: std::collections::HashSet<usize>,
}

impl Chain {
    pub(super) fn symbol(&mut self, name: &str) {
        if !self.names.contains(name) {
            self.names.insert(name.to_string());
            self.links.push(Link::Symbol(name.to_string()));
        }
    }

    pub(super) fn has_section(&self, d: usize) -> bool {
        self.sections.contains(&d)
    }

    /// A section made without a symbol on the chain.
    pub(super) fn section_unlinked(&mut self, d: usize) {
        self.sections.insert(d);
    }

    pub(super) fn section(&mut self, d: usize) {
        if self.sections.insert(d) {
            self.links.push(Link::Section(d));
        }
    }

    /// obj-elf.c's `elf_file_symbol`: at the head unless a file symbol is there already.
    pub(super) fn file(&mut self, name: &str) {
        let link = Link::File(name.to_string());
        if matches!(self.links.first(), Some(Link::File(_))) {
            self.links.push(link);
        } else {
            self.links.insert(0, link);
        }
    }
}

/// `.type NAME, @function`: an ELF `STT_FUNC` symbol.
pub(super) const STT_FUNC: u8 = 2;

/// `.type NAME, %gnu_indirect_function`: an ELF `STT_GNU_IFUNC` symbol.
pub(super) const STT_GNU_IFUNC: u8 = 10;

/// Symbol attributes set by directives.
#[derive(Clone, Debug, Default)]
pub(super) struct SymAttrs {
    pub(super) global: bool,
    pub(super) weak: bool,
    /// STV_* from `.internal` (1), `.hidden` (2), `.protected` (3).
    pub(super) visibility: u8,
    /// STT_* from `.type` (1 object, 2 function).
    pub(super) kind: u8,
    pub(super) size: Option<i64>,
    /// The size is an equated symbol's (a later equate replaces it, `.size` does not).
    pub(super) size_copied: bool,
    /// `.type`'s BFD flags (obj-elf.c `obj_elf_type`) and the walk that set them.
    pub(super) type_bits: u8,
    pub(super) type_pass: u8,
    /// A `.type` that only GNU's ELF has (`%gnu_indirect_function`) was given.
    pub(super) gnu_osabi: bool,
}

impl Assembler<'_> {
    /// A weakref alias's final target (through aliases of aliases), if NAME is one.
    pub(super) fn weakref_target(&self, name: &str) -> Option<String> {
        let mut target = self.weakrefs.get(name)?;
        for _ in 0..self.weakrefs.len() {
            match self.weakrefs.get(target) {
                Some(next) => target = next,
                None => break,
            }
        }
        Some(target.clone())
    }

    /// What NAME stands for in an expression, made in the chain as it is read.
    fn symbol_value(&self, name: &str) -> Option<Val> {
        self.note_symbol(name);
        if self.dot_eqv.contains_key(name) && self.symbols.contains_key(name) {
            return self.eqv_here(name);
        }
        if !self.symbols.contains_key(name) {
            self.forward_refs.borrow_mut().push(name.to_string());
        } else if let Some(deps) = self.set_forward.get(name) {
            // A `.set` symbol that itself waits on later definitions: this expression
            // waits on them too (how `.set a,b` / `.set b,a` is seen to loop).
            self.forward_refs.borrow_mut().extend(deps.iter().cloned());
        }
        if !self.symbols.contains_key(name) && (self.pass == 2 || !self.pass1_symbols.is_empty()) {
            // A `.set`/`.equ` symbol used before its definition: its final value.
            return match self.pass1_symbols.get(name)? {
                SymVal::Abs(v) => Some(v.clone()),
                _ => None,
            };
        }
        Some(self.value_of(name, self.symbols.get(name)?))
    }
}

impl Env for Assembler<'_> {
    fn symbol(&self, name: &str) -> Option<Val> {
        if let Some(target) = self.weakref_target(name) {
            return self.symbol_value(&target);
        }
        if self.pass == 2 {
            self.direct_uses.borrow_mut().insert(name.to_string());
        }
        self.symbol_value(name)
    }
    fn dot(&self) -> Val {
        if let Some(off) = self.absolute {
            return Val::abs(off as i64);
        }
        Val {
            v: self.here() as i64,
            reloc: true,
            sect: Some(self.chunks[self.sect].0),
            ..Default::default()
        }
    }
    fn local(&self, n: u32, forward: bool) -> Option<Val> {
        self.numeric_ref(n, forward)
    }
    fn lenient(&self) -> bool {
        self.pass == 1
    }
    fn external(&self, name: &str) -> Option<Val> {
        // In an object, a symbol defined nowhere is an external reference for the linker.
        (self.object && !name.starts_with(".L")).then(|| Val {
            v: 0,
            reloc: true,
            sym: Some((name.into(), 0)),
            ..Default::default()
        })
    }
}

impl Assembler<'_> {
    /// The value of a `.eqv` symbol whose expression holds `.`, evaluated here.
    pub(super) fn eqv_here(&self, name: &str) -> Option<Val> {
        let text = self.dot_eqv.get(name)?;
        if text == "." {
            return Some(self.dot());
        }
        if self.eqv_depth.get() > 32 {
            return None;
        }
        let (ast, _) = crate::expr::parse(text)?;
        self.eqv_depth.set(self.eqv_depth.get() + 1);
        let v = Eval {
            env: self,
            warnings: Vec::new(),
            undefined: false,
        }
        .eval(&ast)
        .ok();
        self.eqv_depth.set(self.eqv_depth.get() - 1);
        v
    }

    /// A name mentioned in the final walk: it joins the symbol chain if it is new.
    pub(super) fn note_symbol(&self, name: &str) {
        // Numeric local labels (`1:`) are gas's own internal names, never in the table.
        if self.pass == 2 && !name.is_empty() && !name.bytes().all(|b| b.is_ascii_digit()) {
            self.chain.borrow_mut().symbol(name);
        }
    }

    /// A section made (or first entered) by a section directive in the final walk.
    pub(super) fn note_section(&self, d: usize) {
        if self.pass == 2 {
            // A section's symbol bears its name: a second section of that name (in a
            // group) finds the first's and gets its own only from BFD, after the chain.
            let mut chain = self.chain.borrow_mut();
            let named = (0..self.defs.len())
                .any(|o| o != d && self.defs[o].name == self.defs[d].name && chain.has_section(o));
            if named {
                chain.section_unlinked(d);
            } else {
                chain.section(d);
            }
        }
    }

    /// A defined symbol's address or value (executables).
    pub(super) fn symbol_address(&self, name: &str) -> Option<i64> {
        self.symbols.get(name).map(|s| self.value_of(name, s).v)
    }

    pub(super) fn value_of(&self, name: &str, sv: &SymVal) -> Val {
        match sv {
            // A local name for an address in a section (`alias = later`) is that address:
            // gas resolves a branch to it like one to a local label.
            SymVal::Abs(v)
                if v.sect.is_some()
                    && !self.attrs.get(name).is_some_and(|a| a.global || a.weak) =>
            {
                Val {
                    sym: None,
                    ..v.clone()
                }
            }
            SymVal::Abs(v) => v.clone(),
            SymVal::Label(s, off) => {
                let v = (self.bases.get(s).copied().unwrap_or(0) + off) as i64;
                let a = self.attrs.get(name);
                // A relocation names a global symbol, and a function even when local
                // (tc-spu.h's `tc_fix_adjustable`: never reduced to its section's symbol).
                let named = a.is_some_and(|a| a.global || a.weak || a.kind == STT_FUNC);
                Val {
                    v,
                    reloc: true,
                    sect: Some(self.chunks[*s].0),
                    sym: (self.object && named).then(|| (name.into(), v)),
                    ..Default::default()
                }
            }
            SymVal::Common(..) => Val {
                v: 0,
                reloc: true,
                sym: Some((name.into(), 0)),
                ..Default::default()
            },
        }
    }

    pub(super) fn numeric_ref(&self, n: u32, forward: bool) -> Option<Val> {
        // Backward references in a layout walk see this walk's definitions so far;
        // forward ones (and every reference in the final walk) the previous walk's.
        let table = if self.pass == 1 && !forward {
            &self.numeric_next
        } else {
            &self.numeric
        };
        let defs = table.get(&n)?;
        let pick = if forward {
            defs.iter().find(|d| d.0 > self.stmt)
        } else {
            defs.iter().rev().find(|d| d.0 < self.stmt)
        }?;
        Some(Val {
            v: (self.bases.get(&pick.1).copied().unwrap_or(0) + pick.2) as i64,
            reloc: true,
            sect: Some(self.chunks[pick.1].0),
            ..Default::default()
        })
    }

    /// Evaluates a whole expression: its value (and whether it is an address) and any
    /// warnings (division by zero, shift counts).
    pub(super) fn eval_val(&self, text: &str) -> Res<(Val, bool, Vec<String>)> {
        let (val, rest, undefined, warnings) = self.eval_prefix(text)?;
        let used = text.len() - rest.len();
        if !rest.trim().is_empty() {
            return Err((
                used,
                format!("junk at end of expression: `{}`", rest.trim()),
            ));
        }
        Ok((val, undefined, warnings))
    }

    /// Evaluates the expression at the start of `text`, returning the rest as gas's
    /// `expression()` leaves it.
    pub(super) fn eval_prefix<'t>(&self, text: &'t str) -> Res<(Val, &'t str, bool, Vec<String>)> {
        let lead = text.len() - text.trim_start().len();
        self.forward_refs.borrow_mut().clear();
        let Some((ast, rest)) = crate::expr::parse(text) else {
            return Err((lead, "expected an expression".into()));
        };
        let mut e = Eval {
            env: self,
            warnings: Vec::new(),
            undefined: false,
        };
        let v = e.eval(&ast)?;
        Ok((v, rest, e.undefined, e.warnings))
    }

    pub(super) fn eval(&self, text: &str) -> Res<(i64, bool)> {
        self.eval_val(text).map(|(v, u, _)| (v.v, u))
    }

    pub(super) fn define_label(&mut self, name: &str, line: &Line) {
        self.note_symbol(name);
        if let Some(off) = self.absolute {
            // A label in the absolute section (`.struct`) is a number.
            self.symbols
                .insert(name.to_string(), SymVal::Abs(Val::abs(off as i64)));
            return;
        }
        let off = self.offsets.get(&self.sect).copied().unwrap_or(0);
        if name.bytes().all(|b| b.is_ascii_digit()) && name.parse::<u32>().is_err() {
            // read.c: a local label's number must fit gas's `long`-sized counter.
            self.diag(
                Severity::Error,
                line,
                1,
                format!("local label too large near {name}:"),
            );
            return;
        }
        if let Ok(n) = name.parse::<u32>() {
            if self.pass == 1 {
                self.numeric_next
                    .entry(n)
                    .or_default()
                    .push((self.stmt, self.sect, off));
            }
            return;
        }
        let first = self.defined.insert(name.to_string());
        let section = self.defs.iter().position(|d| d.name == name);
        if self.pass == 2 && section.is_some_and(|d| self.chain.borrow().has_section(d)) {
            // A section's symbol bears its name (obj-elf.c), so the label is a second one.
            let m = format!("symbol `{name}' is already defined");
            self.diag(Severity::Error, line, 1, m);
        }
        if self.pass == 1 && (!first || matches!(self.symbols.get(name), Some(SymVal::Common(..))))
        {
            self.diag(
                Severity::Error,
                line,
                1,
                format!("symbol `{name}` is already defined"),
            );
        }
        self.symbols
            .insert(name.to_string(), SymVal::Label(self.sect, off));
    }

    /// read.c `assign_symbol`: a symbol defined already (a label, a common block, an
    /// equate) takes a value again only by `.set`/`.equ`/`=` (`volatile`) over an equate
    /// made by one of them; otherwise "symbol `x' is already defined" and the statement
    /// is dropped (false).
    pub(super) fn may_assign(
        &mut self,
        name: &str,
        volatile: bool,
        line: &Line,
        col: usize,
    ) -> bool {
        let equated = self.equated.get(name).copied();
        let defined = self.defined.contains(name)
            || matches!(self.symbols.get(name), Some(SymVal::Common(..)))
            || equated.is_some();
        if name != "." && defined && !(volatile && equated == Some(true)) {
            self.diag(
                Severity::Error,
                line,
                col,
                format!("symbol `{name}` is already defined"),
            );
            return false;
        }
        if name != "." {
            self.equated.insert(name.to_string(), volatile);
        }
        true
    }

    pub(super) fn set_symbol(&mut self, name: &str, expr: &str, line: &Line) {
        if name == "." {
            let col = line.text.find('=').map_or(1, |c| c + 2);
            self.org(expr, 0, line, col);
            return;
        }
        self.note_symbol(name);
        let col = line.text.find(expr).map_or(1, |c| c + 1);
        let result = self.eval_reported(expr, line, col);
        let forward: Vec<String> = std::mem::take(&mut *self.forward_refs.borrow_mut());
        match result {
            Ok(v) => {
                self.symbols.insert(name.to_string(), SymVal::Abs(v));
                // read.c pseudo_set: equated to a symbol, it takes that symbol's type and
                // size (copy_symbol_attributes).
                let target = expr.trim();
                if target != name
                    && crate::expr::is_ident_start(target.chars().next().unwrap_or(' '))
                    && target.chars().all(crate::expr::is_ident)
                {
                    if let Some(t) = self.attrs.get(target).cloned() {
                        let a = self.attrs.entry(name.to_string()).or_default();
                        if a.kind == 0 {
                            a.kind = t.kind;
                        }
                        if a.size.is_none() || a.size_copied {
                            a.size = t.size;
                            a.size_copied = true;
                        }
                    }
                }
            }
            Err((c, m)) => self.diag(Severity::Error, line, c + 1, m),
        }
        if forward.iter().any(|f| f == name) {
            // gas's resolve_symbol_value finds this when it resolves the symbol.
            self.diag(
                Severity::Error,
                line,
                1,
                format!("symbol definition loop encountered at `{name}'"),
            );
        }
        self.set_forward.insert(name.to_string(), forward);
    }

    /// Evaluates `text` (at column `col` of `line`), reporting its warnings there.
    pub(super) fn eval_reported(&mut self, text: &str, line: &Line, col: usize) -> Res<Val> {
        let (v, _, warnings) = self.eval_val(text)?;
        for w in warnings {
            self.diag(Severity::Warning, line, col, w);
        }
        Ok(v)
    }

    /// gas's `emit_expr`: a value whose bits above `size` bytes are neither all zeros nor
    /// all ones is stored truncated, with a warning in gas's words.
    pub(super) fn truncation_warning(&mut self, v: i64, size: usize, line: &Line, col: usize) {
        if size >= 8 {
            return;
        }
        let mask = !0u64 << (8 * size);
        // read.c emit_expr: leading bits holding both 0s and 1s, of the value and of its
        // negation (so -256 in a byte warns, -128 does not).
        let (high, negated_high) = (v as u64 & mask, (v as u64).wrapping_neg() & mask);
        if high != 0 && negated_high != 0 {
            let kept = v as u64 & !mask;
            self.diag(
                Severity::Warning,
                line,
                col,
                format!("value {:#x} truncated to {kept:#x}", v as u64),
            );
        }
    }
}

/// read.c `get_symbol_name`: a name in double quotes holds any characters, `\` taking
/// the next one as it is, and quoted pieces written together make one name
/// (`"back""slash"` is `backslash`); the name and the text after it.
pub(super) fn quoted_name(text: &str) -> Option<(String, &str)> {
    let mut rest = text.strip_prefix('"')?;
    let mut name = String::new();
    loop {
        let mut chars = rest.char_indices();
        loop {
            match chars.next()? {
                (_, '\\') => name.push(chars.next()?.1),
                (i, '"') => {
                    rest = &rest[i + 1..];
                    break;
                }
                (_, c) => name.push(c),
            }
        }
        match rest.strip_prefix('"') {
            Some(more) => rest = more,
            None => return Some((name, rest)),
        }
    }
}
