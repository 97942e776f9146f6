//! Whole shaded frames (`--shade simple|shadows`): the ray-tracing kernel with the shading
//! module on simulated SPUs, the 32-bit colour frame buffer against the host reference's
//! shading, hit for hit and colour for colour (within `shading::COLOUR_TOLERANCE`; with
//! shadows, a pixel whose shadow ray grazes an occluder's edge may take either outcome's
//! colour, `Reference::shade_alternatives`, and is counted apart).

use spu_isa::timing::TimingConfig;
use spu_loader::frame::{FrameLayout, SCENE_BASE};
use spu_loader::kernel_abi::{
    decode_colour_buffer, decode_frame_buffer, ShadingBlock, MISS, SHADE_SHADOWS, SHADE_SIMPLE,
};
use spu_loader::reference::Reference;
use spu_loader::runtime::{render_frame, FrameRun};
use spu_loader::shading::{self, Light};
use spu_loader::{procedural, Bvh, BvhConfig, Scene, StagedScene};

struct Shaded {
    run: FrameRun,
    colours: Vec<u32>,
    /// Pixels whose hit triangle differs from the reference's, and whose colour differs by
    /// more than the tolerance.
    triangle_mismatches: usize,
    colour_mismatches: usize,
    /// Pixels beyond the tolerance that take the colour of a grazing shadow ray's other
    /// outcome.
    shadow_edges: usize,
}

fn shaded_frame(
    scene: &Scene,
    size: u32,
    spes: usize,
    mode: u32,
    lights: &[Light],
    shadow_early: bool,
    (assoc, sht): (u32, u32),
) -> Shaded {
    let bvh = Bvh::build(
        scene,
        &BvhConfig {
            threads: 1,
            ..BvhConfig::default()
        },
    );
    let staged = StagedScene::new(scene, &bvh, SCENE_BASE).unwrap();
    let basis = scene.camera.basis(size, size);
    let block = ShadingBlock {
        mode,
        shadow_early,
        vertex_cache_log2: 6,
        material_cache_log2: 6,
        lights: lights.to_vec(),
        ..Default::default()
    };
    let layout = FrameLayout::new(&staged, &basis, size, size, spes, 256, 256)
        .unwrap()
        .with_kernel_options(assoc, sht)
        .unwrap()
        .with_shading(&staged, block)
        .unwrap();
    let run = render_frame(
        &staged,
        &layout,
        spes,
        2,
        &TimingConfig::default(),
        false,
        50_000_000_000,
        &mut |_, _| {},
    )
    .unwrap();
    let colours = decode_colour_buffer(run.colour_buffer.as_ref().unwrap(), size, size);
    let pixels = decode_frame_buffer(&run.frame_buffer, size, size);
    let reference = Reference::from_staged(&staged);
    let hits = reference.render(&scene.camera, size, size, 2);
    let expected = reference.shade_image(
        &hits,
        &scene.camera,
        size,
        size,
        lights,
        mode == SHADE_SHADOWS,
        2,
    );
    let mut triangle_mismatches = 0;
    let mut colour_mismatches = 0;
    let mut shadow_edges = 0;
    for (i, ((p, hit), (&c, &e))) in pixels
        .iter()
        .zip(&hits)
        .zip(colours.iter().zip(&expected))
        .enumerate()
    {
        let kernel = if p.triangle == MISS {
            MISS
        } else {
            staged.triangles[p.triangle as usize].original_index
        };
        triangle_mismatches += (kernel != hit.triangle) as usize;
        if shading::channel_difference(c, e) > shading::COLOUR_TOLERANCE {
            let basis = scene.camera.basis(size, size);
            let dir = basis.direction(i as u32 % size, i as u32 / size);
            if mode == SHADE_SHADOWS
                && reference
                    .shade_alternatives(hit, basis.origin, dir, lights)
                    .iter()
                    .any(|&a| shading::channel_difference(c, a) <= shading::COLOUR_TOLERANCE)
            {
                shadow_edges += 1;
                continue;
            }
            // the kernel's triangle, hit on an edge it shares with the reference's
            let tie = reference.shade_edge_tie(
                hit,
                p.triangle,
                basis.origin,
                dir,
                lights,
                mode == SHADE_SHADOWS,
            );
            if tie.is_some_and(|t| shading::channel_difference(c, t) <= shading::COLOUR_TOLERANCE) {
                continue;
            }
            if colour_mismatches < 5 {
                eprintln!("pixel {}: kernel {c:08x}, reference {e:08x}", i);
            }
            colour_mismatches += 1;
        }
    }
    Shaded {
        run,
        colours,
        triangle_mismatches,
        colour_mismatches,
        shadow_edges,
    }
}

