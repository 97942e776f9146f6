//! Conditional assembly (gas's `cond.c`): `.if`, `.ifdef`, `.ifndef`, `.ifeq`, `.ifne`,
//! `.ifc`, `.ifnc`, `.elseif`, `.else`, `.endif`, tracked per list of lines (a file, a
//! macro body, a repetition, a `.sched` block) even where the lines around are skipped.

use super::{Assembler, Severity};
use crate::lex::{split_top, Line};

impl Assembler<'_> {
    /// Whether the condition of `.if*` directive `kind` with operands `args` holds.
    pub(super) fn condition(&mut self, kind: &str, args: &str, line: &Line) -> bool {
        match kind {
            ".ifdef" => self.symbols.contains_key(args.trim()),
            ".ifndef" => !self.symbols.contains_key(args.trim()),
            ".ifc" | ".ifnc" => {
                let parts = split_top(args, ',');
                let eq = parts.first().map(|s| s.trim().trim_matches('\''))
                    == parts.get(1).map(|s| s.trim().trim_matches('\''));
                eq == (kind == ".ifc")
            }
            _ => match self.eval(args) {
                Ok((v, _)) => match kind {
                    ".ifeq" => v == 0,
                    _ => v != 0,
                },
                Err((col, m)) => {
                    self.diag(Severity::Error, line, col + 1, m);
                    false
                }
            },
        }
    }

    /// Applies `word` to the open conditionals `cond` (per level: this branch is assembled,
    /// some branch was taken) if it is `.if*`, `.elseif`, `.else` or `.endif`; whether it
    /// was one.
    pub(super) fn conditional(
        &mut self,
        cond: &mut Vec<(bool, bool)>,
        word: &str,
        args: &str,
        line: &Line,
    ) -> bool {
        let outer = cond.len() < 2 || cond[..cond.len() - 1].iter().all(|c| c.0);
        match word {
            ".if" | ".ifdef" | ".ifndef" | ".ifeq" | ".ifne" | ".ifc" | ".ifnc" => {
                let value = cond.iter().all(|c| c.0) && self.condition(word, args, line);
                cond.push((value, value));
            }
            ".elseif" => {
                if let Some((_, taken)) = cond.last().copied() {
                    let v = !taken && outer && self.condition(".if", args, line);
                    cond.pop();
                    cond.push((v, taken || v));
                }
            }
            ".else" => match cond.last_mut() {
                Some(top) => *top = (!top.1 && outer, true),
                None => self.diag(Severity::Error, line, 1, ".else without .if"),
            },
            ".endif" => {
                if cond.pop().is_none() {
                    self.diag(Severity::Error, line, 1, ".endif without .if");
                }
            }
            _ => return false,
        }
        true
    }
}
