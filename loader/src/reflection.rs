//! Reflection rays (`--shade reflect`, issue #34; the paper's section 7: "each 8x8 primary
//! packet generates one reflection packet (of up to 8x8 rays)"): the model the host
//! reference computes, its image with the hits of every bounce, and how full the
//! reflection packets are.
//!
//! # Model
//!
//! A hit (primary or reflected) on a material with reflectance `r > 0`, with bounces left,
//! casts one reflected ray; with `P` the hit point, `N` the eye-facing shading normal and
//! `d` the incoming direction ([`crate::shading`]):
//!
//! ```text
//! R = d - 2 (dot(d, N) / dot(N, N)) N          (shading::reflect_direction, |R| = |d|)
//! origin P + REFLECT_OFFSET R, direction R     nearest hit with 0 < t
//! colour = blend(own colour, reflected colour, r) = a + r (b - a) + 0.5 per 8-bit channel
//! ```
//!
//! Every hit's own colour is the shadows model (diffuse, interpolated normal, one shadow
//! ray per light); a reflected ray that hits nothing reflects black. Bounce `k`'s rays of
//! one 8x8 primary packet form one reflection packet, masked to the rays whose bounce
//! `k - 1` hit a reflective surface.

use glam::Vec3;

use crate::camera::Camera;
use crate::reference::{Hit, Reference, MISS_COLOUR};
use crate::shading::{self, Light};

/// One ray of a pixel's path: where it starts, where it goes, what it hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounce {
    pub origin: Vec3,
    pub dir: Vec3,
    pub hit: Hit,
}

/// The reflected ray of `bounce`: `None` unless it hits a reflective material.
pub fn reflected_ray(reference: &Reference, bounce: &Bounce) -> Option<(Vec3, Vec3)> {
    let surface = reference.surface(&bounce.hit, bounce.origin, bounce.dir)?;
    if reference.materials[surface.material as usize].reflectance <= 0.0 {
        return None;
    }
    let r = shading::reflect_direction(bounce.dir, surface.normal);
    Some((surface.point + r * shading::REFLECT_OFFSET, r))
}

/// A pixel's rays: its primary ray (with its hit `primary`), then each reflected ray while
/// the surface hit reflects, at most `depth` of them.
pub fn path(
    reference: &Reference,
    origin: Vec3,
    dir: Vec3,
    primary: Hit,
    depth: u32,
) -> Vec<Bounce> {
    let mut path = vec![Bounce {
        origin,
        dir,
        hit: primary,
    }];
    while path.len() <= depth as usize {
        let Some((origin, dir)) = reflected_ray(reference, &path[path.len() - 1]) else {
            break;
        };
        let hit = reference.trace(origin, dir);
        path.push(Bounce { origin, dir, hit });
    }
    path
}

/// The colour of a pixel's `path`: the last ray's own colour, blended into each earlier
/// one's by that one's reflectance.
pub fn shade_path(reference: &Reference, path: &[Bounce], lights: &[Light]) -> u32 {
    let own = |b: &Bounce| reference.shade(&b.hit, b.origin, b.dir, lights, true);
    let Some((last, earlier)) = path.split_last() else {
        return MISS_COLOUR;
    };
    earlier.iter().rev().fold(own(last), |reflected, b| {
        let material = reference.triangles[b.hit.record as usize].material;
        let r = reference.materials[material as usize].reflectance;
        shading::blend(own(b), reflected, r)
    })
}

/// The reference's `--shade reflect` frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ReflectFrame {
    /// Row-major `0xRRGGBBff` colours, top row first.
    pub colours: Vec<u32>,
    /// Per bounce (the first reflection first), per pixel: the reflected ray's hit, `None`
    /// where the pixel casts no ray of that bounce.
    pub bounces: Vec<Vec<Option<Hit>>>,
}

