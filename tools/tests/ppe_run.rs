//! `spu run` of spu-gcc-style programs linked with the built-in runtime (`spu as
//! --runtime`): the start state and argv as `elfspe` passed them, every PPE-assisted call
//! the host serves, and each way a program is stopped (bad pointer, `%n`, unknown class or
//! opcode, a path outside `--root`, too many files, arguments too large), by exact standard
//! output, standard error and exit status.

use std::path::{Path, PathBuf};
use std::process::Command;

fn dir(test: &str) -> PathBuf {
    crate::support::fresh_dir("ppe", test)
}

use crate::support::spu_in as spu;

/// Assembles `source` with the runtime into `dir/prog.elf`.
fn build(dir: &Path, source: &str) {
    std::fs::write(dir.join("prog.s"), source).unwrap();
    let (_, err, code) = spu(&["as", "--runtime", "prog.s", "-o", "prog.elf"], dir);
    assert_eq!(code, 0, "spu as --runtime: {err}");
}

/// main(argc, argv): prints argc and each argument, returns 3.
const ARGV: &str = r#"
        .section .rodata
.LC0:   .string "argc=%d\n"
.LC1:   .string "argv[%d]=%s\n"
        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $82, -48($sp)
        stqd    $sp, -80($sp)
        ai      $sp, $sp, -80
        ori     $80, $3, 0
        ori     $81, $4, 0
        ila     $3, .LC0
        ori     $4, $80, 0
        brsl    $lr, printf
        il      $82, 0
.L2:    ceq     $5, $82, $80
        brnz    $5, .L3
        shli    $5, $82, 2
        a       $6, $81, $5
        lqd     $7, 0($6)
        rotqby  $7, $7, $6
        ila     $3, .LC1
        ori     $4, $82, 0
        ori     $5, $7, 0
        brsl    $lr, printf
        ai      $82, $82, 1
        br      .L2
.L3:    il      $3, 3
        ai      $sp, $sp, 80
        lqd     $82, -48($sp)
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
"#;

#[test]
fn main_gets_argc_and_argv_and_its_return_is_the_exit_status() {
    let d = dir("argv");
    build(&d, ARGV);
    let (out, err, code) = spu(&["run", "-q", "prog.elf", "--", "one", "two words", ""], &d);
    assert_eq!(
        out,
        "argc=4\nargv[0]=prog.elf\nargv[1]=one\nargv[2]=two words\nargv[3]=\n"
    );
    assert_eq!(err, "");
    assert_eq!(code, 3);
}

#[test]
fn dump_entry_shows_the_start_state() {
    let d = dir("entry");
    std::fs::write(
        d.join("p.s"),
        ".text\n.global _start\n_start: stop 0x2000\n",
    )
    .unwrap();
    spu(&["as", "p.s", "-o", "p.elf"], &d);
    let (out, _, code) = spu(&["run", "--dump-entry", "-q", "p.elf", "--", "ab"], &d);
    assert_eq!(code, 0);
    assert_eq!(
        out,
        "entry registers (all others zero):\n\
         $1: 0003ffd0 0003ff50 00000000 00000000\n\
         $3: 00000002 00000000 00000000 00000000\n\
         $4: 0003ffe0 00000000 000fff80 00000020\n\
         argv region: 32 bytes at local store 0x3ffe0, main memory 0xfff80\n\
         3ffe0: 00 03 ff ec 00 03 ff f2 00 00 00 00 70 2e 65 6c\n\
         3fff0: 66 00 61 62 00 00 00 00 00 00 00 00 00 00 00 00\n"
    );
    let (out, _, code) = spu(
        &[
            "run",
            "--dump-entry",
            "-q",
            "p.elf",
            "--argp",
            "0x100000020",
            "--envp",
            "7",
        ],
        &d,
    );
    assert_eq!(code, 0);
    assert_eq!(
        out,
        "entry registers (all others zero):\n\
         $1: 0003fff0 0003ff70 00000000 00000000\n\
         $3: 00000000 53504530 00000000 00000000\n\
         $4: 00000001 00000020 00000000 00000000\n\
         $5: 00000000 00000007 00000000 00000000\n"
    );
}

