//! Built-in deterministic scenes standing in for the paper's three test scenes (which are not
//! public), so that every test and benchmark runs without the shared scene files:
//!
//! - [`room`]: an ERW6-class furnished room (about 800 triangles, paper: 804);
//! - [`conference`]: a meeting room with rows of finely tessellated chairs around long tables
//!   (paper: 280k triangles);
//! - [`beetle`]: a single smooth, finely tessellated car-like body on four wheels whose
//!   triangles are smaller than an 8x8-pixel packet's footprint at 1024x1024 from its
//!   default camera (paper: VW Beetle, 680k triangles) — the case where the triangle cache
//!   stops helping (paper section 5.3).
//!
//! There is no randomness: geometry is a pure function of the code (f32 arithmetic and the
//! platform's `sin`/`cos`/`powf`), so the topology is identical everywhere and the positions
//! identical on a given platform. Units are meters, `+Y` is up.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Vec2, Vec3};

use crate::camera::Camera;
use crate::scene::{Material, Scene, Triangle};
use crate::shading::Light;

/// Accumulates vertices and triangles of primitives placed by a current transform.
struct MeshBuilder {
    positions: Vec<Vec3>,
    triangles: Vec<Triangle>,
    materials: Vec<Material>,
    transform: Affine3A,
}

impl MeshBuilder {
    fn new() -> Self {
        MeshBuilder {
            positions: Vec::new(),
            triangles: Vec::new(),
            materials: Vec::new(),
            transform: Affine3A::IDENTITY,
        }
    }

    fn material(&mut self, name: &str, diffuse: [f32; 3]) -> u32 {
        self.reflective(name, diffuse, 0.0)
    }

    /// A material that `--shade reflect` mirrors with weight `reflectance`.
    fn reflective(&mut self, name: &str, diffuse: [f32; 3], reflectance: f32) -> u32 {
        self.materials
            .push(Material::reflective(name, diffuse, reflectance));
        self.materials.len() as u32 - 1
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        self.positions.push(self.transform.transform_point3(p));
        self.positions.len() as u32 - 1
    }

    fn triangle(&mut self, a: u32, b: u32, c: u32, material: u32) {
        self.triangles.push(Triangle {
            v: [a, b, c],
            material,
        });
    }

