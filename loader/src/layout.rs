//! The big-endian records the SPU kernels DMA from main memory (paper section 5.1), and the
//! staged main-memory image holding them. This module is the single source of truth for their
//! byte offsets: the Rust `pub const`s below are `offset_of!` the `#[repr(C)]` structs, and
//! [`spu_layout_include`] emits the same numbers as a GNU-as include for the SPU assembly.
//!
//! # BVH node, 32 bytes ([`NodeRecord`])
//!
//! | bytes | field |
//! |---|---|
//! | 0..12  | `min.x, min.y, min.z` (f32) |
//! | 12..16 | `link` (u32): inner node: index of the first child `c` (even; children at `c`, `c+1`); leaf: index of its first triangle record |
//! | 16..28 | `max.x, max.y, max.z` (f32) |
//! | 28..32 | `count_axis` (u32) = `(triangle_count << 2) \| split_axis`; `triangle_count == 0` marks an inner node, whose child `c` is the one with the lower centroids along `split_axis`; leaves have axis 0 |
//!
//! The node array has the root at index 0 and an all-zero padding node at 1, so every sibling
//! pair `(2k, 2k+1)` is one 64-byte line. An empty scene's root has an inverted box
//! (`min = f32::MAX`, `max = -f32::MAX`) that every ray misses.
//!
//! # Triangle record, 64 bytes ([`TriangleRecord`])
//!
//! Wald's projection test ("TriAccel", Wald's PhD thesis 2004; used by the
//! paper, section 4.2): 48 bytes that suffice for the hit test, plus 16 bytes for shading.
//! For the triangle `A = v0, B = v1, C = v2` with `N = (B - A) x (C - A)`, let `k` be the axis
//! of the largest `|N_k|` (lowest axis on ties), `u = (k + 1) % 3`, `v = (k + 2) % 3`, and in
//! the `(u, v)` projection `b = C - A`, `c = B - A`, `det = c_u b_v - c_v b_u` (= `N_k`):
//!
//! ```text
//! n_u = N_u / N_k      n_v = N_v / N_k      n_d = dot(N, A) / N_k
//! b_nu =  b_v / det    b_nv = -b_u / det    b_d = (b_u A_v - b_v A_u) / det
//! c_nu = -c_v / det    c_nv =  c_u / det    c_d = (c_v A_u - c_u A_v) / det
//! ```
//!
//! (computed in f64, stored rounded to f32). The hit test for a ray `o + t d` is then
//!
//! ```text
//! t     = ((n_d - o_k) - n_u o_u - n_v o_v) / ((d_k + n_u d_u) + n_v d_v)
//! H_u   = o_u + t d_u,   H_v = o_v + t d_v
//! beta  = (b_nu H_u + b_nv H_v) + b_d        -- barycentric weight of v1 (B)
//! gamma = (c_nu H_u + c_nv H_v) + c_d        -- barycentric weight of v2 (C)
//! hit  <=>  t_min < t < t_max  and  beta >= 0  and  gamma >= 0  and  beta + gamma <= 1
//! ```
//!
//! [`TriangleRecord::intersect`] evaluates exactly this in f32. The record also yields the
//! geometric normal for free: `N / N_k` has components `1` on `k`, `n_u` on `u`, `n_v` on `v`.
//! A degenerate (zero-area) triangle gets `n_* = 0`, `k = 0`, all `c_* = 0` and
//! `b_nu = b_nv = 0, b_d = -1`, so `beta = -1` and it never hits, without any NaN or infinity
//! (the SPU's single-precision unit has neither).
//!
//! | bytes | field |
//! |---|---|
//! | 0..16  | `n_u, n_v, n_d` (f32), `k` (u32) |
//! | 16..32 | `b_nu, b_nv, b_d` (f32), `original_index` (u32: the triangle's index in the scene, which is what kernels report as the hit) |
//! | 32..48 | `c_nu, c_nv, c_d` (f32), `reserved` (u32, 0) |
//! | 48..64 | `v0, v1, v2` (u32 vertex record indices), `material` (u32 material record index) |
//!
//! Records are stored in BVH leaf order (`Bvh::triangle_order`), so each leaf's triangles
//! are the contiguous records `link .. link + count`.
//!
//! # Vertex record, 64 bytes ([`VertexRecord`])
//!
//! `position` xyz f32 + pad (0..16), unit `normal` xyz f32 + pad (16..32), `texcoord` uv f32
//! + 2 pad words (32..48), 16 reserved bytes (48..64). Pads are 0.
//!
//! # Material record, 32 bytes ([`MaterialRecord`])
//!
//! `diffuse` rgb f32 + `reflectance` f32 (0..16), `specular` rgb f32 + `shininess` f32
//! (16..32). The shading kernels read the first quadword's three colour words only, so the
//! reflectance (which only the reflection kernel reads) costs the other programs nothing.
//!
//! # Scene header, 64 bytes ([`SceneHeader`]) and the staged image ([`StagedScene`])
//!
//! The image starts with the header (magic `"SCN1"`, version, then main-memory address and
//! element count of the node, triangle, vertex and material arrays), followed by those four
//! arrays in that order, each starting on a 128-byte boundary. All addresses are absolute
//! (image base + offset), 32-bit.

use std::mem::{offset_of, size_of};

use crate::bvh::Bvh;
use crate::scene::Scene;

