//! Objects from `spu as -c` against GNU as's (spu-elf-as 2.40): every `.s` of the project
//! (kernels, tests, examples) and a corpus of directive and expression forms generated
//! here, compared section by section, relocation by relocation, symbol by symbol (type,
//! size, binding, section, value) and `.debug_line` byte for byte; and `spu dis` against
//! `objdump -d` on the same objects. Where GNU binutils for spu-elf was not found when the
//! test was built, those tests are ignored, saying why (`build.rs` looks for it;
//! `scripts/build-spu-binutils.sh` builds it, and SPU_BINUTILS names its prefix when it
//! is not the script's default).
//!
//! Without binutils the generated corpus still earns its keep: every file of it must
//! assemble here into an object that lies inside its own bytes and reads back unchanged,
//! and every file cut short or mutated must assemble or be refused without a panic.

use spu_asm::elf_check::layout_errors;
use spu_asm::object::Object;
use spu_asm::{assemble_object, assemble_object_file, Options};
use spu_isa::table::OperandKind;
use std::path::{Path, PathBuf};

/// GNU as, as the build script found it.
#[cfg(has_binutils)]
const GNU_AS: &str = env!("SPU_ELF_AS");
#[cfg(not(has_binutils))]
const GNU_AS: &str = "";

/// Expressions of every operator and precedence level, constants only.
const CONSTANT_EXPRESSIONS: &[&str] = &[
    "0",
    "1",
    "-1",
    "0x7f",
    "0x80",
    "0xff",
    "0x7fff",
    "0xffff",
    "0x12345678",
    "0b1011",
    "017",
    "'a'",
    "1+2*3",
    "(1+2)*3",
    "1 + 2 & 3",
    "1 << 2 + 1",
    "2 + 3 == 5",
    "0 || 1 && 0",
    "1 ! 0",
    "-16 >> 28",
    "~0",
    "-(5)",
    "!0",
    "!7",
    "7 / 2",
    "-7 / 2",
    "7 % 3",
    "-7 % 3",
    "6 ^ 3",
    "6 | 9",
    "3 < 4",
    "4 <= 3",
    "3 > 4",
    "4 >= 4",
    "5 != 5",
    "5 <> 6",
    "1 << 31",
    "0x100 - 1",
    "((((1))))",
];

/// Expressions involving symbols and the location counter (`lab` and `ext` are defined
/// by the template: `lab` a label of `.data`, `ext` an undefined external).
const SYMBOL_EXPRESSIONS: &[&str] = &[
    "lab",
    "lab+4",
    "lab-4",
    "lab2-lab",
    ".-lab",
    "ext",
    "ext+8",
    "glob",
    "glob+2",
    "CONST",
    "CONST*2",
    "lab2-lab+CONST",
];

/// The data directives and their sizes.
const DATA: &[(&str, usize)] = &[
    (".byte", 1),
    (".2byte", 2),
    (".short", 2),
    (".hword", 2),
    (".half", 2),
    (".4byte", 4),
    (".long", 4),
    (".int", 4),
    (".word", 4),
    (".8byte", 8),
    (".quad", 8),
];

/// Sources of whole statements: alignment, sections, symbols, strings, blocks and
/// instructions, each a small file of its own.
const STATEMENTS: &[&str] = &[
    ".text\nnop\n.align 3\nnop\n",
    ".text\nnop\n.align 4\nlnop\n",
    ".text\nnop\n.p2align 5\nnop\n",
    ".text\nnop\n.balign 16\nnop\n",
    ".data\n.byte 1\n.align 2\n.byte 2\n",
    ".data\n.byte 1\n.p2align 3, 0xaa\n.byte 2\n",
    ".data\n.byte 1\n.balign 8, 0x55, 3\n.byte 2\n",
    ".data\n.short 1\n.balignw 8, 0x1234\n",
    ".data\n.long 1\n.balignl 16, 0xdeadbeef\n",
    ".data\n.byte 1, 2\n.p2alignw 3, 0x4142\n",
    ".section .rodata\n.long 1\n",
    ".section .text.hot,\"ax\",@progbits\nnop\n",
    ".section .data.rel,\"aw\",@progbits\n.long 5\n",
    ".section .bss\n.space 16\n",
    ".section .bss\n.p2align 4\nbuf: .space 100\n",
    ".section .tbss,\"awT\",@nobits\n.space 8\n",
    ".section .note.x,\"\",@note\n.long 4\n",
    ".section .comment\n.asciz \"x\"\n",
    ".pushsection .data\n.long 1\n.popsection\n.long 2\n",
    ".text\nnop\n.previous\n.data\n.long 3\n.previous\nnop\n",
    ".text 1\nnop\n.text 0\nlnop\n",
    ".data 2\n.byte 2\n.data 1\n.byte 1\n.data\n.byte 0\n",
    ".subsection 1\nnop\n.subsection 0\nlnop\n",
    ".globl f\n.type f, @function\nf: nop\n.size f, .-f\n",
    ".global o\n.type o, @object\n.data\no: .long 1\n.size o, 4\n",
    ".weak w\nw: nop\n",
    ".weak undef_w\n.text\nbrsl $0, undef_w\n",
    ".hidden h\n.globl h\nh: nop\n",
    ".protected p\n.globl p\np: nop\n",
    ".internal i\n.globl i\ni: nop\n",
    ".local l\nl: nop\n",
    ".comm c, 16, 16\n",
    ".comm c4, 4\n",
    ".lcomm lc, 32\n",
    ".data\n.ascii \"abc\"\n",
    ".data\n.asciz \"abc\"\n",
    ".data\n.string \"a\\tb\\n\"\n",
    ".data\n.ascii \"\\x41\\101\\\\\\\"\"\n",
    ".data\n.uleb128 0, 1, 127, 128, 624485\n",
    ".data\n.sleb128 0, -1, 63, 64, -64, -65, -123456\n",
    ".data\n.fill 3, 2, 0x1234\n",
    ".data\n.fill 2, 4, -1\n",
    ".data\n.space 5\n",
    ".data\n.skip 3, 0xee\n",
    ".data\n.zero 7\n",
    ".data\n.byte 1\n.org 8\n.byte 2\n",
    ".data\n.byte 1\n.org 8, 0xff\n.byte 2\n",
    ".data\n.byte 1\n. = 4\n.byte 2\n",
    ".data\n.float 1.5\n",
    ".data\n.double -2.25\n",
    ".data\n.single 0.1\n",
    ".set x, 5\n.data\n.long x\n.set x, x+1\n.long x\n",
    ".equ y, 3\n.data\n.byte y\n",
    "z = 7\n.data\n.byte z\n",
    ".data\n.long later\n.set later, 9\n",
    ".equiv e, 4\n.data\n.short e\n",
    ".eqv v, 2+2\n.data\n.byte v\n",
    ".data\n.rept 3\n.byte 7\n.endr\n",
    ".data\n.irp r, 1, 2, 3\n.byte \\r\n.endr\n",
    ".data\n.irpc c, 123\n.byte \\c\n.endr\n",
    ".macro m a, b=2\n.byte \\a, \\b\n.endm\n.data\nm 1\nm 3, 4\nm b=5, a=6\n",
    ".macro m a\n.byte \\a\n.exitm\n.byte 9\n.endm\n.data\nm 1\n",
    ".macro cnt\n.byte \\@\n.endm\n.data\ncnt\ncnt\n",
    ".macro sum first, rest:vararg\n.byte \\first\n.ifnb \\rest\nsum \\rest\n.endif\n.endm\n.data\nsum 1, 2, 3\n",
    ".macro r a:req\n.byte \\a\n.endm\n.data\nr 4\n.purgem r\n",
    ".data\n.if 1\n.byte 1\n.else\n.byte 2\n.endif\n",
    ".data\n.if 0\n.byte 1\n.elseif 1\n.byte 2\n.endif\n",
    ".data\n.ifdef nothing\n.byte 1\n.endif\n.ifndef nothing\n.byte 2\n.endif\n",
    ".data\n.ifc a, a\n.byte 1\n.endif\n.ifnc a, b\n.byte 2\n.endif\n",
    ".data\n.ifeqs \"a\", \"a\"\n.byte 1\n.endif\n.ifnes \"a\", \"b\"\n.byte 2\n.endif\n",
    ".data\n.ifb\n.byte 1\n.endif\n.ifnb x\n.byte 2\n.endif\n",
    ".data\n.ifge 0\n.byte 1\n.endif\n.iflt 0\n.byte 2\n.endif\n",
    ".struct 0\nfa: .space 4\nfb: .space 8\nfc:\n.data\n.long fa, fb, fc\n",
    ".text\n1: nop\nbr 1b\nbr 1f\n1: nop\n",
    ".text\nl0: nop\nbr l0\nbrsl $0, l0\nbrnz $3, l1\nl1: nop\n",
    ".text\nila $3, 0x3ffff\nilhu $3, 0x12345678@h\niohl $3, 0x12345678@l\n",
    ".text\nila $3, lab\n.data\nlab: .long 0\n",
    ".text\nilhu $3, lab@h\niohl $3, lab@l\n.data\nlab: .long 0\n",
    ".text\nbrsl $0, ext\n",
    ".text\nbra ext\n",
    ".text\nila $4, ext+16\n",
    ".text\nhbrr 1f, ext\nnop\n1: bi $0\n",
    ".globl g\n.text\ng: nop\nbr g\nbrsl $0, g\n",
    ".text\nbr .+8\nnop\nnop\n",
    ".text\nlqd $3, 32($1)\nstqd $3, -16($1)\nlqa $4, 0x100\nlqr $5, 1f\n1: nop\n",
    ".text\nai $3, $3, -512\nai $3, $3, 511\nandbi $3, $4, 0xff\n",
    ".text\nfma $7, $6, $5, $4\nshufb $3, $4, $5, $6\nselb $3, $4, $5, $6\n",
    ".text\nrdch $3, $ch0\nwrch $ch7, $3\nrchcnt $3, $ch29\n",
    ".text\nstop\nstop 0x3fff\nstopd $0, $0, $0\n",
    ".text\nhbr 1f, $0\nnop\n1: bi $0\n",
    ".text\n.reloc ., SPU_ADDR32, ext\n.long 0\n",
    ".data\n.reloc ., BFD_RELOC_32, ext\n.long 0\n.reloc 0, BFD_RELOC_NONE\n",
    ".file \"x.c\"\n.ident \"compiler\"\n.text\nnop\n",
    ".data\nlab: .long lab\n",
    ".data\n.long 1f - 0f\n0: .byte 1\n1:\n",
    "GLOBL gg\n.text\ngg: nop\n",
    ".data\n.byte 1 ; .byte 2 ; .byte 3\n",
    ".data\nlab: lab2: .byte 1\n",
    ".data\n/* comment */ .byte 1 # trailing\n",
    ".altmacro\n.macro m v, s\nLOCAL l\nl: .byte v\n.long l\n.endm\n.data\nm %3+4, <9>\n",
    ".globl f\n.text\nf: nop\n.symver f, f@V1\n",
    ".ident \"one\"\n.ident \"two\"\n.text\nnop\n",
    ".data\n.dc.l 1\n.dcb.b 2, 3\n.ds.w 1\n.octa 5\n",
    ".data\n.irep r, 1, 2\n.byte \\r\n.endr\n.rep 2\n.byte 0\n.endr\n",
    ".def dv, 7\n.data\n.byte dv\n",
    ".offset 4\nof: .space 4\n.data\n.long of\n",
];

