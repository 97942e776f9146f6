//! The shading module (`kernels/modules/shade.s`) alone on the simulator: a small driver
//! gives it packets traced by the host reference (hit records, distances, directions), and
//! its colour blocks are checked against the reference shading, its i-set, pass and cache
//! counters against a host model of the same i-sets and direct-mapped caches, and the
//! module against the register contract in its header.

use std::collections::HashMap;

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_loader::frame::{FrameLayout, SCENE_BASE};
use spu_loader::kernel_abi::{
    Counter, ShadeCounters, ShadingBlock, SHADE_SIMPLE, SHADE_STATS_OFFSET,
};
use spu_loader::reference::{Hit, Reference};
use spu_loader::shading::{self, Light};
use spu_loader::{procedural, Bvh, BvhConfig, Scene, StagedScene};
use spu_tests::{check_register_contract, ModuleHarness, RegisterContract};

/// The driver: fetches the parameter block and stops; the host then calls the module with
/// the packet in the ray arrays (laid out as in a packet context) and its number, which
/// returns to `back`: there the driver waits for the colour block and stops. The frame's
/// registers the module reads (ZERO, EATRIS, the triangle cache's TTAGS, TDATA, TMASK) are
/// set by the host; the shading area is at `area`. The host's 16-line triangle cache holds
/// records 0 to 15, so the module finds some records there and fetches the others.
const DRIVER: &str = r#"
        .include "layout.inc"
        .set ZERO, 2
        .set EATRIS, 13
        .set TTAGS, 20
        .set TDATA, 21
        .set TMASK, 22
        .data
        .align 7
params: .space 128
ray_dx: .space 256
ray_dy: .space 256
ray_dz: .space 256
ray_rx: .space 768
ray_t:  .space 256
ray_id: .space 256
        .align 7
tri_tags: .space 16 * 16
tri_lines: .space 16 * 64
        .align 7
area:
        .text
        .global _start
_start: ila     $66, params
        il      $67, 128
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $4
        wrch    $MFC_Size, $67
        wrch    $MFC_TagID, ZERO
        il      $67, 0x40
        wrch    $MFC_Cmd, $67
        il      $67, 1
        wrch    $MFC_WrTagMask, $67
        il      $67, 2
        wrch    $MFC_WrTagUpdate, $67
        rdch    $67, $MFC_RdTagStat
        stop    0x2001
back:   il      $67, 0xc0
        wrch    $MFC_WrTagMask, $67
        il      $67, 2
        wrch    $MFC_WrTagUpdate, $67
        rdch    $67, $MFC_RdTagStat
        stop    0x2000
# back from a miss routine once its fetch (tag 5) is in, through a register it clobbers
        .irp    R, 84, 85
back\R:  il      $\R, 0x20
        wrch    $MFC_WrTagMask, $\R
        il      $\R, 2
        wrch    $MFC_WrTagUpdate, $\R
        rdch    $\R, $MFC_RdTagStat
        stop    0x2000
        .endr
shadow_rays:                                  # shadows are another module's (shadow_module.rs)
        bi      $127
        .include "modules/shade.s"
"#;

struct Harness {
    h: ModuleHarness,
    layout: FrameLayout,
}

fn harness(staged: &StagedScene, scene: &Scene, block: ShadingBlock) -> Harness {
    harness_sized(staged, scene, block, 64)
}

/// [`harness`] for a `size` x `size` frame.
fn harness_sized(staged: &StagedScene, scene: &Scene, block: ShadingBlock, size: u32) -> Harness {
    harness_of(DRIVER, staged, scene, block, size)
}

