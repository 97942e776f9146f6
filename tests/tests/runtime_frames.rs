//! End-to-end frames through the multi-SPE runtime: the fill program exercises the tile
//! queue and the deterministic memory model; the ray-tracing kernel is checked pixel by
//! pixel against the host reference.

use spu_isa::jit::CodeCache;
use spu_isa::timing::TimingConfig;
use spu_loader::camera::Camera;
use spu_loader::kernel_abi::{
    decode_frame_buffer, pixel_location, MISS, PACKETS_PER_TILE, PACKET_BLOCK_BYTES,
};
use spu_loader::reference::Reference;
use spu_loader::render::{prepare, render, render_with, KernelVariant, Prepared, RenderConfig};
use spu_loader::runtime::FrameRun;

/// A `width x height` frame of `scene` on `spes` SPEs with blocking misses (one packet in
/// flight) and 256-line direct-mapped caches.
fn config(scene: &str, width: u32, height: u32, spes: usize, threads: usize) -> RenderConfig {
    RenderConfig {
        width,
        height,
        spes,
        threads,
        sht: 1,
        max_cycles: 50_000_000_000,
        ..RenderConfig::new(scene)
    }
}

fn frame(
    prepared: &Prepared,
    width: u32,
    height: u32,
    spes: usize,
    threads: usize,
    fill: bool,
) -> FrameRun {
    let config = RenderConfig {
        kernel: if fill {
            KernelVariant::Fill
        } else {
            KernelVariant::Primary
        },
        ..config(&prepared.name, width, height, spes, threads)
    };
    render(prepared, &config, &CodeCache::default())
        .unwrap()
        .run
}

fn word(bytes: &[u8], off: usize) -> u32 {
    u32::from_be_bytes([bytes[off], bytes[off + 1], bytes[off + 2], bytes[off + 3]])
}

/// 16 SPUs contend for 16 tiles of a 256x256 frame: every packet block carries its own
/// tile and packet number exactly once, and the work is spread over several SPUs.
#[test]
fn tile_queue_hands_out_every_tile_once_with_16_spus() {
    let run = frame(&prepare("room").unwrap(), 256, 256, 16, 2, true);
    let tiles = 16;
    for tile in 0..tiles {
        for packet in 0..PACKETS_PER_TILE {
            let block = ((tile * PACKETS_PER_TILE + packet) * PACKET_BLOCK_BYTES) as usize;
            for i in 0..64 {
                assert_eq!(
                    word(&run.frame_buffer, block + 4 * i),
                    tile * 64 + packet,
                    "tile {tile} packet {packet}"
                );
                assert_eq!(
                    f32::from_bits(word(&run.frame_buffer, block + 256 + 4 * i)),
                    1.0
                );
            }
        }
    }
    let total: u64 = run.spus.iter().map(|s| s.tiles).sum();
    assert_eq!(total, tiles as u64);
    assert!(
        run.spus.iter().filter(|s| s.tiles > 0).count() > 1,
        "only one SPU did the work"
    );
}

/// The same frame, statistics and cycles for 1, 2 and 4 host threads.
#[test]
fn frames_are_identical_for_any_thread_count() {
    let room = prepare("room").unwrap();
    let one = frame(&room, 128, 128, 4, 1, false);
    for threads in [2, 4] {
        let other = frame(&room, 128, 128, 4, threads, false);
        assert_eq!(one.frame_buffer, other.frame_buffer, "{threads} threads");
        assert_eq!(one.frame_cycles, other.frame_cycles);
        for (a, b) in one.spus.iter().zip(&other.spus) {
            assert_eq!(
                (a.cycles, a.instructions, a.tiles, a.stats),
                (b.cycles, b.instructions, b.tiles, b.stats)
            );
        }
    }
}

