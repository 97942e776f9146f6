//! GNU as 2.40's generic behaviour that its own testsuites `gas/testsuite/gas/all` and
//! `gas/testsuite/gas/macros` check, as `spu as` copies it (issue #31): equates defined
//! twice, `==`, `.warning`/`.error`, `.nop`, `.string16` and kin, macro definitions and
//! arguments, data over equates defined later, preprocessor line markers, quoted and UTF-8
//! symbol names, `.weakref`, the `.dc` family's float forms. Each case was
//! checked against spu-elf-as 2.40 on the same lines (the messages by file and line; the
//! bytes exactly); `tests/tests/gnu_differential.rs` runs the testsuites themselves.

use spu_asm::{assemble_object, Options};

/// The diagnostics of a source GNU as refuses, each as `spu as` prints it.
fn refused(source: &str) -> Vec<String> {
    match assemble_object(source, "t.s", &Options::default()) {
        Ok(_) => panic!("accepted:\n{source}"),
        Err(diags) => diags.iter().map(|d| d.to_string()).collect(),
    }
}

/// A section's bytes and the warnings of a source GNU as accepts.
fn accepted(source: &str, opts: &Options, section: &str) -> (Vec<u8>, Vec<String>) {
    let (obj, warnings) =
        assemble_object(source, "t.s", opts).unwrap_or_else(|e| panic!("{}\n{source}", e[0]));
    let bytes = obj
        .sections
        .iter()
        .find(|s| s.name == section)
        .map(|s| s.data.clone())
        .unwrap_or_default();
    (bytes, warnings.iter().map(|w| w.to_string()).collect())
}

fn data(source: &str) -> Vec<u8> {
    accepted(source, &Options::default(), ".data").0
}

fn words(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_be_bytes()).collect()
}

#[test]
fn a_symbol_defined_twice_by_equates_is_refused_unless_set_again() {
    // read.c assign_symbol: `.set`/`.equ`/`=` may give a value again over their own; an
    // `.equiv`/`.eqv`, a label or a common block is defined for good (all/equ-bad,
    // eqv-bad, equiv1, equiv2, redef4, redef5).
    for (source, error) in [
        (
            "\t.equ x, 1\n\t.eqv x, 2\n",
            "t.s:2:7: error: symbol `x` is already defined",
        ),
        (
            "\t.eqv x, 1\n\t.eqv x, 2\n",
            "t.s:2:7: error: symbol `x` is already defined",
        ),
        (
            "\t.equiv x, y\n\t.equiv y, 1\n\t.equiv x, 0\n",
            "t.s:3:9: error: symbol `x` is already defined",
        ),
        (
            "\t.equiv x, 1\n\t.set x, 2\n",
            "t.s:2:7: error: symbol `x` is already defined",
        ),
        (
            "\t.data\nsym:\n\t.set sym, 0\n",
            "t.s:3:7: error: symbol `sym` is already defined",
        ),
        (
            "\t.comm sym, 1\n\t.set sym, 0\n",
            "t.s:2:7: error: symbol `sym` is already defined",
        ),
    ] {
        assert_eq!(refused(source), [error], "{source}");
    }
    // all/assign-ok: `=` twice, then `==` (`.eqv`) of a new name.
    assert_eq!(
        data("\txxx = 1\n\txxx = 2\n\tyyy == 3\n\t.data\n\t.long xxx, yyy\n\t.equ xxx, 4\n\t.long xxx\n"),
        words(&[2, 3, 4])
    );
}

#[test]
fn eqv_holding_dot_is_evaluated_where_it_is_used() {
    // all/eqv-dot: `y = . - x` is fixed where it is set; `z == . - x` is `. - x` at each use.
    let source = "\t.data\nx:\t.long 0, 1, 2, . - x\n y = . - x\n z == . - x\n\
                  \t.long y\n\t.long z\n\t.long y\n\t.long z\n";
    assert_eq!(data(source), words(&[0, 1, 2, 0xc, 0x10, 0x14, 0x10, 0x1c]));
    // p2425: `NAME==EXPR` without blanks, used before it is defined (where the
    // section ends, here).
    let source = "\t.data\nf:\t.long 1, 2, G\n\tG==.-f\n";
    assert_eq!(data(source), words(&[1, 2, 12]));
}

