//! The SPU refit (`kernels/refit.s`): the host lays out a staged scene's refit as work items
//! once per topology ([`RefitPlan`]), and a gang of 1 to 16 SPEs, sharing the items through
//! an atomic counter, streams the frame's vertex and node chunks with double-buffered DMA
//! lists and writes the node bounds bottom-up ([`run`]). The result is [`crate::refit`]'s
//! host refit bit for bit; [`run`] checks it against the staged scene's nodes.
//!
//! # Work items
//!
//! The tree is cut into the largest subtrees within an item's limits ([`MAX_SUBTREE_NODES`]
//! descendants, [`MAX_CORNERS`] triangle corners, [`MAX_VERTICES`] distinct vertices): the
//! descendants of a node are one node range (pairs are allocated in pre-order), so a subtree
//! item gathers its distinct vertices once (a DMA list of 16-byte elements from the vertex
//! records), folds its leaves from them through per-corner offsets and its inner nodes from
//! the records it has just folded, and writes the range back with one put. The nodes above
//! the subtrees get heights (one above their higher child; subtrees are height 0) and come
//! in items of up to [`MAX_NODES`] nodes of one height, each node's child pair gathered from
//! main memory (one 64-byte line) and its record scattered back by a DMA list. Items of a
//! height wait for every item of the height below through a row of done counters, one
//! quadword per SPE. `kernels/refit.s` documents the blocks, the claims and the double
//! buffering.
//!
//! For the beetle (693k triangles, 308k nodes) that is 3482 items and 31 MB of DMA a frame;
//! on 16 SPEs at 2.4 GHz the refit takes 3.94M cycles, 8.1% of a 16-SPE shadows frame
//! (`cargo run --release -p spu-loader --example refit_bench -- beetle-drive`).

use crate::frame::SCENE_BASE;
use crate::layout::{StagedScene, NODE_SIZE, VERTEX_SIZE};
use crate::runtime::{Program, QUANTUM_CYCLES, STOP_DONE};
use spu_isa::jit::{CodeCache, Engine};

/// The kernel's source.
pub const SOURCE: &str = include_str!("../../kernels/refit.s");

/// Nodes per work item of the upper tree.
pub const MAX_NODES: usize = 128;
/// A subtree item's limits: descendants of its root (their records and the root's fill
/// [`OUT_BYTES`]), triangle corners, distinct vertices (gathered once each).
pub const MAX_SUBTREE_NODES: usize = MAX_NODES - 1;
pub const MAX_CORNERS: usize = 1536;
pub const MAX_VERTICES: usize = 768;
/// Offset of the node entries in an item's block (after the header's three quadwords).
pub const ENTRIES: usize = 48;
/// Local-store bytes for the largest item's block (one DMA: at most 16 KB).
pub const ITEM_BYTES: usize = 16384;
const _: () =
    assert!(ENTRIES + MAX_NODES * 16 + MAX_CORNERS * 2 + MAX_VERTICES * 8 + 16 <= ITEM_BYTES);