#[test]
fn the_stack_starts_below_the_arguments() {
    // Stores through $1 at entry (what compiled code does first) and reads argv[1].
    let d = dir("stack");
    std::fs::write(
        d.join("p.s"),
        ".text\n.global _start\n_start: stqd $3, -16($1)\n stop 0x2000\n",
    )
    .unwrap();
    spu(&["as", "p.s", "-o", "p.elf"], &d);
    let (out, _, code) = spu(&["run", "p.elf", "--dump-ls", "0x3ffc0:48", "--", "x"], &d);
    assert_eq!(code, 0);
    // $3 (argc = 2) below $1 = 0x3ffd0, the null back chain at $1, then the argv region.
    assert!(
        out.ends_with(
            "3ffc0: 00 00 00 02 00 00 00 00 00 00 00 00 00 00 00 00\n\
             3ffd0: 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00 00\n\
             3ffe0: 00 03 ff ec 00 03 ff f2 00 00 00 00 70 2e 65 6c\n"
        ),
        "{out}"
    );
}

#[test]
fn arguments_larger_than_elfspe_passes_are_refused_before_the_run() {
    let d = dir("bigargv");
    build(&d, ARGV);
    let big = "x".repeat(5000);
    let (out, err, code) = spu(&["run", "prog.elf", "--", &big], &d);
    assert_eq!(out, "");
    assert_eq!(
        err,
        "spu: prog.elf: the program's arguments take 5024 bytes; elfspe passes at most 4096 \
         (SPE_ARG_MAX)\n"
    );
    assert_eq!(code, 2);
}

/// The C99 calls: printf's conversions (vectors too), puts, putchar, stderr, sprintf and
/// snprintf, and a file written, read back, sought and removed under `--root`.
const STDIO: &str = r#"
        .section .rodata
        .align  4
.Lpi:   .long   0x400921f9, 0xf01b866e, 0, 0
.Ltiny: .long   0x3ee4f8b5, 0x88e368f1, 0, 0
.Lone:  .long   0x3ff00000, 0, 0, 0
.Lbytes: .byte  1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16
.Lwords: .long  10, 11, 12, 13
.Lfloats: .long 0x3f800000, 0x40200000, 0xbf000000, 0
.Lints: .string "%d|%5d|%-5d|%05d|%+d|%x|%#X|%o|%u|%c|%s|%.2s|%p|%p|%s|%%|%lld|%hhd\n"
.Lstr:  .string "str"
.Lflt:  .string "%f %.3e %g %g %a %8.2f|%-8.1e|%G\n"
.Lvec:  .string "%vd / %,vlx / %vf / %:vhu\n"
.Lhello: .string "hello"
.Lerr:  .string "to stderr %d\n"
.Lsfmt: .string "%s-%d"
.Lab:   .string "ab"
.Lnum:  .string "%d"
.Lret:  .string "sprintf=%d snprintf=%d\n"
.Lname: .string "out.txt"
.Lw:    .string "w"
.Lr:    .string "r"
.Lline: .string "line one\n"
.Lnfmt: .string "n=%d\n"
.Lxyz:  .string "xyz"
.Ltell: .string "tell=%d getc=%c read=%d eof=%d again=%c removed=%d\n"
.Lesc:  .string "../escape.txt"
.Labs:  .string "/etc/passwd"
.Lfopen: .string "fopen"
.Lnull: .string "escape=%d abs=%d\n"
        .data
        .align  4