/// The generated corpus: (name, source), hundreds of small files, each assembling here.
pub fn generated_corpus() -> Vec<(String, String)> {
    let mut corpus = Vec::new();
    // Every data directive with every constant expression (values wider than the
    // directive are left out: they warn, covered by tests/asm/gnu_warnings.s).
    for (d, size) in DATA {
        for (k, e) in CONSTANT_EXPRESSIONS.iter().enumerate() {
            corpus.push((
                format!("data_{}_{k}.s", d.trim_start_matches('.')),
                format!("\t.data\n\t{d} {e}, ({e})\n"),
            ));
        }
        let _ = size;
    }
    // Expressions with symbols in the 4-byte directives (the only SPU data relocation).
    for d in [".long", ".int", ".word", ".4byte"] {
        for (k, e) in SYMBOL_EXPRESSIONS.iter().enumerate() {
            corpus.push((
                format!("sym_{}_{k}.s", d.trim_start_matches('.')),
                format!(
                    "\t.globl glob\n\t.set CONST, 12\n\t.data\nlab:\t.long 0\nlab2:\t{d} {e}\nglob:\t.long 0\n"
                ),
            ));
        }
    }
    // Constant expressions as immediates of instructions of each immediate width.
    for (k, e) in CONSTANT_EXPRESSIONS.iter().enumerate() {
        corpus.push((
            format!("imm_{k}.s"),
            format!("\t.text\n\til $3, ({e}) & 0x7fff\n\tila $4, ({e}) & 0x3ffff\n\tandbi $5, $6, ({e}) & 0xff\n\tai $7, $7, ({e}) & 0x1ff\n"),
        ));
    }
    for (k, s) in STATEMENTS.iter().enumerate() {
        corpus.push((format!("stmt_{k}.s"), s.to_string()));
    }
    for (k, s) in LINE_TABLES.iter().enumerate() {
        corpus.push((format!("line_{k}.s"), s.to_string()));
    }
    corpus.extend(instruction_forms());
    corpus.extend(directive_forms());
    corpus
}

/// An operand of each kind, written as a GNU source would, with `target` for the
/// addresses (a label, an external symbol, a number).
fn operand(kind: OperandKind, target: &str) -> String {
    use OperandKind as K;
    match kind {
        K::Rt => "$3",
        K::Ra => "$4",
        K::Rb => "$5",
        K::Rc => "$6",
        K::Ch => "$ch9",
        K::Spr => "$2",
        K::S7 => "-5",
        K::S6 => "3",
        K::S3 => "-3",
        K::S7n => "5",
        K::U3 => "3",
        K::U5 => "7",
        K::U6 => "9",
        K::U7 => "100",
        K::Scale173 | K::Scale155 => "10",
        K::S10 => "-100",
        K::S10b => "0x7f",
        K::Off14 => "32",
        K::ParenRa => "($4)",
        K::S16 => "-1000",
        K::X16 => "0x1234",
        K::U18 => "0x3ffff",
        K::U14 => "0x123",
        K::BrInst => "1f",
        K::Abs18 | K::Rel18 => return target.to_string(),
    }
    .to_string()
}

/// Every instruction form of the real SPU, each in a file of its own: with its address
/// operands a label here, an external symbol and a number (the relocation decisions).
fn instruction_forms() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (k, f) in spu_isa::table::FORMS.iter().enumerate() {
        if f.op.info().ext.is_some() {
            continue;
        }
        let takes_address = f
            .operands
            .iter()
            .any(|o| o.is_address() && *o != OperandKind::BrInst);
        let targets: &[&str] = if takes_address {
            &["lab", "ext", "0x100", "glob+8"]
        } else {
            &["lab"]
        };
        for (t, target) in targets.iter().enumerate() {
            let mut text = String::new();
            for (i, o) in f.operands.iter().enumerate() {
                if i > 0 && *o != OperandKind::ParenRa {
                    text.push_str(", ");
                }
                text.push_str(&operand(*o, target));
            }
            out.push((
                format!("insn_{k}_{t}_{}.s", f.mnemonic),
                format!(
                    "\t.text\n\t.globl glob\nlab:\tnop\n\t{} {text}\n\tnop\n1:\tnop\nglob:\tlnop\n",
                    f.mnemonic
                ),
            ));
        }
    }
    // Immediates that relocate: the @h/@l halves, in and out of range, and an address
    // in every immediate width.
    for (k, insn) in [
        "ilhu $3, ext@h",
        "iohl $3, ext@l",
        "ilhu $3, lab@h",
        "iohl $3, lab@l",
        "il $3, ext",
        "il $3, lab",
        "ila $3, ext+4",
        "ila $3, lab-4",
        "ai $3, $3, ext",
        "ai $3, $3, lab",
        "andbi $3, $4, ext",
        "lqa $3, ext",
        "lqr $3, ext+16",
        "stqr $3, lab",
        "br ext",
        "brsl $0, lab+4",
        "brasl $0, ext",
        "hbra 1f, ext",
        "hbrr 1f, lab",
        "il $3, glob",
        "ila $3, glob",
        "br glob",
        "bra glob",
        "brsl $0, glob",
        "il $3, 0x8000",
        "ai $3, $3, 512",
        "il $3, lab2 - lab",
        "ila $3, lab2 - lab",
        "shli $3, $4, 40",
        "rotqbyi $3, $4, 200",
    ]
    .iter()
    .enumerate()
    {
        out.push((
            format!("reloc_{k}.s"),
            format!(
                "\t.text\n\t.globl glob\nlab:\tnop\n\t{insn}\n\tnop\n1:\tnop\nglob:\tlnop\nlab2:\n"
            ),
        ));
    }
    out
}