    /// Two triangles for the quad `a b c d` (counter-clockwise seen from the front).
    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32, material: u32) {
        self.triangle(a, b, c, material);
        self.triangle(a, c, d, material);
    }

    /// A parametric patch `surface(u, v)`, `u, v` in `[0, 1]`, on an `nu x nv` grid with
    /// shared vertices (so smoothing makes it smooth). `wrap_u` closes it in `u` (the
    /// column at `u = 1` is the one at `u = 0`); `pole_start` / `pole_end` collapse the
    /// rows at `v = 0` / `v = 1` to a single vertex and close them with fans, avoiding
    /// zero-area triangles. Produces `2 * nu * nv` triangles minus `nu` per pole.
    #[allow(clippy::too_many_arguments)]
    fn patch(
        &mut self,
        nu: usize,
        nv: usize,
        wrap_u: bool,
        pole_start: bool,
        pole_end: bool,
        material: u32,
        surface: impl Fn(f32, f32) -> Vec3,
    ) {
        let columns = if wrap_u { nu } else { nu + 1 };
        let mut rows: Vec<Vec<u32>> = Vec::with_capacity(nv + 1);
        for j in 0..=nv {
            let v = j as f32 / nv as f32;
            if (j == 0 && pole_start) || (j == nv && pole_end) {
                let pole = self.vertex(surface(0.0, v));
                rows.push(vec![pole; columns]);
            } else {
                let row = (0..columns)
                    .map(|i| self.vertex(surface(i as f32 / nu as f32, v)))
                    .collect();
                rows.push(row);
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let i1 = if wrap_u { (i + 1) % nu } else { i + 1 };
                let (a, b) = (rows[j][i], rows[j][i1]);
                let (c, d) = (rows[j + 1][i1], rows[j + 1][i]);
                if j == 0 && pole_start {
                    self.triangle(a, c, d, material);
                } else if j == nv - 1 && pole_end {
                    self.triangle(a, b, c, material);
                } else {
                    self.quad(a, b, c, d, material);
                }
            }
        }
    }

    /// An axis-aligned box, each face an `n x n` grid with its own vertices (flat shading);
    /// faces point outward, or inward with `inward` (for rooms). `12 * n * n` triangles.
    fn tessellated_box(&mut self, min: Vec3, max: Vec3, n: usize, inward: bool, material: u32) {
        let size = max - min;
        // (origin corner, edge along u, edge along v) with u x v pointing outward.
        let faces = [
            (
                Vec3::new(max.x, min.y, min.z),
                Vec3::new(0.0, 0.0, size.z),
                Vec3::new(0.0, size.y, 0.0),
            ),
            (
                Vec3::new(min.x, min.y, max.z),
                Vec3::new(0.0, 0.0, -size.z),
                Vec3::new(0.0, size.y, 0.0),
            ),
            (
                Vec3::new(min.x, max.y, min.z),
                Vec3::new(0.0, 0.0, size.z),
                Vec3::new(size.x, 0.0, 0.0),
            ),
            (
                Vec3::new(min.x, min.y, min.z),
                Vec3::new(size.x, 0.0, 0.0),
                Vec3::new(0.0, 0.0, size.z),
            ),
            (
                Vec3::new(min.x, min.y, max.z),
                Vec3::new(size.x, 0.0, 0.0),
                Vec3::new(0.0, size.y, 0.0),
            ),
            (
                Vec3::new(max.x, min.y, min.z),
                Vec3::new(-size.x, 0.0, 0.0),
                Vec3::new(0.0, size.y, 0.0),
            ),
        ];
        for (origin, eu, ev) in faces {
            let (eu, ev) = if inward { (ev, eu) } else { (eu, ev) };
            self.patch(n, n, false, false, false, material, |u, v| {
                origin + eu * u + ev * v
            });
        }
    }

    fn simple_box(&mut self, min: Vec3, max: Vec3, material: u32) {
        self.tessellated_box(min, max, 1, false, material);
    }

    /// A closed cylinder (or cone frustum) along +Y from `base`, radii `r0` at the bottom and
    /// `r1` at the top: `2 * segments * rings` side triangles plus `segments` per cap.
    #[allow(clippy::too_many_arguments)]
    fn cylinder(
        &mut self,
        base: Vec3,
        r0: f32,
        r1: f32,
        height: f32,
        segments: usize,
        rings: usize,
        caps: bool,
        material: u32,
    ) {
        self.patch(segments, rings, true, false, false, material, |u, v| {
            let angle = -TAU * u;
            let r = r0 + (r1 - r0) * v;
            base + Vec3::new(r * angle.cos(), height * v, r * angle.sin())
        });
        if caps {
            for (y, r, down) in [(0.0, r0, true), (height, r1, false)] {
                let center = self.vertex(base + Vec3::new(0.0, y, 0.0));
                let ring: Vec<u32> = (0..segments)
                    .map(|i| {
                        let angle = TAU * i as f32 / segments as f32;
                        self.vertex(base + Vec3::new(r * angle.cos(), y, r * angle.sin()))
                    })
                    .collect();
                for i in 0..segments {
                    let (a, b) = (ring[i], ring[(i + 1) % segments]);
                    if down {
                        self.triangle(center, a, b, material);
                    } else {
                        self.triangle(center, b, a, material);
                    }
                }
            }
        }
    }

    /// A closed shell of thickness `thickness` below the surface `top(u, v)` (offset along
    /// `-offset_dir`): top and bottom `nu x nv` patches plus a rim around the border.
    /// `4 * nu * nv + 4 * (nu + nv)` triangles.
    fn shell(
        &mut self,
        nu: usize,
        nv: usize,
        offset: Vec3,
        material: u32,
        top: impl Fn(f32, f32) -> Vec3,
    ) {
        self.patch(nu, nv, false, false, false, material, &top);
        self.patch(nu, nv, false, false, false, material, |u, v| {
            top(1.0 - u, v) - offset
        });
        // The rim walks the border of the parameter square once.
        let mut border: Vec<(f32, f32)> = Vec::with_capacity(2 * (nu + nv));
        border.extend((0..nu).map(|i| (i as f32 / nu as f32, 0.0)));
        border.extend((0..nv).map(|j| (1.0, j as f32 / nv as f32)));
        border.extend((0..nu).map(|i| (1.0 - i as f32 / nu as f32, 1.0)));
        border.extend((0..nv).map(|j| (0.0, 1.0 - j as f32 / nv as f32)));
        let count = border.len();
        for index in 0..count {
            let (u0, v0) = border[index];
            let (u1, v1) = border[(index + 1) % count];
            let a = self.vertex(top(u0, v0));
            let b = self.vertex(top(u1, v1));
            let c = self.vertex(top(u1, v1) - offset);
            let d = self.vertex(top(u0, v0) - offset);
            self.quad(a, d, c, b, material);
        }
    }

    /// A torus around the +X axis through `center` (a wheel), `2 * major * minor` triangles.
    fn torus_x(
        &mut self,
        center: Vec3,
        major_radius: f32,
        minor_radius: f32,
        major: usize,
        minor: usize,
        material: u32,
    ) {
        let grid_u = major;
        let grid_v = minor;
        let mut rows: Vec<Vec<u32>> = Vec::with_capacity(grid_v);
        for j in 0..grid_v {
            let phi = TAU * j as f32 / grid_v as f32;
            let row = (0..grid_u)
                .map(|i| {
                    let theta = TAU * i as f32 / grid_u as f32;
                    let r = major_radius + minor_radius * phi.cos();
                    self.vertex(
                        center
                            + Vec3::new(minor_radius * phi.sin(), r * theta.cos(), r * theta.sin()),
                    )
                })
                .collect();
            rows.push(row);
        }
        for j in 0..grid_v {
            for i in 0..grid_u {
                let (j1, i1) = ((j + 1) % grid_v, (i + 1) % grid_u);
                self.quad(rows[j][i], rows[j][i1], rows[j1][i1], rows[j1][i], material);
            }
        }
    }

    fn finish(self, camera: Camera) -> Scene {
        let mut scene = Scene::from_parts(
            self.positions,
            None,
            Vec::<Vec2>::new(),
            self.triangles,
            self.materials,
        );
        scene.camera = camera;
        scene
    }
}