#[test]
fn warning_and_error_take_a_string_or_nothing() {
    // read.c s_errwarn (all/warn-1), s_err.
    let (_, warnings) = accepted(
        "\t.warning \"a warning message\"\n\t.warning\n\t.warning \"\"\n",
        &Options::default(),
        ".text",
    );
    assert_eq!(
        warnings,
        [
            "t.s:1:2: warning: a warning message",
            "t.s:2:2: warning: .warning directive invoked in source file",
            "t.s:3:2: warning: ",
        ]
    );
    assert_eq!(
        refused("\t.warning a warning message\n"),
        ["t.s:1:2: error: .warning argument must be a string"]
    );
    assert_eq!(
        refused("\t.error\n\t.error \"stop\"\n\t.err\n"),
        [
            "t.s:1:2: error: .error directive invoked in source file",
            "t.s:2:2: error: stop",
            "t.s:3:2: error: .err encountered",
        ]
    );
}

#[test]
fn strings_of_wide_units_and_strings_side_by_side() {
    // all/string, all/asciz.
    let source = "\t.data\n\t.string8 \"ab\"\n\t.string16 \"c\"\n\t.string32 \"d\"\n\
                  \t.string64 \"e\"\n\t.asciz \"f\" \"g\", \"h\"\n\t.ascii \"i\"  \"j\"\n";
    let mut want = b"ab\0".to_vec();
    want.extend([0, b'c', 0, 0]);
    want.extend([0, 0, 0, b'd', 0, 0, 0, 0]);
    want.extend([0, 0, 0, 0, 0, 0, 0, b'e', 0, 0, 0, 0, 0, 0, 0, 0]);
    want.extend(b"fg\0h\0ij");
    assert_eq!(data(source), want);
}

#[test]
fn dot_nop_is_one_no_op_word() {
    let (text, _) = accepted("\t.text\n\t.nop\n\t.nop 8\n", &Options::default(), ".text");
    assert_eq!(text, [0x40, 0x20, 0, 0].repeat(3));
}

#[test]
fn macro_definitions_gas_refuses() {
    // macro.c define_macro and do_formals (macros/badarg, macros/redef).
    for (source, error) in [
        ("\t.macro\n\t.endm\n", "t.s:1:1: error: Missing macro name"),
        (
            "\t.macro ,arg1\n\t.endm\n",
            "t.s:1:1: error: Missing macro name",
        ),
        (
            "\t.macro m1,\n\t.endm\n",
            "t.s:1:1: error: Bad parameter list for macro `m1'",
        ),
        (
            "\t.macro m2,,\n\t.endm\n",
            "t.s:1:1: error: Bad parameter list for macro `m2'",
        ),
        (
            "\t.macro m4,,a\n\t.endm\n",
            "t.s:1:1: error: Bad parameter list for macro `m4'",
        ),
        (
            "\t.macro m5,arg,arg\n\t.endm\n",
            "t.s:1:1: error: A parameter named `arg' already exists for macro `m5'",
        ),
        (
            "\t.macro m\n\t.endm\n\t.macro m\n\t.endm\n",
            "t.s:3:1: error: Macro `m' was already defined",
        ),
        (
            "\t.altmacro\n\t.macro m6,arg\n\tlocal arg\n\t.endm\n\tm6\n",
            "t.s:3:1: error: `arg' was already used as parameter (or another local) name",
        ),
    ] {
        assert_eq!(refused(source), [error], "{source}");
    }
}

#[test]
fn a_pseudo_op_name_is_the_pseudo_op_even_with_a_macro_of_that_name() {
    // tc-spu.h NO_PSEUDO_DOT: `DEF` is `.def` before any macro (macros/altmacro).
    let diags = refused("\t.macro DEF\n\t.long 1\n\t.endm\n\tDEF\n");
    assert_eq!(
        diags,
        [
            "t.s:1:1: warning: attempt to redefine pseudo-op `def' ignored",
            "t.s:4:2: error: .set needs a name and a value",
        ]
    );
}