/// The GNU as directive set for SPU, form by form: data, symbols, sections, macros and
/// conditionals, `.struct`, expressions across sections, each a small file.
fn directive_forms() -> Vec<(String, String)> {
    let mut out: Vec<String> = Vec::new();
    // Strings and floating point.
    for d in [".ascii", ".asciz", ".string"] {
        for arg in [
            "\"\"",
            "\"abc\"",
            "\"a\", \"bc\"",
            "\"\\0\\377\\n\\t\\\\\"",
            "\"\\x41\\x4a\"",
        ] {
            out.push(format!("\t.data\n\t{d} {arg}\n"));
        }
    }
    for d in [".float", ".single", ".double", ".ffloat", ".dfloat"] {
        for v in [
            "0", "1", "-1.5", "3.14159", "1e10", "-2.5e-3", "0f1.5", "1, 2, 3",
        ] {
            out.push(format!("\t.data\n\t{d} {v}\n"));
        }
    }
    // Space, fill and alignment.
    for d in [
        ".space 3",
        ".skip 5, 0x11",
        ".zero 4",
        ".fill 2",
        ".fill 3, 1",
        ".fill 2, 3, 0x123456",
        ".fill 1, 8, -1",
        ".space 0",
        ".fill 0, 4, 1",
    ] {
        out.push(format!("\t.data\n\t.byte 9\n\t{d}\n\t.byte 8\n"));
    }
    for d in [".align", ".p2align", ".balign"] {
        for arg in [
            "0", "1", "2", "3", "4", "8", "16", "2, 0xff", "3, , 1", "3, , 7", "4, 0, 15",
        ] {
            out.push(format!("\t.data\n\t.byte 1\n\t{d} {arg}\n\t.byte 2\n"));
            out.push(format!("\t.text\n\tnop\n\t{d} {arg}\n\tnop\n"));
        }
    }
    for arg in ["4", "16", "4, 0x77", "lab + 6"] {
        out.push(format!("\t.data\nlab:\t.byte 1\n\t.org {arg}\n\t.byte 2\n"));
    }
    // Symbols: equates, bindings, visibility, types and sizes.
    for d in [".set", ".equ", ".equiv", ".eqv"] {
        for v in [
            "5",
            "lab",
            "lab + 4",
            "ext",
            "ext + 4",
            "lab2 - lab",
            ".",
            "CONST * 3",
        ] {
            out.push(format!(
                "\t.set CONST, 7\n\t.data\nlab:\t.long 1\nlab2:\t{d} sym, {v}\n\t.long sym\n"
            ));
            out.push(format!(
                "\t.set CONST, 7\n\t.data\nlab:\t.long 1\nlab2:\t{d} sym, {v}\n"
            ));
        }
    }
    for d in [
        ".global",
        ".globl",
        ".local",
        ".weak",
        ".hidden",
        ".protected",
        ".internal",
    ] {
        for place in [
            "\t.text\nsym:\tnop\n",
            "\t.data\nsym:\t.long sym\n",
            "\t.text\n\tbrsl $0, sym\n",
            "",
            "\t.set sym, 5\n",
        ] {
            out.push(format!("\t{d} sym\n{place}"));
            out.push(format!("{place}\t{d} sym\n"));
        }
    }
    for t in [
        "@function",
        "@object",
        "@notype",
        "%function",
        "STT_FUNC",
        "@tls_object",
        "@common",
        "function",
        "\"function\"",
    ] {
        out.push(format!(
            "\t.globl f\n\t.type f, {t}\n\t.text\nf:\tnop\n\t.size f, .-f\n"
        ));
        out.push(format!(
            "\t.type g, {t}\n\t.data\ng:\t.long 1\n\t.size g, 4\n"
        ));
    }
    for c in [
        ".comm c, 4",
        ".comm c, 16, 16",
        ".comm c, 1, 1",
        ".comm c, 100, 8",
        ".lcomm c, 4",
        ".lcomm c, 100",
        ".lcomm c, 3",
        ".bss c, 8, 16",
        ".bss c, 5, 1",
        ".bss c",
        ".bss c, 4",
        ".bss c, 4, 3",
        ".comm c, 4\n\t.comm c, 8",
    ] {
        out.push(format!("\t.data\n\t.long 0\n\t{c}\n\t.text\n\tila $3, c\n"));
    }
    for v in ["", ", local", ", hidden", ", remove"] {
        out.push(format!(
            "\t.globl f\n\t.text\nf:\tnop\n\t.symver f, f@VERS_1{v}\n"
        ));
        out.push(format!("\t.globl f\n\t.text\nf:\tnop\n\t.symver f, f@@VERS_2{v}\n\t.symver f, f@VERS_1\n\tbrsl $0, f\n"));
    }
    out.push("\t.symver ext, ext@VERS_3\n\t.text\n\tbrsl $0, ext\n".into());
    out.push("\t.symver ext, ext@@@VERS_3\n\t.text\n\tbrsl $0, ext\n".into());
    // Sections: flags, types, entry sizes, groups of subsections, the stack.
    for flags in [
        "", "a", "ax", "aw", "awx", "w", "x", "ams", "aMS", "e", "o", "?", "axG",
    ] {
        for ty in [
            "",
            ", @progbits",
            ", @nobits",
            ", %progbits",
            ", @note",
            ", @init_array",
            ", @fini_array",
            ", @preinit_array",
        ] {
            out.push(format!("\t.section .sec,\"{flags}\"{ty}\n\t.long 0\n"));
        }
    }
    for name in [
        ".text.f",
        ".data.x",
        ".bss.y",
        ".rodata.z",
        ".init",
        ".fini",
        ".ctors",
        ".dtors",
        ".tdata",
        ".tbss",
        ".sdata",
        ".note.gnu",
        ".debug_info",
        ".comment",
        ".toe",
        "._ea",
        ".ovl1",
        "\"quoted name\"",
        "my_sec",
    ] {
        out.push(format!("\t.section {name}\n\t.long 0\n"));
        out.push(format!(
            "\t.section {name}, \"aw\"\n\t.long 0\n\t.section {name}\n\t.long 1\n"
        ));
    }
    for text in [
        "\t.pushsection .a\n\t.long 1\n\t.pushsection .b\n\t.long 2\n\t.popsection\n\t.long 3\n\t.popsection\n\tnop\n",
        "\t.section .a\n\t.long 1\n\t.section .b\n\t.previous\n\t.long 2\n",
        "\t.text 2\n\tnop\n\t.text 1\n\tlnop\n\t.text\n\tstop\n",
        "\t.data 1\nb:\t.long 2\n\t.data 0\na:\t.long a, b\n",
        "\t.section .a, \"aw\"\n\t.subsection 1\n\t.long 1\n\t.subsection 0\n\t.long 0\n",
        "\t.sect .foo\n\t.long 1\n",
        "\t.popsection\n",
        "\t.section .a\nx:\t.long 1\n\t.section .b\ny:\t.long x - y\n",
        "\t.data\nx:\t.long 1\n\t.text\ny:\tnop\n\t.data\n\t.long y - x\n",
        "\t.data\nx:\t.long 1\ny:\t.long y - x, x - y, y - x + ext\n",
        "\t.data\n\t.long ext - .\n\t.long . - ext\n",
        // Differences made pc-relative (R_SPU_REL32), write.c's `fixup_segment`.
        "\t.data\n\t.long 0\n\t.long ext - .\n\t.long ext - . + 4\n",
        "\t.data\n\t.long 0\n\t.long ext - x\nx:\n",
        "\t.data\nx:\t.long 0\n\t.long -x, 3 - x, -x + 5, -(x), 0 - x\n",
        "\t.data\nx:\t.long 0\n\t.section .b\ny:\t.long 0\n\t.long x - y + 7, (x + 7) - (y + 2)\n",
        "\t.data\nx:\t.long 0\n\t.section .b\ny:\t.long 0\n\t.4byte x - y\n\t.int x - y\n\t.globl x\n",
        "\t.data\nx:\t.long 0\n\t.section .b\n\t.weak y\ny:\t.long 0\n\t.long x - y\n",
        "\t.data\nx:\t.long 0\n\t.text\n\t.long 0\n\t.long x - y\ny:\n",
        "\t.data\nx:\t.long 0\n\t.short -x\n",
        "\t.data\n\t.long 0\n\t.long -y\n\t.text\ny:\tnop\n",
        "\t.text\ny:\tnop\n\t.data\n\t.long 0\n\t.long x - y\nx:\n",
        // `nop` is gas's `.nop`: an expression, as many words as cover it.
        "\t.text\n\tnop 5\n\tnop $lr\n\tnop 1+2\n\tnop foo\n\tnop 9\n",
        // `.eqv NAME, .`: `.` where each use is, and where the source ends.
        "\t.data\n\t.long 1\n\t.eqv sym, .\n\t.long sym, sym\n\t.text\n\tnop\n",
        "\t.data\n\t.long 1\n\t.eqv sym, .\n\t.long 5\n\t.section .b\n\t.long 3\n\t.globl sym\n",
        // A character constant in a repetition or macro body holds no parameter.
        "\t.data\n\t.irp c, 1, 2\n\t.byte '\\c', \\c, '\\n'\n\t.endr\n",
        "\t.macro m a\n\t.byte '\\a', \\a, '\"'\n\t.ascii \"\\a'\"\n\t.endm\n\t.data\n\tm 7\n",
        // The header-only line table gas writes beside a source's own `.debug_info`.
        "\t.section .debug_info\n\t.long 0\n\t.text\n\tnop\n",
        "\t.section .debug_info\n\t.long 0\n\t.section .debug_line\n\t.long 7\n",
        "\t.section .debug_info\n\t.file 1 \"a.c\"\n\t.long 0\n",
        "\t.data\nx:\t.long ext2 - ext\n",
        "\t.text\nx:\tnop\n\t.data\n\t.long x + 4, x - 4, (x + 8) - 4\n",
        "\t.data\n\t.byte lab\nlab:\n",
        "\t.data\n\t.short lab\nlab:\n",
        "\t.data\n\t.quad lab\nlab:\n",
        "\t.data\n\t.quad ext\n",
    ] {
        out.push(text.to_string());
    }
    // Macros, repetitions and conditionals.
    for text in [
        "\t.macro m a, b=3\n\t.byte \\a, \\b\n\t.endm\n\t.data\n\tm 1\n\tm 1, 2\n\tm b=4, a=5\n",
        "\t.macro m a:req, b:vararg\n\t.byte \\a\n\t.byte \\b\n\t.endm\n\t.data\n\tm 1, 2, 3, 4\n",
        "\t.macro m\n\t.byte \\@\n\t.endm\n\t.data\n\tm\n\tm\n\tm\n",
        "\t.macro m n\n\t.if \\n\n\t.byte \\n\n\tm \\n-1\n\t.endif\n\t.endm\n\t.data\n\tm 5\n",
        "\t.macro m\n\tnop\n\t.endm\n\t.purgem m\n\t.macro m\n\tlnop\n\t.endm\n\t.text\n\tm\n",
        "\t.altmacro\n\t.macro m x\n\t.byte x\n\t.endm\n\t.data\n\tm %1+2\n\tm <3>\n",
        "\t.altmacro\n\t.macro m\n\tLOCAL a, b\na:\t.long b\nb:\t.long a\n\t.endm\n\t.data\n\tm\n\tm\n",
        "\t.macro m name\n\\name\\()_x:\t.long 0\n\t.endm\n\t.data\n\tm foo\n\tm bar\n",
        "\t.data\n\t.rept 0\n\t.byte 1\n\t.endr\n\t.rept 2\n\t.rept 2\n\t.byte 3\n\t.endr\n\t.endr\n",
        "\t.data\n\t.irp x, a, b, c\n\\x:\t.byte 1\n\t.endr\n",
        "\t.data\n\t.irp x\n\t.byte 1\n\t.endr\n",
        "\t.data\n\t.irpc c, abc\n\t.byte '\\c'\n\t.endr\n",
        "\t.data\n\t.ifdef undefined_thing\n\t.byte 1\n\t.else\n\t.byte 2\n\t.endif\n",
        "\t.data\nx:\n\t.ifdef x\n\t.byte 1\n\t.endif\n\t.ifndef x\n\t.byte 2\n\t.endif\n\t.ifnotdef y\n\t.byte 3\n\t.endif\n",
        "\t.data\n\t.if 1\n\t.if 0\n\t.byte 1\n\t.elseif 1\n\t.byte 2\n\t.else\n\t.byte 3\n\t.endif\n\t.endif\n",
        "\t.data\n\t.ifeq 0\n\t.byte 1\n\t.endif\n\t.ifne 0\n\t.byte 2\n\t.endif\n\t.ifgt 1\n\t.byte 3\n\t.endif\n\t.ifle 1\n\t.byte 4\n\t.endif\n",
        "\t.data\n\t.ifc \"a\",\"a\"\n\t.byte 1\n\t.endif\n\t.ifeqs \"ab\", \"ab\"\n\t.byte 2\n\t.endif\n\t.ifnes \"a\", \"a\"\n\t.byte 3\n\t.endif\n",
        "\t.data\n\t.ifb \n\t.byte 1\n\t.endif\n\t.ifnb ,\n\t.byte 2\n\t.endif\n",
        "\t.data\n\t.if 1\n\t.byte 1\n",
        "\t.data\n\t.endif\n",
        "\t.data\n\t.else\n",
        "\t.data\n\t.err\n",
        "\t.data\n\t.error \"stop here\"\n",
        "\t.data\n\t.warning \"careful\"\n\t.byte 1\n",
        "\t.data\n\t.print \"hello\"\n\t.byte 1\n",
        "\t.macro m\n\t.exitm\n\t.byte 1\n\t.endm\n\t.data\n\tm\n\t.byte 2\n",
        "\t.data\n\t.end\n\t.byte 1\n",
    ] {
        out.push(text.to_string());
    }
    // `.struct` and the absolute section.
    out.push(
        "\t.struct 0\na:\t.long 0\nb:\t.quad 0\nc:\t.space 3\nd:\n\t.data\n\t.long a, b, c, d\n"
            .into(),
    );
    out.push("\t.struct 16\na:\t.byte 0\nb:\n\t.text\n\til $3, b\n".into());
    out.push("\t.data\n\t.struct 0\n\t.long 5\n".into());
    // Expressions: every binary operator with a label and a constant, and the location
    // counter.
    for op in [
        "+", "-", "*", "/", "%", "<<", ">>", "&", "|", "^", "!", "==", "!=", "<>", "<", ">", "<=",
        ">=", "&&", "||",
    ] {
        out.push(format!(
            "\t.data\nx:\t.long 0\ny:\t.long (y - x) {op} 3, 12 {op} (y - x)\n"
        ));
        out.push(format!("\t.data\nx:\t.long x {op} 4\n"));
    }
    for e in [
        "-x",
        "~x",
        "!x",
        "+x",
        "x - .",
        ". - x",
        ". + 4",
        "(. - x) * 2",
    ] {
        out.push(format!("\t.data\nx:\t.long 0\n\t.long {e}\n"));
    }
    // Numeric local labels, `$` and dollar labels, odd names.
    for text in [
        "\t.text\n1:\tnop\n1:\tbr 1b\n\tbr 1f\n1:\tnop\n2:\tbr 2b\n",
        "\t.text\n\tbr 7f\n",
        "\t.text\n\tbr 7b\n7:\n",
        "\t.text\nx.y:\tnop\n_z$:\tnop\n\tbr x.y\n\tbr _z$\n",
        "\t.text\n.Lx:\tnop\n\tbr .Lx\n\t.data\n\t.long .Lx\n",
        "\t.text\n\t.globl .Lg\n.Lg:\tnop\n",
        "\t.text\nx: y: z:\tnop\n",
        "\t.text\nx:\tnop\nx:\tnop\n",
        "\t.data\n\t.long undefined_local_label_.L\n",
    ] {
        out.push(text.to_string());
    }
    // `.file` names, `.ident`, and statements GNU as ignores.
    for text in [
        "\t.file \"a.c\"\n\t.text\n\tnop\n",
        "\t.text\nx:\tnop\n\t.file \"a.c\"\n\t.file \"b.c\"\n",
        "\t.ident \"GCC: 4.1.1\"\n\t.text\nx:\tnop\n\t.data\n\t.long x\n",
        "\t.text\n\t.ident \"a\"\n\t.section .foo\n\t.ident \"b\"\n\t.long 0\n",
        "\t.extern e\n\t.text\n\tnop\n",
        "\t.nolist\n\t.list\n\t.eject\n\t.text\n\tnop\n",
        "\t.loc_mark_labels 0\n\t.text\n\tnop\n",
        "\t.brinfo 1\n\t.text\n\tbr 1f\n1:\tnop\n",
        "\t.text\n\t.long 1\n\tnop\n\t.byte 2\n\t.align 2\n\tnop\n",
        "\t.text\n\t.byte 1\n\tnop\n",
    ] {
        out.push(text.to_string());
    }
    out.into_iter()
        .enumerate()
        .map(|(k, text)| (format!("dir_{k}.s"), text))
        .collect()
}