const _: () = assert!(ENTRIES + MAX_NODES * (16 + 8 + 8) <= ITEM_BYTES);
/// Local-store bytes for an item's gathered vertices (16 bytes each) or child pairs (64).
pub const DATA_BYTES: usize = if MAX_VERTICES * 16 > MAX_NODES * 64 {
    MAX_VERTICES * 16
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

/// One work item.
#[derive(Clone, Debug, PartialEq)]
enum Item {
    /// A whole subtree: `root` and its descendants, the node range `first..end`.
    Subtree {
        root: usize,
        first: usize,
        end: usize,
    },
    /// Nodes of the upper tree at `height`, their child pairs gathered from main memory.
    Upper { height: usize, nodes: Vec<usize> },
}

impl Item {
    fn height(&self) -> usize {
        match self {
            Item::Subtree { .. } => 0,
            Item::Upper { height, .. } => *height,
        }
    }
}

/// A staged scene's refit laid out for the SPEs: the items in claim order (heights upward).
#[derive(Clone, Debug, PartialEq)]
pub struct RefitPlan {
    items: Vec<Item>,
    /// Items of each height.
    per_height: Vec<u32>,
}

impl RefitPlan {
    /// The items refitting `staged`'s nodes: the largest subtrees within an item's limits
    /// (height 0), then the nodes above them by height. Refuses a leaf of more triangles
    /// than an item folds.
    pub fn new(staged: &StagedScene) -> Result<RefitPlan, String> {
        let nodes = &staged.nodes;
        let mut items = Vec::new();
        if staged.triangles.is_empty() {
            return Ok(RefitPlan {
                items,
                per_height: Vec::new(),
            });
        }
        let leaf = |i: usize| nodes[i].triangle_count() > 0;
        // the end of each inner node's descendants (pairs in pre-order: a subtree's
        // descendants are the range link..end)
        let mut end = vec![0usize; nodes.len()];
        for index in (0..nodes.len()).rev() {
            if index != 1 && !leaf(index) {
                let c = nodes[index].link as usize;
                end[index] = (c + 2).max(end[c]).max(end[c + 1]);
            }
        }
        let range = |i: usize| {
            if leaf(i) {
                (i, i)
            } else {
                (nodes[i].link as usize, end[i])
            }
        };
        let fits = |i: usize| -> bool {
            let (first, last) = range(i);
            if last - first > MAX_SUBTREE_NODES {
                return false;
            }
            let mut corners = 0;
            let mut seen = std::collections::HashSet::new();
            for n in (first..last).chain([i]) {
                if leaf(n) {
                    let start = nodes[n].link as usize;
                    for record in
                        &staged.triangles[start..start + nodes[n].triangle_count() as usize]
                    {
                        corners += 3;
                        seen.extend(record.vertices);
                    }
                }
            }
            corners <= MAX_CORNERS && seen.len() <= MAX_VERTICES
        };
        // the subtree roots, top down; the nodes above them get heights bottom up
        let mut height = vec![usize::MAX; nodes.len()];
        let mut upper = Vec::new();
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            if fits(i) {
                let (first, last) = range(i);
                height[i] = 0;
                items.push(Item::Subtree {
                    root: i,
                    first,
                    end: last,
                });
            } else if leaf(i) {
                return Err(format!(
                    "a BVH leaf holds {} triangles; the SPU refit folds at most {} at once",
                    nodes[i].triangle_count(),
                    MAX_CORNERS / 3
                ));
            } else {
                upper.push(i);
                let c = nodes[i].link as usize;
                stack.push(c + 1);
                stack.push(c);
            }
        }
        // subtrees in node order (neighbouring triangles and vertices), then the upper
        // tree: children at higher indices, so from the end each height is known
        items.sort_by_key(|item| match item {
            Item::Subtree { root, .. } => *root,
            Item::Upper { .. } => 0,
        });
        upper.sort_unstable();
        for &i in upper.iter().rev() {
            let c = nodes[i].link as usize;
            height[i] = 1 + height[c].max(height[c + 1]);
        }
        let heights = height[0] + 1;
        let mut per_height = vec![0u32; heights];
        per_height[0] = items.len() as u32;
        let mut by_height: Vec<Vec<usize>> = vec![Vec::new(); heights];
        for &i in &upper {
            by_height[height[i]].push(i);
        }
        for (h, level) in by_height.iter().enumerate().skip(1) {
            for chunk in level.chunks(MAX_NODES) {
                items.push(Item::Upper {
                    height: h,
                    nodes: chunk.to_vec(),
                });
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
        let node_ea = |i: usize| header.node_addr + (i * NODE_SIZE) as u32;
        let index_bytes = (16 * self.items.len()).div_ceil(128) * 128;
        let mut out = vec![0u8; index_bytes];
        let put = |out: &mut Vec<u8>, at: usize, words: &[u32]| {
            for (k, w) in words.iter().enumerate() {
                out[at + 4 * k..at + 4 * k + 4].copy_from_slice(&w.to_be_bytes());
            }
        };
        let row = |h: usize| done_addr + (DONE_ROW * h) as u32;
        for (i, item) in self.items.iter().enumerate() {
            // entries (corners | dest << 16, source, node), corner offsets, gather list,
            // scatter list; a corner's source is a block offset fixed once the entries'
            // size is known
            let mut entries: Vec<(u32, u32, usize)> = Vec::new();
            let mut corners: Vec<u16> = Vec::new();
            let mut gather: Vec<[u32; 2]> = Vec::new();
            let mut scatter: Vec<[u32; 2]> = Vec::new();
            let pairs_local = match item {
                Item::Subtree { root, first, end } => {
                    let mut local = std::collections::HashMap::new();
                    let dest = |n: usize| {
                        if n == *root {
                            (end - first) as u32 * NODE_SIZE as u32
                        } else {
                            (n - first) as u32 * NODE_SIZE as u32
                        }
                    };
                    // the leaves first (in any order), then the inner nodes, children
                    // (at higher indices) before parents
                    let order = (*first..*end).rev().chain([*root]);
                    let (leaves, inner): (Vec<usize>, Vec<usize>) =
                        order.partition(|&n| staged.nodes[n].triangle_count() > 0);
                    for n in leaves.into_iter().chain(inner) {
                        let node = &staged.nodes[n];
                        if node.triangle_count() > 0 {
                            let count = 3 * node.triangle_count();
                            entries.push((count | dest(n) << 16, 2 * corners.len() as u32, n));
                            let start = node.link as usize;
                            for record in
                                &staged.triangles[start..start + node.triangle_count() as usize]
                            {
                                for v in record.vertices {
                                    let next = local.len() as u32;
                                    let slot = *local.entry(v).or_insert_with(|| {
                                        gather.push([
                                            16,
                                            header.vertex_addr + v * VERTEX_SIZE as u32,
                                        ]);
                                        next
                                    });
                                    corners.push(16 * slot as u16);
                                }
                            }
                        } else {
                            let pair = (node.link as usize - first) as u32 * NODE_SIZE as u32;
                            entries.push((dest(n) << 16, pair, n));
                        }
                    }
                    if end > first {
                        scatter.push([((end - first) * NODE_SIZE) as u32, node_ea(*first)]);
                    }
                    scatter.push([NODE_SIZE as u32, node_ea(*root)]);
                    1
                }
                Item::Upper { nodes, .. } => {
                    for (k, &n) in nodes.iter().enumerate() {
                        let link = staged.nodes[n].link as usize;
                        entries.push((((k * NODE_SIZE) as u32) << 16, 64 * k as u32, n));
                        gather.push([64, node_ea(link)]);
                        scatter.push([NODE_SIZE as u32, node_ea(n)]);
                    }
                    0
                }
            };
            let corners_at = ENTRIES + 16 * entries.len();
            let gather_at = corners_at + (2 * corners.len()).div_ceil(16) * 16;
            let scatter_at = gather_at + (8 * gather.len()).div_ceil(16) * 16;
            let bytes = (scatter_at + 8 * scatter.len()).div_ceil(128) * 128;
            let block = out.len();
            out.resize(block + bytes, 0);
            put(&mut out, 16 * i, &[at + block as u32, bytes as u32, 0, 0]);
            let (wait_addr, wait_count) = match item.height() {
                0 => (0, 0),
                h => (row(h - 1), self.per_height[h - 1]),
            };
            put(
                &mut out,
                block,
                &[
                    entries.len() as u32,
                    8 * gather.len() as u32,
                    pairs_local,
                    row(item.height()),
                    wait_addr,
                    wait_count,
                    8 * scatter.len() as u32,
                    item.height() as u32,
                    gather_at as u32,
                    scatter_at as u32,
                    entries.iter().filter(|e| e.0 & 0xffff != 0).count() as u32,
                ],
            );
            for (k, &(word, source, n)) in entries.iter().enumerate() {
                let node = &staged.nodes[n];
                let source = if word & 0xffff != 0 {
                    (corners_at as u32) + source
                } else {
                    source
                };
                put(
                    &mut out,
                    block + ENTRIES + 16 * k,
                    &[word, source, node.link, node.count_axis],
                );
            }
            for (k, &c) in corners.iter().enumerate() {
                let at = block + corners_at + 2 * k;
                out[at..at + 2].copy_from_slice(&c.to_be_bytes());
            }
            for (k, element) in gather.iter().enumerate() {
                put(&mut out, block + gather_at + 8 * k, element);
            }
            for (k, element) in scatter.iter().enumerate() {
                put(&mut out, block + scatter_at + 8 * k, element);
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
    // zero every bound (links and counts stay): whatever the SPEs do not write shows (a
    // tree without triangles has nothing to refit, and its root's empty box stays)
    let zeroed = if plan.items() == 0 { 0 } else { nodes_len };
    for record in memory[nodes_at..nodes_at + zeroed].chunks_exact_mut(NODE_SIZE) {
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
    fn every_node_is_refitted_once_and_heights_ascend() {
        let scene = crate::procedural::room();
        let bvh = crate::Bvh::build(&scene, &crate::BvhConfig::default());
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE).unwrap();
        let plan = RefitPlan::new(&staged).unwrap();
        let mut seen = vec![0; staged.nodes.len()];
        for item in &plan.items {
            match item {
                Item::Subtree { root, first, end } => {
                    assert!(end - first <= MAX_SUBTREE_NODES);
                    for n in (*first..*end).chain([*root]) {
                        seen[n] += 1;
                    }
                }
                Item::Upper { nodes, .. } => nodes.iter().for_each(|&n| seen[n] += 1),
            }
        }
        assert_eq!(seen[1], 0, "the padding node");
        assert!(seen.iter().enumerate().all(|(i, &k)| i == 1 || k == 1));
        assert!(plan
            .items
            .windows(2)
            .all(|w| w[0].height() <= w[1].height()));
        assert_eq!(
            plan.per_height.iter().sum::<u32>() as usize,
            plan.items.len()
        );
        assert!(plan.heights() > 1, "the room is more than one subtree");
    }
}
