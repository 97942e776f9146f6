//! The shading model the SPU shading kernels and the host reference share (paper section
//! 7: diffuse shading with the interpolated vertex normal, point lights, shadows), the
//! point lights and the `--shade` modes.
//!
//! # Model
//!
//! For a primary hit at distance `t` along the (unnormalised) camera ray `o + t d` on a
//! triangle with vertex normals `n0, n1, n2`, barycentrics `beta` (of `v1`) and `gamma` (of
//! `v2`) from the projection test ([`crate::layout::TriangleRecord::intersect`]) and
//! diffuse colour `kd`:
//!
//! ```text
//! P  = o + t d
//! N  = n0 + beta (n1 - n0) + gamma (n2 - n0), negated if dot(N, d) > 0 (facing the eye)
//! per light (position Lp, colour Lc):
//!   L = Lp - P;  c = dot(N, L)
//!   lit if c > 0 (and, with shadows, the light is not occluded: no triangle hit by the
//!   shadow ray Lp + s (P - Lp) with 0 < s < 1 - SHADOW_EPSILON)
//!   E += Lc * c / sqrt(dot(N, N) * dot(L, L))
//! colour = kd * (AMBIENT + E), per channel clamped to [0, 1] and stored as
//! (c * 255 + 0.5) truncated; misses are black. The 32-bit pixel is 0xRRGGBBff.
//! ```
//!
//! Shadow rays start at the light, so that one 8x8 shadow packet per light shares a common
//! origin, like a primary packet, and runs through the same traversal; they are occlusion
//! (any-hit) queries. Without distance fall-off the light colour is the irradiance scale.

use glam::Vec3;

/// At most this many point lights (`--light` is repeatable up to this count).
pub const MAX_LIGHTS: usize = 8;
/// Ambient term added to the lights' diffuse irradiance.
pub const AMBIENT: f32 = 0.1;
/// Shadow rays stop this fraction short of the shaded point, so the point's own triangle
/// does not shadow it.
pub const SHADOW_EPSILON: f32 = 1.0 / 1024.0;
/// `--validate` accepts a colour channel differing by at most this many 8-bit levels: the
/// kernel computes the same model in single precision with the SPU's reciprocal-square-root
/// estimate and Newton step, and its own (fused) operation order.
pub const COLOUR_TOLERANCE: u8 = 2;

/// A point light: position and RGB colour (intensity per channel).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    pub position: Vec3,
    pub colour: Vec3,
}

impl Light {
    pub fn white(position: Vec3) -> Light {
        Light {
            position,
            colour: Vec3::ONE,
        }
    }

    /// Parses the CLI form `x,y,z[,r,g,b]` (colour white when omitted). Every value must be
    /// a finite number; colour channels must be non-negative.
    pub fn parse(text: &str) -> Result<Light, String> {
        let values = text
            .split(',')
            .map(|field| {
                let field = field.trim();
                match field.parse::<f32>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    Ok(_) => Err(format!("--light {text}: '{field}' is not finite")),
                    Err(_) => Err(format!("--light {text}: '{field}' is not a number")),
                }
            })
            .collect::<Result<Vec<f32>, String>>()?;
        let light = match values[..] {
            [x, y, z] => Light::white(Vec3::new(x, y, z)),
            [x, y, z, r, g, b] => Light {
                position: Vec3::new(x, y, z),
                colour: Vec3::new(r, g, b),
            },
            _ => {
                return Err(format!(
                    "--light {text}: expected x,y,z or x,y,z,r,g,b ({} numbers given)",
                    values.len()
                ))
            }
        };
        if light.colour.min_element() < 0.0 {
            return Err(format!("--light {text}: colour channels must be >= 0"));
        }
        Ok(light)
    }
}

/// Parses every `--light` value; more than [`MAX_LIGHTS`] is an error.
pub fn parse_lights(texts: &[String]) -> Result<Vec<Light>, String> {
    if texts.len() > MAX_LIGHTS {
        return Err(format!(
            "{} lights given: at most {MAX_LIGHTS} are supported",
            texts.len()
        ));
    }
    texts.iter().map(|t| Light::parse(t)).collect()
}

/// The lights a scene is rendered with when no `--light` is given: the scene's own (the
/// procedural scenes place theirs) or, for files, one white light above and to the right of
/// the camera, a fifth of the eye-target distance away, so that shadows fall visibly.
pub fn default_lights(scene: &crate::Scene) -> Vec<Light> {
    default_lights_seen_from(scene, &scene.camera)
}

/// [`default_lights`] for the scene seen from `camera` instead of its own.
pub fn default_lights_seen_from(scene: &crate::Scene, camera: &crate::Camera) -> Vec<Light> {
    if !scene.lights.is_empty() {
        return scene.lights.clone();
    }
    let forward = camera.target - camera.eye;
    let distance = forward.length();
    let right = forward.cross(camera.up).normalize_or_zero();
    let up = right.cross(forward).normalize_or_zero();
    vec![Light::white(
        camera.eye + (up * 0.2 + right * 0.1) * distance,
    )]
}