/// [`harness_sized`] with the driver source `driver`.
fn harness_of(
    driver: &str,
    staged: &StagedScene,
    scene: &Scene,
    block: ShadingBlock,
    size: u32,
) -> Harness {
    let basis = scene.camera.basis(size, size);
    let layout = FrameLayout::new(staged, &basis, size, size, 1, 256, 256).unwrap();
    let mut h = ModuleHarness::new(driver, "driver.s", MainMemory::new(Vec::new()));
    let mut layout = layout.with_shading(staged, block).unwrap();
    layout.set_shading_area(h.sym("area")).unwrap();
    h.memory = MainMemory::new(layout.memory_image(staged));
    h.spu.set_reg(13, [staged.header.triangle_addr, 0, 0, 0]);
    h.spu.set_reg(20, [h.sym("tri_tags"), 0, 0, 0]);
    h.spu.set_reg(21, [h.sym("tri_lines"), 0, 0, 0]);
    h.spu.set_reg(22, [15, 0, 0, 0]);
    for r in 0..16u32 {
        h.write_words(h.sym("tri_tags") + 16 * r, [r, 0, 0, 0]);
        let mut line = [0u8; 64];
        staged.triangles[r as usize].write_be(&mut line);
        h.spu.write_ls(h.sym("tri_lines") + 64 * r, &line);
    }
    Harness { h, layout }
}

/// The host's view of one packet: hit, origin and direction per ray.
struct Packet {
    hits: Vec<Hit>,
    dirs: Vec<glam::Vec3>,
}

fn trace_packet(reference: &Reference, scene: &Scene, x0: u32, y0: u32) -> Packet {
    trace_packet_sized(reference, scene, x0, y0, 64)
}

/// [`trace_packet`] in a `size` x `size` frame.
fn trace_packet_sized(reference: &Reference, scene: &Scene, x0: u32, y0: u32, size: u32) -> Packet {
    let basis = scene.camera.basis(size, size);
    let dirs: Vec<glam::Vec3> = (0..64)
        .map(|i| basis.direction(x0 + i % 8, y0 + i / 8))
        .collect();
    let hits = dirs
        .iter()
        .map(|&d| reference.trace(basis.origin, d))
        .collect();
    Packet { hits, dirs }
}

impl Harness {
    /// Shades `packet` as packet number `index` of tile 0 and returns its 64 colours.
    fn shade(&mut self, packet: &Packet, index: u32) -> Vec<u32> {
        self.shade_poisoned(packet, index, &|_| {})
    }

    /// [`Harness::shade`], `poison` called on the SPU once the module's inputs are set.
    fn shade_poisoned(
        &mut self,
        packet: &Packet,
        index: u32,
        poison: &dyn Fn(&mut Spu),
    ) -> Vec<u32> {
        let h = &mut self.h;
        for (name, axis) in [("ray_dx", 0), ("ray_dy", 1), ("ray_dz", 2)] {
            let at = h.sym(name);
            h.write_words(at, packet.dirs.iter().map(|d| d[axis].to_bits()));
        }
        h.write_words(h.sym("ray_t"), packet.hits.iter().map(|h| h.t.to_bits()));
        h.write_words(h.sym("ray_id"), packet.hits.iter().map(|h| h.record));
        h.spu.set_reg(4, [self.layout.param_addr, 0, 0, 0]);
        assert_eq!(h.run_at(h.entry, 100_000_000), StopReason::Stop(0x2001));
        // the module's inputs: $0, $68, $69 and the frame's registers set above
        h.spu.set_reg(0, [h.sym("back"), 0, 0, 0]);
        h.spu.set_reg(68, [h.sym("ray_dx"), 0, 0, 0]);
        h.spu.set_reg(69, [index, 0, 0, 0]);
        poison(&mut h.spu);
        assert_eq!(
            h.run_at(h.sym("shade_packet"), 100_000_000),
            StopReason::Stop(0x2000)
        );
        let colour = self.layout.shading.as_ref().unwrap().colour_addr + index * 256;
        (0..64).map(|i| h.memory.read_u32(colour + 4 * i)).collect()
    }

