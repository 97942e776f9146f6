//! `spu render`: ray-trace a scene with the SPU kernels on 1 to 16 simulated SPEs, as the
//! paper's PPE would drive them, and report the image, the statistics and the validation
//! against the host reference.

use crate::exit::{self, Error, Status};
use crate::options;
use spu_loader::camera::Camera;
use spu_loader::frame::FrameLayout;
use spu_loader::kernel_abi::{decode_colour_buffer, ShadingBlock, SHADE_SHADOWS, SHADE_SIMPLE};
use spu_loader::kernel_abi::{decode_frame_buffer, decode_frame_buffer_colours, PixelResult, MISS};
use spu_loader::reference::Reference;
use spu_loader::runtime::FrameError;
use spu_loader::shading::{self, Light, ShadeMode};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Engine: the block compiler (jit, the default where the host has one; the SPEs
    /// share their compiled blocks) or the interpreter (interp). Results are the same;
    /// only host speed differs.
    #[arg(long, default_value_t = spu_isa::jit::Engine::host_default())]
    engine: spu_isa::jit::Engine,
    #[command(flatten)]
    compile: crate::options::CompileOption,
    /// A built-in scene (room, conference, beetle) or an OBJ/PLY file (optionally .gz).
    #[arg(long, default_value = "room")]
    scene: String,
    #[arg(long, default_value_t = 1024)]
    width: u32,
    #[arg(long, default_value_t = 1024)]
    height: u32,
    /// Simulated SPEs (1..16).
    #[arg(long, default_value_t = 1)]
    spes: usize,
    /// Host threads running the SPEs (results do not depend on it).
    #[arg(long)]
    threads: Option<usize>,
    /// SPU clock in GHz (2.4 for the paper's blade, 3.2 for a PlayStation 3).
    #[arg(long, default_value_t = 2.4)]
    clock: f64,
    /// Camera override: ex,ey,ez,tx,ty,tz,ux,uy,uz,fov.
    #[arg(long, allow_hyphen_values = true)]
    camera: Option<String>,
    /// Lines in the BVH-node cache (power of two, 128..1024).
    #[arg(long = "bvh-cache", default_value_t = 256, value_parser = cache_lines)]
    bvh_cache: u32,
    /// Lines in the triangle cache (power of two, 128..1024).
    #[arg(long = "tri-cache", default_value_t = 256, value_parser = cache_lines)]
    tri_cache: u32,
    /// Ways of both caches: 1 (direct mapped) or 4 (set-associative, LRU).
    #[arg(long, default_value_t = 1, value_parser = associativity)]
    assoc: u32,
    /// Packets each SPE keeps in flight (software hyperthreading, 1..8; 1 = blocking misses).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=8))]
    sht: u32,
    /// Main-memory latency of a DMA in nanoseconds before its bytes move.
    #[arg(long = "dma-latency-ns", default_value_t = 100.0, value_parser = latency_ns, allow_hyphen_values = true)]
    dma_latency_ns: f64,
    /// Run the fill pattern program instead of the ray tracer (tests the runtime).
    #[arg(long)]
    fill: bool,
    /// What each pixel gets: none (primary rays, the eye-light grey), simple (diffuse
    /// shading with the material colour and the interpolated normal, point lights) or
    /// shadows (simple plus one shadow ray per light).
    #[arg(long, default_value = "none", value_parser = ShadeMode::parse)]
    shade: ShadeMode,
    /// A point light x,y,z[,r,g,b] (repeatable, up to 8; default: the scene's own).
    #[arg(long = "light", value_parser = Light::parse, allow_hyphen_values = true)]
    lights: Vec<Light>,
    /// Shadow packets stop as soon as every ray is occluded (on|off).
    #[arg(long = "shadow-early", default_value = "off", value_parser = shadow_early, action = clap::ArgAction::Set)]
    shadow_early: bool,
    /// Entries of the direct-mapped vertex cache (power of two, 16..256).
    #[arg(long = "vertex-cache", default_value_t = 64, value_parser = shading_cache)]
    vertex_cache: u32,
    /// Entries of the direct-mapped material cache (power of two, 16..256).
    #[arg(long = "material-cache", default_value_t = 64, value_parser = shading_cache)]
    material_cache: u32,
    /// Output image (PNG).
    #[arg(short = 'o', long, default_value = "render.png")]
    output: PathBuf,
    /// Statistics as JSON.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Compare every pixel's triangle and distance with the host reference.
    #[arg(long)]
    validate: bool,
    /// Simulated cycles per SPU before giving up.
    #[arg(long, default_value_t = 200_000_000_000)]
    max_cycles: u64,
    /// Write the kernel's annotated profile (per instruction: executions, cycles, stalls
    /// by cause, dual issue; then per label and totals), merged over all SPEs.
    #[arg(long)]
    profile: Option<PathBuf>,
    /// Heat map of the simulated cycles per packet (PNG), and beside it (NAME-wait.png)
    /// the share of them spent waiting on DMA.
    #[arg(long)]
    heatmap: Option<PathBuf>,
    /// Timeline of the frame over simulated time (Chrome/Perfetto trace JSON).
    #[arg(long)]
    trace: Option<PathBuf>,
    /// No progress bar or summary (for `spu paper`, which runs many renders at once).
    #[arg(long, hide = true)]
    quiet: bool,
}

