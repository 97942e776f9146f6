//! The 4-way caches and software hyperthreading of the primary-ray kernel: the LRU module
//! (`kernels/modules/lru.s`) alone on the simulator, and whole frames with 1 to 8 packets
//! in flight and direct-mapped or 4-way caches, which must all give the same image as the
//! blocking direct-mapped kernel and the host reference.

use spu_isa::jit::CodeCache;
use spu_isa::machine::{MainMemory, Spu};
use spu_loader::camera::Camera;
use spu_loader::frame::SCENE_BASE;
use spu_loader::kernel_abi::{decode_frame_buffer, KernelStats, MISS};
use spu_loader::reference::Reference;
use spu_loader::render::{render, Prepared, RenderConfig};
use spu_loader::runtime::FrameRun;
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
    let prepared = Prepared {
        name: "test".into(),
        scene: scene.clone(),
        staged: staged.clone(),
    };
    let config = RenderConfig {
        width: w,
        height: h,
        spes,
        bvh_cache: lines,
        tri_cache: lines,
        assoc,
        sht,
        max_cycles: 20_000_000_000,
        ..RenderConfig::new("test")
    };
    render(&prepared, &config, &CodeCache::default())
        .map(|frame| frame.run)
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
            (p.triangle == MISS) == r.is_hit()
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

/// The packet registers a suspension saves, in the order of their save slots (sht.s).
const PACKET_REGISTERS: [&str; 27] = [
    "OR1X", "OR1Y", "OBX", "OBY", "OBZ", "OR1Z", "PAX", "PAY", "PAZ", "PBX", "PBY", "PBZ", "OAX",
    "OAY", "OAZ", "F2", "RX1", "RY1", "RZ1", "PERMX", "PERMY", "PERMZ", "FT_ADDR", "FT_PAT",
    "FIRST", "CUR", "STK",
];

/// Assembles a driver with the kernel's include files, the register map, its data and the
/// cache and SHT modules; `trav`, `packet_start` and `frame_done` stop with 0x2003, 0x2001
/// and 0x2002.
fn module_program(driver: &str) -> spu_loader::runtime::Program {
    let source = format!(
        "        .include \"layout.inc\"
        .include \"modules/regs.inc\"
        .include \"modules/data.s\"
        .text
        .global _start
_start:
        il      ZERO, 0
{driver}
trav:   stop    0x2003
packet_start:
        stop    0x2001
frame_done:
        stop    0x2002
        .include \"modules/bvh_cache.s\"
        .include \"modules/lru.s\"
        .include \"modules/sht.s\"
"
    );
    spu_loader::runtime::assemble_kernel(&source, "driver.s").expect("assembles")
}

fn symbol(p: &spu_loader::runtime::Program, name: &str) -> u32 {
    p.symbols
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, a)| *a)
        .unwrap_or_else(|| panic!("no symbol {name}"))
}

fn quads(ls: &[u8], from: u32, count: u32) -> String {
    (0..count)
        .map(|q| {
            let a = from + 16 * q;
            format!(
                "{a:05x}: {:08x} {:08x} {:08x} {:08x}\n",
                word(ls, a),
                word(ls, a + 4),
                word(ls, a + 8),
                word(ls, a + 12)
            )
        })
        .collect()
}