    /// The module's counters, as the host reads them; vertex lookups (which the module
    /// leaves to the host) three per triangle record looked up.
    fn counters(&self) -> ShadeCounters {
        let stats = (self.h.sym("area") as usize + SHADE_STATS_OFFSET) as u32;
        let mut counters = ShadeCounters::from_be_bytes(&self.h.bytes(stats, 160));
        assert_eq!(counters.vertex_lookups, Counter(0));
        counters.vertex_lookups = Counter(3 * counters.triangle_lookups.0);
        counters
    }
}

/// The same i-sets, passes and direct-mapped caches, counted on the host.
struct Model {
    vertex_tags: Vec<u32>,
    material_tags: Vec<u32>,
    counters: ShadeCounters,
}

impl Model {
    fn new(vertex_entries: usize, material_entries: usize) -> Model {
        Model {
            vertex_tags: vec![u32::MAX; vertex_entries],
            material_tags: vec![u32::MAX; material_entries],
            counters: ShadeCounters::default(),
        }
    }

    fn packet(&mut self, reference: &Reference, hits: &[Hit]) {
        let mut order = Vec::new();
        for group in hits.chunks(4) {
            if group.iter().all(|h| !h.is_hit()) {
                continue;
            }
            self.counters.groups.0 += 1;
            let same = group.iter().all(|h| h.record == group[0].record);
            self.counters.same.0 += same as u64;
            let lanes = if same { &group[..1] } else { group };
            for hit in lanes.iter().filter(|h| h.is_hit()) {
                self.counters.triangle_lookups.0 += 1;
                self.counters.vertex_lookups.0 += 3;
                self.counters.triangle_misses.0 += (hit.record >= 16) as u64;
                for v in reference.triangles[hit.record as usize].vertices {
                    let entry = v as usize % self.vertex_tags.len();
                    if self.vertex_tags[entry] != v {
                        self.vertex_tags[entry] = v;
                        self.counters.vertex_misses.0 += 1;
                    }
                }
            }
            for hit in group.iter().filter(|h| h.is_hit()) {
                let material = reference.triangles[hit.record as usize].material;
                if !order.contains(&material) {
                    order.push(material);
                }
            }
        }
        for material in order {
            self.counters.passes.0 += 1;
            self.counters.material_lookups.0 += 1;
            let entry = material as usize % self.material_tags.len();
            if self.material_tags[entry] != material {
                self.material_tags[entry] = material;
                self.counters.material_misses.0 += 1;
            }
        }
        self.counters.packets.0 += 1;
    }
}

fn room_setup() -> (Scene, StagedScene, Reference) {
    let scene = procedural::room();
    let bvh = Bvh::build(&scene, &BvhConfig::default());
    let staged = StagedScene::new(&scene, &bvh, SCENE_BASE).unwrap();
    let reference = Reference::from_staged(&staged);
    (scene, staged, reference)
}

fn block(lights: Vec<Light>, vertex_log2: u32, material_log2: u32) -> ShadingBlock {
    ShadingBlock {
        mode: SHADE_SIMPLE,
        vertex_cache_log2: vertex_log2,
        material_cache_log2: material_log2,
        lights,
        ..Default::default()
    }
}

