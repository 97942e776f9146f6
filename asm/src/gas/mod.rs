//! A GNU-as compatible assembler for SPU, split the way GNU as is split. This is the
//! driver (gas's `as.c`): the assembler's state, the walks over the source, and the
//! entry points. The rooms, each one job, the dependency running one way:
//! - `read`: statements, labels and the directives (`read.c`);
//! - `macros` and `cond`: macro and repetition expansion, conditionals (`macro.c`,
//!   `cond.c`), on `crate::expand` and `crate::lex`, which `spu sched` shares;
//! - `symbols`: what names stand for, expressions evaluated against them (`symbols.c`,
//!   on `crate::expr`);
//! - `obj_elf`: sections and symbol attributes (`obj-elf.c`);
//! - `target`: SPU operands and encodings (`tc-spu.c`);
//! - `write`: layout, relocations and output (`write.c`), on `crate::object`;
//! - `dwarf2`: `.file`/`.loc` rows and the `.debug_line` made of them (`dwarf2dbg.c`);
//! - `messages`: diagnostics (`messages.c`).
//!
//! Pass 1 walks the source to give every label an address (every instruction is 4 bytes,
//! so only data directives need values then); pass 2 walks it again with all symbols known
//! and emits bytes. Both passes run the same expansion of `.include`, `.macro`, `.irp`,
//! `.rept` and `.if`, so they see the same statements.

mod cond;
mod dwarf2;
mod macros;
mod messages;
mod obj_elf;
mod read;
mod symbols;
mod target;
mod write;

pub use crate::lex::MAX_SOURCE;
pub use messages::{Diagnostic, Location, Severity};
pub use target::CHANNELS;

use crate::expr::Val;
use crate::lex::{bytes_as_text, to_lines, Line};
use crate::object::Reloc;
use crate::sched::{SchedError, Scheduled};
use macros::Macro;
use obj_elf::SectionDef;
use std::collections::HashMap;
use std::path::PathBuf;
use symbols::{Chain, SymAttrs, SymVal};

/// Assembler settings.
#[derive(Clone, Debug, Default)]
pub struct Options {
    pub include_dirs: Vec<PathBuf>,
    /// In-memory files for `.include` (name, contents), tried before the directories.
    pub virtual_files: Vec<(String, String)>,
    /// Symbols defined before the source (like `--defsym`).
    pub defines: Vec<(String, i64)>,
    /// ISA extensions on from the first line (`--ext`; `.spu_ext` adds more).
    pub extensions: spu_isa::Extensions,
    /// `-g`: line numbers of the assembly source itself, a row per source line with an
    /// instruction, until a `.file N` says the source brings its own (gas's
    /// `DEBUG_DWARF2`).
    pub debug_lines: bool,
    /// `--alternate`: gas's alternate macro syntax from the first line, as `.altmacro`.
    pub alternate: bool,
}

/// The assembled program.
#[derive(Clone, Debug, Default)]
pub struct Output {
    /// Local-store image loaded at address 0: `.text`, then `.data`, then `.bss` (zeros).
    pub image: Vec<u8>,
    /// An SPU ELF executable of the same program.
    pub elf: Vec<u8>,
    /// Global and local symbols (not `.L` locals) with their addresses.
    pub symbols: Vec<(String, u32)>,
    pub entry: u32,
    /// Address, words and source line of every statement that emitted bytes.
    pub listing: String,
    pub warnings: Vec<Diagnostic>,
    /// Section extents: (name, address, size, is code).
    pub sections: Vec<(String, u32, u32, bool)>,
    /// The files `.include` and `.incbin` read from disk: inputs of the command too, so
    /// that it writes no output over one.
    pub included: Vec<std::path::PathBuf>,
}

/// A chunk: one subsection of one section (an index into `Assembler::chunks`). A section
/// is the concatenation of its chunks in subsection order.
type Sect = usize;

