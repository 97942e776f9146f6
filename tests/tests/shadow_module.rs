//! The shadow module (`kernels/modules/shadow.s`) alone on the simulator: a driver gives
//! it an i-set (hit points, normals, materials) and lights in the shading area, and stands
//! in for the traversal: its `trav` copies each shadow packet as the traversal receives it
//! (rays, frustum, first ray, miss handlers) for the host to check against the shadow-ray
//! model, then records the occlusions the host chose and ends the packet, through the
//! early-termination hook (`shadow_leaf`) when `--shadow-early` is on. The module's
//! visibility masks and its ray count are checked too, and the module against the register
//! contract in its header (what it reads, keeps and counts on).

use spu_isa::machine::{MainMemory, Spu, StopReason};
use spu_loader::kernel_abi::{
    ShadingBlock, PARAM_EA_SHADING, SHADE_SHADOWS, SHADE_SIMPLE, SHADOW_AREA, SHADOW_RAYS_OFFSET,
};
use spu_loader::shading::{Light, SHADOW_EPSILON};
use spu_tests::{check_register_contract, ModuleHarness, RegisterContract};

/// Bytes the stand-in traversal copies per shadow packet: the rays (dx, dy, dz, rx, ry, rz,
/// t), 16 registers and vars words, the t array after the leaf hook, the corner rays.
const DUMP_BYTES: u32 = 2352;

const DRIVER: &str = r#"
        .include "layout.inc"
        .include "modules/regs.inc"
        .include "modules/data.s"
        .text
        .global _start
_start: brsl    $127, shadow_rays             # (the host calls the module itself)
back:   stop    0x2000
# the shading module's offsets and the one-context handlers' addresses, for the host
        .align 4
offsets: .long SH_BLOCK, SH_PX, SH_PY, SH_PZ, SH_NX, SH_NY, SH_NZ, SH_MAT, SH_VIS
handlers: .long bvh_miss_one, .Lpf_one
        .align 4
calls:  .long 0, 0, 0, 0
markers: .space 8 * 16                      # per packet: 1 the leaf left rays, 2 it ended
occl:   .space 8 * 256                      # per light: the ids trav records
dump:   .space 8 * 2352
# the stand-in traversal
set_first:
        bi      $0
trav:   lqa     $80, calls
        ai      $81, $80, 1
        stqa    $81, calls
        il      $82, 2352
        mpy     $83, $80, $82
        ila     $84, dump
        a       $83, $83, $84                 # this packet's dump
        il      $85, 0
        il      $91, 1792
1:      lqx     $86, RAYS, $85                # dx .. rz, t: 7 arrays
        stqx    $86, $83, $85
        ai      $85, $85, 16
        ceq     $87, $85, $91
        brz     $87, 1b
        ila     $84, 1792
        a       $84, $84, $83
        stqd    ORIG, 0($84)
        stqd    PAX, 16($84)
        stqd    PAY, 32($84)
        stqd    PAZ, 48($84)
        stqd    PBX, 64($84)
        stqd    PBY, 80($84)
        stqd    PBZ, 96($84)
        stqd    OAX, 112($84)
        stqd    OAY, 128($84)
        stqd    OAZ, 144($84)
        stqd    F2, 160($84)
        stqd    FIRST, 176($84)
        stqd    CUR, 192($84)
        stqd    BMISSH, 208($84)
        lqa     $86, vars+V_NCTX1
        stqd    $86, 224($84)
        lqa     $86, vars+V_PFMISS
        stqd    $86, 240($84)
        il      BMISSH, 0                     # (a leaf's ray loop uses the register)
        ila     $84, 2304
        a       $84, $84, $83
        lqd     $86, CTX_CORNERS(RAYS)
        stqd    $86, 0($84)
        lqd     $86, CTX_CORNERS+16(RAYS)
        stqd    $86, 16($84)
        lqd     $86, CTX_CORNERS+32(RAYS)
        stqd    $86, 32($84)
        shli    $86, $80, 8                   # the host's ids for this packet
        ila     $87, occl
        a       $86, $86, $87
        il      $85, 0
        ila     $89, CTX_RAY_ID
        a       $89, $89, RAYS
1:      lqx     $88, $86, $85
        stqx    $88, $89, $85
        ai      $85, $85, 16
        ceqi    $87, $85, 256
        brz     $87, 1b
        lqa     $80, sv_early
        brnz    $80, shadow_leaf
        br      packet_done
