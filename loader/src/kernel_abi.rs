//! The contract between the host and the ray-tracing kernel (`kernels/primary.s`): the
//! parameter block the kernel fetches at start, the statistics block it writes at the end,
//! and the packet-major frame buffer it fills.
//!
//! The kernel reads every offset below from the `.set` lines of [`spu_include`], so this
//! module is the single source of truth for both sides. All records are big-endian.

use std::mem::{offset_of, size_of};

use crate::camera::CameraBasis;

/// Pixels per tile side (the paper's 64x64 image tiles, section 8).
pub const TILE_SIZE: u32 = 64;
/// Pixels per packet side (8x8 rays, section 3.2).
pub const PACKET_SIZE: u32 = 8;
/// Packets per tile.
pub const PACKETS_PER_TILE: u32 = (TILE_SIZE / PACKET_SIZE) * (TILE_SIZE / PACKET_SIZE);
/// Bytes of one packet's result block: triangle ids, distances, shades, reserved.
pub const PACKET_BLOCK_BYTES: u32 = 1024;
/// Triangle id written for rays that hit nothing.
pub const MISS: u32 = u32::MAX;

/// The 128-byte parameter block, at an effective address passed in `$4`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ParamBlock {
    pub ea_nodes: u32,
    pub ea_triangles: u32,
    pub ea_frame_buffer: u32,
    /// A 128-byte lock line whose first word is the next tile to render.
    pub ea_tile_counter: u32,
    pub width: u32,
    pub height: u32,
    pub tiles_x: u32,
    pub num_tiles: u32,
    pub origin: [f32; 4],
    pub dir00: [f32; 4],
    pub du: [f32; 4],
    pub dv: [f32; 4],
    /// log2 of the number of 64-byte lines in the BVH-node and triangle caches.
    pub bvh_cache_log2: u32,
    pub tri_cache_log2: u32,
    /// Base of the statistics blocks, one of [`STATS_BYTES`] per SPU.
    pub ea_stats: u32,
    pub flags: u32,
    /// Packets each SPU keeps in flight (software hyperthreading, paper section 6):
    /// 1 = blocking cache misses, up to [`MAX_SHT_CONTEXTS`].
    pub sht_contexts: u32,
    /// Ways of both caches: 1 (direct mapped) or 4 (set-associative, LRU).
    pub cache_assoc: u32,
    /// The shading block ([`ShadingBlock`]; 0 when the frame is not shaded) and the
    /// local-store address of the shading module's area, above everything carved at
    /// `cache_area` (the host knows the kernel's symbols and the carve).
    pub ea_shading: u32,
    pub ls_shading: u32,
}
const _: () = assert!(std::mem::size_of::<ParamBlock>() == 128);

pub const PARAM_EA_NODES: usize = std::mem::offset_of!(ParamBlock, ea_nodes);
pub const PARAM_WIDTH: usize = std::mem::offset_of!(ParamBlock, width);
pub const PARAM_ORIGIN: usize = std::mem::offset_of!(ParamBlock, origin);
pub const PARAM_DIR00: usize = std::mem::offset_of!(ParamBlock, dir00);
pub const PARAM_DU: usize = std::mem::offset_of!(ParamBlock, du);
pub const PARAM_DV: usize = std::mem::offset_of!(ParamBlock, dv);
pub const PARAM_BVH_LOG2: usize = std::mem::offset_of!(ParamBlock, bvh_cache_log2);
pub const PARAM_SHT: usize = std::mem::offset_of!(ParamBlock, sht_contexts);

/// The most packets one SPU keeps in flight.
pub const MAX_SHT_CONTEXTS: u32 = 8;
/// Cache line counts the kernel supports (powers of two).
pub const MIN_CACHE_LINES: u32 = 128;
pub const MAX_CACHE_LINES: u32 = 1024;
/// Bytes of one cache line (a BVH node pair or a triangle record) and of its tag.
pub const CACHE_LINE_BYTES: u32 = 64;
pub const CACHE_TAG_BYTES: u32 = 16;

/// One packet context in the kernel's local store (software hyperthreading): the packet's
/// rays, its traversal stack and what it needs to be suspended on a cache miss and resumed.
/// Offsets are from the context pointer (the kernel's `RAYS` register, the first ray
/// array), which sits [`context::HEADER`] bytes into the context; the kernel reads them from
/// `layout.inc`.
pub mod context {
    /// Bytes before the context pointer: the corner rays and the near-child table, within
    /// reach of an `ai` immediate.
    pub const HEADER: i32 = 128;
    /// The corner rays' x, y, z (rays 0, 7, 56, 63) for the packet frustum.
    pub const CORNERS: i32 = -128;
    /// Per axis all ones when the first active ray points down it.
    pub const NEGTAB: i32 = -80;
    /// Ray arrays, 16 vectors of 4 rays each: directions, reciprocals, t, hit id, n.d, 1/|d|.
    pub const RAY_ARRAY_BYTES: i32 = 256;
    pub const RAY_DX: i32 = 0;
    pub const RAY_RX: i32 = 3 * RAY_ARRAY_BYTES;
    pub const RAY_T: i32 = 6 * RAY_ARRAY_BYTES;
    pub const RAY_ID: i32 = 7 * RAY_ARRAY_BYTES;
    pub const RAY_ND: i32 = 8 * RAY_ARRAY_BYTES;
    pub const RAY_INVD: i32 = 9 * RAY_ARRAY_BYTES;
    /// Record index of the triangle in each staging slot (one quadword each; -1: none).
    pub const STAGE_TAGS: i32 = 10 * RAY_ARRAY_BYTES;
    /// Triangles of one leaf the staging area holds (the BVH's leaves hold at most this).
    pub const STAGE_TRIANGLES: u32 = 8;
    /// Registers of the suspended packet, one quadword each; then its resume address (0:
    /// the context is not suspended), its tile * 64 and its packet number in the tile.
    pub const SAVE: i32 = STAGE_TAGS + 16 * STAGE_TRIANGLES as i32;
    pub const SAVE_SLOTS: i32 = 32;
    pub const SAVED_REGISTERS: i32 = 27;
    pub const RESUME: i32 = SAVE + 16 * SAVED_REGISTERS;
    pub const TILE64: i32 = RESUME + 16;
    pub const PACKET: i32 = TILE64 + 16;
    /// The next context in turn (its context pointer), and the DMA tag: (tag, 1 << tag).
    pub const NEXT: i32 = PACKET + 16;
    pub const TAG: i32 = NEXT + 16;
    /// The BVH node pair being fetched.
    pub const STAGE_PAIR: i32 = SAVE + 16 * SAVE_SLOTS;
    /// Triangle records being fetched, 64 bytes each.
    pub const STAGE_TRIS: i32 = STAGE_PAIR + 64;
    /// The traversal stack: what popping an empty stack reads, then 128 entries.
    pub const STACK: i32 = STAGE_TRIS + 64 * STAGE_TRIANGLES as i32 + 16;
    pub const STACK_BYTES: i32 = 2048;
    /// Bytes of one context (a multiple of 128).
    pub const BYTES: u32 = ((HEADER + STACK + STACK_BYTES) as u32).div_ceil(128) * 128;

    // the header fits below the context pointer, the saved state in its slots, the stack
    // after the staging lines
    const _: () = assert!(NEGTAB + 48 <= 0 && CORNERS + 48 <= NEGTAB && -HEADER <= CORNERS);
    const _: () = assert!(TAG < SAVE + 16 * SAVE_SLOTS && STAGE_PAIR == SAVE + 16 * SAVE_SLOTS);
    const _: () = assert!(STACK >= STAGE_TRIS + 64 * STAGE_TRIANGLES as i32 + 16);
    const _: () =
        assert!(HEADER + STACK + STACK_BYTES <= BYTES as i32 && BYTES.is_multiple_of(128));
}

