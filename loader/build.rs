//! Assembles every frame program ([`variants::KernelVariant::ALL`]) at build time, so that `spu render` does not assemble its kernel before
//! every frame (tens of milliseconds; over a hundred for the shaded kernel). The runtime
//! takes a prebuilt program only when the sources it would assemble hash the same as the
//! ones assembled here (`kernels::prebuilt`), and assembles them itself otherwise; a
//! kernel that does not assemble here is left to the runtime, which reports why.
//!
//! It also writes the table of kernel sources the library embeds (`sources.rs`: every file
//! of `kernels/modules/` and every variant's frame program), so that no hand list of them
//! can disagree with the directory.

// Only encoding and the hash are used here.
#[allow(dead_code)]
#[path = "src/kernel_image.rs"]
mod kernel_image;

// The variants, their sources and defines: one declaration for the build and the runtime.
#[allow(dead_code)]
#[path = "src/variants.rs"]
mod variants;

use std::path::Path;

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn main() {
    let kernels = Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels");
    println!("cargo:rerun-if-changed={}", kernels.display());
    println!("cargo:rerun-if-changed=src/kernel_image.rs");
    println!("cargo:rerun-if-changed=src/variants.rs");
    let mut includes = vec![("layout.inc".to_string(), read(&kernels.join("layout.inc")))];
    let mut modules: Vec<_> = std::fs::read_dir(kernels.join("modules"))
        .expect("kernels/modules")
        .map(|e| e.expect("a directory entry").path())
        .collect();
    modules.sort();
    let out_dir = std::env::var("OUT_DIR").expect("OUT_DIR");
    // The embedded sources (`kernels::MODULES`, `kernels::FRAME_SOURCES`).
    let embed = |name: &str, path: &Path| {
        let path = path
            .canonicalize()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        format!(
            "    ({name:?}, include_str!({:?})),\n",
            path.display().to_string()
        )
    };
    let mut sources = String::from("(\n&[\n");
    for path in &modules {
        let file = path.file_name().expect("a file name").to_string_lossy();
        let name = format!("modules/{file}");
        sources += &embed(&name, path);
        includes.push((name, read(path)));
    }
    sources += "],\n&[\n";
    let mut files: Vec<&str> = variants::KernelVariant::ALL
        .iter()
        .map(|v| v.file())
        .collect();
    files.sort();
    files.dedup();
    for file in files {
        sources += &embed(file, &kernels.join(file));
    }
    sources += "],\n)\n";
    let path = Path::new(&out_dir).join("sources.rs");
    std::fs::write(&path, sources).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut table = String::from("&[\n");
    for variant in variants::KernelVariant::ALL {
        let (file, name, defines) = (variant.file(), variant.name(), variant.defines());
        let out = format!("{}.bin", variant.id());
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
        let path = Path::new(&out_dir).join(&out);
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        table += &format!("    include_bytes!(concat!(env!(\"OUT_DIR\"), \"/{out}\")),\n");
    }
    // The runtime's list of them (`kernels::PREBUILT`).
    table += "]\n";
    let path = Path::new(&out_dir).join("prebuilt.rs");
    std::fs::write(&path, table).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
