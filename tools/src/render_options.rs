//! The options of `spu render` and their two directions: parsed into a
//! [`RenderConfig`] and the files to write ([`Args::config`]), and a configuration written
//! back as the options that make it ([`words`], what `spu paper --list-jobs` prints), so the
//! frame a listed command renders is the one `spu paper` rendered in process.

use crate::exit::{self, Error};
use crate::options;
use spu_isa::jit::Engine;
use spu_loader::camera::Camera;
use spu_loader::render::{KernelVariant, RenderConfig, Shading};
use spu_loader::shading::{self, Light, ShadeMode};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Engine: the block compiler (jit, the default where the host has one; the SPEs
    /// share their compiled blocks) or the interpreter (interp). Results are the same;
    /// only host speed differs.
    #[arg(long, default_value_t = Engine::host_default())]
    pub engine: Engine,
    #[command(flatten)]
    pub compile: crate::options::CompileOption,
    #[command(flatten)]
    pub ext: crate::options::ExtOption,
    /// A built-in scene (room, conference, beetle) or an OBJ/PLY file (optionally .gz).
    #[arg(long, default_value = "room")]
    pub scene: String,
    #[arg(long, default_value_t = 1024)]
    pub width: u32,
    #[arg(long, default_value_t = 1024)]
    pub height: u32,
    /// Simulated SPEs (1..64: a Cell has 8, a dual Cell 16, more are hypothetical).
    #[arg(long, default_value_t = 1)]
    pub spes: usize,
    /// Host threads running the SPEs (results do not depend on it).
    #[arg(long)]
    pub threads: Option<usize>,
    /// SPU clock in GHz (2.4 for the paper's blade, 3.2 for a PlayStation 3).
    #[arg(long, default_value_t = 2.4)]
    pub clock: f64,
    /// Camera override: ex,ey,ez,tx,ty,tz,ux,uy,uz,fov.
    #[arg(long, allow_hyphen_values = true)]
    pub camera: Option<String>,
    /// Lines in the BVH-node cache (power of two, 128..1024).
    #[arg(long = "bvh-cache", default_value_t = 256, value_parser = cache_lines)]
    pub bvh_cache: u32,
    /// Lines in the triangle cache (power of two, 128..1024).
    #[arg(long = "tri-cache", default_value_t = 256, value_parser = cache_lines)]
    pub tri_cache: u32,
    /// Ways of both caches: 1 (direct mapped) or 4 (set-associative, LRU).
    #[arg(long, default_value_t = 1, value_parser = associativity)]
    pub assoc: u32,
    /// Packets each SPE keeps in flight (software hyperthreading, 1..8; 1 = blocking misses).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub sht: u32,
    /// Main-memory latency of a DMA in nanoseconds before its bytes move.
    #[arg(long = "dma-latency-ns", default_value_t = 100.0, value_parser = latency_ns, allow_hyphen_values = true)]
    pub dma_latency_ns: f64,
    /// Main-memory bandwidth of the Cell in GB/s, shared by all its SPEs (25.6: XDR).
    #[arg(long = "memory-bandwidth-gbs", default_value_t = 25.6, value_parser = bandwidth_gbs, allow_hyphen_values = true)]
    pub memory_bandwidth_gbs: f64,
    /// Run the fill pattern program instead of the ray tracer (tests the runtime).
    #[arg(long)]
    pub fill: bool,
    /// What each pixel gets: none (primary rays, the eye-light grey), simple (diffuse
    /// shading with the material colour and the interpolated normal, point lights),
    /// shadows (simple plus one shadow ray per light) or reflect (shadows plus reflected
    /// rays off reflective materials, --reflect-depth bounces).
    #[arg(long, default_value = "none", value_parser = ShadeMode::parse)]
    pub shade: ShadeMode,
    /// Reflection bounces per primary ray with --shade reflect (1..4).
    #[arg(long = "reflect-depth", value_parser = shading::parse_reflect_depth)]
    pub reflect_depth: Option<u32>,
    /// A point light `x,y,z[,r,g,b]` (repeatable, up to 8; default: the scene's own).
    #[arg(long = "light", value_parser = Light::parse, allow_hyphen_values = true)]
    pub lights: Vec<Light>,
    /// Shadow packets stop as soon as every ray is occluded (on|off).
    #[arg(long = "shadow-early", default_value = "off", value_parser = shadow_early, action = clap::ArgAction::Set)]
    pub shadow_early: bool,
    /// Entries of the direct-mapped vertex cache (power of two, 16..256).
    #[arg(long = "vertex-cache", default_value_t = 64, value_parser = shading_cache)]
    pub vertex_cache: u32,
    /// Entries of the direct-mapped material cache (power of two, 16..256).
    #[arg(long = "material-cache", default_value_t = 64, value_parser = shading_cache)]
    pub material_cache: u32,
    /// The timing model (off: a functional run without the pipeline's stalls and no
    /// profile; the image is the same).
    #[arg(long, default_value = "on", value_parser = timing, action = clap::ArgAction::Set)]
    pub timing: bool,
    /// Output image (PNG).
    #[arg(short = 'o', long, default_value = "render.png")]
    pub output: PathBuf,
    /// Statistics as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Compare every pixel's triangle and distance with the host reference.
    #[arg(long)]
    pub validate: bool,
    /// Simulated cycles per SPE before giving up (exit 124): each SPE stops at exactly N,
    /// and the message names those it stopped.
    #[arg(long, default_value_t = 200_000_000_000)]
    pub max_cycles: u64,
    /// Write the kernel's annotated profile (per instruction: executions, cycles, stalls
    /// by cause, dual issue; then per label and totals), merged over all SPEs.
    #[arg(long)]
    pub profile: Option<PathBuf>,
    /// Heat map of the simulated cycles per packet (PNG), and beside it (NAME-wait.png)
    /// the share of them spent waiting on DMA.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Timeline of the frame over simulated time (Chrome/Perfetto trace JSON).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Render N frames of a moving scene (1..18000): a built-in one (room-flag,
    /// beetle-drive) or OBJ/PLY keyframes named by a pattern (walk_%03d.obj, frames from 0);
    /// the BVH is refitted on the SPEs each frame. -o out.png writes out_000.png, ...;
    /// --stats a JSON array of the frames' statistics.
    #[arg(long)]
    pub frames: Option<u32>,
    /// With --frames: also every frame as one animated PNG (30 frames per second).
    #[arg(long)]
    pub animation: Option<PathBuf>,
    /// With --frames: rebuild the BVH on the host when its refitted SAH cost exceeds this
    /// many times its cost when built (above 1).
    #[arg(long = "rebuild-ratio", default_value_t = spu_loader::refit::REBUILD_RATIO)]
    pub rebuild_ratio: f32,
}

