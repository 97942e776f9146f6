//! One render API: everything a frame of the ray tracer is made from, in one value
//! ([`RenderConfig`]), a scene prepared once for any number of frames ([`prepare`]), the
//! frame itself ([`render`]) and its check against the host reference ([`validate`]).
//! `spu render`, `spu paper`, `spu bench` and the tests all go through here, so a frame's
//! recipe (layout, kernel, SPUs, statistics) is written once, and nothing a frame depends on
//! is process-wide state: the engine, the timing model and the code cache are passed in.
//!
//! ```
//! use spu_loader::render::{prepare, render, validate, RenderConfig};
//! use spu_isa::jit::{CodeCache, Compiling};
//!
//! let scene = prepare("room").unwrap();
//! let config = RenderConfig {
//!     width: 16,
//!     height: 16,
//!     ..RenderConfig::new("room")
//! };
//! let frame = render(&scene, &config, &CodeCache::with(Compiling::Inline)).unwrap();
//! assert_eq!(frame.colours.len(), 16 * 16);
//! let validation = validate(&scene, &config, &frame).unwrap();
//! assert!(validation.passed(), "{:?}", validation.messages);
//! let stats = frame.stats(&config, Some(&validation));
//! assert_eq!(stats.frame_cycles, frame.run.frame_cycles);
//! ```

use crate::camera::Camera;
use crate::frame::{FrameLayout, SCENE_BASE};
use crate::kernel_abi::{self, PixelResult, ShadingBlock, MISS, SHADE_SHADOWS, SHADE_SIMPLE};
pub use crate::kernels::KernelVariant;
use crate::reference::Reference;
use crate::runtime::{FrameError, FrameRun, Program};
use crate::shading::{self, Light, ShadeMode};
use crate::{procedural, Bvh, BvhConfig, Scene, StagedScene};
use spu_isa::jit::{CodeCache, Engine};

/// What pixels get beyond their hit, and the shading module's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Shading {
    /// None for [`KernelVariant::Primary`] and [`KernelVariant::Fill`]; simple or shadows
    /// for [`KernelVariant::Shaded`].
    pub mode: ShadeMode,
    /// Point lights (at most [`shading::MAX_LIGHTS`]); empty: the scene's own
    /// ([`shading::default_lights_seen_from`]).
    pub lights: Vec<Light>,
    /// Shadow packets stop as soon as every ray is occluded.
    pub shadow_early: bool,
    /// Entries of the direct-mapped vertex cache (a power of two, 16 to 256).
    pub vertex_cache: u32,
    /// Entries of the direct-mapped material cache (a power of two, 16 to 256).
    pub material_cache: u32,
    /// Reflection bounces per primary ray with [`ShadeMode::Reflect`] (1 to
    /// [`shading::MAX_REFLECT_DEPTH`]).
    pub reflect_depth: u32,
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            mode: ShadeMode::None,
            lights: Vec::new(),
            shadow_early: false,
            vertex_cache: 64,
            material_cache: 64,
            reflect_depth: 1,
        }
    }
}

/// The most SPEs a frame runs on: a Cell has 8, the paper's dual-Cell blade 16; up to 64
/// are hypothetical Cells, sharing one memory interface (`docs/memory-model.md`).
pub const MAX_SPES: usize = 64;
/// The range of `--memory-bandwidth-gbs`: from a starved chip to far beyond any XDR.
pub const MIN_BANDWIDTH_GBS: f64 = 0.1;
/// The largest main-memory bandwidth a frame accepts, in GB/s.
pub const MAX_BANDWIDTH_GBS: f64 = 10_000.0;