/// Alignment of every array in the staged image (one DMA-friendly cache line).
pub const STAGE_ALIGN: usize = 128;

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct NodeRecord {
    pub min: [f32; 3],
    pub link: u32,
    pub max: [f32; 3],
    pub count_axis: u32,
}
const _: () = assert!(size_of::<NodeRecord>() == 32);

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TriangleRecord {
    pub n_u: f32,
    pub n_v: f32,
    pub n_d: f32,
    pub k: u32,
    pub b_nu: f32,
    pub b_nv: f32,
    pub b_d: f32,
    pub original_index: u32,
    pub c_nu: f32,
    pub c_nv: f32,
    pub c_d: f32,
    pub reserved: u32,
    pub vertices: [u32; 3],
    pub material: u32,
}
const _: () = assert!(size_of::<TriangleRecord>() == 64);

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct VertexRecord {
    pub position: [f32; 3],
    pub pad0: u32,
    pub normal: [f32; 3],
    pub pad1: u32,
    pub texcoord: [f32; 2],
    pub pad2: [u32; 2],
    pub reserved: [u32; 4],
}
const _: () = assert!(size_of::<VertexRecord>() == 64);

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MaterialRecord {
    pub diffuse: [f32; 3],
    pub reflectance: f32,
    pub specular: [f32; 3],
    pub shininess: f32,
}
const _: () = assert!(size_of::<MaterialRecord>() == 32);

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SceneHeader {
    pub magic: u32,
    pub version: u32,
    pub node_addr: u32,
    pub node_count: u32,
    pub triangle_addr: u32,
    pub triangle_count: u32,
    pub vertex_addr: u32,
    pub vertex_count: u32,
    pub material_addr: u32,
    pub material_count: u32,
    pub reserved: [u32; 6],
}
const _: () = assert!(size_of::<SceneHeader>() == 64);

/// `"SCN1"` as a big-endian word.
pub const SCENE_MAGIC: u32 = u32::from_be_bytes(*b"SCN1");
pub const SCENE_VERSION: u32 = 1;

pub const NODE_SIZE: usize = size_of::<NodeRecord>();
pub const NODE_MIN: usize = offset_of!(NodeRecord, min);
pub const NODE_LINK: usize = offset_of!(NodeRecord, link);
pub const NODE_MAX: usize = offset_of!(NodeRecord, max);
pub const NODE_COUNT_AXIS: usize = offset_of!(NodeRecord, count_axis);
/// `count_axis >> NODE_COUNT_SHIFT` is the triangle count.
pub const NODE_COUNT_SHIFT: usize = 2;
/// `count_axis & NODE_AXIS_MASK` is the split axis.
pub const NODE_AXIS_MASK: usize = 3;

pub const TRI_SIZE: usize = size_of::<TriangleRecord>();
pub const TRI_N_U: usize = offset_of!(TriangleRecord, n_u);
pub const TRI_N_V: usize = offset_of!(TriangleRecord, n_v);
pub const TRI_N_D: usize = offset_of!(TriangleRecord, n_d);
pub const TRI_K: usize = offset_of!(TriangleRecord, k);
pub const TRI_B_NU: usize = offset_of!(TriangleRecord, b_nu);
pub const TRI_B_NV: usize = offset_of!(TriangleRecord, b_nv);
pub const TRI_B_D: usize = offset_of!(TriangleRecord, b_d);
pub const TRI_ORIGINAL_INDEX: usize = offset_of!(TriangleRecord, original_index);
pub const TRI_C_NU: usize = offset_of!(TriangleRecord, c_nu);
pub const TRI_C_NV: usize = offset_of!(TriangleRecord, c_nv);
pub const TRI_C_D: usize = offset_of!(TriangleRecord, c_d);
pub const TRI_VERTICES: usize = offset_of!(TriangleRecord, vertices);
pub const TRI_MATERIAL: usize = offset_of!(TriangleRecord, material);

pub const VERTEX_SIZE: usize = size_of::<VertexRecord>();
pub const VERTEX_POSITION: usize = offset_of!(VertexRecord, position);
pub const VERTEX_NORMAL: usize = offset_of!(VertexRecord, normal);
pub const VERTEX_TEXCOORD: usize = offset_of!(VertexRecord, texcoord);

pub const MATERIAL_SIZE: usize = size_of::<MaterialRecord>();
pub const MATERIAL_DIFFUSE: usize = offset_of!(MaterialRecord, diffuse);
pub const MATERIAL_REFLECTANCE: usize = offset_of!(MaterialRecord, reflectance);
pub const MATERIAL_SPECULAR: usize = offset_of!(MaterialRecord, specular);
pub const MATERIAL_SHININESS: usize = offset_of!(MaterialRecord, shininess);

pub const HEADER_SIZE: usize = size_of::<SceneHeader>();
pub const HEADER_MAGIC: usize = offset_of!(SceneHeader, magic);
pub const HEADER_VERSION: usize = offset_of!(SceneHeader, version);
pub const HEADER_NODE_ADDR: usize = offset_of!(SceneHeader, node_addr);
pub const HEADER_NODE_COUNT: usize = offset_of!(SceneHeader, node_count);
pub const HEADER_TRIANGLE_ADDR: usize = offset_of!(SceneHeader, triangle_addr);
pub const HEADER_TRIANGLE_COUNT: usize = offset_of!(SceneHeader, triangle_count);
pub const HEADER_VERTEX_ADDR: usize = offset_of!(SceneHeader, vertex_addr);
pub const HEADER_VERTEX_COUNT: usize = offset_of!(SceneHeader, vertex_count);
pub const HEADER_MATERIAL_ADDR: usize = offset_of!(SceneHeader, material_addr);
pub const HEADER_MATERIAL_COUNT: usize = offset_of!(SceneHeader, material_count);

