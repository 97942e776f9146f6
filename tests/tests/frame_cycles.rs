//! Whole frames' cycles pinned: three small frames that together run every kernel module
//! (room primary rays on one SPE with blocking misses; the procedural conference shaded,
//! four packets in flight, 4-way caches; the procedural beetle with shadows, ended early,
//! on four SPEs), each run with the interpreter and the block compiler, which must agree,
//! and their cycle-bearing statistics snapshotted (insta). A kernel change that costs or saves a
//! single cycle anywhere in a frame shows here as a diff; one that is meant to accepts it
//! with `cargo insta review` (or `INSTA_UPDATE=always`) and commits the new snapshot.

use spu_isa::jit::{CodeCache, Engine};
use spu_loader::kernel_abi::{ShadeCounters, SHADE_SHADOWS, SHADE_SIMPLE};
use spu_loader::render::{prepare, Prepared, RenderConfig};
use spu_loader::runtime::FrameRun;
use spu_loader::shading::ShadeMode;
use spu_loader::stats::{FrameSetup, FrameStats};
use std::collections::BTreeSet;
use std::sync::OnceLock;

/// One frame's set-up, as `spu render` takes it.
#[derive(Debug)]
struct Setup {
    scene: &'static str,
    size: u32,
    spes: usize,
    /// 0 = primary rays only, else `SHADE_SIMPLE` or `SHADE_SHADOWS`.
    shade: u32,
    shadow_early: bool,
    assoc: u32,
    sht: u32,
}

/// Renders `setup` with `engine`, as `spu render --scene S --width N --height N --spes P
/// --assoc A --sht H [--shade M --shadow-early on|off]` does with the default caches,
/// lights and latency: through the library's render API.
fn render(scene: &Prepared, setup: &Setup, engine: Engine) -> FrameRun {
    let mode = match setup.shade {
        0 => ShadeMode::None,
        SHADE_SIMPLE => ShadeMode::Simple,
        _ => ShadeMode::Shadows,
    };
    let mut config = RenderConfig {
        width: setup.size,
        height: setup.size,
        spes: setup.spes,
        threads: 2,
        assoc: setup.assoc,
        sht: setup.sht,
        kernel: RenderConfig::kernel_for(false, mode),
        engine,
        max_cycles: 50_000_000_000,
        ..RenderConfig::new(setup.scene)
    };
    config.shading.mode = mode;
    config.shading.shadow_early = setup.shadow_early;
    spu_loader::render::render(scene, &config, &CodeCache::default())
        .unwrap()
        .run
}

/// The frame's cycle-bearing statistics as text, one figure a line so that a diff names
/// what moved: the `--stats` figures (without the host-dependent share run compiled) and
/// the raw counters behind them.
fn statistics(run: &FrameRun, setup: &Setup) -> String {
    let stats = FrameStats::new(
        run,
        &FrameSetup {
            scene: setup.scene,
            width: setup.size,
            height: setup.size,
            clock_ghz: 2.4,
        },
        None,
    );
    let mut s = String::new();
    let mut line = |text: String| {
        s.push_str(&text);
        s.push('\n');
    };
    line(format!("frame_cycles: {}", run.frame_cycles));
    for (i, spu) in run.spus.iter().enumerate() {
        line(format!(
            "spu {i}: cycles {}, instructions {}, tiles {}",
            spu.cycles, spu.instructions, spu.tiles
        ));
    }
    line(format!(
        "kernel counters (all SPUs): {:#?}",
        run.kernel_stats()
    ));
    type Count = fn(&ShadeCounters) -> u64;
    let shade: [(&str, Count); 10] = [
        ("packets with a hit", |c| c.groups.0),
        ("of them on one triangle", |c| c.same.0),
        ("passes", |c| c.passes.0),
        ("packets", |c| c.packets.0),
        ("vertex lookups (the host counts 3 a record)", |c| {
            c.vertex_lookups.0
        }),
        ("vertex misses", |c| c.vertex_misses.0),
        ("material lookups", |c| c.material_lookups.0),
        ("material misses", |c| c.material_misses.0),
        ("triangle records looked up", |c| c.triangle_lookups.0),
        ("triangle records fetched", |c| c.triangle_misses.0),
    ];
    if !run.shade_counters.is_empty() {
        line("shading counters (all SPUs):".into());
        for (name, count) in shade {
            let total: u64 = run.shade_counters.iter().map(count).sum();
            line(format!("  {name}: {total}"));
        }
    }
    line(format!("shadow rays: {}", run.shadow_rays));
    line("DMA bytes by region (read, written):".into());
    for (region, read, written) in &run.traffic {
        line(format!("  {region}: {read}, {written}"));
    }
    line(format!("table2: {:#?}", stats.table2));
    line(format!("caches: {:#?}", stats.caches));
    line(format!("table4: {:#?}", stats.table4));
    line(format!("table6: {:#?}", stats.table6));
    line(format!("traversal: {:#?}", stats.traversal));
    line(format!("intersection: {:#?}", stats.intersection));
    line(format!("shading: {:#?}", stats.shading));
    line(format!("profile totals: {:#?}", stats.totals));
    s
}