.Lleaf_refresh:
        il      $90, 1                        # rays left: the traversal goes on
        br      after_leaf
packet_done:
        lqa     $90, sv_early
        brz     $90, 2f
        il      $90, 2                        # every ray occluded: the packet ends
after_leaf:
        lqa     $80, calls
        ai      $80, $80, -1
        shli    $81, $80, 4
        ila     $82, markers
        stqx    $90, $82, $81
        il      $82, 2352
        mpy     $83, $80, $82
        ila     $84, dump+2048
        a       $83, $83, $84
        ila     $89, CTX_RAY_T
        a       $89, $89, RAYS
        il      $85, 0
1:      lqx     $88, $89, $85
        stqx    $88, $83, $85
        ai      $85, $85, 16
        ceqi    $87, $85, 256
        brz     $87, 1b
        lqa     $90, sv_early
        brz     $90, 2f
        stqa    ZERO, sv_early
        br      packet_done
2:      lqa     $66, sv_trace
        brnz    $66, shadow_done
        stop    0x2001
# the one-context miss handlers the module installs (never reached here)
bvh_miss_one:
bvh_miss_ways:
.Lb_one_fetch:
.Lpf_one:
.Lpf_ways:
.Lpf_one_evict:
        stop    0x2002
        .include "modules/shade.s"
        .include "modules/shadow.s"
"#;

const LIMIT: f32 = 1.0 - SHADOW_EPSILON;

/// The shadow module alone, with its shading area at `area` and the shading module's
/// offsets the host writes the i-set at.
struct Harness {
    h: ModuleHarness,
    area: u32,
    offsets: Vec<u32>,
}

fn harness() -> Harness {
    let mut h = ModuleHarness::new(DRIVER, "driver.s", MainMemory::new(vec![0; 4096]));
    let area = h.sym("cache_area").div_ceil(128) * 128;
    assert!(area as usize + spu_loader::kernel_abi::SHADED_LS_BYTES <= 256 * 1024);
    let at = h.sym("offsets");
    let offsets = (0..9).map(|i| h.word(at + 4 * i)).collect();
    // the shading area's address in the parameter block, as the host puts it
    let params = h.sym("params");
    h.write_words(params + PARAM_EA_SHADING as u32 + 4, [area]);
    Harness { h, area, offsets }
}

/// One lane of the i-set: hit point, normal, material (-1: no hit).
#[derive(Clone, Copy)]
struct Lane {
    point: [f32; 3],
    normal: [f32; 3],
    material: i32,
}

/// The temporaries shade.s still reads after `brsl $127, shadow_rays`.
const SHADE_KEEPS: [usize; 9] = [66, 91, 92, 93, 97, 101, 102, 103, 105];

/// The frame registers the module reads (the rest its register contract poisons).
fn registers(area: u32) -> Vec<[u32; 4]> {
    let splat = |w: u32| [w; 4];
    let pat = |k: u32| splat(0x0001_0203 + 0x0404_0404 * k);
    (0..128u32)
        .map(|r| match r {
            2 => splat(0),
            3 => splat(1f32.to_bits()),
            4 => splat(1e30f32.to_bits()),
            5 => splat((-1e30f32).to_bits()),
            7..=10 => pat(r - 7),
            38 => [0, 0x8000_0000, 0, 0x8000_0000],
            41 => [0x40, 0x130, 0, 0],
            66 => [area, 0, 0, 0],
            _ => [r * 0x0101_0101, r, !r, 0x1234_5678 ^ r],
        })
        .collect()
}

impl Harness {
    fn word(&self, at: u32) -> u32 {
        self.h.word(at)
    }

    fn f(&self, at: u32) -> f32 {
        self.h.f(at)
    }

    fn sym(&self, name: &str) -> u32 {
        self.h.sym(name)
    }

    /// What a run leaves that the host reads: the stand-in traversal's dumps, markers and
    /// calls, the visibility masks, the ray count, the miss handlers in vars, sv_trace.
    fn outcome(&self) -> Vec<u8> {
        let h = &self.h;
        let counter = self.area + (SHADOW_AREA + SHADOW_RAYS_OFFSET) as u32;
        [
            (h.sym("calls"), 16),
            (h.sym("markers"), 8 * 16),
            (h.sym("dump"), 8 * DUMP_BYTES),
            (self.area + self.offsets[8], 8 * 256),
            (counter, 4),
            (h.sym("vars") + 496, 80),
            (h.sym("sv_trace"), 16),
        ]
        .into_iter()
        .flat_map(|(at, len)| h.bytes(at, len))
        .collect()
    }