/// Every packet of a 64x64 room frame, shaded by the module, against the reference; the
/// counters against the model (small caches, so that they miss and evict).
#[test]
fn shade_module_matches_the_reference_on_the_room() {
    let (scene, staged, reference) = room_setup();
    let lights = vec![
        Light::white(glam::Vec3::new(-0.6, 2.7, 0.4)),
        Light {
            position: glam::Vec3::new(2.0, 1.0, 2.0),
            colour: glam::Vec3::new(0.6, 0.3, 0.1),
        },
    ];
    let mut h = harness(&staged, &scene, block(lights.clone(), 4, 4));
    let mut model = Model::new(16, 16);
    let basis = scene.camera.basis(64, 64);
    let (mut pixels, mut off, mut worst) = (0, 0, 0);
    let mut distinct = std::collections::HashSet::new();
    for index in 0..64u32 {
        let (x0, y0) = ((index % 8) * 8, (index / 8) * 8);
        let packet = trace_packet(&reference, &scene, x0, y0);
        let colours = h.shade(&packet, index);
        model.packet(&reference, &packet.hits);
        for (i, (&colour, hit)) in colours.iter().zip(&packet.hits).enumerate() {
            let expected = reference.shade(hit, basis.origin, packet.dirs[i], &lights, false);
            let difference = shading::channel_difference(colour, expected);
            worst = worst.max(difference);
            off += (difference > shading::COLOUR_TOLERANCE) as usize;
            pixels += 1;
            distinct.insert(colour);
        }
    }
    assert_eq!(pixels, 4096);
    assert_eq!(off, 0, "worst channel difference {worst}");
    assert!(distinct.len() > 100, "{} colours", distinct.len());
    let counters = h.counters();
    eprintln!(
        "worst {worst}, {} colours, counters {counters:?}",
        distinct.len()
    );
    assert_eq!(counters, model.counters);
    let c = counters;
    assert!(
        c.same.0 > c.groups.0 / 2,
        "same-triangle packets {counters:?}"
    );
    assert!(c.passes.0 > c.packets.0, "some packets need several passes");
    assert!(
        c.vertex_misses.0 > 0 && c.material_misses.0 > 0,
        "the small caches miss"
    );
    assert!(
        c.triangle_misses.0 > 0 && c.triangle_misses.0 < c.triangle_lookups.0,
        "the triangle cache hits some"
    );
}

/// A packet that hits nothing is black, takes no pass and touches no cache.
#[test]
fn shade_module_leaves_misses_black() {
    let (scene, staged, reference) = room_setup();
    let mut h = harness(&staged, &scene, block(vec![], 6, 6));
    let mut packet = trace_packet(&reference, &scene, 0, 0);
    packet.hits = vec![Hit::NONE; 64];
    let colours = h.shade(&packet, 3);
    assert!(colours.iter().all(|&c| c == 0x0000_00ff));
    assert_eq!(
        h.counters(),
        ShadeCounters {
            packets: Counter(1),
            ..Default::default()
        }
    );
    // Without lights, a hit is the ambient term of its material.
    let packet = trace_packet(&reference, &scene, 24, 24);
    let colours = h.shade(&packet, 4);
    for (colour, hit) in colours.iter().zip(&packet.hits) {
        let kd =
            reference.materials[reference.triangles[hit.record as usize].material as usize].diffuse;
        let expected = shading::pixel_colour(kd, glam::Vec3::ZERO);
        assert!(shading::channel_difference(*colour, expected) <= 1);
    }
}

/// The module keeps its register contract (`modules/shade.s`'s header): run on three
/// packets of the room (the first call's set-up, same-triangle and mixed groups, cache
/// misses) with everything outside its inputs poisoned two ways, it gives the same
/// colours and counters and keeps $1..$65.
#[test]
fn shade_module_keeps_its_register_contract() {
    let (scene, staged, reference) = room_setup();
    let lights = shading::default_lights(&scene);
    let contract = RegisterContract::of_module("modules/shade.s", None);
    assert!((1..66).all(|r| contract.keeps(r)));
    let packets: Vec<(u32, Packet)> = [(0, 0), (27, 24), (63, 56)]
        .into_iter()
        .map(|(index, xy)| (index, trace_packet(&reference, &scene, xy, xy)))
        .collect();
    let (_, (colours, counters)) = check_register_contract(&contract, |poison| {
        let mut h = harness(&staged, &scene, block(lights.clone(), 4, 4));
        let colours: Vec<Vec<u32>> = packets
            .iter()
            .map(|(index, packet)| h.shade_poisoned(packet, *index, poison))
            .collect();
        let counters = h.counters();
        (h.h.spu, (colours, counters))
    });
    assert_eq!(counters.packets, Counter(3));
    assert!(counters.groups.0 > 0 && colours.iter().flatten().any(|&c| c != 0xff));
}

