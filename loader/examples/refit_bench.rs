//! Cycles of the SPU refit of a built-in animation's frame 1 on 1 to 16 SPEs (the refit
//! target: the beetle's under 10% of a 16-SPE shadows frame).
//!
//! `cargo run --release -p spu-loader --example refit_bench -- beetle-drive`

use spu_isa::jit::{CodeCache, Compiling, Engine};
use spu_loader::animation::Animation;
use spu_loader::frame::SCENE_BASE;
use spu_loader::refit::{AnimatedBvh, RebuildPolicy};
use spu_loader::spu_refit::{self, RefitConfig, RefitPlan};
use spu_loader::{BvhConfig, StagedScene};

fn main() -> Result<(), String> {
    let name = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "room-flag".into());
    let animation = Animation::open(&name, 2)?;
    let mut tree = AnimatedBvh::new(
        animation.first(),
        &BvhConfig::default(),
        RebuildPolicy::default(),
    );
    let scene = animation.frame(1)?;
    let frame = tree.advance(&scene);
    let staged = StagedScene::new(&scene, &frame.bvh, SCENE_BASE)?;
    let plan = RefitPlan::new(&staged)?;
    let program = spu_refit::program()?;
    let code = CodeCache::with(Compiling::Inline);
    println!(
        "{name}: {} triangles, {} nodes, {} items, {} heights, SAH {} (built {})",
        scene.triangles.len(),
        staged.nodes.len(),
        plan.items(),
        plan.heights(),
        frame.refit_cost,
        frame.built_cost
    );
    for spes in [1, 8, 16] {
        let config = RefitConfig {
            spes,
            threads: 2,
            clock_ghz: 2.4,
            dma_latency_ns: 100.0,
            timed: true,
            engine: Engine::host_default(),
            max_cycles: 10_000_000_000,
        };
        let run = spu_refit::run(&staged, &plan, &config, &program, &code)?;
        let polls: u64 = run.spes.iter().map(|s| s.polls).sum();
        println!(
            "{spes:2} SPEs: {} cycles, DMA {} KB read {} KB written, polls {polls}",
            run.cycles,
            run.dma_bytes.0 / 1024,
            run.dma_bytes.1 / 1024
        );
    }
    Ok(())
}