/// A frame that runs out of cycles on several host threads returns the error (the
/// threads sharing the SPUs end with it) and the same error on one. The limit is per SPE
/// and exact: the last quantum (95,000 is not a multiple of 10,000) ends at the limit, and
/// every SPE's clock stands at it.
#[test]
fn a_frame_out_of_cycles_ends_on_every_thread_count() {
    let room = prepare("room").unwrap();
    for threads in [1, 2, 4] {
        let mut quanta = 0;
        let config = RenderConfig {
            max_cycles: 95_000,
            ..config("room", 128, 128, 4, threads)
        };
        let result = render_with(&room, &config, &CodeCache::default(), &mut |_, _| {
            quanta += 1
        })
        .map(|_| ());
        assert_eq!(
            result.err(),
            Some(spu_loader::runtime::FrameError::CycleLimit {
                limit: 95_000,
                cycles: vec![95_000; 4],
                stopped: vec![0, 1, 2, 3],
            }),
            "{threads} threads"
        );
        assert_eq!(quanta, 10, "{threads} threads: quanta run");
    }
}

/// The kernel's hits agree with the host reference on every pixel of a 128x128 room.
#[test]
fn raytrace_kernel_matches_the_reference_on_the_room() {
    let room = prepare("room").unwrap();
    let (scene, staged) = (&room.scene, &room.staged);
    let (w, h) = (128, 128);
    let run = frame(&room, w, h, 1, 1, false);
    let pixels = decode_frame_buffer(&run.frame_buffer, w, h);
    let reference = Reference::from_staged(staged).render(&scene.camera, w, h, 1);
    let mut bad = Vec::new();
    for (i, (p, r)) in pixels.iter().zip(&reference).enumerate() {
        let kernel = if p.triangle == MISS {
            MISS
        } else {
            staged.triangles[p.triangle as usize].original_index
        };
        let t_ok = !r.is_hit() || (p.t - r.t).abs() <= 1e-4 * r.t.abs();
        if (kernel == MISS) == r.is_hit() || !t_ok {
            bad.push((i as u32 % w, i as u32 / w, kernel, r.triangle, p.t, r.t));
        }
    }
    assert!(
        bad.len() <= 2,
        "{} of {} pixels differ, first: {:?}",
        bad.len(),
        pixels.len(),
        &bad[..bad.len().min(5)]
    );
    let s = run.spus[0].stats;
    assert_eq!(s.packets, 4 * 64);
    assert!(s.traversal_steps > s.packets);
    check_stats(&s);
    let _ = (
        pixel_location(0, 0, 2),
        Camera::parse("0,0,5,0,0,0,0,1,0,45").unwrap(),
    );
}

/// The counters the kernel keeps hold together: two box tests per pair step (one BVH-cache
/// lookup each), every early hit or exit is a box test, misses are lookups.
fn check_stats(s: &spu_loader::kernel_abi::KernelStats) {
    assert_eq!(s.traversal_steps, 2 * s.bvh_lookups, "{s:?}");
    assert!(s.early_hits + s.early_exits <= s.traversal_steps, "{s:?}");
    assert!(s.bvh_cache_misses <= s.bvh_lookups, "{s:?}");
    assert!(s.triangle_cache_misses <= s.triangle_lookups, "{s:?}");
    assert!(
        s.triangle_tests + s.triangles_culled <= s.triangle_lookups,
        "{s:?}"
    );
    assert!(s.leaves <= s.traversal_steps, "{s:?}");
}

