//! The bounding volume hierarchy the kernels traverse (paper section 3.2: a binary BVH over
//! triangles, traversed with 8x8 ray packets), built with the binned surface area heuristic.
//!
//! # Build
//!
//! At each node the triangles' centroids are sorted into [`BIN_COUNT`] = 16 equal-width bins
//! per axis; the 15 planes between bins on each of the 3 axes are split candidates, scored
//! with the SAH
//!
//! ```text
//! cost(split) = C_trav + C_isect * (A(left) * N(left) + A(right) * N(right)) / A(node)
//! cost(leaf)  = C_isect * N(node)
//! ```
//!
//! with `C_trav = 1` and `C_isect = 1` per triangle by default ([`BvhConfig`]): on the SPU a
//! packet-box step costs ~51 cycles and a packet-triangle test of 64 rays ~520 (paper 4.1,
//! 4.2), but a box step touches a 64-byte node pair for two boxes while a triangle touches one
//! 64-byte record that mostly misses the cache (Table 1), so per memory line they are of the
//! same order.
//!
//! `A` is not the box's own area but that of the box grown by a packet's width on every
//! side ([`BvhConfig::packet_footprint`], a fraction of the scene's bounding-box diagonal):
//! the kernels trace 8x8 packets, and a packet visits a box when any of its rays does, so
//! the chance that a packet enters a box is the area of the box's Minkowski sum with the
//! packet's cross-section, not the box's area (the ray SAH's). Where boxes are much larger
//! than a packet this changes nothing; where they are much smaller (a finely tessellated
//! model), splitting a node saves the packet no triangle tests, and the node stays a leaf.
//! The default, 1/128 of the diagonal, is the width of an 8-pixel packet when the scene
//! fills a 1024-pixel view. Against the ray SAH with leaves of 4, it took the 1024x1024
//! primary-ray frames on 1 SPE from 73.19 / 278.68 / 403.46 M cycles to 70.5 / 258.0 /
//! 362.4 M (room, conference, beetle).
//!
//! A node becomes a leaf when `cost(leaf) <= best cost(split)` and it has at most
//! `max_leaf_size` (default 6) triangles. Where the centroids do not separate (all equal) or
//! below [`SAH_DEPTH_LIMIT`] levels, the node is split at the object median of its longest
//! centroid axis instead, which bounds the depth by `SAH_DEPTH_LIMIT + log2(N)` — the kernels'
//! traversal stack can be sized from [`Bvh::max_depth`].
//!
//! With more than one thread ([`BvhConfig::threads`]) the build runs on a rayon pool of
//! that many threads: large nodes bin and bound their triangles in parallel chunks, and the
//! two subtrees of a large node are built as a `rayon::join` (work stealing keeps both cores
//! busy where the halves are uneven, which a fixed split of the top levels did not). Bins and
//! bounds are minima, maxima and integer counts, which come out the same in any order; the
//! partition of a node stays one sequential pass; every subtree is a pure function of its
//! triangle set, and the flat array is laid out afterwards in one deterministic pass. So the
//! result is bit-identical whatever the thread count.
//!
//! # Flat layout
//!
//! `nodes[0]` is the root and `nodes[1]` an unused padding node, so that the two children of
//! every inner node sit at an even index `c` and `c + 1` — one 64-byte line, fetched by a
//! single DMA and cached as a pair (paper section 5.1). Pairs are allocated in depth-first
//! pre-order. For an inner node, child `c` holds the triangles whose centroids are lower along
//! `axis`. A leaf's `link` is the index of its first triangle in [`Bvh::triangle_order`]
//! (= its first triangle record), its triangles being the contiguous range
//! `link .. link + count`.

use glam::Vec3A;

use crate::scene::Scene;

/// Number of SAH bins per axis.
pub const BIN_COUNT: usize = 16;

/// Depth below which the builder stops using the SAH and splits at the object median.
pub const SAH_DEPTH_LIMIT: usize = 48;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhConfig {
    /// Leaves hold at most this many triangles (at least 1).
    pub max_leaf_size: usize,
    /// `C_trav` in the SAH: the cost of visiting an inner node.
    pub traversal_cost: f32,
    /// `C_isect` in the SAH: the cost of one triangle test.
    pub intersection_cost: f32,
    /// Threads for the top levels of the build (1 = sequential; the result does not depend on it).
    pub threads: usize,
    /// The width of a packet as a fraction of the scene's bounding-box diagonal: the SAH
    /// grows every box by it (half on each side) before taking its area. 0 = the ray SAH.
    pub packet_footprint: f32,
}

