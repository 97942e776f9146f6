//! The reflection module's ray generation (`reflect_iset` in `kernels/modules/reflect.s`)
//! alone on the simulator: given an i-set (hit points, eye-facing normals, materials) and
//! the primary rays in local store, it fetches the reflectance table once and writes the
//! next level's rays (origin, direction, cast mask, weights, count), checked against the
//! host model (`shading::reflect_direction`, `REFLECT_OFFSET`); for a reflection's i-set
//! it turns each normal to face its ray, bit for bit. Every register the shading module
//! reads after the call is left as it was.

use glam::Vec3;
use spu_loader::kernel_abi::{
    ShadingBlock, PARAM_EA_SHADING, REFLECT_AREA, REFLECT_AREA_BYTES, SHADED_LS_BYTES,
    SHADE_SHADOWS,
};
use spu_loader::shading::{reflect_direction, REFLECT_OFFSET};
use spu_tests::ModuleHarness;

/// Where the host puts the reflectance table in main memory.
const TABLE_EA: u32 = 0x4000;
/// The materials' reflectances: 0 and 2 reflect, 1 does not.
const REFLECTANCES: [f32; 3] = [0.5, 0.0, 0.25];

struct Setup {
    h: ModuleHarness,
    area: u32,
    rf: u32,
    rays: u32,
}

fn setup(depth: u32) -> Setup {
    let mut h = ModuleHarness::with_stubs(
        &["modules/shade_area.s", "modules/reflect.s"],
        &[
            "test_return",
            "shade_packet",
            "trav",
            "packet_done",
            "bvh_miss_one",
            "bvh_miss_ways",
            ".Lb_one_fetch",
            ".Lpf_one",
            ".Lpf_ways",
            ".Lpf_one_evict",
        ],
        "",
    );
    let area = h.sym("cache_area").div_ceil(128) * 128;
    let rays = area + (SHADED_LS_BYTES + REFLECT_AREA_BYTES) as u32;
    assert!(rays + 768 <= 256 * 1024);
    let params = h.sym("params");
    h.write_words(params + PARAM_EA_SHADING as u32 + 4, [area]);
    let block = ShadingBlock {
        mode: SHADE_SHADOWS,
        reflect_depth: depth,
        ea_reflectances: TABLE_EA,
        vertex_cache_log2: 6,
        material_cache_log2: 6,
        ..Default::default()
    };
    let sh_block = h.value("SH_BLOCK");
    h.spu.write_ls(area + sh_block, &block.to_be_bytes());
    for (i, r) in REFLECTANCES.iter().enumerate() {
        h.memory.write_u32(TABLE_EA + 4 * i as u32, r.to_bits());
    }
    let hold = h.sym("rf_hold");
    h.write_words(hold, [u32::MAX; 4]);
    let rf = area + REFLECT_AREA as u32;
    let regs = h.value("RF_REGS");
    h.write_words(rf + regs + 16 * 68, [rays, 0, 0, 0]);
    Setup { h, area, rf, rays }
}

/// Lane `i`'s hit: its material (-1: none), primary direction, normal and point.
fn lane(i: usize) -> (i32, Vec3, Vec3, Vec3) {
    let material = [0, 1, 2, -1][i % 4];
    let f = i as f32;
    let d = Vec3::new(0.3 + 0.01 * f, -1.0, 0.2 - 0.005 * f);
    let n = if i == 8 {
        Vec3::ZERO // a zero normal reflects nothing
    } else {
        Vec3::new(0.1 * (f % 5.0) - 0.2, 2.0 + 0.03 * f, 0.05 * f - 1.0)
    };
    let p = Vec3::new(1.0 + 0.1 * f, 0.75, -0.5 + 0.02 * f);
    (material, d, n, p)
}

/// Writes the i-set and the primary rays; the registers the shading module reads after
/// the call get distinct values.
fn write_iset(s: &mut Setup) {
    let area = s.area;
    let h = &mut s.h;
    let (nx, px, mat) = (h.value("SH_NX"), h.value("SH_PX"), h.value("SH_MAT"));
    for i in 0..64u32 {
        let (m, d, n, p) = lane(i as usize);
        let at = 4 * i;
        for k in 0..3u32 {
            h.write_words(area + nx + 256 * k + at, [n[k as usize].to_bits()]);
            h.write_words(area + px + 256 * k + at, [p[k as usize].to_bits()]);
            h.write_words(s.rays + 256 * k + at, [d[k as usize].to_bits()]);
        }
        h.write_words(area + mat + at, [m as u32]);
    }
}