/// `.file`/`.loc` forms: the `.debug_line` (and the unit gas adds around it) of each is
/// compared byte for byte.
const LINE_TABLES: &[&str] = &[
    "\t.file 1 \"a.c\"\n\t.loc 1 3 0\n\til $3,1\n\til $3,2\n\t.loc 1 5 2\n\til $4,1\n\t.loc 1 4 0 prologue_end\n\tnop\n",
    "\t.file 1 \"src/a.c\"\n\t.file 2 \"inc/b.h\"\n\t.file 3 \"src/c.c\"\n\t.loc 2 100 7 is_stmt 0\n\til $3,1\n\t.loc 1 1 basic_block\n\til $5,5\n\t.space 400\n\t.loc 1 30 discriminator 3 isa 2\n\til $6,6\n\t.loc 3 2 epilogue_begin\n\t.loc 3 9\n\til $7,7\n",
    "\t.file 1 \"x.c\"\n\t.loc 1 1\n\tnop\n\t.space 16\n\t.loc 1 2\n\tnop\n\t.space 296\n\t.loc 1 40\n\tnop\n\t.loc 1 20\n\tnop\n\t.align 4\n",
    "\t.file 1 \"s.c\"\n\t.text 1\n\t.loc 1 20\n\til $3,1\n\t.text 0\n\t.loc 1 10\n\til $3,2\n\til $3,3\n\t.text 1\n\t.align 4\n\t.loc 1 21\n\til $3,4\n",
    "\t.file 1 \"a.c\"\n\t.global f\n\t.type f,@function\nf:\t.loc 1 1\n\til $3,1\n\tbi $0\n\t.size f,.-f\n\t.section .text.b,\"ax\",@progbits\n\t.type g,@function\ng:\t.loc 1 9\n\tbi $0\n\t.size g,4\n",
    "\t.file 1 \"a.c\"\n\t.loc_mark_labels 1\n\t.loc 1 5\n\til $3,1\nhere:\til $3,2\n",
    "\t.file 1 \"a.c\"\n\t.loc 1 0\n\t.loc 1 7 view .LVU1\n\t.loc 1 8 view .LVU2\n\til $3,1\n\t.data\n\t.long .LVU1, .LVU2\n",
    "\t.file 1 \"/abs/dir/a.c\"\n\t.file 2 \"/b.c\"\n\t.loc 1 1000000\n\til $3,1\n\t.loc 2 1\n\til $3,2\n",
    "\t.file 1 \"a.c\"\n\t.file 2 \"a.c\"\n\t.file 1 \"a.c\"\n\t.loc 2 2 3\n\tnop\n",
];

