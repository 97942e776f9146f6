//! The small SPU runtime shipped in the binary (`kernels/runtime/`), so that `spu as
//! --runtime prog.s` links a spu-gcc-style program (a `main` calling `printf`) with its
//! startup, `exit` and the library calls the PPE serves, and the user needs no files.

/// The runtime's sources, in link order: `crt0.s` first, as spu-gcc put `crt1.o` first.
pub const SOURCES: &[(&str, &str)] = &[
    (
        "kernels/runtime/crt0.s",
        include_str!("../../../kernels/runtime/crt0.s"),
    ),
    (
        "kernels/runtime/ppe.s",
        include_str!("../../../kernels/runtime/ppe.s"),
    ),
    (
        "kernels/runtime/calls.s",
        include_str!("../../../kernels/runtime/calls.s"),
    ),
    (
        "kernels/runtime/string.s",
        include_str!("../../../kernels/runtime/string.s"),
    ),
];

/// The runtime assembled into relocatable objects, to be linked before the program's.
pub fn objects() -> Result<Vec<spu_asm::object::Object>, Vec<spu_asm::Diagnostic>> {
    SOURCES
        .iter()
        .map(|(name, text)| {
            spu_asm::assemble_object(text, name, &Default::default()).map(|(o, _)| o)
        })
        .collect()
}
