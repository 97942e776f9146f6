//! Diagnostics (gas's `messages.c`): errors and warnings with file, line and column, one
//! line each in GNU's form with the column added (`file:line:column: error: message`);
//! reported once each, at most `MAX_DIAGNOSTICS` in full, and sorted by place when the
//! assembly fails.

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

/// An error or warning, with the source line it points into (for callers that show it).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Diagnostic {
    pub severity: Severity,
    pub location: Location,
    pub message: String,
    pub source_line: String,
}

impl std::fmt::Display for Diagnostic {
    /// GNU as 2.40 prints `FILE:LINE: Error: MSG`; this is the same single line with the
    /// column after the line and the severity in lower case, as GCC and Clang write it, so
    /// that editors and scripts that parse compiler output read it unchanged. A report about
    /// a whole file (line 0) names the file alone.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let l = &self.location;
        let kind = match self.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
        };
        match (l.file.is_empty(), l.line) {
            (true, _) => write!(f, "{kind}: {}", self.message),
            (false, 0) => write!(f, "{}: {kind}: {}", l.file, self.message),
            (false, line) => write!(
                f,
                "{}:{line}:{}: {kind}: {}",
                l.file,
                l.column.max(1),
                self.message
            ),
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