buf:    .space  64
buf2:   .space  64

        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $80, -16($sp)
        stqd    $81, -32($sp)
        stqd    $82, -48($sp)
        stqd    $83, -64($sp)
        stqd    $84, -80($sp)
        stqd    $85, -96($sp)
        stqd    $sp, -160($sp)
        ai      $sp, $sp, -160

        ila     $3, .Lints
        il      $4, -42
        il      $5, 42
        il      $6, 42
        il      $7, 42
        il      $8, 42
        il      $9, 255
        il      $10, 255
        il      $11, 8
        il      $12, -1
        il      $13, 65
        ila     $14, .Lstr
        ila     $15, .Lstr
        il      $16, 0x1234
        il      $17, 0
        il      $18, 0
        il      $19, 1
        il      $20, 0x1ff
        brsl    $lr, printf

        ila     $3, .Lflt
        lqr     $4, .Lpi
        lqr     $5, .Lpi
        lqr     $6, .Lpi
        lqr     $7, .Ltiny
        lqr     $8, .Lone
        lqr     $9, .Lpi
        lqr     $10, .Ltiny
        lqr     $11, .Ltiny
        brsl    $lr, printf

        ila     $3, .Lvec
        lqr     $4, .Lbytes
        lqr     $5, .Lwords
        lqr     $6, .Lfloats
        lqr     $7, .Lwords
        brsl    $lr, printf

        ila     $3, .Lhello
        brsl    $lr, puts
        il      $3, 33
        brsl    $lr, putchar
        il      $3, 10
        brsl    $lr, putchar

        ila     $3, stderr
        lqd     $3, 0($3)
        ila     $4, .Lerr
        il      $5, 7
        brsl    $lr, fprintf

        ila     $3, buf
        ila     $4, .Lsfmt
        ila     $5, .Lab
        il      $6, 12
        brsl    $lr, sprintf
        ori     $80, $3, 0
        ila     $3, buf
        brsl    $lr, puts
        ila     $3, buf
        il      $4, 4
        ila     $5, .Lnum
        ilhu    $6, 1
        iohl    $6, 0xe240              # 123456
        brsl    $lr, snprintf
        ori     $81, $3, 0
        ila     $3, buf
        brsl    $lr, puts
        ila     $3, .Lret
        ori     $4, $80, 0
        ori     $5, $81, 0
        brsl    $lr, printf

        # write out.txt
        ila     $3, .Lname
        ila     $4, .Lw
        brsl    $lr, fopen
        ori     $80, $3, 0
        ila     $3, .Lline
        ori     $4, $80, 0
        brsl    $lr, fputs
        ori     $3, $80, 0
        ila     $4, .Lnfmt
        il      $5, 5
        brsl    $lr, fprintf
        ila     $3, .Lxyz
        il      $4, 1
        il      $5, 3
        ori     $6, $80, 0
        brsl    $lr, fwrite
        il      $3, 10
        ori     $4, $80, 0
        brsl    $lr, fputc
        ori     $3, $80, 0
        brsl    $lr, fclose

        # read it back
        ila     $3, .Lname
        ila     $4, .Lr
        brsl    $lr, fopen
        ori     $80, $3, 0
        ila     $3, buf
        il      $4, 64
        ori     $5, $80, 0
        brsl    $lr, fgets
        ila     $3, buf
        ila     $4, stdout
        lqd     $4, 0($4)
        brsl    $lr, fputs
        ori     $3, $80, 0
        brsl    $lr, ftell
        ori     $81, $3, 0
        ori     $3, $80, 0
        brsl    $lr, fgetc
        ori     $82, $3, 0
        ori     $3, $82, 0
        ori     $4, $80, 0
        brsl    $lr, ungetc
        ila     $3, buf2
        il      $4, 1
        il      $5, 20
        ori     $6, $80, 0
        brsl    $lr, fread
        ori     $83, $3, 0
        ori     $3, $80, 0
        brsl    $lr, feof
        ori     $84, $3, 0
        ori     $3, $80, 0
        il      $4, 0
        il      $5, 0
        brsl    $lr, fseek
        ori     $3, $80, 0
        brsl    $lr, fgetc
        ori     $85, $3, 0
        ori     $3, $80, 0
        brsl    $lr, fclose
        ila     $3, .Lname
        brsl    $lr, remove
        ori     $9, $3, 0
        ila     $3, .Ltell
        ori     $4, $81, 0
        ori     $5, $82, 0
        ori     $6, $83, 0
        ori     $7, $84, 0
        ori     $8, $85, 0
        brsl    $lr, printf
        ila     $3, buf2
        ila     $4, stdout
        lqd     $4, 0($4)
        brsl    $lr, fputs

        # paths outside the root
        ila     $3, .Lesc
        ila     $4, .Lr
        brsl    $lr, fopen
        ori     $80, $3, 0
        ila     $3, .Lfopen
        brsl    $lr, perror
        ila     $3, .Labs
        ila     $4, .Lr
        brsl    $lr, fopen
        ori     $5, $3, 0
        ila     $3, .Lnull
        ori     $4, $80, 0
        brsl    $lr, printf

        il      $3, 0
        ai      $sp, $sp, 160
        lqd     $85, -96($sp)
        lqd     $84, -80($sp)
        lqd     $83, -64($sp)
        lqd     $82, -48($sp)
        lqd     $81, -32($sp)
        lqd     $80, -16($sp)
        lqd     $lr, 16($sp)
        bi      $lr