    /// Runs the module on the i-set `lanes` with `block`; `occluded(light, ray)` says
    /// which cast rays the stand-in traversal records a triangle for.
    fn run(
        &mut self,
        lanes: &[Lane; 64],
        block: &ShadingBlock,
        occluded: &dyn Fn(usize, usize) -> bool,
        poison: &dyn Fn(&mut Spu),
    ) {
        let off = self.offsets.clone();
        let area = self.area;
        self.h.spu.write_ls(area + off[0], &block.to_be_bytes());
        for (array, f) in [
            (
                1,
                &(|l: &Lane| l.point[0].to_bits()) as &dyn Fn(&Lane) -> u32,
            ),
            (2, &|l: &Lane| l.point[1].to_bits()),
            (3, &|l: &Lane| l.point[2].to_bits()),
            (4, &|l: &Lane| l.normal[0].to_bits()),
            (5, &|l: &Lane| l.normal[1].to_bits()),
            (6, &|l: &Lane| l.normal[2].to_bits()),
            (7, &|l: &Lane| l.material as u32),
        ] {
            self.h.write_words(area + off[array], lanes.iter().map(f));
        }
        // stale visibility, to see it overwritten
        self.h
            .write_words(area + off[8], std::iter::repeat_n(0x5555_5555, 8 * 64));
        let occl = self.sym("occl");
        let cast_lights: Vec<usize> = (0..block.lights.len())
            .filter(|&l| (0..64).any(|i| cast(lanes[i], &block.lights[l])))
            .collect();
        for (call, &l) in cast_lights.iter().enumerate() {
            let ids = (0..64).map(|i| {
                if cast(lanes[i], &block.lights[l]) && occluded(l, i) {
                    7
                } else {
                    u32::MAX
                }
            });
            self.h.write_words(occl + 256 * call as u32, ids);
        }
        self.h.write_words(self.sym("calls"), [0; 4]);
        // the vars words the module swaps: SHT 4, direct mapped
        let vars = self.sym("vars");
        for (name, value) in [
            (512, 0xaaaa),
            (528, 0xbbbb),
            (544, 0xcccc),
            (560, 0xdddd),
            (496, 0),
        ] {
            self.h.write_words(vars + name, [value, 0, 0, 0]);
        }
        for (r, v) in registers(area).into_iter().enumerate() {
            self.h.spu.set_reg(r, v);
        }
        self.h.spu.set_reg(127, [self.sym("back"), 0, 0, 0]);
        poison(&mut self.h.spu);
        let stop = self.h.run_at(self.sym("shadow_rays"), 10_000_000);
        assert_eq!(stop, StopReason::Stop(0x2000));
    }
}

/// Whether the shading casts a shadow ray for the lane toward the light: a hit facing it.
fn cast(lane: Lane, light: &Light) -> bool {
    let l = light.position - glam::Vec3::from(lane.point);
    lane.material != -1 && glam::Vec3::from(lane.normal).dot(l) > 0.0
}

/// An i-set on exact binary fractions (so P - L is exact): hit points on a wall, normals
/// toward or away from the lights by a pattern, some misses.
fn lanes(light: glam::Vec3) -> [Lane; 64] {
    std::array::from_fn(|i| {
        let point = [
            -1.0 + (i % 8) as f32 / 8.0,
            0.25 + (i / 8) as f32 / 16.0,
            -2.0 + (i % 5) as f32 / 32.0,
        ];
        let towards = (light - glam::Vec3::from(point)).normalize();
        let sign = if i % 7 == 3 { -1.0 } else { 1.0 };
        Lane {
            point,
            normal: (towards * sign).to_array(),
            material: if i % 11 == 5 { -1 } else { (i % 3) as i32 },
        }
    })
}