/// Everything one frame is made from. The image, the cycles and every statistic depend
/// on these fields only (`threads` and `engine` change how fast the host gets there, not
/// what it gets).
#[derive(Clone, Debug, PartialEq)]
pub struct RenderConfig {
    /// The scene: a built-in name ([`procedural::by_name`]) or an OBJ/PLY file; the name
    /// of the [`Prepared`] scene the frame is rendered from, and what the statistics call it.
    pub scene: String,
    /// The camera; `None`: the scene's own.
    pub camera: Option<Camera>,
    pub width: u32,
    pub height: u32,
    /// Simulated SPEs, 1 to [`MAX_SPES`].
    pub spes: usize,
    /// Host threads running the SPEs and the reference (at least 1).
    pub threads: usize,
    /// SPU clock in GHz.
    pub clock_ghz: f64,
    /// Main-memory latency of a DMA in nanoseconds before its bytes move.
    pub dma_latency_ns: f64,
    /// Main-memory bandwidth of the Cell in GB/s, shared by all its SPEs
    /// (`docs/memory-model.md`).
    pub memory_bandwidth_gbs: f64,
    /// Lines of the BVH-node cache (a power of two, 128 to 1024).
    pub bvh_cache: u32,
    /// Lines of the triangle cache (a power of two, 128 to 1024).
    pub tri_cache: u32,
    /// Ways of both caches: 1 (direct mapped) or 4 (set-associative, LRU).
    pub assoc: u32,
    /// Packets each SPE keeps in flight (software hyperthreading, 1 to 8; 1 = blocking).
    pub sht: u32,
    pub shading: Shading,
    /// The frame program; [`KernelVariant::Shaded`] exactly when `shading.mode` shades.
    pub kernel: KernelVariant,
    /// What runs the SPUs' instructions (results are the same with either).
    pub engine: Engine,
    /// The timing model: off, a faster functional run without the pipeline's stalls and
    /// with no profile (the image is the same; the cycles are not the paper's).
    pub timing: bool,
    /// Simulated cycles per SPU before the frame gives up.
    pub max_cycles: u64,
    /// Log every SPU's MFC commands and channel waits (heat maps, timelines).
    pub event_log: bool,
    /// The ISA extensions the SPUs run with (`docs/extensions.md`; none: the real SPU).
    pub extensions: spu_isa::Extensions,
}

impl RenderConfig {
    /// The `spu render` defaults for `scene`: 1024x1024 primary rays on one 2.4 GHz SPE,
    /// 256-line direct-mapped caches, 4 packets in flight, 100 ns memory.
    pub fn new(scene: &str) -> RenderConfig {
        RenderConfig {
            scene: scene.to_string(),
            camera: None,
            width: 1024,
            height: 1024,
            spes: 1,
            threads: 1,
            clock_ghz: 2.4,
            dma_latency_ns: 100.0,
            memory_bandwidth_gbs: 25.6,
            bvh_cache: 256,
            tri_cache: 256,
            assoc: 1,
            sht: 4,
            shading: Shading::default(),
            kernel: KernelVariant::Primary,
            engine: Engine::host_default(),
            timing: true,
            max_cycles: 200_000_000_000,
            event_log: false,
            extensions: spu_isa::Extensions::NONE,
        }
    }

    /// [`RenderConfig::kernel_for`] on SPUs with the extensions `ext`: primary rays with
    /// several hint entries run the kernel that hints for them, shading with the gather
    /// load the kernel that gathers.
    pub fn kernel_with(fill: bool, mode: ShadeMode, ext: spu_isa::Extensions) -> KernelVariant {
        match Self::kernel_for(fill, mode) {
            KernelVariant::Primary if ext.enables(spu_isa::Extension::MultiHint) => {
                KernelVariant::PrimaryMultihint
            }
            KernelVariant::Shaded if ext.enables(spu_isa::Extension::Gather) => {
                KernelVariant::ShadedGather
            }
            kernel => kernel,
        }
    }

    /// The kernel that runs a frame with `mode`: the fill program where `fill`, else the
    /// primary kernel, shaded where `mode` shades.
    pub fn kernel_for(fill: bool, mode: ShadeMode) -> KernelVariant {
        match (fill, mode) {
            (true, _) => KernelVariant::Fill,
            (false, ShadeMode::None) => KernelVariant::Primary,
            (false, ShadeMode::Reflect) => KernelVariant::Reflect,
            (false, _) => KernelVariant::Shaded,
        }
    }

