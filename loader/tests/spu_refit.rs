//! The SPU refit (`kernels/refit.s`) writes the host refit's node bounds bit for bit, on
//! 1 to 16 SPEs, the same whatever the host threads and the engine.

use spu_isa::jit::{CodeCache, Compiling, Engine};
use spu_loader::animation::Animation;
use spu_loader::frame::SCENE_BASE;
use spu_loader::refit::{AnimatedBvh, RebuildPolicy};
use spu_loader::spu_refit::{self, RefitConfig, RefitPlan};
use spu_loader::{BvhConfig, StagedScene};

fn config(spes: usize, threads: usize) -> RefitConfig {
    RefitConfig {
        spes,
        threads,
        clock_ghz: 2.4,
        dma_latency_ns: 100.0,
        timed: true,
        engine: Engine::host_default(),
        max_cycles: 50_000_000,
    }
}

#[test]
fn the_spus_refit_the_moving_flag_bit_for_bit_on_1_to_16_spes() {
    let animation = Animation::open("room-flag", 4).unwrap();
    let bvh_config = BvhConfig {
        threads: 1,
        ..BvhConfig::default()
    };
    let never = RebuildPolicy {
        ratio: f32::INFINITY,
    };
    let mut tree = AnimatedBvh::new(animation.first(), &bvh_config, never);
    let program = spu_refit::program().unwrap();
    let code = CodeCache::with(Compiling::Inline);
    for frame in 1..4 {
        let scene = animation.frame(frame).unwrap();
        let bvh = tree.advance(&scene).bvh;
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE).unwrap();
        let plan = RefitPlan::new(&staged).unwrap();
        assert!(plan.heights() > 3 && plan.items() > plan.heights());
        let mut cycles = Vec::new();
        for spes in [1, 3, 16] {
            // run() refuses a node array that differs from the host refit's
            let run = spu_refit::run(&staged, &plan, &config(spes, 2), &program, &code)
                .unwrap_or_else(|e| panic!("frame {frame} on {spes} SPEs: {e}"));
            assert_eq!(run.spes.len(), spes);
            assert_eq!(
                run.spes.iter().map(|s| s.items).sum::<u64>() as usize,
                plan.items()
            );
            assert_eq!(
                run.spes.iter().map(|s| s.nodes).sum::<u64>() as usize,
                staged.nodes.len() - 1
            );
            let again = spu_refit::run(&staged, &plan, &config(spes, 1), &program, &code).unwrap();
            assert_eq!(again, run, "the same on one host thread");
            let interpreted = RefitConfig {
                engine: Engine::Interp,
                ..config(spes, 2)
            };
            let interpreted =
                spu_refit::run(&staged, &plan, &interpreted, &program, &code).unwrap();
            assert_eq!(interpreted, run, "the same with the interpreter");
            cycles.push(run.cycles);
        }
        assert!(cycles[0] > cycles[1], "{cycles:?}");
    }
}

#[test]
fn a_wrong_host_refit_is_caught() {
    let animation = Animation::open("room-flag", 3).unwrap();
    let first = animation.first();
    let bvh = spu_loader::Bvh::build(first, &BvhConfig::default());
    // staged with frame 0's bounds but frame 2's vertices: the SPUs' bounds differ
    let moved = animation.frame(2).unwrap();
    let staged = StagedScene::new(&moved, &bvh, SCENE_BASE).unwrap();
    let plan = RefitPlan::new(&staged).unwrap();
    let program = spu_refit::program().unwrap();
    let code = CodeCache::with(Compiling::Inline);
    let err = spu_refit::run(&staged, &plan, &config(2, 1), &program, &code).unwrap_err();
    assert!(err.contains("differs from the host refit at node"), "{err}");
}
