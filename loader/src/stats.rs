//! The statistics of one rendered frame as typed data: what `spu render --stats` writes and
//! what `spu paper --collect` reads back. One struct per JSON object, so the keys are
//! spelled once and reading a file checks its shape.
//!
//! Keys added later get `#[serde(default)]` so that stats files written before them still
//! load.

use crate::kernel_abi::{INTERSECTION, SHADING, TRAVERSAL};
use crate::runtime::FrameRun;
use serde::{Deserialize, Serialize};
use spu_isa::profile::RangeSum;
use spu_isa::timing::StallCause;

/// A frame's statistics, the top-level object of a `--stats` file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub clock_ghz: f64,
    /// Cycles of the slowest SPU.
    pub frame_cycles: u64,
    pub rays: u64,
    pub mrays_per_sec: f64,
    pub spus: Vec<SpuStats>,
    /// Present when the frame was compared with the host reference.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validation: Option<Validation>,
    /// The paper's Table 2 figures.
    pub table2: Table2,
    /// The kernel configuration: packets in flight, associativity, cache sizes, DMA latency.
    #[serde(default)]
    pub config: crate::runtime::KernelConfig,
    /// Hit rates per lookup of both caches (the paper's Table 1).
    #[serde(default)]
    pub caches: CacheStats,
    /// The traversal code (`trav` .. `leaf`); null without the timing model.
    pub traversal: Option<SectionStats>,
    /// The intersection code (`leaf` .. `packet_done`); null without the timing model.
    pub intersection: Option<SectionStats>,
    /// The timing model's totals over all SPUs; null without the timing model.
    pub totals: Option<ProfileTotals>,
    /// Frames per second at `clock_ghz` (beside `mrays_per_sec`, the paper's Table 5).
    #[serde(default)]
    pub fps: f64,
    /// Rays cast, by kind.
    #[serde(default)]
    pub rays_by_kind: RaysByKind,
    /// The paper's Table 4 (shaded frames only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table4: Option<Table4>,
    /// The paper's Table 6: kilobytes per frame by main-memory region, counted by the MFC.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table6: Option<Table6>,
    /// The shading code (`shade_packet` .. `shade_end`, shaded frames with the timing model).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shading: Option<SectionStats>,
    /// `--shade reflect`: per bounce, the reflected rays and what tracing them took.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reflections: Vec<BounceStats>,
}

/// Rays cast in a frame, by kind.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RaysByKind {
    pub primary: u64,
    pub shadow: u64,
    /// Reflected rays, all bounces (per bounce: [`FrameStats::reflections`]); absent from
    /// frames that reflect nothing, whose files stay as they were.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub reflected: u64,
}

fn is_zero(n: &u64) -> bool {
    *n == 0
}

/// One reflection bounce of a reflect frame (`modules/reflect.s`'s counters): its rays,
/// how full its packets are, and its traversal's work, cache hit rates and DMA bytes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BounceStats {
    /// 1 for the first reflection.
    pub bounce: u32,
    pub rays: u64,
    /// Of them, the rays that hit a triangle.
    pub hits: u64,
    /// Primary packets with any ray of the bounce (its reflection packets).
    pub packets: u64,
    /// Rays per reflection packet over its 64 (the packets' coherence), percent.
    pub active_ray_percent: f64,
    pub traversal_steps: u64,
    pub leaves: u64,
    /// Hit rates per lookup of the BVH cache (a step's pair) and the triangle cache,
    /// percent.
    pub bvh_hit_percent: f64,
    pub triangle_hit_percent: f64,
    /// Bytes the bounce's cache misses fetched (a 64-byte line each).
    pub dma_bytes: u64,
}