    /// Whether the frame can be rendered: every number in range, the shading settings
    /// those of the kernel. [`render`] checks it before any work.
    pub fn check(&self) -> Result<(), String> {
        let within = |what: &str, value: u64, low: u64, high: u64| {
            if (low..=high).contains(&value) {
                Ok(())
            } else {
                Err(format!("{what} {value}: must be {low} to {high}"))
            }
        };
        within("SPEs", self.spes as u64, 1, MAX_SPES as u64)?;
        within("width", self.width as u64, 1, 8192)?;
        within("height", self.height as u64, 1, 8192)?;
        within("threads", self.threads as u64, 1, 1024)?;
        within("packets in flight", self.sht as u64, 1, 8)?;
        within("max cycles", self.max_cycles, 1, u64::MAX)?;
        if !(self.clock_ghz.is_finite() && (0.01..=100.0).contains(&self.clock_ghz)) {
            return Err(format!("clock {} GHz: must be 0.01 to 100", self.clock_ghz));
        }
        if !(self.dma_latency_ns.is_finite() && (0.0..=1e6).contains(&self.dma_latency_ns)) {
            return Err(format!(
                "DMA latency {} ns: must be 0 to 1000000",
                self.dma_latency_ns
            ));
        }
        if !(self.memory_bandwidth_gbs.is_finite()
            && (MIN_BANDWIDTH_GBS..=MAX_BANDWIDTH_GBS).contains(&self.memory_bandwidth_gbs))
        {
            return Err(format!(
                "memory bandwidth {} GB/s: must be {MIN_BANDWIDTH_GBS} to {MAX_BANDWIDTH_GBS}",
                self.memory_bandwidth_gbs
            ));
        }
        kernel_abi::check_kernel_options(self.bvh_cache, self.tri_cache, self.assoc, self.sht)?;
        let s = &self.shading;
        for (what, n) in [("vertex", s.vertex_cache), ("material", s.material_cache)] {
            if !(n.is_power_of_two() && (16..=256).contains(&n)) {
                return Err(format!(
                    "{what} cache of {n} entries: must be a power of two from 16 to 256"
                ));
            }
        }
        if s.lights.len() > shading::MAX_LIGHTS {
            return Err(format!(
                "{} lights: at most {}",
                s.lights.len(),
                shading::MAX_LIGHTS
            ));
        }
        within(
            "reflection depth",
            s.reflect_depth as u64,
            1,
            shading::MAX_REFLECT_DEPTH as u64,
        )?;
        if (self.kernel == KernelVariant::Reflect) != (s.mode == ShadeMode::Reflect) {
            return Err(format!(
                "the {} kernel {} shading {}",
                self.kernel.id(),
                if self.kernel == KernelVariant::Reflect {
                    "needs"
                } else {
                    "does not do"
                },
                ShadeMode::Reflect.name()
            ));
        }
        if self.kernel.shades() != (s.mode != ShadeMode::None) {
            return Err(format!(
                "the {} kernel {} shading {}",
                self.kernel.id(),
                if self.kernel.shades() {
                    "needs"
                } else {
                    "does not do"
                },
                s.mode.name()
            ));
        }
        if self.kernel == KernelVariant::ShadedGather
            && !self.extensions.enables(spu_isa::Extension::Gather)
        {
            return Err(
                "the shaded-gather kernel needs the gather extension (--ext gather)".into(),
            );
        }
        Ok(())
    }
}

/// A scene ready for frames: loaded, its BVH built and staged in main memory's layout.
/// Frames of any configuration share one (`spu paper` keeps each scene while frames of it
/// remain).
pub struct Prepared {
    /// The name [`RenderConfig::scene`] gives it.
    pub name: String,
    pub scene: Scene,
    pub staged: StagedScene,
}

impl Prepared {
    /// `scene`, built (on the host's cores) and staged, under `name`.
    pub fn from_scene(name: &str, scene: Scene) -> Result<Prepared, String> {
        Prepared::from_scene_on(name, scene, BvhConfig::default().threads)
    }

    /// [`Prepared::from_scene`] with the BVH built on `threads` host threads (`--threads`:
    /// 1 is one thread; the hierarchy does not depend on it).
    pub fn from_scene_on(name: &str, scene: Scene, threads: usize) -> Result<Prepared, String> {
        let config = BvhConfig {
            threads: threads.max(1),
            ..BvhConfig::default()
        };
        let bvh = Bvh::build(&scene, &config);
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE)?;
        Ok(Prepared {
            name: name.to_string(),
            scene,
            staged,
        })
    }
}

/// Loads the built-in scene or the file `scene` and prepares it on the host's cores.
pub fn prepare(scene: &str) -> Result<Prepared, String> {
    prepare_on(scene, BvhConfig::default().threads)
}

