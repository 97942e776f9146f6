//! The frame programs a render can run, declared once: the build script (`build.rs`
//! includes this file to assemble each one ahead of time), the runtime (which runs the one a
//! [`crate::render::RenderConfig`] names) and the profiler (which annotates the program
//! that ran) all iterate [`KernelVariant::ALL`]. A new variant is a kernel source, an entry
//! here, one `spu render` option and one test.
//!
//! Plain `const` data and `std` only, so that the build script can include it.

/// One frame program: a kernel source under `kernels/` assembled with its defines.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum KernelVariant {
    /// Primary rays, each pixel the eye-light grey of its hit (`kernels/primary.s`).
    Primary,
    /// Primary rays shaded by the shading module, with shadow rays where the frame's
    /// shading block asks for them (`kernels/primary.s` with `SHADE`).
    Shaded,
    /// The fill pattern that exercises the runtime without tracing (`kernels/fill.s`).
    Fill,
    /// [`KernelVariant::Primary`] for SPUs with several hint entries (the `multihint`
    /// extension, `docs/extensions.md`): data-dependent branches turned into `bi`s to
    /// `selb`-chosen targets hinted beside the loops' own hints, and the slow path and
    /// leaf paths reworked (`kernels/primary.s` with `EXT_MULTIHINT`).
    PrimaryMultihint,
    /// [`KernelVariant::Shaded`] with the reflection pass (`modules/reflect.s`): each
    /// primary packet's reflective hits spawn reflected rays, traced, shaded with shadows
    /// and blended in (`kernels/primary.s` with `SHADE` and `REFLECT`).
    Reflect,
    /// [`KernelVariant::Shaded`] for SPUs with the gather load (the `gather` extension,
    /// `docs/extensions.md`): the i-set's groups on different triangles looked up for
    /// their four lanes at once with `lgw`/`lgwx` (`kernels/primary.s` with `SHADE` and
    /// `EXT_GATHER`).
    ShadedGather,
}

impl KernelVariant {
    /// Every variant, in the order the build assembles them.
    pub const ALL: [KernelVariant; 6] = [
        KernelVariant::Primary,
        KernelVariant::Shaded,
        KernelVariant::Fill,
        KernelVariant::PrimaryMultihint,
        KernelVariant::Reflect,
        KernelVariant::ShadedGather,
    ];

    /// A short name: prebuilt file names, messages.
    pub const fn id(self) -> &'static str {
        match self {
            KernelVariant::Primary => "primary",
            KernelVariant::Shaded => "shaded",
            KernelVariant::Fill => "fill",
            KernelVariant::PrimaryMultihint => "primary-multihint",
            KernelVariant::Reflect => "reflect",
            KernelVariant::ShadedGather => "shaded-gather",
        }
    }

    /// The source file, relative to `kernels/`.
    pub const fn file(self) -> &'static str {
        match self {
            KernelVariant::Primary
            | KernelVariant::Shaded
            | KernelVariant::PrimaryMultihint
            | KernelVariant::Reflect
            | KernelVariant::ShadedGather => "primary.s",
            KernelVariant::Fill => "fill.s",
        }
    }

    /// The name diagnostics and the sources' hash use.
    pub const fn name(self) -> &'static str {
        match self {
            KernelVariant::Primary
            | KernelVariant::Shaded
            | KernelVariant::PrimaryMultihint
            | KernelVariant::Reflect
            | KernelVariant::ShadedGather => "kernels/primary.s",
            KernelVariant::Fill => "kernels/fill.s",
        }
    }

    /// The symbols defined as `--defsym` does before assembling.
    pub const fn defines(self) -> &'static [(&'static str, i64)] {
        match self {
            KernelVariant::Shaded => &[("SHADE", 1)],
            KernelVariant::PrimaryMultihint => &[("EXT_MULTIHINT", 1)],
            KernelVariant::Reflect => &[("SHADE", 1), ("REFLECT", 1)],
            KernelVariant::ShadedGather => &[("SHADE", 1), ("EXT_GATHER", 1)],
            KernelVariant::Primary | KernelVariant::Fill => &[],
        }
    }

    /// Whether the program traces rays (and so carves caches and packet contexts above its
    /// `cache_area`, and has its hits validated); the fill program only writes a pattern.
    pub const fn traces(self) -> bool {
        !matches!(self, KernelVariant::Fill)
    }

    /// Whether the program runs the shading module (and needs the frame's shading block).
    pub const fn shades(self) -> bool {
        matches!(
            self,
            KernelVariant::Shaded | KernelVariant::Reflect | KernelVariant::ShadedGather
        )
    }
}