"#;

#[test]
fn c99_calls() {
    let d = dir("c99");
    build(&d, STDIO);
    std::fs::create_dir(d.join("root")).unwrap();
    let (out, err, code) = spu(&["run", "-q", "--root", "root", "prog.elf"], &d);
    assert_eq!(
        out,
        "-42|   42|42   |00042|+42|ff|0XFF|10|4294967295|A|str|st|0x1234|(nil)|(null)|%|\
         4294967297|-1\n\
         3.141590 3.142e+00 3.14159 1e-05 0x1p+0     3.14|1.0e-05 |1E-05\n\
         1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 / a,b,c,d / 1.000000 2.500000 -0.500000 \
         0.000000 / 0:10:0:11:0:12:0:13\n\
         hello\n!\n\
         ab-12\n123\nsprintf=5 snprintf=6\n\
         line one\n\
         tell=9 getc=n read=8 eof=1 again=l removed=0\n\
         n=5\nxyz\n\
         escape=0 abs=0\n"
    );
    assert_eq!(err, "to stderr 7\nfopen: Permission denied\n");
    assert_eq!(code, 0);
    assert!(!d.join("root/out.txt").exists());
}

/// The POSIX.1 calls on a file under `--root`, and their errno values.
const POSIX: &str = r#"
        .section .rodata
.Lname: .string "p.bin"
.Ldata: .string "abcdef"
.Lraw:  .string "raw\n"
.Lfmt:  .string "fd=%d wrote=%d seek=%d read=%d '%s' fsize=%d dup=%d ssize=%d mode=%o\n"
.Lfmt2: .string "unlink=%d reopen=%d errno=%d badwrite=%d errno=%d time=%d stdin=%o\n"
        .data
        .align  4
buf:    .space  64
st:     .space  64

        .text
        .global main
        .type   main, @function
