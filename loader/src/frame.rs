//! One frame in simulated main memory: where the scene, the parameter block, the tile
//! counter, the statistics blocks and the frame buffer live, and the image they make.
//!
//! Every region is 128-byte aligned (the DMA engine's best case, and the tile counter must
//! be a whole lock line for `getllar`/`putllc`).

use crate::camera::CameraBasis;
use crate::kernel_abi::{
    bounce_hits_bytes, check_kernel_options, colour_buffer_bytes, frame_buffer_bytes, ParamBlock,
    ShadingBlock, REFLECT_AREA_BYTES, REFLECT_MATERIALS, SHADED_LS_BYTES, SHADING_BLOCK_BYTES,
    STATS_BYTES,
};

/// Bytes of an SPU's local store.
const LS_BYTES: usize = 256 * 1024;
use crate::layout::StagedScene;

/// Main-memory address where the staged scene image starts.
pub const SCENE_BASE: u32 = 0x1_0000;

fn align128(value: u64) -> u64 {
    value.div_ceil(128) * 128
}

/// The addresses of one frame's regions in main memory.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameLayout {
    pub param_addr: u32,
    pub counter_addr: u32,
    pub stats_addr: u32,
    pub frame_buffer_addr: u32,
    pub frame_buffer_len: usize,
    /// Total bytes of main memory needed.
    pub memory_len: usize,
    pub params: ParamBlock,
    /// The shading block and the 32-bit colour frame buffer of a shaded frame.
    pub shading: Option<ShadingRegion>,
}

/// Where a shaded frame's shading block and colour frame buffer live.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadingRegion {
    pub block_addr: u32,
    pub colour_addr: u32,
    pub colour_len: usize,
    pub block: ShadingBlock,
    /// A reflect frame's: the reflectance table and the bounces' hits.
    pub reflect: Option<ReflectRegion>,
}

/// Where a reflect frame's per-material reflectance table and bounce-hit buffer live
/// (`modules/reflect.s`).
#[derive(Clone, Debug, PartialEq)]
pub struct ReflectRegion {
    pub table_addr: u32,
    pub hits_addr: u32,
    pub hits_len: usize,
}

impl FrameLayout {
    /// Places a `width x height` frame rendered by `spes` SPUs after the staged scene.
    pub fn new(
        staged: &StagedScene,
        basis: &CameraBasis,
        width: u32,
        height: u32,
        spes: usize,
        bvh_cache_lines: u32,
        tri_cache_lines: u32,
    ) -> Result<FrameLayout, String> {
        if staged.base != SCENE_BASE {
            return Err(format!("the scene must be staged at {SCENE_BASE:#x}"));
        }
        check_kernel_options(bvh_cache_lines, tri_cache_lines, 1, 1)?;
        let scene_end = SCENE_BASE as u64 + staged.image.len() as u64;
        let param_addr = align128(scene_end);
        let counter_addr = param_addr + 128;
        let stats_addr = counter_addr + 128;
        let frame_buffer_addr = align128(stats_addr + (spes * STATS_BYTES) as u64);
        let frame_buffer_len = frame_buffer_bytes(width, height);
        let memory_len = align128(frame_buffer_addr + frame_buffer_len as u64);
        if memory_len > u32::MAX as u64 {
            return Err(format!(
                "the frame needs {memory_len} bytes of main memory, over 4 GiB"
            ));
        }
        let mut params = ParamBlock::new(basis, width, height);
        params.ea_nodes = staged.header.node_addr;
        params.ea_triangles = staged.header.triangle_addr;
        params.ea_frame_buffer = frame_buffer_addr as u32;
        params.ea_tile_counter = counter_addr as u32;
        params.ea_stats = stats_addr as u32;
        params.bvh_cache_log2 = bvh_cache_lines.trailing_zeros();
        params.tri_cache_log2 = tri_cache_lines.trailing_zeros();
        Ok(FrameLayout {
            param_addr: param_addr as u32,
            counter_addr: counter_addr as u32,
            stats_addr: stats_addr as u32,
            frame_buffer_addr: frame_buffer_addr as u32,
            frame_buffer_len,
            memory_len: memory_len as usize,
            params,
            shading: None,
        })
    }

