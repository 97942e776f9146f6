//! The kernels assemble from their modules, with `layout.inc` from its one source; the
//! checked-in copy of `layout.inc` and the embedded module list match the files.

use spu_loader::kernels::{self, KernelVariant};

fn kernels_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels")
}

#[test]
fn kernels_assemble() {
    for variant in KernelVariant::ALL {
        let program = variant.program().unwrap_or_else(|e| panic!("{e}"));
        assert!(program.image.len() > 256, "{variant:?}");
        assert!(program.symbols.iter().any(|(n, _)| n == "_start"));
    }
}

/// `kernels/layout.inc` is the generated text. To regenerate it after changing
/// `loader::layout` or `loader::kernel_abi`: `SPU_BLESS_LAYOUT=1 cargo test -p spu-loader
/// --test all kernels_assemble`.
#[test]
fn checked_in_layout_inc_is_the_generated_one() {
    let path = kernels_dir().join("layout.inc");
    let generated = kernels::layout_include();
    if std::env::var_os("SPU_BLESS_LAYOUT").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let on_disk = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        on_disk == generated,
        "kernels/layout.inc differs from loader::layout and loader::kernel_abi; regenerate it \
         with SPU_BLESS_LAYOUT=1 cargo test -p spu-loader --test all kernels_assemble"
    );
}

#[test]
fn every_module_file_is_embedded() {
    let mut on_disk: Vec<String> = std::fs::read_dir(kernels_dir().join("modules"))
        .unwrap()
        .map(|e| format!("modules/{}", e.unwrap().file_name().to_string_lossy()))
        .collect();
    on_disk.sort();
    let mut embedded: Vec<String> = kernels::MODULES.iter().map(|m| m.0.to_string()).collect();
    embedded.sort();
    assert_eq!(
        on_disk, embedded,
        "loader::kernels::MODULES lists kernels/modules/"
    );
}

/// The frame programs assembled at build time are exactly what the assembler makes of the
/// embedded sources (image, entry, symbols), and the runtime finds them (the sources it
/// would assemble hash the same); other sources are not served from the build.
#[test]
fn prebuilt_kernels_are_what_the_assembler_makes() {
    let includes = kernels::include_files();
    for variant in KernelVariant::ALL {
        let (source, name, defines) = (variant.source(), variant.name(), variant.defines());
        let prebuilt = kernels::prebuilt(source, name, defines, &includes)
            .unwrap_or_else(|| panic!("{name} {defines:?}: no prebuilt program for these sources"));
        let opts = spu_asm::Options {
            virtual_files: includes.clone(),
            defines: defines.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
            ..Default::default()
        };
        let fresh = spu_asm::assemble(source, name, &opts).expect("assembles");
        assert!(
            prebuilt == (fresh.image, fresh.entry, fresh.symbols),
            "{name} {defines:?}: the prebuilt program differs"
        );
    }
    let (source, name) = (
        KernelVariant::Primary.source(),
        KernelVariant::Primary.name(),
    );
    let edited = format!("{source}\n\tnop\n");
    assert!(kernels::prebuilt(&edited, name, &[], &includes).is_none());
    assert!(kernels::prebuilt(source, name, &[("SHADE", 2)], &includes).is_none());
}

/// A malformed or truncated encoded program is refused, not misread.
#[test]
fn kernel_images_decode_only_whole() {
    use spu_loader::kernel_image::{decode, encode};
    let image = (
        vec![1, 2, 3, 4],
        8,
        vec![("_start".to_string(), 0), ("x".to_string(), 16)],
    );
    let bytes = encode(42, &image);
    assert_eq!(decode(&bytes), Some((42, image)));
    for n in 0..bytes.len() {
        assert_eq!(decode(&bytes[..n]), None, "{n} bytes");
    }
    let mut longer = bytes.clone();
    longer.push(0);
    assert_eq!(decode(&longer), None);
    assert_eq!(decode(&[]), None);
}
