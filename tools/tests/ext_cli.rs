//! `--ext` and `.spu_ext` through the `spu` command (docs/extensions.md): a gather program
//! assembles only with its extension, runs only with it (else an abnormal stop, 134, that
//! names it), disassembles by name only with it; a bad list is bad usage (2).

use std::path::PathBuf;
use std::process::Command;

/// `spu ARGS`: (exit status, stdout, stderr).
fn spu(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "spu {args:?}: {stderr}");
    (
        out.status.code().expect("exited"),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

fn dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("spu-ext-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const BODY: &str = "        .text
        .global _start
_start: lqr     $6, addrs
        lgw     $3, $6
        stop    0x2000
        .align  4
addrs:  .long   data, data+4, data+9, data+0x4000c
data:   .long   1, 2, 3, 4
";

#[test]
fn the_command_switches_the_gather_extension() {
    let d = dir();
    let plain = d.join("plain.s");
    std::fs::write(&plain, BODY).unwrap();
    let plain = plain.to_str().unwrap();
    let elf = d.join("g.elf");
    let elf = elf.to_str().unwrap();

    let (status, _, stderr) = spu(&["as", plain, "-o", elf]);
    assert_eq!(status, 2, "{stderr}");
    assert!(
        stderr.contains("'lgw' is an instruction of the gather extension, which is off")
            && stderr.contains(&format!("{plain}:4:9")),
        "{stderr}"
    );
    assert!(!std::path::Path::new(elf).exists());

    let (status, _, stderr) = spu(&["as", "--ext", "gather", plain, "-o", elf]);
    assert_eq!(status, 0, "{stderr}");

    let (status, stdout, stderr) = spu(&["run", elf, "--dump-regs"]);
    assert_eq!(status, 134, "{stdout}");
    assert!(
        stderr.contains("illegal instruction 0x38a00303 at 0x4 (an instruction of the gather extension, which is off: --ext gather)"),
        "{stderr}"
    );
    let (status, stdout, stderr) = spu(&["run", "--ext", "gather", elf, "--dump-regs"]);
    assert_eq!(status, 0, "{stderr}");
    assert!(
        stdout.contains("$3: 00000001 00000002 00000003 00000004"),
        "{stdout}"
    );

    let (_, stdout, _) = spu(&["dis", elf]);
    assert!(stdout.contains(".long 0x38a00303"), "{stdout}");
    let (_, stdout, _) = spu(&["dis", "--ext", "multihint=2,gather", elf]);
    assert!(stdout.contains("lgw\t$3,$6"), "{stdout}");

    // The directive in the source does what the option does.
    let with = d.join("with.s");
    std::fs::write(&with, format!("        .spu_ext gather\n{BODY}")).unwrap();
    let (status, _, stderr) = spu(&["as", with.to_str().unwrap(), "-o", elf]);
    assert_eq!(status, 0, "{stderr}");

    for bad in ["scatter", "multihint=0", "multihint=9", "gather,"] {
        let (status, _, stderr) = spu(&["run", "--ext", bad, elf]);
        assert_eq!(status, 2, "--ext {bad}: {stderr}");
        assert!(stderr.contains("--ext"), "--ext {bad}: {stderr}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// `spu render --ext gather` with a shading mode runs the gather kernel: the same image as
/// without the extension, in fewer shading cycles.
#[test]
fn render_with_the_gather_extension_shades_the_same_image() {
    // (a directory of its own: the other test removes `dir()` when it ends)
    let d = std::env::temp_dir().join(format!("spu-ext-render-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let render = |ext: &str| {
        let png = d.join(format!("{ext}.png"));
        let stats = d.join(format!("{ext}.json"));
        let (status, _, stderr) = spu(&[
            "render",
            "--scene",
            "conference",
            "--width",
            "64",
            "--height",
            "64",
            "--shade",
            "simple",
            "--ext",
            ext,
            "-o",
            png.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ]);
        assert_eq!(status, 0, "--ext {ext}: {stderr}");
        let stats = std::fs::read_to_string(&stats).unwrap();
        let json: serde_json::Value = serde_json::from_str(&stats).unwrap();
        let cycles = json["shading"]["cycles"].as_u64().unwrap();
        (std::fs::read(&png).unwrap(), cycles)
    };
    let (plain, plain_cycles) = render("none");
    let (gather, gather_cycles) = render("gather");
    assert!(plain == gather, "the images differ");
    // The shading module's cycles: the baseline kernel's, the gather kernel's.
    assert_eq!((plain_cycles, gather_cycles), (1_267_288, 520_761));
    std::fs::remove_dir_all(&d).ok();
}

/// The gather kernel's lighting has a one-channel run for a grey first light and the
/// three-channel run for any other light (docs/extensions.md): a coloured light, and a
/// white light after a coloured one (whose sums are not grey), shade the same image as
/// without the extension, in the cycles pinned here.
#[test]
fn the_gather_kernel_shades_coloured_lights_as_the_baseline() {
    let d = std::env::temp_dir().join(format!("spu-ext-lights-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let render = |ext: &str, lights: &[&str]| {
        let png = d.join(format!("{ext}.png"));
        let stats = d.join(format!("{ext}.json"));
        let mut args = vec![
            "render", "--scene", "room", "--width", "64", "--height", "64",
        ];
        args.extend(["--shade", "shadows", "--ext", ext]);
        for light in lights {
            args.extend(["--light", light]);
        }
        args.extend([
            "-o",
            png.to_str().unwrap(),
            "--stats",
            stats.to_str().unwrap(),
        ]);
        let (status, _, stderr) = spu(&args);
        assert_eq!(status, 0, "--ext {ext} {lights:?}: {stderr}");
        let stats = std::fs::read_to_string(&stats).unwrap();
        let json: serde_json::Value = serde_json::from_str(&stats).unwrap();
        let cycles = json["shading"]["cycles"].as_u64().unwrap();
        (std::fs::read(&png).unwrap(), cycles)
    };
    let mut cycles = Vec::new();
    for lights in [&["0,5,0,1,0.5,0.25"][..], &["2,3,1,0.3,0.6,0.9", "0,5,0"]] {
        let (plain, plain_cycles) = render("none", lights);
        let (gather, gather_cycles) = render("gather", lights);
        assert!(plain == gather, "{lights:?}: the images differ");
        cycles.push((plain_cycles, gather_cycles));
    }
    assert_eq!(cycles, [(503_961, 372_207), (547_982, 418_745)]);
    std::fs::remove_dir_all(&d).ok();
}