/// `--bvh-cache` / `--tri-cache`: a power of two from 128 to 1024.
fn cache_lines(text: &str) -> Result<u32, String> {
    let lines: u32 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a number of cache lines"))?;
    spu_loader::kernel_abi::check_kernel_options(lines, lines, 1, 1)
        .map_err(|_| format!("{lines} lines: must be a power of two from 128 to 1024"))?;
    Ok(lines)
}

/// Whether the kernel traces shadow packets (`--shade shadows`); until it does, the mode
/// is refused before any work and `spu paper` says why its shadow rows are empty.
pub const KERNEL_TRACES_SHADOWS: bool = true;

/// `--shadow-early`: on or off.
fn shadow_early(text: &str) -> Result<bool, String> {
    shading::parse_on_off("--shadow-early", text)
}

/// `--vertex-cache` / `--material-cache`: a power of two from 16 to 256 entries.
fn shading_cache(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(n) if n.is_power_of_two() && (16..=256).contains(&n) => Ok(n),
        _ => Err(format!(
            "{text:?}: must be a power of two from 16 to 256 entries"
        )),
    }
}

/// `--assoc`: 1 or 4 ways.
fn associativity(text: &str) -> Result<u32, String> {
    match text {
        "1" => Ok(1),
        "4" => Ok(4),
        _ => Err(format!(
            "{text:?}: must be 1 (direct mapped) or 4 (4-way, LRU)"
        )),
    }
}

/// `--dma-latency-ns`: finite, not negative, at most a millisecond.
fn latency_ns(text: &str) -> Result<f64, String> {
    let ns: f64 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a latency in nanoseconds"))?;
    if !ns.is_finite() || !(0.0..=1e6).contains(&ns) {
        return Err(format!(
            "{ns} ns: must be a finite latency from 0 to 1000000 ns"
        ));
    }
    Ok(ns)
}

/// Per-pixel comparison with the reference: (pixels, mismatches); the first few
/// mismatches are printed.
fn validate(
    pixels: &[PixelResult],
    reference: &[spu_loader::reference::Hit],
    record_to_original: &[u32],
    width: u32,
) -> (usize, usize) {
    let mut mismatches = 0;
    for (i, (p, r)) in pixels.iter().zip(reference).enumerate() {
        let kernel_tri = if p.triangle == MISS {
            MISS
        } else {
            record_to_original
                .get(p.triangle as usize)
                .copied()
                .unwrap_or(u32::MAX - 1)
        };
        let same_triangle = kernel_tri == r.triangle;
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-30);
        let ok = match (kernel_tri == MISS, r.is_hit()) {
            (true, false) => true,
            (false, true) => {
                same_triangle && close(p.t, r.t) || (!same_triangle && close(p.t, r.t))
            }
            _ => false,
        };
        if !ok {
            if mismatches < 10 {
                eprintln!(
                    "mismatch at ({}, {}): kernel triangle {} t {} / reference triangle {} t {}",
                    i as u32 % width,
                    i as u32 / width,
                    kernel_tri as i64,
                    p.t,
                    r.triangle as i64,
                    r.t
                );
            }
            mismatches += 1;
        }
    }
    (pixels.len(), mismatches)
}

