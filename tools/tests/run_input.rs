//! A run's inputs. Those it would misuse are refused before it starts (issue 31, item 4):
//! an ELF segment outside local store or over another, an empty file, a text file given as
//! a program image, and a source `spu timing` would time though `spu as` refuses it; each
//! case asserts the exact message and exit status 2 (bad input). Mailbox values beyond the
//! four the mailbox holds go in as the program waits for them.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Runs `spu` and gives (status, stdout, stderr).
fn spu(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().expect("exited, not killed by a signal"),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-refusals-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> String {
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path.to_str().unwrap().to_string()
}

/// An SPU executable of PT_LOAD segments `(vaddr, bytes)`, entry 0, built by hand.
fn executable(segments: &[(u32, &[u8])]) -> Vec<u8> {
    let mut elf = vec![0u8; 52];
    elf[0..4].copy_from_slice(b"\x7fELF");
    elf[4] = 1; // ELFCLASS32
    elf[5] = 2; // big-endian
    elf[6] = 1;
    elf[16..18].copy_from_slice(&2u16.to_be_bytes()); // ET_EXEC
    elf[18..20].copy_from_slice(&23u16.to_be_bytes()); // EM_SPU
    elf[28..32].copy_from_slice(&52u32.to_be_bytes()); // e_phoff
    elf[42..44].copy_from_slice(&32u16.to_be_bytes());
    elf[44..46].copy_from_slice(&(segments.len() as u16).to_be_bytes());
    let mut at = 52 + 32 * segments.len() as u32;
    let mut bodies = Vec::new();
    for (vaddr, data) in segments {
        let size = data.len() as u32;
        for w in [1, at, *vaddr, *vaddr, size, size, 7, 16] {
            elf.extend(w.to_be_bytes());
        }
        bodies.extend_from_slice(data);
        at += size;
    }
    elf.extend(bodies);
    elf
}

/// `stop 0x2000`, then `stop 0x2001`.
const EXIT_0_THEN_1: [u8; 8] = [0, 0, 0x20, 0, 0, 0, 0x20, 1];

#[test]
fn a_well_formed_executable_runs() {
    let d = dir("ok");
    let elf = write(&d, "ok.elf", executable(&[(0, &EXIT_0_THEN_1)]));
    let (status, _, stderr) = spu(&["run", "-q", &elf]);
    assert_eq!((status, stderr.as_str()), (0, ""));
}

#[test]
fn a_segment_outside_local_store_is_refused() {
    let d = dir("outside");
    // 8 bytes at 0x3fffc: the last 4 would wrap around to address 0.
    let elf = write(&d, "wrap.elf", executable(&[(0x3fffc, &EXIT_0_THEN_1)]));
    let (status, stdout, stderr) = spu(&["run", &elf]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(stdout, "");
    assert_eq!(
        stderr,
        format!(
            "spu: {elf}: segment at 0x3fffc of 8 bytes lies outside local store (0..0x40000)\n"
        )
    );
}

#[test]
fn overlapping_segments_are_refused() {
    let d = dir("overlap");
    let elf = write(
        &d,
        "overlap.elf",
        executable(&[(0x100, &[0; 32]), (0x110, &EXIT_0_THEN_1)]),
    );
    let (status, _, stderr) = spu(&["run", &elf]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(
        stderr,
        format!("spu: {elf}: segment at 0x110..0x118 overlaps the segment at 0x100..0x120\n")
    );
}

#[test]
fn an_empty_file_is_refused() {
    let d = dir("empty");
    let empty = write(&d, "empty.bin", b"");
    let (status, _, stderr) = spu(&["run", &empty]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(
        stderr,
        format!("spu: {empty}: an empty file: nothing to run\n")
    );
}

#[test]
fn a_relocatable_object_is_refused_until_linked() {
    let d = dir("object");
    let source = write(&d, "p.s", "_start: nop\n stop 0x2005\n");
    let object = d.join("p.o").display().to_string();
    let (status, _, stderr) = spu(&["as", "-c", &source, "-o", &object]);
    assert_eq!(status, 0, "{stderr}");
    let (status, _, stderr) = spu(&["run", &object]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(
        stderr,
        format!(
            "spu: {object}: a relocatable object, not an SPU program: link it first (spu ld \
             OBJ.o -o PROG)\n"
        )
    );
    let program = d.join("p.elf").display().to_string();
    let (status, _, stderr) = spu(&["ld", &object, "-o", &program]);
    assert_eq!(status, 0, "{stderr}");
    assert_eq!(spu(&["run", "-q", &program]).0, 5);
}

#[test]
fn text_given_as_an_image_is_refused() {
    let d = dir("text");
    let source = "_start:\n\tstop 0x2000\n";
    for name in ["prog.asm", "prog.S"] {
        let path = write(&d, name, source);
        let (status, _, stderr) = spu(&["run", &path]);
        assert_eq!(status, 2, "{stderr}");
        assert_eq!(
            stderr,
            format!(
                "spu: {path}: an assembly source, not an SPU program: assemble it first, or \
                 name it .s\n"
            )
        );
    }
    let path = write(&d, "prog.img", source);
    let (status, _, stderr) = spu(&["run", &path]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(
        stderr,
        format!("spu: {path}: a text file, not an SPU program: assemble it first, or name it .s\n")
    );
    // The same text named .s is assembled and runs.
    let path = write(&d, "prog.s", source);
    let (status, _, stderr) = spu(&["run", "-q", &path]);
    assert_eq!((status, stderr.as_str()), (0, ""));
}

#[test]
fn timing_checks_operands_as_the_assembler_does() {
    let d = dir("timing");
    let path = write(&d, "bad.s", "\tlqd $500,0($1)\n");
    let (status, stdout, stderr) = spu(&["timing", &path]);
    assert_eq!(status, 2, "{stderr}");
    assert_eq!(stdout, "");
    assert_eq!(
        stderr,
        format!("spu: {path}:1:6: error: register number 500 out of range [0, 127]\n")
    );
    let path = write(&d, "good.s", "\tlqd $5,0($1)\n");
    let (status, _, stderr) = spu(&["timing", &path]);
    assert_eq!((status, stderr.as_str()), (0, ""));
}

#[test]
fn mailbox_values_beyond_four_go_in_as_the_program_waits() {
    let d = dir("mbox");
    // Sums six mailbox values into $3.
    let src = write(
        &d,
        "sum.s",
        "_start: il $5, 6\n il $3, 0\nl: rdch $4, $SPU_RdInMbox\n a $3, $3, $4\n \
         ai $5, $5, -1\n brnz $5, l\n stop 0x2000\n",
    );
    let values = ["--mbox-in", "1", "--mbox-in", "2", "--mbox-in", "3"];
    let more = ["--mbox-in", "4", "--mbox-in", "5", "--mbox-in", "6"];
    let (status, _, stderr) = spu(&[&["run", "-q", &src][..], &values, &more].concat());
    assert_eq!((status, stderr.as_str()), (0, ""));
    // The sum is in $3.
    let (status, stdout, _) = spu(&[&["run", "--json", &src][..], &values, &more].concat());
    assert_eq!(status, 0);
    let run: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(run["registers"][3][0], 21);
    // Five values: the sixth read waits for ever.
    let (status, _, stderr) = spu(&[&["run", &src][..], &values, &more[..4]].concat());
    assert_eq!(status, 134);
    assert_eq!(
        stderr,
        format!(
            "spu: {src}: SPU stopped abnormally: deadlock at 0x8 on channel SPU_RdInMbox (29)\n"
        )
    );
}
