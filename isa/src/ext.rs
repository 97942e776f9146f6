//! The ISA extensions the paper proposes (section 9.5), off by default: several branch hints
//! outstanding at once (`multihint`), and a gather load (`gather`).
//!
//! An extension's instructions are rows of the one table ([`crate::for_each_op!`]) tagged
//! with their [`Extension`]; [`Extensions`] is the set a tool runs or assembles with.
//! With the set empty every encoding, semantic and cycle is the real SPU's: an extension's
//! words then decode as no operation ([`crate::codec::decode`]). `docs/extensions.md`
//! states and justifies each choice.

use std::fmt;

/// One extension, as a table row's tag names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Extension {
    /// A branch target buffer of several entries (no new instruction).
    MultiHint,
    /// `lgw`/`lgwx`: load the four words whose addresses are a register's four word slots.
    Gather,
}

impl Extension {
    /// The name the options and the `.spu_ext` directive use.
    pub const fn name(self) -> &'static str {
        match self {
            Extension::MultiHint => "multihint",
            Extension::Gather => "gather",
        }
    }
}

/// Local-store reads a gather load makes: one per word slot, one per cycle on the
/// single-ported local store.
pub const GATHER_LS_CYCLES: u32 = 4;

/// Cycles from a gather's issue until its result may be used: the last of its four reads
/// starts 3 cycles after the issue and takes the 6-cycle load pipeline.
pub const GATHER_LATENCY: u32 = GATHER_LS_CYCLES - 1 + 6;

/// The largest branch target buffer `multihint` allows.
pub const MAX_HINT_ENTRIES: u8 = 8;

/// The entries `multihint` gives when no number follows it.
pub const DEFAULT_HINT_ENTRIES: u8 = 4;

/// A set of enabled extensions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Extensions {
    /// Entries of the branch target buffer (1: the real SPU's one hint, `multihint` off).
    pub hint_entries: u8,
    /// The gather load instructions decode and run.
    pub gather: bool,
}

impl Default for Extensions {
    fn default() -> Self {
        Extensions::NONE
    }
}

impl Extensions {
    /// The real SPU: every extension off.
    pub const NONE: Extensions = Extensions {
        hint_entries: 1,
        gather: false,
    };

    /// Every extension on (tools that read any extension's instruction: `spu timing`).
    pub const ALL: Extensions = Extensions {
        hint_entries: DEFAULT_HINT_ENTRIES,
        gather: true,
    };

    /// Whether `ext` is on.
    pub const fn enables(self, ext: Extension) -> bool {
        match ext {
            Extension::MultiHint => self.hint_entries > 1,
            Extension::Gather => self.gather,
        }
    }

    /// Whether every extension is off.
    pub const fn is_none(self) -> bool {
        self.hint_entries == 1 && !self.gather
    }

    /// Adds the extensions of `list`: comma-separated `multihint[=N]` (N entries, 1 to 8;
    /// 4 without a number), `gather`, or `none` (which turns everything off).
    pub fn add(&mut self, list: &str) -> Result<(), String> {
        for item in list.split(',').map(str::trim) {
            let (name, value) = match item.split_once('=') {
                Some((n, v)) => (n.trim(), Some(v.trim())),
                None => (item, None),
            };
            match (name, value) {
                ("none", None) => *self = Extensions::NONE,
                ("gather", None) => self.gather = true,
                ("multihint", None) => self.hint_entries = DEFAULT_HINT_ENTRIES,
                ("multihint", Some(v)) => match v.parse::<u8>() {
                    Ok(n) if (1..=MAX_HINT_ENTRIES).contains(&n) => self.hint_entries = n,
                    _ => {
                        return Err(format!(
                        "multihint={v}: the number of hint entries must be 1 to {MAX_HINT_ENTRIES}"
                    ))
                    }
                },
                ("", None) => return Err("an empty extension name".into()),
                _ => {
                    return Err(format!(
                        "unknown extension `{item}` (known: multihint[=N], gather, none)"
                    ))
                }
            }
        }
        Ok(())
    }

    /// Parses a list as [`Extensions::add`] reads it, from every extension off.
    pub fn parse(list: &str) -> Result<Extensions, String> {
        let mut e = Extensions::NONE;
        e.add(list)?;
        Ok(e)
    }
}

impl fmt::Display for Extensions {
    /// The list [`Extensions::parse`] reads back (`none` when every extension is off).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        if self.hint_entries > 1 {
            parts.push(format!("multihint={}", self.hint_entries));
        }
        if self.gather {
            parts.push("gather".to_string());
        }
        if parts.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&parts.join(","))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_and_print_back() {
        assert_eq!(Extensions::parse("none").unwrap(), Extensions::NONE);
        let e = Extensions::parse("multihint=8, gather").unwrap();
        assert_eq!((e.hint_entries, e.gather), (8, true));
        assert_eq!(e.to_string(), "multihint=8,gather");
        assert_eq!(Extensions::parse("multihint").unwrap().hint_entries, 4);
        assert!(!Extensions::parse("multihint=1")
            .unwrap()
            .enables(Extension::MultiHint));
        assert_eq!(Extensions::parse(&e.to_string()).unwrap(), e);
        assert_eq!(Extensions::NONE.to_string(), "none");
        assert!(Extensions::parse("multihint=9")
            .unwrap_err()
            .contains("1 to 8"));
        assert!(Extensions::parse("multihint=0").is_err());
        assert!(Extensions::parse("scatter")
            .unwrap_err()
            .contains("unknown extension `scatter`"));
        assert!(Extensions::parse("gather,").is_err());
    }
}