main:   stqd    $lr, 16($sp)
        stqd    $sp, -256($sp)
        ai      $sp, $sp, -256
        # fd = open("p.bin", O_WRONLY|O_CREAT|O_TRUNC, 0644); write(fd, "abcdef", 6)
        ila     $3, .Lname
        il      $4, 0x241
        il      $5, 0x1a4
        brsl    $lr, open
        stqd    $3, 32($sp)
        ila     $4, .Ldata
        il      $5, 6
        brsl    $lr, write
        stqd    $3, 48($sp)
        lqd     $3, 32($sp)
        brsl    $lr, close
        # fd = open("p.bin", O_RDWR); lseek(fd, 2, SEEK_SET); read(fd, buf, 10)
        ila     $3, .Lname
        il      $4, 2
        il      $5, 0
        brsl    $lr, open
        stqd    $3, 64($sp)
        il      $4, 2
        il      $5, 0
        brsl    $lr, lseek
        stqd    $3, 80($sp)
        lqd     $3, 64($sp)
        ila     $4, buf
        il      $5, 10
        brsl    $lr, read
        stqd    $3, 96($sp)
        # fstat(fd, &st): size is word 7
        lqd     $3, 64($sp)
        ila     $4, st
        brsl    $lr, fstat
        ila     $4, st
        lqd     $4, 16($4)
        rotqbyi $4, $4, 12
        stqd    $4, 112($sp)
        # dup, ftruncate(fd, 3), stat("p.bin")
        lqd     $3, 64($sp)
        brsl    $lr, dup
        stqd    $3, 128($sp)
        brsl    $lr, close
        lqd     $3, 64($sp)
        il      $4, 3
        brsl    $lr, ftruncate
        lqd     $3, 64($sp)
        brsl    $lr, close
        ila     $3, .Lname
        ila     $4, st
        brsl    $lr, stat
        ila     $4, st
        lqd     $5, 16($4)
        rotqbyi $5, $5, 12
        stqd    $5, 144($sp)
        lqd     $6, 0($4)
        rotqbyi $6, $6, 8
        andi    $6, $6, 0x1ff
        stqd    $6, 160($sp)
        ila     $3, .Lfmt
        lqd     $4, 32($sp)
        lqd     $5, 48($sp)
        lqd     $6, 80($sp)
        lqd     $7, 96($sp)
        ila     $8, buf
        lqd     $9, 112($sp)
        lqd     $10, 128($sp)
        lqd     $11, 144($sp)
        lqd     $12, 160($sp)
        brsl    $lr, printf
        # write(1, "raw\n", 4)
        il      $3, 1
        ila     $4, .Lraw
        il      $5, 4
        brsl    $lr, write
        # unlink; open fails with ENOENT; write(99) fails with EBADF
        ila     $3, .Lname
        brsl    $lr, unlink
        stqd    $3, 32($sp)
        ila     $3, .Lname
        il      $4, 0
        il      $5, 0
        brsl    $lr, open
        stqd    $3, 48($sp)
        ila     $3, errno
        lqd     $3, 0($3)
        stqd    $3, 64($sp)
        il      $3, 99
        ila     $4, .Lraw
        il      $5, 4
        brsl    $lr, write
        stqd    $3, 80($sp)
        ila     $3, errno
        lqd     $3, 0($3)
        stqd    $3, 96($sp)
        il      $3, 0
        brsl    $lr, time
        stqd    $3, 112($sp)            # the simulated clock: 0 seconds in
        il      $3, 0
        ila     $4, st
        brsl    $lr, fstat
        ila     $4, st
        lqd     $4, 0($4)
        rotqbyi $4, $4, 8
        stqd    $4, 128($sp)
        ila     $3, .Lfmt2
        lqd     $4, 32($sp)
        lqd     $5, 48($sp)
        lqd     $6, 64($sp)
        lqd     $7, 80($sp)
        lqd     $8, 96($sp)
        lqd     $9, 112($sp)
        lqd     $10, 128($sp)
        brsl    $lr, printf
        il      $3, 0
        ai      $sp, $sp, 256
        lqd     $lr, 16($sp)
        bi      $lr
"#;

#[test]
fn posix1_calls() {
    let d = dir("posix1");
    build(&d, POSIX);
    std::fs::create_dir(d.join("root")).unwrap();
    let (out, err, code) = spu(&["run", "-q", "--root", "root", "prog.elf"], &d);
    assert_eq!(
        out,
        "fd=3 wrote=6 seek=2 read=4 'cdef' fsize=6 dup=4 ssize=3 mode=644\n\
         raw\n\
         unlink=0 reopen=-1 errno=2 badwrite=-1 errno=9 time=0 stdin=20620\n"
    );
    assert_eq!(err, "");
    assert_eq!(code, 0);
}

/// Runs `source` (with the runtime) and returns (stdout, stderr, status).
fn run_program(test: &str, source: &str, extra: &[&str]) -> (String, String, i32) {
    let d = dir(test);
    build(&d, source);
    std::fs::create_dir(d.join("root")).unwrap();
    std::fs::write(d.join("root/f"), b"data").unwrap();
    let mut args = vec!["run", "-q", "--root", "root"];
    args.extend_from_slice(extra);
    args.push("prog.elf");
    spu(&args, &d)
}