/// The caches' miss routines alone (`modules/shade_cache.s`' register contracts), with
/// everything outside their inputs poisoned two ways: sh_tri_miss queues a triangle
/// record into its slot and counts it; sh_vertex_miss queues a vertex record into the
/// next staging slot, marks its tag in flight, leaves the copy for SH_LAND and counts it.
#[test]
fn shade_cache_misses_keep_their_register_contracts() {
    let (scene, staged, _) = room_setup();
    let new = || harness(&staged, &scene, block(vec![], 6, 6));
    let h = new();
    let value = |name: &str| h.h.value(name);
    let (stage, stats, vtags, vdata, vstage, defer, dcount, nrm) = (
        value("SH_STAGE"),
        value("SH_STATS"),
        value("SH_VTAGS"),
        value("SH_VDATA"),
        value("SH_VSTAGE"),
        value("SH_DEFER"),
        value("SH_DCOUNT"),
        value("SH_NRM"),
    );
    let ea_vertices = h.layout.shading.as_ref().unwrap().block.ea_vertices;
    let area = h.h.sym("area");

    let contract = RegisterContract::of_module("modules/shade_cache.s", Some("sh_tri_miss"));
    let (_, (record, count)) = check_register_contract(&contract, |poison| {
        let mut h = new().h;
        for (r, v) in [
            (66, area),
            (80, 20),
            (82, area + stage + 64),
            (88, h.sym("back84")),
        ] {
            h.spu.set_reg(r, [v, 0, 0, 0]);
        }
        poison(&mut h.spu);
        assert_eq!(
            h.run_at(h.sym("sh_tri_miss"), 1_000_000),
            StopReason::Stop(0x2000)
        );
        let count = h.word(area + stats + h.value("SHS_TMISS"));
        let record = h.bytes(area + stage + 64, 64);
        (h.spu, (record, count))
    });
    let mut expected = [0u8; 64];
    staged.triangles[20].write_be(&mut expected);
    assert_eq!((record, count), (expected.to_vec(), 1));

    let contract = RegisterContract::of_module("modules/shade_cache.s", Some("sh_vertex_miss"));
    let vertex = 37u32;
    let entry = vertex % 64; // the vertex cache has 2^6 lines
    let (tag, line, lane) = (
        area + vtags + 16 * entry,
        area + vdata + 64 * entry,
        nrm + 64 + 16,
    );
    let (spu, outcome) = check_register_contract(&contract, |poison| {
        let mut h = new().h;
        for (r, v) in [
            (66, area),
            (81, vertex),
            (83, tag),
            (84, line),
            (88, h.sym("back85")),
            (89, lane),
            (100, ea_vertices),
        ] {
            h.spu.set_reg(r, [v, 0, 0, 0]);
        }
        poison(&mut h.spu);
        assert_eq!(
            h.run_at(h.sym("sh_vertex_miss"), 1_000_000),
            StopReason::Stop(0x2000)
        );
        let outcome = (
            h.word(area + dcount),
            h.bytes(area + defer, 32),
            h.word(tag),
            h.word(area + stats + h.value("SHS_VMISS")),
            h.bytes(area + vstage, 64),
        );
        (h.spu, outcome)
    });
    let (bytes, copy, tag_word, misses, slot) = outcome;
    assert_eq!(spu.reg(82)[0], area + vstage, "the first staging slot");
    assert_eq!(
        spu.reg(94)[0],
        vertex | 0x8000_0000,
        "the vertex, in flight"
    );
    assert_eq!((bytes, tag_word, misses), (32, vertex | 0x8000_0000, 1));
    let word = |at: usize| u32::from_be_bytes(copy[at..at + 4].try_into().unwrap());
    assert_eq!(
        [word(0), word(4), word(8), word(12), word(16)],
        [area + vstage, area + lane, tag, vertex, line],
        "the copy: source, lane, tag, vertex; line"
    );
    let mut record = [0u8; 64];
    staged.vertices[vertex as usize].write_be(&mut record);
    assert_eq!(slot, record.to_vec(), "the vertex record, fetched");
}

