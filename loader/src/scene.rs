//! The in-memory triangle scene every other module works from, whatever its source (OBJ,
//! PLY, gzip'd or not, or procedural), and the file-level loading entry point.
//!
//! Invariants of a [`Scene`] (checked by [`Scene::validate`]):
//! - `normals.len() == positions.len()`: one unit normal per vertex, taken from the file
//!   where it has them, else the area-weighted average of the adjacent faces' normals
//!   ([`Scene::compute_smooth_normals`]);
//! - `texcoords` is empty or has one entry per vertex;
//! - every triangle's vertex indices are `< positions.len()` and its material is
//!   `< materials.len()` (there is always at least one material).

use std::io::Read;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::camera::Camera;
use crate::error::LoadError;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Triangle {
    /// Indices into the scene's per-vertex arrays.
    pub v: [u32; 3],
    /// Index into the scene's materials.
    pub material: u32,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    pub diffuse: [f32; 3],
    pub specular: [f32; 3],
    /// Phong exponent (`Ns` in MTL files).
    pub shininess: f32,
    /// Mirror weight in [0, 1] (MTL `illum 3` with `Km`, else `Ks`'s largest channel; 0:
    /// not reflective): `--shade reflect` blends the reflected colour in by it
    /// ([`crate::shading`]).
    pub reflectance: f32,
}

impl Material {
    pub fn new(name: impl Into<String>, diffuse: [f32; 3]) -> Self {
        Material {
            name: name.into(),
            diffuse,
            specular: [0.0; 3],
            shininess: 0.0,
            reflectance: 0.0,
        }
    }

    /// [`Material::new`] with a mirror weight (`reflectance` in [0, 1]).
    pub fn reflective(name: impl Into<String>, diffuse: [f32; 3], reflectance: f32) -> Self {
        Material {
            reflectance,
            ..Material::new(name, diffuse)
        }
    }

    /// The color used when a file names a material but does not define it: a deterministic
    /// function of the name, so that different groups stay distinguishable in images.
    pub fn default_for_name(name: &str) -> Self {
        let mut hash: u32 = 0x811c_9dc5;
        for byte in name.bytes() {
            hash = (hash ^ byte as u32).wrapping_mul(0x0100_0193);
        }
        let channel = |shift: u32| 0.35 + 0.55 * (((hash >> shift) & 0xff) as f32 / 255.0);
        Material::new(name, [channel(0), channel(8), channel(16)])
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::new("default", [0.8, 0.8, 0.8])
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub texcoords: Vec<Vec2>,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub camera: Camera,
    /// The scene's own point lights (the procedural scenes place theirs); empty means
    /// [`crate::shading::default_lights`] derives one from the camera.
    pub lights: Vec<crate::shading::Light>,
}

impl Scene {
    /// Loads an OBJ or PLY file, gzip-compressed or not. The format is sniffed from the
    /// content (gzip magic `1f 8b`, then `ply` magic) and otherwise taken from the file
    /// extension with any `.gz` removed. The camera frames the scene's bounding box.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, LoadError> {
        let path = path.as_ref();
        let bytes = read_maybe_gzipped(path)?;
        let stem_extension = {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            let name = name.strip_suffix(".gz").unwrap_or(&name).to_string();
            Path::new(&name)
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default()
        };
        let scene = if bytes.starts_with(b"ply") {
            crate::ply::parse_ply(path, &bytes)?
        } else if stem_extension == "obj" {
            crate::obj::parse_obj(path, &bytes)?
        } else if stem_extension == "ply" {
            return Err(LoadError::new(
                path,
                Some(1),
                "PLY file does not start with the 'ply' magic",
            ));
        } else {
            return Err(LoadError::new(
                path,
                None,
                "unknown scene format (expected .obj or .ply, optionally .gz)",
            ));
        };
        scene
            .check_loaded()
            .map_err(|e| LoadError::new(path, None, e))?;
        Ok(scene)
    }

    /// What every loaded scene must satisfy before it is rendered: the invariants, at least
    /// one triangle, and positions the kernel can compute with.
    pub fn check_loaded(&self) -> Result<(), String> {
        self.validate()?;
        if self.triangles.is_empty() {
            return Err("the scene has no triangles".into());
        }
        for (index, &p) in self.positions.iter().enumerate() {
            check_position(index, p)?;
        }
        Ok(())
    }