/// The context's DMA tag: `CONTEXT_TAG0 + context index`.
pub const CONTEXT_TAG0: u32 = 8;

/// Checks the cache and software-hyperthreading options the kernel supports.
pub fn check_kernel_options(
    bvh_cache_lines: u32,
    tri_cache_lines: u32,
    assoc: u32,
    sht: u32,
) -> Result<(), String> {
    for (what, lines) in [("BVH", bvh_cache_lines), ("triangle", tri_cache_lines)] {
        if !lines.is_power_of_two() || !(MIN_CACHE_LINES..=MAX_CACHE_LINES).contains(&lines) {
            return Err(format!(
                "{what} cache of {lines} lines: must be a power of two from {MIN_CACHE_LINES} to {MAX_CACHE_LINES}"
            ));
        }
    }
    if assoc != 1 && assoc != 4 {
        return Err(format!(
            "cache associativity {assoc}: must be 1 (direct mapped) or 4"
        ));
    }
    if !(1..=MAX_SHT_CONTEXTS).contains(&sht) {
        return Err(format!(
            "{sht} packets in flight (SHT): must be 1 to {MAX_SHT_CONTEXTS}"
        ));
    }
    Ok(())
}

/// Local-store bytes the kernel carves at `cache_area` for its caches and packet contexts.
pub fn carved_bytes(bvh_cache_lines: u32, tri_cache_lines: u32, sht: u32) -> u32 {
    (bvh_cache_lines + tri_cache_lines) * (CACHE_LINE_BYTES + CACHE_TAG_BYTES)
        + sht * context::BYTES
}

impl ParamBlock {
    pub fn new(basis: &CameraBasis, width: u32, height: u32) -> Self {
        let v = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        let tiles_x = width.div_ceil(TILE_SIZE);
        let tiles_y = height.div_ceil(TILE_SIZE);
        ParamBlock {
            width,
            height,
            tiles_x,
            num_tiles: tiles_x * tiles_y,
            origin: v(basis.origin),
            dir00: v(basis.dir00),
            du: v(basis.du),
            dv: v(basis.dv),
            bvh_cache_log2: 8,
            tri_cache_log2: 8,
            sht_contexts: 1,
            cache_assoc: 1,
            ..Default::default()
        }
    }

    /// The block as the kernel reads it (big-endian words).
    pub fn to_be_bytes(&self) -> [u8; 128] {
        let mut words = vec![
            self.ea_nodes,
            self.ea_triangles,
            self.ea_frame_buffer,
            self.ea_tile_counter,
            self.width,
            self.height,
            self.tiles_x,
            self.num_tiles,
        ];
        for v in [self.origin, self.dir00, self.du, self.dv] {
            words.extend(v.iter().map(|f| f.to_bits()));
        }
        words.extend([
            self.bvh_cache_log2,
            self.tri_cache_log2,
            self.ea_stats,
            self.flags,
            self.sht_contexts,
            self.cache_assoc,
        ]);
        words.extend([self.ea_shading, self.ls_shading]);
        let mut out = [0u8; 128];
        for (chunk, w) in out.chunks_exact_mut(4).zip(words) {
            chunk.copy_from_slice(&w.to_be_bytes());
        }
        out
    }
}

/// Offset in the parameter block of the shading block's address and the shading area's
/// (zero when the frame is not shaded, `--shade none`): the quadword holding them and the
/// byte rotation that brings the address to the preferred slot (the area's is 4 further).
pub const PARAM_EA_SHADING: usize = std::mem::offset_of!(ParamBlock, ea_shading);
pub const PARAM_SHADING_QUAD: usize = PARAM_EA_SHADING & !15;
pub const PARAM_SHADING_ROT: usize = PARAM_EA_SHADING & 15;
const _: () = assert!(
    std::mem::offset_of!(ParamBlock, ls_shading) == PARAM_EA_SHADING + 4 && PARAM_SHADING_ROT <= 8
);

/// Shading modes as the kernel reads them ([`ShadingBlock::mode`]).
pub const SHADE_SIMPLE: u32 = 1;
pub const SHADE_SHADOWS: u32 = 2;

/// One quadword of local store or of a record: four big-endian words.
pub type Quad = [u32; 4];

/// The shading block (`modules/shade.s`), at [`PARAM_EA_SHADING`]: where the vertex and
/// material records and the 32-bit colour frame buffer are, the mode, the shading caches'
/// sizes and up to [`crate::shading::MAX_LIGHTS`] point lights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadingBlock {
    pub ea_vertices: u32,
    pub ea_materials: u32,
    /// The colour frame buffer: 256 bytes (64 pixels 0xRRGGBBAA, row-major in the packet)
    /// per packet, packet-major like the result blocks: 4 MiB for a 1024x1024 frame.
    pub ea_colour: u32,
    pub mode: u32,
    /// Shadow packets stop as soon as every active ray is occluded.
    pub shadow_early: bool,
    /// log2 of the entries of the direct-mapped vertex and material caches (4..=8).
    pub vertex_cache_log2: u32,
    pub material_cache_log2: u32,
    pub lights: Vec<crate::shading::Light>,
    /// Reflection bounces per primary ray (0: none; the reflect program only).
    pub reflect_depth: u32,
    /// Where the reflectance of every material is ([`REFLECT_MATERIALS`] words, f32) and
    /// where the bounces' hits go ([`bounce_hits_bytes`]); set by the frame's layout.
    pub ea_reflectances: u32,
    pub ea_bounce_hits: u32,
}

/// The shading block as the kernel reads it ([`ShadingBlock::to_be_bytes`]): its offsets
/// are the `SHB_*` of `layout.inc`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadingBlockRecord {
    pub ea_vertices: u32,
    pub ea_materials: u32,
    pub ea_colour: u32,
    pub light_count: u32,
    /// The mode, then the three words the kernel reads with it in one quadword: shadow
    /// early termination (0 or 1), the vertex and material caches' log2 entries.
    pub mode: u32,
    pub shadow_early: u32,
    pub vertex_cache_log2: u32,
    pub material_cache_log2: u32,
    /// Reflect frames' (`modules/reflect.s`; zero in the others): reflection bounces per
    /// primary ray, the per-material reflectance table, the bounces' hit buffer.
    pub reflect_depth: u32,
    pub ea_reflectances: u32,
    pub ea_bounce_hits: u32,
    pub reserved: [u32; 5],
    pub lights: [LightRecord; crate::shading::MAX_LIGHTS],
    /// Room for two more lights: the block stays the 384 bytes the kernel fetches.
    pub spare: [LightRecord; 2],
}

/// One point light of the shading block.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LightRecord {
    /// x, y, z, 0.
    pub position: [f32; 4],
    /// r, g, b, 0.
    pub colour: [f32; 4],
}

/// Bytes of the shading block.
pub const SHADING_BLOCK_BYTES: usize = size_of::<ShadingBlockRecord>();
pub const SHB_EA_VERTICES: usize = offset_of!(ShadingBlockRecord, ea_vertices);
pub const SHB_LIGHT_COUNT: usize = offset_of!(ShadingBlockRecord, light_count);
pub const SHB_REFLECT: usize = offset_of!(ShadingBlockRecord, reflect_depth);
pub const SHB_MODE: usize = offset_of!(ShadingBlockRecord, mode);
pub const SHB_LIGHTS: usize = offset_of!(ShadingBlockRecord, lights);
/// Bytes per light: position (x, y, z, 0), colour (r, g, b, 0).
pub const SHB_LIGHT_BYTES: usize = size_of::<LightRecord>();
const _: () = assert!(SHADING_BLOCK_BYTES == 384 && SHADING_BLOCK_BYTES.is_multiple_of(128));
// the kernel reads the mode and the three words after it as one quadword
const _: () = assert!(
    SHB_MODE.is_multiple_of(16)
        && offset_of!(ShadingBlockRecord, material_cache_log2) == SHB_MODE + 12
);
/// Bytes of one packet's block in the colour frame buffer.
pub const COLOUR_BLOCK_BYTES: u32 = 256;

