//! The SPU refit (`kernels/refit.s`): the host lays out a staged scene's refit as work items
//! once per topology ([`RefitPlan`]), and a gang of 1 to 16 SPEs, sharing the items through
//! an atomic counter, streams the frame's vertex and node chunks with double-buffered DMA
//! lists and writes the node bounds bottom-up ([`run`]). The result is [`crate::refit`]'s
//! host refit bit for bit; [`run`] checks it against the staged scene's nodes.
//!
//! # Work items
//!
//! Nodes are grouped by height (leaves 0; an inner node one above its higher child): the
//! leaves in triangle order, so that neighbouring leaves gather neighbouring corners, then
//! each height's inner nodes in index order. An item is up to [`MAX_NODES`] nodes of one
//! height with at most [`MAX_ELEMENTS`] elements to fold (a leaf: three corners per triangle;
//! an inner node: its child pair), so one 2 KB block holds its header, its nodes, the DMA
//! list gathering its corners (16 bytes of each vertex record) or child pairs (one 64-byte
//! line each) and the DMA list scattering its node records. Items of a height wait for every
//! item of the height below through a done counter per height.

use crate::frame::SCENE_BASE;
use crate::layout::{StagedScene, NODE_SIZE, VERTEX_SIZE};
use crate::runtime::{Program, QUANTUM_CYCLES, STOP_DONE};
use spu_isa::jit::{CodeCache, Engine};

/// The kernel's source.
pub const SOURCE: &str = include_str!("../../kernels/refit.s");

/// Nodes per work item.
pub const MAX_NODES: usize = 128;
/// Points or boxes an item folds (341 triangles' corners).
pub const MAX_ELEMENTS: usize = 1024;
/// Offset of the node entries in an item's block (after the header's three quadwords).
pub const ENTRIES: usize = 48;
/// Local-store bytes for the largest item's block.
pub const ITEM_BYTES: usize =
    (ENTRIES + MAX_NODES * 16 + MAX_ELEMENTS * 8 + MAX_NODES * 8).div_ceil(128) * 128;
/// Local-store bytes for an item's gathered points (16 bytes each) or child pairs (64).
pub const DATA_BYTES: usize = if MAX_ELEMENTS * 16 > MAX_NODES * 64 {
    MAX_ELEMENTS * 16
} else {
    MAX_NODES * 64
}
.div_ceil(128)
    * 128;
/// Local-store bytes for an item's node records.
pub const OUT_BYTES: usize = (MAX_NODES * NODE_SIZE).div_ceil(128) * 128;
/// Bytes of a height's row of done counters: a quadword per SPE.
const DONE_ROW: usize = 16 * 16;

/// The symbols the kernel is assembled with: its buffers' sizes and item offsets, from
/// the constants above.
pub fn defines() -> Vec<(&'static str, i64)> {
    vec![
        ("REFIT_ITEM_BYTES", ITEM_BYTES as i64),
        ("REFIT_DATA_BYTES", DATA_BYTES as i64),
        ("REFIT_OUT_BYTES", OUT_BYTES as i64),
    ]
}

/// The assembled refit program.
pub fn program() -> Result<Program, String> {
    crate::runtime::assemble_kernel_with(SOURCE, "kernels/refit.s", &defines())
}

/// One work item: nodes of one height.
#[derive(Clone, Debug, PartialEq)]
struct Item {
    height: usize,
    nodes: Vec<usize>,
}

/// A staged scene's refit laid out for the SPEs: the items in claim order (heights upward).
#[derive(Clone, Debug, PartialEq)]
pub struct RefitPlan {
    items: Vec<Item>,
    /// Items of each height.
    per_height: Vec<u32>,
}