impl BounceStats {
    /// From the frame's per-bounce counters.
    pub fn from_counters(counters: &[crate::kernel_abi::ReflectCounters]) -> Vec<BounceStats> {
        let percent = |part: u64, whole: u64| {
            if whole == 0 {
                0.0
            } else {
                rounded(100.0 * part as f64 / whole as f64, 2)
            }
        };
        counters
            .iter()
            .enumerate()
            .map(|(k, c)| BounceStats {
                bounce: k as u32 + 1,
                rays: c.rays.0,
                hits: c.hits.0,
                packets: c.packets.0,
                active_ray_percent: percent(c.rays.0, 64 * c.packets.0),
                traversal_steps: c.steps.0,
                leaves: c.leaves.0,
                bvh_hit_percent: percent(c.steps.0.saturating_sub(c.bvh_misses.0), c.steps.0),
                triangle_hit_percent: percent(
                    c.triangle_lookups.0.saturating_sub(c.triangle_misses.0),
                    c.triangle_lookups.0,
                ),
                dma_bytes: 64 * (c.bvh_misses.0 + c.triangle_misses.0),
            })
            .collect()
    }
}

/// The shading module's i-set and cache figures (the paper's Table 4). Keys missing from a
/// file read as 0.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Table4 {
    /// Intersection packets (4 rays, at least one hit) whose rays all hit one triangle.
    pub same_triangle_pct: f64,
    /// Shading passes (distinct materials) per 8x8 packet.
    pub passes_per_packet: f64,
    pub vertex_cache_hit_pct: f64,
    pub material_cache_hit_pct: f64,
    /// Triangle records shading found in the traversal's triangle cache.
    pub triangle_record_hit_pct: f64,
}

/// Kilobytes (1024 bytes) per frame moved by the MFCs, per main-memory region. Keys
/// missing from a file read as 0.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Table6 {
    pub bvh_nodes_kb: f64,
    pub triangle_records_kb: f64,
    pub vertex_data_kb: f64,
    pub shader_data_kb: f64,
    /// The sum of the four reads above (the paper's total).
    pub total_read_kb: f64,
    /// Written: the 32-bit colour frame buffer (4096 KB at 1024x1024).
    pub frame_buffer_written_kb: f64,
    /// Written: the packet result blocks (hit and t per ray, for validation; the eye-light
    /// grey too in an unshaded frame).
    pub result_blocks_written_kb: f64,
}

impl Table4 {
    /// From the shading module's counters summed over the SPUs.
    pub fn new(counters: &[crate::runtime::ShadeCounters]) -> Option<Table4> {
        if counters.is_empty() {
            return None;
        }
        let sum = crate::kernel_abi::ShadeCounters::sum(counters);
        let pct = |x: u64, of: u64| {
            if of > 0 {
                rounded(100.0 * x as f64 / of as f64, 2)
            } else {
                0.0
            }
        };
        let (groups, same, passes, packets) =
            (sum.groups.0, sum.same.0, sum.passes.0, sum.packets.0);
        let (vmiss, mlook, mmiss, tlook, tmiss) = (
            sum.vertex_misses.0,
            sum.material_lookups.0,
            sum.material_misses.0,
            sum.triangle_lookups.0,
            sum.triangle_misses.0,
        );
        let vlook = 3 * tlook;
        Some(Table4 {
            same_triangle_pct: pct(same, groups),
            passes_per_packet: if packets > 0 {
                rounded(passes as f64 / packets as f64, 3)
            } else {
                0.0
            },
            vertex_cache_hit_pct: pct(vlook - vmiss.min(vlook), vlook),
            material_cache_hit_pct: pct(mlook - mmiss.min(mlook), mlook),
            triangle_record_hit_pct: pct(tlook - tmiss.min(tlook), tlook),
        })
    }
}

impl Table6 {
    /// From the per-region traffic of a frame (`runtime::traffic_regions`' names).
    pub fn new(traffic: &[(String, u64, u64)]) -> Option<Table6> {
        let find = |name: &str| traffic.iter().find(|(n, _, _)| n == name);
        let kb = |name: &str, written: bool| {
            find(name).map_or(0.0, |(_, r, w)| {
                rounded((if written { *w } else { *r }) as f64 / 1024.0, 2)
            })
        };
        find("colour_frame_buffer")?;
        let (nodes, tris, verts, mats) = (
            kb("bvh_nodes", false),
            kb("triangle_records", false),
            kb("vertices", false),
            kb("materials", false),
        );
        Some(Table6 {
            bvh_nodes_kb: nodes,
            triangle_records_kb: tris,
            vertex_data_kb: verts,
            shader_data_kb: mats,
            total_read_kb: rounded(nodes + tris + verts + mats, 2),
            frame_buffer_written_kb: kb("colour_frame_buffer", true),
            result_blocks_written_kb: kb("result_blocks", true),
        })
    }
}