#[test]
fn shadow_packets_are_generated_traced_and_give_visibility() {
    let lights = vec![
        Light::white(glam::Vec3::new(0.5, 2.5, 1.0)),
        // between the hit points in x: rays of both signs there, no frustum bound
        Light::white(glam::Vec3::new(-0.4375, 3.0, 2.0)),
    ];
    let lanes = lanes(lights[0].position);
    let occluded = |l: usize, i: usize| (i * 7 + l).is_multiple_of(3);
    let contract = RegisterContract::of_module("modules/shadow.s", None);
    for r in SHADE_KEEPS {
        assert!(contract.keeps(r), "${r}: shade.s reads it after the call");
    }
    for early in [false, true] {
        let block = ShadingBlock {
            mode: SHADE_SHADOWS,
            shadow_early: early,
            vertex_cache_log2: 6,
            material_cache_log2: 6,
            lights: lights.clone(),
            ..Default::default()
        };
        // the module alone, everything outside its contract's inputs poisoned two ways
        let (spu, _) = check_register_contract(&contract, |poison| {
            let mut h = harness();
            h.run(&lanes, &block, &occluded, poison);
            let outcome = h.outcome();
            (h.h.spu, outcome)
        });
        let mut h = harness();
        h.h.spu = spu;
        let dump = h.sym("dump");
        let mut cast_total = 0;
        for (l, light) in lights.iter().enumerate() {
            let base = dump + DUMP_BYTES * l as u32;
            let cast: Vec<bool> = lanes.iter().map(|&lane| cast(lane, light)).collect();
            assert!(cast.iter().any(|&c| c) && !cast.iter().all(|&c| c));
            cast_total += cast.iter().filter(|&&c| c).count();
            // the rays: from the light to the hit point, t the limit (or -1: not cast)
            let mut lo = [f32::MAX; 3];
            let mut hi = [f32::MIN; 3];
            for i in 0..64u32 {
                let lane = lanes[i as usize];
                for a in 0..3u32 {
                    let d = h.f(base + 256 * a + 4 * i);
                    assert_eq!(d, lane.point[a as usize] - light.position[a as usize]);
                    let r = h.f(base + 768 + 256 * a + 4 * i);
                    assert!((r * d - 1.0).abs() < 1e-6, "1/d {r} for d {d}");
                    if cast[i as usize] {
                        lo[a as usize] = lo[a as usize].min(r);
                        hi[a as usize] = hi[a as usize].max(r);
                    }
                }
                let t = h.f(base + 1536 + 4 * i);
                assert_eq!(t, if cast[i as usize] { LIMIT } else { -1.0 }, "ray {i}");
            }
            // the packet: the light as origin, the frustum of the cast rays' 1/d, t up to
            // the limit, the first cast ray, the one-context miss handlers
            let regs = base + 1792;
            let quad = |k: u32| [0, 4, 8, 12].map(|b| h.word(regs + 16 * k + b));
            assert_eq!(
                quad(0),
                [light.position.x, light.position.y, light.position.z, 0.0].map(f32::to_bits)
            );
            for a in 0..3u32 {
                let (pa, pb, oa) = (quad(1 + a), quad(4 + a), quad(7 + a));
                let both_signs = lo[a as usize] < 0.0 && hi[a as usize] > 0.0;
                if both_signs {
                    assert_eq!((pa, pb), ([0; 4], [0; 4]), "axis {a}");
                    assert!(f32::from_bits(oa[0]) <= -1e29);
                } else {
                    let lo_k = f32::from_bits(pa[0]) / (1.0 - 1.0 / 65536.0);
                    let hi_k = f32::from_bits(pb[0]) / (1.0 - 1.0 / 65536.0);
                    assert!((lo_k / lo[a as usize] - 1.0).abs() < 1e-6, "axis {a}");
                    assert!((hi_k / hi[a as usize] - 1.0).abs() < 1e-6, "axis {a}");
                }
            }
            assert_eq!(quad(10), [0, (-LIMIT).to_bits(), 0, (-LIMIT).to_bits()]);
            let first = cast.iter().position(|&c| c).unwrap() as u32;
            assert_eq!(quad(11), [first; 4]);
            assert_eq!(quad(12)[..3], [0x40, 0x130, first]);
            let handlers = h.sym("handlers");
            assert_eq!(quad(13)[0], h.word(handlers), "bvh_miss_one");
            assert_eq!(
                quad(14)[0],
                u32::MAX,
                "one context while shadow packets run"
            );
            assert_eq!(quad(15)[0], h.word(handlers + 4), ".Lpf_one");
            // the corner rays d, -d, d, -d: the leaves' culling culls nothing
            let corner = |c: u32| [0, 1, 2].map(|a| h.f(base + 2304 + 16 * a + 4 * c));
            assert!(corner(0).iter().any(|&x| x != 0.0));
            assert_eq!(corner(0), corner(2));
            assert_eq!(corner(1), corner(0).map(|x| -x));
            assert_eq!(corner(3), corner(1));
            // early termination: the occluded rays stop, the packet ends when none is left
            let after = base + 2048;
            if early {
                for i in 0..64u32 {
                    let left = cast[i as usize] && !occluded(l, i as usize);
                    let t = h.f(after + 4 * i);
                    assert_eq!(t, if left { LIMIT } else { -1.0 }, "light {l} ray {i}");
                }
                let marker = h.word(h.sym("markers") + 16 * l as u32);
                assert_eq!(marker, 1, "rays are left: the traversal goes on");
            }
            // the visibility: occluded cast rays only
            let vis = h.area + h.offsets[8] + 256 * l as u32;
            for i in 0..64u32 {
                let visible = !(cast[i as usize] && occluded(l, i as usize));
                assert_eq!(h.word(vis + 4 * i), if visible { u32::MAX } else { 0 });
            }
        }
        assert_eq!(h.word(h.sym("calls")), 2);
        let counter = h.area + (SHADOW_AREA + SHADOW_RAYS_OFFSET) as u32;
        assert_eq!(h.word(counter) as usize, cast_total);
        let vars = h.sym("vars");
        assert_eq!(
            [512, 528, 544, 560, 496].map(|o| h.word(vars + o)),
            [0xaaaa, 0xbbbb, 0xcccc, 0xdddd, 0]
        );
        assert_eq!(h.word(h.sym("sv_trace")), 0);
    }
}

