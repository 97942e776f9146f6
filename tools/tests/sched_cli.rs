//! `spu sched` reads gas syntax with the assembler's own lexer and `.irp` expander: a `#`
//! inside a string is not a comment, and `/* */` comments (on a line, or across lines
//! around an old `.sched` block) are comments. Its former stripper split every line at
//! the first `#` and knew no `/* */`, so this file failed three ways: the include's name
//! was cut at `#`, the commented-out block was taken for a real one, and `/* two
//! registers */` was read as a `.sched` option.

use std::path::PathBuf;
use std::process::Command;

const REGS: &str = "        .set    A, 10           # the inputs
        .set    B, 11
/*      .set    A, 99           an old name, kept in a comment */
";

const SOURCE: &str = r#"        .include "regs#1.inc"
/* the block as it was:
        .sched  pool=30-31
        a       %t, A, B
        .endsched
*/
        .sched  pool=20-21      /* two registers */
        a       %s, A, B        /* the sum */
        ai      %t, %s, 1       # one more
        stqd    %t, 0($3)
        .endsched
        stop
"#;

fn dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-sched-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn comments_and_strings_are_read_as_the_assembler_reads_them() {
    let dir = dir();
    std::fs::write(dir.join("regs#1.inc"), REGS).unwrap();
    let src = dir.join("block.s");
    std::fs::write(&src, SOURCE).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(["sched", src.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    // The comment lines pass through untouched; the block is scheduled with A and B
    // from the include ($10 and $11: `a` waits for nothing, `ai` two cycles for `a`,
    // `stqd` two for `ai`), the `/* */` comment dropped and the `#` comment kept.
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        r#"        .include "regs#1.inc"
/* the block as it was:
        .sched  pool=30-31
        a       %t, A, B
        .endsched
*/
# .sched  pool=20-21      /* two registers */: 3 instructions in 5 cycles (scheduler's model)
	.align	3
	a       $20, A, B
	lnop
	ai      $21, $20, 1   # one more
	lnop
	nop
	stqd    $21, 0($3)
        stop
"#
    );
    assert_eq!(
        stderr,
        format!(
            "{}:7: 3 instructions in 5 cycles (scheduler's model)\n",
            src.display()
        )
    );
    // The assembler reads the file the same way: its `.sched` block assembles to the
    // words of the schedule above, `a $20, $10, $11` first.
    let scheduled = dir.join("scheduled.s");
    std::fs::write(&scheduled, &out.stdout).unwrap();
    let image = |source: &PathBuf| {
        let bin = source.with_extension("bin");
        let out = Command::new(env!("CARGO_BIN_EXE_spu"))
            .args(["as", source.to_str().unwrap(), "--format", "bin", "-o"])
            .arg(&bin)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(bin).unwrap()
    };
    let words = image(&src);
    assert_eq!(words, image(&scheduled));
    assert_eq!(words[..4], 0x1802_c514u32.to_be_bytes());
}