/// One of the shading module's counters: the kernel counts in word 0 of a quadword of its
/// area (32 bits); the host keeps the count, summed over SPUs, in 64.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counter(pub u64);

/// Declares [`ShadeCounters`] from one list: each field, what it counts and its assembler
/// name, from which the offsets in `layout.inc`, the host's decoding and its sums follow.
macro_rules! shade_counters {
    ($($(#[doc = $doc:literal])* $field:ident => $spu:literal,)*) => {
        /// The shading module's counters (`SH_STATS` in its area, one per quadword), in
        /// the order the kernel keeps them; the host reads them from each SPU's local
        /// store, as the PPE reads an SPE's memory-mapped local store.
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
        pub struct ShadeCounters {
            $($(#[doc = $doc])* pub $field: Counter,)*
        }

        impl ShadeCounters {
            /// Each counter's `SHS_*` name (its offset in `SH_STATS`) and offset.
            pub const SPU_NAMES: &[(&str, usize)] =
                &[$(($spu, offset_of!(ShadeCounters, $field)),)*];

            /// Decodes the counters from local-store bytes starting at `SH_STATS` (a
            /// counter past the end reads 0).
            pub fn from_be_bytes(bytes: &[u8]) -> Self {
                let word = |at: usize| {
                    bytes
                        .get(at..at + 4)
                        .map_or(0, |b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as u64)
                };
                ShadeCounters {
                    $($field: Counter(word(offset_of!(ShadeCounters, $field))),)*
                }
            }

            /// Adds `other`'s counts to these.
            pub fn add(&mut self, other: &ShadeCounters) {
                $(self.$field.0 += other.$field.0;)*
            }
        }
    };
}

shade_counters! {
    /// Intersection packets (4 rays) with a hit.
    groups => "SHS_GROUPS",
    /// ... whose 4 rays hit the same triangle.
    same => "SHS_SAME",
    /// Shading passes (one per material of a packet).
    passes => "SHS_PASSES",
    /// Packets shaded.
    packets => "SHS_PACKETS",
    /// Vertex cache lookups (kept 0 by the kernel: three per triangle record looked up,
    /// which the host derives from `triangle_lookups`).
    vertex_lookups => "SHS_VLOOK",
    vertex_misses => "SHS_VMISS",
    /// Material cache lookups (one per pass) and misses.
    material_lookups => "SHS_MLOOK",
    material_misses => "SHS_MMISS",
    /// Triangle records looked up in the traversal's triangle cache, and fetched past it.
    triangle_lookups => "SHS_TLOOK",
    triangle_misses => "SHS_TMISS",
}

impl ShadeCounters {
    /// The counters summed over SPUs.
    pub fn sum(counters: &[ShadeCounters]) -> ShadeCounters {
        let mut total = ShadeCounters::default();
        for c in counters {
            total.add(c);
        }
        total
    }
}

/// The most entries of the shading module's vertex and material caches.
pub const SHADING_CACHE_ENTRIES: usize = 256;
/// Vertex lookups of one intersection packet the slow path keeps in flight (3 per lane).
pub const SHADING_VERTICES_IN_FLIGHT: usize = 12;

/// The shading module's local-store area (`modules/shade_area.s`), at
/// [`ParamBlock::ls_shading`], above everything the kernel carves: its offsets are the
/// `SH_*` of `layout.inc`. Set up on the first call (the block fetched, the lights
/// splatted, the counters and the caches' tags cleared); the host reads the counters.
#[repr(C)]
pub struct ShadingArea {
    /// "SHAD" (word 0) once set up.
    pub flag: Quad,
    pub stats: ShadeCounters,
    /// Over a run of the shading block: the next light, the lights left, the material.
    pub run: [Quad; 3],
    /// The colour block's EA, its tag, the material cache's EA, its index mask.
    pub output: Quad,
    /// The vertex index mask in every lane.
    pub vertex_mask: Quad,
    /// The shading block, as fetched.
    pub block: ShadingBlockRecord,
    /// Per light: position x, y, z and colour r, g, b, each splatted.
    pub lights: [[Quad; 6]; crate::shading::MAX_LIGHTS],
    pub scratch: ShadeScratch,
    /// Per lane: the triangle record (the slow path's staging).
    pub stage: [[Quad; 4]; 4],
    /// Per lane: the vertex normals n0, n1, n2 and one spare.
    pub normals: [[Quad; 4]; 4],
    /// The i-set, 16 vectors of 4 rays each: normal (facing the eye), hit point,
    /// material (-1: none left).
    pub nx: [Quad; 16],
    pub ny: [Quad; 16],
    pub nz: [Quad; 16],
    pub px: [Quad; 16],
    pub py: [Quad; 16],
    pub pz: [Quad; 16],
    pub material: [Quad; 16],
    /// Two colour blocks, alternating.
    pub out: [[u8; COLOUR_BLOCK_BYTES as usize]; 2],
    /// Per light: the rays' visibility masks (the shadow module's, all ones without).
    pub visibility: [[Quad; 16]; crate::shading::MAX_LIGHTS],
    /// The direct-mapped vertex cache: tags, 64-byte lines (vertex records).
    pub vertex_tags: [Quad; SHADING_CACHE_ENTRIES],
    pub vertex_lines: [[Quad; 4]; SHADING_CACHE_ENTRIES],
    /// The direct-mapped material cache: tags, 32-byte lines (material records).
    pub material_tags: [Quad; SHADING_CACHE_ENTRIES],
    pub material_lines: [[Quad; 2]; SHADING_CACHE_ENTRIES],
    /// The vertices in flight (`sh_vertex_miss`): bytes of their copies (word 0), the
    /// copies (source, lane, tag, vertex; line), a spare, and their staging slots.
    pub deferred_bytes: Quad,
    pub deferred: [[Quad; 2]; SHADING_VERTICES_IN_FLIGHT],
    pub spare: [Quad; 7],
    pub vertex_stage: [[Quad; 4]; SHADING_VERTICES_IN_FLIGHT],
}

/// The shading area's scratch (the irradiance sums lie over it and the two arrays after
/// it once the i-set is built).
#[repr(C)]
pub struct ShadeScratch {
    /// The normals' columns.
    pub columns: [Quad; 9],
    /// Which of the fast path's two groups are done.
    pub groups_done: Quad,
    /// The fast path's registers over the slow path.
    pub save: [Quad; 5],
    /// The slow path's same-triangle flag, kept over the fetches.
    pub same: Quad,
}

/// Local-store bytes of the shading module's area.
pub const SHADING_AREA_BYTES: usize = size_of::<ShadingArea>();
/// Offset of the shading module's counters in its area (`SH_STATS`).
pub const SHADE_STATS_OFFSET: usize = offset_of!(ShadingArea, stats);

/// The shadow module's area (`modules/shadow.s`), right above the shading area: its
/// offsets are the `SV_*` of `layout.inc`.
#[repr(C)]
pub struct ShadowArea {
    /// The shadow rays cast (word 0).
    pub rays: Quad,
    /// The light being traced.
    pub light: Quad,
    /// The five miss-handler words of `vars`, saved while the shadow packets run.
    pub handlers: [Quad; 6],
    /// The registers the shadow packets change and the caller keeps, one quadword each
    /// (by register number).
    pub registers: [Quad; 128],
    /// The shadow packets' own packet context.
    pub context: [u8; context::BYTES as usize],
}

/// The shadow area's offset from the shading area.
pub const SHADOW_AREA: usize = SHADING_AREA_BYTES;
/// Offset in the shadow area of the shadow rays cast (word 0 of the quadword).
pub const SHADOW_RAYS_OFFSET: usize = offset_of!(ShadowArea, rays);
/// Offset in the shadow area of the shadow packets' context (its start, not its pointer).
pub const SHADOW_CONTEXT_OFFSET: usize = offset_of!(ShadowArea, context);
/// Bytes of the shadow area.
pub const SHADOW_AREA_BYTES: usize = size_of::<ShadowArea>();
/// Local-store bytes a shaded frame needs above the kernel's caches: the shading and
/// shadow areas.
pub const SHADED_LS_BYTES: usize = SHADING_AREA_BYTES + SHADOW_AREA_BYTES;
/// The DMA tag of the shadow packets' context.
pub const SHADOW_TAG: u32 = 1;

/// The reflection module's area (`modules/reflect.s`), right above the shadow area, in
/// reflect frames only: its offsets are the `RF_*` of `layout.inc`. Level 0 is the
/// primary rays, level `k` the `k`-th reflection.
#[repr(C)]
pub struct ReflectArea {
    /// "REFL" (word 0) once the reflectance table is fetched.
    pub flag: Quad,
    /// The level being shaded, the depth, the packet number, the primary rays' address.
    pub state: Quad,
    /// The ray being traced (word 0).
    pub trace: Quad,
    /// The rays the level casts (word 0).
    pub cast: Quad,
    /// The five miss-handler words of `vars`, saved while the reflected rays run.
    pub handlers: [Quad; 6],
    /// The registers the reflected rays' traversal changes and the caller keeps.
    pub registers: [Quad; 128],
    /// The traversal's statistics when the level's tracing started.
    pub before: [Quad; 8],
    /// Per bounce (1 first), its counters.
    pub counters: [ReflectCounters; crate::shading::MAX_REFLECT_DEPTH as usize],
    /// Per material, its reflectance (f32), as fetched.
    pub reflectances: [u32; REFLECT_MATERIALS],
    /// Per level below the last, the reflectance of each ray's surface where it casts a
    /// reflected ray, 0 where it casts none.
    pub weights: [[Quad; 16]; crate::shading::MAX_REFLECT_DEPTH as usize],
    /// Per level, the colours the shading module gave the packet (its colour block).
    pub colours:
        [[u8; COLOUR_BLOCK_BYTES as usize]; crate::shading::MAX_REFLECT_DEPTH as usize + 1],
    /// The next level's rays: origin and direction (x, y, z), and all ones where cast.
    pub ray_origin: [[Quad; 16]; 3],
    pub ray_dir: [[Quad; 16]; 3],
    pub ray_cast: [Quad; 16],
    /// The traced level's hits (the triangle record or -1, t), as put to the bounce-hit
    /// buffer.
    pub hit_id: [Quad; 16],
    pub hit_t: [Quad; 16],
    /// The traced level's hits as the shading module reads a packet's rays (at the packet
    /// context's ray offsets): the hit point as `d`, `t` = 1, the record.
    pub rays: [u8; context::RAY_ND as usize],
    /// The reflected rays' packet context (one ray each).
    pub context: [u8; context::BYTES as usize],
}

/// One bounce's counters in the reflection area (word 0 of each quadword), read by the
/// host as the shading module's.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReflectCounters {
    /// Rays cast, packets with any ray, rays that hit.
    pub rays: Counter,
    pub packets: Counter,
    pub hits: Counter,
    /// The traversal's work for them: pair steps, BVH cache misses, leaves, triangle
    /// lookups and triangle cache misses.
    pub steps: Counter,
    pub bvh_misses: Counter,
    pub leaves: Counter,
    pub triangle_lookups: Counter,
    pub triangle_misses: Counter,
}

impl ReflectCounters {
    /// Decodes the counters from local-store bytes at their offset.
    pub fn from_be_bytes(bytes: &[u8]) -> ReflectCounters {
        let word = |i: usize| {
            bytes
                .get(16 * i..16 * i + 4)
                .map_or(0, |w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]) as u64)
        };
        ReflectCounters {
            rays: Counter(word(0)),
            packets: Counter(word(1)),
            hits: Counter(word(2)),
            steps: Counter(word(3)),
            bvh_misses: Counter(word(4)),
            leaves: Counter(word(5)),
            triangle_lookups: Counter(word(6)),
            triangle_misses: Counter(word(7)),
        }
    }

    pub fn add(&mut self, o: &ReflectCounters) {
        for (a, b) in [
            (&mut self.rays, o.rays),
            (&mut self.packets, o.packets),
            (&mut self.hits, o.hits),
            (&mut self.steps, o.steps),
            (&mut self.bvh_misses, o.bvh_misses),
            (&mut self.leaves, o.leaves),
            (&mut self.triangle_lookups, o.triangle_lookups),
            (&mut self.triangle_misses, o.triangle_misses),
        ] {
            a.0 += b.0;
        }
    }
}

/// Materials a reflect frame's reflectance table holds (a scene with more is refused).
pub const REFLECT_MATERIALS: usize = 256;
/// The reflection area's offset from the shading area.
pub const REFLECT_AREA: usize = SHADOW_AREA + SHADOW_AREA_BYTES;
/// Bytes of the reflection area.
pub const REFLECT_AREA_BYTES: usize = size_of::<ReflectArea>();
/// Offset in the reflection area of the first bounce's counters.
pub const REFLECT_COUNTERS_OFFSET: usize = offset_of!(ReflectArea, counters);
/// The DMA tag of the reflected rays' context.
pub const REFLECT_TAG: u32 = 4;
/// Bytes of the bounce-hit buffer of a reflect frame: per packet (packet-major like the
/// result blocks), per bounce, 64 triangle records (or -1) and 64 distances.
pub fn bounce_hits_bytes(width: u32, height: u32, depth: u32) -> usize {
    frame_buffer_bytes(width, height) / 2 * depth as usize
}

impl ShadingBlock {
    /// The block as a record: its lights (at most [`crate::shading::MAX_LIGHTS`]) and
    /// their count.
    pub fn record(&self) -> ShadingBlockRecord {
        let mut lights = [LightRecord::default(); crate::shading::MAX_LIGHTS];
        for (record, light) in lights.iter_mut().zip(&self.lights) {
            let v = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
            *record = LightRecord {
                position: v(light.position),
                colour: v(light.colour),
            };
        }
        ShadingBlockRecord {
            ea_vertices: self.ea_vertices,
            ea_materials: self.ea_materials,
            ea_colour: self.ea_colour,
            light_count: self.lights.len().min(lights.len()) as u32,
            mode: self.mode,
            shadow_early: self.shadow_early as u32,
            vertex_cache_log2: self.vertex_cache_log2,
            material_cache_log2: self.material_cache_log2,
            reflect_depth: self.reflect_depth,
            ea_reflectances: self.ea_reflectances,
            ea_bounce_hits: self.ea_bounce_hits,
            lights,
            ..Default::default()
        }
    }

    /// The block as the kernel reads it (big-endian words at the record's offsets).
    pub fn to_be_bytes(&self) -> [u8; SHADING_BLOCK_BYTES] {
        let r = self.record();
        let mut out = [0u8; SHADING_BLOCK_BYTES];
        let mut put = |at: usize, word: u32| out[at..at + 4].copy_from_slice(&word.to_be_bytes());
        for (at, word) in [
            (SHB_EA_VERTICES, r.ea_vertices),
            (offset_of!(ShadingBlockRecord, ea_materials), r.ea_materials),
            (offset_of!(ShadingBlockRecord, ea_colour), r.ea_colour),
            (SHB_LIGHT_COUNT, r.light_count),
            (SHB_MODE, r.mode),
            (offset_of!(ShadingBlockRecord, shadow_early), r.shadow_early),
            (
                offset_of!(ShadingBlockRecord, vertex_cache_log2),
                r.vertex_cache_log2,
            ),
            (
                offset_of!(ShadingBlockRecord, material_cache_log2),
                r.material_cache_log2,
            ),
            (SHB_REFLECT, r.reflect_depth),
            (
                offset_of!(ShadingBlockRecord, ea_reflectances),
                r.ea_reflectances,
            ),
            (
                offset_of!(ShadingBlockRecord, ea_bounce_hits),
                r.ea_bounce_hits,
            ),
        ] {
            put(at, word);
        }
        for (i, light) in r.lights.iter().enumerate() {
            let at = SHB_LIGHTS + i * SHB_LIGHT_BYTES;
            for c in 0..4 {
                put(
                    at + offset_of!(LightRecord, position) + 4 * c,
                    light.position[c].to_bits(),
                );
                put(
                    at + offset_of!(LightRecord, colour) + 4 * c,
                    light.colour[c].to_bits(),
                );
            }
        }
        out
    }
}

/// Bytes of the packet-major 32-bit colour frame buffer for a `width x height` image.
pub fn colour_buffer_bytes(width: u32, height: u32) -> usize {
    frame_buffer_bytes(width, height) / (PACKET_BLOCK_BYTES / COLOUR_BLOCK_BYTES) as usize
}

/// Decodes the colour frame buffer into row-major 0xRRGGBBAA pixels.
pub fn decode_colour_buffer(fb: &[u8], width: u32, height: u32) -> Vec<u32> {
    let tiles_x = width.div_ceil(TILE_SIZE);
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x in 0..width {
            let (block, i) = pixel_location(x, y, tiles_x);
            let off = block / (PACKET_BLOCK_BYTES / COLOUR_BLOCK_BYTES) as usize + 4 * i;
            out.push(
                fb.get(off..off + 4)
                    .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
                    .unwrap_or(0),
            );
        }
    }
    out
}