/// A simple chair (seat, backrest, four legs) of 72 triangles facing `-Z` in local space.
fn simple_chair(builder: &mut MeshBuilder, seat: u32, frame: u32) {
    let leg = 0.03;
    for (x, z) in [
        (-0.2, -0.2),
        (0.2 - leg, -0.2),
        (-0.2, 0.2 - leg),
        (0.2 - leg, 0.2 - leg),
    ] {
        builder.simple_box(
            Vec3::new(x, 0.0, z),
            Vec3::new(x + leg, 0.45, z + leg),
            frame,
        );
    }
    builder.simple_box(
        Vec3::new(-0.22, 0.45, -0.22),
        Vec3::new(0.22, 0.49, 0.22),
        seat,
    );
    builder.simple_box(
        Vec3::new(-0.22, 0.49, 0.18),
        Vec3::new(0.22, 0.95, 0.22),
        seat,
    );
}

/// The mirror weights of the procedural scenes' reflective surfaces (`--shade reflect`):
/// the room's polished table, the conference's lacquered tables, the beetle's car paint.
/// Every other material reflects nothing.
pub const ROOM_TABLE_REFLECTANCE: f32 = 0.4;
pub const CONFERENCE_TABLE_REFLECTANCE: f32 = 0.3;
pub const BEETLE_PAINT_REFLECTANCE: f32 = 0.25;

