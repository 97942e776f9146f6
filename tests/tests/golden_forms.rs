//! The golden corpus `tests/golden/forms.tsv`: every assembler form of the table, with
//! words derived by hand from the ISA field layout (README "Fields") and text as GNU
//! objdump prints it (binutils `opcodes/spu-dis.c`). Columns:
//! `pc<TAB>word<TAB>source<TAB>objdump text`. The same rows drive the decoder and the
//! assembler, and every form of `FORMS` must appear in them.

use spu_asm::{assemble, Options};
use spu_isa::disasm::{instruction_text, NoSymbols};
use spu_isa::table::{OperandKind, FORMS};

struct Row {
    line: usize,
    pc: u32,
    word: u32,
    source: String,
    text: String,
}

fn corpus() -> Vec<Row> {
    let text = include_str!("../golden/forms.tsv");
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.starts_with('#') || line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.splitn(4, '\t').collect();
        assert_eq!(
            cols.len(),
            4,
            "forms.tsv:{}: want 4 columns: {line:?}",
            i + 1
        );
        let pc = u32::from_str_radix(cols[0].trim_start_matches("0x"), 16)
            .unwrap_or_else(|e| panic!("forms.tsv:{}: bad pc: {e}", i + 1));
        let word = u32::from_str_radix(cols[1], 16)
            .unwrap_or_else(|e| panic!("forms.tsv:{}: bad word: {e}", i + 1));
        rows.push(Row {
            line: i + 1,
            pc,
            word,
            source: cols[2].to_string(),
            text: cols[3].to_string(),
        });
    }
    assert!(rows.len() >= 243, "the corpus has {} rows", rows.len());
    rows
}

#[test]
fn decoder_prints_every_row_as_objdump() {
    let mut failures = Vec::new();
    for r in corpus() {
        let got = instruction_text(r.word, r.pc, &NoSymbols);
        if got != r.text {
            failures.push(format!(
                "forms.tsv:{}: {:08x} at {:#x} ({}): got {got:?}, want {:?}",
                r.line, r.word, r.pc, r.source, r.text
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} rows differ:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn assembler_encodes_every_row() {
    let mut failures = Vec::new();
    for r in corpus() {
        // `base` names address 0, so `base+0x40` is an address (made PC-relative by
        // branches), as in GNU as; a bare constant would be the offset itself.
        // (No `.space 0`: GNU as warns that a zero count is ignored.)
        let space = if r.pc > 0 {
            format!("\t.space {}\n", r.pc)
        } else {
            String::new()
        };
        let source = format!("\t.text\nbase:\n{space}\t{}\n", r.source);
        // GNU as takes `nop` as its `.nop` pseudo-op (SPU gas reads pseudo-ops without the
        // dot): the operand is read and dropped, `nop $79` is 0x40200000 (checked against
        // spu-elf-as 2.40). The row's word is what the decoder reads as `nop $79`.
        let want = if r.source.starts_with("nop") {
            0x4020_0000
        } else {
            r.word
        };
        match assemble(&source, "row.s", &Options::default()) {
            Err(diags) => {
                let msgs: Vec<String> = diags.iter().map(|d| d.message.clone()).collect();
                failures.push(format!(
                    "forms.tsv:{}: {:?}: {}",
                    r.line,
                    r.source,
                    msgs.join("; ")
                ));
            }
            Ok(out) => {
                let at = r.pc as usize;
                let got = out
                    .image
                    .get(at..at + 4)
                    .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]));
                if got != Some(want) {
                    failures.push(format!(
                        "forms.tsv:{}: {:?} at {:#x}: got {}, want {:08x}",
                        r.line,
                        r.source,
                        r.pc,
                        got.map_or("nothing".to_string(), |w| format!("{w:08x}")),
                        want
                    ));
                }
                // gas warns (and still encodes) for shift counts of the wrong sign and
                // byte immediates outside -128..255; other warnings are failures.
                if let Some(w) = out
                    .warnings
                    .iter()
                    .find(|w| !w.message.starts_with("Constant expression"))
                {
                    failures.push(format!(
                        "forms.tsv:{}: {:?}: unexpected warning {}",
                        r.line, r.source, w.message
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} rows differ:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// The number of comma-separated operands of a source line.
fn operand_count(source: &str) -> usize {
    match source.split_once(char::is_whitespace) {
        Some((_, ops)) if !ops.trim().is_empty() => ops.split(',').count(),
        _ => 0,
    }
}

#[test]
fn corpus_covers_every_form() {
    let rows = corpus();
    // The extensions' forms (`docs/extensions.md`) are no GNU tool's.
    let real = || FORMS.iter().filter(|f| f.op.info().ext.is_none());
    assert_eq!(
        real().count(),
        243,
        "the table has 243 real assembler forms"
    );
    let mut missing = Vec::new();
    for form in real() {
        // `off14(ra)` and `u7(ra)` are one source operand but two kinds in the table.
        let parens = form
            .operands
            .iter()
            .filter(|k| matches!(k, OperandKind::ParenRa))
            .count();
        let want = form.operands.len() - parens;
        let found = rows.iter().any(|r| {
            r.source.split_whitespace().next() == Some(form.mnemonic)
                && operand_count(&r.source) == want
        });
        if !found {
            missing.push(format!("{} {:?}", form.mnemonic, form.operands));
        }
    }
    assert!(
        missing.is_empty(),
        "forms without a golden row:\n{}",
        missing.join("\n")
    );
}
