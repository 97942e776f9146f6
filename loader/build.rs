//! Assembles the frame programs (`kernels/primary.s` with and without `SHADE`, and
//! `kernels/fill.s`) at build time, so that `spu render` does not assemble its kernel before
//! every frame (tens of milliseconds; over a hundred for the shaded kernel). The runtime
//! takes a prebuilt program only when the sources it would assemble hash the same as the
//! ones assembled here (`kernels::prebuilt`), and assembles them itself otherwise; a
//! kernel that does not assemble here is left to the runtime, which reports why.

// Only encoding and the hash are used here.
#[allow(dead_code)]
#[path = "src/kernel_image.rs"]
mod kernel_image;

use std::path::Path;

type Program = (
    &'static str,
    &'static str,
    &'static [(&'static str, i64)],
    &'static str,
);

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn main() {
    let kernels = Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels");
    println!("cargo:rerun-if-changed={}", kernels.display());
    println!("cargo:rerun-if-changed=src/kernel_image.rs");
    let mut includes = vec![("layout.inc".to_string(), read(&kernels.join("layout.inc")))];
    let mut modules: Vec<_> = std::fs::read_dir(kernels.join("modules"))
        .expect("kernels/modules")
        .map(|e| e.expect("a directory entry").path())
        .collect();
    modules.sort();
    for path in modules {
        let file = path.file_name().expect("a file name").to_string_lossy();
        includes.push((format!("modules/{file}"), read(&path)));
    }
    let out_dir = std::env::var("OUT_DIR").expect("OUT_DIR");
    // (source file, name, defines, output file)
    let programs: [Program; 3] = [
        ("primary.s", "kernels/primary.s", &[], "primary.bin"),
        (
            "primary.s",
            "kernels/primary.s",
            &[("SHADE", 1)],
            "primary-shade.bin",
        ),
        ("fill.s", "kernels/fill.s", &[], "fill.bin"),
    ];
    let mut table = String::from("&[\n");
    for (file, name, defines, out) in programs {
        let source = read(&kernels.join(file));
        let opts = spu_asm::Options {
            virtual_files: includes.clone(),
            defines: defines.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            ..Default::default()
        };
        let bytes = match spu_asm::assemble(&source, name, &opts) {
            Ok(program) => {
                let hash = kernel_image::sources_hash(name, &source, defines, &includes);
                kernel_image::encode(hash, &(program.image, program.entry, program.symbols))
            }
            Err(_) => Vec::new(),
        };
        let path = Path::new(&out_dir).join(out);
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        table += &format!("    include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{out}\")),\n");
    }
    // The runtime's list of them (`kernels::PREBUILT`).
    table += "]\n";
    let path = Path::new(&out_dir).join("prebuilt.rs");
    std::fs::write(&path, table).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