/// What one SPU did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpuStats {
    pub cycles: u64,
    pub instructions: u64,
    pub tiles: u64,
    /// Of `instructions`, those run by compiled blocks (0 with the interpreter).
    #[serde(default)]
    pub compiled_instructions: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    pub pixels: usize,
    pub mismatches: usize,
    /// Shaded frames: pixels whose colour differs from the reference shading by more than
    /// `shading::COLOUR_TOLERANCE` in a channel.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour_mismatches: Option<usize>,
    /// `--shade shadows`: pixels beyond the tolerance that take the colour of a shadow ray
    /// grazing an occluder's edge (within 2^-16 barycentric), which either outcome gives
    /// (`loader::reference::Reference::shadow_grazes`); not counted as mismatches.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shadow_edge_pixels: Option<usize>,
}

/// Per-packet averages, percentages and per-SPU speed, as in the paper's Table 2.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Table2 {
    pub traversal_steps_per_packet: f64,
    pub pair_steps_per_packet: f64,
    pub triangle_tests_per_packet: f64,
    pub triangles_culled_per_packet: f64,
    pub early_exits_pct: f64,
    pub early_hits_pct: f64,
    pub bvh_cache_hit_pct: f64,
    pub bvh_cache_hit_per_node_pct: f64,
    pub triangle_cache_hit_pct: f64,
    pub mrays_per_sec_per_spu: f64,
}

/// Lookups, misses (fetches) and hits per lookup of the BVH-node and triangle caches. A
/// BVH lookup is one traversal step (both children of a node); a triangle lookup, one
/// triangle of a leaf the packet visits.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CacheStats {
    pub bvh_lookups: u64,
    pub bvh_misses: u64,
    pub bvh_hit_pct: f64,
    pub triangle_lookups: u64,
    pub triangle_misses: u64,
    pub triangle_hit_pct: f64,
}

impl CacheStats {
    fn new(run: &FrameRun) -> Self {
        let k = run.kernel_stats();
        let hit = |misses: u64, lookups: u64| {
            if lookups > 0 {
                rounded(100.0 * (1.0 - misses as f64 / lookups as f64), 2)
            } else {
                0.0
            }
        };
        CacheStats {
            bvh_lookups: k.bvh_lookups,
            bvh_misses: k.bvh_cache_misses,
            bvh_hit_pct: hit(k.bvh_cache_misses, k.bvh_lookups),
            triangle_lookups: k.triangle_lookups,
            triangle_misses: k.triangle_cache_misses,
            triangle_hit_pct: hit(k.triangle_cache_misses, k.triangle_lookups),
        }
    }
}

/// Stall cycles by cause, in [`StallCause::NAMES`] order.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stalls {
    pub dep: u64,
    pub branch: u64,
    pub hint: u64,
    pub dp: u64,
    pub chan: u64,
    pub fetch: u64,
}

impl Stalls {
    fn from_array(a: &[u64; spu_isa::timing::STALL_CLASSES]) -> Self {
        // the field order above is the index order of the timing model's causes
        debug_assert_eq!(
            StallCause::NAMES,
            ["dep", "branch", "hint", "dp", "chan", "fetch"]
        );
        Stalls {
            dep: a[0],
            branch: a[1],
            hint: a[2],
            dp: a[3],
            chan: a[4],
            fetch: a[5],
        }
    }
}

