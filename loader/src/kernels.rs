//! The SPU kernels' sources, built into the binary so `spu render` needs no files: the frame
//! programs, the modules they compose with `.include`, and `layout.inc`, which is generated
//! from [`crate::layout`] and [`crate::kernel_abi`] (the checked-in `kernels/layout.inc` is
//! for users assembling from a checkout, and a test keeps it equal to the generated text).
//!
//! The lists of sources are written by the build script from `kernels/modules/` and
//! [`KernelVariant::ALL`], so they cannot disagree with the files or the variants.

use crate::runtime::Program;
pub use crate::variants::KernelVariant;

/// (every kernel module by the name frame programs `.include` it with, relative to
/// `kernels/`; every frame program's source by its file name under `kernels/`).
type Sources = (
    &'static [(&'static str, &'static str)],
    &'static [(&'static str, &'static str)],
);

const SOURCES: Sources = include!(concat!(env!("OUT_DIR"), "/sources.rs"));

/// Every kernel module, by the name frame programs `.include` it with (relative to
/// `kernels/`).
pub const MODULES: &[(&str, &str)] = SOURCES.0;

/// The frame programs' sources, by file name under `kernels/`.
pub const FRAME_SOURCES: &[(&str, &str)] = SOURCES.1;

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

impl KernelVariant {
    /// The frame program's source text, as built in.
    pub fn source(self) -> &'static str {
        FRAME_SOURCES
            .iter()
            .find(|(file, _)| *file == self.file())
            .map_or("", |(_, text)| text)
    }

    /// The assembled program: the build's where the sources are the ones it assembled,
    /// else assembled now.
    pub fn program(self) -> Result<Program, String> {
        crate::runtime::assemble_kernel_with(self.source(), self.name(), self.defines())
    }
}
