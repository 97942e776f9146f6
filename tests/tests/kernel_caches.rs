//! The 4-way caches and software hyperthreading of the primary-ray kernel: the LRU module
//! (`kernels/modules/lru.s`) alone on the simulator, and whole frames with 1 to 8 packets
//! in flight and direct-mapped or 4-way caches, which must all give the same image as the
//! blocking direct-mapped kernel and the host reference.

use spu_isa::machine::{MainMemory, Spu};
use spu_isa::timing::TimingConfig;
use spu_loader::camera::Camera;
use spu_loader::frame::{FrameLayout, SCENE_BASE};
use spu_loader::kernel_abi::{decode_frame_buffer, KernelStats, MISS};
use spu_loader::reference::Reference;
use spu_loader::runtime::{render_frame, FrameRun};
use spu_loader::{procedural, Bvh, BvhConfig, Scene, StagedScene};

/// A driver for `lru.s`: one 4-way set whose ways are 16 bytes (tags) and 64 bytes (lines)
/// apart, way w holding tag 0x1000 + 0x40 w and a line whose words are 0x100 w + word.
/// It looks for way 2's key (a hit in another way), moves way 2 to the front, looks for a
/// key that is not there, evicts the least recent way (rotating way 3 to the front), and
/// stores what lru_find answered at `found`.
const LRU_DRIVER: &str = "
        .text
        .global _start
_start:
        ila     $101, tags
        ila     $102, lines
        il      $103, 16
        il      $104, 64
        ila     $116, 0x1080                  # way 2's key
        brsl    $0, lru_find
        stqa    $100, found
        brsl    $0, lru_rotate                # way 2 is now the most recent
        ila     $116, 0x1234                  # not in the set
        brsl    $0, lru_find
        stqa    $100, found+16
        il      $100, 3
        brsl    $0, lru_rotate                # the least recent way goes to the front
        stop    0x2000

        .data
        .align  4
found:  .space  32
tags:   .long   0x1000, 0, 0, 0
        .long   0x1040, 0, 0, 0
        .long   0x1080, 0, 0, 0
        .long   0x10c0, 0, 0, 0
lines:  .rept   4
        .endr
";

fn lru_program() -> String {
    let mut lines = String::new();
    for way in 0..4 {
        for word in 0..16 {
            lines += &format!("        .long   {:#x}\n", 0x100 * way + word);
        }
    }
    LRU_DRIVER.replace(
        "lines:  .rept   4\n        .endr\n",
        &format!("lines:\n{lines}"),
    ) + include_str!("../../kernels/modules/lru.s")
}

fn word(ls: &[u8], addr: u32) -> u32 {
    let a = addr as usize;
    u32::from_be_bytes([ls[a], ls[a + 1], ls[a + 2], ls[a + 3]])
}

/// lru_find finds a key in ways 1..3 (and says 0 when it is not there); lru_rotate keeps
/// the ways in the order of their last use: a hit in way 2 gives (2, 0, 1, 3), an eviction
/// then (3, 2, 0, 1), tags and lines moving together.
#[test]
fn lru_module_finds_and_rotates_a_four_way_set() {
    let out =
        spu_asm::assemble(&lru_program(), "lru_driver.s", &Default::default()).expect("assembles");
    let symbol = |name: &str| {
        out.symbols
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| *a)
            .unwrap()
    };
    let mut spu = Spu::new(0);
    spu.load_image(&out.image);
    spu.set_pc(out.entry);
    let mut mem = MainMemory::zeroed(4096);
    let stop = spu.run(&mut mem, 1_000_000);
    let ls = spu.ls();
    let (found, tags, lines) = (symbol("found"), symbol("tags"), symbol("lines"));
    assert_eq!(word(ls, found), 2, "way 2 holds the key");
    assert_eq!(word(ls, found + 16), 0, "no way holds it");
    let order: Vec<u32> = (0..4)
        .map(|w| (word(ls, tags + 16 * w) - 0x1000) / 0x40)
        .collect();
    assert_eq!(order, [3, 2, 0, 1]);
    for (w, old) in order.iter().enumerate() {
        for k in 0..16 {
            assert_eq!(
                word(ls, lines + 64 * w as u32 + 4 * k),
                0x100 * old + k,
                "way {w} word {k}"
            );
        }
    }
    let mut text = format!("stop: {stop}\ncycles: {}\n", spu.cycles());
    for n in [0, 100, 101, 102, 103, 104, 116] {
        let r = spu.reg(n);
        text += &format!(
            "${n}: {:08x} {:08x} {:08x} {:08x}\n",
            r[0], r[1], r[2], r[3]
        );
    }
    for q in 0..(32 + 64 + 256) / 16 {
        let a = found + 16 * q;
        text += &format!(
            "{a:05x}: {:08x} {:08x} {:08x} {:08x}\n",
            word(ls, a),
            word(ls, a + 4),
            word(ls, a + 8),
            word(ls, a + 12)
        );
    }
    insta::assert_snapshot!(text);
}

fn staged(scene: &Scene) -> StagedScene {
    let bvh = Bvh::build(
        scene,
        &BvhConfig {
            threads: 1,
            ..BvhConfig::default()
        },
    );
    StagedScene::new(scene, &bvh, SCENE_BASE).unwrap()
}