/// A ray through the edge two triangles share: pixel (1021, 164) of the 1024x1024 room
/// meets the picture frame's corner, where its front (lit) and its side (facing away from
/// the light) are hit at one distance. The reference takes the side; the SPU's intersection
/// test took the front, and the module shades that hit as the front's, so the frame's
/// colour check must accept the other triangle's colour there (`Reference::shade_edge_tie`)
/// and nowhere else.
#[test]
fn an_edge_shared_by_two_triangles_takes_either_triangles_colour() {
    let (scene, staged, reference) = room_setup();
    let lights = shading::default_lights(&scene);
    let basis = scene.camera.basis(1024, 1024);
    let (o, d) = (basis.origin, basis.direction(1021, 164));
    let hit = reference.trace(o, d);
    let own = reference.shade(&hit, o, d, &lights, false);
    let ties: Vec<(u32, u32)> = (0..reference.triangles.len() as u32)
        .filter_map(|r| {
            reference
                .shade_edge_tie(&hit, r, o, d, &lights, false)
                .map(|c| (r, c))
        })
        .collect();
    assert_eq!(
        ties.len(),
        1,
        "one other triangle shares the edge: {ties:?}"
    );
    let (record, tie_colour) = ties[0];
    let side = &reference.triangles[hit.record as usize];
    let front = &reference.triangles[record as usize];
    assert_eq!((side.original_index, front.original_index), (780, 788));
    assert_eq!((own, tie_colour), (0x0409_13ff, 0x2557_baff));
    assert!(shading::channel_difference(own, tie_colour) > shading::COLOUR_TOLERANCE);
    // Not a tie: the reference's own triangle, and a miss.
    assert_eq!(
        reference.shade_edge_tie(&hit, hit.record, o, d, &lights, false),
        None
    );
    assert_eq!(
        reference.shade_edge_tie(&Hit::NONE, record, o, d, &lights, false),
        None
    );

    // The module, given the SPU's hit (the front, at its own t), shades the front's colour.
    let mut h = harness_sized(&staged, &scene, block(lights.clone(), 8, 6), 1024);
    let mut packet = trace_packet_sized(&reference, &scene, 1016, 160, 1024);
    let lane = 4 * 8 + 5;
    assert_eq!(packet.hits[lane], hit);
    packet.hits[lane] = Hit {
        triangle: front.original_index,
        t: 4.092_560_3, // the SPU's distance
        record,
    };
    let colours = h.shade(&packet, 0);
    assert_eq!(colours[lane], tie_colour);
    for (i, (&colour, hit)) in colours.iter().zip(&packet.hits).enumerate() {
        let expected = reference.shade(hit, o, packet.dirs[i], &lights, false);
        assert!(shading::channel_difference(colour, expected) <= shading::COLOUR_TOLERANCE);
    }
}