#[test]
fn simple_shading_of_the_room_matches_the_reference() {
    let scene = procedural::room();
    let lights = shading::default_lights(&scene);
    let shaded = shaded_frame(&scene, 128, 2, SHADE_SIMPLE, &lights, false, (1, 1));
    assert_eq!(shaded.triangle_mismatches, 0);
    assert_eq!(shaded.colour_mismatches, 0);
    let distinct: std::collections::HashSet<u32> = shaded.colours.iter().copied().collect();
    assert!(distinct.len() > 500, "{} colours", distinct.len());
    // Every packet was shaded once, on one SPU or the other.
    let packets: u64 = shaded.run.shade_counters.iter().map(|c| c.packets.0).sum();
    assert_eq!(packets, 16 * 16);
    let passes: u64 = shaded.run.shade_counters.iter().map(|c| c.passes.0).sum();
    assert!(passes > packets && passes < 3 * packets, "{passes} passes");
    // Table 4 and 6: the colour frame buffer is 4 bytes a pixel, the scene data read is
    // what the caches missed; the shading section is profiled.
    let stats = spu_loader::stats::FrameStats::new(
        &shaded.run,
        &spu_loader::stats::FrameSetup {
            scene: "room",
            width: 128,
            height: 128,
            clock_ghz: 2.4,
        },
        None,
    );
    let table4 = stats.table4.as_ref().unwrap();
    assert!(
        (50.0..100.0).contains(&table4.same_triangle_pct),
        "{table4:?}"
    );
    assert!(table4.vertex_cache_hit_pct > 50.0, "{table4:?}");
    assert!(table4.material_cache_hit_pct > 90.0, "{table4:?}");
    let table6 = stats.table6.as_ref().unwrap();
    assert_eq!(table6.frame_buffer_written_kb, 64.0);
    // the result blocks carry hit and t only (512 of their 1024 bytes) in a shaded frame
    assert_eq!(table6.result_blocks_written_kb, 128.0);
    assert!(table6.bvh_nodes_kb > 0.0 && table6.triangle_records_kb > 0.0);
    // every material record read is one 32-byte miss
    let material_misses: u64 = shaded
        .run
        .shade_counters
        .iter()
        .map(|c| c.material_misses.0)
        .sum();
    assert!((table6.shader_data_kb - material_misses as f64 * 32.0 / 1024.0).abs() < 0.006);
    let vertex_misses: u64 = shaded
        .run
        .shade_counters
        .iter()
        .map(|c| c.vertex_misses.0)
        .sum();
    assert!((table6.vertex_data_kb - vertex_misses as f64 * 64.0 / 1024.0).abs() < 0.006);
    assert!(stats.shading.as_ref().unwrap().instructions > 0);
    assert!(stats.fps > 0.0);
}

/// With four packets in flight (software hyperthreading) and 4-way caches, packets finish
/// out of order and the shading module reads each from its own context: still exact.
#[test]
fn simple_shading_with_hyperthreading_and_4_way_caches() {
    let scene = procedural::room();
    let lights = room_lights();
    let shaded = shaded_frame(&scene, 64, 1, SHADE_SIMPLE, &lights, false, (4, 4));
    assert_eq!(shaded.triangle_mismatches, 0);
    assert_eq!(shaded.colour_mismatches, 0);
    assert_eq!(shaded.run.shade_counters[0].packets.0, 64);
}

/// Shadow packets (one per light and primary packet, from the light) traced by the kernel's
/// traversal as occlusion queries: the room's shadows match the reference, with early
/// termination on and off alike, and only the lit hits cast shadow rays.
#[test]
fn shadows_of_the_room_match_the_reference_with_and_without_early_termination() {
    let scene = procedural::room();
    let lights = room_lights();
    let simple = shaded_frame(&scene, 64, 1, SHADE_SIMPLE, &lights, false, (1, 1));
    assert_eq!(simple.run.shadow_rays, 0);
    let mut colours = Vec::new();
    for early in [false, true] {
        let shaded = shaded_frame(&scene, 64, 1, SHADE_SHADOWS, &lights, early, (1, 1));
        assert_eq!(shaded.triangle_mismatches, 0, "early {early}");
        assert_eq!(shaded.colour_mismatches, 0, "early {early}");
        assert!(
            shaded.shadow_edges <= 8,
            "{} edge pixels",
            shaded.shadow_edges
        );
        // shadows only darken, and some pixels are in shadow
        let darker = shaded
            .colours
            .iter()
            .zip(&simple.colours)
            .filter(|(s, p)| s != p)
            .count();
        assert!(darker > 50, "{darker} pixels in shadow");
        for (s, p) in shaded.colours.iter().zip(&simple.colours) {
            let (s, p) = (s.to_be_bytes(), p.to_be_bytes());
            assert!((0..3).all(|c| s[c] <= p[c]), "{s:?} brighter than {p:?}");
        }
        // a shadow ray per lit hit and light: at most two per pixel, most pixels lit
        let rays = shaded.run.shadow_rays;
        assert!(
            rays > 64 * 64 / 2 && rays <= 2 * 64 * 64,
            "{rays} shadow rays"
        );
        colours.push(shaded.colours);
    }
    assert_eq!(colours[0], colours[1], "early termination changes no pixel");
}

/// Shadow packets with four primary packets in flight and 4-way caches: the shadow
/// packets run in a context of their own with blocking misses, the suspended primary
/// packets resume untouched.
#[test]
fn shadows_with_hyperthreading_and_4_way_caches() {
    let scene = procedural::room();
    let lights = shading::default_lights(&scene);
    for early in [false, true] {
        let shaded = shaded_frame(&scene, 64, 2, SHADE_SHADOWS, &lights, early, (4, 4));
        assert_eq!(shaded.triangle_mismatches, 0);
        assert_eq!(shaded.colour_mismatches, 0);
        let packets: u64 = shaded.run.shade_counters.iter().map(|c| c.packets.0).sum();
        assert_eq!(packets, 64);
        assert!(shaded.run.shadow_rays > 0);
    }
}

/// Two lights in the room, one white and one dim blue, so that passes add irradiance.
fn room_lights() -> [Light; 2] {
    [
        Light::white(glam::Vec3::new(-0.6, 2.7, 0.4)),
        Light {
            position: glam::Vec3::new(2.5, 1.2, 2.0),
            colour: glam::Vec3::new(0.3, 0.3, 0.6),
        },
    ]
}