/// A main whose body is `body`, with `.rodata` strings `data`.
fn program(data: &str, body: &str) -> String {
    format!(
        "        .section .rodata\n{data}\n        .data\n        .align 4\nbuf: .space 64\n\
         \x20       .text\n        .global main\nmain:   stqd $lr, 16($sp)\n\
         \x20       stqd $sp, -64($sp)\n        ai $sp, $sp, -64\n{body}\n\
         \x20       il $3, 0\n        ai $sp, $sp, 64\n        lqd $lr, 16($sp)\n\
         \x20       bi $lr\n"
    )
}

#[test]
fn a_pointer_outside_local_store_stops_the_program() {
    let src = program("", "        ilhu $3, 4\n        brsl $lr, puts\n");
    let (out, err, code) = run_program("badptr", &src, &[]);
    assert_eq!(out, "");
    assert!(
        err.ends_with(
            ": the string to put: 1 bytes at 0x40000 lie outside local store (0..0x40000)\n"
        ),
        "{err}"
    );
    assert!(
        err.starts_with("spu: prog.elf: the program stopped at 0x"),
        "{err}"
    );
    assert_eq!(code, 134);
}

#[test]
fn a_read_of_2_gb_stops_the_program() {
    let src = program(
        "",
        "        il $3, 0\n        ila $4, buf\n        ilhu $5, 0x8000\n        brsl $lr, read\n",
    );
    let (out, err, code) = run_program("read2g", &src, &[]);
    assert_eq!(out, "");
    assert!(
        err.contains(": read's buffer: 2147483648 bytes at 0x"),
        "{err}"
    );
    assert_eq!(code, 134);
}

#[test]
fn percent_n_is_refused() {
    let src = program(
        ".Lf: .string \"ab%n\\n\"",
        "        ila $3, .Lf\n        ila $4, buf\n        brsl $lr, printf\n",
    );
    let (out, err, code) = run_program("percentn", &src, &[]);
    assert_eq!(out, "");
    assert!(
        err.ends_with(": printf: %n (writing the count into the program's memory) is refused\n"),
        "{err}"
    );
    assert_eq!(code, 134);
}

#[test]
fn unknown_opcodes_and_classes_stop_the_program_naming_both() {
    let src = program(
        "",
        "        stop 0x2100\n        .long (99 << 24) | 0x100\n",
    );
    let (_, err, code) = run_program("badop", &src, &[]);
    assert!(
        err.ends_with(": stop 0x2100: C99 opcode 99 (unknown) is not served by this host\n"),
        "{err}"
    );
    assert_eq!(code, 134);
    let src = program(
        "",
        "        stop 0x2101\n        .long (11 << 24) | 0x100\n",
    );
    let (_, err, code) = run_program("badposix", &src, &[]);
    assert!(
        err.ends_with(": stop 0x2101: POSIX.1 opcode 11 (mmap) is not served by this host\n"),
        "{err}"
    );
    assert_eq!(code, 134);
    let src = program("", "        stop 0x2107\n        .long (1 << 24) | 0x100\n");
    let (_, err, code) = run_program("badclass", &src, &[]);
    assert!(
        err.ends_with(
            ": stop 0x2107: PPE-assisted call class 7 (opcode 1) is not one this host serves \
             (0 = C99, 1 = POSIX.1)\n"
        ),
        "{err}"
    );
    assert_eq!(code, 134);
}