/// Every option checked before the scene is loaded: numbers in range, output paths
/// writable and in a format the command writes.
fn check_options(args: &Args) -> exit::Result<Option<Camera>> {
    options::count("--spes", args.spes, 1..=16)?;
    options::count("--width", args.width, 1..=8192)?;
    options::count("--height", args.height, 1..=8192)?;
    if let Some(threads) = args.threads {
        options::count("--threads", threads, 1..=1024)?;
    }
    options::clock_ghz(args.clock)?;
    options::max_cycles(args.max_cycles)?;
    if args.fill && args.validate {
        return Err(Error::input(
            "--validate compares the ray tracer's hits; --fill renders none",
        ));
    }
    if args.lights.len() > shading::MAX_LIGHTS {
        return Err(Error::input(format!(
            "{} --light options: at most {} lights",
            args.lights.len(),
            shading::MAX_LIGHTS
        )));
    }
    if args.shade == ShadeMode::Shadows && !KERNEL_TRACES_SHADOWS {
        return Err(Error::input(
            "--shade shadows: the kernel does not trace shadow packets yet (the host reference \
             does, loader::reference::Reference::shade); use --shade simple",
        ));
    }
    if args.fill && args.shade != ShadeMode::None {
        return Err(Error::input(format!(
            "--fill runs the fill program, which does not shade: drop --shade {}",
            args.shade.name()
        )));
    }
    let camera = match &args.camera {
        Some(text) => Some(Camera::parse(text).map_err(|e| format!("--camera: {e}"))?),
        None => None,
    };
    let is_png = |path: &std::path::Path| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"))
    };
    let heatmaps = args.heatmap.as_deref().map(crate::heatmap::paths);
    let images = std::iter::once(("-o", args.output.as_path())).chain(
        heatmaps
            .iter()
            .map(|(cycles, _)| ("--heatmap", cycles.as_path())),
    );
    for (option, path) in images {
        if !is_png(path) {
            return Err(Error::input(format!(
                "{option} {}: the image is written as PNG; name it .png",
                path.display()
            )));
        }
    }
    exit::check_writable(&args.output)?;
    if let Some((_, wait)) = &heatmaps {
        exit::check_writable(wait)?;
    }
    for path in [&args.stats, &args.profile, &args.heatmap, &args.trace]
        .into_iter()
        .flatten()
    {
        exit::check_writable(path)?;
    }
    Ok(camera)
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    spu_isa::jit::Engine::set_default(args.engine);
    args.compile.apply();
    let camera = check_options(&args)?;
    let started = Instant::now();
    let prepared = crate::prepared::prepare(&args.scene, args.camera.as_deref(), camera)?;
    let (scene, staged) = (&prepared.scene, &prepared.staged);
    let basis = scene.camera.basis(args.width, args.height);
    let layout = FrameLayout::new(
        staged,
        &basis,
        args.width,
        args.height,
        args.spes,
        args.bvh_cache,
        args.tri_cache,
    )?
    .with_kernel_options(args.assoc, args.sht)?;
    let lights = if args.lights.is_empty() {
        shading::default_lights(scene)
    } else {
        args.lights.clone()
    };
    let layout = match args.shade {
        ShadeMode::None => layout,
        mode => layout.with_shading(
            staged,
            ShadingBlock {
                mode: if mode == ShadeMode::Shadows {
                    SHADE_SHADOWS
                } else {
                    SHADE_SIMPLE
                },
                shadow_early: args.shadow_early,
                vertex_cache_log2: args.vertex_cache.trailing_zeros(),
                material_cache_log2: args.material_cache.trailing_zeros(),
                lights: lights.clone(),
                ..Default::default()
            },
        )?,
    };
    if !args.quiet {
        eprintln!(
            "scene {}: {} triangles, {} BVH nodes, prepared in {:.2} s",
            args.scene,
            scene.triangles.len(),
            staged.nodes.len(),
            started.elapsed().as_secs_f64()
        );
    }
    let threads = args.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let bar = indicatif::ProgressBar::new(layout.params.num_tiles as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} tiles {pos}/{len} {wide_bar} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    if args.quiet {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let sim_started = Instant::now();
    let run = spu_loader::runtime::render_frame_with(
        staged,
        &layout,
        args.spes,
        threads,
        &spu_isa::timing::TimingConfig {
            clock_ghz: args.clock,
            dma_latency_ns: args.dma_latency_ns,
            ..Default::default()
        },
        args.fill,
        args.max_cycles,
        &spu_loader::runtime::FrameOptions {
            event_log: args.heatmap.is_some() || args.trace.is_some(),
            code: crate::prepared::code(),
        },
        &mut |taken, _| bar.set_position(taken as u64),
    );
    bar.finish_and_clear();
    let run = run.map_err(|e| match e {
        FrameError::Setup(message) => Error::failure(message),
        FrameError::CycleLimit(_) => Error::new(Status::CycleLimit, e.to_string()),
        FrameError::SpuStopped { .. } => Error::new(Status::AbnormalStop, e.to_string()),
    })?;
    let host_seconds = sim_started.elapsed().as_secs_f64();
    // The hits are only looked at to validate them.
    let validating = args.validate && !args.fill;
    let pixels = if validating {
        decode_frame_buffer(&run.frame_buffer, args.width, args.height)
    } else {
        Vec::new()
    };
    let colours: Vec<u32> = match &run.colour_buffer {
        Some(buffer) => decode_colour_buffer(buffer, args.width, args.height),
        None if validating => pixels.iter().map(|p| p.rgba).collect(),
        None => decode_frame_buffer_colours(&run.frame_buffer, args.width, args.height),
    };
    write_png(&args.output, &colours, args.width, args.height)?;

    let record_to_original: Vec<u32> = staged.triangles.iter().map(|t| t.original_index).collect();
    let mut colour_validation = None;
    let mut shadow_edges = None;
    let mut edge_ties = 0;
    let validation = if validating {
        let reference = Reference::from_staged(staged);
        let hits = reference.render(&scene.camera, args.width, args.height, threads);
        if run.colour_buffer.is_some() {
            let expected = reference.shade_image(
                &hits,
                &scene.camera,
                args.width,
                args.height,
                &lights,
                args.shade == ShadeMode::Shadows,
                threads,
            );
            let basis = scene.camera.basis(args.width, args.height);
            // A pixel beyond the tolerance whose shadow ray grazes an occluder's edge may
            // take the colour of either outcome (Reference::shade_alternatives).
            let grazing = |i: usize| {
                args.shade == ShadeMode::Shadows && {
                    let (x, y) = (i as u32 % args.width, i as u32 / args.width);
                    reference
                        .shade_alternatives(&hits[i], basis.origin, basis.direction(x, y), &lights)
                        .iter()
                        .any(|&c| {
                            shading::channel_difference(colours[i], c) <= shading::COLOUR_TOLERANCE
                        })
                }
            };
            // A pixel whose ray hits an edge two triangles share may be the kernel's
            // triangle's (Reference::shade_edge_tie).
            let edge_tie = |i: usize| {
                let (x, y) = (i as u32 % args.width, i as u32 / args.width);
                let tie = reference.shade_edge_tie(
                    &hits[i],
                    pixels[i].triangle,
                    basis.origin,
                    basis.direction(x, y),
                    &lights,
                    args.shade == ShadeMode::Shadows,
                );
                tie.is_some_and(|c| {
                    shading::channel_difference(colours[i], c) <= shading::COLOUR_TOLERANCE
                })
            };
            let (off, edges, ties) =
                validate_colours(&colours, &expected, args.width, &grazing, &edge_tie);
            colour_validation = Some(off);
            edge_ties = ties;
            shadow_edges = (args.shade == ShadeMode::Shadows).then_some(edges);
        }
        Some(validate(&pixels, &hits, &record_to_original, args.width))
    } else {
        None
    };
    let rays = args.width as u64 * args.height as u64;
    let seconds = run.frame_cycles as f64 / (args.clock * 1e9);
    let mrays = if seconds > 0.0 {
        rays as f64 / seconds / 1e6
    } else {
        0.0
    };
    let instructions: u64 = run.spus.iter().map(|s| s.instructions).sum();
    if !args.quiet {
        outln!(
        "{} SPE(s): {} cycles per frame, {:.2} MRays/s at {} GHz; {} instructions simulated in {:.1} s ({:.0} M/s); wrote {}",
        args.spes,
        run.frame_cycles,
        mrays,
        args.clock,
        instructions,
        host_seconds,
        instructions as f64 / host_seconds / 1e6,
        args.output.display()
    );
        if run.jit.blocks > 0 {
            outln!(
                "block compiler: {:.1}% ran compiled; {} blocks ({} instructions) compiled in {:.2} s{}",
                100.0 * run.jit.compiled_instructions as f64 / instructions.max(1) as f64,
                run.jit.blocks,
                run.jit.block_instructions,
                run.jit.compile_seconds,
                match args.compile.compile {
                    spu_isa::jit::Compiling::Background => " on a thread of its own",
                    spu_isa::jit::Compiling::Inline => "",
                }
            );
        }
    }
    match (validation, colour_validation) {
        (Some((n, bad)), Some(off)) => outln!(
            "validation: {bad} of {n} pixels differ from the host reference in the hit triangle, {off} in colour (more than {} of 255 in a channel){}{}",
            shading::COLOUR_TOLERANCE,
            if edge_ties > 0 {
                format!(
                    "; {edge_ties} more hit, at the reference's distance, another triangle \
                     sharing an edge with the reference's and take that triangle's colour"
                )
            } else {
                String::new()
            },
            match shadow_edges {
                Some(edges) => format!(
                    "; {edges} more take the colour of a shadow ray grazing an occluder's edge \
                     (within 2^-16 barycentric), which either outcome gives"
                ),
                None => String::new(),
            }
        ),
        (Some((n, bad)), None) => {
            outln!("validation: {bad} of {n} pixels differ from the host reference")
        }
        _ => {}
    }
    if let Some(path) = &args.stats {
        let mut stats = spu_loader::stats::FrameStats::new(
            &run,
            &spu_loader::stats::FrameSetup {
                scene: &args.scene,
                width: args.width,
                height: args.height,
                clock_ghz: args.clock,
            },
            validation,
        );
        if let Some(v) = stats.validation.as_mut() {
            v.colour_mismatches = colour_validation;
            v.shadow_edge_pixels = shadow_edges;
        }
        let json = stats.to_json();
        exit::write_file(path, json.as_bytes())?;
    }
    if args.heatmap.is_some() || args.trace.is_some() {
        crate::frame_views::write(
            &run,
            &layout,
            (args.width, args.height, args.spes, args.clock),
            args.heatmap.as_deref(),
            args.trace.as_deref(),
        )?;
    }
    if let Some(path) = &args.profile {
        let text = kernel_profile(&run, args.fill, args.shade != ShadeMode::None)
            .map_err(Error::failure)?;
        exit::write_file(path, text.as_bytes())?;
    }
    Ok(validation_status(validation, colour_validation).into())
}