/// Bytes of one SPU's statistics block.
pub const STATS_BYTES: usize = 128;

/// What the kernel counted, as it writes it: pairs of words at the start of quadwords.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KernelStats {
    pub packets: u64,
    /// BVH node visits: box tests of the packet against a node (the kernel tests both
    /// children of a node in one step, so two per step).
    pub traversal_steps: u64,
    /// Steps decided by the first active ray hitting the box.
    pub early_hits: u64,
    /// Steps decided by the packet frustum missing the box.
    pub early_exits: u64,
    /// Packet-triangle tests after frustum culling.
    pub triangle_tests: u64,
    pub triangles_culled: u64,
    pub bvh_cache_misses: u64,
    pub leaves: u64,
    pub triangle_lookups: u64,
    pub triangle_cache_misses: u64,
    /// BVH-cache lookups (one per traversal step of the pair kernel, which tests both
    /// children of a node in one step).
    pub bvh_lookups: u64,
}

/// One SPU's statistics block as the kernel writes it (`frame_done.s`): pairs of words
/// at the start of quadwords; its offsets are the `STAT_*` of `layout.inc`.
#[repr(C)]
pub struct StatsBlock {
    /// Packets, traversal steps.
    pub packets: Quad,
    /// The sums of the all-ones masks of first-ray misses and of early exits.
    pub m1sum: Quad,
    /// Triangle tests, triangles culled.
    pub tris: Quad,
    /// BVH cache misses, leaves.
    pub bmiss: Quad,
    /// Triangle cache lookups, misses.
    pub tlook: Quad,
    /// BVH cache lookups.
    pub blook: Quad,
    pub reserved: [Quad; 2],
}
const _: () = assert!(size_of::<StatsBlock>() == STATS_BYTES);