    /// Builds a scene from raw arrays, computing missing normals and a framing camera.
    pub fn from_parts(
        positions: Vec<Vec3>,
        normals: Option<Vec<Vec3>>,
        texcoords: Vec<Vec2>,
        triangles: Vec<Triangle>,
        mut materials: Vec<Material>,
    ) -> Scene {
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let mut scene = Scene {
            normals: Vec::new(),
            positions,
            texcoords,
            triangles,
            materials,
            camera: Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0),
            lights: Vec::new(),
        };
        match normals {
            Some(normals) if normals.len() == scene.positions.len() => scene.normals = normals,
            _ => scene.compute_smooth_normals(),
        }
        scene.camera = scene.framing_camera();
        scene
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Axis-aligned bounds of the vertices referenced by triangles (`(ZERO, ZERO)` if none).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut min = Vec3::splat(f32::INFINITY);
        let mut max = Vec3::splat(f32::NEG_INFINITY);
        for triangle in &self.triangles {
            for &index in &triangle.v {
                let p = self.positions[index as usize];
                min = min.min(p);
                max = max.max(p);
            }
        }
        if min.x > max.x {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (min, max)
        }
    }

    pub fn framing_camera(&self) -> Camera {
        let (min, max) = self.bounds();
        Camera::framing(min, max)
    }

    /// The three corner positions of triangle `index`.
    pub fn triangle_positions(&self, index: usize) -> [Vec3; 3] {
        let t = &self.triangles[index];
        [
            self.positions[t.v[0] as usize],
            self.positions[t.v[1] as usize],
            self.positions[t.v[2] as usize],
        ]
    }

    /// Replaces all normals by area-weighted averages of the adjacent faces' normals: the
    /// unnormalized cross product of a face is twice its area times its unit normal, so
    /// summing cross products weights by area. Vertices without any non-degenerate face get
    /// `+Z` so that every normal stays a unit vector.
    pub fn compute_smooth_normals(&mut self) {
        let mut all = vec![true; self.positions.len()];
        self.compute_smooth_normals_where(&mut all);
    }

    /// Like [`Scene::compute_smooth_normals`], but only for vertices whose flag is set
    /// (used when a file has normals for some vertices only).
    pub fn compute_smooth_normals_where(&mut self, needs_normal: &mut [bool]) {
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        for triangle in &self.triangles {
            let [a, b, c] = triangle.v.map(|i| i as usize);
            if !(needs_normal[a] || needs_normal[b] || needs_normal[c]) {
                continue;
            }
            let pa = self.positions[a];
            let face = (self.positions[b] - pa).cross(self.positions[c] - pa);
            sums[a] += face;
            sums[b] += face;
            sums[c] += face;
        }
        self.normals.resize(self.positions.len(), Vec3::Z);
        for (index, sum) in sums.into_iter().enumerate() {
            if needs_normal[index] {
                self.normals[index] = sum.try_normalize().unwrap_or(Vec3::Z);
            }
        }
    }

    /// `p -> p * scale + translate` for positions and the camera; normals are unchanged for
    /// positive `scale` (and flipped for negative, to keep them facing the same side).
    pub fn transform(&mut self, scale: f32, translate: Vec3) {
        for p in &mut self.positions {
            *p = *p * scale + translate;
        }
        if scale < 0.0 {
            for n in &mut self.normals {
                *n = -*n;
            }
        }
        self.camera.eye = self.camera.eye * scale + translate;
        self.camera.target = self.camera.target * scale + translate;
    }

    /// Scales and centers the scene so that its bounding box is centered at the origin and
    /// its longest side is 1. Returns the `(scale, translate)` applied.
    pub fn normalize_to_unit_box(&mut self) -> (f32, Vec3) {
        let (min, max) = self.bounds();
        let longest = (max - min).max_element();
        let scale = if longest > 0.0 { 1.0 / longest } else { 1.0 };
        let translate = -(min + max) * 0.5 * scale;
        self.transform(scale, translate);
        (scale, translate)
    }

    /// Checks the invariants listed in the module docs.
    pub fn validate(&self) -> Result<(), String> {
        if self.normals.len() != self.positions.len() {
            return Err(format!(
                "{} normals for {} positions",
                self.normals.len(),
                self.positions.len()
            ));
        }
        if !self.texcoords.is_empty() && self.texcoords.len() != self.positions.len() {
            return Err(format!(
                "{} texcoords for {} positions",
                self.texcoords.len(),
                self.positions.len()
            ));
        }
        if self.materials.is_empty() {
            return Err("no materials".into());
        }
        for (index, triangle) in self.triangles.iter().enumerate() {
            if triangle
                .v
                .iter()
                .any(|&v| v as usize >= self.positions.len())
            {
                return Err(format!(
                    "triangle {index} has a vertex index out of range: {:?}",
                    triangle.v
                ));
            }
            if triangle.material as usize >= self.materials.len() {
                return Err(format!(
                    "triangle {index} has material {} out of range",
                    triangle.material
                ));
            }
        }
        Ok(())
    }

    /// A 64-bit FNV-1a hash of the geometry (positions, normals, texcoords bit patterns,
    /// triangles, material colors) — for determinism checks.
    pub fn content_hash(&self) -> u64 {
        let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
        let mut feed = |word: u32| {
            for byte in word.to_le_bytes() {
                hash = (hash ^ byte as u64).wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for p in &self.positions {
            p.to_array().iter().for_each(|x| feed(x.to_bits()));
        }
        for n in &self.normals {
            n.to_array().iter().for_each(|x| feed(x.to_bits()));
        }
        for t in &self.texcoords {
            t.to_array().iter().for_each(|x| feed(x.to_bits()));
        }
        for t in &self.triangles {
            t.v.iter().for_each(|&v| feed(v));
            feed(t.material);
        }
        for m in &self.materials {
            m.diffuse
                .iter()
                .chain(m.specular.iter())
                .for_each(|x| feed(x.to_bits()));
        }
        hash
    }
}

/// The largest scene file, and the largest it may decompress to: 1 GiB, several times the
/// largest real scene (the 871k-triangle dragon is 60 MB of text), so that a file that
/// never ends or a gzip bomb fails with a message instead of exhausting memory.
pub const MAX_SCENE_BYTES: u64 = 1 << 30;

/// Reads a file, transparently decompressing it if it starts with the gzip magic; neither
/// the file nor its decompressed data may exceed [`MAX_SCENE_BYTES`].
pub fn read_maybe_gzipped(path: &Path) -> Result<Vec<u8>, LoadError> {
    read_maybe_gzipped_limited(path, MAX_SCENE_BYTES)
}

/// [`read_maybe_gzipped`] with another limit.
pub fn read_maybe_gzipped_limited(path: &Path, limit: u64) -> Result<Vec<u8>, LoadError> {
    let file = std::fs::File::open(path)
        .map_err(|e| LoadError::new(path, None, format!("cannot read: {e}")))?;
    let too_large = |what: &str| {
        LoadError::new(
            path,
            None,
            format!("{what} larger than the {limit}-byte limit for a scene"),
        )
    };
    let mut raw = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut raw)
        .map_err(|e| LoadError::new(path, None, format!("cannot read: {e}")))?;
    if raw.len() as u64 > limit {
        return Err(too_large("file"));
    }
    if raw.starts_with(&[0x1f, 0x8b]) {
        let mut out = Vec::new();
        flate2::read::MultiGzDecoder::new(&raw[..])
            .take(limit + 1)
            .read_to_end(&mut out)
            .map_err(|e| LoadError::new(path, None, format!("corrupt gzip data: {e}")))?;
        if out.len() as u64 > limit {
            return Err(too_large("decompressed data"));
        }
        Ok(out)
    } else {
        Ok(raw)
    }
}

