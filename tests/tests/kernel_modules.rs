//! Each kernel module runs alone on the simulator: a small driver assembles the module with
//! the shared register map and local-store data (`modules/regs.inc`, `modules/data.s`)
//! and a `stop` stub for every label it leaves to; the host sets the registers and local
//! store a module expects, runs it from its entry label with the timing model, and
//! snapshots the registers and local store it leaves (and checks them against the host
//! reference). The mechanism is the tests' one module harness
//! (`spu_tests::ModuleHarness`); the frame's state it sets up is below.

use spu_loader::layout::TriangleRecord;
use spu_tests::ModuleHarness as Harness;
use std::fmt::Write;

/// The frame's state the modules expect, as `_start` (modules/frame.s) sets it up, and the
/// snapshot of what a module leaves.
trait FrameState {
    fn frame_constants(&mut self);
    fn context(&mut self, base: u32);
    fn var(&mut self, name: &str, value: [u32; 4]);
    fn ctx(&self, offset: &str) -> u32;
    fn triangle_cache(&mut self, bvh_lines: u32, lines: u32, ea: u32);
    fn snapshot(&self, exit: &str, regs: &[&str], regions: &[(&str, u32)]) -> String;
}

impl FrameState for Harness {
    /// The frame constants `_start` sets (modules/frame.s), from the same data.
    fn frame_constants(&mut self) {
        self.splat("ZERO", 0);
        self.splat("ONE", 1.0f32.to_bits());
        self.splat("BIG", 0x7149_f2ca);
        self.splat("NBIG", 0xf149_f2ca);
        let pat = self.sym("k_pat");
        for k in 0..4u32 {
            let q = self.quad(pat + 16 * k);
            self.set(&format!("PAT{k}"), q);
        }
        let q = self.quad(self.sym("k_swap"));
        self.set("SWAP", q);
        self.splat("SIGNS", 0x8000_0000);
        let q = self.quad(self.sym("k_negodd"));
        self.set("NEGODD", q);
    }

    /// One packet context at `base` (blocking misses, as `_start` sets up one context):
    /// RAYS points past its header; its DMA tag is the first context's.
    fn context(&mut self, base: u32) {
        let rays = base + self.value("CTX_HEADER");
        self.splat("RAYS", rays);
        self.splat("NEGTAB", rays.wrapping_add(self.value("CTX_NEGTAB")));
        let stack = rays + self.value("CTX_STACK");
        self.splat("STKBASE", stack);
        self.splat("STK", stack);
        let tag = self.value("CONTEXT_TAG0");
        self.write_words(rays + self.value("CTX_TAG"), [tag, 1 << tag, 0, 0]);
        self.var("V_NCTX1", [u32::MAX; 4]);
        self.var("V_ASSOC4", [0; 4]);
    }

    /// Writes a cold variable (`vars+V_*`).
    fn var(&mut self, name: &str, value: [u32; 4]) {
        let addr = self.sym("vars") + self.value(name);
        self.write_words(addr, value);
    }

    /// An address in the current packet context.
    fn ctx(&self, offset: &str) -> u32 {
        self.reg("RAYS")[0].wrapping_add(self.value(offset))
    }

    /// The triangle cache as `_start` carves it (after a BVH cache of `bvh_lines`), every
    /// tag invalid; triangle records at `ea` in main memory.
    fn triangle_cache(&mut self, bvh_lines: u32, lines: u32, ea: u32) {
        let ttags = self.sym("cache_area") + bvh_lines * 16 + bvh_lines * 64;
        self.splat("TTAGS", ttags);
        self.splat("TDATA", ttags + lines * 16);
        self.splat("TMASK", lines - 1);
        self.splat("EATRIS", ea);
        self.write_words(ttags, vec![u32::MAX; 4 * lines as usize]);
    }

    /// Named registers, then local-store regions (a label, or an offset `CTX_*` in the
    /// packet context; bytes), as hex words.
    fn snapshot(&self, exit: &str, regs: &[&str], regions: &[(&str, u32)]) -> String {
        let mut out = format!("exit: {exit}\ncycles: {}\n", self.spu.cycles());
        for r in regs {
            let mut q = self.reg(r);
            if *r == "STK" {
                // Relative to the stack's base: the snapshot does not move with the code.
                q = q.map(|w| w.wrapping_sub(self.reg("STKBASE")[0]));
            }
            writeln!(
                out,
                "{r:<8} {:08x} {:08x} {:08x} {:08x}",
                q[0], q[1], q[2], q[3]
            )
            .unwrap();
        }
        for (label, len) in regions {
            let base = if label.starts_with("CTX_") {
                self.ctx(label)
            } else {
                self.sym(label)
            };
            writeln!(out, "{label}:").unwrap();
            for off in (0..*len).step_by(16) {
                let q = self.quad(base + off);
                writeln!(
                    out,
                    "  +{off:<4} {:08x} {:08x} {:08x} {:08x}",
                    q[0], q[1], q[2], q[3]
                )
                .unwrap();
            }
        }
        out
    }
}

