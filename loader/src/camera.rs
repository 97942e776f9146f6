//! The pinhole camera and the one primary-ray convention shared by the host reference and
//! the SPU kernels, so that their per-pixel results can be compared hit for hit.
//!
//! # Convention
//!
//! Pixel `(x, y)` of a `width x height` image has `y = 0` at the **top** row. With
//!
//! - `forward = normalize(target - eye)`
//! - `right = normalize(cross(forward, up))`
//! - `up_ortho = cross(right, forward)` (unit length, orthogonal to both)
//! - `ty = tan(fov_y / 2)`, `tx = ty * width / height`
//!
//! the primary ray of pixel `(x, y)` goes through the pixel **center**:
//!
//! ```text
//! d(x, y) = forward + (2 (x + 0.5) / width - 1) * tx * right
//!                   + (1 - 2 (y + 0.5) / height) * ty * up_ortho
//! ```
//!
//! `d` is deliberately **not normalized**: kernels generate it incrementally as
//! `d = dir00 + x * du + y * dv` from a [`CameraBasis`] (one multiply-add per pixel
//! coordinate and component), and every hit distance `t` — in the kernels and in the host
//! reference — is measured in units of this unnormalized `d`, i.e. the hit point is
//! `eye + t * d`. Since `forward` has unit length, `|d| >= 1`, and `t * |d|` is the
//! Euclidean distance. The host evaluates `d` in f32 exactly as
//! `(dir00 + du * x) + dv * y` per component; a kernel using fused multiply-adds may
//! differ in the last bits, which comparisons of `t` must tolerate (1e-4 relative is ample).

use glam::Vec3;

/// A pinhole camera; `fov_y_degrees` is the full vertical field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y_degrees: f32,
}

/// The per-image ray generator: ray `(x, y)` is `origin + t * (dir00 + x * du + y * dv)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraBasis {
    pub origin: Vec3,
    /// Unnormalized direction through the center of the top-left pixel `(0, 0)`.
    pub dir00: Vec3,
    /// Direction step for `x + 1` (one pixel to the right).
    pub du: Vec3,
    /// Direction step for `y + 1` (one pixel down).
    pub dv: Vec3,
}

impl Camera {
    pub fn new(eye: Vec3, target: Vec3, up: Vec3, fov_y_degrees: f32) -> Self {
        Camera {
            eye,
            target,
            up,
            fov_y_degrees,
        }
    }

    /// Parses the CLI form `"ex,ey,ez,tx,ty,tz,ux,uy,uz,fov"` (ten numbers, spaces allowed).
    pub fn parse(text: &str) -> Result<Camera, String> {
        let values = text
            .split(',')
            .map(|field| {
                field
                    .trim()
                    .parse::<f32>()
                    .map_err(|_| format!("camera: '{}' is not a number", field.trim()))
            })
            .collect::<Result<Vec<f32>, String>>()?;
        if values.len() != 10 {
            return Err(format!(
                "camera: expected 10 comma-separated numbers eye(3),target(3),up(3),fov, got {}",
                values.len()
            ));
        }
        let camera = Camera {
            eye: Vec3::new(values[0], values[1], values[2]),
            target: Vec3::new(values[3], values[4], values[5]),
            up: Vec3::new(values[6], values[7], values[8]),
            fov_y_degrees: values[9],
        };
        camera.validate()?;
        Ok(camera)
    }

    /// Rejects cameras whose basis would be degenerate or non-finite.
    pub fn validate(&self) -> Result<(), String> {
        let finite = self.eye.is_finite()
            && self.target.is_finite()
            && self.up.is_finite()
            && self.fov_y_degrees.is_finite();
        if !finite {
            return Err("camera: non-finite value".into());
        }
        let largest = self.eye.abs().max(self.target.abs()).max_element();
        if largest > crate::scene::MAX_COORDINATE {
            return Err(format!(
                "camera: coordinate {largest:e} exceeds the largest the kernel handles ({:e})",
                crate::scene::MAX_COORDINATE
            ));
        }
        let forward = self.target - self.eye;
        if forward.length_squared() == 0.0 {
            return Err("camera: eye and target coincide".into());
        }
        if forward.normalize().cross(self.up).length_squared() < 1e-12 {
            return Err("camera: up is parallel to the view direction (or zero)".into());
        }
        if !(self.fov_y_degrees > 0.0 && self.fov_y_degrees < 180.0) {
            return Err(format!(
                "camera: fov {} not in (0, 180) degrees",
                self.fov_y_degrees
            ));
        }
        Ok(())
    }