/// What `spu render` writes and says besides rendering.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Outputs {
    pub image: PathBuf,
    pub stats: Option<PathBuf>,
    pub profile: Option<PathBuf>,
    pub heatmap: Option<PathBuf>,
    pub trace: Option<PathBuf>,
    pub validate: bool,
    /// No progress bar or summary (`spu paper` runs many frames at once).
    pub quiet: bool,
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

/// `--shadow-early`: on or off.
fn shadow_early(text: &str) -> Result<bool, String> {
    shading::parse_on_off("--shadow-early", text)
}

/// `--timing`: on or off.
fn timing(text: &str) -> Result<bool, String> {
    shading::parse_on_off("--timing", text)
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

/// `--memory-bandwidth-gbs`: finite, within the range a frame accepts.
fn bandwidth_gbs(text: &str) -> Result<f64, String> {
    use spu_loader::render::{MAX_BANDWIDTH_GBS, MIN_BANDWIDTH_GBS};
    let gbs: f64 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a bandwidth in GB/s"))?;
    if !gbs.is_finite() || !(MIN_BANDWIDTH_GBS..=MAX_BANDWIDTH_GBS).contains(&gbs) {
        return Err(format!(
            "{gbs} GB/s: must be from {MIN_BANDWIDTH_GBS} to {MAX_BANDWIDTH_GBS} GB/s"
        ));
    }
    Ok(gbs)
}

impl Args {
    /// The frame and the files the options ask for, every option checked before the scene
    /// is loaded: numbers in range, output paths writable and in a format the command
    /// writes.
    pub fn config(&self) -> exit::Result<(RenderConfig, Outputs)> {
        options::count("--spes", self.spes, 1..=spu_loader::render::MAX_SPES)?;
        options::count("--width", self.width, 1..=8192)?;
        options::count("--height", self.height, 1..=8192)?;
        let (threads, thread_notes) = options::threads(
            self.threads,
            self.spes,
            ("SPE", "SPEs"),
            options::host_cores(),
        )?;
        options::clock_ghz(self.clock)?;
        options::max_cycles(self.max_cycles)?;
        if self.fill && self.validate {
            return Err(Error::input(
                "--validate compares the ray tracer's hits; --fill renders none",
            ));
        }
        if self.lights.len() > shading::MAX_LIGHTS {
            return Err(Error::input(format!(
                "{} --light options: at most {} lights",
                self.lights.len(),
                shading::MAX_LIGHTS
            )));
        }
        if !self.lights.is_empty() && self.shade == ShadeMode::None {
            return Err(Error::input(
                "--light lights a shaded frame, and this one is not shaded: add --shade simple or --shade shadows",
            ));
        }
        if self.reflect_depth.is_some() && self.shade != ShadeMode::Reflect {
            return Err(Error::input(
                "--reflect-depth sets the bounces of --shade reflect, and this frame does not reflect",
            ));
        }
        if self.fill && self.shade != ShadeMode::None {
            return Err(Error::input(format!(
                "--fill runs the fill program, which does not shade: drop --shade {}",
                self.shade.name()
            )));
        }
        if self.profile.is_some() && !self.timing {
            return Err(Error::input(
                "--profile needs the timing model: drop --timing off",
            ));
        }
        let camera = match &self.camera {
            Some(text) => Some(Camera::parse(text).map_err(|e| format!("--camera: {e}"))?),
            None => None,
        };
        match self.frames {
            // an animation's files are its own (cmd_animate)
            Some(_) => crate::cmd_animate::check_options(self)?,
            None if self.animation.is_some() => {
                return Err(Error::input("--animation writes the frames of --frames N"))
            }
            None => check_outputs(self)?,
        }
        let config = RenderConfig {
            camera,
            width: self.width,
            height: self.height,
            spes: self.spes,
            threads,
            clock_ghz: self.clock,
            dma_latency_ns: self.dma_latency_ns,
            memory_bandwidth_gbs: self.memory_bandwidth_gbs,
            bvh_cache: self.bvh_cache,
            tri_cache: self.tri_cache,
            assoc: self.assoc,
            sht: self.sht,
            shading: Shading {
                mode: self.shade,
                lights: self.lights.clone(),
                shadow_early: self.shadow_early,
                vertex_cache: self.vertex_cache,
                material_cache: self.material_cache,
                reflect_depth: self.reflect_depth.unwrap_or(1),
            },
            kernel: RenderConfig::kernel_with(self.fill, self.shade, self.ext.ext),
            engine: self.engine,
            timing: self.timing,
            max_cycles: self.max_cycles,
            event_log: self.heatmap.is_some() || self.trace.is_some(),
            extensions: self.ext.ext,
            ..RenderConfig::new(&self.scene)
        };
        let outputs = Outputs {
            image: self.output.clone(),
            stats: self.stats.clone(),
            profile: self.profile.clone(),
            heatmap: self.heatmap.clone(),
            trace: self.trace.clone(),
            validate: self.validate,
            quiet: false,
        };
        // said once, after every check passed and before any work
        for note in thread_notes {
            eprintln!("spu: {note}");
        }
        Ok((config, outputs))
    }
}

/// The images are PNG files and every output can be written.
fn check_outputs(args: &Args) -> exit::Result<()> {
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
    let mut files = crate::outputs::Files::new();
    if !spu_loader::procedural::is_built_in(&args.scene) {
        files.input("the scene", std::path::Path::new(&args.scene));
        for library in crate::outputs::material_libraries(std::path::Path::new(&args.scene)) {
            files.input("the scene's material library", &library);
        }
    }
    files.output("-o", &args.output);
    if let Some((cycles, wait)) = &heatmaps {
        files.output("--heatmap", cycles).output("--heatmap", wait);
    }
    for (option, path) in [
        ("--stats", &args.stats),
        ("--profile", &args.profile),
        ("--trace", &args.trace),
    ] {
        if let Some(path) = path {
            files.output(option, path);
        }
    }
    files.check()
}

/// The `spu render` options (after `render`) that render `config` and write `outputs`:
/// the frame's size, SPEs, clock, caches and shading always, the other settings where they
/// are not the defaults. Host threads and the engine are left out: results do not depend
/// on them.
pub fn words(config: &RenderConfig, outputs: &Outputs) -> Vec<String> {
    let defaults = RenderConfig::new(&config.scene);
    let mut words: Vec<String> = Vec::new();
    let mut option = |name: &str, value: String| {
        words.push(name.to_string());
        words.push(value);
    };
    option("--scene", config.scene.clone());
    option("--width", config.width.to_string());
    option("--height", config.height.to_string());
    option("--spes", config.spes.to_string());
    option("--clock", config.clock_ghz.to_string());
    option("--bvh-cache", config.bvh_cache.to_string());
    option("--tri-cache", config.tri_cache.to_string());
    option("--assoc", config.assoc.to_string());
    option("--sht", config.sht.to_string());
    let s = &config.shading;
    option("--shade", s.mode.name().to_string());
    if let Some(c) = &config.camera {
        let v = [c.eye.to_array(), c.target.to_array(), c.up.to_array()].concat();
        let v: Vec<String> = v
            .iter()
            .chain(&[c.fov_y_degrees])
            .map(f32::to_string)
            .collect();
        option("--camera", v.join(","));
    }
    if config.dma_latency_ns != defaults.dma_latency_ns {
        option("--dma-latency-ns", config.dma_latency_ns.to_string());
    }
    if config.memory_bandwidth_gbs != defaults.memory_bandwidth_gbs {
        option(
            "--memory-bandwidth-gbs",
            config.memory_bandwidth_gbs.to_string(),
        );
    }
    for light in &s.lights {
        let v = [light.position.to_array(), light.colour.to_array()].concat();
        let v: Vec<String> = v.iter().map(f32::to_string).collect();
        option("--light", v.join(","));
    }
    if s.shadow_early {
        option("--shadow-early", "on".into());
    }
    if s.vertex_cache != defaults.shading.vertex_cache {
        option("--vertex-cache", s.vertex_cache.to_string());
    }
    if s.material_cache != defaults.shading.material_cache {
        option("--material-cache", s.material_cache.to_string());
    }
    if s.mode == ShadeMode::Reflect {
        option("--reflect-depth", s.reflect_depth.to_string());
    }
    if !config.timing {
        option("--timing", "off".into());
    }
    if config.max_cycles != defaults.max_cycles {
        option("--max-cycles", config.max_cycles.to_string());
    }
    if !config.extensions.is_none() {
        option("--ext", config.extensions.to_string());
    }
    let paths = [
        ("--heatmap", &outputs.heatmap),
        ("--trace", &outputs.trace),
        ("--profile", &outputs.profile),
        ("--stats", &outputs.stats),
    ];
    for (name, path) in paths {
        if let Some(path) = path {
            option(name, path.display().to_string());
        }
    }
    option("-o", outputs.image.display().to_string());
    if config.kernel == KernelVariant::Fill {
        words.push("--fill".into());
    }
    if outputs.validate {
        words.push("--validate".into());
    }
    words
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser)]
    #[command(name = "render", no_binary_name = true)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    /// A configuration written as options parses back to itself.
    #[test]
    fn words_parse_back_to_the_configuration() {
        let dir = std::env::temp_dir().join(format!("spu-render-words-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let outputs = Outputs {
            image: dir.join("a.png"),
            stats: Some(dir.join("a.json")),
            heatmap: Some(dir.join("a-heat.png")),
            validate: true,
            ..Outputs::default()
        };
        let shaded = RenderConfig {
            camera: Some(Camera::parse("1,2.5,-3,0,0,0,0,1,0,45.5").unwrap()),
            width: 96,
            height: 64,
            spes: 3,
            threads: 2,
            clock_ghz: 3.2,
            dma_latency_ns: 12.5,
            bvh_cache: 512,
            tri_cache: 128,
            assoc: 4,
            sht: 2,
            shading: Shading {
                mode: ShadeMode::Shadows,
                lights: vec![Light::parse("1,-2,3.25,0.5,1,1").unwrap()],
                shadow_early: true,
                vertex_cache: 16,
                material_cache: 256,
                reflect_depth: 1,
            },
            kernel: KernelVariant::Shaded,
            event_log: true,
            max_cycles: 12345,
            ..RenderConfig::new("conference")
        };
        let fill = RenderConfig {
            kernel: KernelVariant::Fill,
            timing: false,
            threads: 2,
            event_log: true,
            ..RenderConfig::new("room")
        };
        for (config, validate) in [(shaded, true), (fill, false)] {
            let outputs = Outputs {
                validate,
                ..outputs.clone()
            };
            let mut w = words(&config, &outputs);
            w.extend(["--threads".into(), "2".into()]);
            let cli = <Cli as clap::Parser>::try_parse_from(&w).unwrap();
            let (parsed, out) = cli.args.config().unwrap();
            assert_eq!(parsed, config, "{w:?}");
            assert_eq!(out, outputs);
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
}
