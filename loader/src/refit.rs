//! BVH refit for moving scenes (paper section 9.3): the topology is built once, and each
//! frame only the node bounds are recomputed, bottom-up, from the frame's vertices; and the
//! policy that rebuilds the tree on the host when refitting has let it degrade.
//!
//! # The bounds, bit for bit
//!
//! A leaf's box is folded over its triangle records in order (`link .. link + count`), each
//! triangle's corners `v0, v1, v2` in order; an inner node's over its children `c`, `c + 1`.
//! The fold starts from the first point or box and takes, per coordinate, the new value
//! where it is smaller (minimum) or larger (maximum) by the SPU's own single-precision
//! comparison (`fcgt`, [`spu_isa::float::fcgt`]: denormals compare as zero, `-0 == +0`
//! keeps the value held). Minima and maxima round nothing, so the result is exact; fixing the
//! order and the comparison makes it the same bits as the SPU refit kernel's
//! ([`crate::spu_refit`]), which a test checks.
//!
//! # Rebuild policy
//!
//! A refitted tree keeps the split decisions of the frame it was built for; as the scene
//! moves, boxes grow and overlap and the tree's SAH cost rises. [`AnimatedBvh`] refits while
//! the refitted cost stays within [`RebuildPolicy::ratio`] times the cost the tree had when
//! it was built, and rebuilds on the host (a new topology) when it does not: comparing with
//! the last build's cost rather than a fresh build's costs no build per frame.

use glam::Vec3A;

use crate::bvh::{sah_cost, Bvh, BvhConfig};
use crate::scene::Scene;

/// `value` where it is below `held` (the SPU's `fcgt(held, value)`), else `held`.
fn lower(held: f32, value: f32) -> f32 {
    if spu_isa::float::fcgt(held.to_bits(), value.to_bits()) {
        value
    } else {
        held
    }
}

/// `value` where it is above `held` (the SPU's `fcgt(value, held)`), else `held`.
fn higher(held: f32, value: f32) -> f32 {
    if spu_isa::float::fcgt(value.to_bits(), held.to_bits()) {
        value
    } else {
        held
    }
}

/// A box folded as the SPU folds it.
#[derive(Clone, Copy)]
struct Fold {
    min: [f32; 3],
    max: [f32; 3],
}

impl Fold {
    fn of(min: Vec3A, max: Vec3A) -> Fold {
        Fold {
            min: min.to_array(),
            max: max.to_array(),
        }
    }

    fn grow(&mut self, min: Vec3A, max: Vec3A) {
        for k in 0..3 {
            self.min[k] = lower(self.min[k], min[k]);
            self.max[k] = higher(self.max[k], max[k]);
        }
    }
}

/// `bvh`'s topology with the bounds of `scene`'s positions (the scene `bvh` was built for,
/// or a frame of the same topology); the SAH cost is the refitted tree's.
pub fn refit(bvh: &Bvh, scene: &Scene) -> Bvh {
    let mut nodes = bvh.nodes.clone();
    let corner = |slot: usize, k: usize| {
        let t = &scene.triangles[bvh.triangle_order[slot] as usize];
        Vec3A::from(scene.positions[t.v[k] as usize])
    };
    // Children sit at higher indices than their parent (pairs in pre-order): from the end,
    // every child is refitted before its parent.
    for index in (0..nodes.len()).rev() {
        let node = nodes[index];
        if index == 1 || (index == 0 && bvh.triangle_order.is_empty()) {
            continue;
        }
        let fold = if node.is_leaf() {
            let first = corner(node.link as usize, 0);
            let mut fold = Fold::of(first, first);
            for slot in node.link as usize..(node.link + node.count) as usize {
                for k in 0..3 {
                    let p = corner(slot, k);
                    fold.grow(p, p);
                }
            }
            fold
        } else {
            let (a, b) = (nodes[node.link as usize], nodes[node.link as usize + 1]);
            let mut fold = Fold::of(a.min, a.max);
            fold.grow(b.min, b.max);
            fold
        };
        nodes[index].min = Vec3A::from_array(fold.min);
        nodes[index].max = Vec3A::from_array(fold.max);
    }
    let sah_cost = if bvh.triangle_order.is_empty() {
        0.0
    } else {
        sah_cost(&nodes, &bvh.config)
    };
    Bvh {
        nodes,
        triangle_order: bvh.triangle_order.clone(),
        config: bvh.config,
        sah_cost,
    }
}

/// When a refitted tree is rebuilt instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RebuildPolicy {
    /// Rebuild when the refitted SAH cost exceeds this times the cost at the last build
    /// (above 1; `f32::INFINITY`: never).
    pub ratio: f32,
}

/// The default [`RebuildPolicy::ratio`]: a tree 30% costlier than built is rebuilt.
pub const REBUILD_RATIO: f32 = 1.3;

impl Default for RebuildPolicy {
    fn default() -> Self {
        RebuildPolicy {
            ratio: REBUILD_RATIO,
        }
    }
}

/// What the policy did for one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameTree {
    /// The frame's tree: refitted, or rebuilt where `rebuilt`.
    pub bvh: Bvh,
    /// The refitted tree's SAH cost (before any rebuild).
    pub refit_cost: f32,
    /// The cost of the tree at its last build, which the policy compares against.
    pub built_cost: f32,
    /// Whether the host rebuilt the tree for this frame (its topology changed).
    pub rebuilt: bool,
}