/// One SHT context switch: packet A (context 0, its packet registers 0xa000 + slot) is
/// suspended and packet B (context 1, suspended with 0xb000 + slot saved, its fetch done)
/// resumes where it left: A's registers and resume address are in A's save area, B's are
/// back in the registers, the context pointer, near-child table and stack base are B's,
/// and B is marked running.
#[test]
fn sht_switch_saves_one_packet_and_resumes_the_next() {
    use spu_loader::kernel_abi::context as ctx;
    let mut driver = String::from(
        "        ila     $70, ctxs+CTX_HEADER
        il      $71, CTX_BYTES
        a       $71, $70, $71
        stqd    $71, CTX_NEXT($70)
        stqd    $70, CTX_NEXT($71)
        lqa     $72, tags
        stqd    $72, CTX_TAG($70)
        lqa     $72, tags+16
        stqd    $72, CTX_TAG($71)
        ila     $72, resumed_b
        stqd    $72, CTX_RESUME($71)
        ila     $73, 0xb000
",
    );
    for (k, r) in PACKET_REGISTERS.iter().enumerate() {
        driver += &format!(
            "        ila     {r}, {:#x}\n        ai      $74, $73, {k}\n        stqd    $74, CTX_SAVE+{}($71)\n",
            0xa000 + k,
            16 * k
        );
    }
    driver += "        ori     RAYS, $70, 0
        ila     $80, resumed_a
        br      suspend
resumed_a:
        stop    0x2004
resumed_b:
        stop    0x2000
        .data
        .align  4
tags:   .long   CONTEXT_TAG0, 1 << CONTEXT_TAG0, 0, 0
        .long   CONTEXT_TAG0 + 1, 2 << CONTEXT_TAG0, 0, 0
        .align  7
ctxs:   .space  2 * CTX_BYTES
        .text
";
    let program = module_program(&driver);
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    let mut mem = MainMemory::zeroed(4096);
    let stop = spu.run(&mut mem, 1_000_000);
    assert_eq!(format!("{stop}"), "stop 0x2000", "B resumed");
    let a = symbol(&program, "ctxs") + ctx::HEADER as u32;
    let b = a + ctx::BYTES;
    let ls = spu.ls();
    for (k, _) in PACKET_REGISTERS.iter().enumerate() {
        let slot = (ctx::SAVE + 16 * k as i32) as u32;
        assert_eq!(word(ls, a + slot), 0xa000 + k as u32, "A's slot {k}");
    }
    // their numbers (modules/regs.inc)
    let regs = [
        11, 25, 27, 28, 29, 39, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 60,
        61, 62, 63, 64,
    ];
    for (k, r) in regs.iter().enumerate() {
        assert_eq!(spu.reg(*r)[0], 0xb000 + k as u32, "register ${r}");
    }
    assert_eq!(
        word(ls, a + ctx::RESUME as u32),
        symbol(&program, "resumed_a")
    );
    assert_eq!(word(ls, b + ctx::RESUME as u32), 0, "B runs");
    assert_eq!(spu.reg(1)[0], b, "RAYS");
    assert_eq!(spu.reg(42)[0], (b as i32 + ctx::NEGTAB) as u32, "NEGTAB");
    assert_eq!(spu.reg(40)[0], b + ctx::STACK as u32, "STKBASE");
    let mut text = format!("{stop}\ncycles: {}\n", spu.cycles());
    for r in [1, 40, 42, 80, 98] {
        let v = spu.reg(r);
        text += &format!(
            "${r}: {:08x} {:08x} {:08x} {:08x}\n",
            v[0], v[1], v[2], v[3]
        );
    }
    text += "A's save area:\n";
    text += &quads(ls, a + ctx::SAVE as u32, 32);
    text += "B's save area:\n";
    text += &quads(ls, b + ctx::SAVE as u32, 32);
    insta::assert_snapshot!(text);
}