/// Vertex misses are fetched without waiting and land once a group's lanes are looked up:
/// a packet whose 64 rays hit 64 different records misses many vertices per group of 4
/// rays, and with a 16-line vertex cache some group's vertices share a line (the second
/// miss lands the first). Colours against the reference and counters against the model
/// (the cache's misses as one lookup after the other) stay exact.
#[test]
fn vertex_misses_of_a_group_land_together() {
    let (scene, staged, reference) = room_setup();
    let lights = shading::default_lights(&scene);
    let basis = scene.camera.basis(64, 64);
    for vertex_log2 in [8, 4] {
        let mut h = harness(&staged, &scene, block(lights.clone(), vertex_log2, 6));
        let mut model = Model::new(1 << vertex_log2, 64);
        let mut packet = trace_packet(&reference, &scene, 24, 24);
        for (i, hit) in packet.hits.iter_mut().enumerate() {
            let record = (i as u32 * 5) % 64;
            *hit = Hit {
                triangle: reference.triangles[record as usize].original_index,
                t: hit.t,
                record,
            };
        }
        let shared_line = packet.hits.chunks(4).any(|group| {
            let mut lines = HashMap::new();
            group.iter().any(|hit| {
                reference.triangles[hit.record as usize]
                    .vertices
                    .iter()
                    .any(|&v| *lines.entry(v % (1 << vertex_log2)).or_insert(v) != v)
            })
        });
        assert_eq!(shared_line, vertex_log2 == 4);
        for index in 0..2 {
            let colours = h.shade(&packet, index);
            model.packet(&reference, &packet.hits);
            for (i, (&colour, hit)) in colours.iter().zip(&packet.hits).enumerate() {
                let expected = reference.shade(hit, basis.origin, packet.dirs[i], &lights, false);
                let difference = shading::channel_difference(colour, expected);
                assert!(
                    difference <= shading::COLOUR_TOLERANCE,
                    "ray {i}: {colour:08x} {expected:08x}"
                );
            }
        }
        let counters = h.counters();
        assert_eq!(counters, model.counters, "vertex cache of 2^{vertex_log2}");
        assert!(counters.vertex_misses.0 > 64, "{counters:?}");
    }
}

/// The gather variant of the module (`EXT_GATHER`, `modules/shade_gather.s`: the groups
/// the fast path leaves batched per packet, records and normals by DMA lists, lookups by
/// `lgw`/`lgwx`) on an SPU with the gather load: every packet of a 64x64 room frame, with
/// small caches that miss and a 16-line triangle cache that holds records 0 to 15 only,
/// gives the baseline module's colours and the same i-set (hit points and normals, bit for
/// bit, in the shading area); groups, passes and material lookups are counted alike, and
/// the batch ran (only it counts triangle records and vertices fetched).
#[test]
fn the_gather_module_builds_the_baseline_i_set() {
    let (scene, staged, reference) = room_setup();
    let lights = vec![Light::white(glam::Vec3::new(-0.6, 2.7, 0.4))];
    let mut base = harness(&staged, &scene, block(lights.clone(), 4, 4));
    let gather_driver = format!("        .set EXT_GATHER, 1\n{DRIVER}");
    let mut gather = harness_of(&gather_driver, &staged, &scene, block(lights, 4, 4), 64);
    gather
        .h
        .spu
        .set_extensions(spu_isa::Extensions::parse("gather").unwrap());
    let i_set = |h: &Harness| {
        let area = h.h.sym("area");
        let at = |name: &str| area + h.h.value(name);
        h.h.bytes(at("SH_NX"), at("SH_MAT") - at("SH_NX"))
    };
    let mut differing = 0;
    for index in 0..64u32 {
        let (x0, y0) = ((index % 8) * 8, (index / 8) * 8);
        let packet = trace_packet(&reference, &scene, x0, y0);
        let colours = base.shade(&packet, index);
        assert_eq!(gather.shade(&packet, index), colours, "packet {index}");
        differing += (i_set(&gather) != i_set(&base)) as usize;
    }
    assert_eq!(differing, 0, "packets whose i-set differs");
    let (b, g) = (base.counters(), gather.counters());
    assert_eq!(
        (
            g.groups,
            g.same,
            g.passes,
            g.packets,
            g.material_lookups,
            g.triangle_lookups
        ),
        (
            b.groups,
            b.same,
            b.passes,
            b.packets,
            b.material_lookups,
            b.triangle_lookups
        )
    );
    assert!(
        g.triangle_misses.0 > 0 && g.vertex_misses.0 > 0,
        "the batch fetched records and normals: {g:?}"
    );
}
