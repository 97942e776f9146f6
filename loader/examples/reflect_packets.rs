//! The reflection packets `--shade reflect` would trace, from the host reference: per scene
//! and bounce, the reflected rays, their hits, the 8x8 packets with any ray and their
//! active-ray fraction (the figures of docs/reflections.md). Run in release:
//!
//! `cargo run --release -p spu-loader --example reflect_packets -- [SIZE] [DEPTH] [--ppm DIR]`
//!
//! (SIZE x SIZE pixels, default 1024; DEPTH bounces, default 4.) `--ppm DIR` also writes
//! each scene's reference image with reflections as `DIR/<scene>-reflect.ppm`, to eyeball.

use std::time::Instant;

use spu_loader::reference::Reference;
use spu_loader::reflection::ReflectFrame;
use spu_loader::{render, shading};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let ppm = args
        .iter()
        .position(|a| a == "--ppm")
        .and_then(|i| args.get(i + 1).cloned());
    let numbers: Vec<u32> = args.iter().filter_map(|a| a.parse().ok()).collect();
    let size = numbers.first().copied().unwrap_or(1024);
    let depth = numbers
        .get(1)
        .copied()
        .unwrap_or(shading::MAX_REFLECT_DEPTH);
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    for name in ["room", "conference", "beetle"] {
        let started = Instant::now();
        let prepared = render::prepare(name).expect("a built-in scene");
        let reference = Reference::from_staged(&prepared.staged);
        let camera = &prepared.scene.camera;
        let hits = reference.render(camera, size, size, threads);
        let lights = shading::default_lights(&prepared.scene);
        let frame = ReflectFrame::render(
            &reference, &hits, camera, size, size, &lights, depth, threads,
        );
        let packets = size.div_ceil(8) * size.div_ceil(8);
        for b in frame.packets(size, size) {
            println!(
                "{name} {size}x{size} bounce {}: {} rays, {} hit; {} of {packets} packets, {:.1}% of their rays active",
                b.bounce,
                b.rays,
                b.hits,
                b.packets,
                100.0 * b.active_fraction()
            );
        }
        eprintln!("{name}: {:.1} s", started.elapsed().as_secs_f64());
        if let Some(dir) = &ppm {
            let mut bytes = format!("P6 {size} {size} 255\n").into_bytes();
            for c in &frame.colours {
                bytes.extend_from_slice(&c.to_be_bytes()[..3]);
            }
            let path = std::path::Path::new(dir).join(format!("{name}-reflect.ppm"));
            std::fs::write(&path, bytes).expect("write the image");
        }
    }
}
