//! Behaviours of GNU as for SPU (binutils gas/config/tc-spu.c, gas/expr.c, gas/write.c)
//! that are easy to get wrong, one test each.

use spu_asm::{assemble, Options, Severity};

fn out(src: &str) -> spu_asm::Output {
    assemble(src, "t.s", &Options::default()).unwrap_or_else(|e| {
        panic!(
            "{}",
            e.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        )
    })
}

fn text_words(src: &str) -> Vec<u32> {
    let o = out(src);
    let size = o.sections[0].2 as usize;
    o.image[..size]
        .chunks(4)
        .map(|c| u32::from_be_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

fn warnings(src: &str) -> Vec<String> {
    out(src)
        .warnings
        .iter()
        .map(|w| w.message.clone())
        .collect()
}

fn errors(src: &str) -> Vec<String> {
    match assemble(src, "t.s", &Options::default()) {
        Ok(_) => vec![],
        Err(d) => d
            .iter()
            .filter(|d| d.severity == Severity::Error)
            .map(|d| d.message.clone())
            .collect(),
    }
}

#[test]
fn expression_precedence_is_gas_not_c() {
    // expr.c op_rank: * / % << >> (8) > | ! ^ & (7) > + - (5) > comparisons (4) > && (3) > || (2).
    let w = text_words(
        "il $3, 1 + 2 & 3\nil $3, 1 << 2 + 1\nil $3, 2 + 3 == 5\nil $3, 0 || 1 && 0\nil $3, 1 ! 0\nil $3, -16 >> 28\n",
    );
    let imm = |w: u32| ((w >> 7) & 0xffff) as i16 as i32;
    assert_eq!(imm(w[0]), 3); // 1 + (2 & 3)
    assert_eq!(imm(w[1]), 5); // (1 << 2) + 1
    assert_eq!(imm(w[2]), -1); // (2 + 3) == 5 is -1
    assert_eq!(imm(w[3]), 0); // 0 || (1 && 0)
    assert_eq!(imm(w[4]), -1); // 1 | ~0
                               // >> is unsigned on 64 bits, then the operand keeps the low 32 bits: 0xffffffff -> -1.
    assert_eq!(imm(w[5]), -1);
}

#[test]
fn constant_branch_operands_are_offsets_labels_are_addresses() {
    // tc-spu.c get_imm: a constant goes into the field as is (>> 2); a label is PC-relative.
    let w = text_words("nop\nnop\nbr 8\nbr .+8\nt: br t\nhbrr 8, 16\n");
    assert_eq!(w[2], 0x32000100); // br 8: offset 2 words
    assert_eq!(w[3], 0x32000100); // br .+8: the same
    assert_eq!(w[4], 0x32000000); // br to itself
    assert_eq!(w[5], 0x12000202); // hbrr: brinst 8 -> 2, target 16 -> 4
}

#[test]
fn at_h_and_at_l_apply_to_the_whole_expression() {
    let w = text_words(
        ".set v, 0x1234fff0\nilhu $3, v+0x10@h\niohl $3, v+0x10@l\nilhu $4, 0x12345678@h\n",
    );
    assert_eq!((w[0] >> 7) & 0xffff, 0x1235);
    assert_eq!((w[1] >> 7) & 0xffff, 0x0000);
    assert_eq!((w[2] >> 7) & 0xffff, 0x1234);
}

#[test]
fn range_warnings_and_errors_follow_arg_encode() {
    // A_S7 (rotmi): error outside -64..63, warning outside -63..0.
    assert_eq!(
        warnings("rotmi $3,$4,5"),
        ["Constant expression 5 out of range, [-63, 0]."]
    );
    assert!(warnings("rotmi $3,$4,-7").is_empty());
    assert_eq!(
        errors("rotmi $3,$4,64"),
        ["Constant expression 64 out of range, [-64, 63]."]
    );
    // A_U5 (shlqbyi): warning above 31, error above 127.
    assert_eq!(
        warnings("shlqbyi $3,$4,32"),
        ["Constant expression 32 out of range, [0, 31]."]
    );
    // A_U7 / A_S7N / A_U3: no check, the low 7 bits are kept.
    assert_eq!(text_words("roti $3,$4,200")[0], 0x0f120203);
    // Byte immediates: warning outside -128..255.
    assert_eq!(
        warnings("andbi $3,$4,256"),
        ["Constant expression 256 out of range, [-128, 255]."]
    );
    // lqd: an offset that is not a multiple of 16 is shifted silently.
    assert!(warnings("lqd $3,20($1)").is_empty());
    assert_eq!(
        text_words("lqd $3,20($1)\nlqd $3,-4($1)"),
        [0x34004083, 0x34ffc083]
    );
    // Branch distances are checked on addresses.
    let far = "br t\n.space 0x40000\nt: nop\n";
    assert!(
        errors(far)
            .iter()
            .any(|e| e.starts_with("Relocation doesn't fit")),
        "{:?}",
        errors(far)
    );
}

#[test]
fn alternate_forms_are_chosen_by_operand_shape() {
    assert_eq!(
        text_words("nop\nnop $5\nstop\nstop 0x2000\nhgt $3,$4\nfscrwr $5\n"),
        // `nop $5` is gas's `.nop` pseudo-op (read without its dot): the operand is
        // dropped, as spu-elf-as 2.40 writes it.
        [0x40200000, 0x40200000, 0x00000000, 0x00002000, 0x4b010180, 0x77400280]
    );
}

#[test]
fn register_operands_accept_names_and_constant_expressions() {
    let w = text_words(".set R, 5\nai R, $sp, (R+1)\nrdch $3, $MFC_RdTagStat\nrdch $3, $ch24\nwrch 21, $3\nmfspr $3,$sp2\nlr $lr, $fp\n");
    assert_eq!(w[0], 0x1c018085); // ai $5,$1,6
    assert_eq!(w[1], 0x01a00c03);
    assert_eq!(w[2], 0x01a00c03);
    assert_eq!(w[3], 0x21a00a83);
    assert_eq!(w[4], 0x01800103);
    assert_eq!(w[5], 0x04003f80); // ori $0,$127,0
}

#[test]
fn section_end_is_padded_to_its_alignment_with_nop_lnop() {
    // write.c SUB_SEGMENT_ALIGN (HANDLE_ALIGN defined): the last frag is aligned too.
    let w = text_words("il $3,1\n.align 4\nil $3,2\n");
    assert_eq!(
        w,
        [
            0x40800083, 0x00200000, 0x40200000, 0x00200000, 0x40800103, 0x00200000, 0x40200000,
            0x00200000
        ]
    );
    // A leading partial word is zero bytes.
    let o = out(".byte 1\n.align 3\n");
    assert_eq!(&o.image[..8], &[1, 0, 0, 0, 0x00, 0x20, 0, 0]);
}

#[test]
fn syntax_errors_name_the_argument_like_gas() {
    let e = errors("ai $3,$4\n");
    assert_eq!(e, ["Error in argument 3.  Expecting:  \"ai\treg,reg,IMM\""]);
    assert_eq!(errors("frob $3"), ["Invalid mnemonic 'frob'"]);
}

/// GNU's nesting limits, not lower ones: 100 macro expansions inside one another
/// (macro.c's max_macro_nest) assemble, the 101st is "macros nested too deeply"; and
/// repetitions nest 200 deep. On a test thread's stack, so the host's stack holds them.
#[test]
fn nesting_as_deep_as_gnu_allows() {
    let deep = |levels: i64| {
        format!(
            ".macro down n\n.if \\n\n.byte \\n\ndown \\n-1\n.endif\n.endm\n.data\ndown {levels}\n"
        )
    };
    let o = out(&deep(99)); // 100 expansions: 99 .. 1, then 0
    let data = &o.image[o.sections[1].1 as usize..][..99];
    assert_eq!(data[0], 99);
    assert_eq!(data[98], 1);
    assert_eq!(
        errors(&deep(100)),
        vec!["macros nested too deeply".to_string()]
    );
    let mut src = String::from(".data\n");
    for _ in 0..200 {
        src.push_str(".rept 1\n");
    }
    src.push_str(".byte 7\n");
    for _ in 0..200 {
        src.push_str(".endr\n");
    }
    let out = out(&src);
    assert_eq!(out.image[out.sections[1].1 as usize], 7);
}

/// A file that includes itself stops at the nesting bound with an error, not a stack
/// overflow (on a test thread's stack).
#[test]
fn self_inclusion_stops_at_the_bound() {
    let opts = Options {
        virtual_files: vec![("self.s".into(), ".include \"self.s\"\n".into())],
        ..Default::default()
    };
    let e = assemble(".include \"self.s\"\n", "t.s", &opts).unwrap_err();
    assert!(
        e.iter()
            .any(|d| d.message == "macros, includes or repetitions nested too deeply"),
        "{e:?}"
    );
}