/// CPI, instructions, cycles and stalls of the code between two kernel labels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SectionStats {
    pub from: String,
    pub to: String,
    pub instructions: u64,
    pub instructions_without_nops: u64,
    pub cycles: u64,
    pub cpi: f64,
    pub cpi_without_nops: f64,
    pub dual_issue_pct: f64,
    pub stalls: Stalls,
}

/// Dependency stall cycles by the producing instruction's class, in IBM's report order.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct DependencyByUnit {
    pub FX2: u64,
    pub SHUF: u64,
    pub FX3: u64,
    pub LS: u64,
    pub BR: u64,
    pub SPR: u64,
    pub LNOP: u64,
    pub NOP: u64,
    pub FXB: u64,
    pub FP6: u64,
    pub FP7: u64,
    pub FPD: u64,
}

/// The timing model's totals (see `spu_isa::profile::Totals`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProfileTotals {
    pub cycles: u64,
    pub instructions: u64,
    pub instructions_without_nops: u64,
    /// Null when no instruction ran.
    pub cpi: Option<f64>,
    pub cpi_without_nops: Option<f64>,
    pub single_cycles: u64,
    pub dual_cycles: u64,
    pub branches_taken: u64,
    pub branches_not_taken: u64,
    pub branch_misses: u64,
    pub hints: u64,
    pub hint_hits: u64,
    pub pair_dependency: u64,
    pub ls_contention: u64,
    pub dma_contention: u64,
    pub idle_cycles: u64,
    pub spus: u32,
    pub stall: Stalls,
    pub dependency_by_unit: DependencyByUnit,
}

/// `x` rounded to `decimals` places exactly as `format!("{x:.N}")` prints it, so the file
/// shows the figure at the precision it means.
pub fn rounded(x: f64, decimals: usize) -> f64 {
    if !x.is_finite() {
        return x;
    }
    format!("{x:.decimals$}").parse().unwrap_or(x)
}

fn finite(x: f64, decimals: usize) -> Option<f64> {
    x.is_finite().then(|| rounded(x, decimals))
}

impl ProfileTotals {
    pub fn new(t: &spu_isa::profile::Totals) -> Self {
        use spu_isa::profile::UNITS;
        let by_unit = |name: &str| {
            UNITS
                .iter()
                .find(|u| spu_isa::profile::unit_name(**u) == name)
                .map_or(0, |u| t.dep_by_unit[*u as usize])
        };
        ProfileTotals {
            cycles: t.cycles,
            instructions: t.instructions,
            instructions_without_nops: t.instructions - t.nops,
            cpi: finite(t.cpi(), 4),
            cpi_without_nops: finite(t.cpi_without_nops(), 4),
            single_cycles: t.single_cycles(),
            dual_cycles: t.dual_cycles,
            branches_taken: t.branches_taken,
            branches_not_taken: t.branches_not_taken,
            branch_misses: t.branch_misses,
            hints: t.hints,
            hint_hits: t.hint_hits,
            pair_dependency: t.pair_dependency,
            ls_contention: t.ls_contention,
            dma_contention: t.dma_contention,
            idle_cycles: t.idle_cycles,
            spus: t.spus,
            stall: Stalls::from_array(&t.stall),
            dependency_by_unit: DependencyByUnit {
                FX2: by_unit("FX2"),
                SHUF: by_unit("SHUF"),
                FX3: by_unit("FX3"),
                LS: by_unit("LS"),
                BR: by_unit("BR"),
                SPR: by_unit("SPR"),
                LNOP: by_unit("LNOP"),
                NOP: by_unit("NOP"),
                FXB: by_unit("FXB"),
                FP6: by_unit("FP6"),
                FP7: by_unit("FP7"),
                FPD: by_unit("FPD"),
            },
        }
    }
}

/// What a frame was rendered as, for [`FrameStats::new`].
#[derive(Clone, Debug)]
pub struct FrameSetup<'a> {
    pub scene: &'a str,
    pub width: u32,
    pub height: u32,
    pub clock_ghz: f64,
}

