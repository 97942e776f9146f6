//! Whole shaded frames (`--shade simple|shadows`): the ray-tracing kernel with the shading
//! module on simulated SPUs, the 32-bit colour frame buffer against the host reference's
//! shading, hit for hit and colour for colour (within `shading::COLOUR_TOLERANCE`; with
//! shadows, a pixel whose shadow ray grazes an occluder's edge may take either outcome's
//! colour, `Reference::shade_alternatives`, and is counted apart).

use spu_isa::jit::CodeCache;
use spu_loader::kernel_abi::{decode_frame_buffer, MISS};
use spu_loader::render::{prepare, render, validate, KernelVariant, Prepared, RenderConfig};
use spu_loader::runtime::FrameRun;
use spu_loader::shading::{self, Light, ShadeMode};

struct Shaded {
    run: FrameRun,
    colours: Vec<u32>,
    /// Pixels whose hit triangle differs from the reference's (even at the same distance),
    /// and whose colour differs by more than the tolerance.
    triangle_mismatches: usize,
    colour_mismatches: usize,
    /// Pixels beyond the tolerance that take the colour of a grazing shadow ray's other
    /// outcome.
    shadow_edges: usize,
    /// The frame's statistics, with its validation.
    stats: spu_loader::stats::FrameStats,
}

fn shaded_frame(
    room: &Prepared,
    size: u32,
    spes: usize,
    mode: ShadeMode,
    lights: &[Light],
    shadow_early: bool,
    (assoc, sht): (u32, u32),
) -> Shaded {
    let mut config = RenderConfig {
        width: size,
        height: size,
        spes,
        threads: 2,
        assoc,
        sht,
        kernel: KernelVariant::Shaded,
        max_cycles: 50_000_000_000,
        ..RenderConfig::new(&room.name)
    };
    config.shading.mode = mode;
    config.shading.lights = lights.to_vec();
    config.shading.shadow_early = shadow_early;
    let frame = render(room, &config, &CodeCache::default()).unwrap();
    let validation = validate(room, &config, &frame).unwrap();
    for message in &validation.messages {
        eprintln!("{message}");
    }
    let pixels = decode_frame_buffer(&frame.run.frame_buffer, size, size);
    let hits = spu_loader::reference::Reference::from_staged(&room.staged).render(
        &room.scene.camera,
        size,
        size,
        2,
    );
    let triangle_mismatches = pixels
        .iter()
        .zip(&hits)
        .filter(|(p, hit)| {
            let kernel = match p.triangle {
                MISS => MISS,
                t => room.staged.triangles[t as usize].original_index,
            };
            kernel != hit.triangle
        })
        .count();
    Shaded {
        stats: frame.stats(&config, Some(&validation)),
        colours: frame.colours,
        run: frame.run,
        triangle_mismatches,
        colour_mismatches: validation.colour_mismatches.unwrap(),
        shadow_edges: validation.shadow_edge_pixels.unwrap_or(0),
    }
}

#[test]
fn simple_shading_of_the_room_matches_the_reference() {
    let room = prepare("room").unwrap();
    let lights = shading::default_lights(&room.scene);
    let shaded = shaded_frame(&room, 128, 2, ShadeMode::Simple, &lights, false, (1, 1));
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
    let stats = &shaded.stats;
    let validation = stats.validation.as_ref().unwrap();
    assert_eq!((validation.pixels, validation.mismatches), (128 * 128, 0));
    assert_eq!(
        (validation.colour_mismatches, validation.shadow_edge_pixels),
        (Some(0), None)
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
    let room = prepare("room").unwrap();
    let lights = room_lights();
    let shaded = shaded_frame(&room, 64, 1, ShadeMode::Simple, &lights, false, (4, 4));
    assert_eq!(shaded.triangle_mismatches, 0);
    assert_eq!(shaded.colour_mismatches, 0);
    assert_eq!(shaded.run.shade_counters[0].packets.0, 64);
}

/// Shadow packets (one per light and primary packet, from the light) traced by the kernel's
/// traversal as occlusion queries: the room's shadows match the reference, with early
/// termination on and off alike, and only the lit hits cast shadow rays.
#[test]
fn shadows_of_the_room_match_the_reference_with_and_without_early_termination() {
    let room = prepare("room").unwrap();
    let lights = room_lights();
    let simple = shaded_frame(&room, 64, 1, ShadeMode::Simple, &lights, false, (1, 1));
    assert_eq!(simple.run.shadow_rays, 0);
    let mut colours = Vec::new();
    for early in [false, true] {
        let shaded = shaded_frame(&room, 64, 1, ShadeMode::Shadows, &lights, early, (1, 1));
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
    let room = prepare("room").unwrap();
    let lights = shading::default_lights(&room.scene);
    for early in [false, true] {
        let shaded = shaded_frame(&room, 64, 2, ShadeMode::Shadows, &lights, early, (4, 4));
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