/// `--validate` that found differing pixels (hit triangles, or colours beyond the
/// tolerance) exits 3 (after writing every output).
fn validation_status(validation: Option<(usize, usize)>, colours_off: Option<usize>) -> Status {
    match validation {
        Some((_, bad)) if bad + colours_off.unwrap_or(0) > 0 => Status::Differences,
        _ => Status::Success,
    }
}

/// The annotated listing of the kernel that ran, from its image and symbols.
fn kernel_profile(
    run: &spu_loader::runtime::FrameRun,
    fill: bool,
    shaded: bool,
) -> Result<String, String> {
    use spu_isa::profile::{annotated_listing, executed_lines, ListingOptions};
    let profile = run
        .profile
        .as_ref()
        .ok_or("no profile: the timing model was off (SPU_NO_TIMING)")?;
    let (source, name) = spu_loader::kernels::frame_program(fill);
    let defines: &[(&str, i64)] = if shaded { &[("SHADE", 1)] } else { &[] };
    let program = spu_loader::runtime::assemble_kernel_with(source, name, defines)?;
    let lines = executed_lines(profile, &program.image, &program.symbols);
    let opts = ListingOptions {
        range: None,
        executed_only: true,
    };
    Ok(annotated_listing(profile, &lines, &opts))
}

/// Colours against the reference shading: the pixels with a channel off by more than
/// [`shading::COLOUR_TOLERANCE`]; the first few are printed.
/// Colours beyond the tolerance: `(differing, accepted by grazing, accepted by edge_tie)`,
/// where `grazing(pixel)` says whether another legitimate outcome of a shadow ray gives the
/// kernel's colour, `edge_tie(pixel)` whether the kernel's triangle, hit on an edge it
/// shares with the reference's, does.
fn validate_colours(
    colours: &[u32],
    expected: &[u32],
    width: u32,
    grazing: &dyn Fn(usize) -> bool,
    edge_tie: &dyn Fn(usize) -> bool,
) -> (usize, usize, usize) {
    let mut off = 0;
    let mut edges = 0;
    let mut ties = 0;
    for (i, (&c, &e)) in colours.iter().zip(expected).enumerate() {
        if shading::channel_difference(c, e) > shading::COLOUR_TOLERANCE {
            if grazing(i) {
                edges += 1;
                continue;
            }
            if edge_tie(i) {
                ties += 1;
                continue;
            }
            if off < 10 {
                eprintln!(
                    "colour mismatch at ({}, {}): kernel {c:08x} / reference {e:08x}",
                    i as u32 % width,
                    i as u32 / width
                );
            }
            off += 1;
        }
    }
    (off, edges, ties)
}