/// The default [`BvhConfig::packet_footprint`]: 8 pixels of a 1024-pixel view of the scene.
pub const PACKET_FOOTPRINT: f32 = 1.0 / 128.0;

impl Default for BvhConfig {
    fn default() -> Self {
        BvhConfig {
            max_leaf_size: 6,
            traversal_cost: 1.0,
            intersection_cost: 1.0,
            threads: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            packet_footprint: PACKET_FOOTPRINT,
        }
    }
}

/// One node of the flat hierarchy (host form of [`crate::layout::NodeRecord`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhNode {
    pub min: Vec3A,
    pub max: Vec3A,
    /// Inner node: index of the first child (even). Leaf: index of the first triangle record.
    pub link: u32,
    /// Number of triangles; 0 for an inner node.
    pub count: u32,
    /// Inner node: the axis (0, 1, 2) along which the children are ordered. Leaf: 0.
    pub axis: u32,
}

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    fn empty() -> Self {
        BvhNode {
            min: Vec3A::ZERO,
            max: Vec3A::ZERO,
            link: 0,
            count: 0,
            axis: 0,
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    /// `nodes[0]` root, `nodes[1]` padding, then sibling pairs.
    pub nodes: Vec<BvhNode>,
    /// `triangle_order[i]` is the scene triangle stored as triangle record `i`.
    pub triangle_order: Vec<u32>,
    pub config: BvhConfig,
    /// SAH cost of the whole tree: `sum_inner A/A_root * C_trav + sum_leaf A/A_root * N * C_isect`.
    pub sah_cost: f32,
}

/// Summary figures for logs and tests.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BvhStats {
    pub inner_nodes: usize,
    pub leaves: usize,
    pub max_depth: usize,
    pub max_leaf_triangles: usize,
    pub mean_leaf_triangles: f64,
}

/// The build-time tree, before it is laid out flat.
enum BuildNode {
    Leaf {
        min: Vec3A,
        max: Vec3A,
        start: usize,
        count: usize,
    },
    Inner {
        min: Vec3A,
        max: Vec3A,
        axis: u32,
        children: Box<[BuildNode; 2]>,
    },
}

struct Primitives {
    min: Vec<Vec3A>,
    max: Vec<Vec3A>,
    centroid: Vec<Vec3A>,
    /// Half a packet's width: the SAH grows every box by it on each side.
    growth: Vec3A,
}

#[derive(Clone, Copy)]
struct Bin {
    min: Vec3A,
    max: Vec3A,
    count: usize,
}

impl Bin {
    const EMPTY: Bin = Bin {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
        count: 0,
    };

    fn grow(&mut self, min: Vec3A, max: Vec3A, count: usize) {
        self.min = self.min.min(min);
        self.max = self.max.max(max);
        self.count += count;
    }
}

/// Half the surface area of a box (the SAH only uses ratios); 0 for an empty box.
fn half_area(min: Vec3A, max: Vec3A) -> f32 {
    let d = (max - min).max(Vec3A::ZERO);
    d.x * d.y + d.y * d.z + d.z * d.x
}

/// Half the surface area of a box grown by `growth` on every side (0 for an empty box): how
/// likely a packet is to enter it.
fn packet_area(min: Vec3A, max: Vec3A, growth: Vec3A) -> f32 {
    if min.cmpgt(max).any() {
        0.0
    } else {
        half_area(min - growth, max + growth)
    }
}

/// Subtrees smaller than this are built on the thread that reached them (a rayon task
/// costs microseconds; a subtree of 16384 triangles takes milliseconds).
const PARALLEL_THRESHOLD: usize = 16 * 1024;

/// Triangles per task where a node bins and bounds its triangles in parallel (nodes of
/// fewer than twice this do it on one thread).
const PARALLEL_CHUNK: usize = 16 * 1024;

/// A node's box and its triangles' centroids' box.
#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
    cmin: Vec3A,
    cmax: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
        cmin: Vec3A::splat(f32::INFINITY),
        cmax: Vec3A::splat(f32::NEG_INFINITY),
    };

    fn of(primitives: &Primitives, order: &[u32]) -> Bounds {
        order.iter().fold(Bounds::EMPTY, |b, &t| {
            let t = t as usize;
            Bounds {
                min: b.min.min(primitives.min[t]),
                max: b.max.max(primitives.max[t]),
                cmin: b.cmin.min(primitives.centroid[t]),
                cmax: b.cmax.max(primitives.centroid[t]),
            }
        })
    }

    /// The bounds of both: minima and maxima of finite coordinates (a scene's are checked
    /// finite), the same in whatever order chunks are joined.
    fn union(a: Bounds, b: Bounds) -> Bounds {
        Bounds {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
            cmin: a.cmin.min(b.cmin),
            cmax: a.cmax.max(b.cmax),
        }
    }
}