/// Every constant exported to SPU assembly, by its assembler name.
pub const SPU_LAYOUT_CONSTANTS: &[(&str, usize)] = &[
    ("STAGE_ALIGN", STAGE_ALIGN),
    ("NODE_SIZE", NODE_SIZE),
    ("NODE_SHIFT", NODE_SIZE.trailing_zeros() as usize),
    ("NODE_MIN", NODE_MIN),
    ("NODE_LINK", NODE_LINK),
    ("NODE_MAX", NODE_MAX),
    ("NODE_COUNT_AXIS", NODE_COUNT_AXIS),
    ("NODE_COUNT_SHIFT", NODE_COUNT_SHIFT),
    ("NODE_AXIS_MASK", NODE_AXIS_MASK),
    ("TRI_SIZE", TRI_SIZE),
    ("TRI_SHIFT", TRI_SIZE.trailing_zeros() as usize),
    ("TRI_N_U", TRI_N_U),
    ("TRI_N_V", TRI_N_V),
    ("TRI_N_D", TRI_N_D),
    ("TRI_K", TRI_K),
    ("TRI_B_NU", TRI_B_NU),
    ("TRI_B_NV", TRI_B_NV),
    ("TRI_B_D", TRI_B_D),
    ("TRI_ORIGINAL_INDEX", TRI_ORIGINAL_INDEX),
    ("TRI_C_NU", TRI_C_NU),
    ("TRI_C_NV", TRI_C_NV),
    ("TRI_C_D", TRI_C_D),
    ("TRI_VERTICES", TRI_VERTICES),
    ("TRI_MATERIAL", TRI_MATERIAL),
    ("VERTEX_SIZE", VERTEX_SIZE),
    ("VERTEX_SHIFT", VERTEX_SIZE.trailing_zeros() as usize),
    ("VERTEX_POSITION", VERTEX_POSITION),
    ("VERTEX_NORMAL", VERTEX_NORMAL),
    ("VERTEX_TEXCOORD", VERTEX_TEXCOORD),
    ("MATERIAL_SIZE", MATERIAL_SIZE),
    ("MATERIAL_SHIFT", MATERIAL_SIZE.trailing_zeros() as usize),
    ("MATERIAL_DIFFUSE", MATERIAL_DIFFUSE),
    ("MATERIAL_REFLECTANCE", MATERIAL_REFLECTANCE),
    ("MATERIAL_SPECULAR", MATERIAL_SPECULAR),
    ("MATERIAL_SHININESS", MATERIAL_SHININESS),
    ("HEADER_SIZE", HEADER_SIZE),
    ("HEADER_MAGIC", HEADER_MAGIC),
    ("HEADER_VERSION", HEADER_VERSION),
    ("HEADER_NODE_ADDR", HEADER_NODE_ADDR),
    ("HEADER_NODE_COUNT", HEADER_NODE_COUNT),
    ("HEADER_TRIANGLE_ADDR", HEADER_TRIANGLE_ADDR),
    ("HEADER_TRIANGLE_COUNT", HEADER_TRIANGLE_COUNT),
    ("HEADER_VERTEX_ADDR", HEADER_VERTEX_ADDR),
    ("HEADER_VERTEX_COUNT", HEADER_VERTEX_COUNT),
    ("HEADER_MATERIAL_ADDR", HEADER_MATERIAL_ADDR),
    ("HEADER_MATERIAL_COUNT", HEADER_MATERIAL_COUNT),
    ("SCENE_MAGIC", SCENE_MAGIC as usize),
];

/// The GNU-as include (`.set NAME, value` lines) giving SPU assembly the record layouts.
pub fn spu_layout_include() -> String {
    let mut text = String::from(
        "# Generated by spu_loader::layout::spu_layout_include(); do not edit.\n\
         # Record layouts of the staged scene image (big-endian), see loader/src/layout.rs.\n",
    );
    for (name, value) in SPU_LAYOUT_CONSTANTS {
        text.push_str(&format!(".set {name}, {value}\n"));
    }
    text
}

/// Writes 32-bit words big-endian into `out` (which must hold `4 * words.len()` bytes).
fn put_words(out: &mut [u8], words: &[u32]) {
    for (chunk, word) in out.chunks_exact_mut(4).zip(words) {
        chunk.copy_from_slice(&word.to_be_bytes());
    }
}

fn bits(values: [f32; 3]) -> [u32; 3] {
    values.map(f32::to_bits)
}

impl NodeRecord {
    /// Writes the 32-byte big-endian record into `out[..32]`.
    pub fn write_be(&self, out: &mut [u8]) {
        let [a, b, c] = bits(self.min);
        let [d, e, f] = bits(self.max);
        put_words(
            &mut out[..NODE_SIZE],
            &[a, b, c, self.link, d, e, f, self.count_axis],
        );
    }

    pub fn from_node(node: &crate::bvh::BvhNode) -> Self {
        NodeRecord {
            min: node.min.to_array(),
            link: node.link,
            max: node.max.to_array(),
            count_axis: (node.count << NODE_COUNT_SHIFT) | node.axis,
        }
    }

    pub fn triangle_count(&self) -> u32 {
        self.count_axis >> NODE_COUNT_SHIFT
    }

    pub fn axis(&self) -> u32 {
        self.count_axis & NODE_AXIS_MASK as u32
    }
}

impl TriangleRecord {
    /// Precomputes the projection record of triangle `(a, b, c)` (see the module docs).
    pub fn new(
        positions: [glam::Vec3; 3],
        vertices: [u32; 3],
        material: u32,
        original_index: u32,
    ) -> Self {
        let [a, b, c] = positions.map(|p| glam::DVec3::new(p.x as f64, p.y as f64, p.z as f64));
        let edge_c = b - a; // B - A
        let edge_b = c - a; // C - A
        let normal = edge_c.cross(edge_b);
        let abs = normal.abs();
        let k = if abs.x >= abs.y && abs.x >= abs.z {
            0
        } else if abs.y >= abs.z {
            1
        } else {
            2
        };
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let mut record = TriangleRecord {
            original_index,
            vertices,
            material,
            ..Default::default()
        };
        let det = normal[k];
        let finite = |x: f64| x.is_finite() && x.abs() < f32::MAX as f64;
        let candidate = TriangleRecord {
            n_u: (normal[u] / det) as f32,
            n_v: (normal[v] / det) as f32,
            n_d: (normal.dot(a) / det) as f32,
            k: k as u32,
            b_nu: (edge_b[v] / det) as f32,
            b_nv: (-edge_b[u] / det) as f32,
            b_d: ((edge_b[u] * a[v] - edge_b[v] * a[u]) / det) as f32,
            c_nu: (-edge_c[v] / det) as f32,
            c_nv: (edge_c[u] / det) as f32,
            c_d: ((edge_c[v] * a[u] - edge_c[u] * a[v]) / det) as f32,
            ..record
        };
        let all_finite = [
            candidate.n_u,
            candidate.n_v,
            candidate.n_d,
            candidate.b_nu,
            candidate.b_nv,
            candidate.b_d,
        ]
        .iter()
        .chain([candidate.c_nu, candidate.c_nv, candidate.c_d].iter())
        .all(|&x| finite(x as f64));
        if det != 0.0 && all_finite {
            record = candidate;
        } else {
            record.b_d = -1.0;
        }
        record
    }