/// The assembler's state through its walks over the source: sections and their bytes,
/// symbols, macros, diagnostics.
struct Assembler<'o> {
    opts: &'o Options,
    pass: u8,
    sect: Sect,
    /// `.previous` and the `.pushsection` stack.
    prev_sect: Sect,
    sect_stack: Vec<(Sect, Sect)>,
    defs: Vec<SectionDef>,
    /// Sections `.attach_to_group` put in a group, with the flags they had before: each
    /// walk starts from those, so both walks meet the same sections.
    attached: Vec<(usize, u64)>,
    /// Each chunk's section definition and subsection number.
    chunks: Vec<(usize, i64)>,
    /// Writing a relocatable object: addresses are section offsets and references that
    /// depend on them become relocations.
    object: bool,
    relocs: Vec<(usize, Reloc, Location, String)>,
    attrs: HashMap<String, SymAttrs>,
    /// Total statements expanded from macros and repetitions (bounded).
    expanded: usize,
    /// Diagnostics already reported (constant-time deduplication) and the count dropped.
    seen_diags: std::collections::HashSet<(String, usize, usize, String)>,
    dropped_diags: usize,
    /// Files on disk that `.include` and `.incbin` read, each once, in the order first read.
    included: Vec<std::path::PathBuf>,
    /// The value of the operand whose relocation `instruction` is about to record.
    pending: Option<Val>,
    /// Labels defined so far in this walk.
    defined: std::collections::HashSet<String>,
    /// Bytes other than zero were stored in a NOBITS section (reported once per statement).
    nonzero_in_nobits: bool,
    offsets: HashMap<Sect, u32>,
    align: HashMap<Sect, u32>,
    bases: HashMap<Sect, u32>,
    symbols: HashMap<String, SymVal>,
    /// The symbols as pass 1 left them (for forward references in pass 2).
    pass1_symbols: HashMap<String, SymVal>,
    /// Numeric local label definitions: label -> list of (statement number, section, offset).
    numeric: HashMap<u32, Vec<(usize, Sect, u32)>>,
    /// The same, being collected by the current layout walk.
    numeric_next: HashMap<u32, Vec<(usize, Sect, u32)>>,
    stmt: usize,
    bytes: HashMap<Sect, Vec<u8>>,
    diags: Vec<Diagnostic>,
    macros: HashMap<String, Macro>,
    macro_counter: usize,
    listing: String,
    depth: usize,
    /// Macro expansions under way, and whether `.exitm` asked the innermost one to stop.
    macro_depth: usize,
    exitm: bool,
    /// `.sched` blocks already scheduled in an earlier pass: the same lines, options and
    /// start give the same schedule when every register name the scheduler resolved
    /// still resolves the same (layout passes repeat each block unchanged).
    schedules: HashMap<SchedKey, SchedEntry>,
    /// Names the expression being evaluated used before their definition in this walk
    /// (through `.set` symbols too), and each `.set` symbol's: symbol definition loops.
    forward_refs: std::cell::RefCell<Vec<String>>,
    set_forward: HashMap<String, Vec<String>>,
    /// `.struct`: the offset in gas's absolute section, where labels are numbers and
    /// data only advances the offset, until a section directive leaves it.
    absolute: Option<u32>,
    /// A statement in the absolute section tried to store bytes other than zero.
    nonzero_in_absolute: bool,
    /// `.altmacro` is on: `<...>` and `%expr` arguments, `LOCAL`, bare parameter names.
    altmacro: bool,
    /// `LOCAL` names made so far (`.LL0001`, ...), as macro.c's `loccnt`.
    local_counter: usize,
    /// `.symver NAME, NAME2@VERSION[, local|hidden|remove]` (final walk): the versioned
    /// names objects give symbols.
    symvers: Vec<(String, String, String)>,
    /// `.weakref ALIAS, TARGET` (kept from the first walk, so a use before the directive
    /// reads it too): the alias stands for its target and is never in the table.
    weakrefs: HashMap<String, String>,
    /// Names used in an expression by themselves, not through a weakref alias (final
    /// walk): a target so used is a strong reference (symbols.c `S_IS_WEAKREFD`).
    direct_uses: std::cell::RefCell<std::collections::HashSet<String>>,
    /// Names `.eqv NAME, EXPR` (`NAME == EXPR`) made with `.` in EXPR, and EXPR: gas
    /// resolves their `.` where each is used, and for the symbol table where the source
    /// ends (`dot_symbol` resolved late).
    dot_eqv: HashMap<String, String>,
    /// `.eqv` expressions being evaluated inside one another (a bound on loops).
    eqv_depth: std::cell::Cell<usize>,
    /// Names given a value in this walk, each with whether it may be given another: by
    /// `.set`/`.equ`/`=` yes (gas's volatile symbols), by `.equiv`/`.eqv` no.
    equated: HashMap<String, bool>,
    /// `.file N`/`.loc` line-table state of this walk (`dwarf2dbg.c`).
    dwarf: dwarf2::LineState,
    /// The ISA extensions on at this point of the walk (the options', then `.spu_ext`).
    extensions: spu_isa::Extensions,
    /// The order the final walk made symbols in (an object's symbol table order).
    chain: std::cell::RefCell<Chain>,
    /// `.end` was read: the walk reads nothing more.
    ended: bool,
}