impl Bvh {
    /// Builds the hierarchy over all triangles of `scene`.
    pub fn build(scene: &Scene, config: &BvhConfig) -> Bvh {
        let config = BvhConfig {
            max_leaf_size: config.max_leaf_size.max(1),
            threads: config.threads.max(1),
            ..*config
        };
        if config.threads > 1 {
            // A pool of exactly `threads`, not rayon's global one (sized by the host), so
            // that the caller's thread count holds; a pool that cannot start (no threads
            // left) builds on this thread, with the same result.
            if let Ok(pool) = rayon::ThreadPoolBuilder::new()
                .num_threads(config.threads)
                .thread_name(|i| format!("bvh-{i}"))
                .build()
            {
                return pool.install(|| Bvh::build_with(scene, &config, true));
            }
        }
        Bvh::build_with(scene, &config, false)
    }

    /// [`Bvh::build`] with its checked `config`, in parallel (on the current rayon pool)
    /// where `parallel`.
    fn build_with(scene: &Scene, config: &BvhConfig, parallel: bool) -> Bvh {
        let config = *config;
        let n = scene.triangle_count();
        let boxes = |index: usize| {
            let [a, b, c] = scene.triangle_positions(index).map(Vec3A::from);
            let (min, max) = (a.min(b).min(c), a.max(b).max(c));
            (min, (max, (min + max) * 0.5))
        };
        let (mut min, mut max, mut centroid) = (
            vec![Vec3A::ZERO; n],
            vec![Vec3A::ZERO; n],
            vec![Vec3A::ZERO; n],
        );
        // one chunk's boxes: its number, and its minima, maxima and centroids
        type Chunk<'a> = (usize, ((&'a mut [Vec3A], &'a mut [Vec3A]), &'a mut [Vec3A]));
        let fill = |(chunk, ((min, max), centroid)): Chunk| {
            for (i, ((min, max), centroid)) in min.iter_mut().zip(max).zip(centroid).enumerate() {
                (*min, (*max, *centroid)) = boxes(chunk * PARALLEL_CHUNK + i);
            }
        };
        if parallel {
            use rayon::prelude::*;
            min.par_chunks_mut(PARALLEL_CHUNK)
                .zip(max.par_chunks_mut(PARALLEL_CHUNK))
                .zip(centroid.par_chunks_mut(PARALLEL_CHUNK))
                .enumerate()
                .for_each(fill);
        } else {
            min.chunks_mut(PARALLEL_CHUNK)
                .zip(max.chunks_mut(PARALLEL_CHUNK))
                .zip(centroid.chunks_mut(PARALLEL_CHUNK))
                .enumerate()
                .for_each(fill);
        }
        let mut primitives = Primitives {
            min,
            max,
            centroid,
            growth: Vec3A::ZERO,
        };
        let (scene_min, scene_max) = primitives.min.iter().zip(&primitives.max).fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), (&min, &max)| (lo.min(min), hi.max(max)),
        );
        let diagonal = if n == 0 {
            0.0
        } else {
            (scene_max - scene_min).length()
        };
        primitives.growth = Vec3A::splat(0.5 * diagonal * config.packet_footprint.max(0.0));
        let mut order: Vec<u32> = (0..n as u32).collect();
        let root = if n == 0 {
            // An inverted (min > max) box that every ray misses: the root of an empty scene.
            // Its count is 0, so it reads as an inner node, but it is never entered.
            BuildNode::Leaf {
                min: Vec3A::splat(f32::MAX),
                max: Vec3A::splat(-f32::MAX),
                start: 0,
                count: 0,
            }
        } else {
            build_recursive(&primitives, &config, &mut order, 0, 0, parallel)
        };

        let mut nodes = vec![BvhNode::empty(); 2];
        flatten(&root, 0, &mut nodes);
        let sah_cost = if n == 0 {
            0.0
        } else {
            sah_cost(&nodes, &config)
        };
        Bvh {
            nodes,
            triangle_order: order,
            config,
            sah_cost,
        }
    }

    pub fn root(&self) -> &BvhNode {
        &self.nodes[0]
    }

    /// Node and leaf counts, depth (root = depth 1) and leaf sizes.
    pub fn stats(&self) -> BvhStats {
        let mut stats = BvhStats {
            inner_nodes: 0,
            leaves: 0,
            max_depth: 0,
            max_leaf_triangles: 0,
            mean_leaf_triangles: 0.0,
        };
        let mut stack = vec![(0usize, 1usize)];
        let mut leaf_triangles = 0usize;
        while let Some((index, depth)) = stack.pop() {
            let node = &self.nodes[index];
            stats.max_depth = stats.max_depth.max(depth);
            if node.is_leaf() || (index == 0 && self.triangle_order.is_empty()) {
                stats.leaves += 1;
                stats.max_leaf_triangles = stats.max_leaf_triangles.max(node.count as usize);
                leaf_triangles += node.count as usize;
            } else {
                stats.inner_nodes += 1;
                stack.push((node.link as usize, depth + 1));
                stack.push((node.link as usize + 1, depth + 1));
            }
        }
        stats.mean_leaf_triangles = leaf_triangles as f64 / stats.leaves.max(1) as f64;
        stats
    }

    /// Levels from the root to the deepest leaf (root alone = 1).
    pub fn max_depth(&self) -> usize {
        self.stats().max_depth
    }

    /// Checks the structural invariants against `scene`: every triangle in exactly one leaf,
    /// leaves are contiguous ranges covering `triangle_order` in order, children pairs at even
    /// indices, boxes containing their children and triangles, children ordered along `axis`.
    pub fn validate(&self, scene: &Scene) -> Result<(), String> {
        let n = scene.triangles.len();
        if self.triangle_order.len() != n {
            return Err(format!(
                "{} triangles ordered for {n} in the scene",
                self.triangle_order.len()
            ));
        }
        let mut seen = vec![false; n];
        for &t in &self.triangle_order {
            if t as usize >= n || std::mem::replace(&mut seen[t as usize], true) {
                return Err(format!("triangle {t} out of range or referenced twice"));
            }
        }
        if n == 0 {
            return Ok(());
        }
        let mut next_triangle = 0usize;
        let mut visited = vec![false; self.nodes.len()];
        // Depth-first, children in order, so leaves must appear in triangle order.
        let mut stack = vec![0usize];
        while let Some(index) = stack.pop() {
            let node = self
                .nodes
                .get(index)
                .ok_or_else(|| format!("node {index} out of range"))?;
            if std::mem::replace(&mut visited[index], true) {
                return Err(format!("node {index} reached twice"));
            }
            if node.is_leaf() {
                if node.link as usize != next_triangle {
                    return Err(format!(
                        "leaf {index} starts at {} but {next_triangle} expected",
                        node.link
                    ));
                }
                if node.count as usize > self.config.max_leaf_size {
                    return Err(format!("leaf {index} has {} triangles", node.count));
                }
                for slot in node.link as usize..(node.link + node.count) as usize {
                    for p in scene.triangle_positions(self.triangle_order[slot] as usize) {
                        let p = Vec3A::from(p);
                        if p.cmplt(node.min).any() || p.cmpgt(node.max).any() {
                            return Err(format!(
                                "leaf {index} does not contain triangle slot {slot}"
                            ));
                        }
                    }
                }
                next_triangle += node.count as usize;
            } else {
                let c = node.link as usize;
                if !c.is_multiple_of(2) || c < 2 || c + 1 >= self.nodes.len() {
                    return Err(format!("inner node {index} has bad child index {c}"));
                }
                if node.axis > 2 {
                    return Err(format!("inner node {index} has axis {}", node.axis));
                }
                for child in [&self.nodes[c], &self.nodes[c + 1]] {
                    if child.min.cmplt(node.min).any() || child.max.cmpgt(node.max).any() {
                        return Err(format!("inner node {index} does not contain its child"));
                    }
                }
                stack.push(c + 1);
                stack.push(c);
            }
        }
        if next_triangle != n {
            return Err(format!("leaves cover {next_triangle} of {n} triangles"));
        }
        Ok(())
    }
}