impl RefitPlan {
    /// The items refitting `staged`'s nodes. Refuses a leaf of more triangles than an item
    /// folds.
    pub fn new(staged: &StagedScene) -> Result<RefitPlan, String> {
        let nodes = &staged.nodes;
        if staged.triangles.is_empty() {
            return Ok(RefitPlan {
                items: Vec::new(),
                per_height: Vec::new(),
            });
        }
        let mut height = vec![0usize; nodes.len()];
        for index in (0..nodes.len()).rev() {
            let node = &nodes[index];
            if index != 1 && node.triangle_count() == 0 {
                let c = node.link as usize;
                height[index] = 1 + height[c].max(height[c + 1]);
            }
        }
        let heights = height[0] + 1;
        let mut by_height: Vec<Vec<usize>> = vec![Vec::new(); heights];
        for (index, &h) in height.iter().enumerate() {
            if index != 1 {
                by_height[h].push(index);
            }
        }
        by_height[0].sort_by_key(|&leaf| nodes[leaf].link);
        let mut items = Vec::new();
        let mut per_height = vec![0u32; heights];
        for (h, level) in by_height.iter().enumerate() {
            let mut item = Item {
                height: h,
                nodes: Vec::new(),
            };
            let mut elements = 0;
            for &node in level {
                let wanted = if h == 0 {
                    3 * nodes[node].triangle_count() as usize
                } else {
                    2
                };
                if wanted > MAX_ELEMENTS {
                    return Err(format!(
                        "a BVH leaf holds {} triangles; the SPU refit folds at most {} per leaf",
                        wanted / 3,
                        MAX_ELEMENTS / 3
                    ));
                }
                if item.nodes.len() == MAX_NODES || elements + wanted > MAX_ELEMENTS {
                    items.push(std::mem::replace(
                        &mut item,
                        Item {
                            height: h,
                            nodes: Vec::new(),
                        },
                    ));
                    per_height[h] += 1;
                    elements = 0;
                }
                item.nodes.push(node);
                elements += wanted;
            }
            if !item.nodes.is_empty() {
                items.push(item);
                per_height[h] += 1;
            }
        }
        Ok(RefitPlan { items, per_height })
    }

    /// Work items.
    pub fn items(&self) -> usize {
        self.items.len()
    }

    /// Heights (levels processed in order).
    pub fn heights(&self) -> usize {
        self.per_height.len()
    }

    /// The first item of the top heights that have one item each: from it on, one claim
    /// takes everything (one SPE refits the top of the tree without waiting on others).
    pub fn tail(&self) -> usize {
        let single = self
            .per_height
            .iter()
            .rev()
            .take_while(|&&n| n == 1)
            .count();
        self.items.len() - single
    }

    /// The items' index (block EA, bytes) and blocks for main memory at `at`, the done rows
    /// of each height at `done_addr`.
    fn encode(&self, staged: &StagedScene, at: u32, done_addr: u32) -> Vec<u8> {
        let header = &staged.header;
        let index_bytes = (16 * self.items.len()).div_ceil(128) * 128;
        let mut out = vec![0u8; index_bytes];
        let put = |out: &mut Vec<u8>, at: usize, words: &[u32]| {
            for (k, w) in words.iter().enumerate() {
                out[at + 4 * k..at + 4 * k + 4].copy_from_slice(&w.to_be_bytes());
            }
        };
        let row = |h: usize| done_addr + (DONE_ROW * h) as u32;
        for (i, item) in self.items.iter().enumerate() {
            let leaves = item.height == 0;
            let mut gather = Vec::new();
            for &index in &item.nodes {
                let node = &staged.nodes[index];
                if leaves {
                    let first = node.link as usize;
                    for record in &staged.triangles[first..first + node.triangle_count() as usize] {
                        for v in record.vertices {
                            gather.push([16, header.vertex_addr + v * VERTEX_SIZE as u32]);
                        }
                    }
                } else {
                    gather.push([64, header.node_addr + node.link * NODE_SIZE as u32]);
                }
            }
            let n = item.nodes.len();
            let gather_at = ENTRIES + 16 * n;
            let scatter_at = gather_at + (8 * gather.len()).div_ceil(16) * 16;
            let bytes = (scatter_at + 8 * n).div_ceil(128) * 128;
            let block = out.len();
            out.resize(block + bytes, 0);
            put(&mut out, 16 * i, &[at + block as u32, bytes as u32, 0, 0]);
            let (wait_addr, wait_count) = match item.height {
                0 => (0, 0),
                h => (row(h - 1), self.per_height[h - 1]),
            };
            put(
                &mut out,
                block,
                &[
                    n as u32,
                    8 * gather.len() as u32,
                    if leaves { 0 } else { 16 },
                    row(item.height),
                    wait_addr,
                    wait_count,
                    8 * n as u32,
                    item.height as u32,
                    gather_at as u32,
                    scatter_at as u32,
                ],
            );
            for (k, &index) in item.nodes.iter().enumerate() {
                let node = &staged.nodes[index];
                let elements = if leaves { 3 * node.triangle_count() } else { 2 };
                put(
                    &mut out,
                    block + ENTRIES + 16 * k,
                    &[elements, index as u32, node.link, node.count_axis],
                );
                put(
                    &mut out,
                    block + scatter_at + 8 * k,
                    &[32, header.node_addr + (index * NODE_SIZE) as u32],
                );
            }
            for (k, element) in gather.iter().enumerate() {
                put(&mut out, block + gather_at + 8 * k, element);
            }
        }
        out
    }
}