/// [`prepare`] with the BVH built on `threads` host threads (`--threads`).
pub fn prepare_on(scene: &str, threads: usize) -> Result<Prepared, String> {
    let loaded = match procedural::by_name(scene) {
        Some(built_in) => built_in,
        None => Scene::load(scene).map_err(|e| e.to_string())?,
    };
    Prepared::from_scene_on(scene, loaded, threads)
}

/// A rendered frame: the runtime's outcome and the image.
pub struct FrameResult {
    /// The frame buffers, cycles, per-SPU counters, profile and the program that ran.
    pub run: FrameRun,
    /// The image, row by row, as `0xRRGGBBAA`.
    pub colours: Vec<u32>,
    /// The layout the frame ran in (heat maps and timelines place packets by it).
    pub layout: FrameLayout,
    /// The lights the frame was shaded with (empty for an unshaded frame).
    pub lights: Vec<Light>,
}

impl FrameResult {
    /// The frame's statistics, with the validation where there was one.
    pub fn stats(
        &self,
        config: &RenderConfig,
        validation: Option<&Validation>,
    ) -> crate::stats::FrameStats {
        crate::stats::FrameStats::new(
            &self.run,
            &crate::stats::FrameSetup {
                scene: &config.scene,
                width: config.width,
                height: config.height,
                clock_ghz: config.clock_ghz,
            },
            validation.map(|v| crate::stats::Validation {
                pixels: v.pixels,
                mismatches: v.mismatches,
                colour_mismatches: v.colour_mismatches,
                shadow_edge_pixels: v.shadow_edge_pixels,
            }),
        )
    }

    /// The annotated listing of the program that ran (per instruction: executions, cycles,
    /// stalls by cause, dual issue; then per label and totals), merged over all SPUs.
    pub fn profile_listing(&self) -> Result<String, String> {
        use spu_isa::profile::{annotated_listing, executed_lines, ListingOptions};
        let profile = self
            .run
            .profile
            .as_ref()
            .ok_or("no profile: the frame ran without the timing model")?;
        let lines = executed_lines(profile, &self.run.kernel_image, &self.run.symbols);
        let opts = ListingOptions {
            range: None,
            executed_only: true,
        };
        Ok(annotated_listing(profile, &lines, &opts))
    }
}

/// The layout of a frame of `config` for `program`, whole: the scene's records, the
/// parameter block with the caches and packets in flight, and for a shaded frame the
/// shading block, the colour buffer and the shading module's area in local store (above
/// everything the kernel carves at its `cache_area`).
pub fn frame_layout(
    prepared: &Prepared,
    config: &RenderConfig,
    program: &Program,
    lights: &[Light],
) -> Result<FrameLayout, String> {
    let staged = &prepared.staged;
    let basis = camera(prepared, config).basis(config.width, config.height);
    let layout = FrameLayout::new(
        staged,
        &basis,
        config.width,
        config.height,
        config.spes,
        config.bvh_cache,
        config.tri_cache,
    )?
    .with_kernel_options(config.assoc, config.sht)?;
    if !config.kernel.shades() {
        return Ok(layout);
    }
    let s = &config.shading;
    let mut layout = layout.with_shading(
        staged,
        ShadingBlock {
            mode: if s.mode.shadows() {
                SHADE_SHADOWS
            } else {
                SHADE_SIMPLE
            },
            reflect_depth: if s.mode == ShadeMode::Reflect {
                s.reflect_depth
            } else {
                0
            },
            shadow_early: s.shadow_early,
            vertex_cache_log2: s.vertex_cache.trailing_zeros(),
            material_cache_log2: s.material_cache.trailing_zeros(),
            lights: lights.to_vec(),
            ..Default::default()
        },
    )?;
    let start = program
        .symbols
        .iter()
        .find(|(n, _)| n == "cache_area")
        .map(|(_, a)| *a)
        .ok_or("the kernel has no cache_area")?;
    let carved = kernel_abi::carved_bytes(config.bvh_cache, config.tri_cache, config.sht);
    layout.set_shading_area(start + carved)?;
    Ok(layout)
}

/// The frame's camera: the configuration's, else the scene's.
fn camera<'a>(prepared: &'a Prepared, config: &'a RenderConfig) -> &'a Camera {
    config.camera.as_ref().unwrap_or(&prepared.scene.camera)
}