    /// The projection hit test in f32, in exactly the operation order of the module docs.
    /// Returns `(t, beta, gamma)` for a hit with `t_min < t < t_max`.
    #[inline]
    pub fn intersect(
        &self,
        o: [f32; 3],
        d: [f32; 3],
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        self.intersect_with_slack(o, d, t_min, t_max, 0.0)
    }

    /// [`TriangleRecord::intersect`] with the barycentric range widened (positive `slack`)
    /// or narrowed (negative) by `slack`: to tell whether a hit depends on an edge.
    #[inline]
    pub fn intersect_with_slack(
        &self,
        o: [f32; 3],
        d: [f32; 3],
        t_min: f32,
        t_max: f32,
        slack: f32,
    ) -> Option<(f32, f32, f32)> {
        let k = self.k as usize;
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let numerator = ((self.n_d - o[k]) - self.n_u * o[u]) - self.n_v * o[v];
        let denominator = (d[k] + self.n_u * d[u]) + self.n_v * d[v];
        let t = numerator / denominator;
        if !(t > t_min && t < t_max) {
            return None;
        }
        let hu = o[u] + t * d[u];
        let hv = o[v] + t * d[v];
        let beta = (self.b_nu * hu + self.b_nv * hv) + self.b_d;
        let gamma = (self.c_nu * hu + self.c_nv * hv) + self.c_d;
        (beta >= -slack && gamma >= -slack && beta + gamma <= 1.0 + slack)
            .then_some((t, beta, gamma))
    }

    /// The barycentric weights `(beta, gamma)` of `v1` and `v2` at the point `o + t d`, by
    /// the same projection and operation order as [`TriangleRecord::intersect`] (shading
    /// recomputes them from the hit distance alone).
    #[inline]
    pub fn barycentrics(&self, o: [f32; 3], d: [f32; 3], t: f32) -> (f32, f32) {
        let k = self.k as usize;
        let (u, v) = ((k + 1) % 3, (k + 2) % 3);
        let hu = o[u] + t * d[u];
        let hv = o[v] + t * d[v];
        let beta = (self.b_nu * hu + self.b_nv * hv) + self.b_d;
        let gamma = (self.c_nu * hu + self.c_nv * hv) + self.c_d;
        (beta, gamma)
    }

    /// The unnormalized geometric normal `N / N_k` encoded in the record.
    pub fn geometric_normal(&self) -> glam::Vec3 {
        let mut n = [0.0f32; 3];
        let k = self.k as usize;
        n[k] = 1.0;
        n[(k + 1) % 3] = self.n_u;
        n[(k + 2) % 3] = self.n_v;
        glam::Vec3::from_array(n)
    }

    /// Writes the 64-byte big-endian record into `out[..64]`.
    pub fn write_be(&self, out: &mut [u8]) {
        put_words(
            &mut out[..TRI_SIZE],
            &[
                self.n_u.to_bits(),
                self.n_v.to_bits(),
                self.n_d.to_bits(),
                self.k,
                self.b_nu.to_bits(),
                self.b_nv.to_bits(),
                self.b_d.to_bits(),
                self.original_index,
                self.c_nu.to_bits(),
                self.c_nv.to_bits(),
                self.c_d.to_bits(),
                self.reserved,
                self.vertices[0],
                self.vertices[1],
                self.vertices[2],
                self.material,
            ],
        );
    }
}

impl VertexRecord {
    /// Writes the 64-byte big-endian record into `out[..64]`.
    pub fn write_be(&self, out: &mut [u8]) {
        let [px, py, pz] = bits(self.position);
        let [nx, ny, nz] = bits(self.normal);
        let [r0, r1, r2, r3] = self.reserved;
        put_words(
            &mut out[..VERTEX_SIZE],
            &[
                px,
                py,
                pz,
                self.pad0,
                nx,
                ny,
                nz,
                self.pad1,
                self.texcoord[0].to_bits(),
                self.texcoord[1].to_bits(),
                self.pad2[0],
                self.pad2[1],
                r0,
                r1,
                r2,
                r3,
            ],
        );
    }
}

impl MaterialRecord {
    /// Writes the 32-byte big-endian record into `out[..32]`.
    pub fn write_be(&self, out: &mut [u8]) {
        let [d0, d1, d2] = bits(self.diffuse);
        let [s0, s1, s2] = bits(self.specular);
        put_words(
            &mut out[..MATERIAL_SIZE],
            &[
                d0,
                d1,
                d2,
                self.reflectance.to_bits(),
                s0,
                s1,
                s2,
                self.shininess.to_bits(),
            ],
        );
    }
}

impl SceneHeader {
    /// Writes the 64-byte big-endian record into `out[..64]`.
    pub fn write_be(&self, out: &mut [u8]) {
        let mut words = vec![
            self.magic,
            self.version,
            self.node_addr,
            self.node_count,
            self.triangle_addr,
            self.triangle_count,
            self.vertex_addr,
            self.vertex_count,
            self.material_addr,
            self.material_count,
        ];
        words.extend_from_slice(&self.reserved);
        put_words(&mut out[..HEADER_SIZE], &words);
    }
}