pub const STAT_PACKETS: usize = offset_of!(StatsBlock, packets);
pub const STAT_M1SUM: usize = offset_of!(StatsBlock, m1sum);
pub const STAT_TRIS: usize = offset_of!(StatsBlock, tris);
pub const STAT_BMISS: usize = offset_of!(StatsBlock, bmiss);
pub const STAT_TLOOK: usize = offset_of!(StatsBlock, tlook);
pub const STAT_BLOOK: usize = offset_of!(StatsBlock, blook);

impl KernelStats {
    /// Decodes one SPU's block (see the kernel's `frame_done`).
    pub fn from_be_bytes(block: &[u8]) -> Self {
        let word = |off: usize| {
            block
                .get(off..off + 4)
                .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
                .unwrap_or(0)
        };
        let steps = word(STAT_PACKETS + 4) as u64;
        // The kernel sums the all-ones masks of first-ray misses and early exits.
        let first_ray_misses = (word(STAT_M1SUM) as i32).unsigned_abs() as u64;
        KernelStats {
            packets: word(STAT_PACKETS) as u64,
            traversal_steps: steps,
            early_hits: steps.saturating_sub(first_ray_misses),
            early_exits: (word(STAT_M1SUM + 4) as i32).unsigned_abs() as u64,
            triangle_tests: word(STAT_TRIS) as u64,
            triangles_culled: word(STAT_TRIS + 4) as u64,
            bvh_cache_misses: word(STAT_BMISS) as u64,
            leaves: word(STAT_BMISS + 4) as u64,
            triangle_lookups: word(STAT_TLOOK) as u64,
            triangle_cache_misses: word(STAT_TLOOK + 4) as u64,
            bvh_lookups: word(STAT_BLOOK) as u64,
        }
    }

    pub fn merge(&mut self, other: &KernelStats) {
        self.packets += other.packets;
        self.traversal_steps += other.traversal_steps;
        self.early_hits += other.early_hits;
        self.early_exits += other.early_exits;
        self.triangle_tests += other.triangle_tests;
        self.triangles_culled += other.triangles_culled;
        self.bvh_cache_misses += other.bvh_cache_misses;
        self.leaves += other.leaves;
        self.triangle_lookups += other.triangle_lookups;
        self.triangle_cache_misses += other.triangle_cache_misses;
        self.bvh_lookups += other.bvh_lookups;
    }
}