/// A BVH that follows an animation: built for frame 0, refitted or rebuilt each frame.
pub struct AnimatedBvh {
    bvh: Bvh,
    built_cost: f32,
    config: BvhConfig,
    policy: RebuildPolicy,
    /// Rebuilds so far (frame 0's build not counted).
    pub rebuilds: u32,
}

impl AnimatedBvh {
    /// The tree built for `first`, the animation's frame 0.
    pub fn new(first: &Scene, config: &BvhConfig, policy: RebuildPolicy) -> AnimatedBvh {
        let bvh = Bvh::build(first, config);
        AnimatedBvh {
            built_cost: bvh.sah_cost,
            bvh,
            config: *config,
            policy,
            rebuilds: 0,
        }
    }

    /// The tree in use (the last frame's, or frame 0's as built).
    pub fn current(&self) -> &Bvh {
        &self.bvh
    }

    /// The tree for `scene`, a frame of the animation: the current tree refitted, or rebuilt
    /// where the refit's cost passes the policy's ratio.
    pub fn advance(&mut self, scene: &Scene) -> FrameTree {
        let refitted = refit(&self.bvh, scene);
        let refit_cost = refitted.sah_cost;
        let built_cost = self.built_cost;
        let rebuilt = refit_cost > self.policy.ratio * built_cost;
        self.bvh = if rebuilt {
            self.rebuilds += 1;
            let bvh = Bvh::build(scene, &self.config);
            self.built_cost = bvh.sah_cost;
            bvh
        } else {
            refitted
        };
        FrameTree {
            bvh: self.bvh.clone(),
            refit_cost,
            built_cost,
            rebuilt,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::animation::Animation;

    fn config() -> BvhConfig {
        BvhConfig {
            threads: 1,
            ..BvhConfig::default()
        }
    }

    #[test]
    fn refitting_a_tree_to_its_own_scene_gives_the_build_bounds() {
        let scene = crate::procedural::room();
        let bvh = Bvh::build(&scene, &config());
        let again = refit(&bvh, &scene);
        assert_eq!(again.nodes, bvh.nodes);
        assert_eq!(again.sah_cost.to_bits(), bvh.sah_cost.to_bits());
    }

    #[test]
    fn a_refitted_tree_contains_the_moved_triangles_tightly() {
        let animation = Animation::open("room-flag", 20).unwrap();
        let bvh = Bvh::build(animation.first(), &config());
        let moved = animation.frame(9).unwrap();
        let refitted = refit(&bvh, &moved);
        refitted.validate(&moved).unwrap();
        // tight: every leaf box is its triangles' box, so some corner lies on each face
        for node in refitted.nodes.iter().filter(|n| n.is_leaf()) {
            let slots = node.link as usize..(node.link + node.count) as usize;
            let corners: Vec<Vec3A> = slots
                .flat_map(|s| moved.triangle_positions(bvh.triangle_order[s] as usize))
                .map(Vec3A::from)
                .collect();
            let min = corners.iter().fold(Vec3A::INFINITY, |a, &p| a.min(p));
            let max = corners.iter().fold(Vec3A::NEG_INFINITY, |a, &p| a.max(p));
            assert_eq!((node.min, node.max), (min, max));
        }
        assert_ne!(refitted.nodes, bvh.nodes, "the flag moved");
        assert_eq!(refitted.triangle_order, bvh.triangle_order);
    }

    #[test]
    fn the_policy_rebuilds_when_the_cost_passes_the_ratio_and_says_so() {
        let animation = Animation::open("room-flag", 24).unwrap();
        let frames: Vec<Scene> = (0..24).map(|f| animation.frame(f).unwrap()).collect();
        // never: the tree keeps its topology
        let mut never = AnimatedBvh::new(
            &frames[0],
            &config(),
            RebuildPolicy {
                ratio: f32::INFINITY,
            },
        );
        let costs: Vec<FrameTree> = frames.iter().map(|f| never.advance(f)).collect();
        assert!(costs.iter().all(|t| !t.rebuilt));
        assert_eq!(never.rebuilds, 0);
        let worst = costs.iter().map(|t| t.refit_cost).fold(0.0, f32::max);
        let built = costs[0].built_cost;
        assert!(worst > built, "{worst} {built}");
        // a ratio just under the worst refit: some frame rebuilds, and reports it
        let ratio = (worst / built + 1.0) / 2.0;
        let mut sometimes = AnimatedBvh::new(&frames[0], &config(), RebuildPolicy { ratio });
        let trees: Vec<FrameTree> = frames.iter().map(|f| sometimes.advance(f)).collect();
        let rebuilt: Vec<&FrameTree> = trees.iter().filter(|t| t.rebuilt).collect();
        assert!(!rebuilt.is_empty());
        assert_eq!(sometimes.rebuilds as usize, rebuilt.len());
        for t in rebuilt {
            assert!(t.refit_cost > ratio * t.built_cost);
        }
        for (tree, frame) in trees.iter().zip(&frames) {
            tree.bvh.validate(frame).unwrap();
        }
    }
}