/// The ERW6-class room: 6 x 3 x 5 m with walls, floor and ceiling (4x4 grids), a table, four
/// chairs, a floor lamp and a picture (792 triangles, 9 materials).
pub fn room() -> Scene {
    let mut b = MeshBuilder::new();
    let floor = b.material("floor", [0.55, 0.38, 0.22]);
    let walls = b.material("walls", [0.85, 0.82, 0.72]);
    let ceiling = b.material("ceiling", [0.95, 0.95, 0.95]);
    let table = b.reflective("table", [0.45, 0.25, 0.12], ROOM_TABLE_REFLECTANCE);
    let seat = b.material("chair seat", [0.7, 0.12, 0.1]);
    let frame = b.material("chair frame", [0.2, 0.2, 0.22]);
    let metal = b.material("lamp metal", [0.6, 0.6, 0.65]);
    let shade = b.material("lamp shade", [0.95, 0.85, 0.45]);
    let picture = b.material("picture", [0.15, 0.35, 0.75]);

    // The shell: one inward box whose floor and ceiling faces get their own materials.
    let first = b.triangles.len();
    b.tessellated_box(
        Vec3::new(-3.0, 0.0, -2.5),
        Vec3::new(3.0, 3.0, 2.5),
        4,
        true,
        walls,
    );
    for (face, triangle) in b.triangles[first..].iter_mut().enumerate() {
        match face / 32 {
            2 => triangle.material = ceiling,
            3 => triangle.material = floor,
            _ => {}
        }
    }

    // Table: 1.6 x 0.9 top at 0.75 m, four legs.
    b.simple_box(
        Vec3::new(-0.8, 0.72, -0.45),
        Vec3::new(0.8, 0.76, 0.45),
        table,
    );
    for (x, z) in [(-0.75, -0.4), (0.7, -0.4), (-0.75, 0.35), (0.7, 0.35)] {
        b.simple_box(
            Vec3::new(x, 0.0, z),
            Vec3::new(x + 0.05, 0.72, z + 0.05),
            table,
        );
    }
    // Four chairs around it, each turned to face the table.
    for (position, angle) in [
        (Vec3::new(-0.4, 0.0, 0.75), 0.0),
        (Vec3::new(0.4, 0.0, 0.75), 0.0),
        (Vec3::new(-0.4, 0.0, -0.75), PI),
        (Vec3::new(0.4, 0.0, -0.75), PI),
    ] {
        b.transform = Affine3A::from_translation(position) * Affine3A::from_rotation_y(angle);
        simple_chair(&mut b, seat, frame);
    }
    b.transform = Affine3A::from_translation(Vec3::new(2.3, 0.0, -1.8));
    b.cylinder(Vec3::ZERO, 0.2, 0.2, 0.04, 24, 1, true, metal);
    b.cylinder(
        Vec3::new(0.0, 0.04, 0.0),
        0.02,
        0.02,
        1.45,
        12,
        1,
        true,
        metal,
    );
    b.cylinder(
        Vec3::new(0.0, 1.45, 0.0),
        0.28,
        0.14,
        0.3,
        24,
        2,
        false,
        shade,
    );
    b.transform = Affine3A::IDENTITY;
    b.simple_box(
        Vec3::new(-0.9, 1.3, -2.5),
        Vec3::new(0.9, 2.3, -2.47),
        picture,
    );

    let camera = Camera::new(
        Vec3::new(2.6, 1.7, 2.2),
        Vec3::new(-0.2, 0.6, -0.3),
        Vec3::Y,
        60.0,
    );
    let mut scene = b.finish(camera);
    // A ceiling light off the room's centre, so the table and chairs cast shadows.
    scene.lights = vec![Light::white(Vec3::new(-0.6, 2.7, 0.4))];
    scene
}

/// A conference chair: curved seat and backrest shells, four legs, two armrests, 9,728
/// triangles, facing `-Z` (toward the table) in local space.
fn conference_chair(b: &mut MeshBuilder, shell_material: u32, metal: u32, arm: u32) {
    let (width, depth, height) = (0.5f32, 0.48f32, 0.46f32);
    let n = 32;
    // Seat: dished in the middle, rolled up at the front and back edges.
    b.shell(n, n, Vec3::new(0.0, 0.035, 0.0), shell_material, |u, v| {
        let (x, z) = (2.0 * u - 1.0, 2.0 * v - 1.0);
        let y = height - 0.025 * (1.0 - x * x) * (1.0 - z * z) + 0.03 * z.powi(4);
        Vec3::new(-x * width * 0.5, y, z * depth * 0.5)
    });
    // Backrest: wrapped around the sitter, leaning back.
    b.shell(n, n, Vec3::new(0.0, 0.0, -0.03), shell_material, |u, v| {
        let x = 2.0 * u - 1.0;
        let y = height + 0.08 + 0.5 * v;
        let z = depth * 0.5 + 0.04 + 0.08 * v + 0.06 * x * x;
        Vec3::new(x * width * 0.5, y, z)
    });
    for (x, z) in [(-0.21, -0.19), (0.21, -0.19), (-0.21, 0.19), (0.21, 0.19)] {
        b.cylinder(
            Vec3::new(x, 0.0, z),
            0.016,
            0.014,
            height - 0.03,
            16,
            4,
            true,
            metal,
        );
    }
    for x in [-0.27f32, 0.23] {
        b.tessellated_box(
            Vec3::new(x, 0.62, -0.18),
            Vec3::new(x + 0.04, 0.66, 0.2),
            4,
            false,
            arm,
        );
    }
}

