//! The host reference ray caster: what the SPU kernels must produce, computed with a plain
//! single-ray traversal over the very same node and triangle records (and the same f32
//! projection test, [`TriangleRecord::intersect`]), so kernel and reference can be compared
//! pixel by pixel. It is itself checked against an f64 brute-force Möller–Trumbore caster.
//!
//! Conventions shared with the kernels:
//! - rays come from [`CameraBasis::direction`](crate::CameraBasis::direction) (unnormalized; `t` is in units of that
//!   direction, see [`crate::camera`]);
//! - a hit needs `T_MIN < t < t_max`, where `t_max` starts at [`T_MAX`] (finite: the SPU has
//!   no infinity) and shrinks to the nearest hit so far; of two hits at exactly the same `t`
//!   the first one tested wins;
//! - a miss reports triangle [`MISS`] and `t = T_MAX`;
//! - the reported triangle is the record's `original_index` (the scene's triangle index);
//! - boxes are tested with slabs: per axis `t0 = (min - o) * inv`, `t1 = (max - o) * inv`
//!   with `inv = 1 / d` (a zero component uses `1e30`, there being no infinity on the SPU),
//!   `entry = max(T_MIN, min(t0, t1) over axes)`, `exit = min(t_max, max(t0, t1) over
//!   axes)`, hit iff `entry <= exit`;
//! - traversal visits the nearer child (smaller entry) first, child `c` on equal entries.
//!   Only exact ties in `t` between two triangles can make an order-dependent difference,
//!   and a packet kernel, which orders children by the packet's direction signs along the
//!   node's split axis instead, may legitimately report the other triangle there.

use glam::Vec3;

use crate::bvh::Bvh;
use crate::camera::Camera;
use crate::layout::{
    material_records, node_records, triangle_records, vertex_records, MaterialRecord, NodeRecord,
    StagedScene, TriangleRecord, VertexOrder, VertexRecord,
};
use crate::scene::Scene;
use crate::shading::{self, Light};

/// Triangle index reported for a ray that hits nothing.
pub const MISS: u32 = u32::MAX;
/// Hits need `t > T_MIN`.
pub const T_MIN: f32 = 0.0;
/// The initial (and miss) `t`.
pub const T_MAX: f32 = f32::MAX;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Original scene index of the nearest triangle hit, or [`MISS`].
    pub triangle: u32,
    pub t: f32,
    /// Index of the hit triangle's record (valid only for hits).
    pub record: u32,
}

impl Hit {
    pub const NONE: Hit = Hit {
        triangle: MISS,
        t: T_MAX,
        record: MISS,
    };

    pub fn is_hit(&self) -> bool {
        self.triangle != MISS
    }
}

/// The records the caster runs over (and the shading data: vertices and materials).
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    pub nodes: Vec<NodeRecord>,
    pub triangles: Vec<TriangleRecord>,
    pub vertices: Vec<VertexRecord>,
    pub materials: Vec<MaterialRecord>,
}

/// The eye-light shade `|N.D| / (|N| |D|)`, clamped to `[0, 1]`, computed in f32 as
/// `abs(dot(n, d)) / sqrt(dot(n, n) * dot(d, d))`; 0 for a zero vector.
pub fn shade_eye_light(normal: Vec3, dir: Vec3) -> f32 {
    let lengths = (normal.dot(normal) * dir.dot(dir)).sqrt();
    if lengths > 0.0 {
        (normal.dot(dir).abs() / lengths).min(1.0)
    } else {
        0.0
    }
}

