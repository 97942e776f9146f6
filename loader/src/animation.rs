//! Moving scenes (issue #34 part 2): a sequence of frames that share one topology (the
//! same vertices and triangles, only the positions move), so that the BVH is built once and
//! refitted each frame ([`crate::refit`]).
//!
//! Two sources:
//! - built-in animations, pure functions of the frame number: `room-flag` (the room with a
//!   flag waving over the table: a small non-rigid motion, for tests) and `beetle-drive`
//!   (the 693k-triangle beetle swerving while its wheels turn: the refit benchmark);
//! - OBJ/PLY keyframe sequences named by a printf-style pattern, `walk_%03d.obj` (`%d` or
//!   `%0Nd`, frames numbered from 0), every keyframe checked against the first: vertex and
//!   face counts (naming the file and the line where they part), the triangles' vertices
//!   and materials, finite positions.
//!
//! The camera and the lights are frame 0's for every frame, so the view holds still while
//! the scene moves.

use std::f32::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec3};

use crate::procedural;
use crate::scene::{Material, Scene, Triangle};

/// The most frames an animation may have (`--frames`): ten minutes at 30 frames per second,
/// far beyond what a simulated frame rate renders in a session, small enough that a mistyped
/// count is refused rather than run for days.
pub const MAX_FRAMES: u32 = 18_000;

/// The built-in animations' names.
pub const BUILT_IN: [&str; 2] = ["room-flag", "beetle-drive"];

/// Whether `name` is a built-in animation's.
pub fn is_built_in(name: &str) -> bool {
    BUILT_IN.contains(&name)
}

/// Whether `scene` names a keyframe sequence (a pattern with a `%d` or `%0Nd`).
pub fn is_pattern(scene: &str) -> bool {
    parse_pattern(scene).is_some()
}

/// `(text before, zero-padded width, text after)` of a `%d`/`%0Nd` pattern.
fn parse_pattern(pattern: &str) -> Option<(&str, usize, &str)> {
    let at = pattern.find('%')?;
    let rest = &pattern[at + 1..];
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    if rest.as_bytes().get(digits) != Some(&b'd') {
        return None;
    }
    let width = match &rest[..digits] {
        "" => 0,
        w if w.starts_with('0') => w.parse().ok().filter(|&w: &usize| w <= 9)?,
        _ => return None,
    };
    let after = &rest[digits + 1..];
    (!after.contains('%')).then_some((&pattern[..at], width, after))
}

/// The file of keyframe `frame` of `pattern`.
pub fn keyframe_path(pattern: &str, frame: u32) -> Option<PathBuf> {
    let (before, width, after) = parse_pattern(pattern)?;
    Some(PathBuf::from(format!("{before}{frame:0width$}{after}")))
}

/// Checks a frame count before any work.
pub fn check_frames(frames: u32) -> Result<(), String> {
    if frames == 0 || frames > MAX_FRAMES {
        return Err(format!(
            "--frames {frames}: an animation has 1 to {MAX_FRAMES} frames"
        ));
    }
    Ok(())
}

/// Where a frame's positions come from.
enum Source {
    /// The room with a waving flag: the flag's grid starts at this vertex.
    RoomFlag { first_flag_vertex: usize },
    /// The beetle's rest positions, and which of them are a wheel's (a tire triangle's).
    BeetleDrive { rest: Vec<Vec3>, wheel: Vec<bool> },
    /// Keyframe files of a pattern.
    Keyframes { pattern: String },
}

/// An animated scene: frame 0 (topology, materials, camera and lights for every frame) and
/// how to make any other.
pub struct Animation {
    /// What the statistics and the frames' configuration call it.
    pub name: String,
    pub frames: u32,
    first: Scene,
    source: Source,
}

/// Flag grid: columns and rows of quads.
const FLAG_COLUMNS: usize = 24;
const FLAG_ROWS: usize = 14;

