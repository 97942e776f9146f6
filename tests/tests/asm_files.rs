//! Assembler tests written as `.s` files in `tests/asm/`, with expectations inline:
//!
//! - `insn ...   # => 40801503` — the bytes at the address of that line's (first)
//!   statement, as hex groups (`40801503` is a word, `ab` a byte, `abcd` two bytes);
//! - `# error: LINE:COL: substring` / `# warning: LINE:COL: substring` — a diagnostic at
//!   that line and column of this file whose message contains the substring.
//!
//! Every diagnostic must be expected, and every expected one must be reported.

use spu_asm::elf_check::layout_errors;
use spu_asm::{assemble_file, assemble_object_file, Options, Severity};
use std::path::Path;

struct Expected {
    severity: Severity,
    line: usize,
    column: usize,
    text: String,
}

fn check(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("asm").join(name);
    let source = std::fs::read_to_string(&path).expect("test file");
    let mut words: Vec<(usize, String, Vec<u8>)> = Vec::new();
    let mut diags: Vec<Expected> = Vec::new();
    let mut failures_early: Vec<String> = Vec::new();
    for (i, line) in source.lines().enumerate() {
        if let Some((code, hex)) = line.rsplit_once("# =>") {
            let mut bytes = Vec::new();
            for group in hex.split_whitespace() {
                assert!(
                    group.len() % 2 == 0,
                    "{name}:{}: odd hex group {group:?}",
                    i + 1
                );
                for k in (0..group.len()).step_by(2) {
                    bytes.push(u8::from_str_radix(&group[k..k + 2], 16).expect("hex"));
                }
            }
            words.push((i + 1, code.trim_end().to_string(), bytes));
        }
        for (tag, severity) in [
            ("# error:", Severity::Error),
            ("# warning:", Severity::Warning),
        ] {
            if let Some((_, rest)) = line.split_once(tag) {
                let mut parts = rest.trim().splitn(3, ':');
                let line_no = parts.next().unwrap().trim().parse().expect("line number");
                let column = parts.next().unwrap().trim().parse().expect("column");
                let text = parts.next().unwrap_or("").trim().to_string();
                diags.push(Expected {
                    severity,
                    line: line_no,
                    column,
                    text,
                });
            }
        }
    }
    // Every object and executable the file gives lies inside its own bytes.
    if let Ok((obj, _)) = assemble_object_file(&path, &Options::default()) {
        match obj.to_elf() {
            Ok(elf) => {
                for e in layout_errors(&elf) {
                    failures_early.push(format!("object: {e}"));
                }
            }
            Err(e) => failures_early.push(format!("object: {e}")),
        }
    }
    let result = assemble_file(&path, &Options::default());
    if let Ok(out) = &result {
        for e in layout_errors(&out.elf) {
            failures_early.push(format!("executable: {e}"));
        }
    }
    let (out, reported) = match result {
        Ok(out) => {
            let w = out.warnings.clone();
            (Some(out), w)
        }
        Err(d) => (None, d),
    };
    let mut failures = failures_early;
    // Diagnostics: each reported one must be expected and vice versa.
    let mut matched = vec![false; diags.len()];
    for d in &reported {
        let hit = diags.iter().enumerate().position(|(k, e)| {
            !matched[k]
                && e.severity == d.severity
                && e.line == d.location.line
                && e.column == d.location.column
                && d.location.file.ends_with(name)
                && d.message.contains(&e.text)
        });
        match hit {
            Some(k) => matched[k] = true,
            None => failures.push(format!(
                "unexpected {:?} {}:{}:{}: {}",
                d.severity, d.location.file, d.location.line, d.location.column, d.message
            )),
        }
    }
    for (k, e) in diags.iter().enumerate() {
        if !matched[k] {
            failures.push(format!(
                "missing {:?} {name}:{}:{}: {}",
                e.severity, e.line, e.column, e.text
            ));
        }
    }
    // Bytes at each statement's address, found through the listing (line, address, text).
    match &out {
        None if !words.is_empty() => failures.push("assembly failed; no bytes to check".into()),
        None => {}
        Some(out) => {
            for (line, code, want) in &words {
                // Listing lines: `LINE ADDRESS WORDS... SOURCE`; prefer the entry whose
                // source text is this line (an included file may use the same number).
                let entries: Vec<(usize, u32, &str)> = out
                    .listing
                    .lines()
                    .filter_map(|l| {
                        let mut f = l.split_whitespace();
                        let n: usize = f.next()?.parse().ok()?;
                        let a = u32::from_str_radix(f.next()?, 16).ok()?;
                        Some((n, a, l.get(49..).unwrap_or("").trim()))
                    })
                    .collect();
                let addr = entries
                    .iter()
                    .find(|e| e.0 == *line && e.2.starts_with(code.trim()))
                    .or_else(|| entries.iter().find(|e| e.0 == *line))
                    .map(|e| e.1);
                let Some(addr) = addr else {
                    failures.push(format!("{name}:{line}: no statement emitted bytes"));
                    continue;
                };
                let at = addr as usize;
                let got = out.image.get(at..at + want.len());
                if got != Some(&want[..]) {
                    failures.push(format!(
                        "{name}:{line}: at {addr:#x} got {}, want {}",
                        got.map_or("nothing".into(), hex),
                        hex(want)
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{name}:\n{}", failures.join("\n"));
}

fn hex(b: &[u8]) -> String {
    b.iter().map(|x| format!("{x:02x}")).collect()
}

macro_rules! asm_files {
    ($($test:ident => $file:literal,)*) => {
        $( #[test] fn $test() { check($file); } )*
    };
}

asm_files! {
    sections => "sections.s",
    data => "data.s",
    symbols => "symbols.s",
    macros => "macros.s",
    control => "control.s",
    expressions => "expr.s",
    include => "include.s",
    errors => "errors.s",
    gnu_directives => "gnu_directives.s",
    bad_input => "bad_input.s",
    gnu_warnings => "gnu_warnings.s",
    symbol_loops => "symbol_loops.s",
    gnu_directives2 => "gnu_directives2.s",
    gnu_directive_errors => "gnu_directive_errors.s",
    gnu_altmacro => "gnu_altmacro.s",
}