/// A large scene with a small BVH cache and triangle cache: the miss paths, the third
/// traversal case (first ray misses, frustum does not) and the leaf prefetch all run, and
/// every pixel still agrees with the reference up to ties.
#[test]
fn raytrace_kernel_matches_the_reference_on_the_conference_with_small_caches() {
    let conference = prepare("conference").unwrap();
    let (scene, staged) = (&conference.scene, &conference.staged);
    let (w, h) = (64, 64);
    let config = RenderConfig {
        bvh_cache: 128,
        tri_cache: 128,
        max_cycles: 20_000_000_000,
        ..config("conference", w, h, 1, 1)
    };
    let run = render(&conference, &config, &CodeCache::default())
        .unwrap()
        .run;
    let pixels = decode_frame_buffer(&run.frame_buffer, w, h);
    let reference = Reference::from_staged(staged).render(&scene.camera, w, h, 1);
    let mut bad = 0;
    for (p, r) in pixels.iter().zip(&reference) {
        let hit_agrees = (p.triangle == MISS) != r.is_hit();
        let t_agrees = !r.is_hit() || (p.t - r.t).abs() <= 1e-4 * r.t.abs();
        if !hit_agrees || !t_agrees {
            bad += 1;
        }
    }
    assert!(bad <= 1, "{bad} of {} pixels differ", pixels.len());
    let s = run.spus[0].stats;
    check_stats(&s);
    assert!(
        s.bvh_cache_misses > 0 && s.triangle_cache_misses > 0,
        "{s:?}"
    );
    assert!(
        s.early_hits + s.early_exits < s.traversal_steps,
        "the third case never ran: {s:?}"
    );
}

/// The degenerate BVHs: a scene of one triangle (the root is a leaf) and a scene of none
/// (the root is an inverted box, the kernel skips traversal): the kernel agrees with the
/// reference and stops.
#[test]
fn raytrace_kernel_handles_a_leaf_root_and_an_empty_scene() {
    use glam::{Vec2, Vec3};
    use spu_loader::scene::Triangle;
    let one = spu_loader::Scene::from_parts(
        vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        None,
        Vec::<Vec2>::new(),
        vec![Triangle {
            v: [0, 1, 2],
            material: 0,
        }],
        Vec::new(),
    );
    let empty = spu_loader::Scene::from_parts(Vec::new(), None, Vec::new(), Vec::new(), Vec::new());
    for (mut scene, expect_hits) in [(one, true), (empty, false)] {
        scene.camera = Camera::parse("0,0,3,0,0,0,0,1,0,60").unwrap();
        let (w, h) = (32, 32);
        let prepared = Prepared::from_scene("degenerate", scene).unwrap();
        let run = frame(&prepared, w, h, 1, 1, false);
        let pixels = decode_frame_buffer(&run.frame_buffer, w, h);
        let reference =
            Reference::from_staged(&prepared.staged).render(&prepared.scene.camera, w, h, 1);
        let mut hits = 0;
        for (p, r) in pixels.iter().zip(&reference) {
            assert_eq!(p.triangle == MISS, !r.is_hit());
            if r.is_hit() {
                hits += 1;
                assert!((p.t - r.t).abs() <= 1e-4 * r.t.abs());
            }
        }
        assert_eq!(hits > 0, expect_hits);
        assert_eq!(run.spus[0].stats.packets, 64); // one 64x64 tile
    }
}

/// The ray-tracing kernel with the timing model's block memoization (replays, chained
/// blocks, replays run in one go by the core) and without it: the same frame, cycles and
/// counters, total and per address. A small frame of the conference with small caches, so
/// that DMA, cache misses and every traversal case interleave with replayed blocks. (Below
/// the render API: memoization is the timing model's own setting, which no frame changes.)
#[test]
fn raytrace_kernel_times_the_same_with_and_without_block_memoization() {
    let conference = prepare("conference").unwrap();
    let config = RenderConfig {
        bvh_cache: 128,
        tri_cache: 128,
        ..config("conference", 24, 16, 2, 1)
    };
    let pp = assert_memo_times_the_same(&conference, &config, "");
    assert!(pp.totals.branch_misses > 0 && pp.totals.instructions > 100_000);
}

