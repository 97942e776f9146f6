//! `spu render`: ray-trace a scene with the SPU kernels on 1 to 16 simulated SPEs, as the
//! paper's PPE would drive them, and report the image, the statistics and the validation
//! against the host reference.

use spu_loader::camera::Camera;
use spu_loader::frame::{FrameLayout, SCENE_BASE};
use spu_loader::kernel_abi::{decode_frame_buffer, PixelResult, MISS};
use spu_loader::reference::Reference;
use spu_loader::{procedural, Bvh, BvhConfig, Scene, StagedScene};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Engine: the block compiler (jit; the default where the host has one) or the
    /// interpreter (interp). Results are the same; only host speed differs.
    #[arg(long, default_value_t = spu_isa::jit::Engine::host_default())]
    engine: spu_isa::jit::Engine,
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
    #[arg(long = "bvh-cache", default_value_t = 256)]
    bvh_cache: u32,
    /// Lines in the triangle cache (power of two, 128..1024).
    #[arg(long = "tri-cache", default_value_t = 256)]
    tri_cache: u32,
    /// Run the fill pattern program instead of the ray tracer (tests the runtime).
    #[arg(long)]
    fill: bool,
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
}

/// Loads a built-in scene by name, or a file.
pub fn load_scene(name: &str) -> Result<Scene, String> {
    if let Some(scene) = procedural::by_name(name) {
        return Ok(scene);
    }
    Scene::load(name).map_err(|e| e.to_string())
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

pub fn run(args: Args) -> Result<ExitCode, String> {
    spu_isa::jit::Engine::set_default(args.engine);
    if !(1..=16).contains(&args.spes) {
        return Err(format!("--spes {}: must be 1 to 16", args.spes));
    }
    if args.width == 0 || args.height == 0 || args.width > 8192 || args.height > 8192 {
        return Err("--width and --height must be 1 to 8192".into());
    }
    let started = Instant::now();
    let mut scene = load_scene(&args.scene)?;
    if let Some(text) = &args.camera {
        scene.camera = Camera::parse(text)?;
    }
    let bvh = Bvh::build(&scene, &BvhConfig::default());
    let staged = StagedScene::new(&scene, &bvh, SCENE_BASE)?;
    let basis = scene.camera.basis(args.width, args.height);
    let layout = FrameLayout::new(
        &staged,
        &basis,
        args.width,
        args.height,
        args.spes,
        args.bvh_cache,
        args.tri_cache,
    )?;
    eprintln!(
        "scene {}: {} triangles, {} BVH nodes, prepared in {:.2} s",
        args.scene,
        scene.triangles.len(),
        staged.nodes.len(),
        started.elapsed().as_secs_f64()
    );
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
    let sim_started = Instant::now();
    let run = spu_loader::runtime::render_frame(
        &staged,
        &layout,
        args.spes,
        threads,
        &spu_isa::timing::TimingConfig {
            clock_ghz: args.clock,
            ..Default::default()
        },
        args.fill,
        args.max_cycles,
        &mut |taken, _| bar.set_position(taken as u64),
    );
    bar.finish_and_clear();
    let run = run?;
    let host_seconds = sim_started.elapsed().as_secs_f64();
    let pixels = decode_frame_buffer(&run.frame_buffer, args.width, args.height);
    write_png(&args.output, &pixels, args.width, args.height)?;

    let record_to_original: Vec<u32> = staged.triangles.iter().map(|t| t.original_index).collect();
    let validation = if args.validate && !args.fill {
        let reference =
            Reference::from_staged(&staged).render(&scene.camera, args.width, args.height, threads);
        Some(validate(
            &pixels,
            &reference,
            &record_to_original,
            args.width,
        ))
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
    println!(
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
    if let Some((n, bad)) = validation {
        println!("validation: {bad} of {n} pixels differ from the host reference");
    }
    if let Some(path) = &args.stats {
        let json = run.stats_json(
            &args.scene,
            args.width,
            args.height,
            args.clock,
            mrays,
            validation,
        );
        std::fs::write(path, json).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    if let Some(path) = &args.profile {
        let text = kernel_profile(&run, args.fill)?;
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The annotated listing of the kernel that ran, from its image and symbols.
fn kernel_profile(run: &spu_loader::runtime::FrameRun, fill: bool) -> Result<String, String> {
    use spu_isa::profile::{annotated_listing, executed_lines, ListingOptions};
    let profile = run
        .profile
        .as_ref()
        .ok_or("no profile: the timing model was off (SPU_NO_TIMING)")?;
    let (source, name) = if fill {
        (spu_loader::runtime::FILL_SOURCE, "kernels/fill.s")
    } else {
        (spu_loader::runtime::RAYTRACE_SOURCE, "kernels/raytrace.s")
    };
    let program = spu_loader::runtime::assemble_kernel(source, name)?;
    let lines = executed_lines(profile, &program.image, &program.symbols);
    let opts = ListingOptions {
        range: None,
        executed_only: true,
    };
    Ok(annotated_listing(profile, &lines, &opts))
}

fn write_png(
    path: &PathBuf,
    pixels: &[PixelResult],
    width: u32,
    height: u32,
) -> Result<(), String> {
    let mut rgb = Vec::with_capacity(pixels.len() * 3);
    for p in pixels {
        let [r, g, b, _] = p.rgba.to_be_bytes();
        rgb.extend([r, g, b]);
    }
    image::save_buffer(path, &rgb, width, height, image::ColorType::Rgb8)
        .map_err(|e| format!("{}: {e}", path.display()))
}