/// What a `.sched` block's schedule is made from: its lines, options and start address.
type SchedKey = (Vec<String>, String, u32);

/// A scheduled `.sched` block: the register names the scheduler resolved (with their
/// numbers) and its schedule.
type SchedEntry = (Vec<(String, Option<u8>)>, Result<Scheduled, SchedError>);

/// A result with an error at a column (0-based, in the text given) and its message.
type Res<T> = Result<T, (usize, String)>;

/// Statements that macros, `.rept` and `.irp` may expand to in all: a bound on work, so
/// nested repetitions cannot run for ever.
const MAX_EXPANDED: usize = 1_000_000;

/// Files, macro expansions and repetitions open inside one another: past GNU's macro
/// limit (100) and deep enough for any include chain, within the host's stack.
const MAX_NESTING: usize = 256;

/// gas's `max_macro_nest`: macro expansions inside one another.
const MAX_MACRO_NEST: usize = 100;

/// Bytes of SPU local store: the most a program can occupy.
const LOCAL_STORE: usize = 256 * 1024;

impl<'o> Assembler<'o> {
    fn new(opts: &'o Options, object: bool) -> Assembler<'o> {
        let mut asm = Assembler {
            extensions: opts.extensions,
            opts,
            pass: 1,
            sect: 0,
            prev_sect: 0,
            sect_stack: Vec::new(),
            defs: Vec::new(),
            attached: Vec::new(),
            chunks: Vec::new(),
            object,
            relocs: Vec::new(),
            attrs: HashMap::new(),
            expanded: 0,
            seen_diags: Default::default(),
            dropped_diags: 0,
            included: Vec::new(),
            pending: None,
            defined: Default::default(),
            nonzero_in_nobits: false,
            offsets: HashMap::new(),
            align: HashMap::new(),
            bases: HashMap::new(),
            symbols: HashMap::new(),
            pass1_symbols: HashMap::new(),
            numeric: HashMap::new(),
            numeric_next: HashMap::new(),
            stmt: 0,
            bytes: HashMap::new(),
            diags: Vec::new(),
            macros: HashMap::new(),
            macro_counter: 0,
            listing: String::new(),
            depth: 0,
            macro_depth: 0,
            exitm: false,
            schedules: HashMap::new(),
            forward_refs: Default::default(),
            set_forward: HashMap::new(),
            absolute: None,
            nonzero_in_absolute: false,
            altmacro: false,
            local_counter: 0,
            symvers: Vec::new(),
            weakrefs: HashMap::new(),
            direct_uses: Default::default(),
            dot_eqv: Default::default(),
            eqv_depth: Default::default(),
            equated: HashMap::new(),
            dwarf: Default::default(),
            chain: Default::default(),
            ended: false,
        };
        // gas always has .text, .data and .bss, in that order.
        for name in [".text", ".data", ".bss"] {
            asm.chunk(SectionDef::named(name), 0);
        }
        asm
    }

    /// One walk over the source: `pass` 1 lays out (unknown symbols read as 0), pass 2
    /// emits with every address known.
    fn run_pass(&mut self, lines: &[Line], pass: u8) {
        self.pass = pass;
        self.sect = 0;
        self.prev_sect = 0;
        self.sect_stack.clear();
        for (d, flags) in std::mem::take(&mut self.attached) {
            (self.defs[d].group, self.defs[d].flags) = (None, flags);
        }
        self.offsets.clear();
        self.stmt = 0;
        self.macros.clear();
        self.macro_counter = 0;
        self.expanded = 0;
        self.exitm = false;
        self.defined.clear();
        self.equated.clear();
        self.set_forward.clear();
        self.absolute = None;
        self.altmacro = self.opts.alternate;
        self.local_counter = 0;
        self.dwarf = Default::default();
        self.ended = false;
        if pass == 2 {
            // gas makes the `--defsym` symbols (the last given first), then .text, .data
            // and .bss (and their symbols), before reading.
            let mut chain = Chain::default();
            for (n, _) in self.opts.defines.iter().rev() {
                chain.symbol(n);
            }
            for d in 0..3 {
                chain.section(d);
            }
            *self.chain.borrow_mut() = chain;
            self.bytes.clear();
            self.relocs.clear();
            self.listing.clear();
        }
        // Labels keep the values of the previous walk (forward references); `.set`
        // symbols are defined again in order, earlier ones read from the previous walk.
        let labels: HashMap<String, SymVal> = self
            .symbols
            .iter()
            .filter(|(_, v)| matches!(v, SymVal::Label(..)))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        if !self.symbols.is_empty() {
            self.pass1_symbols = std::mem::replace(&mut self.symbols, labels);
        }
        for (n, v) in &self.opts.defines {
            self.symbols.insert(n.clone(), SymVal::Abs(Val::abs(*v)));
        }
        self.extensions = self.opts.extensions;
        self.run_lines(lines);
        self.finish_sections();
        if pass == 1 {
            self.numeric = std::mem::take(&mut self.numeric_next);
        }
    }

    /// Lays out until addresses stop changing (sizes can depend on later symbols:
    /// `.org`, `.uleb128`, `.space`), then emits.
    pub(super) fn assemble_lines(&mut self, lines: &[Line]) {
        let mut previous = None;
        for _ in 0..6 {
            self.run_pass(lines, 1);
            self.lay_out();
            let now = (
                self.label_values(),
                self.bases.clone(),
                self.offsets.clone(),
            );
            if previous.as_ref() == Some(&now) {
                break;
            }
            previous = Some(now);
            if self.diags.iter().any(|d| d.severity == Severity::Error) {
                break;
            }
        }
        if self.expanded > MAX_EXPANDED {
            return; // reported by the layout walk; a second walk would only repeat it
        }
        self.run_pass(lines, 2);
        self.dwarf_finish_checks();
        self.symver_checks();
    }
}

/// Assembles `source` (named `file_name` in diagnostics) into an executable image at 0.
pub fn assemble(source: &str, file_name: &str, opts: &Options) -> Result<Output, Vec<Diagnostic>> {
    assemble_chars(&bytes_as_text(source.as_bytes()), file_name, opts)
}

/// Assembles `source` into a relocatable object: every section at offset 0, references
/// to addresses left as SPU relocations, undefined symbols external.
pub fn assemble_object(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<(crate::object::Object, Vec<Diagnostic>), Vec<Diagnostic>> {
    assemble_object_chars(&bytes_as_text(source.as_bytes()), file_name, opts)
}

/// `assemble` of a source whose characters are its bytes (`bytes_as_text`).
pub(crate) fn assemble_chars(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<Output, Vec<Diagnostic>> {
    let lines = to_lines(source, file_name);
    let mut asm = Assembler::new(opts, false);
    asm.assemble_lines(&lines);
    let (errors, warnings) = asm.take_diagnostics();
    if !errors.is_empty() {
        return Err(errors);
    }
    write::executable(asm, &lines, file_name, warnings)
}

/// `assemble_object` of a source whose characters are its bytes.
pub(crate) fn assemble_object_chars(
    source: &str,
    file_name: &str,
    opts: &Options,
) -> Result<(crate::object::Object, Vec<Diagnostic>), Vec<Diagnostic>> {
    let lines = to_lines(source, file_name);
    let mut asm = Assembler::new(opts, true);
    asm.assemble_lines(&lines);
    let (errors, warnings) = asm.take_diagnostics();
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok((write::object(asm, file_name), warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(src: &str) -> Vec<u32> {
        let out = assemble(src, "t.s", &Options::default()).unwrap_or_else(|e| {
            panic!(
                "{}",
                e.iter()
                    .map(|d| d.to_string())
                    .collect::<Vec<_>>()
                    .join("\n")
            )
        });
        let text = out.sections[0].2 as usize;
        out.image[..text]
            .chunks(4)
            .map(|c| u32::from_be_bytes([c[0], c[1], c[2], c[3]]))
            .collect()
    }

    #[test]
    fn readme_encodings() {
        assert_eq!(
            words("il $3,42\nfma $7,$6,$5,$4\nlqd $5,32($1)\nbi $3\nbid $3"),
            vec![0x40801503, 0xe0e14304, 0x34008085, 0x35000180, 0x35080180]
        );
    }

    #[test]
    fn labels_locals_and_set_registers() {
        // `1b` on the line that defines `1:` is that very label (offset 0), as in GNU as.
        let w = words(".set R, 5\n1: ai R, R, 1\n brnz R, 1b\n br 2f\n2: stop\n 1: brz R, 1b\n");
        assert_eq!(w[0], 0x1c004285);
        assert_eq!(w[1], 0x217fff85); // brnz $5, -4 bytes
        assert_eq!(w[2], 0x32000080); // br +4
        assert_eq!(w[4], 0x20000005); // brz $5, 0
    }

    #[test]
    fn irp_with_register_expressions() {
        let w = words(".irp J, 0, 1\n ai (\\J+80), (\\J+80), 1\n.endr\n");
        // ai $80,$80,1 and ai $81,$81,1
        assert_eq!(w, vec![0x1c006850, 0x1c0068d1]);
    }

    #[test]
    fn a_parameter_ends_at_its_separator() {
        // `\()` ends a parameter's name (gas's rule; the one `crate::expand` gives `.sched`
        // blocks too): `$\N\()0` with N = 1 is `$10`.
        let w = words(".irp N, 1, 2\n il $\\N\\()0, 5\n.endr\n");
        assert_eq!(w, vec![0x4080028a, 0x40800294]);
    }

    #[test]
    fn alignment_pads_with_nop_and_lnop() {
        // The section end is padded to its alignment too (gas SUB_SEGMENT_ALIGN).
        let w = words("il $3,1\n.align 4\nil $3,2\n");
        assert_eq!(
            w,
            vec![
                0x40800083, 0x00200000, 0x40200000, 0x00200000, 0x40800103, 0x00200000, 0x40200000,
                0x00200000
            ]
        );
    }

    #[test]
    fn errors_name_file_line_column_and_continue() {
        let e = assemble(
            "il $3, 40000\nfoo $1\nai $3,$3,1\nlqd $3, 4($1)\n",
            "bad.s",
            &Options::default(),
        )
        .unwrap_err();
        let text: Vec<String> = e
            .iter()
            .map(|d| format!("{}:{}", d.location.line, d.message))
            .collect();
        assert!(
            text.iter()
                .any(|t| t.starts_with("1:Constant expression 40000 out of range")),
            "{text:?}"
        );
        assert!(
            text.iter().any(|t| t.starts_with("2:Invalid mnemonic")),
            "{text:?}"
        );
    }

    #[test]
    fn string_escapes_and_forward_equ() {
        let out = assemble(
            ".data\nx: .ascii \"\\x41\\101\\n\"\n.text\nil $3, LATER\n.equ LATER, 7\n",
            "t.s",
            &Options::default(),
        )
        .unwrap();
        let data = &out.image[out.sections[1].1 as usize..][..3];
        assert_eq!(data, b"AA\n");
        assert_eq!(&out.image[0..4], &0x40800383u32.to_be_bytes()); // il $3,7
    }
}