/// The SAH cost of a flat hierarchy (`nodes[1]` the padding): `sum_inner A/A_root * C_trav +
/// sum_leaf A/A_root * N * C_isect`, summed in f64 in node order; 0 where the root has no area.
/// The build reports it, and a refit compares its own against the build's.
pub fn sah_cost(nodes: &[BvhNode], config: &BvhConfig) -> f32 {
    let Some(root) = nodes.first() else {
        return 0.0;
    };
    let root_area = half_area(root.min, root.max);
    let mut cost = 0.0f64;
    if root_area > 0.0 {
        for (index, node) in nodes.iter().enumerate() {
            if index == 1 {
                continue;
            }
            let weight = half_area(node.min, node.max) as f64 / root_area as f64;
            cost += if node.is_leaf() {
                weight * node.count as f64 * config.intersection_cost as f64
            } else {
                weight * config.traversal_cost as f64
            };
        }
    }
    cost as f32
}

fn build_recursive(
    primitives: &Primitives,
    config: &BvhConfig,
    order: &mut [u32],
    start: usize,
    depth: usize,
    parallel: bool,
) -> BuildNode {
    let count = order.len();
    let data_parallel = parallel && count >= PARALLEL_CHUNK * 2;
    let Bounds {
        min,
        max,
        cmin,
        cmax,
    } = if data_parallel {
        use rayon::prelude::*;
        order
            .par_chunks(PARALLEL_CHUNK)
            .map(|chunk| Bounds::of(primitives, chunk))
            .reduce(|| Bounds::EMPTY, Bounds::union)
    } else {
        Bounds::of(primitives, order)
    };
    let leaf = || BuildNode::Leaf {
        min,
        max,
        start,
        count,
    };
    if count == 1 {
        return leaf();
    }

    let extent = cmax - cmin;
    let leaf_cost = config.intersection_cost * count as f32;
    let split = if depth < SAH_DEPTH_LIMIT && extent.max_element() > 0.0 {
        best_binned_split(
            primitives,
            config,
            order,
            (min, max),
            cmin,
            extent,
            data_parallel,
        )
    } else {
        None
    };

    let (axis, mid) = match split {
        Some((cost, _, _)) if cost >= leaf_cost && count <= config.max_leaf_size => return leaf(),
        Some((_, axis, bin)) => {
            let scale = BIN_COUNT as f32 / extent[axis];
            let in_left =
                |t: u32| bin_index(primitives.centroid[t as usize][axis], cmin[axis], scale) < bin;
            // Below the top levels the subtrees already keep every thread busy, and the
            // parallel passes cost more instructions than the one sequential pass.
            let top_level = depth < 32 && 1 << depth < config.threads;
            let mid = if data_parallel && top_level {
                partition_in_parallel(order, in_left)
            } else {
                partition(order, in_left)
            };
            (axis, mid)
        }
        None if count <= config.max_leaf_size => return leaf(),
        None => {
            let axis = if extent.max_element() > 0.0 {
                extent.max_position()
            } else {
                (max - min).max_position()
            };
            let mid = count / 2;
            let key = |t: &u32| (primitives.centroid[*t as usize][axis], *t);
            order.select_nth_unstable_by(mid, |a, b| {
                key(a)
                    .partial_cmp(&key(b))
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            (axis, mid)
        }
    };

    let (left_order, right_order) = order.split_at_mut(mid);
    let mut left =
        move || build_recursive(primitives, config, left_order, start, depth + 1, parallel);
    let mut right = move || {
        build_recursive(
            primitives,
            config,
            right_order,
            start + mid,
            depth + 1,
            parallel,
        )
    };
    let children = if parallel && count >= PARALLEL_THRESHOLD {
        let (left, right) = rayon::join(left, right);
        [left, right]
    } else {
        [left(), right()]
    };
    BuildNode::Inner {
        min,
        max,
        axis: axis as u32,
        children: Box::new(children),
    }
}

fn bin_index(centroid: f32, cmin: f32, scale: f32) -> usize {
    (((centroid - cmin) * scale) as usize).min(BIN_COUNT - 1)
}

/// The cheapest `(cost, axis, first right bin)` over all axes with a nonzero centroid extent,
/// or `None` if no plane separates the centroids.
fn best_binned_split(
    primitives: &Primitives,
    config: &BvhConfig,
    order: &[u32],
    (min, max): (Vec3A, Vec3A),
    cmin: Vec3A,
    extent: Vec3A,
    parallel: bool,
) -> Option<(f32, usize, usize)> {
    let scale = Vec3A::new(
        if extent.x > 0.0 {
            BIN_COUNT as f32 / extent.x
        } else {
            0.0
        },
        if extent.y > 0.0 {
            BIN_COUNT as f32 / extent.y
        } else {
            0.0
        },
        if extent.z > 0.0 {
            BIN_COUNT as f32 / extent.z
        } else {
            0.0
        },
    );
    let fill = |order: &[u32]| {
        let mut bins = [[Bin::EMPTY; BIN_COUNT]; 3];
        for &t in order {
            let t = t as usize;
            let c = primitives.centroid[t];
            for axis in 0..3 {
                let b = bin_index(c[axis], cmin[axis], scale[axis]);
                bins[axis][b].grow(primitives.min[t], primitives.max[t], 1);
            }
        }
        bins
    };
    let bins = if parallel {
        use rayon::prelude::*;
        order.par_chunks(PARALLEL_CHUNK).map(fill).reduce(
            || [[Bin::EMPTY; BIN_COUNT]; 3],
            |mut a, b| {
                for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
                    a.grow(b.min, b.max, b.count);
                }
                a
            },
        )
    } else {
        fill(order)
    };
    let growth = primitives.growth;
    let parent_area = packet_area(min, max, growth);
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        // right_cost[b] = A * N of bins b..BIN_COUNT
        let mut right_cost = [0.0f32; BIN_COUNT];
        let mut right_count = [0usize; BIN_COUNT];
        let mut acc = Bin::EMPTY;
        for b in (1..BIN_COUNT).rev() {
            let bin = bins[axis][b];
            acc.grow(bin.min, bin.max, bin.count);
            right_cost[b] = packet_area(acc.min, acc.max, growth) * acc.count as f32;
            right_count[b] = acc.count;
        }
        let mut left = Bin::EMPTY;
        for b in 1..BIN_COUNT {
            let bin = bins[axis][b - 1];
            left.grow(bin.min, bin.max, bin.count);
            if left.count == 0 || right_count[b] == 0 {
                continue;
            }
            let weighted =
                packet_area(left.min, left.max, growth) * left.count as f32 + right_cost[b];
            let cost = if parent_area > 0.0 {
                config.traversal_cost + config.intersection_cost * weighted / parent_area
            } else {
                config.traversal_cost + config.intersection_cost * order.len() as f32
            };
            if best.is_none_or(|(best_cost, _, _)| cost < best_cost) {
                best = Some((cost, axis, b));
            }
        }
    }
    best
}