impl ReflectFrame {
    /// Every pixel's path from its primary hit (`primary`, [`Reference::render`]) with up to
    /// `depth` bounces, and its colour, computed on up to `threads` threads (the result does
    /// not depend on the count).
    #[allow(clippy::too_many_arguments)]
    pub fn render(
        reference: &Reference,
        primary: &[Hit],
        camera: &Camera,
        width: u32,
        height: u32,
        lights: &[Light],
        depth: u32,
        threads: usize,
    ) -> ReflectFrame {
        let basis = camera.basis(width, height);
        let pixels = primary.len();
        let mut paths: Vec<(u32, Vec<Option<Hit>>)> = vec![(MISS_COLOUR, Vec::new()); pixels];
        let chunk = pixels.div_ceil(threads.max(1)).max(1);
        std::thread::scope(|scope| {
            for (number, out) in paths.chunks_mut(chunk).enumerate() {
                let basis = &basis;
                scope.spawn(move || {
                    for (i, slot) in out.iter_mut().enumerate() {
                        let pixel = number * chunk + i;
                        let dir = basis.direction(pixel as u32 % width, pixel as u32 / width);
                        let path = path(reference, basis.origin, dir, primary[pixel], depth);
                        let hits = path[1..].iter().map(|b| Some(b.hit)).collect();
                        *slot = (shade_path(reference, &path, lights), hits);
                    }
                });
            }
        });
        let mut bounces = vec![vec![None; pixels]; depth as usize];
        for (pixel, (_, hits)) in paths.iter().enumerate() {
            for (bounce, hit) in hits.iter().enumerate() {
                bounces[bounce][pixel] = *hit;
            }
        }
        ReflectFrame {
            colours: paths.into_iter().map(|(c, _)| c).collect(),
            bounces,
        }
    }

    /// Per bounce, the reflection packets an SPU kernel of 8x8 packets would trace and how
    /// full they are.
    pub fn packets(&self, width: u32, height: u32) -> Vec<BouncePackets> {
        self.bounces
            .iter()
            .enumerate()
            .map(|(k, hits)| {
                let mut counts = BouncePackets {
                    bounce: k as u32 + 1,
                    ..BouncePackets::default()
                };
                for py in (0..height).step_by(8) {
                    for px in (0..width).step_by(8) {
                        let mut rays = 0;
                        for y in py..(py + 8).min(height) {
                            for x in px..(px + 8).min(width) {
                                if let Some(hit) = hits[(y * width + x) as usize] {
                                    rays += 1;
                                    counts.hits += u64::from(hit.is_hit());
                                }
                            }
                        }
                        counts.rays += rays;
                        counts.packets += u64::from(rays > 0);
                    }
                }
                counts
            })
            .collect()
    }
}

/// One bounce's reflection packets ([`ReflectFrame::packets`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BouncePackets {
    /// 1 for the first reflection.
    pub bounce: u32,
    /// Reflected rays cast.
    pub rays: u64,
    /// Of them, the rays that hit a triangle.
    pub hits: u64,
    /// 8x8 packets with at least one ray (a packet without any is not traced).
    pub packets: u64,
}

impl BouncePackets {
    /// The share of the traced packets' 64 rays that are active (their coherence).
    pub fn active_fraction(&self) -> f64 {
        if self.packets == 0 {
            0.0
        } else {
            self.rays as f64 / (64 * self.packets) as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{Bvh, BvhConfig};
    use crate::scene::{Material, Scene, Triangle};

    /// A mirror floor (reflectance 0.5) at y = 0 and a red wall at x = 2: a ray down onto
    /// the floor at 45 degrees bounces into the wall, and the pixel is half its own colour,
    /// half the wall's; a second mirror above (x < 0) makes the path as long as the depth
    /// allows.
    fn mirrors(ceiling_reflects: bool) -> Reference {
        let positions = vec![
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(-5.0, 0.0, 5.0),
            Vec3::new(2.0, -1.0, -5.0),
            Vec3::new(2.0, 0.9, -5.0),
            Vec3::new(2.0, 0.9, 5.0),
            Vec3::new(2.0, -1.0, 5.0),
            Vec3::new(-5.0, 1.0, -5.0),
            Vec3::new(0.0, 1.0, -5.0),
            Vec3::new(0.0, 1.0, 5.0),
            Vec3::new(-5.0, 1.0, 5.0),
        ];
        let triangles = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [8, 9, 10],
            [8, 10, 11],
        ]
        .iter()
        .enumerate()
        .map(|(i, &v)| Triangle {
            v,
            material: (i / 2) as u32,
        })
        .collect();
        let materials = vec![
            Material::reflective("mirror", [0.2, 0.2, 0.2], 0.5),
            Material::new("red", [1.0, 0.0, 0.0]),
            Material::reflective("ceiling", [0.0, 0.0, 1.0], f32::from(ceiling_reflects)),
        ];
        let scene = Scene::from_parts(positions, None, Vec::new(), triangles, materials);
        Reference::new(&scene, &Bvh::build(&scene, &BvhConfig::default()))
    }

    #[test]
    fn a_mirror_floor_blends_in_what_it_reflects() {
        let reference = mirrors(false);
        let light = [Light::white(Vec3::new(0.0, 0.5, 0.0))];
        let (o, d) = (Vec3::new(1.0, 0.5, 0.0), Vec3::new(1.0, -1.0, 0.0));
        let primary = reference.trace(o, d);
        let path = path(&reference, o, d, primary, 1);
        assert_eq!(path.len(), 2, "{path:?}");
        assert!((path[0].hit.t - 0.5).abs() < 1e-6);
        assert_eq!(path[1].dir, Vec3::new(1.0, 1.0, 0.0));
        let wall = path[1].hit;
        assert_eq!(
            reference.triangles[wall.record as usize].material, 1,
            "the wall"
        );
        let own = reference.shade(&primary, o, d, &light, true);
        let reflected = reference.shade(&wall, path[1].origin, path[1].dir, &light, true);
        assert_eq!(
            shade_path(&reference, &path, &light),
            shading::blend(own, reflected, 0.5)
        );
        // A reflection that misses reflects black; a path without reflection is its colour.
        let (o2, d2) = (Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.0, -1.0, 1.0));
        let p2 = path_of(&reference, o2, d2, 1);
        assert_eq!(p2.len(), 2);
        assert!(!p2[1].hit.is_hit());
        let own2 = reference.shade(&p2[0].hit, o2, d2, &light, true);
        assert_eq!(
            shade_path(&reference, &p2, &light),
            shading::blend(own2, MISS_COLOUR, 0.5)
        );
        let straight = path_of(&reference, o, Vec3::X, 4);
        assert_eq!(straight.len(), 1, "the wall reflects nothing");
        assert_eq!(
            shade_path(&reference, &straight, &light),
            reference.shade(&straight[0].hit, o, Vec3::X, &light, true)
        );
    }

