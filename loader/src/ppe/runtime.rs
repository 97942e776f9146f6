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
    (
        "kernels/runtime/malloc.s",
        include_str!("../../../kernels/runtime/malloc.s"),
    ),
    (
        "kernels/runtime/divdi3.s",
        include_str!("../../../kernels/runtime/divdi3.s"),
    ),
    (
        "kernels/runtime/divsi3.s",
        include_str!("../../../kernels/runtime/divsi3.s"),
    ),
    (
        "kernels/runtime/clock.s",
        include_str!("../../../kernels/runtime/clock.s"),
    ),
    (
        "kernels/runtime/floatsidf.s",
        include_str!("../../../kernels/runtime/floatsidf.s"),
    ),
    (
        "kernels/runtime/fixdfsi.s",
        include_str!("../../../kernels/runtime/fixdfsi.s"),
    ),
    (
        "kernels/runtime/divdf3.s",
        include_str!("../../../kernels/runtime/divdf3.s"),
    ),
    (
        "kernels/runtime/floatdidf.s",
        include_str!("../../../kernels/runtime/floatdidf.s"),
    ),
    (
        "kernels/runtime/fixdfdi.s",
        include_str!("../../../kernels/runtime/fixdfdi.s"),
    ),
];

/// Assembles one runtime source; a failure (a broken runtime) is reported whole.
fn assemble(name: &str, text: &str) -> Result<spu_asm::object::Object, String> {
    spu_asm::assemble_object(text, name, &Default::default())
        .map(|(o, _)| o)
        .map_err(|d| {
            d.iter()
                .map(|d| d.to_string())
                .collect::<Vec<_>>()
                .join("\n")
        })
}

/// The startup object (`crt0.s`), linked before the program's objects.
pub fn start_file() -> Result<spu_asm::object::Object, String> {
    let (name, text) = SOURCES[0];
    assemble(name, text)
}

/// The rest of the runtime as a library (`libspu.a`), searched after the program's objects
/// as GNU ld searches `-lc`: a program links only the members it calls.
pub fn library() -> Result<spu_asm::archive::Archive, String> {
    let mut members = Vec::new();
    for (name, text) in &SOURCES[1..] {
        let data = assemble(name, text)?.to_elf()?;
        let file = name.rsplit('/').next().unwrap_or(name).replace(".s", ".o");
        members.push(spu_asm::archive::Member { name: file, data });
    }
    Ok(spu_asm::archive::Archive::new(members))
}