/// The flag's vertex at grid `(i, j)` in frame `frame`: hung from a bar along x, rippling in
/// z with a wave running away from the bar (period 24 frames), sagging as it ripples.
fn flag_point(i: usize, j: usize, frame: u32) -> Vec3 {
    let u = i as f32 / FLAG_COLUMNS as f32;
    let v = j as f32 / FLAG_ROWS as f32;
    let phase = TAU * (1.5 * u - frame as f32 / 24.0);
    let z = -1.2 + 0.22 * u * phase.sin();
    let y = 1.95 - 0.7 * v - 0.03 * u * (phase.cos() + 1.0);
    Vec3::new(-1.1 + 1.5 * u, y, z)
}

/// The room with the flag of frame 0 appended (its own material).
fn room_flag_scene() -> (Scene, usize) {
    let room = procedural::room();
    let first_flag_vertex = room.positions.len();
    let mut positions = room.positions.clone();
    let mut triangles = room.triangles.clone();
    let mut materials = room.materials.clone();
    let flag = materials.len() as u32;
    materials.push(Material::new("flag", [0.8, 0.1, 0.12]));
    for j in 0..=FLAG_ROWS {
        for i in 0..=FLAG_COLUMNS {
            positions.push(flag_point(i, j, 0));
        }
    }
    let at = |i: usize, j: usize| (first_flag_vertex + j * (FLAG_COLUMNS + 1) + i) as u32;
    for j in 0..FLAG_ROWS {
        for i in 0..FLAG_COLUMNS {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.push(Triangle {
                v: [a, b, c],
                material: flag,
            });
            triangles.push(Triangle {
                v: [a, c, d],
                material: flag,
            });
        }
    }
    let mut scene = Scene::from_parts(positions, None, Vec::new(), triangles, materials);
    scene.camera = room.camera;
    scene.lights = room.lights;
    (scene, first_flag_vertex)
}

/// The beetle's pose in `frame`: the body swerves (a slow sine in heading and sideways
/// offset, period 60 frames) and the wheels turn with the distance driven.
fn beetle_pose(frame: u32) -> (Affine3A, f32) {
    let t = frame as f32 / 60.0;
    let heading = 0.35 * (TAU * t).sin();
    let forward = 0.5 * (TAU * t).sin();
    let side = 0.25 * (PI * t).sin();
    let body = Affine3A::from_translation(Vec3::new(forward, 0.0, side))
        * Affine3A::from_rotation_y(heading);
    // distance along the path over the wheel radius (0.33 m)
    let spin = -(forward + TAU * t * 0.6) / 0.33;
    (body, spin)
}

impl Animation {
    /// The animation `scene` with `frames` frames: a built-in's name or a keyframe pattern.
    /// Checks the frame count and loads (and checks) keyframe 0; a later keyframe is loaded
    /// and checked when its frame comes ([`Animation::frame`]).
    pub fn open(scene: &str, frames: u32) -> Result<Animation, String> {
        check_frames(frames)?;
        let (first, source) = match scene {
            "room-flag" => {
                let (scene, first_flag_vertex) = room_flag_scene();
                (scene, Source::RoomFlag { first_flag_vertex })
            }
            "beetle-drive" => {
                let beetle = procedural::beetle();
                let mut wheel = vec![false; beetle.positions.len()];
                for t in &beetle.triangles {
                    if beetle.materials[t.material as usize].name == "tire" {
                        for v in t.v {
                            wheel[v as usize] = true;
                        }
                    }
                }
                let rest = beetle.positions.clone();
                let mut animation = Animation {
                    name: scene.to_string(),
                    frames,
                    first: beetle,
                    source: Source::BeetleDrive { rest, wheel },
                };
                animation.first = animation.frame(0)?;
                return Ok(animation);
            }
            pattern if is_pattern(pattern) => {
                let path = keyframe_path(pattern, 0).expect("a pattern");
                let first = Scene::load(&path).map_err(|e| e.to_string())?;
                (
                    first,
                    Source::Keyframes {
                        pattern: pattern.to_string(),
                    },
                )
            }
            other => {
                return Err(format!(
                    "{other:?} is not an animation: a built-in one ({}) or a keyframe \
                     pattern such as walk_%03d.obj",
                    BUILT_IN.join(", ")
                ))
            }
        };
        Ok(Animation {
            name: scene.to_string(),
            frames,
            first,
            source,
        })
    }