/// The largest coordinate a scene may have: the kernel multiplies coordinates (edge cross
/// products, distances), and beyond this their products overflow single precision.
pub const MAX_COORDINATE: f32 = 1e18;

/// Refuses a vertex position that is not finite or exceeds [`MAX_COORDINATE`], which would
/// otherwise render as a silently black or wrong image.
pub fn check_position(index: usize, p: Vec3) -> Result<(), String> {
    if !p.is_finite() {
        return Err(format!(
            "vertex {index} is not finite ({}, {}, {})",
            p.x, p.y, p.z
        ));
    }
    if p.abs().max_element() > MAX_COORDINATE {
        return Err(format!(
            "vertex {index} ({}, {}, {}) exceeds the largest coordinate the kernel handles ({MAX_COORDINATE:e})",
            p.x, p.y, p.z
        ));
    }
    Ok(())
}

/// Where the shared test scenes live (`<repo>/../shared/scenes`), if present.
pub fn shared_scenes_dir() -> Option<std::path::PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes");
    dir.is_dir().then_some(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> Scene {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let triangles = vec![
            Triangle {
                v: [0, 1, 2],
                material: 0,
            },
            Triangle {
                v: [0, 2, 3],
                material: 0,
            },
        ];
        Scene::from_parts(positions, None, Vec::new(), triangles, Vec::new())
    }

    #[test]
    fn smooth_normals_are_area_weighted_unit_vectors() {
        let mut scene = quad();
        assert!(scene.validate().is_ok());
        assert!(scene.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
        // Fold the second triangle up: vertex 0 and 2 are shared, so they average.
        scene.positions[3] = Vec3::new(0.0, 0.0, 1.0);
        scene.compute_smooth_normals();
        assert!(scene
            .normals
            .iter()
            .all(|n| (n.length() - 1.0).abs() < 1e-6));
        assert!((scene.normals[1] - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn normalize_to_unit_box_centers_and_scales() {
        let mut scene = quad();
        scene.normalize_to_unit_box();
        let (min, max) = scene.bounds();
        assert!((max.x - min.x - 1.0).abs() < 1e-6);
        assert!(((min + max) * 0.5).length() < 1e-6);
        assert!(scene.camera.target.length() < 1e-6);
    }

    #[test]
    fn gzip_and_format_are_sniffed() {
        use std::io::Write;
        let dir = std::env::temp_dir().join(format!("spu-loader-gz-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let gzip = |text: &str| {
            let mut encoder =
                flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            encoder.write_all(text.as_bytes()).unwrap();
            encoder.finish().unwrap()
        };
        let obj = dir.join("tri.obj.gz");
        std::fs::write(&obj, gzip("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).unwrap();
        assert_eq!(Scene::load(&obj).unwrap().triangle_count(), 1);
        // PLY is recognized by its magic whatever the name says.
        let ply = dir.join("tri.data.gz");
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                    0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        std::fs::write(&ply, gzip(text)).unwrap();
        assert_eq!(Scene::load(&ply).unwrap().triangle_count(), 1);
        // Errors in compressed text files still name the file and line.
        std::fs::write(&ply, gzip(&text.replace("3 0 1 2", "3 0 1 3"))).unwrap();
        let err = Scene::load(&ply).unwrap_err();
        assert_eq!(
            (err.path.as_path(), err.line),
            (ply.as_path(), Some(13)),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn inputs_are_read_with_a_limit_gzip_bombs_included() {
        use std::io::Write;
        let dir = std::env::temp_dir().join(format!("spu-loader-limit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
        encoder.write_all(&vec![b' '; 100_000]).unwrap();
        let bomb = encoder.finish().unwrap();
        assert!(bomb.len() < 1000);
        let path = dir.join("bomb.obj.gz");
        std::fs::write(&path, &bomb).unwrap();
        let err = read_maybe_gzipped_limited(&path, 10_000).unwrap_err();
        assert_eq!(
            err.reason,
            "decompressed data larger than the 10000-byte limit for a scene"
        );
        assert_eq!(
            read_maybe_gzipped_limited(&path, 100_000).unwrap().len(),
            100_000
        );
        let err = read_maybe_gzipped_limited(&path, 100).unwrap_err();
        assert_eq!(
            err.reason,
            "file larger than the 100-byte limit for a scene"
        );
        // A device that never ends is cut off at the limit too.
        let err = read_maybe_gzipped_limited(Path::new("/dev/zero"), 4096).unwrap_err();
        assert!(err.reason.starts_with("file larger"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn a_loaded_scene_needs_triangles() {
        let dir = std::env::temp_dir().join(format!("spu-loader-empty-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("points.obj");
        std::fs::write(&path, "v 0 0 0\nv 1 0 0\n").unwrap();
        let err = Scene::load(&path).unwrap_err();
        assert_eq!(err.reason, "the scene has no triangles");
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn missing_and_unknown_files_fail_with_the_path() {
        let err = Scene::load("/nonexistent/dir/scene.obj").unwrap_err();
        assert!(
            err.to_string().contains("/nonexistent/dir/scene.obj"),
            "{err}"
        );
        let dir = std::env::temp_dir().join(format!("spu-loader-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.xyz");
        std::fs::write(&path, b"hello").unwrap();
        let err = Scene::load(&path).unwrap_err();
        assert!(err.reason.contains("unknown scene format"), "{err}");
        let gz = dir.join("broken.obj.gz");
        std::fs::write(&gz, [0x1f, 0x8b, 8, 0, 0, 0]).unwrap();
        let err = Scene::load(&gz).unwrap_err();
        assert!(err.reason.contains("gzip"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