/// How the refit's SPEs run.
#[derive(Clone, Debug)]
pub struct RefitConfig {
    /// SPEs, 1 to 16.
    pub spes: usize,
    /// Host threads running them (the result does not depend on it).
    pub threads: usize,
    pub clock_ghz: f64,
    pub dma_latency_ns: f64,
    /// Whether the SPUs run with the timing model.
    pub timed: bool,
    pub engine: Engine,
    /// Simulated cycles per SPU before the refit gives up.
    pub max_cycles: u64,
}

/// What one SPE did in a refit.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RefitSpe {
    pub cycles: u64,
    pub items: u64,
    pub nodes: u64,
    /// Polls of a done counter while waiting for the height below.
    pub polls: u64,
}

/// The outcome of a refit on the SPEs.
#[derive(Clone, Debug, PartialEq)]
pub struct RefitRun {
    /// The node array the SPEs wrote (big-endian records, as staged).
    pub node_bytes: Vec<u8>,
    /// The slowest SPE's cycles.
    pub cycles: u64,
    pub spes: Vec<RefitSpe>,
    pub items: usize,
    pub heights: usize,
    /// Bytes the SPEs' DMA moved (read, written) over main memory.
    pub dma_bytes: (u64, u64),
}

/// Refits the node bounds of `staged` (a frame's scene, staged with its host-refitted tree)
/// on the SPEs as `plan` lays out: the bounds in memory start zeroed, so every node is the
/// SPEs' own, and the node array they leave must be `staged`'s byte for byte.
pub fn run(
    staged: &StagedScene,
    plan: &RefitPlan,
    config: &RefitConfig,
    program: &Program,
    code: &CodeCache,
) -> Result<RefitRun, String> {
    use spu_isa::machine::{MainMemory, StopReason};
    use spu_spe::{ContextConfig, Outcome, Quantum, State, System};
    use std::ops::ControlFlow;
    if !(1..=16).contains(&config.spes) {
        return Err(format!(
            "the refit runs on 1 to 16 SPEs, not {}",
            config.spes
        ));
    }
    if staged.base != SCENE_BASE {
        return Err(format!("the scene must be staged at {SCENE_BASE:#x}"));
    }
    let align = |x: usize| x.div_ceil(128) * 128;
    let scene_end = SCENE_BASE as usize + staged.image.len();
    let params = align(scene_end);
    let claim = params + 128;
    let done = claim + 128;
    let items = align(done + DONE_ROW * plan.heights());
    let encoded = plan.encode(staged, items as u32, done as u32);
    let end = items + encoded.len();
    if end > u32::MAX as usize {
        return Err("the refit's work does not fit a 32-bit address space".into());
    }
    let mut memory = vec![0u8; end];
    memory[SCENE_BASE as usize..scene_end].copy_from_slice(&staged.image);
    let nodes_at = staged.header.node_addr as usize;
    let nodes_len = staged.nodes.len() * NODE_SIZE;
    // zero every bound (links and counts stay): whatever the SPEs do not write shows
    for record in memory[nodes_at..nodes_at + nodes_len].chunks_exact_mut(NODE_SIZE) {
        record[0..12].fill(0);
        record[16..28].fill(0);
    }
    // SPE i starts on items [i * first, (i + 1) * first); the counter hands out the rest,
    // claims shrinking as (tail - claimed) >> shift (a share of what is left per SPE)
    let spes = config.spes as u32;
    let shift = (2 * spes).next_power_of_two().trailing_zeros();
    let first = plan.tail() as u32 / (2 * spes);
    let words = [
        items as u32,
        plan.items() as u32,
        claim as u32,
        plan.tail() as u32,
        shift,
        first,
    ];
    for (k, word) in words.iter().enumerate() {
        memory[params + 4 * k..params + 4 * k + 4].copy_from_slice(&word.to_be_bytes());
    }
    memory[claim..claim + 4].copy_from_slice(&(first * spes).to_be_bytes());
    memory[items..end].copy_from_slice(&encoded);
    let stats_at = program
        .symbols
        .iter()
        .find(|(n, _)| n == "refit_stats")
        .map(|(_, a)| *a as usize)
        .ok_or("the refit kernel has no refit_stats")?;

    let mut system = System::with_memory(MainMemory::new(memory));
    system.set_quantum(Quantum::Aligned(QUANTUM_CYCLES));
    system.set_threads(config.threads.max(1));
    let regions = vec![(0u64, end as u64)];
    for i in 0..config.spes {
        let id = system.create_context(ContextConfig {
            engine: config.engine,
            timing: config.timed.then(|| spu_isa::timing::TimingConfig {
                clock_ghz: config.clock_ghz,
                dma_latency_ns: config.dma_latency_ns,
                ..Default::default()
            }),
            code: Some(code.clone()),
            extensions: spu_isa::Extensions::default(),
        });
        let spu = system.spu_mut(id);
        spu.load_image(&program.image);
        spu.set_pc(program.entry);
        spu.set_reg(3, [i as u32, 0, 0, 0]);
        spu.set_reg(4, [params as u32, 0, 0, 0]);
        spu.count_traffic(regions.clone());
    }
    let finished = |state: &State| *state == State::Stopped(StopReason::Stop(STOP_DONE));
    let outcome = system.run_observed(config.max_cycles, |_, states| {
        let failed = states
            .iter()
            .any(|s| !finished(s) && !matches!(s, State::Runnable | State::Waiting { .. }));
        if failed {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let contexts: Vec<_> = system.contexts().collect();
    for (i, &id) in contexts.iter().enumerate() {
        let state = system.state(id).clone();
        if finished(&state) && system.read_out_mbox(id) == Some(1) {
            continue;
        }
        if outcome == Outcome::CycleLimit {
            return Err(format!(
                "the refit did not finish within {} cycles",
                config.max_cycles
            ));
        }
        let reason = match state {
            State::Waiting { channel, pc } => {
                format!("deadlock at {pc:#x} on channel {}", channel.number())
            }
            State::Stopped(other) => other.to_string(),
            State::Faulted { message, .. } => message,
            State::Runnable => "still running".to_string(),
        };
        return Err(format!("refit SPU {i} stopped: {reason}"));
    }
    let word = |ls: &[u8], at: usize| {
        u32::from_be_bytes([ls[at], ls[at + 1], ls[at + 2], ls[at + 3]]) as u64
    };
    let spes: Vec<RefitSpe> = contexts
        .iter()
        .map(|&id| {
            let ls = system.ls(id);
            RefitSpe {
                cycles: system.spu(id).cycles(),
                items: word(ls, stats_at),
                nodes: word(ls, stats_at + 16),
                polls: word(ls, stats_at + 32),
            }
        })
        .collect();
    let dma_bytes = contexts.iter().fold((0, 0), |(r, w), &id| {
        let t = system.spu(id).traffic();
        (r + t.read[0], w + t.written[0])
    });
    let node_bytes = system.memory().bytes()[nodes_at..nodes_at + nodes_len].to_vec();
    let expected = &staged.image[nodes_at - SCENE_BASE as usize..][..nodes_len];
    if let Some(at) = (0..nodes_len).find(|&b| node_bytes[b] != expected[b]) {
        return Err(format!(
            "the SPU refit differs from the host refit at node {} (byte {})",
            at / NODE_SIZE,
            at % NODE_SIZE
        ));
    }
    Ok(RefitRun {
        node_bytes,
        cycles: spes.iter().map(|s| s.cycles).max().unwrap_or(0),
        spes,
        items: plan.items(),
        heights: plan.heights(),
        dma_bytes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_hold_one_height_and_fit_their_block() {
        let scene = crate::procedural::room();
        let bvh = crate::Bvh::build(&scene, &crate::BvhConfig::default());
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE).unwrap();
        let plan = RefitPlan::new(&staged).unwrap();
        let covered: usize = plan.items.iter().map(|i| i.nodes.len()).sum();
        assert_eq!(
            covered,
            staged.nodes.len() - 1,
            "every node but the padding"
        );
        assert!(plan.items.windows(2).all(|w| w[0].height <= w[1].height));
        assert_eq!(plan.items.last().unwrap().nodes, vec![0], "the root last");
        assert_eq!(
            plan.per_height.iter().sum::<u32>() as usize,
            plan.items.len()
        );
    }
}