/// The lights a shaded frame of `config` uses: the configuration's, else the scene's.
pub fn lights(prepared: &Prepared, config: &RenderConfig) -> Vec<Light> {
    if !config.kernel.shades() {
        Vec::new()
    } else if config.shading.lights.is_empty() {
        shading::default_lights_seen_from(&prepared.scene, camera(prepared, config))
    } else {
        config.shading.lights.clone()
    }
}

/// Renders one frame of `prepared` as `config` says, the SPEs sharing the compiled blocks
/// of `code` (and adding theirs to it: later frames reuse them; results do not depend on
/// it).
pub fn render(
    prepared: &Prepared,
    config: &RenderConfig,
    code: &CodeCache,
) -> Result<FrameResult, FrameError> {
    render_with(prepared, config, code, &mut |_, _| {})
}

/// [`render`], telling `progress` the tiles taken so far and the frame's tiles.
pub fn render_with(
    prepared: &Prepared,
    config: &RenderConfig,
    code: &CodeCache,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<FrameResult, FrameError> {
    config.check()?;
    if prepared.name != config.scene {
        return Err(FrameError::Setup(format!(
            "the frame is of scene {:?}, the prepared scene is {:?}",
            config.scene, prepared.name
        )));
    }
    let program = config.kernel.program()?;
    let lights = lights(prepared, config);
    let layout = frame_layout(prepared, config, &program, &lights)?;
    let run = crate::runtime::run_frame(
        &crate::runtime::Frame {
            staged: &prepared.staged,
            layout: &layout,
            program: &program,
            kernel: config.kernel,
            spes: config.spes,
            threads: config.threads,
            timing: spu_isa::timing::TimingConfig {
                clock_ghz: config.clock_ghz,
                dma_latency_ns: config.dma_latency_ns,
                memory_bandwidth_gbs: config.memory_bandwidth_gbs,
                ..Default::default()
            },
            timed: config.timing,
            engine: config.engine,
            max_cycles: config.max_cycles,
            event_log: config.event_log,
            code,
            extensions: config.extensions,
        },
        progress,
    )?;
    let colours = match &run.colour_buffer {
        Some(buffer) => kernel_abi::decode_colour_buffer(buffer, config.width, config.height),
        None => {
            kernel_abi::decode_frame_buffer_colours(&run.frame_buffer, config.width, config.height)
        }
    };
    Ok(FrameResult {
        run,
        colours,
        layout,
        lights,
    })
}

/// A frame against the host reference.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Validation {
    pub pixels: usize,
    /// Pixels whose hit (triangle, or distance within 1e-4 relative) differs.
    pub mismatches: usize,
    /// Shaded frames: pixels whose colour differs by more than
    /// [`shading::COLOUR_TOLERANCE`] in a channel.
    pub colour_mismatches: Option<usize>,
    /// Shadows: pixels beyond the tolerance that take the colour of a shadow ray grazing an
    /// occluder's edge, which either outcome gives (not counted as mismatches).
    pub shadow_edge_pixels: Option<usize>,
    /// Shaded frames: pixels beyond the tolerance that hit, at the reference's distance,
    /// another triangle sharing an edge with the reference's and take its colour (not
    /// counted as mismatches).
    pub edge_ties: usize,
    /// Reflect frames: per bounce (the first reflection first), the reflected rays the
    /// reference casts, and the pixels whose ray differs (cast or not, its hit triangle or
    /// distance as the primary hits are compared).
    pub bounce_rays: Vec<usize>,
    pub bounce_mismatches: Vec<usize>,
    /// The first few differences, described (colours first, then hits).
    pub messages: Vec<String>,
}

impl Validation {
    /// No pixel differs.
    pub fn passed(&self) -> bool {
        self.mismatches
            + self.colour_mismatches.unwrap_or(0)
            + self.bounce_mismatches.iter().sum::<usize>()
            == 0
    }
}

/// Differences described per kind before the rest are only counted.
const MESSAGES: usize = 10;