#[test]
fn macro_arguments_as_gas_takes_them() {
    // macros/strings: a quoted argument loses its quotes and keeps its escapes.
    let source = "\t.macro M arg1\n\t.ascii \"\\arg1\"\n\t.endm\n\t.data\n\
                  \tM \"\\\\\\\"foo\\\\\\\"\"\n\tM \"bar\"\n\tM baz\n";
    assert_eq!(data(source), b"\\\"foo\\\"barbaz".to_vec());
    // macros/vararg: blanks around `:`; the rest of the arguments for the last.
    let source = "\t.macro v1 arg1 : req, args : vararg\n\t.long \\arg1\n\t.ifnb \\args\n\
                  \tv1 \\args\n\t.endif\n\t.endm\n\t.data\n\tv1 1\n\tv1 2, 3\n\tv1 4, 5, 6\n";
    assert_eq!(data(source), words(&[1, 2, 3, 4, 5, 6]));
    // all/altmac2 under `--alternate`: `&str` in a string is the parameter; `!` escapes.
    let opts = Options {
        alternate: true,
        ..Options::default()
    };
    let source = ".macro\tm1 str\n\t.ascii\t\"&str\"\n.endm\n\t.data\nm1\t<!>!<!!>\n";
    assert_eq!(accepted(source, &opts, ".data").0, b"><!".to_vec());
    // all/altmacro: `!` escapes in a quoted argument too; `&str` outside quotes.
    let source = ".macro\tm3 str\n\t.ascii\t&str\n.endm\n\t.data\nm3\t\"!!<>'\"\n";
    assert_eq!(accepted(source, &opts, ".data").0, b"!<>'".to_vec());
}

#[test]
fn data_over_an_equate_defined_later_must_fit_its_field() {
    // all/overflow: a value known only later is gas's fixup, refused where it does not
    // fit (write.c fixup_segment); a value known now is truncated with a warning.
    let diags = refused(
        "\t.data\n\t.dc.b 0x100\n\t.dc.b zero+0x80\n\t.dc.b zero+0x100\n\
         \t.dc.b zero-0x100\n\t.equ zero, 0\n",
    );
    assert_eq!(
        diags,
        [
            "t.s:2:8: warning: value 0x100 truncated to 0x0",
            "t.s:4:8: error: value of 256 too large for field of 1 byte at 00000002",
            "t.s:5:8: error: value of ffffff00 too large for field of 1 byte at 00000003",
        ]
    );
}

#[test]
fn line_markers_renumber_the_lines_after_them() {
    // all/cond-2, all/linefile: `# N "FILE"` in the first column, even in a false `.if`;
    // a leading zero, a number past INT_MAX or no file name make it a comment.
    let source = "\t.if 0\n# 1003 \"t.s\"\n\t.endif\n\n\t.warning \"a\"\n# 07 \"x.s\"\n\
                  \t.warning \"b\"\n# 20 \"y.s\" 1\n\t.warning \"c\"\n";
    let (_, warnings) = accepted(source, &Options::default(), ".text");
    assert_eq!(
        warnings,
        [
            "t.s:1005:2: warning: a",
            "t.s:1007:2: warning: b",
            "y.s:20:2: warning: c",
        ]
    );
}

#[test]
fn endc_ends_a_conditional_and_huge_local_labels_are_refused() {
    // all/cond (`.endc`), all/local-label-overflow.
    assert_eq!(
        data("\t.data\n\t.if 1\n\t.long 1\n\t.endc\n\t.if 0\n\t.long 2\n\t.endc\n"),
        words(&[1])
    );
    assert_eq!(
        refused("8888888888888888888888888888:\n"),
        ["t.s:1:1: error: local label too large near 8888888888888888888888888888:"]
    );
}

#[test]
fn psize_wants_absolute_numbers_and_a_useful_width() {
    // all/pr27384 (listing.c listing_psize).
    assert_eq!(
        refused("\t.psize f,-7\n\t.psize 60, 132\n"),
        [
            "t.s:1:2: error: bad or irreducible absolute expression",
            "t.s:1:2: error: new paper width is too small",
        ]
    );
}

