//! The SPU kernels' sources, built into the binary so `spu render` needs no files: the frame
//! programs, the modules they compose with `.include`, and `layout.inc`, which is generated
//! from [`crate::layout`] and [`crate::kernel_abi`] (the checked-in `kernels/layout.inc` is
//! for users assembling from a checkout, and a test keeps it equal to the generated text).

/// The primary-ray frame program (`kernels/primary.s`).
pub const PRIMARY_SOURCE: &str = include_str!("../../kernels/primary.s");
/// The fill-pattern program that exercises the runtime (`kernels/fill.s`).
pub const FILL_SOURCE: &str = include_str!("../../kernels/fill.s");

/// Every kernel module, by the name frame programs `.include` it with (relative to
/// `kernels/`).
pub const MODULES: &[(&str, &str)] = &[
    (
        "modules/regs.inc",
        include_str!("../../kernels/modules/regs.inc"),
    ),
    (
        "modules/data.s",
        include_str!("../../kernels/modules/data.s"),
    ),
    (
        "modules/frame.s",
        include_str!("../../kernels/modules/frame.s"),
    ),
    (
        "modules/raygen.s",
        include_str!("../../kernels/modules/raygen.s"),
    ),
    (
        "modules/traverse.s",
        include_str!("../../kernels/modules/traverse.s"),
    ),
    (
        "modules/bvh_cache.s",
        include_str!("../../kernels/modules/bvh_cache.s"),
    ),
    (
        "modules/triangle.s",
        include_str!("../../kernels/modules/triangle.s"),
    ),
    (
        "modules/tri_cache.s",
        include_str!("../../kernels/modules/tri_cache.s"),
    ),
    ("modules/lru.s", include_str!("../../kernels/modules/lru.s")),
    ("modules/sht.s", include_str!("../../kernels/modules/sht.s")),
    (
        "modules/output.s",
        include_str!("../../kernels/modules/output.s"),
    ),
    (
        "modules/frame_done.s",
        include_str!("../../kernels/modules/frame_done.s"),
    ),
    (
        "modules/shade.s",
        include_str!("../../kernels/modules/shade.s"),
    ),
    (
        "modules/shade_area.s",
        include_str!("../../kernels/modules/shade_area.s"),
    ),
    (
        "modules/shade_iset.s",
        include_str!("../../kernels/modules/shade_iset.s"),
    ),
    (
        "modules/shade_light.s",
        include_str!("../../kernels/modules/shade_light.s"),
    ),
    (
        "modules/shade_iset_slow.s",
        include_str!("../../kernels/modules/shade_iset_slow.s"),
    ),
    (
        "modules/shade_cache.s",
        include_str!("../../kernels/modules/shade_cache.s"),
    ),
    (
        "modules/shadow.s",
        include_str!("../../kernels/modules/shadow.s"),
    ),
];

/// The text of `layout.inc`: record layouts and the kernel ABI, from their one definition.
pub fn layout_include() -> String {
    crate::layout::spu_layout_include() + &crate::kernel_abi::spu_include()
}

/// The frame programs assembled at build time (`build.rs`), encoded
/// ([`crate::kernel_image`]; empty where a kernel did not assemble then).
const PREBUILT: &[&[u8]] = include!(concat!(env!("OUT_DIR"), "/prebuilt.rs"));

/// The program the build assembled from exactly these sources (`source` named `name`,
/// `defines`, the include files `includes`), if it did: the one whose sources hash the
/// same.
pub fn prebuilt(
    source: &str,
    name: &str,
    defines: &[(&str, i64)],
    includes: &[(String, String)],
) -> Option<crate::kernel_image::Image> {
    let wanted = crate::kernel_image::sources_hash(name, source, defines, includes);
    // The hash leads each encoding: only the program found is decoded.
    let bytes = PREBUILT
        .iter()
        .find(|bytes| bytes.get(..8) == Some(&wanted.to_le_bytes()[..]))?;
    crate::kernel_image::decode(bytes).map(|(_, image)| image)
}

/// The in-memory files a kernel's `.include`s resolve to: `layout.inc` and the modules.
pub fn include_files() -> Vec<(String, String)> {
    let mut files = vec![("layout.inc".to_string(), layout_include())];
    files.extend(
        MODULES
            .iter()
            .map(|(name, text)| (name.to_string(), text.to_string())),
    );
    files
}

/// The frame program `spu render` runs: (source, name for diagnostics).
pub fn frame_program(fill: bool) -> (&'static str, &'static str) {
    if fill {
        (FILL_SOURCE, "kernels/fill.s")
    } else {
        (PRIMARY_SOURCE, "kernels/primary.s")
    }
}