    /// Frame 0.
    pub fn first(&self) -> &Scene {
        &self.first
    }

    /// Frame `frame` (< [`Animation::frames`]): frame 0's topology, materials, camera and
    /// lights with this frame's positions and their smooth normals (a keyframe's own normals
    /// where its file has them).
    pub fn frame(&self, frame: u32) -> Result<Scene, String> {
        if frame >= self.frames {
            return Err(format!(
                "frame {frame} of an animation of {} frames",
                self.frames
            ));
        }
        let mut scene = self.first.clone();
        match &self.source {
            Source::RoomFlag { first_flag_vertex } => {
                for j in 0..=FLAG_ROWS {
                    for i in 0..=FLAG_COLUMNS {
                        scene.positions[first_flag_vertex + j * (FLAG_COLUMNS + 1) + i] =
                            flag_point(i, j, frame);
                    }
                }
                scene.compute_smooth_normals();
            }
            Source::BeetleDrive { rest, wheel } => {
                let (body, spin) = beetle_pose(frame);
                let turn = |hub: Vec3| {
                    Affine3A::from_translation(hub)
                        * Affine3A::from_rotation_z(spin)
                        * Affine3A::from_translation(-hub)
                };
                // the wheels' hubs (procedural::beetle): front and back, left and right
                let x = |p: Vec3| if p.x < 0.0 { -1.25 } else { 1.3 };
                let z = |p: Vec3| if p.z < 0.0 { -0.72 } else { 0.72 };
                for ((out, &p), &on_wheel) in scene.positions.iter_mut().zip(rest).zip(wheel) {
                    let local = if on_wheel {
                        turn(Vec3::new(x(p), 0.33, z(p))).transform_point3(p)
                    } else {
                        p
                    };
                    *out = body.transform_point3(local);
                }
                scene.compute_smooth_normals();
            }
            Source::Keyframes { pattern } => {
                if frame > 0 {
                    let path = keyframe_path(pattern, frame).expect("a pattern");
                    let key = Scene::load(&path).map_err(|e| e.to_string())?;
                    check_same_topology(&path, &self.first, &key)?;
                    scene.positions = key.positions;
                    scene.normals = key.normals;
                }
            }
        }
        scene.check_loaded()?;
        Ok(scene)
    }
}

/// Refuses keyframe `key` (read from `path`) unless it has `first`'s vertices and triangles.
/// A count that differs names the line of the first vertex or face past frame 0's count, or
/// the file's last line where it has fewer.
fn check_same_topology(path: &Path, first: &Scene, key: &Scene) -> Result<(), String> {
    let counts = [
        ("vertices", "v", first.positions.len(), key.positions.len()),
        ("triangles", "f", first.triangles.len(), key.triangles.len()),
    ];
    for (what, keyword, want, have) in counts {
        if want != have {
            let line = crate::scene::read_maybe_gzipped(path)
                .ok()
                .map(|bytes| statement_line(&bytes, keyword, want))
                .map(|line| format!(":{line}"))
                .unwrap_or_default();
            return Err(format!(
                "{}{line}: keyframe has {have} {what}, frame 0 has {want} (a keyframe sequence \
                 keeps its topology)",
                path.display()
            ));
        }
    }
    if let Some(t) = (0..first.triangles.len()).find(|&t| first.triangles[t] != key.triangles[t]) {
        return Err(format!(
            "{}: triangle {t} has vertices {:?} (material {}), frame 0's has {:?} (material {})",
            path.display(),
            key.triangles[t].v,
            key.triangles[t].material,
            first.triangles[t].v,
            first.triangles[t].material
        ));
    }
    Ok(())
}

