//! Macros and repetitions (gas's `macro.c` as `read.c` drives it): `.macro` definitions
//! and their expansion with arguments, `.rept`, `.irp` and `.irpc`, and the expansion of a
//! `.sched` block's macro calls before it is scheduled. The text handling (arguments,
//! substitution) is `crate::expand`, shared with `spu sched`.

use super::read::block_word;
use super::{Assembler, Severity, MAX_EXPANDED};
use crate::expand::{block_end, irp_values, macro_argument, substitute};
use crate::lex::{split_top, strip_comment, Line};
use std::collections::HashMap;

/// A `.macro`: its parameters (with defaults) and its body.
#[derive(Clone, Debug)]
pub(super) struct Macro {
    pub(super) params: Vec<(String, Option<String>)>,
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
                let (var, values) = irp_values(kind == ".irpc", args);
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
                let mut it = args.splitn(2, |c: char| c.is_whitespace() || c == ',');
                let name = it.next().unwrap_or("").to_string();
                let params = it
                    .next()
                    .unwrap_or("")
                    .split(|c: char| c == ',' || c.is_whitespace())
                    .filter(|s| !s.is_empty())
                    .map(|p| match p.split_once('=') {
                        Some((n, d)) => (n.trim().to_string(), Some(d.trim().to_string())),
                        None => (p.trim().to_string(), None),
                    })
                    .collect();
                self.macros
                    .insert(name.to_ascii_lowercase(), Macro { params, body });
            }
        }
    }

    pub(super) fn expand_macro(&mut self, m: &Macro, args: &str, line: &Line) {
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
        let given: Vec<String> = if args.trim().is_empty() {
            vec![]
        } else {
            split_top(args, ',')
                .iter()
                .map(|s| macro_argument(s.trim()))
                .collect()
        };
        let mut subst = Vec::new();
        let mut positional = given.iter();
        for (name, default) in &m.params {
            let named = given.iter().find_map(|g| {
                g.split_once('=')
                    .filter(|(n, _)| n.trim() == name)
                    .map(|(_, v)| v.trim().to_string())
            });
            let value = named
                .or_else(|| positional.next().filter(|g| !g.contains('=')).cloned())
                .or_else(|| default.clone())
                .unwrap_or_default();
            subst.push((name.clone(), value));
        }
        let mut body = Vec::new();
        for l in &m.body {
            body.push(Line {
                text: substitute(&l.text, &subst, Some(&counter)),
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