/// 10,000 opens of one file, and 10,000 fopens, without closing: the tables fill, then
/// each further call fails with EMFILE.
#[test]
fn ten_thousand_open_files_end_in_emfile() {
    let body = "
        il $80, 0
        il $81, 0
        ilhu $82, 0
        iohl $82, 10000
1:      ila $3, .Lf
        il $4, 0
        il $5, 0
        brsl $lr, open
        cgti $5, $3, -1
        brz $5, 2f
        ai $80, $80, 1
2:      ila $3, .Lr
        ila $4, .Lmode
        brsl $lr, fopen
        brz $3, 3f
        ai $81, $81, 1
3:      ai $82, $82, -1
        brnz $82, 1b
        ila $3, .Lfmt
        ori $4, $80, 0
        ori $5, $81, 0
        ila $6, errno
        lqd $6, 0($6)
        brsl $lr, printf
";
    let src = program(
        ".Lf: .string \"f\"\n.Lr: .string \"f\"\n.Lmode: .string \"r\"\n\
         .Lfmt: .string \"opened=%d fopened=%d errno=%d\\n\"",
        body,
    );
    let (out, err, code) = run_program("emfile", &src, &[]);
    assert_eq!(out, "opened=253 fopened=13 errno=24\n");
    assert_eq!(err, "");
    assert_eq!(code, 0);
}

#[test]
fn without_root_no_file_opens() {
    let src = program(
        ".Lf: .string \"f\"\n.Lmode: .string \"r\"\n.Lp: .string \"open\"",
        "        ila $3, .Lf\n        ila $4, .Lmode\n        brsl $lr, fopen\n\
         \x20       ila $3, .Lp\n        brsl $lr, perror\n",
    );
    let d = dir("noroot");
    build(&d, &src);
    std::fs::write(d.join("f"), b"x").unwrap();
    let (out, err, code) = spu(&["run", "-q", "prog.elf"], &d);
    assert_eq!(out, "");
    assert_eq!(err, "open: Permission denied\n");
    assert_eq!(code, 0);
}