/// The node records of `bvh`, in node-array order.
pub fn node_records(bvh: &Bvh) -> Vec<NodeRecord> {
    bvh.nodes
        .iter()
        .enumerate()
        .map(|(index, node)| {
            if index == 1 {
                NodeRecord::default()
            } else {
                NodeRecord::from_node(node)
            }
        })
        .collect()
}

/// The vertex cache the host's choice of [`VertexOrder`] is made for: the kernel's default
/// (the paper's) direct-mapped vertex cache, record `r` on line `r % VERTEX_ORDER_LINES`.
pub const VERTEX_ORDER_LINES: usize = 64;

/// Where each scene vertex goes among the vertex records. The kernel's vertex cache is
/// direct mapped by record index, so a mesh numbered row by row with rows a multiple of the
/// line count long (the beetle: 576 vertices around) puts both rows of every quad on the
/// same lines and thrashes them. The host counts the misses of a [`VERTEX_ORDER_LINES`]-line
/// direct-mapped cache over the triangles' vertices in `bvh` leaf order (neighbouring
/// records are neighbouring triangles, as rays meet them) for the scene's own order and for
/// the order in which the leaves first use the vertices (unused ones after, in scene order),
/// and takes the leaf order only where it at least halves those misses: a scene whose own
/// order already suits the cache keeps it (for the room and the conference the two counts
/// are within 1% and 10%, and the leaf order costs frame cycles there: rays do not meet
/// triangles with the leaf order's weights).
#[derive(Debug, Clone, PartialEq)]
pub struct VertexOrder {
    /// `record_of[v]`: the vertex record of scene vertex `v`.
    pub record_of: Vec<u32>,
    /// `scene_of[r]`: the scene vertex stored as vertex record `r`.
    pub scene_of: Vec<u32>,
}

impl VertexOrder {
    pub fn new(scene: &Scene, bvh: &Bvh) -> VertexOrder {
        let leaf = VertexOrder::leaf_first_use(scene, bvh);
        let own_misses = VertexOrder::modelled_misses(scene, bvh, |v| v);
        let leaf_misses = VertexOrder::modelled_misses(scene, bvh, |v| leaf.record_of[v as usize]);
        if 2 * leaf_misses <= own_misses {
            leaf
        } else {
            VertexOrder::scene_order(scene)
        }
    }

    /// The scene's own order.
    pub fn scene_order(scene: &Scene) -> VertexOrder {
        let identity: Vec<u32> = (0..scene.positions.len() as u32).collect();
        VertexOrder {
            record_of: identity.clone(),
            scene_of: identity,
        }
    }

    /// The order in which the triangles in `bvh` leaf order first use the vertices, then the
    /// unused ones in scene order.
    pub fn leaf_first_use(scene: &Scene, bvh: &Bvh) -> VertexOrder {
        const UNSEEN: u32 = u32::MAX;
        let mut record_of = vec![UNSEEN; scene.positions.len()];
        let mut scene_of = Vec::with_capacity(scene.positions.len());
        let leaf_vertices = bvh
            .triangle_order
            .iter()
            .flat_map(|&t| scene.triangles[t as usize].v);
        for v in leaf_vertices.chain(0..scene.positions.len() as u32) {
            if record_of[v as usize] == UNSEEN {
                record_of[v as usize] = scene_of.len() as u32;
                scene_of.push(v);
            }
        }
        VertexOrder {
            record_of,
            scene_of,
        }
    }

    /// Misses of a [`VERTEX_ORDER_LINES`]-line direct-mapped cache looking up the vertices of
    /// the triangles in `bvh` leaf order, scene vertex `v` being record `record_of(v)`.
    pub fn modelled_misses(scene: &Scene, bvh: &Bvh, record_of: impl Fn(u32) -> u32) -> usize {
        let mut lines = [u32::MAX; VERTEX_ORDER_LINES];
        let mut misses = 0;
        for &t in &bvh.triangle_order {
            for v in scene.triangles[t as usize].v {
                let record = record_of(v);
                let line = &mut lines[record as usize % VERTEX_ORDER_LINES];
                if *line != record {
                    *line = record;
                    misses += 1;
                }
            }
        }
        misses
    }
}

/// The triangle records of `scene` in `bvh` leaf order, their vertex indices those of
/// `order`'s vertex records.
pub fn triangle_records(scene: &Scene, bvh: &Bvh, order: &VertexOrder) -> Vec<TriangleRecord> {
    bvh.triangle_order
        .iter()
        .map(|&original| {
            let triangle = &scene.triangles[original as usize];
            TriangleRecord::new(
                scene.triangle_positions(original as usize),
                triangle.v.map(|v| order.record_of[v as usize]),
                triangle.material,
                original,
            )
        })
        .collect()
}

/// The vertex records of `scene` in `order`.
pub fn vertex_records(scene: &Scene, order: &VertexOrder) -> Vec<VertexRecord> {
    order
        .scene_of
        .iter()
        .map(|&v| {
            let i = v as usize;
            VertexRecord {
                position: scene.positions[i].to_array(),
                normal: scene
                    .normals
                    .get(i)
                    .copied()
                    .unwrap_or(glam::Vec3::Z)
                    .to_array(),
                texcoord: scene
                    .texcoords
                    .get(i)
                    .copied()
                    .unwrap_or(glam::Vec2::ZERO)
                    .to_array(),
                ..Default::default()
            }
        })
        .collect()
}

pub fn material_records(scene: &Scene) -> Vec<MaterialRecord> {
    scene
        .materials
        .iter()
        .map(|m| MaterialRecord {
            diffuse: m.diffuse,
            reflectance: m.reflectance,
            specular: m.specular,
            shininess: m.shininess,
        })
        .collect()
}