/// Moves the elements satisfying `in_left` to the front; returns how many there are.
fn partition(order: &mut [u32], in_left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0usize;
    let mut j = order.len();
    while i < j {
        if in_left(order[i]) {
            i += 1;
        } else {
            j -= 1;
            order.swap(i, j);
        }
    }
    i
}

/// [`partition`]'s exact result (the same order, not only the same two sets: the leaves'
/// triangle order, and so the kernels' layout and cycles, follow it), in parallel passes.
///
/// The sequential pass takes candidates from the front while they go left; one that goes
/// right is put at the back, and the next candidate is the back's next. With `l` elements
/// going left, the front's candidates are exactly positions `0..l` and the back's `l..n`
/// (as many go right in `0..l` as go left in `l..n`), so: the `k`th front element going right
/// (ascending) is replaced by the `k`th back element going left (descending) and lands where
/// the `k-1`th of those was, one lower (the first at `n - 1`); every other back element going
/// right moves one down; and the back's untouched tail below the last of them (all going
/// right) rotates by one, its first element to its end. Each position's source is found
/// from these, so the moves are one parallel gather.
fn partition_in_parallel(order: &mut [u32], in_left: impl Fn(u32) -> bool + Sync) -> usize {
    use rayon::prelude::*;
    let n = order.len();
    let left: Vec<bool> = order.par_iter().map(|&t| in_left(t)).collect();
    let l = left.par_iter().filter(|&&x| x).count();
    // (rayon's collect keeps the order)
    let front_right: Vec<u32> = (0..l)
        .into_par_iter()
        .filter(|&i| !left[i])
        .map(|i| i as u32)
        .collect();
    let back_left: Vec<u32> = (l..n)
        .into_par_iter()
        .rev()
        .filter(|&i| left[i])
        .map(|i| i as u32)
        .collect();
    debug_assert_eq!(front_right.len(), back_left.len());
    // Where the back's candidates stopped: below it, the untouched tail.
    let tail_end = back_left.last().map_or(n, |&j| j as usize);
    // Each chunk of destinations finds its first ranks among the moved by a search, then
    // counts on.
    let gather = |(c, chunk): (usize, &mut [u32])| {
        let first = c * PARALLEL_CHUNK;
        // front elements going right before `d`; back elements going left above `d + 1`
        let mut front = front_right.partition_point(|&p| (p as usize) < first);
        let mut back = back_left.partition_point(|&j| j as usize > first + 1);
        for (i, slot) in chunk.iter_mut().enumerate() {
            let d = first + i;
            let s = d + 1;
            let from = if d < l {
                if left[d] {
                    d
                } else {
                    front += 1;
                    back_left[front - 1] as usize
                }
            } else if s == tail_end && tail_end > l {
                l
            } else if s == n {
                front_right[0] as usize
            } else if left[s] {
                front_right[back + 1] as usize
            } else {
                s
            };
            if s + 1 < n && s + 1 >= l && left[s + 1] {
                back -= 1;
            }
            *slot = order[from];
        }
    };
    let mut moved = vec![0u32; n];
    moved
        .par_chunks_mut(PARALLEL_CHUNK)
        .enumerate()
        .for_each(gather);
    order
        .par_chunks_mut(PARALLEL_CHUNK)
        .zip(moved.par_chunks(PARALLEL_CHUNK))
        .for_each(|(to, from)| to.copy_from_slice(from));
    l
}

