//! The numbers "Ray Tracing on the Cell Processor" (Benthin et al. 2006) reports, as data:
//! the one place `spu paper` takes the paper's side of every comparison from.

/// The paper's three test scenes: the columns of its tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PaperScene {
    Erw6,
    Conference,
    Beetle,
}

impl PaperScene {
    pub fn name(self) -> &'static str {
        match self {
            PaperScene::Erw6 => "ERW6",
            PaperScene::Conference => "Conference",
            PaperScene::Beetle => "VW Beetle",
        }
    }

    fn column(self) -> usize {
        self as usize
    }
}

/// The paper's size for every measurement: 1024x1024 primary rays.
pub const PAPER_SIZE: u32 = 1024;

/// Cache sizes of Table 1, in lines.
pub const CACHE_SIZES: [u32; 4] = [128, 256, 512, 1024];

/// Table 1: cache hit rates in %, `[size index][scene]` as (4-way, direct mapped).
const TABLE1_BC: [[(f64, f64); 3]; 4] = [
    [(99.8, 99.4), (95.7, 91.2), (87.6, 84.4)],
    [(99.9, 99.7), (98.0, 94.4), (91.6, 88.3)],
    [(99.9, 99.9), (98.5, 96.9), (93.5, 91.6)],
    [(99.9, 99.9), (98.7, 97.8), (94.1, 93.2)],
];
const TABLE1_TC: [[(f64, f64); 3]; 4] = [
    [(98.1, 96.8), (71.0, 61.5), (45.1, 39.8)],
    [(98.4, 97.4), (80.0, 74.8), (50.9, 45.8)],
    [(98.7, 98.4), (86.7, 82.7), (55.1, 50.4)],
    [(98.7, 98.7), (89.2, 86.5), (57.2, 53.9)],
];

/// Which cache a Table 1 row is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cache {
    Bvh,
    Triangle,
}

/// Table 1: hit rate (%) of a cache of `lines` lines, 4-way (`assoc` 4) or direct mapped.
pub fn table1(cache: Cache, lines: u32, assoc: u32, scene: PaperScene) -> Option<f64> {
    let i = CACHE_SIZES.iter().position(|&s| s == lines)?;
    let (four_way, dm) = match cache {
        Cache::Bvh => TABLE1_BC[i][scene.column()],
        Cache::Triangle => TABLE1_TC[i][scene.column()],
    };
    Some(if assoc == 4 { four_way } else { dm })
}

/// Table 2's rows: per-SPE figures at 2.4 GHz, 256-line caches, blocking DMA.
pub const TABLE2: [(&str, [f64; 3]); 5] = [
    ("traversal steps per packet", [18.73, 55.33, 43.90]),
    ("triangle intersections per packet", [1.47, 5.94, 7.21]),
    ("traversal early exits (%)", [44.0, 40.0, 34.0]),
    ("traversal early hits (%)", [52.0, 52.0, 48.0]),
    ("MRays/s per SPE", [30.08, 6.7, 5.3]),
];

/// Table 3: MRays/s on one 2.4 GHz SPE without and with software hyperthreading.
pub const TABLE3_WITHOUT: [f64; 3] = [30.08, 6.7, 5.3];
pub const TABLE3_WITH: [f64; 3] = [30.1, 7.8, 7.0];
/// The speed-up row, in % as printed.
pub const TABLE3_SPEEDUP_PCT: [f64; 3] = [0.01, 15.7, 33.5];

/// Table 4's rows (simple shading, 64-entry vertex and material caches).
pub const TABLE4: [(&str, [f64; 3]); 4] = [
    ("same triangle probability (%)", [97.18, 88.74, 78.49]),
    ("shading passes per 8x8 packet", [1.005, 1.23, 1.07]),
    ("vertex cache hit (%)", [99.54, 96.11, 89.35]),
    ("material cache hit (%)", [99.99, 98.04, 99.62]),
];

/// The shading modes of Table 5, as `spu render --shade` names them.
pub const SHADE_MODES: [&str; 3] = ["none", "simple", "shadows"];

/// A machine of Table 5: SPEs and clock.
#[derive(Clone, Copy, Debug)]
pub struct Machine {
    pub name: &'static str,
    pub spes: usize,
    pub clock_ghz: f64,
}