/// Compares every pixel of `frame` (rendered from `prepared` as `config` says) with the
/// host reference: its hit, and for a shaded frame its colour.
pub fn validate(
    prepared: &Prepared,
    config: &RenderConfig,
    frame: &FrameResult,
) -> Result<Validation, String> {
    if !config.kernel.traces() {
        return Err(format!(
            "the {} program traces no rays to compare",
            config.kernel.id()
        ));
    }
    let (width, height) = (config.width, config.height);
    let pixels = kernel_abi::decode_frame_buffer(&frame.run.frame_buffer, width, height);
    let staged = &prepared.staged;
    let reference = Reference::from_staged(staged);
    let camera = camera(prepared, config);
    let hits = reference.render(camera, width, height, config.threads);
    let mut validation = Validation {
        pixels: pixels.len(),
        ..Validation::default()
    };
    let reflect = (config.shading.mode == ShadeMode::Reflect).then(|| {
        crate::reflection::ReflectFrame::render(
            &reference,
            &hits,
            camera,
            width,
            height,
            &frame.lights,
            config.shading.reflect_depth,
            config.threads,
        )
    });
    if frame.run.colour_buffer.is_some() {
        // Reflect frames shade every level with shadows; a grazing shadow ray's or an
        // edge's other outcome is looked for where the pixel is its primary hit's colour
        // alone (it casts no reflected ray), not in a blend.
        let shadows = config.shading.mode.shadows();
        let unblended = |i: usize| {
            reflect
                .as_ref()
                .is_none_or(|r| r.bounces.first().is_none_or(|b| b[i].is_none()))
        };
        let lights = &frame.lights;
        let expected = match &reflect {
            Some(r) => r.colours.clone(),
            None => reference.shade_image(
                &hits,
                camera,
                width,
                height,
                lights,
                shadows,
                config.threads,
            ),
        };
        let basis = camera.basis(width, height);
        let ray = |i: usize| {
            (
                basis.origin,
                basis.direction(i as u32 % width, i as u32 / width),
            )
        };
        let within = |i: usize, c: u32| {
            shading::channel_difference(frame.colours[i], c) <= shading::COLOUR_TOLERANCE
        };
        let (mut off, mut edges) = (0, 0);
        for (i, (&c, &e)) in frame.colours.iter().zip(&expected).enumerate() {
            if shading::channel_difference(c, e) <= shading::COLOUR_TOLERANCE {
                continue;
            }
            let (origin, dir) = ray(i);
            // A shadow ray grazing an occluder's edge may give either outcome's colour
            // (Reference::shade_alternatives).
            if shadows
                && unblended(i)
                && reference
                    .shade_alternatives(&hits[i], origin, dir, lights)
                    .iter()
                    .any(|&a| within(i, a))
            {
                edges += 1;
                continue;
            }
            // A ray hitting an edge two triangles share may take the kernel's triangle's
            // colour (Reference::shade_edge_tie).
            let tie = reference.shade_edge_tie(
                &hits[i],
                pixels[i].triangle,
                origin,
                dir,
                lights,
                shadows,
            );
            if unblended(i) && tie.is_some_and(|t| within(i, t)) {
                validation.edge_ties += 1;
                continue;
            }
            if off < MESSAGES {
                validation.messages.push(format!(
                    "colour mismatch at ({}, {}): kernel {c:08x} / reference {e:08x}",
                    i as u32 % width,
                    i as u32 / width
                ));
            }
            off += 1;
        }
        validation.colour_mismatches = Some(off);
        validation.shadow_edge_pixels = shadows.then_some(edges);
    }
    let record_to_original: Vec<u32> = staged.triangles.iter().map(|t| t.original_index).collect();
    let (mismatches, messages) = compare_hits(
        &pixels,
        &hits,
        &record_to_original,
        width,
        PRIMARY_T_TOLERANCE,
    );
    validation.mismatches = mismatches;
    validation.messages.extend(messages);
    if let (Some(r), Some(buffer)) = (&reflect, &frame.run.bounce_hits) {
        let depth = config.shading.reflect_depth;
        for (k, expected) in r.bounces.iter().enumerate() {
            let kernel = decode_bounce_hits(buffer, width, height, depth, k as u32);
            let cast: Vec<bool> = kernel.iter().map(|(_, cast)| *cast).collect();
            let as_pixels: Vec<PixelResult> = kernel.iter().map(|(p, _)| *p).collect();
            // a ray the reference does not cast is compared as a miss the kernel must not
            // cast either
            let reference_hits: Vec<crate::reference::Hit> = expected
                .iter()
                .map(|h| h.unwrap_or(crate::reference::Hit::NONE))
                .collect();
            let (mut bad, mut messages) = compare_hits(
                &as_pixels,
                &reference_hits,
                &record_to_original,
                width,
                BOUNCE_T_TOLERANCE,
            );
            for (i, (e, &c)) in expected.iter().zip(&cast).enumerate() {
                if e.is_some() != c {
                    if messages.len() < MESSAGES {
                        messages.push(format!(
                            "bounce {} at ({}, {}): the kernel {} a ray, the reference {}",
                            k + 1,
                            i as u32 % width,
                            i as u32 / width,
                            if c { "casts" } else { "casts no" },
                            if e.is_some() { "does" } else { "does not" }
                        ));
                    }
                    bad += 1;
                }
            }
            validation.messages.extend(
                messages
                    .into_iter()
                    .map(|m| format!("bounce {}: {m}", k + 1)),
            );
            validation
                .bounce_rays
                .push(expected.iter().flatten().count());
            validation.bounce_mismatches.push(bad);
        }
    }
    Ok(validation)
}

