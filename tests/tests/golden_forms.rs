//! `tests/golden/forms.tsv`: one row per assembler form of the instruction table
//! (`word<TAB>source<TAB>objdump text[<TAB>pc]`). The decoder must print the objdump text
//! for the word, and the assembler must produce the word from the source.
//!
//! `GOLDEN_REGEN=1 cargo test -p spu-tests --test golden_forms` rewrites the file from the
//! current encoder and disassembler; every row was then checked by hand against the
//! field layouts of the SPU ISA and objdump's output conventions.

use spu_isa::codec::{all_forms, encode};
use spu_isa::disasm::{instruction_text, NoSymbols};
use spu_isa::table::{FormInfo, OperandKind};

const PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/golden/forms.tsv");

struct Row {
    word: u32,
    source: String,
    text: String,
    pc: u32,
}

fn rows() -> Vec<Row> {
    let text = std::fs::read_to_string(PATH).expect("tests/golden/forms.tsv");
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let cols: Vec<&str> = l.split('\t').collect();
            assert!(cols.len() >= 3, "bad row: {l:?}");
            Row {
                word: u32::from_str_radix(cols[0], 16).unwrap(),
                source: cols[1].to_string(),
                text: cols[2].replace("\\t", "\t"),
                pc: cols.get(3).map(|p| u32::from_str_radix(p.trim_start_matches("0x"), 16).unwrap()).unwrap_or(0),
            }
        })
        .collect()
}

/// Representative operands of a form: (source text, value for the encoder), and the pc.
fn sample(form: &FormInfo) -> (String, Vec<i64>, u32) {
    use OperandKind::*;
    let branchy = form.operands.iter().any(|k| matches!(k, Rel18 | BrInst));
    let pc = if branchy { 0x100 } else { 0 };
    let mut src: Vec<String> = Vec::new();
    let mut vals = Vec::new();
    let mut regs = [3i64, 4, 5, 6].into_iter();
    for k in form.operands {
        let (s, v) = match k {
            Rt | Ra | Rb | Rc => {
                let r = regs.next().unwrap();
                (format!("${r}"), r)
            }
            Ch => ("$ch21".into(), 21),
            Spr => ("$sp5".into(), 5),
            S7 => ("-5".into(), -5),
            S6 => ("-3".into(), -3),
            S3 => ("-2".into(), -2),
            S7n => ("7".into(), 7),
            U3 => ("5".into(), 5),
            U5 => ("12".into(), 12),
            U6 => ("20".into(), 20),
            U7 => ("100".into(), 100),
            Scale173 | Scale155 => ("10".into(), 10),
            S10 => ("-100".into(), -100),
            S10b => ("100".into(), 100),
            Off14 => ("48".into(), 48),
            ParenRa => ("($4)".into(), 4),
            S16 => ("-1000".into(), -1000),
            X16 => ("0xabcd".into(), 0xabcd),
            U18 => ("0x12345".into(), 0x12345),
            Abs18 => ("0x2000".into(), 0x2000),
            Rel18 => ("0x180".into(), 0x180),
            BrInst => ("0x108".into(), 0x108),
            U14 => ("0x1234".into(), 0x1234),
        };
        src.push(s);
        vals.push(v);
    }
    // `32($4)` is written without a comma between the offset and the base.
    let mut text = String::new();
    for (i, s) in src.iter().enumerate() {
        if i > 0 && !s.starts_with('(') {
            text.push_str(", ");
        }
        text.push_str(s);
    }
    let source = if text.is_empty() {
        form.mnemonic.to_string()
    } else {
        format!("{} {text}", form.mnemonic)
    };
    (source, vals, pc)
}

#[test]
fn regenerate_when_asked() {
    if std::env::var_os("GOLDEN_REGEN").is_none() {
        return;
    }
    let mut out = String::from("# word\tsource\tobjdump text (\\t = tab)\tpc (hex, when not 0)\n");
    for form in all_forms() {
        let (source, vals, pc) = sample(form);
        let word = encode(form, &vals, pc);
        let text = instruction_text(word, pc, &NoSymbols).replace('\t', "\\t");
        out.push_str(&format!("{word:08x}\t{source}\t{text}"));
        if pc != 0 {
            out.push_str(&format!("\t{pc:x}"));
        }
        out.push('\n');
    }
    std::fs::write(PATH, out).unwrap();
}

#[test]
fn one_row_per_form() {
    assert_eq!(rows().len(), all_forms().len());
    for (row, form) in rows().iter().zip(all_forms()) {
        let m = row.source.split_whitespace().next().unwrap();
        assert_eq!(m, form.mnemonic, "rows follow the table order");
    }
}

#[test]
fn decoder_prints_the_objdump_text() {
    let mut bad = Vec::new();
    for r in rows() {
        let got = instruction_text(r.word, r.pc, &NoSymbols);
        if got != r.text {
            bad.push(format!("{:08x} @{:x}: want {:?}, got {got:?}", r.word, r.pc, r.text));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn assembler_produces_the_word() {
    let mut bad = Vec::new();
    for r in rows() {
        let src = format!(".text\n.space {}\n{}\n", r.pc, r.source);
        match spu_asm::assemble(&src, "forms.s", &spu_asm::Options::default()) {
            Ok(out) => {
                let at = r.pc as usize;
                let w = out.image.get(at..at + 4).map(|b| u32::from_be_bytes(b.try_into().unwrap()));
                if w != Some(r.word) {
                    bad.push(format!("{}: want {:08x}, got {:x?}", r.source, r.word, w));
                }
                if !out.warnings.is_empty() {
                    bad.push(format!("{}: unexpected warnings {:?}", r.source, out.warnings));
                }
            }
            Err(e) => bad.push(format!("{}: {}", r.source, e[0])),
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
