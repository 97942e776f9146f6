//! Why a scene file could not be loaded, precise enough to fix the file: every error names
//! the file, the line where the format is textual, and the reason.

use std::fmt;
use std::path::{Path, PathBuf};

/// A failed scene load. Loading never panics on bad input; it returns one of these.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadError {
    pub path: PathBuf,
    /// 1-based line number for text formats, `None` for binary data or whole-file problems.
    pub line: Option<usize>,
    pub reason: String,
}

impl LoadError {
    pub fn new(path: &Path, line: Option<usize>, reason: impl Into<String>) -> Self {
        LoadError {
            path: path.to_path_buf(),
            line,
            reason: reason.into(),
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.path.display(), line, self.reason),
            None => write!(f, "{}: {}", self.path.display(), self.reason),
        }
    }
}

impl std::error::Error for LoadError {}