/// Bounce `bounce`'s hits (0: the first reflection) of a reflect frame's bounce-hit
/// buffer ([`crate::kernel_abi::bounce_hits_bytes`]), row-major: the hit (record or
/// [`MISS`], t) and whether the pixel cast a ray (t = 0 where not: the kernel writes 0, or
/// nothing for a packet that casts none).
pub fn decode_bounce_hits(
    buffer: &[u8],
    width: u32,
    height: u32,
    depth: u32,
    bounce: u32,
) -> Vec<(PixelResult, bool)> {
    let tiles_x = width.div_ceil(kernel_abi::TILE_SIZE);
    let word = |at: usize| {
        buffer
            .get(at..at + 4)
            .map_or(0, |w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]))
    };
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let (block, index) = kernel_abi::pixel_location(x, y, tiles_x);
            let packet = block / kernel_abi::PACKET_BLOCK_BYTES as usize;
            let at = (packet * depth as usize + bounce as usize) * 512 + 4 * index;
            // a packet that casts no ray of the bounce puts nothing: zeros, as t = 0 says
            let t = f32::from_bits(word(at + 256));
            let cast = t != 0.0;
            out.push((
                PixelResult {
                    triangle: if cast { word(at) } else { MISS },
                    t,
                    rgba: 0,
                },
                cast,
            ));
        }
    }
    out
}

/// Per-pixel hits against the reference's: the pixels that differ, the first few described.
/// Primary hits agree when their distances differ by at most this fraction: kernel and
/// reference trace the very same rays.
const PRIMARY_T_TOLERANCE: (f32, f32) = (1e-4, 0.0);
/// Reflected hits agree within this fraction, or within 1/256 of the offset a reflected
/// ray starts off its surface: the kernel computes the reflected ray in its own rounding
/// (a reciprocal estimate and a Newton step for 1 / N.N, fused multiply-adds, its own hit
/// point), which a grazing ray that hits its own surface again turns into a larger
/// difference of distance (the beetle's 0.0041071 against 0.0041066), and a ray that hits
/// right beside its start (the room's table legs, t = 0.0003) into a larger fraction.
const BOUNCE_T_TOLERANCE: (f32, f32) = (1e-3, shading::REFLECT_OFFSET / 256.0);