/// Every `.s` of the project (kernels, tests, examples), in a stable order.
pub(crate) fn project_sources() -> Vec<PathBuf> {
    sources_under(&Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
}

/// Every `.s` under `root` (not in hidden directories, `target` or `shared`), sorted.
fn sources_under(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut dirs = vec![root.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            if p.is_dir() {
                if !name.starts_with('.') && name != "target" && name != "shared" {
                    dirs.push(p);
                }
            } else if name.ends_with(".s") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// An ELF32 big-endian object as lines of text, one fact per line, in file order: the
/// header, each section header, each symbol in table order, each relocation in section
/// order and each section's contents 16 bytes to a line. Two objects are the same object
/// when these lines are the same; where they differ, the first differing lines say how
/// (the byte comparison after it catches anything the lines leave out: padding).
pub(crate) fn elf_lines(elf: &[u8]) -> Result<Vec<String>, String> {
    let u16_at = |o: usize| -> Result<usize, String> {
        elf.get(o..o + 2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]) as usize)
            .ok_or_else(|| format!("ELF cut short at {o:#x}"))
    };
    let u32_at = |o: usize| -> Result<usize, String> {
        elf.get(o..o + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as usize)
            .ok_or_else(|| format!("ELF cut short at {o:#x}"))
    };
    let cstr = |o: usize| -> String {
        let tail = elf.get(o..).unwrap_or(&[]);
        let end = tail.iter().position(|&b| b == 0).unwrap_or(tail.len());
        String::from_utf8_lossy(&tail[..end]).into_owned()
    };
    if elf.get(..6) != Some(b"\x7fELF\x01\x02".as_slice()) {
        return Err("not ELF32 big-endian".into());
    }
    let mut out = vec![format!(
        "header: ident {:02x?} type {} machine {} version {} entry {:#x} flags {:#x} ehsize {} shentsize {}",
        &elf[..16],
        u16_at(16)?,
        u16_at(18)?,
        u32_at(20)?,
        u32_at(24)?,
        u32_at(36)?,
        u16_at(40)?,
        u16_at(46)?
    )];
    let (shoff, shnum, shstrndx) = (u32_at(32)?, u16_at(48)?, u16_at(50)?);
    out.push(format!("section headers at {shoff:#x}, {shnum} of them"));
    // name, type, offset, size, link, entsize
    let mut headers = Vec::new();
    for k in 0..shnum {
        let h = shoff + 40 * k;
        let f: Vec<usize> = (0..10)
            .map(|i| u32_at(h + 4 * i))
            .collect::<Result<_, _>>()?;
        headers.push(f);
    }
    let shstr = headers.get(shstrndx).map_or(0, |h| h[4]);
    let name = |k: usize| {
        headers
            .get(k)
            .map_or(format!("#{k}"), |h| cstr(shstr + h[0]))
    };
    for (k, h) in headers.iter().enumerate() {
        out.push(format!(
            "[{k}] {} (name at {}) type {} flags {:#x} addr {:#x} off {:#x} size {:#x} link {} info {} align {} entsize {}",
            name(k), h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8], h[9]
        ));
    }
    // The symbol table's names, for the relocations.
    let mut sym_names = Vec::new();
    for h in &headers {
        if h[1] != 2 {
            continue;
        }
        let strtab = headers.get(h[6]).map_or(0, |s| s[4]);
        for i in 0..h[5] / 16 {
            let o = h[4] + 16 * i;
            let (nm, value, size) = (u32_at(o)?, u32_at(o + 4)?, u32_at(o + 8)?);
            let (info, other, shndx) = (
                *elf.get(o + 12).ok_or("cut short")?,
                *elf.get(o + 13).ok_or("cut short")?,
                u16_at(o + 14)?,
            );
            let place = match shndx {
                0 => "UND".to_string(),
                0xfff1 => "ABS".to_string(),
                0xfff2 => "COM".to_string(),
                k => name(k),
            };
            let n = if info & 15 == 3 {
                name(shndx)
            } else {
                cstr(strtab + nm)
            };
            out.push(format!(
                "sym {i}: `{}' {place} value {value:#x} size {size} type {} bind {} other {other} (name at {nm})",
                cstr(strtab + nm),
                info & 15,
                info >> 4
            ));
            sym_names.push(n);
        }
    }
    for h in &headers {
        if h[1] == 4 {
            for i in 0..h[5] / 12 {
                let o = h[4] + 12 * i;
                let (off, info, addend) = (u32_at(o)?, u32_at(o + 4)?, u32_at(o + 8)? as i32);
                out.push(format!(
                    "reloc {}[{i}] {off:#x} type {} sym {} `{}' {addend:+}",
                    name(h[7]),
                    info & 0xff,
                    info >> 8,
                    sym_names.get(info >> 8).map_or("?", |s| s.as_str())
                ));
            }
        } else if h[1] != 8 {
            let bytes = elf.get(h[4]..h[4] + h[5]).ok_or("section past the end")?;
            for (i, c) in bytes.chunks(16).enumerate() {
                out.push(format!(
                    "{}+{:#x}: {:02x?}",
                    name(headers.iter().position(|x| x == h).unwrap_or(0)),
                    16 * i,
                    c
                ));
            }
        }
    }
    Ok(out)
}

