//! Macros and repetitions (gas's `macro.c` as `read.c` drives it): `.macro` definitions
//! and their expansion with arguments, `.rept`, `.irp` and `.irpc`, and the expansion of a
//! `.sched` block's macro calls before it is scheduled. The text handling (arguments,
//! substitution) is `crate::expand`, shared with `spu sched`.

use super::read::block_word;
use super::{Assembler, Severity, MAX_EXPANDED, MAX_MACRO_NEST};
use crate::expand::{
    alt_arguments, block_end, irp_values, macro_argument, substitute, substitute_bare,
};
use crate::lex::{split_top, strip_comment, Line};
use std::collections::HashMap;

/// A `.macro`: its parameters (with defaults) and its body.
#[derive(Clone, Debug)]
pub(super) struct Macro {
    pub(super) name: String,
    pub(super) params: Vec<(String, Option<String>)>,
    /// Parameters qualified `:req` (a call must give them).
    pub(super) required: Vec<String>,
    /// The last parameter qualified `:vararg` takes the rest of the arguments as written.
    pub(super) vararg: bool,
    pub(super) body: Vec<Line>,
}

impl Assembler<'_> {
    pub(super) fn block(&mut self, kind: &str, args: &str, body: Vec<Line>, line: &Line) {
        match kind {
            ".rept" => match self.eval(args) {
                Ok((n, _)) => {
                    if n > 1 << 20 {
                        self.diag(
                            Severity::Error,
                            line,
                            1,
                            format!(".rept count {n} is more than {}", 1 << 20),
                        );
                        return;
                    }
                    for _ in 0..n.max(0) {
                        if self.exitm || self.expanded > MAX_EXPANDED {
                            break;
                        }
                        self.run_lines(&body);
                    }
                }
                Err((c, m)) => self.diag(Severity::Error, line, c + 1, m),
            },
            ".irp" | ".irpc" => {
                let (var, mut values) = irp_values(kind == ".irpc", args);
                if values.is_empty() {
                    values.push(String::new()); // macro.c: no values, the body once
                }
                for v in values {
                    if self.exitm || self.expanded > MAX_EXPANDED {
                        break;
                    }
                    let expanded: Vec<Line> = body
                        .iter()
                        .map(|l| Line {
                            text: substitute(&l.text, &[(var.clone(), v.clone())], None),
                            ..l.clone()
                        })
                        .collect();
                    self.run_lines(&expanded);
                }
            }
            _ => {
                // .macro NAME params
                let args = args.trim_start();
                let end = args
                    .find(|c: char| c.is_whitespace() || c == ',')
                    .unwrap_or(args.len());
                let (name, list) = (args[..end].to_string(), &args[end..]);
                if name.is_empty() {
                    self.diag(Severity::Error, line, 1, "Missing macro name");
                    return;
                }
                // macro.c do_formals: parameters apart by commas (or blanks), one comma
                // after the name; an empty one is a bad list.
                let list = list.trim_start();
                let list = list.strip_prefix(',').unwrap_or(list);
                let bad_list = (list.len() != args[end..].trim_start().len()
                    && list.trim().is_empty())
                    || (!list.trim().is_empty()
                        && list.split(',').any(|piece| piece.trim().is_empty()));
                if bad_list {
                    self.diag(
                        Severity::Error,
                        line,
                        1,
                        format!("Bad parameter list for macro `{name}'"),
                    );
                    return;
                }
                if self.macros.contains_key(&name.to_ascii_lowercase()) {
                    self.diag(
                        Severity::Error,
                        line,
                        1,
                        format!("Macro `{name}' was already defined"),
                    );
                    return;
                }
                if super::read::names_pseudo_op(&name) {
                    // read.c s_macro: the pseudo-op keeps the name when read (the macro
                    // is defined all the same).
                    self.diag(
                        Severity::Warning,
                        line,
                        1,
                        format!(
                            "attempt to redefine pseudo-op `{}' ignored",
                            name.to_ascii_lowercase()
                        ),
                    );
                }
                let mut params: Vec<(String, Option<String>)> = Vec::new();
                let mut required = Vec::new();
                let mut vararg = false;
                // `name : qual` and `name = default` may have blanks around `:` and `=`.
                let mut joined = String::new();
                for c in list.chars() {
                    if matches!(c, ':' | '=') {
                        joined.truncate(joined.trim_end().len());
                    } else if c.is_whitespace() && joined.ends_with([':', '=']) {
                        continue;
                    }
                    joined.push(c);
                }
                let words: Vec<&str> = joined
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|s| !s.is_empty())
                    .collect();
                for (k, p) in words.iter().enumerate() {
                    let (head, default) = match p.split_once('=') {
                        Some((n, d)) => (n.trim(), Some(d.trim().to_string())),
                        None => (p.trim(), None),
                    };
                    // macro.c do_formals: `name:req` and `name:vararg` (the last only).
                    let (pname, qual) = head.split_once(':').unwrap_or((head, ""));
                    match qual {
                        "" => {}
                        "req" => required.push(pname.to_string()),
                        "vararg" if k + 1 == words.len() => vararg = true,
                        "vararg" => self.diag(
                            Severity::Error,
                            line,
                            1,
                            format!(
                                "Only the last formal of macro `{name}' may be :vararg ({pname})"
                            ),
                        ),
                        q => self.diag(
                            Severity::Error,
                            line,
                            1,
                            format!("`{q}' is not a valid parameter qualifier for `{pname}'"),
                        ),
                    }
                    if params.iter().any(|(p, _)| p == pname) {
                        self.diag(
                            Severity::Error,
                            line,
                            1,
                            format!(
                                "A parameter named `{pname}' already exists for macro `{name}'"
                            ),
                        );
                        return;
                    }
                    params.push((pname.to_string(), default));
                }
                self.macros.insert(
                    name.to_ascii_lowercase(),
                    Macro {
                        name,
                        params,
                        required,
                        vararg,
                        body,
                    },
                );
            }
        }
    }

    /// `.purgem NAME`: forgets a macro (gas warns when there is none).
    pub(super) fn purge_macro(&mut self, args: &str, line: &Line, col: usize) {
        let name = args.trim().to_ascii_lowercase();
        if self.macros.remove(&name).is_none() {
            self.diag(
                Severity::Warning,
                line,
                col,
                format!("Attempt to purge non-existing macro `{}'", args.trim()),
            );
        }
    }

    pub(super) fn expand_macro(&mut self, m: &Macro, args: &str, line: &Line) {
        if self.macro_depth >= MAX_MACRO_NEST {
            self.diag(Severity::Error, line, 1, "macros nested too deeply");
            return;
        }
        let body = self.macro_lines(m, args, line);
        self.macro_depth += 1;
        self.run_lines(&body);
        self.macro_depth -= 1;
        self.exitm = false;
    }

    /// A macro's body with its arguments substituted, at the calling line.
    pub(super) fn macro_lines(&mut self, m: &Macro, args: &str, line: &Line) -> Vec<Line> {
        // `\@` is the number of expansions before this one (GNU as counts from 0).
        let counter = self.macro_counter.to_string();
        self.macro_counter += 1;
        let pieces = if args.trim().is_empty() {
            vec![]
        } else {
            split_top(args, ',')
        };
        let given: Vec<String> = if self.altmacro {
            let mut given = alt_arguments(args);
            for g in &mut given {
                // `%EXPR`: the expression's value, in decimal.
                if let Some(e) = g.strip_prefix('%') {
                    match self.eval(e) {
                        Ok((v, _)) => *g = v.to_string(),
                        Err((_, m)) => self.diag(Severity::Error, line, 1, m),
                    }
                }
            }
            given
        } else {
            pieces.iter().map(|s| macro_argument(s.trim())).collect()
        };
        let pieces = if self.altmacro { given.clone() } else { pieces };
        let mut subst = Vec::new();
        let mut missing = false;
        let mut next_positional = 0;
        for (k, (name, default)) in m.params.iter().enumerate() {
            if m.vararg && k + 1 == m.params.len() {
                // The rest of the arguments as written, commas and all.
                let rest = pieces.get(next_positional..).unwrap_or(&[]).join(",");
                let rest = rest.trim().to_string();
                let value = if rest.is_empty() {
                    default.clone().unwrap_or_default()
                } else {
                    rest
                };
                subst.push((name.clone(), value));
                continue;
            }
            let named = given.iter().find_map(|g| {
                g.split_once('=')
                    .filter(|(n, _)| n.trim() == name)
                    .map(|(_, v)| v.trim().to_string())
            });
            let positional = || {
                let g = given.get(next_positional).filter(|g| !g.contains('='))?;
                Some(g.clone())
            };
            let value = match named {
                Some(v) => Some(v),
                None => {
                    let p = positional();
                    if p.is_some() {
                        next_positional += 1;
                    }
                    p
                }
            }
            .filter(|v| !v.is_empty());
            if value.is_none() && m.required.contains(name) {
                missing = true;
                let col = match args.trim() {
                    "" => line.text.len() - line.text.trim_start().len() + 1,
                    a => line.text.find(a).map_or(1, |c| c + 1),
                };
                self.diag(
                    Severity::Error,
                    line,
                    col,
                    format!(
                        "Missing value for required parameter `{name}' of macro `{}'",
                        m.name
                    ),
                );
            }
            let value = value.or_else(|| default.clone()).unwrap_or_default();
            subst.push((name.clone(), value));
        }
        let mut body = Vec::new();
        if missing {
            return body; // macro.c expands nothing when a required argument is missing
        }
        for l in &m.body {
            if self.altmacro {
                // `LOCAL a, b`: each name a new label of its own per expansion.
                let t = strip_comment(&l.text);
                let t = t.trim();
                if t.len() > 6 && t.get(..6).is_some_and(|w| w.eq_ignore_ascii_case("local ")) {
                    for name in t[6..].split(',').map(str::trim).filter(|n| !n.is_empty()) {
                        if subst.iter().any(|(s, _)| s == name) {
                            // macro.c: a LOCAL name must be new to the expansion.
                            self.diag(
                                Severity::Error,
                                l,
                                1,
                                format!(
                                    "`{name}' was already used as parameter (or another local) name"
                                ),
                            );
                            continue;
                        }
                        self.local_counter += 1;
                        subst.push((name.to_string(), format!(".LL{:04x}", self.local_counter)));
                    }
                    continue;
                }
            }
            let text = substitute(&l.text, &subst, Some(&counter));
            let text = if self.altmacro {
                substitute_bare(&text, &subst)
            } else {
                text
            };
            body.push(Line {
                text,
                file: line.file.clone(),
                line: line.line,
            });
        }
        body
    }

    /// A `.sched` block's lines with its conditionals resolved and its macro calls expanded
    /// (the scheduler sees only instructions, labels and `.irp`), so that one macro can serve
    /// several blocks and a block can differ by a symbol. Conditionals are resolved before
    /// the block's `.irp`, so they cannot test its parameters.
    pub(super) fn sched_macros(&mut self, body: &[Line], depth: usize) -> Vec<Line> {
        let mut out = Vec::new();
        // Per open conditional: (this branch is assembled, some branch was taken).
        let mut cond: Vec<(bool, bool)> = Vec::new();
        for l in body {
            let text = strip_comment(&l.text);
            let text = text.trim();
            let (word, args) = match text.find(char::is_whitespace) {
                Some(p) => (&text[..p], text[p..].trim()),
                None => (text, ""),
            };
            let word_lower = word.to_ascii_lowercase();
            if self.conditional(&mut cond, &word_lower, args, l) {
                continue;
            }
            if !cond.iter().all(|c| c.0) {
                continue;
            }
            match self.macros.get(&word_lower).cloned() {
                Some(m) if depth < 16 => {
                    let lines = self.macro_lines(&m, args, l);
                    out.extend(self.sched_macros(&lines, depth + 1));
                }
                _ => out.push(l.clone()),
            }
        }
        if !cond.is_empty() {
            if let Some(l) = body.last() {
                self.diag(Severity::Error, l, 1, "missing .endif in the .sched block");
            }
        }
        out
    }
}

/// A block's body (the lines from `start` to its `.endm`/`.endr`) and the index after that
/// end (one past the lines when the block is never closed).
pub(super) fn collect_block(lines: &[Line], start: usize) -> (Vec<Line>, usize) {
    let no_macros = HashMap::new();
    let word = |l: &Line| {
        let text = strip_comment(&l.text);
        block_word(text.split_whitespace().next().unwrap_or(""), &no_macros)
    };
    match block_end(lines, start, word) {
        Some(end) => (lines[start..end].to_vec(), end + 1),
        None => (lines[start..].to_vec(), lines.len() + 1),
    }
}