/// The conference room: 30 x 4 x 14 m, two 12 m tables with 14 chairs each (7 per side),
/// 284,640 triangles, 8 materials.
pub fn conference() -> Scene {
    let mut b = MeshBuilder::new();
    let carpet = b.material("carpet", [0.3, 0.35, 0.5]);
    let walls = b.material("walls", [0.85, 0.83, 0.78]);
    let ceiling = b.material("ceiling", [0.95, 0.95, 0.93]);
    let wood = b.reflective(
        "table wood",
        [0.55, 0.36, 0.2],
        CONFERENCE_TABLE_REFLECTANCE,
    );
    let shell = b.material("chair shell", [0.75, 0.15, 0.12]);
    let metal = b.material("chrome", [0.7, 0.7, 0.75]);
    let arm = b.material("armrest", [0.1, 0.1, 0.1]);
    let lamp = b.material("ceiling lamp", [1.0, 0.97, 0.85]);

    let first = b.triangles.len();
    b.tessellated_box(
        Vec3::new(-15.0, 0.0, -7.0),
        Vec3::new(15.0, 4.0, 7.0),
        16,
        true,
        walls,
    );
    let per_face = 2 * 16 * 16;
    for (index, triangle) in b.triangles[first..].iter_mut().enumerate() {
        match index / per_face {
            2 => triangle.material = ceiling,
            3 => triangle.material = carpet,
            _ => {}
        }
    }

    for table_z in [-3.0f32, 3.0] {
        b.transform = Affine3A::from_translation(Vec3::new(0.0, 0.0, table_z));
        b.tessellated_box(
            Vec3::new(-6.0, 0.72, -0.8),
            Vec3::new(6.0, 0.77, 0.8),
            16,
            false,
            wood,
        );
        for x in [-5.7f32, -1.9, 1.9, 5.7] {
            for z in [-0.6f32, 0.6] {
                b.cylinder(Vec3::new(x, 0.0, z), 0.05, 0.05, 0.72, 16, 4, true, metal);
            }
        }
        for i in 0..7 {
            let x = -5.1 + 1.7 * i as f32;
            for (side, angle) in [(-1.0f32, PI), (1.0, 0.0)] {
                b.transform = Affine3A::from_translation(Vec3::new(x, 0.0, table_z + side * 1.15))
                    * Affine3A::from_rotation_y(angle);
                conference_chair(&mut b, shell, metal, arm);
            }
        }
    }
    b.transform = Affine3A::IDENTITY;
    for x in [-10.0f32, -5.0, 0.0, 5.0, 10.0] {
        for z in [-3.0f32, 3.0] {
            b.tessellated_box(
                Vec3::new(x - 0.6, 3.9, z - 0.3),
                Vec3::new(x + 0.6, 3.98, z + 0.3),
                2,
                false,
                lamp,
            );
        }
    }

    let camera = Camera::new(
        Vec3::new(-8.5, 2.3, 5.2),
        Vec3::new(-1.0, 0.7, 0.0),
        Vec3::Y,
        60.0,
    );
    let mut scene = b.finish(camera);
    scene.lights = vec![Light::white(Vec3::new(-3.0, 3.6, 1.5))];
    scene
}

/// Segments around the beetle body, along it, and of the wheels (major, minor).
const BEETLE_AROUND: usize = 576;
const BEETLE_ALONG: usize = 560;
const WHEEL_MAJOR: usize = 128;
const WHEEL_MINOR: usize = 48;