    /// Adds the shading block (its record addresses filled in from `staged`) and the colour
    /// frame buffer after the frame's other regions, and points the parameter block at it
    /// (the runtime places the module's local-store area: [`FrameLayout::set_shading_area`]).
    pub fn with_shading(
        mut self,
        staged: &StagedScene,
        mut block: ShadingBlock,
    ) -> Result<FrameLayout, String> {
        for (what, log2) in [
            ("vertex", block.vertex_cache_log2),
            ("material", block.material_cache_log2),
        ] {
            if !(4..=8).contains(&log2) {
                return Err(format!(
                    "{what} cache of {} entries: must be a power of two from 16 to 256",
                    1u64 << log2.min(63)
                ));
            }
        }
        if block.lights.len() > crate::shading::MAX_LIGHTS {
            return Err(format!(
                "{} lights: at most {}",
                block.lights.len(),
                crate::shading::MAX_LIGHTS
            ));
        }
        let block_addr = align128(self.memory_len as u64);
        let colour_addr = align128(block_addr + SHADING_BLOCK_BYTES as u64);
        let colour_len = colour_buffer_bytes(self.params.width, self.params.height);
        let mut memory_len = align128(colour_addr + colour_len as u64);
        let mut reflect = None;
        if block.reflect_depth > 0 {
            if staged.materials.len() > REFLECT_MATERIALS {
                return Err(format!(
                    "--shade reflect: the scene has {} materials, at most {REFLECT_MATERIALS}",
                    staged.materials.len()
                ));
            }
            let table_addr = memory_len;
            let hits_addr = align128(table_addr + 4 * REFLECT_MATERIALS as u64);
            let hits_len =
                bounce_hits_bytes(self.params.width, self.params.height, block.reflect_depth);
            memory_len = align128(hits_addr + hits_len as u64);
            block.ea_reflectances = table_addr as u32;
            block.ea_bounce_hits = hits_addr as u32;
            reflect = Some(ReflectRegion {
                table_addr: table_addr as u32,
                hits_addr: hits_addr as u32,
                hits_len,
            });
        }
        if memory_len > u32::MAX as u64 {
            return Err(format!(
                "the frame needs {memory_len} bytes of main memory, over 4 GiB"
            ));
        }
        block.ea_vertices = staged.header.vertex_addr;
        block.ea_materials = staged.header.material_addr;
        block.ea_colour = colour_addr as u32;
        self.params.ea_shading = block_addr as u32;
        self.memory_len = memory_len as usize;
        self.shading = Some(ShadingRegion {
            block_addr: block_addr as u32,
            colour_addr: colour_addr as u32,
            colour_len,
            block,
            reflect,
        });
        Ok(self)
    }

    /// Where the shading module works in local store (`modules/shade.s`): `ls_area`,
    /// rounded up to 128 bytes, must leave the shading and shadow areas (SHADED_LS_BYTES,
    /// `modules/shadow.s` works above the shading area) below 256 KiB.
    pub fn set_shading_area(&mut self, ls_area: u32) -> Result<(), String> {
        let ls_area = ls_area.div_ceil(128) * 128;
        let reflects = self.shading.as_ref().is_some_and(|s| s.reflect.is_some());
        let (bytes, what) = if reflects {
            (
                SHADED_LS_BYTES + REFLECT_AREA_BYTES,
                "shading, shadow and reflection areas",
            )
        } else {
            (SHADED_LS_BYTES, "shading and shadow areas")
        };
        if ls_area as usize + bytes > LS_BYTES {
            return Err(format!(
                "local store: the {what} ({bytes} bytes) do not fit above the kernel's caches at {ls_area:#x}: use smaller caches or fewer packets in flight"
            ));
        }
        self.params.ls_shading = ls_area;
        Ok(())
    }

    /// Sets the caches' associativity (1 or 4) and the packets each SPU keeps in flight
    /// (software hyperthreading, 1 to 8).
    pub fn with_kernel_options(mut self, assoc: u32, sht: u32) -> Result<FrameLayout, String> {
        check_kernel_options(
            1 << self.params.bvh_cache_log2,
            1 << self.params.tri_cache_log2,
            assoc,
            sht,
        )?;
        self.params.cache_assoc = assoc;
        self.params.sht_contexts = sht;
        Ok(self)
    }

    /// The initial main-memory image: scene, parameters, a zero tile counter, empty
    /// statistics and frame buffer.
    pub fn memory_image(&self, staged: &StagedScene) -> Vec<u8> {
        let mut memory = vec![0u8; self.memory_len];
        let base = SCENE_BASE as usize;
        memory[base..base + staged.image.len()].copy_from_slice(&staged.image);
        let p = self.param_addr as usize;
        memory[p..p + 128].copy_from_slice(&self.params.to_be_bytes());
        if let Some(shading) = &self.shading {
            let b = shading.block_addr as usize;
            memory[b..b + SHADING_BLOCK_BYTES].copy_from_slice(&shading.block.to_be_bytes());
            if let Some(r) = &shading.reflect {
                for (i, m) in staged.materials.iter().enumerate() {
                    let at = r.table_addr as usize + 4 * i;
                    memory[at..at + 4].copy_from_slice(&m.reflectance.to_bits().to_be_bytes());
                }
            }
        }
        memory
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{bvh::BvhConfig, procedural, Bvh};

    #[test]
    fn regions_are_aligned_and_disjoint() {
        let scene = procedural::room();
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE).unwrap();
        let basis = scene.camera.basis(128, 64);
        let f = FrameLayout::new(&staged, &basis, 128, 64, 4, 256, 256).unwrap();
        for a in [
            f.param_addr,
            f.counter_addr,
            f.stats_addr,
            f.frame_buffer_addr,
        ] {
            assert_eq!(a % 128, 0);
        }
        assert!(f.param_addr as usize >= SCENE_BASE as usize + staged.image.len());
        assert_eq!(f.frame_buffer_len, 2 * 64 * 1024);
        assert_eq!(f.params.num_tiles, 2);
        assert_eq!(f.params.bvh_cache_log2, 8);
        let memory = f.memory_image(&staged);
        assert_eq!(memory.len(), f.memory_len);
        let p = f.param_addr as usize;
        assert_eq!(&memory[p..p + 4], &staged.header.node_addr.to_be_bytes());
        assert!(FrameLayout::new(&staged, &basis, 128, 64, 4, 100, 256).is_err());
        let f4 = f.clone().with_kernel_options(4, 8).unwrap();
        assert_eq!((f4.params.cache_assoc, f4.params.sht_contexts), (4, 8));
        assert!(f.clone().with_kernel_options(3, 1).is_err());
        assert!(f.clone().with_kernel_options(1, 0).is_err());
        assert!(f.with_kernel_options(1, 9).is_err());
    }
}