/// What `spu render` computes per pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShadeMode {
    /// Primary rays with the eye-light grey (the paper's "ray casting, no shading").
    None,
    /// Diffuse shading with the material colour and the interpolated normal.
    Simple,
    /// Simple shading plus one shadow ray per light.
    Shadows,
    /// Shadows plus reflections: a hit on a reflective material blends in the colour its
    /// reflected ray finds (up to `--reflect-depth` bounces, [`crate::reflection`]).
    Reflect,
}

impl ShadeMode {
    pub fn parse(text: &str) -> Result<ShadeMode, String> {
        match text {
            "none" => Ok(ShadeMode::None),
            "simple" => Ok(ShadeMode::Simple),
            "shadows" => Ok(ShadeMode::Shadows),
            "reflect" => Ok(ShadeMode::Reflect),
            _ => Err(format!(
                "--shade {text}: expected none, simple, shadows or reflect"
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ShadeMode::None => "none",
            ShadeMode::Simple => "simple",
            ShadeMode::Shadows => "shadows",
            ShadeMode::Reflect => "reflect",
        }
    }

    /// Whether the mode casts shadow rays (reflections are shaded with shadows too).
    pub fn shadows(self) -> bool {
        matches!(self, ShadeMode::Shadows | ShadeMode::Reflect)
    }
}

/// `--reflect-depth`: reflection bounces per primary ray, at most this many.
pub const MAX_REFLECT_DEPTH: u32 = 4;
/// A reflected ray starts this fraction of its direction off the surface it leaves, so
/// that the surface does not reflect itself.
pub const REFLECT_OFFSET: f32 = 1.0 / 1024.0;

/// Parses `--reflect-depth`: 1 to [`MAX_REFLECT_DEPTH`].
pub fn parse_reflect_depth(text: &str) -> Result<u32, String> {
    match text.parse::<u32>() {
        Ok(n) if (1..=MAX_REFLECT_DEPTH).contains(&n) => Ok(n),
        _ => Err(format!(
            "--reflect-depth {text}: expected a number of bounces from 1 to {MAX_REFLECT_DEPTH}"
        )),
    }
}

/// The mirror image of `dir` about the (eye-facing, unnormalised) shading normal:
/// `d - 2 (dot(d, N) / dot(N, N)) N`, as long as `d`; `d` itself for a zero normal.
pub fn reflect_direction(dir: Vec3, normal: Vec3) -> Vec3 {
    let nn = normal.dot(normal);
    if nn > 0.0 {
        let k = 2.0 * dir.dot(normal) / nn;
        dir - normal * k
    } else {
        dir
    }
}

/// The colour of a reflective hit: per 8-bit channel `a + r (b - a)` of its own colour `a`
/// and the reflected colour `b` (both `0xRRGGBBff`), plus 0.5, truncated. The blend works
/// on the 8-bit colours each bounce has already stored, as a kernel that shades a bounce
/// and then the next one blends them.
pub fn blend(local: u32, reflected: u32, reflectance: f32) -> u32 {
    let a = local.to_be_bytes();
    let b = reflected.to_be_bytes();
    let c = |i: usize| {
        let (a, b) = (a[i] as f32, b[i] as f32);
        (a + reflectance * (b - a) + 0.5).clamp(0.0, 255.0) as u8
    };
    u32::from_be_bytes([c(0), c(1), c(2), 0xff])
}

/// `on`/`off` for flags such as `--shadow-early`.
pub fn parse_on_off(option: &str, text: &str) -> Result<bool, String> {
    match text {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("{option} {text}: expected on or off")),
    }
}

/// The interpolated, eye-facing shading normal (not normalised) of the model.
pub fn shading_normal(normals: [Vec3; 3], beta: f32, gamma: f32, dir: Vec3) -> Vec3 {
    let [n0, n1, n2] = normals;
    let n = n0 + (n1 - n0) * beta + (n2 - n0) * gamma;
    if n.dot(dir) > 0.0 {
        -n
    } else {
        n
    }
}

/// The diffuse irradiance factor `dot(N, L) / (|N| |L|)` of one light, 0 when it faces away.
pub fn light_cosine(normal: Vec3, to_light: Vec3) -> f32 {
    let c = normal.dot(to_light);
    if c > 0.0 {
        let lengths = (normal.dot(normal) * to_light.dot(to_light)).sqrt();
        if lengths > 0.0 {
            (c / lengths).min(1.0)
        } else {
            0.0
        }
    } else {
        0.0
    }
}

/// `kd * (AMBIENT + irradiance)` as an opaque `0xRRGGBBff` pixel.
pub fn pixel_colour(diffuse: [f32; 3], irradiance: Vec3) -> u32 {
    let c = Vec3::from(diffuse) * (Vec3::splat(AMBIENT) + irradiance);
    let [r, g, b] = c.to_array().map(crate::reference::shade_to_u8);
    u32::from_be_bytes([r, g, b, 0xff])
}

/// Largest per-channel difference of two `0xRRGGBBAA` pixels.
pub fn channel_difference(a: u32, b: u32) -> u8 {
    a.to_be_bytes()
        .iter()
        .zip(b.to_be_bytes())
        .map(|(x, y)| x.abs_diff(y))
        .max()
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lights_parse_and_bad_ones_are_refused() {
        assert_eq!(
            Light::parse("1,2,3").unwrap(),
            Light::white(Vec3::new(1.0, 2.0, 3.0))
        );
        let l = Light::parse("1, -2, 3, 0.5, 1, 0").unwrap();
        assert_eq!(l.colour, Vec3::new(0.5, 1.0, 0.0));
        for bad in [
            "1,2",
            "1,2,3,4",
            "a,b,c",
            "1,2,inf",
            "nan,0,0",
            "0,0,0,1,-1,1",
            "",
        ] {
            assert!(Light::parse(bad).is_err(), "{bad}");
        }
        let nine: Vec<String> = (0..9).map(|i| format!("{i},0,0")).collect();
        assert!(parse_lights(&nine).unwrap_err().contains("at most 8"));
        assert_eq!(parse_lights(&nine[..8]).unwrap().len(), 8);
    }

    #[test]
    fn modes_and_switches_parse() {
        assert_eq!(ShadeMode::parse("shadows").unwrap(), ShadeMode::Shadows);
        assert!(ShadeMode::parse("phong")
            .unwrap_err()
            .contains("none, simple, shadows or reflect"));
        assert_eq!(ShadeMode::parse("reflect").unwrap(), ShadeMode::Reflect);
        assert!(ShadeMode::Reflect.shadows() && !ShadeMode::Simple.shadows());
        assert!(parse_on_off("--shadow-early", "on").unwrap());
        assert!(parse_on_off("--shadow-early", "yes").is_err());
    }

    #[test]
    fn the_model_by_hand() {
        // Normal +Z, light straight above: full irradiance, kd * 1.1 clamped.
        let n = shading_normal([Vec3::Z; 3], 0.2, 0.3, -Vec3::Z);
        assert_eq!(n, Vec3::Z);
        assert_eq!(light_cosine(n, Vec3::new(0.0, 0.0, 5.0)), 1.0);
        assert_eq!(
            pixel_colour([0.5, 1.0, 0.0], Vec3::ONE),
            u32::from_be_bytes([140, 255, 0, 255])
        );
        // Seen from below, the normal turns to the eye; a light behind gives nothing.
        assert_eq!(shading_normal([Vec3::Z; 3], 0.0, 0.0, Vec3::Z), -Vec3::Z);
        assert_eq!(light_cosine(Vec3::Z, -Vec3::Z), 0.0);
        // Interpolation: halfway between +X and +Y.
        let n = shading_normal([Vec3::X, Vec3::Y, Vec3::Y], 0.25, 0.25, -Vec3::Z);
        assert_eq!(n, Vec3::new(0.5, 0.5, 0.0));
        assert!((light_cosine(n, Vec3::X) - 0.70710677).abs() < 1e-6);
        assert_eq!(channel_difference(0x0102_03ff, 0x0300_03ff), 2);
    }

    #[test]
    fn reflections_by_hand() {
        // A ray down at 45 degrees onto a floor whose normal is +Y (unnormalised) leaves up
        // at 45 degrees, as long as it came.
        let d = Vec3::new(1.0, -1.0, 0.0);
        assert_eq!(
            reflect_direction(d, Vec3::new(0.0, 3.0, 0.0)),
            Vec3::new(1.0, 1.0, 0.0)
        );
        assert_eq!(reflect_direction(d, Vec3::ZERO), d);
        // Blends: none, half, all, and the rounding of a + r (b - a) + 0.5.
        let (red, blue) = (0xff00_00ff, 0x0000_ffff);
        assert_eq!(blend(red, blue, 0.0), red);
        assert_eq!(blend(red, blue, 1.0), blue);
        assert_eq!(blend(red, blue, 0.5), 0x8000_80ff);
        assert_eq!(blend(0x6400_00ff, 0xc800_00ff, 0.25), 0x7d00_00ff); // 100 + 25 + 0.5
        for (text, depth) in [("1", 1), ("4", 4)] {
            assert_eq!(parse_reflect_depth(text).unwrap(), depth);
        }
        for bad in ["0", "5", "-1", "x", ""] {
            assert!(
                parse_reflect_depth(bad).unwrap_err().contains("1 to 4"),
                "{bad}"
            );
        }
    }
}
