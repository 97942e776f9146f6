//! Loads (or generates) scenes and reports load, BVH build and reference render times — the
//! figures quoted for the host side. Run in release:
//!
//! `cargo run --release -p spu-loader --example scene_stats -- [room|conference|beetle|PATH]... [--render N] [--png DIR] [--bvh-threads 1,2,...]`
//!
//! `--bvh-threads` also times the BVH build on each of those thread counts (the median of 7
//! builds), the benchmark of the parallel build (docs/parallel.md).
//!
//! `--png DIR` also writes each reference eye-light image as `DIR/<scene>.png` (grayscale), to
//! eyeball the default cameras.

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
    let mut png_dir = None;
    if let Some(i) = args.iter().position(|a| a == "--png") {
        png_dir = args.get(i + 1).cloned();
        args.drain(i..(i + 2).min(args.len()));
        if render_size == 0 {
            render_size = 512;
        }
    }
    let mut bvh_threads: Vec<usize> = Vec::new();
    if let Some(i) = args.iter().position(|a| a == "--bvh-threads") {
        bvh_threads = args
            .get(i + 1)
            .map(|list| list.split(',').filter_map(|n| n.parse().ok()).collect())
            .unwrap_or_default();
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
        for &threads in &bvh_threads {
            let config = BvhConfig {
                threads,
                ..BvhConfig::default()
            };
            let mut seconds: Vec<f64> = (0..7)
                .map(|_| {
                    let start = Instant::now();
                    let again = Bvh::build(&scene, &config);
                    assert_eq!(again.nodes, bvh.nodes, "{threads} threads");
                    start.elapsed().as_secs_f64()
                })
                .collect();
            seconds.sort_by(f64::total_cmp);
            println!(
                "{name}: BVH build on {threads} thread(s): median {:.3} s (min {:.3}, max {:.3}, 7 builds)",
                seconds[3], seconds[0], seconds[6]
            );
        }
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
            if let Some(dir) = &png_dir {
                let image =
                    reference.eye_light_image(&hits, &scene.camera, render_size, render_size);
                let stem = std::path::Path::new(&name)
                    .file_name()
                    .unwrap()
                    .to_string_lossy()
                    .replace('.', "_");
                let path = std::path::Path::new(dir).join(format!("{stem}.png"));
                std::fs::write(&path, gray_png(&image, render_size, render_size))
                    .expect("write png");
                println!("  wrote {}", path.display());
            }
        }
    }
}

/// A minimal grayscale PNG (the tools crate owns real image output).
fn gray_png(pixels: &[u8], width: u32, height: u32) -> Vec<u8> {
    use std::io::Write;
    fn crc32(bytes: &[u8]) -> u32 {
        let mut crc = !0u32;
        for &byte in bytes {
            crc ^= byte as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let start = out.len();
        out.extend_from_slice(kind);
        out.extend_from_slice(data);
        let crc = crc32(&out[start..]);
        out.extend_from_slice(&crc.to_be_bytes());
    }
    let mut raw = Vec::with_capacity(pixels.len() + height as usize);
    for row in pixels.chunks(width as usize) {
        raw.push(0);
        raw.extend_from_slice(row);
    }
    let mut encoder = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
    encoder.write_all(&raw).unwrap();
    let compressed = encoder.finish().unwrap();
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut header = Vec::new();
    header.extend_from_slice(&width.to_be_bytes());
    header.extend_from_slice(&height.to_be_bytes());
    header.extend_from_slice(&[8, 0, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &header);
    chunk(&mut out, b"IDAT", &compressed);
    chunk(&mut out, b"IEND", &[]);
    out
}