    fn path_of(reference: &Reference, o: Vec3, d: Vec3, depth: u32) -> Vec<Bounce> {
        path(reference, o, d, reference.trace(o, d), depth)
    }

    #[test]
    fn two_mirrors_bounce_as_deep_as_allowed() {
        let reference = mirrors(true);
        let (o, d) = (Vec3::new(-4.0, 0.5, 0.0), Vec3::new(0.5, -0.5, 0.0));
        for depth in 1..=shading::MAX_REFLECT_DEPTH {
            let path = path_of(&reference, o, d, depth);
            assert_eq!(path.len(), depth as usize + 1, "depth {depth}");
            // floor, ceiling, floor, ...: the directions alternate in y
            for (k, b) in path.iter().enumerate() {
                assert_eq!(b.dir.y > 0.0, k % 2 == 1, "{k}");
            }
        }
    }

    /// In the room only the table reflects: the reflect frame is the shadows frame except
    /// on the table's pixels, each of which casts one first-bounce ray; the counts do not
    /// depend on the threads.
    #[test]
    fn the_room_reflects_on_its_table_only() {
        let scene = crate::procedural::room();
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let reference = Reference::new(&scene, &bvh);
        let (w, h) = (64, 48);
        let hits = reference.render(&scene.camera, w, h, 2);
        let lights = shading::default_lights(&scene);
        let shadows = reference.shade_image(&hits, &scene.camera, w, h, &lights, true, 2);
        let frame = ReflectFrame::render(&reference, &hits, &scene.camera, w, h, &lights, 2, 3);
        assert_eq!(
            frame,
            ReflectFrame::render(&reference, &hits, &scene.camera, w, h, &lights, 2, 1)
        );
        let table = |hit: &Hit| {
            hit.is_hit()
                && reference.materials[reference.triangles[hit.record as usize].material as usize]
                    .reflectance
                    > 0.0
        };
        let mut on_table = 0;
        for (i, hit) in hits.iter().enumerate() {
            assert_eq!(frame.bounces[0][i].is_some(), table(hit), "pixel {i}");
            if table(hit) {
                on_table += 1;
            } else {
                assert_eq!(frame.colours[i], shadows[i], "pixel {i}");
            }
        }
        assert!(on_table > 50, "{on_table} table pixels");
        let changed = (0..hits.len())
            .filter(|&i| frame.colours[i] != shadows[i])
            .count();
        assert!(changed > on_table / 2, "{changed} of {on_table} changed");
        let packets = frame.packets(w, h);
        assert_eq!(packets.len(), 2);
        assert_eq!(packets[0].bounce, 1);
        assert_eq!(packets[0].rays, on_table as u64);
        assert_eq!(packets[0].hits, packets[0].rays, "a closed room");
        assert!(packets[0].packets > 0 && packets[0].packets <= 48);
        let f = packets[0].active_fraction();
        assert!(f > 0.0 && f <= 1.0, "{f}");
    }
}