/// Runs `config`'s frame of `prepared` (one host thread) with the block memo off and on and
/// asserts the same image, cycles, profile totals and per-address counters; gives the
/// profile. `what` names the case in a failure.
pub(crate) fn assert_memo_times_the_same(
    prepared: &Prepared,
    config: &RenderConfig,
    what: &str,
) -> spu_isa::profile::Profile {
    let program = config.kernel.program().unwrap();
    let layout = spu_loader::render::frame_layout(prepared, config, &program, &[]).unwrap();
    let run = |memoize: bool| {
        spu_loader::runtime::run_frame(
            &spu_loader::runtime::Frame {
                staged: &prepared.staged,
                layout: &layout,
                program: &program,
                kernel: config.kernel,
                spes: config.spes,
                threads: 1,
                timing: TimingConfig {
                    memoize,
                    ..Default::default()
                },
                timed: true,
                engine: config.engine,
                max_cycles: 20_000_000_000,
                event_log: false,
                code: &CodeCache::default(),
                extensions: config.extensions,
            },
            &mut |_, _| {},
        )
        .unwrap()
    };
    let (plain, memo) = (run(false), run(true));
    assert_eq!(plain.frame_buffer, memo.frame_buffer, "{what}");
    assert_eq!(plain.frame_cycles, memo.frame_cycles, "{what}");
    let (pp, pm) = (plain.profile.unwrap(), memo.profile.unwrap());
    assert_eq!(pp.totals, pm.totals, "{what}");
    let per_address = |p: &spu_isa::profile::Profile| -> Vec<_> {
        p.addresses().map(|(pc, s)| (pc, *s)).collect()
    };
    assert_eq!(per_address(&pp), per_address(&pm), "{what}");
    pp
}

/// Every frame program through the render API on a 64x64 room on two SPEs: the ray tracers
/// agree with the host reference on every pixel (hits, and colours where they shade), the
/// fill program writes each packet's number; the profile annotates the program that ran.
/// (A new [`KernelVariant`] must say here what its frames are.)
#[test]
fn every_kernel_variant_renders_and_validates() {
    let room = prepare("room").unwrap();
    for variant in KernelVariant::ALL {
        let mut config = RenderConfig {
            kernel: variant,
            ..config("room", 64, 64, 2, 2)
        };
        config.shading.mode = match variant {
            KernelVariant::Primary | KernelVariant::Fill | KernelVariant::PrimaryMultihint => {
                spu_loader::shading::ShadeMode::None
            }
            KernelVariant::Shaded | KernelVariant::ShadedGather => {
                spu_loader::shading::ShadeMode::Shadows
            }
            KernelVariant::Reflect => spu_loader::shading::ShadeMode::Reflect,
        };
        if variant == KernelVariant::ShadedGather {
            config.extensions = spu_isa::Extensions::parse("gather").unwrap();
        }
        let frame = render(&room, &config, &CodeCache::default()).unwrap();
        assert_eq!(frame.run.kernel_image, variant.program().unwrap().image);
        assert!(frame
            .profile_listing()
            .unwrap()
            .contains(if variant.traces() { "trav" } else { "_start" }));
        match variant {
            KernelVariant::Primary
            | KernelVariant::Shaded
            | KernelVariant::PrimaryMultihint
            | KernelVariant::Reflect
            | KernelVariant::ShadedGather => {
                let v = spu_loader::render::validate(&room, &config, &frame).unwrap();
                assert!(v.passed(), "{variant:?}: {:?}", v.messages);
                assert_eq!(v.pixels, 64 * 64);
                assert_eq!(v.colour_mismatches.is_some(), variant.shades());
                assert_eq!(frame.run.shadow_rays > 0, variant.shades());
                // the room's table reflects: the reflect frame traces its rays
                let reflects = variant == KernelVariant::Reflect;
                assert_eq!(v.bounce_rays.first().is_some_and(|&n| n > 0), reflects);
                assert_eq!(
                    frame.run.reflect_counters.first().map(|c| c.rays.0),
                    reflects.then_some(v.bounce_rays.first().copied().unwrap_or(0) as u64)
                );
            }
            KernelVariant::Fill => {
                assert!(spu_loader::render::validate(&room, &config, &frame).is_err());
                for packet in 0..PACKETS_PER_TILE {
                    let block = (packet * PACKET_BLOCK_BYTES) as usize;
                    assert_eq!(word(&frame.run.frame_buffer, block), packet);
                }
            }
        }
    }
}