/// A scene packed for simulated main memory: header, nodes, triangle records, vertices and
/// materials as one big-endian image, each part 128-byte aligned, to be placed at `base`.
#[derive(Debug, Clone, PartialEq)]
pub struct StagedScene {
    /// Main-memory address the image is meant to be placed at (a multiple of 128).
    pub base: u32,
    pub image: Vec<u8>,
    pub header: SceneHeader,
    /// Host copies of the records, for the reference caster and tests.
    pub nodes: Vec<NodeRecord>,
    pub triangles: Vec<TriangleRecord>,
    pub vertices: Vec<VertexRecord>,
    pub materials: Vec<MaterialRecord>,
}

fn align_up(value: usize, alignment: usize) -> usize {
    value.div_ceil(alignment) * alignment
}

impl StagedScene {
    /// Packs `scene` with its hierarchy `bvh` for placement at main-memory address `base`.
    pub fn new(scene: &Scene, bvh: &Bvh, base: u32) -> Result<StagedScene, String> {
        if !(base as usize).is_multiple_of(STAGE_ALIGN) {
            return Err(format!(
                "image base {base:#x} is not {STAGE_ALIGN}-byte aligned"
            ));
        }
        let nodes = node_records(bvh);
        let order = VertexOrder::new(scene, bvh);
        let triangles = triangle_records(scene, bvh, &order);
        let vertices = vertex_records(scene, &order);
        let materials = material_records(scene);

        let node_offset = align_up(HEADER_SIZE, STAGE_ALIGN);
        let triangle_offset = align_up(node_offset + nodes.len() * NODE_SIZE, STAGE_ALIGN);
        let vertex_offset = align_up(triangle_offset + triangles.len() * TRI_SIZE, STAGE_ALIGN);
        let material_offset = align_up(vertex_offset + vertices.len() * VERTEX_SIZE, STAGE_ALIGN);
        let end = align_up(
            material_offset + materials.len() * MATERIAL_SIZE,
            STAGE_ALIGN,
        );
        if base as u64 + end as u64 > u32::MAX as u64 + 1 {
            return Err(format!(
                "scene image of {end} bytes at {base:#x} exceeds the 32-bit address space"
            ));
        }
        let address = |offset: usize| base + offset as u32;
        let header = SceneHeader {
            magic: SCENE_MAGIC,
            version: SCENE_VERSION,
            node_addr: address(node_offset),
            node_count: nodes.len() as u32,
            triangle_addr: address(triangle_offset),
            triangle_count: triangles.len() as u32,
            vertex_addr: address(vertex_offset),
            vertex_count: vertices.len() as u32,
            material_addr: address(material_offset),
            material_count: materials.len() as u32,
            reserved: [0; 6],
        };
        let mut image = vec![0u8; end];
        header.write_be(&mut image[..HEADER_SIZE]);
        for (i, record) in nodes.iter().enumerate() {
            record.write_be(&mut image[node_offset + i * NODE_SIZE..]);
        }
        for (i, record) in triangles.iter().enumerate() {
            record.write_be(&mut image[triangle_offset + i * TRI_SIZE..]);
        }
        for (i, record) in vertices.iter().enumerate() {
            record.write_be(&mut image[vertex_offset + i * VERTEX_SIZE..]);
        }
        for (i, record) in materials.iter().enumerate() {
            record.write_be(&mut image[material_offset + i * MATERIAL_SIZE..]);
        }
        Ok(StagedScene {
            base,
            image,
            header,
            nodes,
            triangles,
            vertices,
            materials,
        })
    }