fn flatten(node: &BuildNode, index: usize, nodes: &mut Vec<BvhNode>) {
    match node {
        BuildNode::Leaf {
            min,
            max,
            start,
            count,
        } => {
            nodes[index] = BvhNode {
                min: *min,
                max: *max,
                link: *start as u32,
                count: *count as u32,
                axis: 0,
            };
        }
        BuildNode::Inner {
            min,
            max,
            axis,
            children,
        } => {
            let first = nodes.len();
            nodes.push(BvhNode::empty());
            nodes.push(BvhNode::empty());
            nodes[index] = BvhNode {
                min: *min,
                max: *max,
                link: first as u32,
                count: 0,
                axis: *axis,
            };
            flatten(&children[0], first, nodes);
            flatten(&children[1], first + 1, nodes);
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::scene::Triangle;
    use glam::Vec3;

    /// A deterministic triangle soup: small triangles scattered by an LCG, plus some
    /// duplicates (identical centroids) to exercise the median fallback.
    pub(crate) fn soup(count: usize) -> Scene {
        soup_sized(count, 0.3)
    }

    pub(crate) fn soup_sized(count: usize, size: f32) -> Scene {
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..count {
            let center = if i % 10 == 9 {
                Vec3::splat(0.5)
            } else {
                Vec3::new(next(), next(), next()) * 10.0
            };
            for _ in 0..3 {
                positions.push(center + Vec3::new(next(), next(), next()) * size);
            }
            let base = (3 * i) as u32;
            triangles.push(Triangle {
                v: [base, base + 1, base + 2],
                material: 0,
            });
        }
        Scene::from_parts(positions, None, Vec::new(), triangles, Vec::new())
    }

    #[test]
    fn invariants_hold_for_various_leaf_sizes() {
        let scene = soup(3000);
        for max_leaf_size in [1, 2, 4, 8] {
            let bvh = Bvh::build(
                &scene,
                &BvhConfig {
                    max_leaf_size,
                    ..Default::default()
                },
            );
            bvh.validate(&scene).unwrap();
            let stats = bvh.stats();
            assert_eq!(stats.leaves, stats.inner_nodes + 1);
            assert_eq!(bvh.nodes.len(), 2 * stats.inner_nodes + 2);
            assert!(bvh.sah_cost > 0.0 && bvh.sah_cost.is_finite());
        }
    }

    #[test]
    fn sah_cost_is_far_below_a_single_leaf() {
        let scene = soup(5000);
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        // One leaf would cost N * C_isect = 5000; a good tree is a few dozen.
        assert!(bvh.sah_cost < 100.0, "SAH cost {}", bvh.sah_cost);
    }

    #[test]
    fn result_does_not_depend_on_thread_count() {
        let scene = soup(60_000);
        let one = Bvh::build(
            &scene,
            &BvhConfig {
                threads: 1,
                ..Default::default()
            },
        );
        let four = Bvh::build(
            &scene,
            &BvhConfig {
                threads: 4,
                ..Default::default()
            },
        );
        assert_eq!(one.nodes, four.nodes);
        assert_eq!(one.triangle_order, four.triangle_order);
        one.validate(&scene).unwrap();
    }

    #[test]
    fn a_procedural_scene_builds_the_same_nodes_on_any_thread_count() {
        let scene = crate::procedural::by_name("beetle").unwrap();
        let build = |threads| {
            Bvh::build(
                &scene,
                &BvhConfig {
                    threads,
                    ..Default::default()
                },
            )
        };
        let one = build(1);
        one.validate(&scene).unwrap();
        for threads in [2, 3, 8] {
            let other = build(threads);
            assert_eq!(one.nodes, other.nodes, "{threads} threads");
            assert_eq!(
                one.triangle_order, other.triangle_order,
                "{threads} threads"
            );
            assert_eq!(one.sah_cost.to_bits(), other.sah_cost.to_bits());
        }
    }

    /// The parallel partition leaves every element where the sequential one does: random
    /// orders and sides, every share going left from none to all (the tail's rotation
    /// included), sizes around the parallel chunk's.
    #[test]
    fn the_parallel_partition_gives_the_sequential_order() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let sizes = [
            0,
            1,
            2,
            3,
            5,
            17,
            100,
            1000,
            PARALLEL_CHUNK + 3,
            3 * PARALLEL_CHUNK,
        ];
        for n in sizes {
            for share in 0..=8 {
                let mut order: Vec<u32> = (0..n as u32).collect();
                for i in (1..n).rev() {
                    order.swap(i, next() as usize % (i + 1));
                }
                let sides: Vec<bool> = (0..n).map(|_| next() % 8 < share).collect();
                let in_left = |t: u32| sides[t as usize];
                let mut sequential = order.clone();
                let l = partition(&mut sequential, in_left);
                let mut parallel = order.clone();
                let m = pool.install(|| partition_in_parallel(&mut parallel, in_left));
                assert_eq!(l, m, "{n} elements, {share}/8 left");
                assert!(sequential == parallel, "{n} elements, {share}/8 left");
            }
        }
    }

    #[test]
    fn tiny_and_degenerate_inputs() {
        let empty = Scene::from_parts(Vec::new(), None, Vec::new(), Vec::new(), Vec::new());
        let bvh = Bvh::build(&empty, &BvhConfig::default());
        assert_eq!(bvh.nodes.len(), 2);
        bvh.validate(&empty).unwrap();

        let one = soup(1);
        let bvh = Bvh::build(&one, &BvhConfig::default());
        assert!(bvh.root().is_leaf());
        bvh.validate(&one).unwrap();

        // Twenty identical triangles: no plane separates them, so median splits.
        let mut same = soup(1);
        same.triangles = vec![same.triangles[0]; 20];
        let bvh = Bvh::build(&same, &BvhConfig::default());
        bvh.validate(&same).unwrap();
        assert!(bvh.stats().max_leaf_triangles <= BvhConfig::default().max_leaf_size);
    }

    #[test]
    fn a_packet_wide_footprint_keeps_packet_sized_patches_in_one_leaf() {
        // A 128 x 128 grid of quads in the unit square (diagonal 1.41): a packet, 1/128 of
        // the diagonal, is about one quad wide, so splitting two quads buys a packet few
        // triangle tests, and the packet SAH keeps them in one leaf.
        let cells = 128u32;
        let mut positions = Vec::new();
        for y in 0..=cells {
            for x in 0..=cells {
                positions.push(Vec3::new(x as f32, y as f32, 0.0) / cells as f32);
            }
        }
        let mut triangles = Vec::new();
        for y in 0..cells {
            for x in 0..cells {
                let v = y * (cells + 1) + x;
                for v in [[v, v + 1, v + cells + 2], [v, v + cells + 2, v + cells + 1]] {
                    triangles.push(Triangle { v, material: 0 });
                }
            }
        }
        let scene = Scene::from_parts(positions, None, Vec::new(), triangles, Vec::new());
        let build = |packet_footprint| {
            let bvh = Bvh::build(
                &scene,
                &BvhConfig {
                    packet_footprint,
                    ..Default::default()
                },
            );
            bvh.validate(&scene).unwrap();
            bvh.stats()
        };
        let ray = build(0.0);
        let packet = build(PACKET_FOOTPRINT);
        // The ray SAH: a leaf per quad; the packet SAH: a leaf per two quads.
        assert_eq!((ray.leaves, ray.max_leaf_triangles), (16384, 2));
        assert_eq!((packet.leaves, packet.max_leaf_triangles), (8192, 4));
        // A footprint far below every box is the ray SAH.
        assert_eq!(build(1e-9).leaves, ray.leaves);
    }
}