/// A packet of 8x8 primary rays from `origin` through a grid on the plane z = 0.
fn packet_rays(origin: [f32; 3]) -> Vec<[f32; 3]> {
    (0..64)
        .map(|i| {
            let (row, col) = ((i / 8) as f32, (i % 8) as f32);
            // Off the triangles' shared edge by construction (a third of a step).
            let x = -1.0 + (col + 0.37) * 0.25;
            let y = -1.0 + (row + 0.29) * 0.25;
            [x - origin[0], y - origin[1], -origin[2]]
        })
        .collect()
}

#[test]
fn triangle_test_on_a_packet() {
    let mut h = Harness::with_stubs(
        &["modules/triangle.s", "modules/tri_cache.s", "modules/lru.s"],
        &["packet_done", "trav", "suspend"],
        "        .set    .Lnewcur, trav\nharness_pf_one: br .Lpf_one\n",
    );
    h.frame_constants();
    // A quad made of two triangles across part of the packet, and one triangle off to the
    // side that every corner ray misses (culled).
    let quads = [
        [[-0.8f32, -0.6, 0.0], [0.5, -0.6, 0.0], [0.5, 0.7, 0.0]],
        [[-0.8, -0.6, 0.0], [0.5, 0.7, 0.0], [-0.8, 0.7, 0.0]],
        [[5.0, 5.0, 1.0], [6.0, 5.0, 1.0], [5.0, 6.0, 1.0]],
    ];
    let records: Vec<TriangleRecord> = quads
        .iter()
        .enumerate()
        .map(|(i, p)| TriangleRecord::new(p.map(glam::Vec3::from_array), [0, 1, 2], 0, i as u32))
        .collect();
    let ea = 0x4000u32;
    let mut bytes = vec![0u8; 64 * records.len()];
    for (i, r) in records.iter().enumerate() {
        r.write_be(&mut bytes[64 * i..64 * i + 64]);
    }
    assert!(h.memory.write_bytes(ea as u64, &bytes));
    h.triangle_cache(256, 128, ea);
    let contexts = h.reg("TDATA")[0] + 128 * 64;
    h.context(contexts);
    let pf_one = h.sym("harness_pf_one");
    h.var("V_PFMISS", [pf_one; 4]);
    // The packet: origin, directions (structure of arrays), t = 1e30, no hit yet.
    let origin = [0.1f32, -0.2, 3.0];
    h.set(
        "ORIG",
        [
            origin[0].to_bits(),
            origin[1].to_bits(),
            origin[2].to_bits(),
            0,
        ],
    );
    let rays = packet_rays(origin);
    let dx = h.ctx("CTX_RAY_DX");
    for axis in 0..3 {
        let words: Vec<u32> = rays.iter().map(|d| d[axis].to_bits()).collect();
        h.write_words(dx + 256 * axis as u32, &words);
        let recip: Vec<u32> = rays.iter().map(|d| (1.0 / d[axis]).to_bits()).collect();
        h.write_words(dx + 256 * (3 + axis as u32), &recip);
    }
    let t_addr = h.ctx("CTX_RAY_T");
    h.write_words(t_addr, [0x7149_f2ca; 64]);
    h.write_words(h.ctx("CTX_RAY_ID"), [u32::MAX; 64]);
    let corners: Vec<u32> = (0..3)
        .flat_map(|axis| [0, 7, 56, 63].map(|i| rays[i][axis].to_bits()))
        .collect();
    h.write_words(h.ctx("CTX_CORNERS"), &corners);
    h.splat("FIRST", 0);
    h.set("CUR", [0, (records.len() as u32) << 6, 0, 0]);
    for s in ["S_TRIS", "S_CULLED", "S_TLOOK"] {
        h.splat(s, 0);
    }

    let exit = h.run_from("leaf");

    // Against the host reference: per ray the nearest hit of the records.
    let mut hits = 0;
    for (i, d) in rays.iter().enumerate() {
        let mut best: Option<(f32, u32)> = None;
        for (k, r) in records.iter().enumerate() {
            let t_max = best.map_or(1e30, |b| b.0);
            if let Some((t, _, _)) = r.intersect(origin, *d, 0.0, t_max) {
                best = Some((t, k as u32));
            }
        }
        let (vec, lane) = (i as u32 / 4 * 16, i as u32 % 4);
        let id = h.quad(h.ctx("CTX_RAY_ID") + vec)[lane as usize];
        let t = h.quad(t_addr + vec)[lane as usize];
        match best {
            Some((bt, bk)) => {
                hits += 1;
                // The kernel divides by a refined reciprocal: t within 1e-4 relative, as
                // `spu render --validate` compares (loader::camera).
                let kt = f32::from_bits(t);
                assert_eq!(id, bk, "ray {i}");
                assert!(
                    (kt - bt).abs() <= 1e-4 * bt.abs(),
                    "ray {i}: t {kt} vs {bt}"
                );
            }
            None => assert_eq!((id, t), (u32::MAX, 0x7149_f2ca), "ray {i}"),
        }
    }
    assert!(
        hits > 10 && hits < 64,
        "{hits} hits: the quad covers part of the packet"
    );
    assert_eq!(
        exit, "packet_done",
        "the stack was empty: the packet is done"
    );
    assert_eq!(h.reg("S_CULLED")[0], 1, "the third triangle is culled");
    insta::assert_snapshot!(h.snapshot(
        &exit,
        &["S_TRIS", "S_CULLED", "S_TLOOK", "F2"],
        &[
            ("CTX_RAY_T", 256),
            ("CTX_RAY_ID", 256),
            ("CTX_RAY_ND", 256),
            ("vars", 272)
        ],
    ));
}