/// The kernel ABI's constants by their assembler names: the parameter block, the shading
/// block, area and counters, the shadow area, the packet context and the statistics
/// block, each from its one definition above.
pub fn spu_constants() -> Vec<(&'static str, i64)> {
    let mut constants = vec![
        ("PARAM_EA_NODES", PARAM_EA_NODES as i64),
        ("PARAM_WIDTH", PARAM_WIDTH as i64),
        ("PARAM_ORIGIN", PARAM_ORIGIN as i64),
        ("PARAM_DIR00", PARAM_DIR00 as i64),
        ("PARAM_DU", PARAM_DU as i64),
        ("PARAM_DV", PARAM_DV as i64),
        ("PARAM_BVH_LOG2", PARAM_BVH_LOG2 as i64),
        ("PARAM_SHT", PARAM_SHT as i64),
        ("PARAM_SHADING_QUAD", PARAM_SHADING_QUAD as i64),
        ("PARAM_SHADING_ROT", PARAM_SHADING_ROT as i64),
        ("SHADING_BLOCK_BYTES", SHADING_BLOCK_BYTES as i64),
        ("SHB_EA_VERTICES", SHB_EA_VERTICES as i64),
        ("SHB_LIGHT_COUNT", SHB_LIGHT_COUNT as i64),
        ("SHB_MODE", SHB_MODE as i64),
        ("SHB_LIGHTS", SHB_LIGHTS as i64),
        ("SHB_LIGHT_BYTES", SHB_LIGHT_BYTES as i64),
        ("SHADE_SIMPLE", SHADE_SIMPLE as i64),
        ("SHADE_SHADOWS", SHADE_SHADOWS as i64),
        ("AMBIENT_BITS", crate::shading::AMBIENT.to_bits() as i64),
        (
            "SHADOW_LIMIT_BITS",
            (1.0 - crate::shading::SHADOW_EPSILON).to_bits() as i64,
        ),
        ("SHADOW_AREA", SHADOW_AREA as i64),
        (
            "SHADOW_CTX",
            (SHADOW_AREA + SHADOW_CONTEXT_OFFSET) as i64 + context::HEADER as i64,
        ),
        ("SHADOW_TAG", SHADOW_TAG as i64),
        ("CONTEXT_TAG0", CONTEXT_TAG0 as i64),
        ("STAGE_TRIANGLES", context::STAGE_TRIANGLES as i64),
        ("CTX_HEADER", context::HEADER as i64),
        ("CTX_CORNERS", context::CORNERS as i64),
        ("CTX_NEGTAB", context::NEGTAB as i64),
        ("CTX_RAY_DX", context::RAY_DX as i64),
        ("CTX_RAY_RX", context::RAY_RX as i64),
        ("CTX_RAY_T", context::RAY_T as i64),
        ("CTX_RAY_ID", context::RAY_ID as i64),
        ("CTX_RAY_ND", context::RAY_ND as i64),
        ("CTX_RAY_INVD", context::RAY_INVD as i64),
        ("CTX_STAGE_TAGS", context::STAGE_TAGS as i64),
        ("CTX_SAVE", context::SAVE as i64),
        ("CTX_RESUME", context::RESUME as i64),
        ("CTX_TILE64", context::TILE64 as i64),
        ("CTX_PACKET", context::PACKET as i64),
        ("CTX_NEXT", context::NEXT as i64),
        ("CTX_TAG", context::TAG as i64),
        ("CTX_STAGE_PAIR", context::STAGE_PAIR as i64),
        ("CTX_STAGE_TRIS", context::STAGE_TRIS as i64),
        ("CTX_STACK", context::STACK as i64),
        ("CTX_BYTES", context::BYTES as i64),
        ("STAT_PACKETS", STAT_PACKETS as i64),
        ("STAT_M1SUM", STAT_M1SUM as i64),
        ("STAT_TRIS", STAT_TRIS as i64),
        ("STAT_BMISS", STAT_BMISS as i64),
        ("STAT_TLOOK", STAT_TLOOK as i64),
        ("STAT_BLOOK", STAT_BLOOK as i64),
    ];
    let area = |name, offset: usize| (name, offset as i64);
    constants.extend([
        area("SH_FLAG", offset_of!(ShadingArea, flag)),
        area("SH_STATS", offset_of!(ShadingArea, stats)),
    ]);
    constants.extend(
        ShadeCounters::SPU_NAMES
            .iter()
            .map(|&(name, offset)| (name, offset as i64)),
    );
    constants.extend([
        area("SH_RUN", offset_of!(ShadingArea, run)),
        area("SH_RUN_OUT", offset_of!(ShadingArea, output)),
        area("SH_VMASK", offset_of!(ShadingArea, vertex_mask)),
        area("SH_BLOCK", offset_of!(ShadingArea, block)),
        area("SH_LIGHTS", offset_of!(ShadingArea, lights)),
        area("SH_LIGHT_BYTES", size_of::<[Quad; 6]>()),
        area("SH_SCRATCH", offset_of!(ShadingArea, scratch)),
        area("SH_DONE", offset_of!(ShadingArea, scratch.groups_done)),
        area("SH_SAVE", offset_of!(ShadingArea, scratch.save)),
        area("SH_SAME", offset_of!(ShadingArea, scratch.same)),
        area("SH_STAGE", offset_of!(ShadingArea, stage)),
        area("SH_NRM", offset_of!(ShadingArea, normals)),
        area("SH_NX", offset_of!(ShadingArea, nx)),
        area("SH_NY", offset_of!(ShadingArea, ny)),
        area("SH_NZ", offset_of!(ShadingArea, nz)),
        area("SH_PX", offset_of!(ShadingArea, px)),
        area("SH_PY", offset_of!(ShadingArea, py)),
        area("SH_PZ", offset_of!(ShadingArea, pz)),
        area("SH_MAT", offset_of!(ShadingArea, material)),
        area("SH_OUT", offset_of!(ShadingArea, out)),
        area("SH_VIS", offset_of!(ShadingArea, visibility)),
        area("SH_VTAGS", offset_of!(ShadingArea, vertex_tags)),
        area("SH_VDATA", offset_of!(ShadingArea, vertex_lines)),
        area("SH_MTAGS", offset_of!(ShadingArea, material_tags)),
        area("SH_MDATA", offset_of!(ShadingArea, material_lines)),
        area("SH_DCOUNT", offset_of!(ShadingArea, deferred_bytes)),
        area("SH_DEFER", offset_of!(ShadingArea, deferred)),
        area("SH_VSTAGE", offset_of!(ShadingArea, vertex_stage)),
        area("SH_IN_FLIGHT", SHADING_VERTICES_IN_FLIGHT),
        area("SH_AREA_BYTES", SHADING_AREA_BYTES),
        area("SV_RAYS", offset_of!(ShadowArea, rays)),
        area("SV_LIGHT", offset_of!(ShadowArea, light)),
        area("SV_HANDLERS", offset_of!(ShadowArea, handlers)),
        area("SV_REGS", offset_of!(ShadowArea, registers)),
        ("SHB_REFLECT", SHB_REFLECT as i64),
        ("REFLECT_AREA", REFLECT_AREA as i64),
        (
            "REFLECT_CTX",
            (REFLECT_AREA + offset_of!(ReflectArea, context)) as i64 + context::HEADER as i64,
        ),
        ("REFLECT_TAG", REFLECT_TAG as i64),
        (
            "REFLECT_OFFSET_BITS",
            crate::shading::REFLECT_OFFSET.to_bits() as i64,
        ),
        area("RF_FLAG", offset_of!(ReflectArea, flag)),
        area("RF_STATE", offset_of!(ReflectArea, state)),
        area("RF_TRACE", offset_of!(ReflectArea, trace)),
        area("RF_CASTS", offset_of!(ReflectArea, cast)),
        area("RF_HANDLERS", offset_of!(ReflectArea, handlers)),
        area("RF_REGS", offset_of!(ReflectArea, registers)),
        area("RF_BEFORE", offset_of!(ReflectArea, before)),
        area("RF_COUNTERS", offset_of!(ReflectArea, counters)),
        area("RF_COUNTER_BYTES", size_of::<ReflectCounters>()),
        area("RF_TABLE", offset_of!(ReflectArea, reflectances)),
        area("RF_WEIGHTS", offset_of!(ReflectArea, weights)),
        area("RF_COLOURS", offset_of!(ReflectArea, colours)),
        area("RF_OX", offset_of!(ReflectArea, ray_origin)),
        area("RF_DX", offset_of!(ReflectArea, ray_dir)),
        area("RF_CAST", offset_of!(ReflectArea, ray_cast)),
        area("RF_HIT_ID", offset_of!(ReflectArea, hit_id)),
        area("RF_HIT_T", offset_of!(ReflectArea, hit_t)),
        area("RF_RAYS", offset_of!(ReflectArea, rays)),
        area("RF_MATERIALS", REFLECT_MATERIALS),
    ]);
    constants
}

/// The `.set` lines of [`spu_constants`], for `layout.inc`.
pub fn spu_include() -> String {
    let mut out = String::from("# kernel ABI: generated by spu_loader::kernel_abi\n");
    for (name, value) in spu_constants() {
        out.push_str(&format!("        .set {name}, {value}\n"));
    }
    out
}

/// A stretch of the kernel's code the statistics report apart (CPI, stalls): from label
/// `from` up to label `to`, both in the kernel's symbols.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CodeSection {
    pub from: &'static str,
    pub to: &'static str,
}