impl FrameStats {
    /// The statistics of a finished frame, with its comparison with the reference where
    /// there was one ([`crate::render::FrameResult::stats`] makes both).
    pub fn new(run: &FrameRun, setup: &FrameSetup, validation: Option<Validation>) -> Self {
        let FrameSetup {
            scene,
            width,
            height,
            clock_ghz,
        } = *setup;
        let rays = width as u64 * height as u64;
        let seconds = run.frame_cycles as f64 / (clock_ghz * 1e9);
        let mrays_per_sec = if seconds > 0.0 {
            rays as f64 / seconds / 1e6
        } else {
            0.0
        };
        FrameStats {
            scene: scene.to_string(),
            width,
            height,
            clock_ghz,
            frame_cycles: run.frame_cycles,
            rays,
            mrays_per_sec: rounded(mrays_per_sec, 3),
            spus: run
                .spus
                .iter()
                .map(|s| SpuStats {
                    cycles: s.cycles,
                    instructions: s.instructions,
                    tiles: s.tiles,
                    compiled_instructions: s.compiled_instructions,
                })
                .collect(),
            validation,
            table2: Table2::new(run, rays, clock_ghz),
            config: run.config.clone(),
            caches: CacheStats::new(run),
            traversal: section(run, TRAVERSAL.from, TRAVERSAL.to),
            intersection: section(run, INTERSECTION.from, INTERSECTION.to),
            totals: run.profile.as_ref().map(|p| ProfileTotals::new(&p.totals)),
            fps: if seconds > 0.0 {
                rounded(1.0 / seconds, 3)
            } else {
                0.0
            },
            rays_by_kind: RaysByKind {
                primary: rays,
                shadow: run.shadow_rays,
                reflected: run.reflect_counters.iter().map(|c| c.rays.0).sum(),
            },
            reflections: BounceStats::from_counters(&run.reflect_counters),
            table4: Table4::new(&run.shade_counters),
            table6: Table6::new(&run.traffic),
            shading: if run.shade_counters.is_empty() {
                None
            } else {
                section(run, SHADING.from, SHADING.to)
            },
        }
    }

    /// The file's text: pretty JSON with a final newline.
    pub fn to_json(&self) -> String {
        let mut s = serde_json::to_string_pretty(self).expect("plain data serialises");
        s.push('\n');
        s
    }

    pub fn from_json(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| e.to_string())
    }
}

impl Table2 {
    fn new(run: &FrameRun, rays: u64, clock_ghz: f64) -> Self {
        let k = run.kernel_stats();
        let per = |x: u64| {
            let v = if k.packets > 0 {
                x as f64 / k.packets as f64
            } else {
                0.0
            };
            rounded(v, 2)
        };
        let pct = |x: u64, of: u64| {
            if of > 0 {
                100.0 * x as f64 / of as f64
            } else {
                0.0
            }
        };
        let cycles_per_spu = run.spus.iter().map(|s| s.cycles).max().unwrap_or(0);
        let per_spu_mrays = if cycles_per_spu > 0 {
            rays as f64
                / run.spus.len().max(1) as f64
                / (cycles_per_spu as f64 / (clock_ghz * 1e9))
                / 1e6
        } else {
            0.0
        };
        let lookups = if k.bvh_lookups > 0 {
            k.bvh_lookups
        } else {
            k.traversal_steps
        };
        Table2 {
            traversal_steps_per_packet: per(k.traversal_steps),
            pair_steps_per_packet: per(lookups),
            triangle_tests_per_packet: per(k.triangle_tests),
            triangles_culled_per_packet: per(k.triangles_culled),
            early_exits_pct: rounded(pct(k.early_exits, k.traversal_steps), 1),
            early_hits_pct: rounded(pct(k.early_hits, k.traversal_steps), 1),
            bvh_cache_hit_pct: rounded(100.0 - pct(k.bvh_cache_misses, lookups), 1),
            bvh_cache_hit_per_node_pct: rounded(
                100.0 - pct(k.bvh_cache_misses, k.traversal_steps),
                1,
            ),
            triangle_cache_hit_pct: rounded(
                100.0 - pct(k.triangle_cache_misses, k.triangle_lookups),
                1,
            ),
            mrays_per_sec_per_spu: rounded(per_spu_mrays, 2),
        }
    }
}