/// The BVH cache as `_start` carves it, every tag invalid; node records at `ea`.
fn bvh_cache(h: &mut Harness, lines: u32, ea: u32) {
    let btags = h.sym("cache_area");
    let bdata = btags + lines * 16;
    h.splat("BTAGS", btags);
    h.splat("BDATA", bdata);
    h.splat("BDATA16", bdata + 16);
    h.splat("BDATA32", bdata + 32);
    h.splat("BDATA48", bdata + 48);
    h.splat("BMASK64", (lines - 1) * 64);
    h.splat("EANODES", ea);
    h.write_words(btags, vec![u32::MAX; 4 * lines as usize]);
}

#[test]
fn ray_generation_packet_setup_and_one_traversal_step() {
    // Ray generation and the packet setup (modules/raygen.s) enter traversal at the root's
    // children; the step (modules/traverse.s) misses the BVH cache (modules/bvh_cache.s),
    // fills the line, tests both children, descends to the near leaf and pushes the far
    // one; the first ray misses one child, so find_first gives that child its own first
    // ray (5). The next step sees the leaf and leaves for the triangle test.
    let mut h = Harness::with_stubs(
        &[
            "modules/raygen.s",
            "modules/traverse.s",
            "modules/bvh_cache.s",
            "modules/lru.s",
        ],
        &["leaf", "packet_done", "suspend"],
        "",
    );
    h.frame_constants();
    // Two triangles side by side, one leaf each under an inner root.
    use glam::Vec3;
    let positions = vec![
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(-0.1, -1.0, 0.0),
        Vec3::new(-0.5, 1.0, 0.0),
        Vec3::new(0.1, -1.0, -0.5),
        Vec3::new(1.0, -1.0, -0.5),
        Vec3::new(0.5, 1.0, -0.5),
    ];
    let triangles = (0..2)
        .map(|t| spu_loader::Triangle {
            v: [3 * t, 3 * t + 1, 3 * t + 2],
            material: 0,
        })
        .collect();
    let scene = spu_loader::Scene::from_parts(positions, None, Vec::new(), triangles, Vec::new());
    let config = spu_loader::BvhConfig {
        max_leaf_size: 1,
        ..Default::default()
    };
    let bvh = spu_loader::Bvh::build(&scene, &config);
    let nodes = spu_loader::layout::node_records(&bvh);
    assert!(
        !bvh.root().is_leaf() && nodes.len() == 4,
        "a root and two leaves"
    );
    let ea = 0x8000u32;
    let mut bytes = vec![0u8; 32 * nodes.len()];
    for (i, n) in nodes.iter().enumerate() {
        n.write_be(&mut bytes[32 * i..32 * i + 32]);
    }
    assert!(h.memory.write_bytes(ea as u64, &bytes));
    bvh_cache(&mut h, 256, ea);
    h.triangle_cache(256, 128, 0x4000);
    let contexts = h.reg("TDATA")[0] + 128 * 64;
    h.context(contexts);
    let miss = h.sym("bvh_miss_one");
    h.splat("BMISSH", miss);
    // The root as a traversal state, as `_start` makes it: (child-pair offset, meta << 4).
    let root = &nodes[0];
    h.set("ROOTST", [root.link * 32, root.count_axis << 4, 0, 0]);
    // The camera: packet 0 of tile 0 looks at the triangles from z = 3.
    let origin = [0.05f32, 0.0, 3.0];
    h.set(
        "ORIG",
        [
            origin[0].to_bits(),
            origin[1].to_bits(),
            origin[2].to_bits(),
            0,
        ],
    );
    for (k, name) in ["OXS", "OYS", "OZS"].iter().enumerate() {
        h.splat(name, origin[k].to_bits());
    }
    let word = |x: f32| x.to_bits();
    h.var("V_DIR00", [word(-0.6), word(-0.7), word(-3.0), 0]);
    h.var("V_DU", [word(0.15), 0, 0, 0]);
    h.var("V_DV", [0, word(0.18), 0, 0]);
    for s in ["S_STEPS", "M1V", "EEV", "S_TRIS", "S_CULLED", "S_TLOOK"] {
        h.splat(s, 0);
    }

    let exit = h.run_from("packet_loop");

    assert_eq!(exit, "leaf");
    assert_eq!(
        h.reg("S_STEPS")[0],
        1,
        "one pair step (the cache miss reruns it)"
    );
    let stkbase = h.reg("STKBASE")[0];
    assert_eq!(h.reg("STK")[0], stkbase + 16, "the far child is pushed");
    // The two children are the two leaves: CUR holds one, the stack the other.
    let leaves: Vec<u32> = nodes[2..].iter().map(|n| n.link).collect();
    let near = h.reg("CUR")[0];
    let far = h.quad(stkbase)[0];
    assert!(
        leaves.contains(&near) && leaves.contains(&far) && near != far,
        "{near} {far} {leaves:?}"
    );
    insta::assert_snapshot!(h.snapshot(
        &exit,
        &["CUR", "STK", "FIRST", "S_STEPS", "M1V", "EEV", "F2", "PAX", "PBX", "OAX", "OBX"],
        &[("CTX_STACK", 32), ("CTX_CORNERS", 48), ("cache_area", 32)],
    ));
}

