//! A moving scene's frames on the SPEs (`spu render --frames`): for each frame in order, the
//! animation's positions ([`crate::animation`]), the BVH refitted on the SPEs
//! ([`crate::spu_refit`], checked bit for bit against the host refit) or, where the policy
//! says so, rebuilt on the host ([`crate::refit`]), then the frame rendered and validated
//! as any other ([`crate::render`]).

use crate::animation::Animation;
use crate::frame::SCENE_BASE;
use crate::refit::{AnimatedBvh, RebuildPolicy};
use crate::render::{self, FrameResult, Prepared, RenderConfig};
use crate::runtime::{FrameError, Program};
use crate::spu_refit::{self, RefitConfig, RefitPlan, RefitRun};
use crate::{BvhConfig, StagedScene};
use spu_isa::jit::CodeCache;

/// Renders an animation's frames one after another.
pub struct Animator {
    pub animation: Animation,
    tree: AnimatedBvh,
    program: Program,
    /// The refit's work items, laid out for the current topology (rebuilds so far).
    plan: Option<(u32, RefitPlan)>,
    next: u32,
}

/// One rendered frame of an animation.
pub struct AnimatedFrame {
    pub index: u32,
    /// The frame's scene, staged with its tree (for validation).
    pub prepared: Prepared,
    pub frame: FrameResult,
    /// The SPEs' refit; `None` where the host rebuilt the tree instead.
    pub refit: Option<RefitRun>,
    /// The refitted tree's SAH cost and the cost at its last build.
    pub refit_cost: f32,
    pub built_cost: f32,
}

impl AnimatedFrame {
    /// Whether the host rebuilt the tree for this frame.
    pub fn rebuilt(&self) -> bool {
        self.refit.is_none()
    }

    /// The frame's statistics: refit and trace cycles, and frames per second with and
    /// without the refit at `clock_ghz`.
    pub fn stats(&self, clock_ghz: f64, validation: Option<&render::Validation>) -> FrameStats {
        let refit_cycles = self.refit.as_ref().map_or(0, |r| r.cycles);
        let trace_cycles = self.frame.run.frame_cycles;
        let fps = |cycles: u64| clock_ghz * 1e9 / cycles.max(1) as f64;
        FrameStats {
            frame: self.index,
            refit_cycles,
            trace_cycles,
            fps: fps(refit_cycles + trace_cycles),
            fps_without_refit: fps(trace_cycles),
            rebuilt: self.rebuilt(),
            sah_refit: self.refit_cost,
            sah_built: self.built_cost,
            refit_items: self.refit.as_ref().map_or(0, |r| r.items as u64),
            refit_dma_read: self.refit.as_ref().map_or(0, |r| r.dma_bytes.0),
            refit_dma_written: self.refit.as_ref().map_or(0, |r| r.dma_bytes.1),
            refit_spes: self
                .refit
                .as_ref()
                .map(|r| r.spes.clone())
                .unwrap_or_default(),
            mismatches: validation.map(|v| v.mismatches + v.colour_mismatches.unwrap_or(0)),
        }
    }
}

/// One frame's line of `spu render --frames --stats` (a JSON array of them).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrameStats {
    pub frame: u32,
    /// The slowest SPE's cycles refitting the BVH (0 where the host rebuilt it).
    pub refit_cycles: u64,
    /// The frame's ray-tracing cycles (the slowest SPE's).
    pub trace_cycles: u64,
    /// Frames per second including the refit.
    pub fps: f64,
    pub fps_without_refit: f64,
    /// The host rebuilt the tree (the refit's SAH cost passed the rebuild ratio).
    pub rebuilt: bool,
    pub sah_refit: f32,
    pub sah_built: f32,
    pub refit_items: u64,
    pub refit_dma_read: u64,
    pub refit_dma_written: u64,
    pub refit_spes: Vec<spu_refit::RefitSpe>,
    /// With `--validate`: pixels differing from the host reference (hits and colours).
    pub mismatches: Option<usize>,
}

impl Animator {
    /// The animation `scene` of `frames` frames, its tree built for frame 0 (and rebuilt
    /// when the policy says) on `threads` host threads (`--threads`; the trees do not
    /// depend on it).
    pub fn new(
        scene: &str,
        frames: u32,
        policy: RebuildPolicy,
        threads: usize,
    ) -> Result<Animator, String> {
        if policy.ratio.is_nan() || policy.ratio <= 1.0 {
            return Err(format!(
                "rebuild ratio {}: must be above 1 (a tree is never cheaper than built)",
                policy.ratio
            ));
        }
        let animation = Animation::open(scene, frames)?;
        let config = BvhConfig {
            threads: threads.max(1),
            ..BvhConfig::default()
        };
        let tree = AnimatedBvh::new(animation.first(), &config, policy);
        Ok(Animator {
            animation,
            tree,
            program: spu_refit::program()?,
            plan: None,
            next: 0,
        })
    }

    /// The next frame (they come in order: the tree follows the motion), rendered as
    /// `config` says (its scene must be the animation's name).
    pub fn next_frame(
        &mut self,
        config: &RenderConfig,
        code: &CodeCache,
        progress: &mut dyn FnMut(u32, u32),
    ) -> Result<AnimatedFrame, FrameError> {
        let index = self.next;
        let scene = self.animation.frame(index)?;
        let tree = self.tree.advance(&scene);
        let staged = StagedScene::new(&scene, &tree.bvh, SCENE_BASE)?;
        let refit = if tree.rebuilt {
            None
        } else {
            if self.plan.as_ref().map(|(r, _)| *r) != Some(self.tree.rebuilds) {
                self.plan = Some((self.tree.rebuilds, RefitPlan::new(&staged)?));
            }
            let (_, plan) = self.plan.as_ref().expect("laid out above");
            let refit_config = RefitConfig {
                spes: config.spes,
                threads: config.threads,
                clock_ghz: config.clock_ghz,
                dma_latency_ns: config.dma_latency_ns,
                timed: config.timing,
                engine: config.engine,
                max_cycles: config.max_cycles,
            };
            Some(spu_refit::run(
                &staged,
                plan,
                &refit_config,
                &self.program,
                code,
            )?)
        };
        let prepared = Prepared {
            name: self.animation.name.clone(),
            scene,
            staged,
        };
        let frame = render::render_with(&prepared, config, code, progress)?;
        self.next += 1;
        Ok(AnimatedFrame {
            index,
            prepared,
            frame,
            refit,
            refit_cost: tree.refit_cost,
            built_cost: tree.built_cost,
        })
    }
}