/// The beetle: a smooth, closed, rounded car body (a superelliptic body of revolution with
/// a glazed cabin hump) on four torus wheels; 693,120 triangles, 3 materials.
pub fn beetle() -> Scene {
    let mut b = MeshBuilder::new();
    let paint = b.reflective("paint", [0.2, 0.55, 0.25], BEETLE_PAINT_REFLECTANCE);
    let tire = b.material("tire", [0.12, 0.12, 0.12]);
    let glass = b.material("window glass", [0.35, 0.45, 0.55]);
    let (length, width, height, ground) = (4.0f32, 1.6f32, 1.05f32, 0.42f32);
    let exponent = 2.0 / 2.6; // superellipse: boxier than an ellipse
    let signed_pow = |x: f32, p: f32| x.signum() * x.abs().powf(p);
    b.patch(
        BEETLE_AROUND,
        BEETLE_ALONG,
        true,
        true,
        true,
        paint,
        |u, t| {
            // Rings crowd toward the nose and tail, where the section radius changes fastest.
            let s = 0.5 - 0.5 * (PI * t).cos();
            let x = -0.5 * length * (PI * s).cos();
            let profile = (PI * s).sin().max(0.0);
            let hump = 1.0 + 0.45 * (-((s - 0.55) / 0.17).powi(2)).exp();
            let half_width = 0.5 * width * profile.powf(0.45);
            let half_height = 0.5 * height * profile.powf(0.5) * hump;
            let angle = TAU * u;
            let mut y = half_height * signed_pow(angle.sin(), exponent);
            let z = half_width * signed_pow(angle.cos(), exponent);
            if y < 0.0 {
                y *= 0.35; // a flat underbody
            }
            Vec3::new(x, ground + 0.2 + y, z)
        },
    );
    // The top of the cabin hump is glazed: a third material, so that shading the body
    // takes more than one pass where windows and paint meet. Chosen by grid position (the
    // body is the first patch: vertex 0 is the nose pole, then rows of BEETLE_AROUND), not
    // by coordinates, so the topology stays the same on every platform.
    let body_vertices = 2 + (BEETLE_ALONG - 1) * BEETLE_AROUND;
    for triangle in &mut b.triangles {
        let first = triangle.v.iter().min().copied().unwrap_or(0) as usize;
        if first == 0 || first >= body_vertices {
            continue;
        }
        let (row, column) = ((first - 1) / BEETLE_AROUND, (first - 1) % BEETLE_AROUND);
        let along = (BEETLE_ALONG * 45 / 100..BEETLE_ALONG * 62 / 100).contains(&row);
        let top = (BEETLE_AROUND / 10..BEETLE_AROUND * 4 / 10).contains(&column);
        if along && top {
            triangle.material = glass;
        }
    }
    for x in [-1.25f32, 1.3] {
        for z in [-0.72f32, 0.72] {
            b.transform = Affine3A::from_translation(Vec3::new(x, 0.33, z))
                * Affine3A::from_rotation_y(PI / 2.0);
            b.torus_x(Vec3::ZERO, 0.22, 0.11, WHEEL_MAJOR, WHEEL_MINOR, tire);
        }
    }
    let camera = Camera::new(
        Vec3::new(3.6, 2.1, 4.6),
        Vec3::new(0.0, 0.55, 0.0),
        Vec3::Y,
        42.0,
    );
    let mut scene = b.finish(camera);
    scene.lights = vec![Light::white(Vec3::new(2.5, 6.0, 3.0))];
    scene
}

/// The procedural scene called `name` (`room`, `conference` or `beetle`).
pub fn by_name(name: &str) -> Option<Scene> {
    built_in(name).map(|build| build())
}

/// Whether `name` is a built-in scene's (and not a file's), without building it.
pub fn is_built_in(name: &str) -> bool {
    built_in(name).is_some()
}