/// The BVH cache's one-context miss handler alone (`modules/bvh_cache.s`), entered as the
/// traversal step leaves a miss: the lookup's $66 (the line's offset) and $72 (the tag's)
/// and the pair in CUR, everything outside its register contract poisoned two ways. It
/// fetches the pair, installs it axis-major in the line with CUR as the tag, takes back
/// the step's count and returns to `trav`.
#[test]
fn bvh_miss_handler_takes_the_steps_lookup() {
    use spu_loader::layout::NodeRecord;
    let contract =
        spu_tests::RegisterContract::of_module("modules/bvh_cache.s", Some("bvh_miss_one"));
    let node = |lo: f32, link: u32, count_axis: u32| NodeRecord {
        min: [lo, lo + 1.0, lo + 2.0],
        link,
        max: [lo + 3.0, lo + 4.0, lo + 5.0],
        count_axis,
    };
    // the pair 1 (nodes 2 and 3): an inner node and a leaf of 3 triangles
    let nodes = [
        node(0.0, 2, 0),
        node(0.0, 0, 0),
        node(10.0, 6, 1),
        node(20.0, 9, 3 << 2),
    ];
    let ea = 0x8000u32;
    let (spu, (exit, line)) = spu_tests::check_register_contract(&contract, |poison| {
        let mut h = Harness::with_stubs(
            &["modules/bvh_cache.s", "modules/lru.s"],
            &["trav", "suspend"],
            "",
        );
        h.frame_constants();
        let mut bytes = vec![0u8; 32 * nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            n.write_be(&mut bytes[32 * i..32 * i + 32]);
        }
        assert!(h.memory.write_bytes(ea as u64, &bytes));
        bvh_cache(&mut h, 256, ea);
        h.triangle_cache(256, 128, 0x4000);
        let contexts = h.reg("TDATA")[0] + 128 * 64;
        h.context(contexts);
        h.set("CUR", [64, 0x40, 0, 0]);
        h.splat("S_STEPS", 5);
        let line = 64; // the pair's line: CUR & BMASK64
        h.spu.set_reg(66, [line, 0, 0, 0]);
        h.spu.set_reg(72, [line / 4, 0, 0, 0]);
        poison(&mut h.spu);
        let exit = h.run_from("bvh_miss_one");
        let cache = h.sym("cache_area");
        let mut out = h.bytes(cache + 16, 16);
        out.extend(h.bytes(cache + 256 * 16 + 64, 64));
        (h.spu, (exit, out))
    });
    assert_eq!(exit, "trav");
    let steps = spu_tests::kernel_names().register("S_STEPS").unwrap() as usize;
    assert_eq!(spu.reg(steps)[0], 4, "the step counts again");
    let word = |at: usize| u32::from_be_bytes(line[at..at + 4].try_into().unwrap());
    assert_eq!([word(0), word(4)], [64, 0x40], "the tag is the pair");
    let f = |at: usize| f32::from_bits(word(16 + at));
    // x planes (min2.x, max2.x, min3.x, max3.x), then y, z; then (link', meta) per child
    assert_eq!([f(0), f(4), f(8), f(12)], [10.0, 13.0, 20.0, 23.0]);
    assert_eq!([f(16), f(20), f(24), f(28)], [11.0, 14.0, 21.0, 24.0]);
    assert_eq!([f(32), f(36), f(40), f(44)], [12.0, 15.0, 22.0, 25.0]);
    assert_eq!(
        [word(64), word(68), word(72), word(76)],
        [6 * 32, 1 << 4, 9, (3 << 2) << 4]
    );
}