fn compare_hits(
    pixels: &[PixelResult],
    reference: &[crate::reference::Hit],
    record_to_original: &[u32],
    width: u32,
    (tolerance, absolute): (f32, f32),
) -> (usize, Vec<String>) {
    let mut mismatches = 0;
    let mut messages = Vec::new();
    let close = |a: f32, b: f32| {
        let d = (a - b).abs();
        d <= tolerance * a.abs().max(b.abs()).max(1e-30) || d <= absolute
    };
    for (i, (p, r)) in pixels.iter().zip(reference).enumerate() {
        let kernel_tri = if p.triangle == MISS {
            MISS
        } else {
            record_to_original
                .get(p.triangle as usize)
                .copied()
                .unwrap_or(u32::MAX - 1)
        };
        // Either triangle at the same distance: rays through a shared edge may hit either.
        let ok = match (kernel_tri == MISS, r.is_hit()) {
            (true, false) => true,
            (false, true) => close(p.t, r.t),
            _ => false,
        };
        if !ok {
            if mismatches < MESSAGES {
                messages.push(format!(
                    "mismatch at ({}, {}): kernel triangle {} t {} / reference triangle {} t {}",
                    i as u32 % width,
                    i as u32 / width,
                    kernel_tri as i64,
                    p.t,
                    r.triangle as i64,
                    r.t
                ));
            }
            mismatches += 1;
        }
    }
    (mismatches, messages)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::Hit;

    #[test]
    fn hits_differ_by_miss_or_distance_not_by_a_triangle_at_the_same_distance() {
        let pixel = |triangle, t| PixelResult {
            triangle,
            t,
            rgba: 0,
        };
        let hit = |triangle, t| Hit {
            triangle,
            t,
            record: 0,
        };
        let kernel = [pixel(0, 1.0), pixel(MISS, 0.0), pixel(1, 2.0)];
        let records = [10, 11];
        let same = [hit(10, 1.0), Hit::NONE, hit(12, 2.0)];
        assert_eq!(
            compare_hits(&kernel, &same, &records, 3, PRIMARY_T_TOLERANCE).0,
            0
        );
        // A miss where the reference hits, and a hit at another distance.
        let other = [hit(10, 1.0), hit(10, 5.0), hit(11, 2.5)];
        let (bad, messages) = compare_hits(&kernel, &other, &records, 3, PRIMARY_T_TOLERANCE);
        assert_eq!(bad, 2);
        assert_eq!(
            messages[0],
            "mismatch at (1, 0): kernel triangle 4294967295 t 0 / reference triangle 10 t 5"
        );
    }

    #[test]
    fn a_configuration_is_checked_before_any_work() {
        let ok = RenderConfig::new("room");
        assert_eq!(ok.check(), Ok(()));
        let shaded = RenderConfig {
            shading: Shading {
                mode: ShadeMode::Simple,
                ..Shading::default()
            },
            ..ok.clone()
        };
        assert_eq!(
            shaded.check(),
            Err("the primary kernel does not do shading simple".into())
        );
        let shaded = RenderConfig {
            kernel: RenderConfig::kernel_for(false, ShadeMode::Simple),
            ..shaded
        };
        assert_eq!(shaded.kernel, KernelVariant::Shaded);
        assert_eq!(shaded.check(), Ok(()));
        for bad in [
            RenderConfig {
                spes: 65,
                ..ok.clone()
            },
            RenderConfig {
                sht: 9,
                ..ok.clone()
            },
            RenderConfig {
                assoc: 2,
                ..ok.clone()
            },
            RenderConfig {
                bvh_cache: 100,
                ..ok.clone()
            },
            RenderConfig {
                clock_ghz: f64::NAN,
                ..ok.clone()
            },
            RenderConfig {
                max_cycles: 0,
                ..ok.clone()
            },
            RenderConfig {
                threads: 0,
                ..ok.clone()
            },
            RenderConfig {
                shading: Shading {
                    reflect_depth: 5,
                    ..Shading::default()
                },
                ..ok.clone()
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
        }
        let reflect = RenderConfig {
            shading: Shading {
                mode: ShadeMode::Reflect,
                ..Shading::default()
            },
            kernel: RenderConfig::kernel_for(false, ShadeMode::Reflect),
            ..ok.clone()
        };
        assert_eq!(reflect.kernel, KernelVariant::Reflect);
        assert_eq!(reflect.check(), Ok(()));
        let not_reflecting = RenderConfig {
            kernel: KernelVariant::Shaded,
            ..reflect.clone()
        };
        assert_eq!(
            not_reflecting.check(),
            Err("the shaded kernel does not do shading reflect".into())
        );
        let wrong_scene = prepare("room").map(|mut p| {
            p.name = "beetle".into();
            p
        });
        let code = CodeCache::with(spu_isa::jit::Compiling::Inline);
        match render(&wrong_scene.unwrap(), &ok, &code) {
            Err(FrameError::Setup(m)) => assert!(m.contains("prepared scene"), "{m}"),
            _ => panic!("a frame of another scene is refused"),
        }
    }

    #[test]
    fn a_scene_prepared_on_one_thread_is_the_one_prepared_on_several() {
        // `--threads 1` builds the BVH on one thread: the staged scene is the same
        let one = prepare_on("conference", 1).unwrap();
        for threads in [2, 3] {
            let more = prepare_on("conference", threads).unwrap();
            assert!(one.staged.image == more.staged.image, "{threads} threads");
        }
    }
}