/// Runs the BVH cache's miss handler `handler` on a 16-line cache (4 sets of 4 ways when
/// `assoc4`) whose ways hold the tags `ways` in the pair's set, with the pair at
/// main-memory offset 0x200: child 0 an inner node (first child 20, split axis 1), child 1
/// a leaf of 3 triangles from 7. Returns the local store, the cache's symbols and the
/// number of fetches the handler counted.
fn bvh_cache_case(handler: &str, assoc4: bool, ways: [u32; 4]) -> (Vec<u8>, u32, u32, u32) {
    use spu_loader::layout::NodeRecord;
    let (set_bytes, mask64) = if assoc4 { (64, 3 * 64) } else { (256, 15 * 64) };
    let pair = 0x200u32;
    let set = pair & mask64; // the way-0 line offset trav computes
    let mut driver = format!(
        "        lqa     SWAP, k_swap                  # (a frame constant the install uses)
        ila     RAYS, ctx+CTX_HEADER
        lqa     $70, tag
        stqd    $70, CTX_TAG(RAYS)
        ila     BTAGS, btags
        ila     BDATA, bdata
        il      EANODES, 0
        il      S_STEPS, 5
        il      $70, {a4}
        stqa    $70, vars+V_ASSOC4
        il      $70, {wt}
        stqa    $70, vars+V_BWAYT
        il      $70, {wd}
        stqa    $70, vars+V_BWAYD
        ila     $70, .Lb_one_fetch
        stqa    $70, vars+V_BFETCH
        stqa    ZERO, vars+V_BMISS
        lqa     CUR, cur
        il      $66, {set}
        il      $72, {tagoff}
",
        a4 = if assoc4 { -1 } else { 0 },
        wt = set_bytes / 4 * 16 / 4,
        wd = set_bytes / 4 * 64 / 4,
        tagoff = set / 4,
    );
    // ways w of the set: tags at btags + tagoff + w * wt, lines at bdata + set + w * wd
    let (wt, wd) = (set_bytes / 4 * 16 / 4, set_bytes / 4 * 64 / 4);
    for (w, t) in ways.iter().enumerate() {
        let w = w as u32;
        driver += &format!(
            "        ila     $70, {t:#x}\n        stqa    $70, btags+{}\n",
            set / 4 + w * wt
        );
        for q in 0..4 {
            driver += &format!(
                "        ila     $70, {:#x}\n        stqa    $70, bdata+{}\n",
                (t & 0xffff) * 16 + q,
                set + w * wd + 16 * q
            );
        }
    }
    driver += &format!(
        "        br      {handler}
        .data
        .align  4
tag:    .long   CONTEXT_TAG0, 1 << CONTEXT_TAG0, 0, 0
cur:    .long   {pair:#x}, 0x10, 3, 0
btags:  .space  16 * 16
        .align  7
bdata:  .space  16 * 64
ctx:    .space  CTX_BYTES
        .text
"
    );
    let program = module_program(&driver);
    let mut memory = MainMemory::zeroed(0x1000);
    let inner = NodeRecord {
        min: [1.0, 2.0, 3.0],
        link: 20,
        max: [4.0, 5.0, 6.0],
        count_axis: 1,
    };
    let leaf = NodeRecord {
        min: [-1.0, -2.0, -3.0],
        link: 7,
        max: [-0.5, -1.5, -2.5],
        count_axis: 3 << 2,
    };
    let mut bytes = [0u8; 64];
    inner.write_be(&mut bytes[..32]);
    leaf.write_be(&mut bytes[32..]);
    memory.write_bytes(pair as u64, &bytes);
    let mut spu = Spu::new(0);
    spu.load_image(&program.image);
    spu.set_pc(program.entry);
    let stop = spu.run(&mut memory, 1_000_000);
    assert_eq!(
        format!("{stop}"),
        "stop 0x2003",
        "back in the traversal step"
    );
    let misses = word(spu.ls(), symbol(&program, "vars") + 224);
    (
        spu.ls().to_vec(),
        symbol(&program, "btags") + set / 4,
        symbol(&program, "bdata") + set,
        misses,
    )
}

/// The pair as the cache line must hold it: planes axis-major, then (link', meta) with an
/// inner child's link' the byte offset of its pair and meta = count_axis << 4.
const INSTALLED: [[f32; 4]; 3] = [
    [1.0, 4.0, -1.0, -0.5],
    [2.0, 5.0, -2.0, -1.5],
    [3.0, 6.0, -3.0, -2.5],
];

fn assert_installed(ls: &[u8], line: u32) {
    for (q, planes) in INSTALLED.iter().enumerate() {
        for (k, p) in planes.iter().enumerate() {
            assert_eq!(
                f32::from_bits(word(ls, line + 16 * q as u32 + 4 * k as u32)),
                *p
            );
        }
    }
    let links: Vec<u32> = (0..4).map(|k| word(ls, line + 48 + 4 * k)).collect();
    assert_eq!(links, [20 * 32, 1 << 4, 7, (3 << 2) << 4]);
}

/// BVH-cache misses: direct mapped, the pair is fetched and installed transposed in its
/// line (one fetch); 4-way with the pair in way 2, a hit there moves it to the front (no
/// fetch); 4-way without it, the least recent way is evicted and the fetched pair becomes
/// way 0.
#[test]
fn bvh_cache_misses_fetch_install_and_keep_lru_order() {
    let mut text = String::new();
    // direct mapped: a miss
    let (ls, tags, line, misses) = bvh_cache_case("bvh_miss_one", false, [0x1000, 0, 0, 0]);
    assert_eq!((word(&ls, tags), misses), (0x200, 1));
    assert_installed(&ls, line);
    text += "direct mapped, miss:\n";
    text += &quads(&ls, tags, 1);
    text += &quads(&ls, line, 4);
    // 4-way: the pair in way 2
    let (ls, tags, line, misses) =
        bvh_cache_case("bvh_miss_ways", true, [0x1000, 0x1040, 0x200, 0x10c0]);
    let order: Vec<u32> = (0..4).map(|w| word(&ls, tags + 64 * w)).collect();
    assert_eq!(
        (order.as_slice(), misses),
        ([0x200, 0x1000, 0x1040, 0x10c0].as_slice(), 0)
    );
    for (w, t) in order.iter().enumerate() {
        assert_eq!(
            word(&ls, line + 256 * w as u32),
            (t & 0xffff) * 16,
            "way {w}'s line"
        );
    }
    text += "4-way, hit in way 2:\n";
    for w in 0..4 {
        text += &quads(&ls, tags + 64 * w, 1);
        text += &quads(&ls, line + 256 * w, 4);
    }
    // 4-way: not in the set
    let (ls, tags, line, misses) =
        bvh_cache_case("bvh_miss_ways", true, [0x1000, 0x1040, 0x1080, 0x10c0]);
    let order: Vec<u32> = (0..4).map(|w| word(&ls, tags + 64 * w)).collect();
    assert_eq!(
        (order.as_slice(), misses),
        ([0x200, 0x1000, 0x1040, 0x1080].as_slice(), 1)
    );
    assert_installed(&ls, line);
    for w in 1..4u32 {
        assert_eq!(word(&ls, line + 256 * w), (order[w as usize] & 0xffff) * 16);
    }
    text += "4-way, miss:\n";
    for w in 0..4 {
        text += &quads(&ls, tags + 64 * w, 1);
        text += &quads(&ls, line + 256 * w, 4);
    }
    insta::assert_snapshot!(text);
}

/// lru_find and lru_rotate keep their register contracts (`modules/lru.s`' header), each
/// called alone on the set of [`LRU_DRIVER`] with everything but its inputs poisoned two
/// ways: lru_find answers way 2 for way 2's key, lru_rotate of way 2 gives (2, 0, 1, 3).
#[test]
fn lru_routines_keep_their_register_contracts() {
    let mut src = String::from(
        "        .text\n        .global _start\n_start: stop 0x2100\nback:   stop 0x2000\n        .include \"modules/lru.s\"\n        .data\n        .align 4\ntags:\n",
    );
    for way in 0..4 {
        src += &format!("        .long {:#x}, 0, 0, 0\n", 0x1000 + 0x40 * way);
    }
    src += "lines:\n";
    for way in 0..4 {
        for word in 0..16 {
            src += &format!("        .long {:#x}\n", 0x100 * way + word);
        }
    }
    for entry in ["lru_find", "lru_rotate"] {
        let contract = spu_tests::RegisterContract::of_module("modules/lru.s", Some(entry));
        let (spu, ls) = spu_tests::check_register_contract(&contract, |poison| {
            let mut h =
                spu_tests::ModuleHarness::new(&src, "lru_driver.s", MainMemory::zeroed(4096));
            let (tags, lines, back) = (h.sym("tags"), h.sym("lines"), h.sym("back"));
            for (r, v) in [
                (0, back),
                (100, 2),
                (101, tags),
                (102, lines),
                (103, 16),
                (104, 64),
                (116, 0x1080),
            ] {
                h.spu.set_reg(r, [v, 0, 0, 0]);
            }
            poison(&mut h.spu);
            let stop = h.run_at(h.sym(entry), 100_000);
            assert_eq!(stop, spu_isa::machine::StopReason::Stop(0x2000), "{entry}");
            let ls = h.bytes(tags, 64 + 256);
            (h.spu, ls)
        });
        let tag_order: Vec<u32> = (0..4)
            .map(|w| (word(&ls, 16 * w) - 0x1000) / 0x40)
            .collect();
        if entry == "lru_find" {
            assert_eq!(spu.reg(100)[0], 2, "way 2 holds the key");
            assert_eq!(tag_order, [0, 1, 2, 3], "nothing moves");
        } else {
            assert_eq!(tag_order, [2, 0, 1, 3]);
            assert_eq!(
                word(&ls, 64 + 64 + 4 * 5),
                5,
                "way 1 holds the old way 0's line"
            );
        }
    }
}