/// An object's symbols as (name, value, global, weak, defined).
fn symbols(source: &str) -> Vec<(String, u64, bool, bool, bool)> {
    let (obj, _) =
        assemble_object(source, "t.s", &Options::default()).unwrap_or_else(|e| panic!("{}", e[0]));
    obj.symbols
        .iter()
        .filter(|s| s.kind != 3)
        .map(|s| {
            let defined = s.section != spu_asm::object::SymSection::Undefined;
            (s.name.clone(), s.value, s.global, s.weak, defined)
        })
        .collect()
}

#[test]
fn quoted_symbol_names_take_any_characters() {
    // read.c get_symbol_name: `\` keeps the next character, quoted pieces side by side
    // make one name (all/quoted-sym-names.s).
    let got = symbols("\t.data\n\t.globl \"test-a\"\n\"test-a\": .byte 1\n\"back\\\"slash\": .byte 2\n\"back\"\"slash\": .byte 3\n");
    let want = [
        ("test-a", 0, true),
        ("back\"slash", 1, false),
        ("backslash", 2, false),
    ];
    let want: Vec<_> = want
        .iter()
        .map(|&(n, v, g)| (n.to_string(), v, g, false, true))
        .collect();
    assert_eq!(got, want);
}

#[test]
fn symbol_names_may_hold_utf8() {
    // Bytes 128-255 are name characters to gas's lexer; the name keeps its UTF-8 bytes
    // (all/multibyte.s).
    let got = symbols("\t.text\n\t.globl h\u{e9}\nh\u{e9}:\n\tnop\n");
    assert_eq!(got, vec![("h\u{e9}".to_string(), 0, true, false, true)]);
}

#[test]
fn weakref_aliases_stand_for_their_targets() {
    // read.c s_weakref (all/weakref1.s): the alias is never in the table; a target only
    // used through an alias is weak, one also used by itself global, one never used
    // absent; the relocations name the target.
    let source = "\t.text\n\t.long Wa\n\t.weakref Wa, a\n\t.weakref Wb, b\n\t.long Wb\n\t.long b\n\t.weakref Wn, n\n";
    let got = symbols(source);
    let want = vec![
        ("a".to_string(), 0, true, true, false),
        ("b".to_string(), 0, true, false, false),
    ];
    assert_eq!(got, want);
    let (obj, _) = assemble_object(source, "t.s", &Options::default()).unwrap();
    let targets: Vec<_> = obj.sections[0]
        .relocs
        .iter()
        .map(|r| r.target.clone())
        .collect();
    let named = |n: &str| spu_asm::RelocTarget::Symbol(n.to_string());
    assert_eq!(targets, vec![named("a"), named("b"), named("b")]);
    assert_eq!(
        refused("\t.weakref a, b\n\t.weakref b, a\n\t.weakref c\n"),
        [
            "t.s:2:2: error: b: would close weakref loop: b => a => b",
            "t.s:3:2: error: expected comma after \"c\"",
        ]
    );
}

#[test]
fn float_forms_of_the_dc_family() {
    // read.c parse_one_float/hex_float/s_float_space (all/float.s): any `0LETTER` before a
    // float, `:HEX` giving the bytes from the first, `.dcb.*` repeating one float (zero
    // when none is given), `.ds.x` filling 12-byte units sign-extended; hex too long for
    // the float stores nothing.
    let source = "\t.data\n\t.single 0r1.5\n\t.single 0f:1234\n\t.double 0d:1\n\t.dc.x 0x:1_2\n\t.dcb.s 2, 0s:4321\n\t.dcb.d 1\n\t.ds.x 1, -2\n\t.single 0f:123456789\n";
    let (bytes, warnings) = accepted(source, &Options::default(), ".data");
    let want = words(&[
        0x3fc0_0000,
        0x1234_0000,
        0x1000_0000,
        0,
        0x1200_0000,
        0,
        0,
        0x4321_0000,
        0x4321_0000,
        0,
        0,
        0xffff_ffff,
        0xffff_ffff,
        0xffff_fffe,
    ]);
    assert_eq!(bytes, want);
    assert_eq!(
        warnings,
        ["t.s:9:2: warning: floating point constant too large"]
    );
    // SPU's gas has no decimal extended floats.
    assert_eq!(
        refused("\t.data\n\t.dc.x 1.0\n"),
        ["t.s:2:2: error: bad floating literal: Unrecognized or unsupported floating point constant"]
    );
}