/// The traversal steps (`modules/traverse.s` and its miss paths, up to the leaves).
pub const TRAVERSAL: CodeSection = CodeSection {
    from: "trav",
    to: "leaf",
};
/// The leaves' triangle tests (`modules/triangle.s` and its miss paths).
pub const INTERSECTION: CodeSection = CodeSection {
    from: "leaf",
    to: "packet_done",
};
/// The shading module (`modules/shade.s` and the files it composes), with `SHADE`.
pub const SHADING: CodeSection = CodeSection {
    from: "shade_packet",
    to: "shade_end",
};

/// One decoded pixel of the frame buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelResult {
    pub triangle: u32,
    pub t: f32,
    /// 0xRRGGBBAA: the eye-light grey; 0 in a shaded frame (its colours are in the colour
    /// buffer, `FrameRun::colour_buffer`).
    pub rgba: u32,
}

/// Bytes of the packet-major frame buffer for a `width x height` image.
pub fn frame_buffer_bytes(width: u32, height: u32) -> usize {
    let tiles = (width.div_ceil(TILE_SIZE) * height.div_ceil(TILE_SIZE)) as usize;
    tiles * PACKETS_PER_TILE as usize * PACKET_BLOCK_BYTES as usize
}

/// Where pixel `(x, y)` lives in the packet-major frame buffer: the block and the index.
pub fn pixel_location(x: u32, y: u32, tiles_x: u32) -> (usize, usize) {
    let tile = (y / TILE_SIZE) * tiles_x + x / TILE_SIZE;
    let packet =
        ((y % TILE_SIZE) / PACKET_SIZE) * (TILE_SIZE / PACKET_SIZE) + (x % TILE_SIZE) / PACKET_SIZE;
    let index = (y % PACKET_SIZE) * PACKET_SIZE + x % PACKET_SIZE;
    let block = (tile * PACKETS_PER_TILE + packet) as usize * PACKET_BLOCK_BYTES as usize;
    (block, index as usize)
}

/// Decodes the frame buffer into row-major pixels.
pub fn decode_frame_buffer(fb: &[u8], width: u32, height: u32) -> Vec<PixelResult> {
    decode_pixels(fb, width, height, |words| PixelResult {
        triangle: words.word(0),
        t: f32::from_bits(words.word(256)),
        rgba: words.word(512),
    })
}

/// The colours alone of [`decode_frame_buffer`] (`rgba`, row by row): what the image needs
/// when nothing else of the pixels is looked at, a third of the memory.
pub fn decode_frame_buffer_colours(fb: &[u8], width: u32, height: u32) -> Vec<u32> {
    decode_pixels(fb, width, height, |words| words.word(512))
}

/// One pixel's words in a frame buffer (0 where the buffer is short).
struct PixelWords<'a> {
    fb: &'a [u8],
    /// The pixel's block plus 4 times its index in the packet.
    at: usize,
}

impl PixelWords<'_> {
    /// The pixel's word in the array at `array` of its packet block (0 triangle, 256
    /// distance, 512 colour).
    #[inline(always)]
    fn word(&self, array: usize) -> u32 {
        let off = self.at + array;
        self.fb
            .get(off..off + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(0)
    }
}