/// The triangle cache's one-context prefetch miss alone (`modules/tri_cache.s`), entered
/// as the leaf's prefetch pass leaves a missing triangle, everything outside its register
/// contract poisoned two ways: the record is fetched straight into way 0 (the tag first),
/// the miss counted, and the pass goes on with a fetch in flight ($78 = 1).
#[test]
fn triangle_prefetch_miss_takes_the_pass_lookup() {
    let contract = spu_tests::RegisterContract::of_module("modules/tri_cache.s", Some(".Lpf_one"));
    let (index, ea) = (21u32, 0x4000u32);
    let record: Vec<u8> = (0..64u8).map(|b| b ^ 0x5a).collect();
    // .Lpf_next waits for the fetch (through a register the handler clobbers) and stops;
    // the handler's local label is reached through a global one
    let extra = "
harness_pf_one: br .Lpf_one
.Lpf_next:
        il      $87, 1 << CONTEXT_TAG0
        wrch    $MFC_WrTagMask, $87
        il      $87, 2
        wrch    $MFC_WrTagUpdate, $87
        rdch    $87, $MFC_RdTagStat
        stop    0x2200
";
    let (spu, (exit, outcome)) = spu_tests::check_register_contract(&contract, |poison| {
        let mut h = Harness::with_stubs(
            &["modules/tri_cache.s", "modules/lru.s"],
            &[".Lpf", ".Ltri_hit", "leaf_cull", "leaf_probe", "suspend"],
            extra,
        );
        h.frame_constants();
        assert!(h.memory.write_bytes((ea + 64 * index) as u64, &record));
        h.triangle_cache(256, 128, ea);
        let contexts = h.reg("TDATA")[0] + 128 * 64;
        h.context(contexts);
        let line = index & 127;
        for (r, v) in [(76, index), (79, 64), (80, line), (81, 16 * line)] {
            h.spu.set_reg(r, [v, 0, 0, 0]);
        }
        poison(&mut h.spu);
        let exit = h.run_from("harness_pf_one");
        let ttags = h.reg("TTAGS")[0];
        let tdata = h.reg("TDATA")[0];
        let mut out = h.bytes(ttags + 16 * line, 16);
        out.extend(h.bytes(tdata + 64 * line, 64));
        out.extend(h.bytes(h.sym("vars") + h.value("V_TMISS"), 4));
        (h.spu, (exit, out))
    });
    assert_eq!(exit, "stop 0x2200", "back to the pass");
    assert_eq!(spu.reg(78)[0], 1, "a fetch is in flight");
    assert_eq!(outcome[..4], index.to_be_bytes(), "the tag");
    assert_eq!(outcome[16..80], record[..], "the record, in way 0");
    assert_eq!(outcome[80..84], 1u32.to_be_bytes(), "one miss counted");
}