/// CPI, instructions, cycles and stalls of the code between two kernel labels; `None`
/// without a profile or when a label is missing.
pub fn section(run: &FrameRun, from: &str, to: &str) -> Option<SectionStats> {
    let symbol = |name: &str| run.symbols.iter().find(|(n, _)| n == name).map(|(_, a)| *a);
    let (Some(profile), Some(a), Some(b)) = (&run.profile, symbol(from), symbol(to)) else {
        return None;
    };
    let r: RangeSum = profile.range_totals(a, b);
    // IBM's simulator counts nop, lnop and hints apart: the CPI without them is the
    // figure to compare, the pairing nops of scheduled code would flatter it
    let nops: u64 = profile
        .addresses()
        .filter(|(pc, _)| (a..b).contains(pc))
        .filter(|(pc, _)| {
            let word = run
                .kernel_image
                .get(*pc as usize..*pc as usize + 4)
                .map_or(0, |w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
            let op = spu_isa::codec::decode(word).op;
            use spu_isa::table::Op;
            spu_isa::analysis::is_nop(op) || matches!(op, Op::Hbr | Op::Hbra | Op::Hbrr)
        })
        .map(|(_, s)| s.executions)
        .sum();
    let real = r.executions - nops.min(r.executions);
    Some(SectionStats {
        from: from.to_string(),
        to: to.to_string(),
        instructions: r.executions,
        instructions_without_nops: real,
        cycles: r.cycles,
        cpi: rounded(r.cpi(), 3),
        cpi_without_nops: rounded(
            if real > 0 {
                r.cycles as f64 / real as f64
            } else {
                0.0
            },
            3,
        ),
        // both halves of a pair count a dual issue: the share of cycles that issue two
        dual_issue_pct: rounded(
            if r.cycles > 0 {
                50.0 * r.dual as f64 / r.cycles as f64
            } else {
                0.0
            },
            1,
        ),
        stalls: Stalls::from_array(&r.stall),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_matches_the_printed_figure() {
        assert_eq!(rounded(11.0999, 2), 11.1);
        assert_eq!(rounded(2.0 / 3.0, 3), 0.667);
        assert_eq!(rounded(0.125, 2).to_string(), format!("{:.2}", 0.125_f64));
        assert!(rounded(f64::NAN, 2).is_nan());
    }

    #[test]
    fn a_file_without_a_profile_or_validation_loads_and_keeps_its_shape() {
        let text = r#"{"scene": "room", "width": 8, "height": 8, "clock_ghz": 3.2,
            "frame_cycles": 100, "rays": 64, "mrays_per_sec": 2.048,
            "spus": [{"cycles": 100, "instructions": 50, "tiles": 1}],
            "table2": {"traversal_steps_per_packet": 1.5, "pair_steps_per_packet": 1,
              "triangle_tests_per_packet": 0, "triangles_culled_per_packet": 0,
              "early_exits_pct": 0, "early_hits_pct": 0, "bvh_cache_hit_pct": 100,
              "bvh_cache_hit_per_node_pct": 100, "triangle_cache_hit_pct": 100,
              "mrays_per_sec_per_spu": 2.05},
            "traversal": null, "intersection": null, "totals": null}"#;
        let stats = FrameStats::from_json(text).unwrap();
        assert_eq!(stats.frame_cycles, 100);
        assert_eq!(stats.table2.pair_steps_per_packet, 1.0);
        assert!(stats.validation.is_none() && stats.totals.is_none());
        let again = FrameStats::from_json(&stats.to_json()).unwrap();
        assert_eq!(again, stats);
        assert!(!stats.to_json().contains("validation"));
    }

    #[test]
    fn a_truncated_file_is_an_error() {
        let err = FrameStats::from_json(r#"{"scene": "room", "width": 8"#).unwrap_err();
        assert!(err.contains("EOF") || err.contains("missing"), "{err}");
    }
}
