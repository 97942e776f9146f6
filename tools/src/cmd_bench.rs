//! `spu bench`: simulator speed in simulated instructions per host second, on a mixed
//! loop (loads, float multiply-adds, shuffles, adds, a hinted branch), with the timing
//! model off and on, with the interpreter and the block compiler, measured in one run; and
//! on a frame of the ray tracer (the room, through the render API, as `spu render` runs it).

use crate::exit::{self, Status};
use crate::options;
use spu_isa::jit::Engine;
use spu_isa::machine::{MainMemory, Spu, StopReason};
use std::process::ExitCode;
use std::time::Instant;

#[derive(clap::Args)]
pub struct Args {
    /// Loop iterations (11 instructions each), at least 1.
    #[arg(long, default_value_t = 10_000_000)]
    iterations: u32,
    /// Measure only this engine (interp or jit); both by default.
    #[arg(long)]
    engine: Option<Engine>,
    #[command(flatten)]
    compile: crate::options::CompileOption,
    #[command(flatten)]
    ext: crate::options::ExtOption,
    /// Also a SIZExSIZE frame of the room on one SPE with the timing model (0: none).
    #[arg(long, default_value_t = 128)]
    frame: u32,
}

/// The benchmark loop, assembled from source so it reads like SPU code.
pub const LOOP: &str = "
        .text
        .global _start
_start: ila     $3, data
        il      $4, 0
        ilhu    $10, 0x3f80
        ilhu    $9, ITER@h
        iohl    $9, ITER@l
        ila     $11, 0x10203
loop:   hbrr    .Lback, loop
        lqd     $5, 0($3)
        lqd     $6, 16($3)
        fma     $7, $5, $6, $7
        fma     $8, $6, $10, $8
        shufb   $12, $5, $6, $11
        a       $4, $4, $12
        ai      $9, $9, -1
        fa      $13, $7, $8
        stqd    $13, 32($3)
.Lback: brnz    $9, loop
        stop    0x2000
        .data
        .align  4
data:   .float  1.5, 2.0, 0.5, 3.0, 0.25, 1.0, 2.0, 4.0
        .space  16
";

fn measure(
    iterations: u32,
    timing: bool,
    engine: Engine,
    compile: &options::CompileOption,
    ext: spu_isa::Extensions,
) -> exit::Result<(u64, u64, f64)> {
    let opts = spu_asm::Options {
        defines: vec![("ITER".into(), iterations as i64)],
        ..Default::default()
    };
    let program = spu_asm::assemble(LOOP, "bench.s", &opts)
        .map_err(|d| exit::Error::failure(format!("the benchmark loop: {d:?}")))?;
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    spu.set_engine(engine);
    spu.set_extensions(ext);
    spu.share_code(&compile.cache());
    if timing {
        spu.enable_timing(Default::default());
    }
    let mut memory = MainMemory::zeroed(4096);
    let started = Instant::now();
    let stop = spu.run(&mut memory, u64::MAX);
    let seconds = started.elapsed().as_secs_f64();
    if stop != StopReason::Stop(0x2000) {
        return Err(exit::Error::new(
            Status::of_stop(&stop),
            format!("benchmark loop stopped with {stop}"),
        ));
    }
    Ok((spu.instructions(), spu.cycles(), seconds))
}

/// A frame of the room on one SPE with `engine`: (instructions, cycles, host seconds).
fn measure_frame(
    room: &spu_loader::render::Prepared,
    size: u32,
    engine: Engine,
    compile: &options::CompileOption,
    ext: spu_isa::Extensions,
) -> exit::Result<(u64, u64, f64)> {
    let config = spu_loader::render::RenderConfig {
        width: size,
        height: size,
        engine,
        extensions: ext,
        kernel: spu_loader::render::RenderConfig::kernel_with(
            false,
            spu_loader::shading::ShadeMode::None,
            ext,
        ),
        ..spu_loader::render::RenderConfig::new(&room.name)
    };
    let started = Instant::now();
    let frame = spu_loader::render::render(room, &config, &compile.cache())
        .map_err(|e| exit::Error::failure(e.to_string()))?;
    let seconds = started.elapsed().as_secs_f64();
    let instructions = frame.run.spus.iter().map(|s| s.instructions).sum();
    Ok((instructions, frame.run.frame_cycles, seconds))
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    options::count("--iterations", args.iterations, 1..=u32::MAX)?;
    options::count("--frame", args.frame, 0..=1024)?;
    let engines = match args.engine {
        Some(e) => vec![e],
        None if Engine::SUPPORTED => vec![Engine::Interp, Engine::Jit],
        None => vec![Engine::Interp],
    };
    outln!("mixed loop: {} iterations", args.iterations);
    let mut rates = Vec::new();
    for &engine in &engines {
        let (n_off, _, s_off) =
            measure(args.iterations, false, engine, &args.compile, args.ext.ext)?;
        let (n_on, cycles, s_on) =
            measure(args.iterations, true, engine, &args.compile, args.ext.ext)?;
        let off = n_off as f64 / s_off.max(1e-9) / 1e6;
        let on = n_on as f64 / s_on.max(1e-9) / 1e6;
        outln!("{engine:6} timing off: {off:8.1} M simulated instructions per host second ({n_off} instructions)");
        outln!("{engine:6} timing on:  {on:8.1} M simulated instructions per host second ({cycles} cycles, CPI {:.3})", cycles as f64 / n_on as f64);
        outln!("{engine:6} timing overhead: {:.2}x", off / on);
        rates.push((off, on));
    }
    if let [(i_off, i_on), (j_off, j_on)] = rates[..] {
        outln!(
            "jit / interp: {:.2}x timing off, {:.2}x timing on",
            j_off / i_off,
            j_on / i_on
        );
    }
    if args.frame > 0 {
        let room = spu_loader::render::prepare("room").map_err(exit::Error::failure)?;
        let size = args.frame;
        for &engine in &engines {
            let (n, cycles, s) = measure_frame(&room, size, engine, &args.compile, args.ext.ext)?;
            outln!(
                "{engine:6} room {size}x{size} frame: {:8.1} M simulated instructions per host second ({n} instructions, {cycles} cycles, {s:.3} s)",
                n as f64 / s.max(1e-9) / 1e6
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}