    /// Offset within [`StagedScene::image`] of main-memory address `address`.
    pub fn offset_of_address(&self, address: u32) -> usize {
        (address - self.base) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A `columns` x `rows` grid of quads in the z = 0 plane, its vertices numbered row by
    /// row (rows of `columns + 1`).
    fn grid(columns: u32, rows: u32) -> Scene {
        let mut positions = Vec::new();
        for y in 0..=rows {
            for x in 0..=columns {
                positions.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
        let at = |x: u32, y: u32| y * (columns + 1) + x;
        let mut triangles = Vec::new();
        for y in 0..rows {
            for x in 0..columns {
                let (a, b, c, d) = (at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1));
                triangles.push(crate::scene::Triangle {
                    v: [a, b, d],
                    material: 0,
                });
                triangles.push(crate::scene::Triangle {
                    v: [a, d, c],
                    material: 0,
                });
            }
        }
        Scene::from_parts(positions, None, Vec::new(), triangles, Vec::new())
    }

    #[test]
    fn vertex_order_leaves_a_cache_friendly_scene_and_reorders_a_thrashing_one() {
        use crate::bvh::BvhConfig;
        // Rows of 64 vertices: the two rows of every quad fall on the same lines of a
        // 64-line direct-mapped cache. Rows of 41 do not.
        for (columns, reordered) in [(63, true), (40, false)] {
            let scene = grid(columns, 40);
            let bvh = Bvh::build(&scene, &BvhConfig::default());
            let order = VertexOrder::new(&scene, &bvh);
            let own = VertexOrder::modelled_misses(&scene, &bvh, |v| v);
            let leaf = VertexOrder::leaf_first_use(&scene, &bvh);
            let leaf_misses =
                VertexOrder::modelled_misses(&scene, &bvh, |v| leaf.record_of[v as usize]);
            assert_eq!(
                order != VertexOrder::scene_order(&scene),
                reordered,
                "{columns}"
            );
            assert_eq!(2 * leaf_misses <= own, reordered, "{own} {leaf_misses}");
            // A permutation, and the staged records are the scene's, renumbered.
            let mut seen = order.scene_of.clone();
            seen.sort_unstable();
            assert!(seen.iter().copied().eq(0..scene.positions.len() as u32));
            let staged = StagedScene::new(&scene, &bvh, 0).unwrap();
            for (record, &original) in staged.triangles.iter().zip(&bvh.triangle_order) {
                let scene_vertices = scene.triangles[original as usize].v;
                for (r, v) in record.vertices.iter().zip(scene_vertices) {
                    assert_eq!(order.scene_of[*r as usize], v);
                    assert_eq!(
                        staged.vertices[*r as usize].position,
                        scene.positions[v as usize].to_array()
                    );
                }
            }
        }
    }

    #[test]
    fn include_matches_offset_of() {
        let text = spu_layout_include();
        let value_of = |name: &str| -> usize {
            let prefix = format!(".set {name}, ");
            let line = text
                .lines()
                .find(|l| l.starts_with(&prefix))
                .unwrap_or_else(|| panic!("{name} missing"));
            line[prefix.len()..].parse().unwrap()
        };
        assert_eq!(value_of("NODE_MIN"), offset_of!(NodeRecord, min));
        assert_eq!(value_of("NODE_LINK"), offset_of!(NodeRecord, link));
        assert_eq!(value_of("NODE_MAX"), offset_of!(NodeRecord, max));
        assert_eq!(
            value_of("NODE_COUNT_AXIS"),
            offset_of!(NodeRecord, count_axis)
        );
        assert_eq!(value_of("NODE_SIZE"), size_of::<NodeRecord>());
        assert_eq!(value_of("TRI_N_U"), offset_of!(TriangleRecord, n_u));
        assert_eq!(value_of("TRI_K"), offset_of!(TriangleRecord, k));
        assert_eq!(value_of("TRI_B_NU"), offset_of!(TriangleRecord, b_nu));
        assert_eq!(
            value_of("TRI_ORIGINAL_INDEX"),
            offset_of!(TriangleRecord, original_index)
        );
        assert_eq!(value_of("TRI_C_NU"), offset_of!(TriangleRecord, c_nu));
        assert_eq!(value_of("TRI_C_D"), offset_of!(TriangleRecord, c_d));
        assert_eq!(
            value_of("TRI_VERTICES"),
            offset_of!(TriangleRecord, vertices)
        );
        assert_eq!(
            value_of("TRI_MATERIAL"),
            offset_of!(TriangleRecord, material)
        );
        assert_eq!(value_of("VERTEX_NORMAL"), offset_of!(VertexRecord, normal));
        assert_eq!(
            value_of("VERTEX_TEXCOORD"),
            offset_of!(VertexRecord, texcoord)
        );
        assert_eq!(
            value_of("MATERIAL_SPECULAR"),
            offset_of!(MaterialRecord, specular)
        );
        assert_eq!(
            value_of("MATERIAL_SHININESS"),
            offset_of!(MaterialRecord, shininess)
        );
        assert_eq!(
            value_of("HEADER_MATERIAL_COUNT"),
            offset_of!(SceneHeader, material_count)
        );
        assert_eq!(value_of("NODE_SHIFT"), 5);
        assert_eq!(value_of("TRI_SHIFT"), 6);
        // The documented numbers, so a field reorder cannot silently move them.
        assert_eq!(
            (NODE_MIN, NODE_LINK, NODE_MAX, NODE_COUNT_AXIS),
            (0, 12, 16, 28)
        );
        assert_eq!(
            (
                TRI_N_U,
                TRI_K,
                TRI_B_NU,
                TRI_ORIGINAL_INDEX,
                TRI_C_NU,
                TRI_VERTICES,
                TRI_MATERIAL
            ),
            (0, 12, 16, 28, 32, 48, 60)
        );
        assert_eq!(
            (VERTEX_POSITION, VERTEX_NORMAL, VERTEX_TEXCOORD),
            (0, 16, 32)
        );
        assert_eq!(
            (MATERIAL_DIFFUSE, MATERIAL_SPECULAR, MATERIAL_SHININESS),
            (0, 16, 28)
        );
        for (name, _) in SPU_LAYOUT_CONSTANTS {
            assert!(name
                .chars()
                .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_'));
        }
    }

    #[test]
    fn node_bytes_are_big_endian() {
        let node = NodeRecord {
            min: [1.0, -2.0, 0.5],
            link: 0x0102_0304,
            max: [3.0, 4.0, 1.5],
            count_axis: (3 << 2) | 2,
        };
        let mut out = [0u8; 32];
        node.write_be(&mut out);
        #[rustfmt::skip]
        let expected: [u8; 32] = [
            0x3f, 0x80, 0x00, 0x00,  0xc0, 0x00, 0x00, 0x00,  0x3f, 0x00, 0x00, 0x00,  0x01, 0x02, 0x03, 0x04,
            0x40, 0x40, 0x00, 0x00,  0x40, 0x80, 0x00, 0x00,  0x3f, 0xc0, 0x00, 0x00,  0x00, 0x00, 0x00, 0x0e,
        ];
        assert_eq!(out, expected);
        assert_eq!(node.triangle_count(), 3);
        assert_eq!(node.axis(), 2);
    }

    #[test]
    fn triangle_record_bytes_and_hit_test() {
        let positions = [
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        ];
        let record = TriangleRecord::new(positions, [7, 8, 9], 5, 42);
        // N = (0, 0, 1): k = z, u = x, v = y; the plane z = 2.
        assert_eq!(
            (record.k, record.n_u, record.n_v, record.n_d),
            (2, 0.0, 0.0, 2.0)
        );
        assert_eq!((record.b_nu, record.b_nv, record.b_d), (1.0, 0.0, 0.0));
        assert_eq!((record.c_nu, record.c_nv, record.c_d), (0.0, 1.0, 0.0));
        let mut out = [0u8; 64];
        record.write_be(&mut out);
        assert_eq!(&out[8..16], &[0x40, 0, 0, 0, 0, 0, 0, 2]);
        assert_eq!(&out[28..32], &[0, 0, 0, 42]);
        assert_eq!(
            &out[48..64],
            &[0, 0, 0, 7, 0, 0, 0, 8, 0, 0, 0, 9, 0, 0, 0, 5]
        );

        let (t, beta, gamma) = record
            .intersect([0.25, 0.5, 0.0], [0.0, 0.0, 4.0], 0.0, f32::MAX)
            .unwrap();
        assert_eq!((t, beta, gamma), (0.5, 0.25, 0.5));
        assert!(record
            .intersect([0.75, 0.5, 0.0], [0.0, 0.0, 1.0], 0.0, f32::MAX)
            .is_none());
        assert!(record
            .intersect([0.25, 0.5, 0.0], [0.0, 0.0, 1.0], 0.0, 1.5)
            .is_none());
        assert!(record
            .intersect([0.25, 0.5, 0.0], [0.0, 0.0, -1.0], 0.0, f32::MAX)
            .is_none());
        assert_eq!(record.geometric_normal(), Vec3::Z);
    }

    #[test]
    fn barycentrics_match_the_vertices_for_a_tilted_triangle() {
        let [a, b, c] = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(4.0, -1.0, 2.5),
            Vec3::new(0.5, 0.0, -2.0),
        ];
        let record = TriangleRecord::new([a, b, c], [0, 1, 2], 0, 0);
        let target = a * 0.2 + b * 0.3 + c * 0.5;
        let origin = Vec3::new(10.0, 7.0, -3.0);
        let (t, beta, gamma) = record
            .intersect(
                origin.to_array(),
                (target - origin).to_array(),
                0.0,
                f32::MAX,
            )
            .unwrap();
        assert!((t - 1.0).abs() < 1e-5 && (beta - 0.3).abs() < 1e-5 && (gamma - 0.5).abs() < 1e-5);
        let n = (b - a).cross(c - a);
        assert!(record.geometric_normal().normalize().dot(n.normalize()) > 0.99999);
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let p = Vec3::new(1.0, 1.0, 1.0);
        for positions in [[p, p, p], [Vec3::ZERO, p, p * 2.0]] {
            let record = TriangleRecord::new(positions, [0, 1, 2], 0, 0);
            assert_eq!(record.b_d, -1.0);
            assert!(record
                .intersect([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0, f32::MAX)
                .is_none());
        }
    }

    #[test]
    fn staged_image_has_aligned_arrays_and_a_header() {
        let scene = crate::bvh::tests::soup(100);
        let bvh = Bvh::build(&scene, &Default::default());
        let staged = StagedScene::new(&scene, &bvh, 0x10_0000).unwrap();
        let h = staged.header;
        for addr in [h.node_addr, h.triangle_addr, h.vertex_addr, h.material_addr] {
            assert_eq!(addr as usize % STAGE_ALIGN, 0);
        }
        assert_eq!(&staged.image[0..4], b"SCN1");
        assert_eq!(h.triangle_count, 100);
        assert_eq!(h.node_count as usize, bvh.nodes.len());
        let word = |offset: usize| {
            u32::from_be_bytes(staged.image[offset..offset + 4].try_into().unwrap())
        };
        assert_eq!(word(HEADER_TRIANGLE_ADDR), h.triangle_addr);
        let root = staged.offset_of_address(h.node_addr);
        assert_eq!(word(root + NODE_LINK), staged.nodes[0].link);
        assert_eq!(
            &staged.image[root + NODE_SIZE..root + 2 * NODE_SIZE],
            &[0u8; 32]
        );
        let first_tri = staged.offset_of_address(h.triangle_addr);
        assert_eq!(word(first_tri + TRI_ORIGINAL_INDEX), bvh.triangle_order[0]);
        assert_eq!(staged.image.len() % STAGE_ALIGN, 0);
        assert!(StagedScene::new(&scene, &bvh, 0x10_0004).is_err());
    }

    /// The shading data is real: every triangle record's spare 16 bytes name its scene
    /// vertices and material, and the vertex and material records carry the scene's smooth
    /// normals and colours, big-endian in the image.
    #[test]
    fn shading_records_carry_the_scene_data() {
        let scene = crate::procedural::room();
        let bvh = Bvh::build(&scene, &Default::default());
        let staged = StagedScene::new(&scene, &bvh, 0x1_0000).unwrap();
        let word = |offset: usize| {
            u32::from_be_bytes(staged.image[offset..offset + 4].try_into().unwrap())
        };
        let h = staged.header;
        assert_eq!(h.vertex_count as usize, scene.positions.len());
        assert_eq!(h.material_count, 9);
        let mut materials_seen = std::collections::HashSet::new();
        for (i, record) in staged.triangles.iter().enumerate() {
            let triangle = scene.triangles[record.original_index as usize];
            let at = staged.offset_of_address(h.triangle_addr) + i * TRI_SIZE;
            assert_eq!(
                [0, 1, 2].map(|c| word(at + TRI_VERTICES + 4 * c)),
                triangle.v
            );
            assert_eq!(word(at + TRI_MATERIAL), triangle.material);
            materials_seen.insert(triangle.material);
        }
        assert_eq!(materials_seen.len(), 9);
        for (i, normal) in scene.normals.iter().enumerate() {
            let at = staged.offset_of_address(h.vertex_addr) + i * VERTEX_SIZE;
            let read = |o: usize| f32::from_bits(word(at + o));
            assert!((normal.length() - 1.0).abs() < 1e-5);
            assert_eq!(
                [
                    read(VERTEX_NORMAL),
                    read(VERTEX_NORMAL + 4),
                    read(VERTEX_NORMAL + 8)
                ],
                normal.to_array()
            );
            assert_eq!(read(VERTEX_POSITION + 4), scene.positions[i].y);
        }
        for (i, material) in scene.materials.iter().enumerate() {
            let at = staged.offset_of_address(h.material_addr) + i * MATERIAL_SIZE;
            assert_eq!(
                f32::from_bits(word(at + MATERIAL_DIFFUSE + 4)),
                material.diffuse[1]
            );
            assert_eq!(
                f32::from_bits(word(at + MATERIAL_REFLECTANCE)),
                material.reflectance
            );
        }
        assert_eq!(staged.vertices.len(), scene.positions.len());
        assert_eq!(staged.materials[4].diffuse, scene.materials[4].diffuse);
    }
}