/// A shade in `[0, 1]` as an 8-bit value: `(shade * 255 + 0.5)` truncated.
pub fn shade_to_u8(shade: f32) -> u8 {
    (shade.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// Eye-light gray level of a hit: [`shade_to_u8`] of [`shade_eye_light`].
pub fn eye_light_gray(normal: Vec3, dir: Vec3) -> u8 {
    shade_to_u8(shade_eye_light(normal, dir))
}

/// Eye-light color of a hit on a material with `diffuse` color: per channel
/// [`shade_to_u8`]`(diffuse_c * shade)`.
pub fn eye_light_rgb(normal: Vec3, dir: Vec3, diffuse: [f32; 3]) -> [u8; 3] {
    let shade = shade_eye_light(normal, dir);
    diffuse.map(|c| shade_to_u8(c * shade))
}

/// Slab test; returns the entry distance if the box is hit within `(t_min, t_max]`.
#[inline]
fn hit_box(
    node: &NodeRecord,
    origin: [f32; 3],
    inverse: [f32; 3],
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let mut near = t_min;
    let mut far = t_max;
    for axis in 0..3 {
        let t0 = (node.min[axis] - origin[axis]) * inverse[axis];
        let t1 = (node.max[axis] - origin[axis]) * inverse[axis];
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    (near <= far).then_some(near)
}

/// `node`'s box grown by `slack` of its extent and of its coordinates' magnitude per axis:
/// it holds its triangles widened by `slack` (barycentric) and their rounding.
fn grown(node: &NodeRecord, slack: f32) -> NodeRecord {
    let mut g = *node;
    for a in 0..3 {
        let m = slack * ((node.max[a] - node.min[a]) + node.min[a].abs().max(node.max[a].abs()));
        g.min[a] -= m;
        g.max[a] += m;
    }
    g
}

/// `1 / d` per component, with zero components treated as `±1e-30` so no infinities arise
/// (the SPU has none) and the slab test stays correct for rays parallel to a slab.
fn safe_inverse(d: [f32; 3]) -> [f32; 3] {
    d.map(|x| {
        if x == 0.0 {
            1e30
        } else if x.abs() < 1e-30 {
            1.0 / 1e-30f32.copysign(x)
        } else {
            1.0 / x
        }
    })
}

impl Reference {
    pub fn new(scene: &Scene, bvh: &Bvh) -> Reference {
        let order = VertexOrder::new(scene, bvh);
        Reference {
            nodes: node_records(bvh),
            triangles: triangle_records(scene, bvh, &order),
            vertices: vertex_records(scene, &order),
            materials: material_records(scene),
        }
    }

    pub fn from_staged(staged: &StagedScene) -> Reference {
        Reference {
            nodes: staged.nodes.clone(),
            triangles: staged.triangles.clone(),
            vertices: staged.vertices.clone(),
            materials: staged.materials.clone(),
        }
    }

    /// The nearest hit of the ray `origin + t * dir` with `T_MIN < t < T_MAX`.
    pub fn trace(&self, origin: Vec3, dir: Vec3) -> Hit {
        self.trace_within(origin, dir, T_MAX)
    }

    /// Whether anything lies on `origin + t * dir` with `T_MIN < t < t_max` (the shadow
    /// rays' occlusion query: the nearest hit exists exactly when any hit does).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.trace_within(origin, dir, t_max).is_hit()
    }

    /// The nearest hit with `T_MIN < t < t_max` (a miss keeps `t = t_max`).
    pub fn trace_within(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Hit {
        self.trace_within_slack(origin, dir, t_max, 0.0)
    }

    /// Whether the shadow ray from `light` to `point` grazes an occluder's edge: it is
    /// occluded when every triangle is widened by [`SHADOW_GRAZE`] (barycentric) and not
    /// when every triangle is narrowed by it. Such a ray may come out either way in the
    /// SPU's truncating single precision, which computes the point and the test in its
    /// own rounding.
    pub fn shadow_grazes(&self, light: Vec3, point: Vec3) -> bool {
        let limit = 1.0 - shading::SHADOW_EPSILON;
        let dir = point - light;
        self.trace_within_slack(light, dir, limit, SHADOW_GRAZE)
            .is_hit()
            != self
                .trace_within_slack(light, dir, limit, -SHADOW_GRAZE)
                .is_hit()
    }

    /// [`Reference::trace_within`] with every triangle's barycentric range widened (or
    /// narrowed, negative) by `slack`.
    pub fn trace_within_slack(&self, origin: Vec3, dir: Vec3, t_max: f32, slack: f32) -> Hit {
        let o = origin.to_array();
        let d = dir.to_array();
        let inverse = safe_inverse(d);
        let mut best = Hit {
            t: t_max,
            ..Hit::NONE
        };
        if self.triangles.is_empty() {
            // The empty scene's root is an inverted box whose slabs, swapped by the ray's
            // direction, would read as a valid one: there is nothing to find.
            return best;
        }
        let mut stack: Vec<(u32, f32)> = Vec::with_capacity(128);
        // widened triangles reach past their boxes: the boxes grow with them
        let test_box = |node: &NodeRecord, t_max: f32| {
            if slack > 0.0 {
                hit_box(&grown(node, slack), o, inverse, T_MIN, t_max)
            } else {
                hit_box(node, o, inverse, T_MIN, t_max)
            }
        };
        if let Some(entry) = test_box(&self.nodes[0], best.t) {
            stack.push((0, entry));
        }
        while let Some((index, entry)) = stack.pop() {
            if entry > best.t {
                continue;
            }
            let node = &self.nodes[index as usize];
            let count = node.triangle_count();
            if count > 0 {
                for record in node.link..node.link + count {
                    let triangle = &self.triangles[record as usize];
                    if let Some((t, _, _)) =
                        triangle.intersect_with_slack(o, d, T_MIN, best.t, slack)
                    {
                        best = Hit {
                            triangle: triangle.original_index,
                            t,
                            record,
                        };
                    }
                }
                continue;
            }
            let c = node.link;
            let near = test_box(&self.nodes[c as usize], best.t);
            let far = test_box(&self.nodes[c as usize + 1], best.t);
            match (near, far) {
                (Some(a), Some(b)) if a <= b => {
                    stack.push((c + 1, b));
                    stack.push((c, a));
                }
                (Some(a), Some(b)) => {
                    stack.push((c, a));
                    stack.push((c + 1, b));
                }
                (Some(a), None) => stack.push((c, a)),
                (None, Some(b)) => stack.push((c + 1, b)),
                (None, None) => {}
            }
        }
        best
    }

    /// Primary-ray hits of a `width x height` image, row-major from the top row, computed on
    /// up to `threads` threads (the result does not depend on the thread count).
    pub fn render(&self, camera: &Camera, width: u32, height: u32, threads: usize) -> Vec<Hit> {
        let basis = camera.basis(width, height);
        let mut hits = vec![Hit::NONE; width as usize * height as usize];
        if hits.is_empty() {
            return hits;
        }
        let threads = threads.max(1).min(height as usize);
        let rows_per_chunk = (height as usize).div_ceil(threads * 8).max(1);
        // Interleaved chunks balance the load; each pixel is computed independently, so the
        // assignment cannot change the result.
        let mut work: Vec<Vec<(usize, &mut [Hit])>> = (0..threads).map(|_| Vec::new()).collect();
        for (number, chunk) in hits.chunks_mut(rows_per_chunk * width as usize).enumerate() {
            work[number % threads].push((number, chunk));
        }
        let trace_chunks = |chunks: Vec<(usize, &mut [Hit])>| {
            for (number, chunk) in chunks {
                let first_row = number * rows_per_chunk;
                for (i, hit) in chunk.iter_mut().enumerate() {
                    let x = (i % width as usize) as u32;
                    let y = (first_row + i / width as usize) as u32;
                    *hit = self.trace(basis.origin, basis.direction(x, y));
                }
            }
        };
        std::thread::scope(|scope| {
            let mut work = work.into_iter();
            let mine = work.next().unwrap_or_default();
            for chunks in work {
                scope.spawn(|| trace_chunks(chunks));
            }
            trace_chunks(mine);
        });
        hits
    }

    /// Eye-light gray image (row-major, top row first) of `hits` from [`Reference::render`],
    /// shaded with the geometric normal stored in the triangle record; misses are 0.
    pub fn eye_light_image(
        &self,
        hits: &[Hit],
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Vec<u8> {
        let basis = camera.basis(width, height);
        hits.iter()
            .enumerate()
            .map(|(i, hit)| {
                if !hit.is_hit() {
                    return 0;
                }
                let dir = basis.direction(i as u32 % width, i as u32 / width);
                eye_light_gray(self.triangles[hit.record as usize].geometric_normal(), dir)
            })
            .collect()
    }
}

impl Reference {
    /// The colour of the model in [`crate::shading`] for a primary hit on the ray
    /// `origin + t * dir` (black for a miss); `shadows` adds the occlusion query per light.
    pub fn shade(
        &self,
        hit: &Hit,
        origin: Vec3,
        dir: Vec3,
        lights: &[Light],
        shadows: bool,
    ) -> u32 {
        self.shade_with(hit, origin, dir, lights, &|_, light, point| {
            !(shadows
                && self.occluded(
                    light.position,
                    point - light.position,
                    1.0 - shading::SHADOW_EPSILON,
                ))
        })
    }

    /// Every colour [`Reference::shade`] with shadows may legitimately give the pixel: the
    /// shadow rays that graze an occluder's edge ([`Reference::shadow_grazes`]) taken as
    /// occluded and as not, in every combination (one colour when none grazes).
    pub fn shade_alternatives(
        &self,
        hit: &Hit,
        origin: Vec3,
        dir: Vec3,
        lights: &[Light],
    ) -> Vec<u32> {
        if !hit.is_hit() {
            return vec![MISS_COLOUR];
        }
        let point = origin + dir * hit.t;
        let grazing: Vec<usize> = (0..lights.len())
            .filter(|&i| self.shadow_grazes(lights[i].position, point))
            .collect();
        (0..1u32 << grazing.len())
            .map(|choice| {
                self.shade_with(hit, origin, dir, lights, &|i, light, point| match grazing
                    .iter()
                    .position(|&g| g == i)
                {
                    Some(bit) => choice & (1 << bit) != 0,
                    None => !self.occluded(
                        light.position,
                        point - light.position,
                        1.0 - shading::SHADOW_EPSILON,
                    ),
                })
            })
            .collect()
    }

    /// The colour of the kernel's hit on staged record `record` when it is another triangle
    /// than the reference's nearest `hit` yet an equally valid one: a ray through an edge
    /// two triangles share (a box's corner, a crease) hits both at one distance, and single
    /// precision gives it to either, whose normals may shade it differently (the room's
    /// picture frame at (1021, 164) of 1024x1024: its front lit, its side not). The kernel's
    /// triangle, widened by [`EDGE_TIE`] (barycentric), must be hit within 1e-4 (relative)
    /// of `hit.t`. `None` when it is the reference's own triangle or no such tie.
    pub fn shade_edge_tie(
        &self,
        hit: &Hit,
        record: u32,
        origin: Vec3,
        dir: Vec3,
        lights: &[Light],
        shadows: bool,
    ) -> Option<u32> {
        if !hit.is_hit() || record == hit.record {
            return None;
        }
        let triangle = self.triangles.get(record as usize)?;
        let (t, _, _) = triangle.intersect_with_slack(
            origin.to_array(),
            dir.to_array(),
            T_MIN,
            T_MAX,
            EDGE_TIE,
        )?;
        if (t - hit.t).abs() > 1e-4 * t.abs().max(hit.t.abs()) {
            return None;
        }
        let tie = Hit {
            triangle: triangle.original_index,
            t,
            record,
        };
        Some(self.shade(&tie, origin, dir, lights, shadows))
    }

    /// The model's colour with `visible(light index, light, point)` deciding each light's
    /// occlusion (asked only for lights the surface faces).
    fn shade_with(
        &self,
        hit: &Hit,
        origin: Vec3,
        dir: Vec3,
        lights: &[Light],
        visible: &dyn Fn(usize, &Light, Vec3) -> bool,
    ) -> u32 {
        let Some(Surface {
            point,
            normal,
            material,
        }) = self.surface(hit, origin, dir)
        else {
            return MISS_COLOUR;
        };
        let mut irradiance = Vec3::ZERO;
        for (i, light) in lights.iter().enumerate() {
            let cosine = shading::light_cosine(normal, light.position - point);
            if cosine > 0.0 && visible(i, light, point) {
                irradiance += light.colour * cosine;
            }
        }
        shading::pixel_colour(self.materials[material as usize].diffuse, irradiance)
    }

    /// Where the ray `origin + t * dir` hits with `hit` (`None` for a miss): the point, the
    /// model's eye-facing shading normal there and the material.
    pub fn surface(&self, hit: &Hit, origin: Vec3, dir: Vec3) -> Option<Surface> {
        if !hit.is_hit() {
            return None;
        }
        let record = &self.triangles[hit.record as usize];
        let (beta, gamma) = record.barycentrics(origin.to_array(), dir.to_array(), hit.t);
        let normals = record
            .vertices
            .map(|v| Vec3::from(self.vertices[v as usize].normal));
        Some(Surface {
            point: origin + dir * hit.t,
            normal: shading::shading_normal(normals, beta, gamma, dir),
            material: record.material,
        })
    }

    /// [`Reference::shade`] for every pixel of `hits` from [`Reference::render`].
    #[allow(clippy::too_many_arguments)]
    pub fn shade_image(
        &self,
        hits: &[Hit],
        camera: &Camera,
        width: u32,
        height: u32,
        lights: &[Light],
        shadows: bool,
        threads: usize,
    ) -> Vec<u32> {
        let basis = camera.basis(width, height);
        let mut colours = vec![MISS_COLOUR; hits.len()];
        let threads = threads.max(1);
        let chunk = hits.len().div_ceil(threads).max(1);
        std::thread::scope(|scope| {
            for (number, out) in colours.chunks_mut(chunk).enumerate() {
                let basis = &basis;
                scope.spawn(move || {
                    for (i, colour) in out.iter_mut().enumerate() {
                        let pixel = (number * chunk + i) as u32;
                        let dir = basis.direction(pixel % width, pixel / width);
                        *colour =
                            self.shade(&hits[pixel as usize], basis.origin, dir, lights, shadows);
                    }
                });
            }
        });
        colours
    }
}

/// A hit's shading data ([`Reference::surface`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// `origin + t * dir`.
    pub point: Vec3,
    /// The interpolated vertex normal, turned to face the ray (not normalised).
    pub normal: Vec3,
    /// Index of the material record.
    pub material: u32,
}

/// Barycentric margin within which a shadow ray grazes an occluder's edge
/// ([`Reference::shadow_grazes`]).
pub const SHADOW_GRAZE: f32 = 1.0 / 65536.0;

/// Barycentric margin within which a primary ray through an edge shared by two
/// triangles may hit either ([`Reference::shade_edge_tie`]).
pub const EDGE_TIE: f32 = 1.0 / 65536.0;

/// The colour of a pixel whose primary ray hits nothing: opaque black.
pub const MISS_COLOUR: u32 = 0x0000_00ff;

/// Möller–Trumbore in f64 against every triangle: `(triangle, t, beta, gamma)` of the
/// nearest hit with `t > 0`, for checking [`Reference::trace`]. `slack` widens (positive) or
/// narrows (negative) the barycentric acceptance range.
pub fn brute_force_trace(
    scene: &Scene,
    origin: Vec3,
    dir: Vec3,
    slack: f64,
) -> Option<(u32, f64, f64, f64)> {
    let o = origin.as_dvec3();
    let d = dir.as_dvec3();
    let mut best: Option<(u32, f64, f64, f64)> = None;
    for index in 0..scene.triangles.len() {
        let [a, b, c] = scene.triangle_positions(index).map(|p| p.as_dvec3());
        let e1 = b - a;
        let e2 = c - a;
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            continue;
        }
        let inv = 1.0 / det;
        let s = o - a;
        let beta = s.dot(p) * inv;
        let q = s.cross(e1);
        let gamma = d.dot(q) * inv;
        let t = e2.dot(q) * inv;
        let inside = beta >= -slack && gamma >= -slack && beta + gamma <= 1.0 + slack;
        if inside && t > 0.0 && best.is_none_or(|(_, best_t, _, _)| t < best_t) {
            best = Some((index as u32, t, beta, gamma));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::BvhConfig;

    /// A scene without triangles: every ray misses (and the trace ends).
    #[test]
    fn the_empty_scene_is_missed() {
        let scene = Scene::from_parts(Vec::new(), None, Vec::new(), Vec::new(), Vec::new());
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let reference = Reference::new(&scene, &bvh);
        let hit = reference.trace(Vec3::new(0.5, 0.5, 5.0), Vec3::new(0.0, 0.0, -1.0));
        assert!(!hit.is_hit());
        let camera = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0);
        assert!(reference
            .render(&camera, 8, 8, 1)
            .iter()
            .all(|h| !h.is_hit()));
    }

    /// Compares the reference with brute force for every pixel. Disagreements are allowed
    /// only where f32 vs f64 precision legitimately decides: the reference's triangle is hit
    /// (with a tiny barycentric slack) at the same distance as brute force's (a tie or a
    /// shared edge), or brute force's hit lies on a triangle edge.
    fn check_against_brute_force(scene: &Scene, camera: &Camera, width: u32, height: u32) -> usize {
        let bvh = Bvh::build(scene, &BvhConfig::default());
        bvh.validate(scene).unwrap();
        let reference = Reference::new(scene, &bvh);
        let hits = reference.render(camera, width, height, 2);
        let basis = camera.basis(width, height);
        let mut hit_count = 0;
        for (i, hit) in hits.iter().enumerate() {
            let (x, y) = (i as u32 % width, i as u32 / width);
            let dir = basis.direction(x, y);
            let exact = brute_force_trace(scene, basis.origin, dir, 0.0);
            hit_count += usize::from(hit.is_hit());
            let agree = match exact {
                None => !hit.is_hit(),
                Some((triangle, t, _, _)) => {
                    hit.triangle == triangle
                        && ((hit.t as f64 - t).abs() <= 1e-4 * t.abs().max(1e-3))
                }
            };
            if agree {
                continue;
            }
            let near_edge = |beta: f64, gamma: f64| beta.min(gamma).min(1.0 - beta - gamma) < 1e-4;
            let explained = match exact {
                Some((_, t, beta, gamma))
                    if near_edge(beta, gamma)
                        && (!hit.is_hit() || hit.t as f64 >= t * (1.0 - 1e-4)) =>
                {
                    true
                }
                Some((_, t, _, _)) if hit.is_hit() => {
                    let mut single = scene.clone();
                    single.triangles = vec![scene.triangles[hit.triangle as usize]];
                    brute_force_trace(&single, basis.origin, dir, 1e-4).is_some_and(
                        |(_, t_ref, _, _)| (t_ref - t).abs() <= 1e-4 * t.abs().max(1e-3),
                    )
                }
                _ => false,
            };
            assert!(
                explained,
                "pixel ({x},{y}): reference {hit:?}, brute force {exact:?}"
            );
        }
        hit_count
    }

    #[test]
    fn reference_matches_brute_force_on_a_triangle_soup() {
        let scene = crate::bvh::tests::soup_sized(400, 2.5);
        let camera = Camera::new(
            Vec3::new(5.0, 6.0, 25.0),
            Vec3::new(5.0, 5.0, 5.0),
            Vec3::Y,
            40.0,
        );
        let hits = check_against_brute_force(&scene, &camera, 48, 40);
        assert!(hits > 300, "only {hits} pixels hit");
    }

    #[test]
    fn reference_matches_brute_force_on_the_room() {
        let scene = crate::procedural::room();
        let hits = check_against_brute_force(&scene, &scene.camera, 64, 48);
        assert_eq!(hits, 64 * 48, "a closed room is hit everywhere");
    }

    #[test]
    fn render_is_independent_of_threads_and_shading_is_defined() {
        let scene = crate::procedural::room();
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let reference = Reference::new(&scene, &bvh);
        let one = reference.render(&scene.camera, 40, 30, 1);
        let three = reference.render(&scene.camera, 40, 30, 3);
        assert_eq!(one, three);
        let image = reference.eye_light_image(&one, &scene.camera, 40, 30);
        assert_eq!(image.len(), 1200);
        assert!(image.iter().any(|&g| g > 100));

        assert_eq!(eye_light_gray(Vec3::Z, Vec3::new(0.0, 0.0, -3.0)), 255);
        assert_eq!(eye_light_gray(Vec3::X, Vec3::Z), 0);
        assert_eq!(eye_light_gray(Vec3::new(0.0, 1.0, 1.0), Vec3::Z), 180); // 0.7071 * 255 + 0.5 = 180.8
        assert_eq!(
            eye_light_rgb(Vec3::Z, Vec3::Z, [1.0, 0.5, 0.0]),
            [255, 128, 0]
        );
        assert_eq!(eye_light_gray(Vec3::ZERO, Vec3::Z), 0);
    }

    /// A floor quad (kd 0.5, 0.25, 1.0) lit from straight above, with a small blocker half
    /// way up: the colour under the light is shadowed to the ambient term, next to it lit.
    #[test]
    fn shading_and_shadows_by_hand() {
        use crate::scene::{Material, Triangle};
        let positions = vec![
            Vec3::new(-2.0, 0.0, -2.0),
            Vec3::new(2.0, 0.0, -2.0),
            Vec3::new(2.0, 0.0, 2.0),
            Vec3::new(-2.0, 0.0, 2.0),
            Vec3::new(-0.1, 1.0, -0.1),
            Vec3::new(0.1, 1.0, -0.1),
            Vec3::new(0.1, 1.0, 0.1),
            Vec3::new(-0.1, 1.0, 0.1),
        ];
        let triangles = [[0, 2, 1], [0, 3, 2], [4, 6, 5], [4, 7, 6]]
            .iter()
            .enumerate()
            .map(|(i, &v)| Triangle {
                v,
                material: (i / 2) as u32,
            })
            .collect();
        let materials = vec![
            Material::new("floor", [0.5, 0.25, 1.0]),
            Material::new("blocker", [1.0, 1.0, 1.0]),
        ];
        let scene = Scene::from_parts(positions, None, Vec::new(), triangles, materials);
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let reference = Reference::new(&scene, &bvh);
        let light = [Light::white(Vec3::new(0.0, 2.0, 0.0))];
        let look = |x: f32| {
            let origin = Vec3::new(x, 3.0, 0.0);
            // Straight down onto the floor at (x, 0, 0), through the blocker's plane.
            let dir = Vec3::new(0.0, -1.0, 0.0);
            (origin, dir)
        };
        // Beside the blocker: cos = 1 with the light 2 above (x = 0.5: cos = 2/sqrt(4.25)).
        let (o, d) = look(0.5);
        let hit = reference.trace(o, d);
        assert!(hit.is_hit() && (hit.t - 3.0).abs() < 1e-6);
        let cosine = 2.0 / 4.25f32.sqrt();
        let expected = shading::pixel_colour([0.5, 0.25, 1.0], Vec3::splat(cosine));
        assert_eq!(reference.shade(&hit, o, d, &light, false), expected);
        assert_eq!(reference.shade(&hit, o, d, &light, true), expected);
        // Under the blocker, seen from below the blocker's height (from the side).
        let o = Vec3::new(0.0, 0.5, 1.5);
        let d = Vec3::new(0.0, -0.5, -1.5);
        let hit = reference.trace(o, d);
        assert_eq!(hit.triangle / 2, 0, "the floor");
        let lit = reference.shade(&hit, o, d, &light, false);
        assert_eq!(lit, shading::pixel_colour([0.5, 0.25, 1.0], Vec3::ONE));
        assert_eq!(
            reference.shade(&hit, o, d, &light, true),
            shading::pixel_colour([0.5, 0.25, 1.0], Vec3::ZERO),
            "shadowed: ambient only"
        );
        assert_eq!(reference.shade(&Hit::NONE, o, d, &light, true), MISS_COLOUR);
        // The blocker seen from below faces the eye, but the light is behind it.
        let o = Vec3::new(0.0, 0.5, 0.0);
        let d = Vec3::Y;
        let hit = reference.trace(o, d);
        assert_eq!(hit.triangle / 2, 1);
        assert_eq!(
            reference.shade(&hit, o, d, &light, false),
            shading::pixel_colour([1.0; 3], Vec3::ZERO)
        );
    }

    #[test]
    fn room_shading_uses_materials_and_shadows_darken() {
        let scene = crate::procedural::room();
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let reference = Reference::new(&scene, &bvh);
        let (w, h) = (48, 36);
        let hits = reference.render(&scene.camera, w, h, 2);
        let lights = shading::default_lights(&scene);
        let simple = reference.shade_image(&hits, &scene.camera, w, h, &lights, false, 1);
        let shadows = reference.shade_image(&hits, &scene.camera, w, h, &lights, true, 3);
        assert_eq!(
            simple,
            reference.shade_image(&hits, &scene.camera, w, h, &lights, false, 4)
        );
        let distinct: std::collections::HashSet<u32> = simple.iter().copied().collect();
        assert!(distinct.len() > 50, "{} colours", distinct.len());
        let darker = simple.iter().zip(&shadows).filter(|(a, b)| a != b).count();
        assert!(darker > 20, "{darker} shadowed pixels");
        for (a, b) in simple.iter().zip(&shadows) {
            let [ar, ag, ab, _] = a.to_be_bytes();
            let [br, bg, bb, _] = b.to_be_bytes();
            assert!(br <= ar && bg <= ag && bb <= ab, "shadows only darken");
        }
    }
}
