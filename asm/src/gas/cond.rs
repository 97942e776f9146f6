//! Conditional assembly (gas's `cond.c`): `.if`, `.ifdef`/`.ifndef`/`.ifnotdef`,
//! `.ifeq`/`.ifne`/`.ifge`/`.ifgt`/`.ifle`/`.iflt`, `.ifc`/`.ifnc`, `.ifeqs`/`.ifnes`,
//! `.ifb`/`.ifnb`, `.elseif`, `.else`, `.endif`, tracked per list of lines (a file, a
//! macro body, a repetition, a `.sched` block) even where the lines around are skipped.
//! An unknown `.if...` is an error that still opens a level, so its `.endif` closes it
//! instead of cascading into errors about unrelated lines.

use super::{Assembler, Severity};
use crate::lex::{split_top, unquote, Line};

/// The conditionals gas knows (cond.c's, as read.c's table names them).
pub(super) const CONDITIONALS: &[&str] = &[
    ".if",
    ".ifdef",
    ".ifndef",
    ".ifnotdef",
    ".ifeq",
    ".ifne",
    ".ifge",
    ".ifgt",
    ".ifle",
    ".iflt",
    ".ifc",
    ".ifnc",
    ".ifeqs",
    ".ifnes",
    ".ifb",
    ".ifnb",
];

impl Assembler<'_> {
    /// Whether the condition of `.if*` directive `kind` with operands `args` holds.
    pub(super) fn condition(&mut self, kind: &str, args: &str, line: &Line) -> bool {
        match kind {
            ".ifdef" => self.symbols.contains_key(args.trim()),
            ".ifndef" | ".ifnotdef" => !self.symbols.contains_key(args.trim()),
            // cond.c s_ifb: whether the rest of the line is blank.
            ".ifb" => args.trim().is_empty(),
            ".ifnb" => !args.trim().is_empty(),
            ".ifeqs" | ".ifnes" => {
                // cond.c s_ifeqs: two double-quoted strings, compared after escapes.
                let parts = split_top(args, ',');
                let strings: Vec<Option<Vec<u8>>> =
                    parts.iter().map(|p| unquote(p.trim())).collect();
                match strings.as_slice() {
                    [Some(a), Some(b)] => (a == b) == (kind == ".ifeqs"),
                    _ => {
                        let col = line.text.find(args).map_or(1, |c| c + 1);
                        self.diag(
                            Severity::Error,
                            line,
                            col,
                            format!("{kind} needs two quoted strings: expected \"A\",\"B\""),
                        );
                        false
                    }
                }
            }
            ".ifc" | ".ifnc" => {
                let parts = split_top(args, ',');
                let eq = parts.first().map(|s| s.trim().trim_matches('\''))
                    == parts.get(1).map(|s| s.trim().trim_matches('\''));
                eq == (kind == ".ifc")
            }
            _ => match self.eval(args) {
                Ok((v, _)) => match kind {
                    ".ifeq" => v == 0,
                    ".ifge" => v >= 0,
                    ".ifgt" => v > 0,
                    ".ifle" => v <= 0,
                    ".iflt" => v < 0,
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
            w if CONDITIONALS.contains(&w) => {
                let value = cond.iter().all(|c| c.0) && self.condition(word, args, line);
                cond.push((value, value));
            }
            w if w.starts_with(".if") && w[3..].chars().all(|c| c.is_ascii_alphanumeric()) => {
                let active = cond.iter().all(|c| c.0);
                if active {
                    let col = line.text.find(w).map_or(1, |c| c + 1);
                    self.diag(
                        Severity::Error,
                        line,
                        col,
                        format!("unknown pseudo-op: `{w}`"),
                    );
                }
                // Its lines are assembled (as gas goes on after an unknown pseudo-op) and
                // its `.else`/`.endif` are its own.
                cond.push((active, true));
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
            // `.endc`: read.c's other name for `.endif`.
            ".endif" | ".endc" => {
                if cond.pop().is_none() {
                    self.diag(Severity::Error, line, 1, ".endif without .if");
                }
            }
            _ => return false,
        }
        true
    }
}