fn built_in(name: &str) -> Option<fn() -> Scene> {
    match name {
        "room" | "erw6" => Some(room),
        "conference" => Some(conference),
        "beetle" => Some(beetle),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// FNV-1a over vertex indices and materials: independent of floating-point libraries.
    fn topology_hash(scene: &Scene) -> u64 {
        let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
        for t in &scene.triangles {
            for word in [t.v[0], t.v[1], t.v[2], t.material] {
                for byte in word.to_le_bytes() {
                    hash = (hash ^ byte as u64).wrapping_mul(0x0000_0100_0000_01b3);
                }
            }
        }
        hash
    }

    #[test]
    fn room_is_erw6_sized_and_deterministic() {
        let a = room();
        let b = room();
        a.validate().unwrap();
        assert_eq!(a.triangle_count(), 792);
        assert_eq!(a.materials.len(), 9);
        assert_eq!(a.content_hash(), b.content_hash());
        let used: std::collections::BTreeSet<u32> =
            a.triangles.iter().map(|t| t.material).collect();
        assert_eq!(used.len(), 9);
        // Pinned: any change to the generator's topology must be deliberate.
        assert_eq!(topology_hash(&a), 0x3671_3ab6_ca4f_a418);
    }

    /// Each built-in scene mirrors on exactly its named surfaces, and the rest of each scene
    /// reflects nothing (so `--shade reflect` spawns rays only there).
    #[test]
    fn the_reflective_surfaces_are_the_named_ones() {
        for (scene, name, weight) in [
            (room(), "table", ROOM_TABLE_REFLECTANCE),
            (conference(), "table wood", CONFERENCE_TABLE_REFLECTANCE),
            (beetle(), "paint", BEETLE_PAINT_REFLECTANCE),
        ] {
            let reflective: Vec<(&str, f32)> = scene
                .materials
                .iter()
                .filter(|m| m.reflectance != 0.0)
                .map(|m| (m.name.as_str(), m.reflectance))
                .collect();
            assert_eq!(reflective, [(name, weight)]);
            assert!(scene
                .triangles
                .iter()
                .any(|t| scene.materials[t.material as usize].name == name));
        }
    }

    #[test]
    fn conference_is_large_and_deterministic() {
        let a = conference();
        a.validate().unwrap();
        assert_eq!(a.triangle_count(), 284_640);
        assert!(a.triangle_count() >= 250_000);
        assert_eq!(a.content_hash(), conference().content_hash());
        assert_eq!(topology_hash(&a), 0xc7a9_5a2f_1caf_846e);
        let bvh = crate::bvh::Bvh::build(&a, &Default::default());
        bvh.validate(&a).unwrap();
        assert!(bvh.sah_cost < 60.0, "SAH cost {}", bvh.sah_cost);
    }

    #[test]
    fn beetle_is_large_smooth_and_finely_tessellated() {
        let scene = beetle();
        scene.validate().unwrap();
        assert_eq!(scene.triangle_count(), 693_120);
        assert_eq!(scene.content_hash(), beetle().content_hash());
        assert_eq!(topology_hash(&scene), 0x6d6c_c6ac_f763_bb21);
        let glass = scene.triangles.iter().filter(|t| t.material == 2).count();
        assert!(
            (10_000..100_000).contains(&glass),
            "{glass} window triangles"
        );
        // No triangle's screen footprint reaches an 8x8 packet at 1024x1024.
        let (width, height) = (1024u32, 1024u32);
        let (forward, right, up) = scene.camera.frame();
        let ty = (scene.camera.fov_y_degrees.to_radians() * 0.5).tan();
        let tx = ty * width as f32 / height as f32;
        let project = |p: Vec3| {
            let q = p - scene.camera.eye;
            let z = q.dot(forward);
            let sx = (q.dot(right) / z / tx + 1.0) * 0.5 * width as f32;
            let sy = (1.0 - q.dot(up) / z / ty) * 0.5 * height as f32;
            Vec2::new(sx, sy)
        };
        let mut largest = 0.0f32;
        let mut on_screen = 0usize;
        for index in 0..scene.triangle_count() {
            let corners = scene.triangle_positions(index).map(project);
            let min = corners[0].min(corners[1]).min(corners[2]);
            let max = corners[0].max(corners[1]).max(corners[2]);
            assert!(
                min.x > 0.0 && min.y > 0.0 && max.x < width as f32 && max.y < height as f32,
                "beetle leaves the frame"
            );
            on_screen += 1;
            largest = largest.max((max - min).max_element());
        }
        assert_eq!(on_screen, scene.triangle_count());
        eprintln!("largest beetle triangle footprint: {largest} px");
        assert!(largest < 8.0, "largest triangle footprint {largest} px");
        // Smooth: normals of neighbouring body vertices differ little.
        let body = &scene.normals[BEETLE_AROUND * 100..BEETLE_AROUND * 100 + BEETLE_AROUND];
        for pair in body.windows(2) {
            assert!(pair[0].dot(pair[1]) > 0.9);
        }
    }
}