/// The 1-based line of statement number `count + 1` with `keyword` in an OBJ text (the
/// first past frame 0's count), or the last line where there are not that many.
fn statement_line(bytes: &[u8], keyword: &str, count: usize) -> usize {
    let mut seen = 0;
    let mut lines = 0;
    for (number, line) in bytes.split(|&b| b == b'\n').enumerate() {
        lines = number + 1;
        let first = line
            .split(u8::is_ascii_whitespace)
            .find(|w| !w.is_empty())
            .unwrap_or_default();
        if first == keyword.as_bytes() {
            seen += 1;
            if seen > count {
                return number + 1;
            }
        }
    }
    if bytes.ends_with(b"\n") {
        lines.saturating_sub(1).max(1)
    } else {
        lines.max(1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_number_frames_from_zero() {
        assert_eq!(
            keyframe_path("walk_%03d.obj", 7),
            Some(PathBuf::from("walk_007.obj"))
        );
        assert_eq!(
            keyframe_path("a%db.ply", 12),
            Some(PathBuf::from("a12b.ply"))
        );
        assert!(!is_pattern("walk.obj"));
        assert!(!is_pattern("walk_%3d.obj"));
        assert!(!is_pattern("walk_%03d_%d.obj"));
        assert!(!is_pattern("walk_%s.obj"));
    }

    #[test]
    fn frame_counts_outside_the_limit_are_refused() {
        assert!(check_frames(0).unwrap_err().contains("1 to 18000"));
        assert!(check_frames(1_000_000_000).is_err());
        assert!(check_frames(1).is_ok() && check_frames(MAX_FRAMES).is_ok());
    }

    #[test]
    fn the_flag_moves_and_the_room_does_not() {
        let animation = Animation::open("room-flag", 30).unwrap();
        let (a, b) = (animation.frame(0).unwrap(), animation.frame(5).unwrap());
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(a.camera, b.camera);
        let room = procedural::room().positions.len();
        assert_eq!(a.positions[..room], b.positions[..room]);
        let moved = (room..a.positions.len())
            .filter(|&v| a.positions[v] != b.positions[v])
            .count();
        assert!(moved > (a.positions.len() - room) / 2, "{moved}");
        // the same frame twice is the same scene
        assert_eq!(animation.frame(5).unwrap(), b);
        assert!(animation.frame(30).is_err());
    }

    #[test]
    fn the_beetle_moves_rigidly_and_its_wheels_turn_about_their_hubs() {
        let animation = Animation::open("beetle-drive", 60).unwrap();
        let (a, b) = (animation.frame(0).unwrap(), animation.frame(7).unwrap());
        assert_eq!(a.triangles, b.triangles);
        assert_eq!(
            a.positions,
            procedural::beetle().positions,
            "frame 0 is at rest"
        );
        let Source::BeetleDrive { wheel, .. } = &animation.source else {
            panic!("a beetle")
        };
        let body: Vec<usize> = (0..wheel.len()).filter(|&v| !wheel[v]).collect();
        let wheels: Vec<usize> = (0..wheel.len()).filter(|&v| wheel[v]).collect();
        assert_eq!(wheels.len(), 4 * 128 * 48, "four tori");
        let distance = |s: &Scene, p: usize, q: usize| s.positions[p].distance(s.positions[q]);
        // the body keeps its shape (to f32 rounding) while it moves
        let (p, q) = (body[0], body[body.len() / 2]);
        assert!((distance(&a, p, q) - distance(&b, p, q)).abs() < 1e-4);
        assert!(a.positions[p].distance(b.positions[p]) > 0.01);
        // two vertices of one wheel keep their distance, but turn relative to the body
        let (w, x) = (wheels[0], wheels[100]);
        assert!((distance(&a, w, x) - distance(&b, w, x)).abs() < 1e-4);
        let relative = |s: &Scene| s.positions[w] - s.positions[p];
        assert!((relative(&a).length() - relative(&b).length()).abs() > 1e-3);
    }

    #[test]
    fn statement_lines_point_past_the_first_frames_count() {
        let text = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\n";
        assert_eq!(statement_line(text, "v", 3), 4);
        assert_eq!(statement_line(text, "f", 1), 5);
        assert_eq!(statement_line(text, "f", 2), 5);
    }
}