pub const MACHINES: [Machine; 4] = [
    Machine {
        name: "2.4 GHz SPE",
        spes: 1,
        clock_ghz: 2.4,
    },
    Machine {
        name: "Single-Cell (8 SPEs, 2.4 GHz)",
        spes: 8,
        clock_ghz: 2.4,
    },
    Machine {
        name: "Dual-Cell (16 SPEs, 2.4 GHz)",
        spes: 16,
        clock_ghz: 2.4,
    },
    Machine {
        name: "PS3-Cell (7 SPEs, 3.2 GHz; extrapolated in the paper)",
        spes: 7,
        clock_ghz: 3.2,
    },
];

/// Table 5: frames per second at 1024x1024, `[mode][machine][scene]`.
pub const TABLE5_FPS: [[[f64; 3]; 4]; 3] = [
    [
        [30.1, 7.8, 7.0],
        [231.4, 57.2, 51.2],
        [430.1, 108.9, 91.4],
        [270.0, 66.7, 59.7],
    ],
    [
        [14.9, 5.1, 3.5],
        [116.3, 38.7, 27.1],
        [222.4, 73.7, 47.1],
        [135.6, 45.2, 31.6],
    ],
    [
        [7.4, 2.6, 1.9],
        [58.1, 20.0, 16.2],
        [110.9, 37.3, 30.6],
        [67.8, 23.2, 18.9],
    ],
];

/// Table 5's baseline, a 2.4 GHz Opteron: fps `[mode][scene]` (for the text, not compared).
pub const TABLE5_X86_FPS: [[f64; 3]; 3] = [[28.1, 8.7, 7.7], [15.3, 6.7, 6.6], [7.2, 3.0, 2.5]];

/// Table 6's rows: KB read per 1024x1024 frame with simple shading, 256-line caches.
pub const TABLE6_KB: [(&str, [f64; 3]); 5] = [
    ("BVH node data", [24.0, 1113.0, 3724.0]),
    ("triangle accel data", [43.0, 2797.0, 4766.0]),
    ("vertex data", [130.0, 1278.0, 4303.0]),
    ("shader data", [0.03, 87.0, 1.53]),
    ("total", [202.0, 5275.0, 12794.0]),
];

/// Figure 2 has no printed numbers; its end points are Table 5's: ray casting on 8 and 16
/// SPEs over one SPE.
pub fn figure2_speedup(spes: usize, scene: PaperScene) -> Option<f64> {
    let one = TABLE5_FPS[0][0][scene.column()];
    let m = MACHINES
        .iter()
        .position(|m| m.spes == spes && m.clock_ghz == 2.4 && spes > 1)?;
    Some(TABLE5_FPS[0][m][scene.column()] / one)
}

/// Column index of a scene in the arrays above.
pub fn col(scene: PaperScene) -> usize {
    scene.column()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_printed_speed_ups_follow_from_the_printed_rates() {
        // Table 3's speed-up row is (with - without) / without; Table 5's 8x/15x are
        // Single-/Dual-Cell over the Opteron: both check that the numbers were typed right
        for s in [PaperScene::Erw6, PaperScene::Conference, PaperScene::Beetle] {
            let c = col(s);
            let pct = 100.0 * (TABLE3_WITH[c] - TABLE3_WITHOUT[c]) / TABLE3_WITHOUT[c];
            assert!((pct - TABLE3_SPEEDUP_PCT[c]).abs() < 2.0, "{s:?} {pct}");
        }
        assert!((TABLE5_FPS[0][1][0] / TABLE5_X86_FPS[0][0] - 8.2).abs() < 0.05);
        assert!((TABLE5_FPS[2][2][2] / TABLE5_X86_FPS[2][2] - 12.2).abs() < 0.05);
        let sum: f64 = TABLE6_KB[..4].iter().map(|(_, v)| v[2]).sum();
        assert!((sum - TABLE6_KB[4].1[2]).abs() < 1.0);
        assert_eq!(
            table1(Cache::Triangle, 256, 1, PaperScene::Beetle),
            Some(45.8)
        );
        assert_eq!(
            table1(Cache::Bvh, 1024, 4, PaperScene::Conference),
            Some(98.7)
        );
        assert_eq!(table1(Cache::Bvh, 64, 4, PaperScene::Conference), None);
        assert!((figure2_speedup(16, PaperScene::Erw6).unwrap() - 430.1 / 30.1).abs() < 1e-9);
        assert_eq!(figure2_speedup(3, PaperScene::Erw6), None);
    }
}