/// A light every ray of which is occluded ends its packet at the first leaf with early
/// termination; a light no hit faces casts nothing and stays visible.
#[test]
fn every_ray_occluded_ends_the_packet_and_no_ray_cast_is_visible() {
    let lit = Light::white(glam::Vec3::new(0.5, 2.5, 1.0));
    let mut lanes = lanes(lit.position);
    for lane in lanes.iter_mut() {
        lane.normal = [0.0, 0.0, 1.0];
        lane.material = 0;
    }
    // the second light is behind the wall (z = -3): no hit faces it
    let behind = Light::white(glam::Vec3::new(0.0, 0.0, -3.0));
    let mut h = harness();
    let block = ShadingBlock {
        mode: SHADE_SHADOWS,
        shadow_early: true,
        lights: vec![behind, lit],
        vertex_cache_log2: 6,
        material_cache_log2: 6,
        ..Default::default()
    };
    h.run(&lanes, &block, &|l, _| l == 1, &|_| {});
    assert_eq!(h.word(h.sym("calls")), 1, "one packet: the second light's");
    assert_eq!(
        h.word(h.sym("markers")),
        2,
        "the packet ended at its first leaf"
    );
    let vis = h.area + h.offsets[8];
    for i in 0..64 {
        assert_eq!(h.word(vis + 4 * i), u32::MAX, "first light: nothing cast");
        assert_eq!(h.word(vis + 256 + 4 * i), 0, "second light: all occluded");
    }
    let counter = h.area + (SHADOW_AREA + SHADOW_RAYS_OFFSET) as u32;
    assert_eq!(h.word(counter), 64);
}

/// `--shade simple`: the module returns at once, every light visible as shade.s set it.
#[test]
fn simple_shading_casts_no_shadow_ray() {
    let light = Light::white(glam::Vec3::new(0.5, 2.5, 1.0));
    let mut h = harness();
    let block = ShadingBlock {
        mode: SHADE_SIMPLE,
        lights: vec![light],
        ..Default::default()
    };
    h.run(&lanes(light.position), &block, &|_, _| true, &|_| {});
    assert_eq!(h.word(h.sym("calls")), 0);
    let vis = h.area + h.offsets[8];
    assert_eq!(h.word(vis), 0x5555_5555, "nothing written");
    for (r, v) in registers(h.area).into_iter().enumerate() {
        if r != 127 {
            assert_eq!(h.h.spu.reg(r), v, "${r}");
        }
    }
}
