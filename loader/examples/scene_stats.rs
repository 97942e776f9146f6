//! Loads (or generates) scenes and reports load, BVH build and reference render times — the
//! figures quoted for the host side. Run in release:
//!
//! `cargo run --release -p spu-loader --example scene_stats -- [room|conference|beetle|PATH]... [--render N]`

use std::time::Instant;

use spu_loader::bvh::{Bvh, BvhConfig};
use spu_loader::layout::StagedScene;
use spu_loader::procedural;
use spu_loader::reference::Reference;
use spu_loader::scene::Scene;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut render_size = 0u32;
    if let Some(i) = args.iter().position(|a| a == "--render") {
        render_size = args.get(i + 1).and_then(|s| s.parse().ok()).unwrap_or(1024);
        args.drain(i..(i + 2).min(args.len()));
    }
    if args.is_empty() {
        args = vec!["room".into(), "conference".into(), "beetle".into()];
    }
    for name in args {
        let start = Instant::now();
        let scene = match procedural::by_name(&name) {
            Some(scene) => scene,
            None => match Scene::load(&name) {
                Ok(scene) => scene,
                Err(e) => {
                    eprintln!("{e}");
                    std::process::exit(1);
                }
            },
        };
        let load = start.elapsed();
        let start = Instant::now();
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let build = start.elapsed();
        let stats = bvh.stats();
        let start = Instant::now();
        let staged = StagedScene::new(&scene, &bvh, 0x10_0000).expect("staging");
        let stage = start.elapsed();
        println!(
            "{name}: {} triangles, {} vertices, {} materials; load {:.3} s; BVH build {:.3} s \
             ({} nodes, {} leaves, depth {}, mean leaf {:.2}, SAH cost {:.2}); staging {:.3} s ({} MiB)",
            scene.triangle_count(),
            scene.positions.len(),
            scene.materials.len(),
            load.as_secs_f64(),
            build.as_secs_f64(),
            bvh.nodes.len(),
            stats.leaves,
            stats.max_depth,
            stats.mean_leaf_triangles,
            bvh.sah_cost,
            stage.as_secs_f64(),
            staged.image.len() >> 20,
        );
        if render_size > 0 {
            let reference = Reference::from_staged(&staged);
            let threads = std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1);
            let start = Instant::now();
            let hits = reference.render(&scene.camera, render_size, render_size, threads);
            let elapsed = start.elapsed();
            let hit_count = hits.iter().filter(|h| h.is_hit()).count();
            println!(
                "  reference {render_size}x{render_size} on {threads} threads: {:.3} s, {hit_count} hits, camera {}",
                elapsed.as_secs_f64(),
                scene.camera.to_cli_string()
            );
        }
    }
}