/// The kernel labels that have run in `run`, by name.
fn executed_labels(run: &FrameRun) -> BTreeSet<String> {
    let profile = run.profile.as_ref().expect("the timing model is on");
    run.symbols
        .iter()
        .filter(|(_, addr)| profile.get(*addr).is_some_and(|s| s.executions > 0))
        .map(|(name, _)| name.clone())
        .collect()
}

/// What a frame leaves for the tests: its statistics and the kernel labels that ran.
struct Outcome {
    text: String,
    labels: BTreeSet<String>,
}

/// Runs `setup` under both engines, checks they agree on everything the frame produced
/// (image, statistics, the profile address by address), and returns the statistics with
/// the set-up they came from.
fn frame(setup: &Setup) -> Outcome {
    let scene = prepare(setup.scene).unwrap();
    let interp = render(&scene, setup, Engine::Interp);
    let text = statistics(&interp, setup);
    if Engine::SUPPORTED {
        let jit = render(&scene, setup, Engine::Jit);
        assert!(
            jit.spus.iter().all(|s| s.compiled_instructions > 0),
            "the block compiler ran nothing on some SPU"
        );
        assert_eq!(text, statistics(&jit, setup), "interp against jit");
        assert!(interp.frame_buffer == jit.frame_buffer, "images differ");
        assert!(interp.colour_buffer == jit.colour_buffer, "colours differ");
        let per_pc = |run: &FrameRun| -> Vec<String> {
            let profile = run.profile.as_ref().unwrap();
            profile
                .addresses()
                .map(|(pc, s)| format!("{pc:#x}: {s:?}"))
                .collect()
        };
        assert!(per_pc(&interp) == per_pc(&jit), "profiles differ");
    }
    // Each frame reaches the paths it is here for.
    let k = interp.kernel_stats();
    assert!(
        k.bvh_cache_misses > 0 && k.triangle_cache_misses > 0,
        "{k:?}"
    );
    assert!(
        interp.spus.iter().all(|s| s.tiles > 0),
        "an SPU took no tile"
    );
    if setup.shade != 0 {
        let all = ShadeCounters::sum(&interp.shade_counters);
        assert!(
            all.vertex_misses.0 > 0 && all.material_misses.0 > 0,
            "vertex and material misses"
        );
    }
    assert_eq!(interp.shadow_rays > 0, setup.shade == SHADE_SHADOWS);
    Outcome {
        text: format!("{setup:?}\n{text}"),
        labels: executed_labels(&interp),
    }
}

fn room() -> &'static Outcome {
    static ROOM: OnceLock<Outcome> = OnceLock::new();
    ROOM.get_or_init(|| {
        frame(&Setup {
            scene: "room",
            size: 128,
            spes: 1,
            shade: 0,
            shadow_early: false,
            assoc: 1,
            sht: 1,
        })
    })
}

fn conference() -> &'static Outcome {
    static CONFERENCE: OnceLock<Outcome> = OnceLock::new();
    CONFERENCE.get_or_init(|| {
        frame(&Setup {
            scene: "conference",
            size: 64,
            spes: 1,
            shade: SHADE_SIMPLE,
            shadow_early: false,
            assoc: 4,
            sht: 4,
        })
    })
}