/// How GNU as and `spu as -c` differ on one object ("" when they do not): the first
/// differing facts of `elf_lines`, or the first differing byte.
pub(crate) fn object_difference(ours: &[u8], theirs: &[u8]) -> String {
    if ours == theirs {
        return String::new();
    }
    match (elf_lines(ours), elf_lines(theirs)) {
        (Ok(a), Ok(b)) => {
            // The first few facts that differ (where the header table starts follows from
            // the rest, so it is named only when nothing else differs).
            let differing: Vec<usize> = (0..a.len().max(b.len()))
                .filter(|&k| a.get(k) != b.get(k))
                .collect();
            // Symbols and relocations first: section offsets and sizes follow from them.
            let rank = |k: &usize| {
                let line = a.get(*k).or(b.get(*k)).map_or("", |s| s.as_str());
                (
                    !(line.starts_with("sym") || line.starts_with("reloc")),
                    *k == 1,
                    *k,
                )
            };
            let mut shown = differing.clone();
            shown.sort_by_key(rank);
            shown.truncate(3);
            if !shown.is_empty() {
                let show = |v: &[String]| {
                    shown
                        .iter()
                        .map(|&k| v.get(k).map_or("(none)", |s| s.as_str()))
                        .collect::<Vec<_>>()
                        .join(" | ")
                };
                return format!("ours: {}\n    GNU:  {}", show(&a), show(&b));
            }
        }
        (Err(e), _) => return format!("ours unreadable: {e}"),
        (_, Err(e)) => return format!("GNU's unreadable: {e}"),
    }
    let k = ours
        .iter()
        .zip(theirs)
        .position(|(a, b)| a != b)
        .unwrap_or(ours.len().min(theirs.len()));
    format!(
        "bytes differ at {k:#x} (ours {} bytes, GNU {})",
        ours.len(),
        theirs.len()
    )
}

/// The lines of a file GNU's messages name with a warning (`FILE:LINE: Warning: ...`),
/// each as `basename:line`, sorted, each once (GNU as warns twice of some divisions by
/// zero in data, once for each time it reads the expression: a count we do not copy).
fn gnu_warning_lines(stderr: &str) -> Vec<String> {
    let mut v: Vec<String> = stderr
        .lines()
        .filter_map(|l| {
            let (place, msg) = l.split_once(": Warning: ")?;
            let _ = msg;
            let (file, line) = place.rsplit_once(':')?;
            Some(format!(
                "{}:{line}",
                Path::new(file).file_name()?.to_string_lossy()
            ))
        })
        .collect();
    v.sort();
    v.dedup();
    v
}

/// What the differential run found.
#[derive(Default)]
pub(crate) struct Differential {
    /// Files both assemblers turned into objects (compared byte for byte).
    pub(crate) compared: usize,
    /// Files both refused.
    pub(crate) refused_by_both: usize,
    /// Project files left out: they use this project's own directives (`.sched`), which
    /// GNU as has not.
    pub(crate) extensions: usize,
    /// gas testsuite files whose `.d` says they are not for spu-elf (`#notarget`,
    /// `#target`), each with the reason.
    pub(crate) not_for_spu: Vec<String>,
    /// gas testsuite files compared without `#as:` options `spu as` has not (both
    /// assemblers run without them), each with the options.
    pub(crate) without_options: Vec<String>,
    pub(crate) failures: Vec<String>,
}

/// Statements of this project's own, beyond GNU as: a file GNU as refuses for one of
/// them (in it or a file it includes) is not compared.
const OWN_DIRECTIVES: &[&str] = &[".sched", ".spu_ext"];

/// The symbols a file is assembled with (`--defsym`), by the path it ends with.
pub(crate) type Defines = fn(&Path) -> Vec<(String, i64)>;

/// Both assemblers over `files`, in parallel: whether each accepts it, the lines each
/// warns on, and the objects byte for byte.
pub(crate) fn differential(
    gas: &Path,
    files: &[PathBuf],
    tmp: &Path,
    defines: Defines,
) -> Differential {
    std::fs::create_dir_all(tmp).unwrap();
    let threads = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .min(8);
    let results = std::sync::Mutex::new(Differential::default());
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for t in 0..threads {
            let (results, next) = (&results, &next);
            scope.spawn(move || {
                let out = tmp.join(format!("gnu{t}.o"));
                loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(file) = files.get(k) else { break };
                    let mut run = suite_run(file);
                    run.defines.extend(defines(file));
                    let mut d = results.lock().unwrap();
                    if let Some(why) = &run.not_for_spu {
                        d.not_for_spu.push(format!("{}: {why}", file.display()));
                        continue;
                    }
                    if !run.lacking.is_empty() {
                        let lacking = run.lacking.join(" ");
                        d.without_options
                            .push(format!("{}: {lacking}", file.display()));
                    }
                    drop(d);
                    let r = compare_one(gas, file, &out, &run);
                    let mut d = results.lock().unwrap();
                    match r {
                        Compared::Same => d.compared += 1,
                        Compared::RefusedByBoth => d.refused_by_both += 1,
                        Compared::Extension => d.extensions += 1,
                        Compared::Differ(m) => {
                            d.compared += 1;
                            d.failures.push(format!("{}: {m}", file.display()));
                        }
                        Compared::Disagree(m) => {
                            d.failures.push(format!("{}: {m}", file.display()))
                        }
                    }
                }
            });
        }
    });
    let mut d = results.into_inner().unwrap();
    d.failures.sort();
    d
}

enum Compared {
    Same,
    RefusedByBoth,
    Extension,
    Differ(String),
    Disagree(String),
}

fn compare_one(gas: &Path, file: &Path, out: &Path, run: &SuiteRun) -> Compared {
    let defines = &run.defines;
    let opts = Options {
        defines: defines.clone(),
        alternate: run.alternate,
        ..Options::default()
    };
    let ours = assemble_object_file(file, &opts);
    let mut cmd = std::process::Command::new(gas);
    if let Some(dir) = file.parent() {
        cmd.arg("-I").arg(dir);
    }
    for (name, value) in defines {
        cmd.arg("--defsym").arg(format!("{name}={value}"));
    }
    cmd.args(&run.gnu_args);
    let _ = std::fs::remove_file(out);
    let gnu = cmd
        .arg(file)
        .arg("-o")
        .arg(out)
        .output()
        .expect("runs GNU as");
    let stderr = String::from_utf8_lossy(&gnu.stderr).into_owned();
    let own = |s: &str| {
        OWN_DIRECTIVES
            .iter()
            .any(|d| s.contains(&format!("unknown pseudo-op: `{d}'")))
    };
    if ours.is_ok() && !gnu.status.success() && own(&stderr) {
        return Compared::Extension;
    }
    let first = |s: &str| {
        s.lines()
            .find(|l| l.contains("rror"))
            .unwrap_or("")
            .to_string()
    };
    match (ours, gnu.status.success()) {
        (Err(_), false) => Compared::RefusedByBoth,
        (Err(e), true) => Compared::Disagree(format!(
            "GNU as accepts what we refuse: {}",
            e.first().map(|d| d.to_string()).unwrap_or_default()
        )),
        (Ok(_), false) => {
            Compared::Disagree(format!("GNU as refuses what we accept: {}", first(&stderr)))
        }
        (Ok((obj, warnings)), true) => {
            let mut ours_warned: Vec<String> = warnings
                .iter()
                .map(|w| {
                    let f = Path::new(&w.location.file).file_name().unwrap_or_default();
                    format!("{}:{}", f.to_string_lossy(), w.location.line)
                })
                .collect();
            ours_warned.sort();
            ours_warned.dedup();
            let mut m = Vec::new();
            let theirs_warned = gnu_warning_lines(&stderr);
            if ours_warned != theirs_warned {
                m.push(format!(
                    "warnings on lines: ours {ours_warned:?}, GNU {theirs_warned:?} ({})",
                    stderr.trim().replace('\n', " / ")
                ));
            }
            match obj.to_elf() {
                Ok(elf) => {
                    let theirs = std::fs::read(out).unwrap_or_default();
                    let d = object_difference(&elf, &theirs);
                    if !d.is_empty() {
                        m.push(d);
                    }
                }
                Err(e) => m.push(format!("ours not written: {e}")),
            }
            if m.is_empty() {
                Compared::Same
            } else {
                Compared::Differ(m.join("\n    "))
            }
        }
    }
}