    /// The CLI form accepted by [`Camera::parse`].
    pub fn to_cli_string(&self) -> String {
        let v = [
            self.eye.x,
            self.eye.y,
            self.eye.z,
            self.target.x,
            self.target.y,
            self.target.z,
            self.up.x,
            self.up.y,
            self.up.z,
            self.fov_y_degrees,
        ];
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Orthonormal `(forward, right, up_ortho)` as defined in the module docs.
    pub fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.eye).normalize();
        let right = forward.cross(self.up).normalize();
        let up_ortho = right.cross(forward);
        (forward, right, up_ortho)
    }

    /// The incremental ray generator for a `width x height` image.
    pub fn basis(&self, width: u32, height: u32) -> CameraBasis {
        let (forward, right, up_ortho) = self.frame();
        let ty = (self.fov_y_degrees.to_radians() * 0.5).tan();
        let tx = ty * width as f32 / height as f32;
        let sx = 2.0 * tx / width as f32;
        let sy = 2.0 * ty / height as f32;
        CameraBasis {
            origin: self.eye,
            dir00: forward + (0.5 * sx - tx) * right + (ty - 0.5 * sy) * up_ortho,
            du: sx * right,
            dv: -sy * up_ortho,
        }
    }

    /// Origin and **unnormalized** direction of pixel `(px, py)`'s primary ray; see the
    /// module docs for the convention and why `t` is measured along this `d`.
    pub fn primary_ray(&self, px: u32, py: u32, width: u32, height: u32) -> (Vec3, Vec3) {
        let basis = self.basis(width, height);
        (basis.origin, basis.direction(px, py))
    }

    /// A camera looking at the box `[min, max]` from the front (+z), a little from above and
    /// to the side, far enough back to see all of it.
    pub fn framing(min: Vec3, max: Vec3) -> Camera {
        let center = (min + max) * 0.5;
        let radius = ((max - min).length() * 0.5).max(1e-6);
        let fov = 45.0f32;
        let distance = radius / (fov.to_radians() * 0.5).sin();
        let view_from = Vec3::new(0.35, 0.3, 1.0).normalize();
        Camera::new(center + view_from * distance, center, Vec3::Y, fov)
    }
}

impl CameraBasis {
    /// `(dir00 + du * x) + dv * y`, evaluated in exactly this order in f32.
    pub fn direction(&self, px: u32, py: u32) -> Vec3 {
        let x = px as f32;
        let y = py as f32;
        Vec3::new(
            (self.dir00.x + self.du.x * x) + self.dv.x * y,
            (self.dir00.y + self.du.y * x) + self.dv.y * y,
            (self.dir00.z + self.du.z * x) + self.dv.z * y,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_round_trips_and_rejects_bad_input() {
        let camera = Camera::parse("0,1,5, 0,1,0, 0,1,0, 60").unwrap();
        assert_eq!(camera.eye, Vec3::new(0.0, 1.0, 5.0));
        assert_eq!(camera.fov_y_degrees, 60.0);
        assert_eq!(Camera::parse(&camera.to_cli_string()).unwrap(), camera);
        assert!(Camera::parse("1,2,3").is_err());
        assert!(Camera::parse("0,0,0,0,0,0,0,1,0,60").is_err());
        assert!(Camera::parse("0,0,1,0,0,0,0,0,1,60").is_err());
        assert!(Camera::parse("0,0,1,0,0,0,0,1,0,x").is_err());
        assert_eq!(
            Camera::parse("0,0,1,0,0,0,0,1,0,inf").unwrap_err(),
            "camera: non-finite value"
        );
        assert_eq!(
            Camera::parse("0,0,1e30,0,0,0,0,1,0,60").unwrap_err(),
            "camera: coordinate 1e30 exceeds the largest the kernel handles (1e18)"
        );
        assert_eq!(
            Camera::parse("0,0,1,0,0,0,0,1,0,180").unwrap_err(),
            "camera: fov 180 not in (0, 180) degrees"
        );
    }

    #[test]
    fn basis_matches_the_documented_formula() {
        let camera = Camera::new(
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-2.0, 0.5, -1.0),
            Vec3::Y,
            50.0,
        );
        let (w, h) = (64u32, 48u32);
        let (forward, right, up) = camera.frame();
        let ty = (50.0f32.to_radians() / 2.0).tan();
        let tx = ty * w as f32 / h as f32;
        for &(x, y) in &[(0u32, 0u32), (63, 0), (0, 47), (31, 20), (63, 47)] {
            let expected = forward
                + (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tx * right
                + (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * ty * up;
            let (origin, dir) = camera.primary_ray(x, y, w, h);
            assert_eq!(origin, camera.eye);
            assert!(
                (dir - expected).length() < 1e-5,
                "{x},{y}: {dir} vs {expected}"
            );
        }
        // Top row looks up, left column looks left.
        let (_, d00) = camera.primary_ray(0, 0, w, h);
        assert!(d00.dot(up) > 0.0 && d00.dot(right) < 0.0);
    }
}