fn beetle() -> &'static Outcome {
    static BEETLE: OnceLock<Outcome> = OnceLock::new();
    BEETLE.get_or_init(|| {
        frame(&Setup {
            scene: "beetle",
            size: 128,
            spes: 4,
            shade: SHADE_SHADOWS,
            shadow_early: true,
            assoc: 1,
            sht: 4,
        })
    })
}

/// Primary rays with blocking misses on one SPE: the one-context miss paths.
#[test]
fn room_primary_rays_on_one_spe() {
    insta::assert_snapshot!(room().text);
}

/// Simple shading with four packets in flight and 4-way caches: the SHT switch, the LRU
/// sets, the shading caches.
#[test]
fn conference_simple_shading_sht_4_four_way() {
    insta::assert_snapshot!(conference().text);
}

/// Shadow packets (ended early where every ray is occluded) on four SPEs.
#[test]
fn beetle_shadows_on_four_spes() {
    insta::assert_snapshot!(beetle().text);
}

/// The code labels of each kernel module that one of the frames must run; every module
/// of `kernels/modules/` but the data is here, so a new module needs a frame that runs it.
/// Not here: `shade_end` (the end of the code, not an instruction) and `tri_miss`, the
/// test loop's fallback for a triangle the leaf's prefetch pass did not leave in the cache,
/// which a leaf's consecutive triangles never miss in these caches.
const MODULE_ENTRIES: &[(&str, &[&str])] = &[
    (
        "bvh_cache.s",
        &["bvh_miss_one", "bvh_miss_ways", "bvh_resume"],
    ),
    (
        "frame.s",
        &[
            "_start",
            "new_tile",
            "next_tile",
            "no_tiles",
            "claim_ahead",
            "packet_start",
            "have_packet",
        ],
    ),
    ("frame_done.s", &["frame_done"]),
    ("lru.s", &["lru_find", "lru_rotate"]),
    ("output.s", &["packet_done"]),
    ("raygen.s", &["packet_loop"]),
    // Reflected rays run in reflect frames only, which none of the pinned frames is (their
    // own frames: runtime_frames' every variant, tools' shade_cli, reflect_module).
    ("reflect.s", &[]),
    ("shade.s", &["shade_packet"]),
    // The shading module's jobs behind shade_packet carry local labels only: they run
    // within it, and the shading counters of the snapshots count what they did.
    ("shade_area.s", &[]),
    ("shade_cache.s", &["sh_vertex_miss", "sh_tri_miss"]),
    // The gather variant's slow path (EXT_GATHER) runs in its own frames only
    // (isa_extensions' gather kernel, shade_module's gather module).
    ("shade_gather.s", &[]),
    ("shade_iset.s", &[]),
    ("shade_iset_slow.s", &[]),
    ("shade_light.s", &[]),
    ("shadow.s", &["shadow_rays", "shadow_done", "shadow_leaf"]),
    (
        "sht.s",
        &["bvh_miss_sht", "suspend", "switch_to", "sched_next"],
    ),
    (
        "traverse.s",
        &["trav", "first_changed", "slow", "set_first"],
    ),
    ("tri_cache.s", &["leaf_resume"]),
    (
        "triangle.s",
        &[
            "leaf",
            "leaf_probe",
            "leaf_cull",
            "tri_loop",
            "ray_loop",
            "tri_next",
            "pop",
        ],
    ),
];

#[test]
fn every_kernel_module_runs_in_one_of_the_frames() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../kernels/modules");
    let mut modules: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".s") && name != "data.s")
        .collect();
    modules.sort();
    let listed: Vec<String> = MODULE_ENTRIES.iter().map(|(m, _)| m.to_string()).collect();
    assert_eq!(modules, listed, "kernels/modules against MODULE_ENTRIES");
    let ran: BTreeSet<&String> = [room(), conference(), beetle()]
        .iter()
        .flat_map(|o| &o.labels)
        .collect();
    let missing: Vec<String> = MODULE_ENTRIES
        .iter()
        .flat_map(|(module, labels)| {
            labels
                .iter()
                .filter(|l| !ran.contains(&l.to_string()))
                .map(move |l| format!("{module}: {l}"))
        })
        .collect();
    assert!(missing.is_empty(), "never ran in any frame: {missing:?}");
}
