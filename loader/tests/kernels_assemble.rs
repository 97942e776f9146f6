//! The kernels assemble with the generated layout include.

#[test]
fn kernels_assemble() {
    for (source, name) in [
        (spu_loader::runtime::RAYTRACE_SOURCE, "raytrace.s"),
        (spu_loader::runtime::FILL_SOURCE, "fill.s"),
    ] {
        let program =
            spu_loader::runtime::assemble_kernel(source, name).unwrap_or_else(|e| panic!("{e}"));
        assert!(program.image.len() > 256, "{name}");
        assert!(program.symbols.iter().any(|(n, _)| n == "_start"));
    }
}