/// GNU as's object for `file` (None when GNU as refuses it too).
pub(crate) fn gnu_object(gas: &Path, file: &Path, tmp: &Path) -> Option<Object> {
    let out = tmp.join("gnu.o");
    let mut cmd = std::process::Command::new(gas);
    if let Some(dir) = file.parent() {
        cmd.arg("-I").arg(dir);
    }
    let status = cmd.arg(file).arg("-o").arg(&out).output().ok()?;
    if !status.status.success() {
        return None;
    }
    Object::from_elf("gnu.o", &std::fs::read(&out).ok()?).ok()
}

/// Writes the generated corpus under `dir` and gives the paths.
pub(crate) fn write_corpus(dir: &Path) -> Vec<PathBuf> {
    std::fs::create_dir_all(dir).unwrap();
    generated_corpus()
        .into_iter()
        .map(|(name, src)| {
            let p = dir.join(name);
            std::fs::write(&p, src).unwrap();
            p
        })
        .collect()
}

/// How a source is assembled for the comparison: what a gas testsuite `.d` beside it
/// (same name, `.d` for `.s`) asks of the run.
#[derive(Default)]
pub(crate) struct SuiteRun {
    /// `--defsym`s (the `.d`'s `#as:` ones, then the project's for the file).
    pub(crate) defines: Vec<(String, i64)>,
    /// `#as: --alternate`.
    pub(crate) alternate: bool,
    /// `#as:` options given to GNU as: `--alternate` (which `alternate` gives `spu as`),
    /// and those that change nothing in the object (`-a` lists to stdout;
    /// `--generate-missing-build-notes=no` is spu-elf's default).
    pub(crate) gnu_args: Vec<String>,
    /// `#as:` options `spu as` has not: both assemble without them.
    pub(crate) lacking: Vec<String>,
    /// Why the `.d` leaves spu-elf out (`#notarget`, `#target`).
    pub(crate) not_for_spu: Option<String>,
}

/// The target triple gas's testsuite matches `#target`/`#notarget` patterns against.
const SPU_TRIPLE: &str = "spu-unknown-elf";

/// A `#target`/`#notarget` pattern (Tcl's `string match`: `*`, `?`, `[...]` procs)
/// against spu-elf. Of the testsuite's procs, `is_elf_format` holds for spu-elf; the
/// others it uses (`is_xcoff_format`, `is_aout_format`, `supports_gnu_osabi`) do not.
fn target_matches(pattern: &str) -> bool {
    if let Some(proc_name) = pattern.strip_prefix('[') {
        return proc_name.trim_end_matches(']') == "is_elf_format";
    }
    fn glob(p: &[u8], s: &[u8]) -> bool {
        match p.split_first() {
            None => s.is_empty(),
            Some((b'*', rest)) => (0..=s.len()).any(|k| glob(rest, &s[k..])),
            Some((&c, rest)) => s
                .split_first()
                .is_some_and(|(&d, tail)| (c == b'?' || c == d) && glob(rest, tail)),
        }
    }
    glob(pattern.as_bytes(), SPU_TRIPLE.as_bytes())
}

/// What the `.d` beside `file` asks of its run (nothing where there is none).
pub(crate) fn suite_run(file: &Path) -> SuiteRun {
    let mut run = SuiteRun::default();
    let Ok(text) = std::fs::read_to_string(file.with_extension("d")) else {
        return run;
    };
    for line in text.lines() {
        let Some((key, value)) = line.strip_prefix('#').and_then(|l| l.split_once(':')) else {
            continue;
        };
        let patterns = || value.split_whitespace();
        match key.trim() {
            "as" => {
                let mut words = value.split_whitespace();
                while let Some(w) = words.next() {
                    match w {
                        "--alternate" => {
                            run.alternate = true;
                            run.gnu_args.push(w.to_string());
                        }
                        "-a" | "--generate-missing-build-notes=no" => {
                            run.gnu_args.push(w.to_string())
                        }
                        // The source's directory is on both include paths already.
                        _ if w.starts_with("-I") => {}
                        "--defsym" => {
                            let d = words.next().unwrap_or("");
                            match d.split_once('=').map(|(n, v)| (n, v.parse::<i64>())) {
                                Some((n, Ok(v))) => run.defines.push((n.to_string(), v)),
                                _ => run.lacking.push(format!("--defsym {d}")),
                            }
                        }
                        _ => run.lacking.push(w.to_string()),
                    }
                }
            }
            "notarget" if patterns().any(target_matches) => {
                run.not_for_spu = Some(format!("#notarget:{value}"));
            }
            "target" if !patterns().any(target_matches) => {
                run.not_for_spu = Some(format!("#target:{value}"));
            }
            _ => {}
        }
    }
    if run.not_for_spu.is_some() {
        run.lacking.clear();
    }
    run
}

/// gas's own testsuite directories (`gas/testsuite/gas/NAME`) compared by default where
/// `scripts/build-spu-binutils.sh` installed them. `elf` joins when its differences are
/// gone (issue #31, the gaself branch): add it here.
const GAS_SUITE_DIRS: &[&str] = &["all", "macros"];

/// Where the build found gas's testsuite (`share/spu-binutils-testsuite/gas` beside
/// GNU as, or `SPU_GAS_TESTSUITE_ROOT`).
#[cfg(has_gas_testsuite)]
const GAS_SUITE_ROOT: Option<&str> = Some(env!("SPU_GAS_TESTSUITE_ROOT"));
#[cfg(not(has_gas_testsuite))]
const GAS_SUITE_ROOT: Option<&str> = None;

/// The `.s` files of gas's testsuite directories (`GAS_SUITE_DIRS`, or the names
/// `SPU_GAS_SUITE_DIRS` gives, `:`-separated), and a line saying what was taken.
pub(crate) fn gas_suite_sources() -> (Vec<PathBuf>, String) {
    let Some(root) = GAS_SUITE_ROOT else {
        return (
            Vec::new(),
            "gas's testsuite (all, macros, elf) not found when the test was built:              scripts/build-spu-binutils.sh --testsuite-only installs it; compared without"
                .to_string(),
        );
    };
    let names: Vec<String> = match std::env::var("SPU_GAS_SUITE_DIRS") {
        Ok(v) => v
            .split(':')
            .filter(|n| !n.is_empty())
            .map(str::to_string)
            .collect(),
        Err(_) => GAS_SUITE_DIRS.iter().map(|n| n.to_string()).collect(),
    };
    let mut files = Vec::new();
    for n in &names {
        let dir = Path::new(root).join(n);
        assert!(
            dir.is_dir(),
            "{}: no such testsuite directory",
            dir.display()
        );
        files.extend(sources_under(&dir));
    }
    let note = format!(
        "gas's testsuite at {root}: {} ({} files)",
        names.join(", "),
        files.len()
    );
    (files, note)
}

/// The `.s` files under the directories `SPU_GAS_TESTSUITE` names (`:`-separated; gas's
/// own `gas/testsuite/gas/spu` for one): extra inputs on a machine that has them.
pub(crate) fn testsuite_sources() -> Vec<PathBuf> {
    let Some(dirs) = std::env::var_os("SPU_GAS_TESTSUITE") else {
        return Vec::new();
    };
    std::env::split_paths(&dirs)
        .flat_map(|d| sources_under(&d))
        .collect()
}

/// GNU as's quirks that `spu as` does not copy, each by a piece of the sources it shows
/// in and why: a corpus file holding the piece may differ, and must (so that the list
/// cannot outlive the difference). All are files of gas's own testsuite
/// (`docs/gas-directives.md`, "gas's own testsuites": what is left and why).
const KNOWN_DIFFERENCES: &[(&str, &str)] = &[
    (
        ".octa ~0x112233445566778899aabbcc0000",
        "all/octa.s: expressions are 64-bit; gas's bignums (128-bit `~`, `-`) are not",
    ),
    (
        " .equ one, -minus_one",
        "all/forward.s: an equate binds the symbol instances of its definition in gas \
         (a volatile symbol set again is a new one); spu as reads names",
    ),
    (
        ".xstabs",
        "all/pr23938.s: stabs (`.xstabs`, `.stabs`) are not written",
    ),
    (
        " .uleb128 L2 - L1",
        "all/relax.s: gas's relaxation keeps an alignment's padding from an earlier round \
         where a `.uleb128` grows; spu as lays out to a fixed point",
    ),
];