fn write_png(path: &PathBuf, colours: &[u32], width: u32, height: u32) -> exit::Result<()> {
    use image::ImageEncoder as _;
    let mut rgb = Vec::with_capacity(colours.len() * 3);
    for colour in colours {
        let [r, g, b, _] = colour.to_be_bytes();
        rgb.extend([r, g, b]);
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::output(path, e))?;
    exit::write_file(path, &png)
}

#[cfg(test)]
mod tests {
    use super::*;
    use spu_loader::reference::Hit;

    #[test]
    fn differing_pixels_make_validation_exit_3() {
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
        let same = [hit(10, 1.0), Hit::NONE, hit(11, 2.0)];
        let records = [10, 11];
        assert_eq!(validate(&kernel, &same, &records, 3), (3, 0));
        assert_eq!(validation_status(Some((3, 0)), None), Status::Success);
        assert_eq!(validation_status(Some((3, 0)), Some(0)), Status::Success);
        assert_eq!(
            validation_status(Some((3, 0)), Some(1)),
            Status::Differences,
            "a colour off is a difference"
        );
        // A miss where the reference hits, and a hit at another distance.
        let other = [hit(10, 1.0), hit(10, 5.0), hit(11, 2.5)];
        assert_eq!(validate(&kernel, &other, &records, 3), (3, 2));
        assert_eq!(validation_status(Some((3, 2)), None), Status::Differences);
        assert_eq!(ExitCode::from(Status::Differences), ExitCode::from(3));
        assert_eq!(validation_status(None, None), Status::Success);
    }
}