/// The calls are served alike by the interpreter, the block compiler, the timing model
/// and the tracer.
#[test]
fn every_engine_serves_the_calls() {
    let d = dir("engines");
    build(&d, ARGV);
    let want = "argc=2\nargv[0]=prog.elf\nargv[1]=x\n";
    for mode in [
        ["--engine", "interp"],
        ["--engine", "jit"],
        ["--timing", "--max-cycles=100000000"],
    ] {
        let (out, _, code) = spu(&["run", "-q", mode[0], mode[1], "prog.elf", "--", "x"], &d);
        assert_eq!((out.as_str(), code), (want, 3), "{mode:?}");
    }
    let (out, _, code) = spu(&["run", "--trace", "prog.elf", "--", "x"], &d);
    let printed: String = out
        .lines()
        .filter(|l| l.starts_with("arg"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!((printed.as_str(), code), (want, 3));
}

/// `time` and `gettimeofday` answer from the simulated clock (the Unix epoch at load, plus
/// the SPU's cycles at 3.2 GHz), never the host's: the same program prints the same times
/// on every run and with either engine; between the two readings lie the loop's 320,000
/// instructions (100 us with the timing model off, one cycle per instruction) and the
/// calls' own. With the timing model on the clock is its cycle count.
#[test]
fn time_is_the_simulated_clock() {
    let source = program(
        ".Lfmt: .string \"%d.%06d %d.%06d %d\\n\"",
        "        ila $3, buf\n        il $4, 0\n        brsl $lr, gettimeofday\n\
         \x20       ila $5, 160000\n.Lloop: ai $5, $5, -1\n        brnz $5, .Lloop\n\
         \x20       ila $3, buf+16\n        il $4, 0\n        brsl $lr, gettimeofday\n\
         \x20       il $3, 0\n        brsl $lr, time\n        ori $8, $3, 0\n\
         \x20       ila $10, buf\n        lqd $4, 0($10)\n        rotqbyi $5, $4, 4\n\
         \x20       lqd $6, 16($10)\n        rotqbyi $7, $6, 4\n\
         \x20       ila $3, .Lfmt\n        brsl $lr, printf",
    );
    let d = dir("time");
    build(&d, &source);
    for mode in [
        ["--engine", "interp"],
        ["--engine", "jit"],
        ["--engine", "interp"],
    ] {
        let (out, err, code) = spu(&["run", "-q", mode[0], mode[1], "prog.elf"], &d);
        assert_eq!(
            (out.as_str(), err.as_str(), code),
            (WANT_TIME, "", 0),
            "{mode:?}"
        );
    }
    let (out, err, code) = spu(&["run", "-q", "--timing", "prog.elf"], &d);
    assert_eq!((out.as_str(), err.as_str(), code), (WANT_TIMED, "", 0));
}
/// The loop at one cycle per instruction.
const WANT_TIME: &str = "0.000000 0.000100 0\n";
/// 25 cycles an iteration: the loop has no branch hint, so each taken `brnz` pays the
/// mispredict.
const WANT_TIMED: &str = "0.000000 0.001250 0\n";

/// scanf from the host's standard input (what it looks at and does not take stays for
/// the next read), sscanf from a string.
#[test]
fn scanf_family() {
    let src = program(
        ".Lf: .string \"%d %s\"\n.Lo: .string \"n=%d s=%s c=%d rest=%s|\\n\"\n\
         .Ls: .string \"1,2\"\n.Lsf: .string \"%d,%d\"\n.Lso: .string \"sscanf=%d a=%d b=%d\\n\"\n\
         \x20       .data\n        .align 4\nn: .space 16\nw: .space 32\nrest: .space 32\n",
        "        ila $3, .Lf\n        ila $4, n\n        ila $5, w\n        brsl $lr, scanf\n\
         \x20       brsl $lr, getchar\n        ori $80, $3, 0\n\
         \x20       ila $3, rest\n        il $4, 32\n        ila $5, stdin\n        lqd $5, 0($5)\n\
         \x20       brsl $lr, fgets\n\
         \x20       ila $3, .Lo\n        ila $4, n\n        lqd $4, 0($4)\n        ila $5, w\n\
         \x20       ori $6, $80, 0\n        ila $7, rest\n        brsl $lr, printf\n\
         \x20       ila $3, .Ls\n        ila $4, .Lsf\n        ila $5, n\n        ila $6, w\n\
         \x20       brsl $lr, sscanf\n        ori $4, $3, 0\n        ila $5, n\n        lqd $5, 0($5)\n\
         \x20       ila $6, w\n        lqd $6, 0($6)\n        ila $3, .Lso\n        brsl $lr, printf\n",
    );
    let d = dir("scanf");
    build(&d, &src);
    let mut child = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(["run", "-q", "prog.elf"])
        .current_dir(&d)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    use std::io::Write;
    child
        .stdin
        .take()
        .unwrap()
        .write_all(b"  17 words\nrest")
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        "n=17 s=words c=10 rest=rest|\nsscanf=2 a=1 b=2\n"
    );
    assert_eq!(out.status.code(), Some(0));
}

/// The runtime's memory and string functions.
#[test]
fn memory_and_string_functions() {
    let src = program(
        ".Labc: .string \"abc\"\n.Labd: .string \"abd\"\n.Lo: .string \"%s %d %d %s\\n\"\n\
         \x20       .data\n        .align 4\nb2: .space 32\n",
        "        ila $3, buf\n        il $4, 120\n        il $5, 5\n        brsl $lr, memset\n\
         \x20       ila $3, buf + 5\n        ila $4, .Labc\n        il $5, 4\n        brsl $lr, memcpy\n\
         \x20       ila $3, b2\n        ila $4, buf\n        brsl $lr, strcpy\n\
         \x20       ila $3, b2 + 1\n        ila $4, b2\n        il $5, 8\n        brsl $lr, memmove\n\
         \x20       ila $3, buf\n        brsl $lr, strlen\n        ori $80, $3, 0\n\
         \x20       ila $3, .Labc\n        ila $4, .Labd\n        brsl $lr, strcmp\n\
         \x20       ori $6, $3, 0\n        ori $5, $80, 0\n        ila $4, buf\n        ila $7, b2\n\
         \x20       ila $3, .Lo\n        brsl $lr, printf\n",
    );
    let (out, err, code) = run_program("string", &src, &[]);
    assert_eq!(out, "xxxxxabc 8 -1 xxxxxxabc\n");
    assert_eq!(err, "");
    assert_eq!(code, 0);
}
