//! Diagnostics (gas's `messages.c`): errors and warnings with file, line and column, shown
//! GNU-style with the source line and a caret; reported once each, at most
//! `MAX_DIAGNOSTICS` in full, and sorted by place when the assembly fails.

use super::Assembler;
use crate::lex::{display_text, Line};

/// Where a diagnostic points.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    pub file: String,
    pub line: usize,
    pub column: usize,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Severity {
    Error,
    Warning,
}

/// An error or warning with its source line, shown GNU-style with a caret.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    pub location: Location,
    pub message: String,
    pub source_line: String,
}

impl std::fmt::Display for Diagnostic {
    /// Rendered by codespan-reporting: the message, `file:line:column`, the line and a caret.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        use codespan_reporting::diagnostic as cd;
        use codespan_reporting::files::SimpleFile;
        use codespan_reporting::term;
        let l = &self.location;
        let plain = |f: &mut std::fmt::Formatter<'_>| {
            let kind = if self.severity == Severity::Error {
                "error"
            } else {
                "warning"
            };
            write!(
                f,
                "{}:{}:{}: {kind}: {}",
                l.file, l.line, l.column, self.message
            )
        };
        if l.line == 0 {
            return plain(f);
        }
        // A file whose line `l.line` is the source line, so the report shows the real number.
        let prefix = "\n".repeat(l.line - 1);
        let text = format!("{prefix}{}\n", self.source_line);
        let start = prefix.len() + l.column.saturating_sub(1).min(self.source_line.len());
        let end = (start + 1)
            .min(prefix.len() + self.source_line.len())
            .max(start);
        let file = SimpleFile::new(l.file.clone(), text);
        let diagnostic = match self.severity {
            Severity::Error => cd::Diagnostic::error(),
            Severity::Warning => cd::Diagnostic::warning(),
        }
        .with_message(self.message.clone())
        .with_labels(vec![cd::Label::primary((), start..end)]);
        let config = term::Config {
            chars: term::Chars::ascii(),
            ..Default::default()
        };
        match term::emit_into_string(&config, &file, &diagnostic) {
            Ok(text) => write!(f, "{}", text.trim_end()),
            Err(_) => plain(f),
        }
    }
}

/// Diagnostics reported in full; more are counted ("and N more").
const MAX_DIAGNOSTICS: usize = 100;

impl Assembler<'_> {
    pub(super) fn diag(
        &mut self,
        sev: Severity,
        line: &Line,
        column: usize,
        message: impl Into<String>,
    ) {
        if self.pass == 2 || sev == Severity::Error {
            let d = Diagnostic {
                severity: sev,
                location: Location {
                    file: line.file.clone(),
                    line: line.line,
                    column: column.max(1),
                },
                message: message.into(),
                source_line: display_text(&line.text),
            };
            let key = (
                d.location.file.clone(),
                d.location.line,
                d.location.column,
                d.message.clone(),
            );
            if self.seen_diags.insert(key) {
                if self.diags.len() < MAX_DIAGNOSTICS {
                    self.diags.push(d);
                } else {
                    self.dropped_diags += 1;
                }
            }
        }
    }

    /// Errors (and warnings) sorted by place, with the count of those left out.
    pub(super) fn take_diagnostics(&mut self) -> (Vec<Diagnostic>, Vec<Diagnostic>) {
        let diags = std::mem::take(&mut self.diags);
        let (mut errors, warnings): (Vec<_>, Vec<_>) = diags
            .into_iter()
            .partition(|d| d.severity == Severity::Error);
        if !errors.is_empty() {
            errors.extend(warnings.iter().cloned());
            errors.sort_by(|a, b| {
                (&a.location.file, a.location.line, a.location.column).cmp(&(
                    &b.location.file,
                    b.location.line,
                    b.location.column,
                ))
            });
        }
        if self.dropped_diags > 0 {
            let last = errors
                .last()
                .or(warnings.last())
                .map(|d| d.location.clone());
            let note = Diagnostic {
                severity: if errors.is_empty() {
                    Severity::Warning
                } else {
                    Severity::Error
                },
                location: last.unwrap_or(Location {
                    file: String::new(),
                    line: 0,
                    column: 0,
                }),
                message: format!("and {} more diagnostics", self.dropped_diags),
                source_line: String::new(),
            };
            errors.push(note);
            if errors.iter().all(|d| d.severity == Severity::Warning) {
                let w = errors;
                return (Vec::new(), w);
            }
        }
        (errors, warnings)
    }
}