/// The failures `KNOWN_DIFFERENCES` accounts for taken out of `failures` (and counted);
/// an error for each of its pieces that no failure showed though one of `files` holds it.
pub(crate) fn without_known(failures: Vec<String>, files: &[PathBuf]) -> (Vec<String>, usize) {
    let mut seen = vec![false; KNOWN_DIFFERENCES.len()];
    let mut left = Vec::new();
    let mut known = 0;
    for f in failures {
        let path = f.split(": ").next().unwrap_or("");
        let text = std::fs::read_to_string(path).unwrap_or_default();
        match KNOWN_DIFFERENCES
            .iter()
            .position(|(piece, _)| text.contains(piece))
        {
            Some(k) => {
                seen[k] = true;
                known += 1;
            }
            None => left.push(f),
        }
    }
    let holds = |piece: &str| {
        files
            .iter()
            .any(|f| std::fs::read_to_string(f).is_ok_and(|t| t.contains(piece)))
    };
    for (k, (piece, why)) in KNOWN_DIFFERENCES.iter().enumerate() {
        if !seen[k] && holds(piece) {
            left.push(format!(
                "no file differs any more where {piece:?} is ({why}): take it off KNOWN_DIFFERENCES"
            ));
        }
    }
    (left, known)
}

/// The symbols the project assembles a kernel with: the refit kernel's buffer sizes.
pub(crate) fn project_defines(file: &Path) -> Vec<(String, i64)> {
    if file.ends_with("kernels/refit.s") {
        spu_loader::spu_refit::defines()
            .into_iter()
            .map(|(n, v)| (n.to_string(), v))
            .collect()
    } else {
        Vec::new()
    }
}

#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn objects_match_gnu_as() {
    let gas = Path::new(GNU_AS);
    assert!(
        gas.is_file(),
        "{GNU_AS} is gone since the build: rebuild (cargo clean -p spu-tests)"
    );
    let tmp = std::env::temp_dir().join(format!("spu-gnu-diff-{}", std::process::id()));
    let mut files = project_sources();
    files.extend(write_corpus(&tmp.join("corpus")));
    let (suite, suite_note) = gas_suite_sources();
    eprintln!("{suite_note}");
    files.extend(suite);
    files.extend(testsuite_sources());
    let d = differential(gas, &files, &tmp, project_defines);
    let (failures, known) = without_known(d.failures, &files);
    for f in &d.not_for_spu {
        eprintln!("not for spu-elf: {f}");
    }
    for f in &d.without_options {
        eprintln!("compared without #as: options spu as has not: {f}");
    }
    eprintln!(
        "{} gas testsuite files not for spu-elf (their .d), {} compared without some #as: \
         options",
        d.not_for_spu.len(),
        d.without_options.len()
    );
    eprintln!(
        "{} files: {} compared with GNU as, {} refused by both, {} use this project's own \
         directives; {} known quirks, {} differences",
        files.len(),
        d.compared,
        d.refused_by_both,
        d.extensions,
        known,
        failures.len()
    );
    let _ = std::fs::remove_dir_all(&tmp);
    assert!(
        d.compared > 1000,
        "GNU as assembled only {} files",
        d.compared
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `spu dis`'s text for `file` against `objdump -d`'s, line by line (the file name
/// line aside, as both print the path they were given): the first difference, if any.
pub fn dis_difference(objdump: &Path, file: &Path) -> Option<String> {
    let dump = std::process::Command::new(objdump)
        .arg("-d")
        .arg(file)
        .output()
        .unwrap();
    assert!(dump.status.success(), "objdump -d {}", file.display());
    let theirs = String::from_utf8_lossy(&dump.stdout).into_owned();
    let data = std::fs::read(file).unwrap();
    let ours = spu_asm::disasm::objdump(&file.display().to_string(), &data, Default::default())
        .unwrap_or_else(|e| e);
    if ours == theirs {
        return None;
    }
    let (a, b): (Vec<&str>, Vec<&str>) = (ours.lines().collect(), theirs.lines().collect());
    let first = (0..a.len().max(b.len()))
        .find(|&i| a.get(i) != b.get(i))
        .unwrap_or(0);
    Some(format!(
        "{}: line {}: ours {:?}, objdump {:?}",
        file.display(),
        first + 1,
        a.get(first),
        b.get(first)
    ))
}

/// `spu dis` against `objdump -d` on GNU's objects of every project source and the
/// generated corpus: the whole text, header lines, `<symbol>:` blocks, `<sym+off>`
/// targets, data in code and `...` for zeros.
#[test]
#[cfg_attr(
    not(has_binutils),
    ignore = "needs GNU binutils for SPU: scripts/build-spu-binutils.sh"
)]
fn disassembly_matches_objdump() {
    let objdump = Path::new(GNU_AS).with_file_name("spu-elf-objdump");
    assert!(objdump.is_file(), "{} not found", objdump.display());
    let gas = Path::new(GNU_AS);
    let tmp = std::env::temp_dir().join(format!("spu-gnu-dis-{}", std::process::id()));
    let mut files = project_sources();
    files.extend(write_corpus(&tmp.join("corpus")));
    let mut failures = Vec::new();
    let mut compared = 0;
    for file in &files {
        if assemble_object_file(file, &Options::default()).is_err()
            || gnu_object(gas, file, &tmp).is_none()
        {
            continue;
        }
        compared += 1;
        failures.extend(dis_difference(&objdump, &tmp.join("gnu.o")));
    }
    let _ = std::fs::remove_dir_all(&tmp);
    eprintln!(
        "compared {compared} disassemblies with objdump, {} differ",
        failures.len()
    );
    assert!(compared > 300, "GNU as assembled only {compared} files");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Without binutils: every file of the generated corpus assembles here into an object that
/// lies inside its own bytes (readelf's reading) and reads back as written, or is refused
/// with errors at a line of it (the corpus holds sources GNU as refuses too: where binutils
/// is, `objects_match_gnu_as` checks that the two refuse the same files).
#[test]
fn generated_corpus_assembles_into_sound_objects() {
    let corpus = generated_corpus();
    assert!(corpus.len() >= 1500, "only {} files", corpus.len());
    let mut failures = Vec::new();
    let mut refused = 0;
    for (name, src) in &corpus {
        let (obj, _) = match assemble_object(src, name, &Options::default()) {
            Ok(o) => o,
            Err(e) => {
                refused += 1;
                if e.is_empty()
                    || e.iter()
                        .any(|d| d.location.line == 0 || d.location.file != *name)
                {
                    failures.push(format!("{name}: refused without a line: {e:?}"));
                }
                continue;
            }
        };
        let elf = match obj.to_elf() {
            Ok(e) => e,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        for e in layout_errors(&elf) {
            failures.push(format!("{name}: {e}"));
        }
        match Object::from_elf(name, &elf) {
            Ok(back) if back.sections == obj.sections && back.to_elf().as_ref() == Ok(&elf) => {}
            Ok(_) => failures.push(format!("{name}: differs after reading back")),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert!(refused < 100, "{refused} files refused");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The corpus through the never-panic checks: each file cut at every eighth byte and
/// with single bytes changed assembles or is refused, without a panic.
#[test]
fn generated_corpus_cut_or_mutated_never_panics() {
    let mut checked = 0;
    for (name, src) in generated_corpus() {
        let bytes = src.as_bytes();
        let mut variants: Vec<Vec<u8>> = (0..bytes.len())
            .step_by(8)
            .map(|n| bytes[..n].to_vec())
            .collect();
        for (k, b) in [b'(', b'"', b'\\', b',', b'\n', 0xff].iter().enumerate() {
            let mut v = bytes.to_vec();
            let at = (k * 7 + 3) % bytes.len().max(1);
            if let Some(x) = v.get_mut(at) {
                *x = *b;
            }
            variants.push(v);
        }
        for v in variants {
            let text: String = v.iter().map(|&b| b as char).collect();
            let _ = assemble_object(&text, &name, &Options::default());
            let _ = spu_asm::assemble(&text, &name, &Options::default());
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} variants");
}