/// Each pixel of a frame buffer, row by row, made by `pixel` from the pixel's words. A
/// packet's row of [`PACKET_SIZE`] pixels is one run of words in each array, so its place
/// is worked out once per run rather than once per pixel.
fn decode_pixels<T>(
    fb: &[u8],
    width: u32,
    height: u32,
    pixel: impl Fn(&PixelWords) -> T,
) -> Vec<T> {
    let tiles_x = width.div_ceil(TILE_SIZE);
    let mut out = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for x0 in (0..width).step_by(PACKET_SIZE as usize) {
            let (block, i) = pixel_location(x0, y, tiles_x);
            let run = PACKET_SIZE.min(width - x0) as usize;
            for j in 0..run {
                out.push(pixel(&PixelWords {
                    fb,
                    at: block + 4 * (i + j),
                }));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The colours alone are the full decoding's, pixel by pixel (a frame of two tiles
    /// across and one down, every word distinct, and a buffer one block short).
    #[test]
    fn colours_alone_decode_as_the_full_pixels() {
        let (width, height) = (2 * TILE_SIZE, TILE_SIZE);
        let words = (width * height) as usize * PACKET_BLOCK_BYTES as usize / 64 / 4;
        let fb: Vec<u8> = (0..words as u32)
            .flat_map(|w| (w * 7 + 1).to_be_bytes())
            .collect();
        for fb in [&fb[..], &fb[..fb.len() - PACKET_BLOCK_BYTES as usize]] {
            let full = decode_frame_buffer(fb, width, height);
            let colours = decode_frame_buffer_colours(fb, width, height);
            assert_eq!(colours, full.iter().map(|p| p.rgba).collect::<Vec<_>>());
            assert!(colours.iter().filter(|&&c| c != 0).count() > colours.len() / 2);
        }
    }

    #[test]
    fn param_block_bytes() {
        let mut p = ParamBlock {
            ea_nodes: 0x1000,
            width: 1024,
            ..Default::default()
        };
        p.origin = [1.0, 2.0, 3.0, 0.0];
        let b = p.to_be_bytes();
        assert_eq!(&b[0..4], &[0, 0, 0x10, 0]);
        assert_eq!(&b[PARAM_WIDTH..PARAM_WIDTH + 4], &1024u32.to_be_bytes());
        assert_eq!(
            &b[PARAM_ORIGIN + 4..PARAM_ORIGIN + 8],
            &2.0f32.to_be_bytes()
        );
        assert_eq!(PARAM_BVH_LOG2, 96);
        assert_eq!(PARAM_SHT, 112);
        let p = ParamBlock {
            sht_contexts: 4,
            cache_assoc: 4,
            ..Default::default()
        };
        let b = p.to_be_bytes();
        assert_eq!(&b[112..120], &[0, 0, 0, 4, 0, 0, 0, 4]);
    }

    #[test]
    fn context_layout_fits_the_kernel() {
        use context::*;
        for off in [
            CORNERS, NEGTAB, STAGE_TAGS, SAVE, RESUME, STAGE_PAIR, STAGE_TRIS, STACK,
        ] {
            assert_eq!(off % 16, 0, "{off}");
        }
        // the largest configuration leaves room for the code and its data
        assert!(carved_bytes(MAX_CACHE_LINES, MAX_CACHE_LINES, MAX_SHT_CONTEXTS) < 216 * 1024);
    }

    #[test]
    fn kernel_options_are_checked() {
        assert!(check_kernel_options(256, 256, 1, 1).is_ok());
        assert!(check_kernel_options(128, 1024, 4, 8).is_ok());
        for (b, t, a, s) in [
            (100, 256, 1, 1),
            (2048, 256, 1, 1),
            (256, 64, 1, 1),
            (256, 256, 3, 1),
            (256, 256, 1, 0),
            (256, 256, 1, 9),
        ] {
            assert!(check_kernel_options(b, t, a, s).is_err(), "{b} {t} {a} {s}");
        }
    }

    /// The read-back takes each packet's row of pixels as one run; each pixel's words are
    /// the ones its own [`pixel_location`] gives, at sizes cut mid-packet and mid-tile.
    #[test]
    fn decoded_pixels_are_read_where_each_pixel_lives() {
        for (width, height) in [(70, 13), (64, 64), (3, 9), (129, 1)] {
            let fb: Vec<u8> = (0..frame_buffer_bytes(width, height))
                .map(|k| (k * 7 + k / 251) as u8)
                .collect();
            let word = |off: usize| u32::from_be_bytes(fb[off..off + 4].try_into().unwrap());
            let tiles_x = width.div_ceil(TILE_SIZE);
            let mut expected = Vec::new();
            for y in 0..height {
                for x in 0..width {
                    let (block, i) = pixel_location(x, y, tiles_x);
                    expected.push(PixelResult {
                        triangle: word(block + 4 * i),
                        t: f32::from_bits(word(block + 256 + 4 * i)),
                        rgba: word(block + 512 + 4 * i),
                    });
                }
            }
            let pixels = decode_frame_buffer(&fb, width, height);
            let bits = |p: &[PixelResult]| -> Vec<(u32, u32, u32)> {
                p.iter()
                    .map(|p| (p.triangle, p.t.to_bits(), p.rgba))
                    .collect()
            };
            assert_eq!(bits(&pixels), bits(&expected), "{width}x{height}");
            let colours: Vec<u32> = expected.iter().map(|p| p.rgba).collect();
            assert_eq!(decode_frame_buffer_colours(&fb, width, height), colours);
        }
    }

    #[test]
    fn pixel_locations_are_packet_major() {
        // Pixel (9, 0): tile 0, packet 1 (second packet of the first row), index 1.
        assert_eq!(pixel_location(9, 0, 16), (1024, 1));
        // Pixel (0, 8): packet 8 (first of the second packet row).
        assert_eq!(pixel_location(0, 8, 16), (8 * 1024, 0));
        // Pixel (64, 0): tile 1.
        assert_eq!(pixel_location(64, 0, 16), (64 * 1024, 0));
        // Pixel (3, 65) with 2 tiles per row: tile 2, packet 0, index 8 + 3.
        assert_eq!(pixel_location(3, 65, 2), (2 * 64 * 1024, 11));
    }

    /// The shading area, shading block, counters and shadow area keep the offsets the
    /// kernel's code was laid out with (a field moved moves the kernel's data), and every
    /// offset reaches `layout.inc` once.
    #[test]
    fn shading_abi_offsets_are_the_documented_ones() {
        assert_eq!((SHADING_AREA_BYTES, SHADE_STATS_OFFSET), (40576, 16));
        assert_eq!(
            (SHADING_BLOCK_BYTES, SHB_LIGHT_COUNT, SHB_MODE, SHB_LIGHTS),
            (384, 12, 16, 64)
        );
        assert_eq!(
            (SHADOW_CONTEXT_OFFSET, SHADOW_AREA_BYTES),
            (2176, 2176 + 6016)
        );
        let constants = spu_constants();
        let value = |name: &str| {
            let found: Vec<i64> = constants
                .iter()
                .filter(|(n, _)| *n == name)
                .map(|(_, v)| *v)
                .collect();
            assert_eq!(found.len(), 1, "{name}");
            found[0]
        };
        for (name, offset) in [
            ("SH_STATS", 16),
            ("SH_RUN", 176),
            ("SH_RUN_OUT", 224),
            ("SH_VMASK", 240),
            ("SH_BLOCK", 256),
            ("SH_LIGHTS", 640),
            ("SH_SCRATCH", 1408),
            ("SH_DONE", 1552),
            ("SH_SAVE", 1568),
            ("SH_SAME", 1648),
            ("SH_STAGE", 1664),
            ("SH_NRM", 1920),
            ("SH_NX", 2176),
            ("SH_MAT", 3712),
            ("SH_OUT", 3968),
            ("SH_VIS", 4480),
            ("SH_VTAGS", 6528),
            ("SH_VDATA", 10624),
            ("SH_MTAGS", 27008),
            ("SH_MDATA", 31104),
            ("SH_DCOUNT", 39296),
            ("SH_DEFER", 39312),
            ("SH_VSTAGE", 39808),
            ("SHS_GROUPS", 0),
            ("SHS_PACKETS", 48),
            ("SHS_TMISS", 144),
            ("SV_HANDLERS", 32),
            ("SV_REGS", 128),
            ("STAT_BLOOK", 80),
        ] {
            assert_eq!(value(name), offset, "{name}");
        }
        let mut names: Vec<&str> = constants.iter().map(|(n, _)| *n).collect();
        names.sort_unstable();
        let count = names.len();
        names.dedup();
        assert_eq!(names.len(), count, "a name generated twice");
    }

    /// No kernel source defines again a name `layout.inc` generates: the generated value
    /// is the only one.
    #[test]
    fn no_kernel_source_mirrors_a_generated_name() {
        let generated: Vec<String> = crate::kernels::layout_include()
            .lines()
            .filter_map(|l| l.trim().strip_prefix(".set "))
            .map(|l| l.split(',').next().unwrap().trim().to_string())
            .collect();
        assert!(generated.iter().any(|n| n == "SH_AREA_BYTES"));
        let sources = crate::kernels::MODULES
            .iter()
            .chain(crate::kernels::FRAME_SOURCES)
            .map(|(name, text)| (*name, *text));
        for (file, text) in sources {
            for line in text.lines() {
                let code = line.split('#').next().unwrap().trim();
                if let Some(rest) = code.strip_prefix(".set") {
                    let name = rest.split(',').next().unwrap().trim();
                    assert!(
                        !generated.iter().any(|g| g == name),
                        "{file} sets {name}, which layout.inc generates: `{line}`"
                    );
                }
            }
        }
    }

    /// The statistics' code sections are stretches of the kernels they measure: both
    /// labels are symbols of the (shaded) primary kernel, in order.
    #[test]
    fn code_sections_are_stretches_of_the_kernel() {
        let primary = crate::kernels::KernelVariant::Primary;
        let (source, name) = (primary.source(), primary.name());
        for (defines, sections) in [
            (&[][..], &[TRAVERSAL, INTERSECTION][..]),
            (&[("SHADE", 1)][..], &[TRAVERSAL, INTERSECTION, SHADING][..]),
        ] {
            let program = crate::runtime::assemble_kernel_with(source, name, defines)
                .unwrap_or_else(|e| panic!("{e}"));
            let at = |label: &str| {
                program
                    .symbols
                    .iter()
                    .find(|(n, _)| n == label)
                    .unwrap_or_else(|| panic!("no {label} in {name} {defines:?}"))
                    .1
            };
            for s in sections {
                assert!(at(s.from) < at(s.to), "{s:?}");
            }
        }
    }

    /// The counters decode by name from local store: word 0 of each quadword, in the
    /// kernel's order; sums add field by field.
    #[test]
    fn shade_counters_decode_by_name() {
        let mut ls = vec![0u8; 160];
        for i in 0..10u32 {
            ls[16 * i as usize..16 * i as usize + 4].copy_from_slice(&(100 + i).to_be_bytes());
            ls[16 * i as usize + 4..16 * i as usize + 8].copy_from_slice(&7u32.to_be_bytes());
        }
        let c = ShadeCounters::from_be_bytes(&ls);
        assert_eq!(
            (c.groups, c.packets, c.vertex_misses, c.triangle_misses),
            (Counter(100), Counter(103), Counter(105), Counter(109))
        );
        let sum = ShadeCounters::sum(&[c, c]);
        assert_eq!(
            (sum.same, sum.material_lookups),
            (Counter(202), Counter(212))
        );
        assert_eq!(ShadeCounters::from_be_bytes(&ls[..18]).same, Counter(0));
    }

    #[test]
    fn stats_decode_the_mask_sums() {
        let mut b = vec![0u8; 128];
        b[0..4].copy_from_slice(&3u32.to_be_bytes());
        b[4..8].copy_from_slice(&100u32.to_be_bytes());
        b[16..20].copy_from_slice(&(-40i32).to_be_bytes());
        b[20..24].copy_from_slice(&(-25i32).to_be_bytes());
        let s = KernelStats::from_be_bytes(&b);
        assert_eq!(
            (s.packets, s.traversal_steps, s.early_hits, s.early_exits),
            (3, 100, 60, 25)
        );
    }
}