/// The frame registers the module reads, and distinct values in every register the
/// shading module keeps over the call.
fn set_registers(s: &mut Setup) -> Vec<(usize, [u32; 4])> {
    let splat = |w: u32| [w; 4];
    let mut kept = Vec::new();
    for r in (0..=66).chain([91, 92, 93, 97, 124]) {
        let v = match r {
            2 => splat(0),
            3 => splat(1f32.to_bits()),
            7..=10 => splat(0x0001_0203 + 0x0404_0404 * (r as u32 - 7)),
            37 => splat(0x8000_0000),
            66 => [s.area, 1, 2, 3],
            _ => [r as u32 * 0x0101_0101, r as u32, !(r as u32), 0x1234_5678],
        };
        s.h.spu.set_reg(r, v);
        kept.push((r, v));
    }
    let ret = s.h.sym("test_return");
    s.h.spu.set_reg(127, [ret, 0, 0, 0]);
    kept
}

fn vec_at(h: &ModuleHarness, base: u32, i: u32) -> Vec3 {
    Vec3::new(
        h.f(base + 4 * i),
        h.f(base + 256 + 4 * i),
        h.f(base + 512 + 4 * i),
    )
}

#[test]
fn the_generation_makes_the_models_reflected_rays() {
    let mut s = setup(1);
    write_iset(&mut s);
    let kept = set_registers(&mut s);
    assert_eq!(s.h.run_from("reflect_iset"), "test_return");
    let h = &s.h;
    for (r, v) in kept {
        assert_eq!(h.spu.reg(r), v, "${r} is kept");
    }
    let rf = s.rf;
    // the table, fetched once, and the flag that says so
    let table = rf + h.value("RF_TABLE");
    for (i, r) in REFLECTANCES.iter().enumerate() {
        assert_eq!(h.f(table + 4 * i as u32), *r);
    }
    assert_eq!(
        h.word(rf + h.value("RF_FLAG")),
        u32::from_be_bytes(*b"REFL")
    );
    let (ox, dx, cast) = (
        rf + h.value("RF_OX"),
        rf + h.value("RF_DX"),
        rf + h.value("RF_CAST"),
    );
    let weights = rf + h.value("RF_WEIGHTS");
    let mut casts = 0;
    for i in 0..64u32 {
        let (m, d, n, p) = lane(i as usize);
        let reflectance = if m >= 0 {
            REFLECTANCES[m as usize]
        } else {
            0.0
        };
        let expect_cast = reflectance > 0.0 && n != Vec3::ZERO;
        assert_eq!(
            h.word(cast + 4 * i),
            if expect_cast { !0 } else { 0 },
            "lane {i}"
        );
        assert_eq!(
            h.f(weights + 4 * i),
            if expect_cast { reflectance } else { 0.0 },
            "lane {i}"
        );
        if !expect_cast {
            continue;
        }
        casts += 1;
        let r = reflect_direction(d, n);
        let got = vec_at(h, dx, i);
        assert!(
            (got - r).length() <= 1e-5 * d.length(),
            "lane {i}: {got} / {r}"
        );
        let o = p + r * REFLECT_OFFSET;
        let got = vec_at(h, ox, i);
        assert!(
            (got - o).length() <= 1e-5 * o.length(),
            "lane {i}: {got} / {o}"
        );
    }
    assert_eq!(casts, 31, "lanes of materials 0 and 2 but lane 8");
    assert_eq!(h.word(rf + h.value("RF_CASTS")), casts);
}

#[test]
fn a_reflections_normals_turn_to_its_rays_and_the_last_level_casts_none() {
    let mut s = setup(1);
    write_iset(&mut s);
    let rf = s.rf;
    let (state, dx, flag) = (
        s.h.value("RF_STATE"),
        s.h.value("RF_DX"),
        s.h.value("RF_FLAG"),
    );
    s.h.write_words(rf + state, [1, 0, 0, 0]); // level 1 of depth 1: the last
    s.h.write_words(rf + flag, [u32::from_be_bytes(*b"REFL"); 4]);
    let ray = |i: u32| Vec3::new(0.5 - 0.02 * i as f32, 1.0 - 0.03 * i as f32, 0.25);
    for i in 0..64u32 {
        let r = ray(i);
        for k in 0..3u32 {
            s.h.write_words(rf + dx + 256 * k + 4 * i, [r[k as usize].to_bits()]);
        }
    }
    let casts = s.h.value("RF_CASTS");
    s.h.write_words(rf + casts, [7, 0, 0, 0]);
    let kept = set_registers(&mut s);
    assert_eq!(s.h.run_from("reflect_iset"), "test_return");
    let h = &s.h;
    for (r, v) in kept {
        assert_eq!(h.spu.reg(r), v, "${r} is kept");
    }
    let nx = s.area + h.value("SH_NX");
    for i in 0..64u32 {
        let (_, _, n, _) = lane(i as usize);
        let r = ray(i);
        // the kernel's sign test: x*x' then two fused multiply-adds
        let dot = (n.z).mul_add(r.z, (n.y).mul_add(r.y, n.x * r.x));
        let expect = if dot > 0.0 { -n } else { n };
        let got = vec_at(h, nx, i);
        assert_eq!(
            got.to_array().map(f32::to_bits),
            expect.to_array().map(f32::to_bits),
            "lane {i}"
        );
    }
    assert_eq!(h.word(rf + casts), 0, "the last level casts no ray");
}