#[allow(clippy::too_many_arguments)]
fn frame(
    scene: &Scene,
    staged: &StagedScene,
    (w, h): (u32, u32),
    spes: usize,
    lines: u32,
    assoc: u32,
    sht: u32,
) -> Result<FrameRun, String> {
    let basis = scene.camera.basis(w, h);
    let layout = FrameLayout::new(staged, &basis, w, h, spes, lines, lines)?
        .with_kernel_options(assoc, sht)?;
    render_frame(
        staged,
        &layout,
        spes,
        1,
        &TimingConfig::default(),
        false,
        20_000_000_000,
        &mut |_, _| {},
    )
    .map_err(|e| e.to_string())
}

fn stats(run: &FrameRun) -> KernelStats {
    run.kernel_stats()
}

fn channel_stalls(run: &FrameRun) -> u64 {
    let chan = spu_isa::timing::StallCause::NAMES
        .iter()
        .position(|n| *n == "chan")
        .unwrap();
    run.profile.as_ref().unwrap().totals.stall[chan]
}

/// The conference at 64x64 with 128-line caches (misses in both caches on most steps):
/// the blocking direct-mapped kernel agrees with the reference; 2, 4 and 8 packets in
/// flight, 4-way caches, and both on 2 SPEs give the very same frame buffer and the same
/// traversal work; packets in flight overlap the fetches (fewer cycles waiting on DMA), and
/// 4-way sets change which lookups hit.
#[test]
fn frames_are_identical_for_every_sht_count_and_associativity() {
    let scene = procedural::conference();
    let staged = staged(&scene);
    let size = (64, 64);
    let base = frame(&scene, &staged, size, 1, 128, 1, 1).unwrap();
    let pixels = decode_frame_buffer(&base.frame_buffer, size.0, size.1);
    let reference = Reference::from_staged(&staged).render(&scene.camera, size.0, size.1, 1);
    let bad = pixels
        .iter()
        .zip(&reference)
        .filter(|(p, r)| {
            (p.triangle == MISS) != !r.is_hit()
                || (r.is_hit() && (p.t - r.t).abs() > 1e-4 * r.t.abs())
        })
        .count();
    assert!(bad <= 1, "{bad} of {} pixels differ", pixels.len());
    let b = stats(&base);
    assert!(
        b.bvh_cache_misses > 100 && b.triangle_cache_misses > 100,
        "{b:?}"
    );
    for (spes, assoc, sht) in [
        (1, 1, 2),
        (1, 1, 4),
        (1, 1, 8),
        (1, 4, 1),
        (1, 4, 4),
        (2, 4, 3),
    ] {
        let run = frame(&scene, &staged, size, spes, 128, assoc, sht).unwrap();
        let what = format!("{spes} SPEs, {assoc}-way, {sht} in flight");
        assert!(
            run.frame_buffer == base.frame_buffer,
            "{what}: another image"
        );
        let s = stats(&run);
        assert_eq!(
            (
                s.packets,
                s.traversal_steps,
                s.triangle_lookups,
                s.triangle_tests
            ),
            (
                b.packets,
                b.traversal_steps,
                b.triangle_lookups,
                b.triangle_tests
            ),
            "{what}"
        );
        assert!(s.bvh_cache_misses <= s.bvh_lookups, "{what}: {s:?}");
        if spes == 1 && sht > 1 {
            assert!(
                channel_stalls(&run) * 2 < channel_stalls(&base),
                "{what}: {} channel stall cycles against {}",
                channel_stalls(&run),
                channel_stalls(&base)
            );
        }
        if assoc == 4 && sht == 1 {
            assert_ne!(s.bvh_cache_misses, b.bvh_cache_misses, "{what}");
            assert_ne!(s.triangle_cache_misses, b.triangle_cache_misses, "{what}");
        }
    }
}

/// The largest configuration (two 1024-line 4-way caches, 8 packet contexts) fits in the
/// local store next to the kernel and renders a one-triangle scene right; a BVH whose
/// leaves hold more triangles than a context can stage is refused before any work.
#[test]
fn largest_configuration_fits_and_oversized_leaves_are_refused() {
    use glam::{Vec2, Vec3};
    use spu_loader::scene::Triangle;
    let mut one = Scene::from_parts(
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
    one.camera = Camera::parse("0,0,3,0,0,0,0,1,0,60").unwrap();
    let staged_one = staged(&one);
    let run = frame(&one, &staged_one, (32, 32), 1, 1024, 4, 8).unwrap();
    let pixels = decode_frame_buffer(&run.frame_buffer, 32, 32);
    let reference = Reference::from_staged(&staged_one).render(&one.camera, 32, 32, 1);
    for (p, r) in pixels.iter().zip(&reference) {
        assert_eq!(p.triangle == MISS, !r.is_hit());
    }
    assert!(reference.iter().any(|r| r.is_hit()));

    let room = procedural::room();
    let bvh = Bvh::build(
        &room,
        &BvhConfig {
            max_leaf_size: 64,
            traversal_cost: 100.0,
            threads: 1,
            ..BvhConfig::default()
        },
    );
    let big_leaves = StagedScene::new(&room, &bvh, SCENE_BASE).unwrap();
    assert!(big_leaves.nodes.iter().any(|n| n.triangle_count() > 8));
    let err = frame(&room, &big_leaves, (64, 64), 1, 256, 1, 4).unwrap_err();
    assert!(err.contains("a BVH leaf holds"), "{err}");
}
