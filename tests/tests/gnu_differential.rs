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
use spu_asm::object::{Object, SymSection};
use spu_asm::{assemble_object, assemble_object_file, Options, RelocTarget};
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
    ".text\n.reloc ., R_SPU_ADDR32, ext\n.long 0\n",
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
    corpus
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
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut out = Vec::new();
    let mut dirs = vec![root.clone()];
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

/// A relocation as comparable text: offset, type, what it names, addend.
fn relocs(obj: &Object, section: usize) -> Vec<String> {
    let mut v: Vec<String> = obj.sections[section]
        .relocs
        .iter()
        .map(|r| {
            let target = match &r.target {
                RelocTarget::Section(s) => obj.sections[*s].name.clone(),
                RelocTarget::Symbol(n) => n.clone(),
            };
            format!("{:#x} {} {target}{:+}", r.offset, r.kind, r.addend)
        })
        .collect();
    v.sort();
    v
}

/// The symbols as comparable text: name, section name, value, size, type, binding.
fn symbols(obj: &Object) -> Vec<String> {
    let mut v: Vec<String> = obj
        .symbols
        .iter()
        .map(|s| {
            let section = match s.section {
                SymSection::Undefined => "UND".to_string(),
                SymSection::Absolute => "ABS".to_string(),
                SymSection::Common => "COM".to_string(),
                SymSection::Section(k) => obj.sections[k].name.clone(),
            };
            let bind = if s.weak {
                "weak"
            } else if s.global {
                "global"
            } else {
                "local"
            };
            format!(
                "{} {section} {:#x} size {} type {} {bind}{}",
                s.name,
                s.value,
                s.size,
                s.kind,
                if s.hidden { " hidden" } else { "" }
            )
        })
        .collect();
    v.sort();
    v
}

/// Every difference between our object and GNU's, in words.
fn differences(name: &str, ours: &Object, theirs: &Object) -> Vec<String> {
    let mut failures = Vec::new();
    for (k, s) in ours.sections.iter().enumerate() {
        let Some(t) = theirs.sections.iter().position(|x| x.name == s.name) else {
            if s.size > 0 || !s.relocs.is_empty() {
                failures.push(format!("{name}: GNU as has no section {}", s.name));
            }
            continue;
        };
        let g = &theirs.sections[t];
        if (s.size, &s.data, s.ty, s.flags) != (g.size, &g.data, g.ty, g.flags) {
            failures.push(format!(
                "{name}: {} differs (ours {} bytes type {} flags {:#x}, GNU {} bytes type {} flags {:#x})",
                s.name, s.size, s.ty, s.flags, g.size, g.ty, g.flags
            ));
        }
        if relocs(ours, k) != relocs(theirs, t) {
            failures.push(format!(
                "{name}: {} relocations: ours {:?}, GNU {:?}",
                s.name,
                relocs(ours, k),
                relocs(theirs, t)
            ));
        }
    }
    for g in &theirs.sections {
        let ours_has = ours.sections.iter().any(|s| s.name == g.name);
        // `.debug_line` byte for byte: a missing one is a difference too.
        if !ours_has && (g.size > 0 || g.name == ".debug_line") {
            failures.push(format!("{name}: we have no section {}", g.name));
        }
    }
    if symbols(ours) != symbols(theirs) {
        failures.push(format!(
            "{name}: symbols: ours {:?}, GNU {:?}",
            symbols(ours),
            symbols(theirs)
        ));
    }
    failures
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
    let mut failures = Vec::new();
    let mut compared = 0;
    for file in &files {
        let Ok((ours, _)) = assemble_object_file(file, &Options::default()) else {
            continue; // the error tests
        };
        let Some(theirs) = gnu_object(gas, file, &tmp) else {
            failures.push(format!("{}: GNU as refuses what we accept", file.display()));
            continue;
        };
        compared += 1;
        let name = file.display().to_string();
        failures.extend(differences(&name, &ours, &theirs));
    }
    eprintln!("compared {compared} objects with GNU as");
    let _ = std::fs::remove_dir_all(&tmp);
    assert!(compared > 300, "GNU as assembled only {compared} files");
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

/// Without binutils: every file of the generated corpus assembles here without an error,
/// into an object that lies inside its own bytes (readelf's reading) and reads back as
/// written.
#[test]
fn generated_corpus_assembles_into_sound_objects() {
    let corpus = generated_corpus();
    assert!(corpus.len() >= 300, "only {} files", corpus.len());
    let mut failures = Vec::new();
    for (name, src) in &corpus {
        let (obj, _) = match assemble_object(src, name, &Options::default()) {
            Ok(o) => o,
            Err(e) => {
                failures.push(format!(
                    "{name}: {}",
                    e.iter()
                        .map(|d| d.to_string())
                        .collect::<Vec<_>>()
                        .join("\n")
                ));
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
            Ok(back) if back.sections == obj.sections => {}
            Ok(_) => failures.push(format!("{name}: sections differ after reading back")),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
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
