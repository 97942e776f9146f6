//! Wavefront OBJ scenes through the `tobj` crate, plus what `tobj` does not give us: a
//! missing `.mtl` library or material is not an error but a warning (each such `usemtl`
//! name gets a deterministic default color instead, [`Material::default_for_name`]), a file
//! without any `usemtl` gets one such material per group/object (so that e.g. Sponza's
//! groups stay distinguishable), comments may hold any bytes, and parse errors in the OBJ
//! and its MTL libraries are traced back to the offending line, since `tobj` reports only
//! the kind of error.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::Path;

use glam::{Vec2, Vec3};

use crate::error::LoadError;
use crate::scene::{read_maybe_gzipped, Material, Scene, Triangle};

/// The library name given to `tobj` for files that use materials but name no library.
const MISSING_LIBRARY: &str = "spu-loader-no-material-library.mtl";

/// Parses OBJ text (already decompressed) that was read from `path`; `path` is used for
/// error messages and to find `mtllib` files next to it (`name.mtl` or `name.mtl.gz`).
/// Warnings (a missing library or material) go to standard error.
pub fn parse_obj(path: &Path, bytes: &[u8]) -> Result<Scene, LoadError> {
    let (scene, warnings) = parse_obj_warned(path, bytes)?;
    for warning in warnings {
        eprintln!("{warning}");
    }
    Ok(scene)
}

/// [`parse_obj`], returning the warnings instead of printing them: each names the file, the
/// line where there is one, and the library or material.
pub fn parse_obj_warned(path: &Path, bytes: &[u8]) -> Result<(Scene, Vec<String>), LoadError> {
    let text = &text_outside_comments(path, bytes)?;

    check_vertex_positions(path, text)?;
    let usemtl_names = used_material_names(text);
    let directory = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let material_error: RefCell<Option<LoadError>> = RefCell::new(None);
    let warnings: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let reflectances: RefCell<HashMap<String, f32>> = RefCell::new(HashMap::new());
    let material_loader = |mtl: &Path| -> tobj::MTLLoadResult {
        let plain = directory.join(mtl);
        let mut gz_name = plain.clone().into_os_string();
        gz_name.push(".gz");
        let gz = std::path::PathBuf::from(gz_name);
        let found = [plain, gz]
            .into_iter()
            .find(|p| p.is_file() && mtl != Path::new(MISSING_LIBRARY));
        match found {
            Some(mtl_path) => {
                let parsed = read_maybe_gzipped(&mtl_path).and_then(|data| {
                    let data = text_outside_comments(&mtl_path, &data)?;
                    check_mtl(&mtl_path, &data)?;
                    reflectances
                        .borrow_mut()
                        .extend(mtl_reflectances(&mtl_path, &data)?);
                    tobj::load_mtl_buf(&mut data.as_bytes()).map_err(|e| {
                        LoadError::new(&mtl_path, None, format!("material library: {e}"))
                    })
                });
                parsed.map_err(|e| {
                    material_error.borrow_mut().get_or_insert(e);
                    tobj::LoadError::MaterialParseError
                })
            }
            None => {
                // No library: define every used name so groups keep distinct materials
                // (as viewers do), saying so, as GNU tools go on after a warning.
                if !usemtl_names.is_empty() {
                    let names: Vec<&str> = usemtl_names.iter().map(|(n, _)| n.as_str()).collect();
                    let missing = if mtl == Path::new(MISSING_LIBRARY) {
                        "no material library (mtllib)".to_string()
                    } else {
                        format!("material library {} not found", mtl.display())
                    };
                    warnings.borrow_mut().push(format!(
                        "warning: {}: {missing}; default colours for {}",
                        path.display(),
                        names.join(", ")
                    ));
                }
                let materials: Vec<tobj::Material> = usemtl_names
                    .iter()
                    .map(|(name, _)| {
                        let default = Material::default_for_name(name);
                        tobj::Material {
                            name: name.clone(),
                            diffuse: Some(default.diffuse),
                            ..Default::default()
                        }
                    })
                    .collect();
                let map = usemtl_names
                    .iter()
                    .enumerate()
                    .map(|(i, (n, _))| (n.clone(), i))
                    .collect();
                Ok((materials, map))
            }
        }
    };

    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // `tobj` only resolves `usemtl` names through a library; a file naming materials without
    // any `mtllib` gets a made-up one (which the loader then finds missing, so defaults).
    // Error lines are located in the original `text`, so the extra line does not shift them.
    let has_library = text
        .lines()
        .any(|line| line.trim_start().starts_with("mtllib"));
    let patched;
    let tobj_input = if !has_library && !usemtl_names.is_empty() {
        patched = format!("mtllib {MISSING_LIBRARY}\n{text}");
        patched.as_str()
    } else {
        text
    };
    let result = tobj::load_obj_buf(&mut tobj_input.as_bytes(), &options, material_loader);
    if let Some(error) = material_error.into_inner() {
        return Err(error);
    }
    let (models, materials) = result.map_err(|kind| locate_obj_error(path, text, kind))?;
    // Library errors are captured above; an `Err` here can only mean "nothing loaded".
    let tobj_materials = materials.unwrap_or_default();
    let mut warnings = warnings.into_inner();
    if warnings.is_empty() {
        // The libraries were read: a name none of them defines gets the default material.
        for (name, line) in &usemtl_names {
            if !tobj_materials.iter().any(|m| &m.name == name) {
                warnings.push(format!(
                    "warning: {}:{line}: usemtl {name}: no such material in the library; default colour",
                    path.display()
                ));
            }
        }
    }

    let mut scene_materials: Vec<Material> = tobj_materials
        .iter()
        .map(|m| Material {
            name: m.name.clone(),
            diffuse: m.diffuse.unwrap_or([0.8; 3]),
            specular: m.specular.unwrap_or([0.0; 3]),
            shininess: m.shininess.unwrap_or(0.0),
            reflectance: reflectances.borrow().get(&m.name).copied().unwrap_or(0.0),
        })
        .collect();
    // Without any `usemtl`, each group/object gets its own default-colored material so that
    // the groups stay distinguishable in images.
    let by_group = usemtl_names.is_empty() && models.len() > 1;
    let mut group_materials: HashMap<&str, u32> = HashMap::new();
    if by_group {
        for model in &models {
            if !group_materials.contains_key(model.name.as_str()) {
                group_materials.insert(&model.name, scene_materials.len() as u32);
                scene_materials.push(Material::default_for_name(&model.name));
            }
        }
    }
    let fallback_material = scene_materials.len() as u32;
    let mut fallback_used = false;

    let vertex_total: usize = models.iter().map(|m| m.mesh.positions.len() / 3).sum();
    let triangle_total: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let any_texcoords = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let mut positions = Vec::with_capacity(vertex_total);
    let mut normals = Vec::with_capacity(vertex_total);
    let mut needs_normal = Vec::with_capacity(vertex_total);
    let mut texcoords = Vec::with_capacity(if any_texcoords { vertex_total } else { 0 });
    let mut triangles = Vec::with_capacity(triangle_total);

    for model in &models {
        let mesh = &model.mesh;
        let base = positions.len() as u32;
        let count = mesh.positions.len() / 3;
        positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        let has_normals = mesh.normals.len() == count * 3;
        if has_normals {
            normals.extend(mesh.normals.chunks_exact(3).map(|n| {
                let n = Vec3::new(n[0], n[1], n[2]);
                n.try_normalize().unwrap_or(Vec3::Z)
            }));
        } else {
            normals.extend(std::iter::repeat_n(Vec3::Z, count));
        }
        needs_normal.extend(std::iter::repeat_n(!has_normals, count));
        if any_texcoords {
            if mesh.texcoords.len() == count * 2 {
                texcoords.extend(
                    mesh.texcoords
                        .chunks_exact(2)
                        .map(|t| Vec2::new(t[0], t[1])),
                );
            } else {
                texcoords.extend(std::iter::repeat_n(Vec2::ZERO, count));
            }
        }
        let material = match mesh.material_id {
            _ if by_group => group_materials[model.name.as_str()],
            Some(id) if id < scene_materials.len() => id as u32,
            _ => {
                fallback_used = true;
                fallback_material
            }
        };
        triangles.extend(mesh.indices.chunks_exact(3).map(|i| Triangle {
            v: [base + i[0], base + i[1], base + i[2]],
            material,
        }));
    }
    if fallback_used || scene_materials.is_empty() {
        scene_materials.push(Material::default());
    }

    let mut scene = Scene::from_parts(
        positions,
        Some(normals),
        texcoords,
        triangles,
        scene_materials,
    );
    if needs_normal.iter().any(|&n| n) {
        scene.compute_smooth_normals_where(&mut needs_normal);
    }
    Ok((scene, warnings))
}

/// The text of an OBJ or MTL file, a comment that is not UTF-8 cut at its `#` (comments may
/// hold any bytes: a Latin-1 author's name, say); anything else that is not UTF-8 is refused
/// naming its line. Lines keep their numbers.
fn text_outside_comments(path: &Path, bytes: &[u8]) -> Result<String, LoadError> {
    if let Ok(text) = std::str::from_utf8(bytes) {
        return Ok(text.to_string());
    }
    let mut text = String::with_capacity(bytes.len());
    for (number, line) in bytes.split(|&b| b == b'\n').enumerate() {
        if number > 0 {
            text.push('\n');
        }
        let line = match std::str::from_utf8(line) {
            Ok(line) => line,
            Err(e) => {
                let hash = line.iter().position(|&b| b == b'#');
                match hash {
                    Some(at) if at < e.valid_up_to() => {
                        std::str::from_utf8(&line[..at]).expect("UTF-8 up to here")
                    }
                    _ => {
                        return Err(LoadError::new(
                            path,
                            Some(number + 1),
                            "invalid UTF-8 outside a comment",
                        ))
                    }
                }
            }
        };
        text.push_str(line);
    }
    Ok(text)
}

/// Refuses, naming the line, a `v` line whose position is not finite or too large for the
/// kernel ([`crate::scene::check_position`]); `tobj` would take `inf` and `nan` as given.
fn check_vertex_positions(path: &Path, text: &str) -> Result<(), LoadError> {
    let mut index = 0;
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_ascii_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        let values: Vec<f32> = words.take(3).map_while(|w| w.parse().ok()).collect();
        if let [x, y, z] = values[..] {
            crate::scene::check_position(index, Vec3::new(x, y, z))
                .map_err(|reason| LoadError::new(path, Some(number + 1), reason))?;
        }
        index += 1;
    }
    Ok(())
}

/// Checks the colour and number statements of an MTL library line by line, so that a bad
/// value is reported with its line (`tobj` reports only that parsing failed) and no
/// non-finite or negative colour reaches the shaders.
fn check_mtl(path: &Path, text: &str) -> Result<(), LoadError> {
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_ascii_whitespace();
        let keyword = words.next();
        let error = |reason: String| {
            LoadError::new(
                path,
                Some(number + 1),
                format!("material library: {reason}"),
            )
        };
        // What `tobj` refuses without saying where.
        match keyword {
            Some(
                k @ ("newmtl" | "map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns"
                | "map_ns" | "map_NS" | "bump" | "map_d"),
            ) if line.trim()[k.len()..].trim().is_empty() => {
                return Err(error(format!("{k} needs a name")));
            }
            Some("illum")
                if words
                    .clone()
                    .next()
                    .and_then(|w| w.parse::<u8>().ok())
                    .is_none() =>
            {
                return Err(error(
                    "illum needs an illumination model number 0 to 255".into(),
                ));
            }
            _ => {}
        }
        let (expected, what) = match keyword {
            Some("Kd" | "Ka" | "Ks" | "Ke" | "Tf") => (3, "colour needs three numbers >= 0"),
            Some("Ns" | "Ni" | "d" | "Tr") => (1, "needs one finite number"),
            _ => continue,
        };
        let values: Vec<Option<f32>> = words
            .take(expected)
            .map(|w| w.parse::<f32>().ok().filter(|v| v.is_finite()))
            .collect();
        let colour = expected == 3;
        let ok = values.len() == expected
            && values
                .iter()
                .all(|v| v.is_some_and(|v| !colour || v >= 0.0));
        if !ok {
            let keyword = line.split_ascii_whitespace().next().unwrap_or("");
            return Err(LoadError::new(
                path,
                Some(number + 1),
                format!("material library: {keyword}: {what}"),
            ));
        }
    }
    Ok(())
}

/// The mirror weight of every reflective material of an MTL library, by name: a material
/// with `illum 3` (reflection on) reflects with its `Km` where it has one, else with its
/// `Ks`'s largest channel; a weight outside [0, 1] is an error naming its line (a `Km`
/// anywhere, a `Ks` of a reflective material). Numbers are known finite ([`check_mtl`]).
fn mtl_reflectances(path: &Path, text: &str) -> Result<HashMap<String, f32>, LoadError> {
    #[derive(Default)]
    struct Block {
        name: Option<String>,
        illum: Option<u8>,
        ks: Option<(f32, usize)>,
        km: Option<f32>,
    }
    let out_of_range = |line: usize, what: &str, value: f32| -> Result<(), LoadError> {
        if (0.0..=1.0).contains(&value) {
            Ok(())
        } else {
            Err(LoadError::new(
                path,
                Some(line),
                format!("material library: {what} {value}: a reflectance must be 0 to 1"),
            ))
        }
    };
    let mut weights = HashMap::new();
    let mut finish = |block: Block| -> Result<(), LoadError> {
        if let (Some(name), Some(3)) = (block.name, block.illum) {
            let weight = match (block.km, block.ks) {
                (Some(km), _) => km,
                (None, Some((ks, line))) => {
                    out_of_range(line, "Ks (illum 3)", ks)?;
                    ks
                }
                (None, None) => 0.0,
            };
            weights.insert(name, weight);
        }
        Ok(())
    };
    let mut block = Block::default();
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_ascii_whitespace();
        let keyword = words.next();
        let mut number_after = || words.next().and_then(|w| w.parse::<f32>().ok());
        match keyword {
            Some("newmtl") => {
                finish(std::mem::take(&mut block))?;
                block.name = Some(line.trim()["newmtl".len()..].trim().to_string());
            }
            Some("illum") => block.illum = words.next().and_then(|w| w.parse().ok()),
            Some("Ks") => {
                let largest = (0..3).filter_map(|_| number_after()).fold(0.0f32, f32::max);
                block.ks = Some((largest, number + 1));
            }
            Some("Km") => {
                let km = number_after().filter(|v| v.is_finite()).ok_or_else(|| {
                    LoadError::new(
                        path,
                        Some(number + 1),
                        "material library: Km needs one finite number",
                    )
                })?;
                out_of_range(number + 1, "Km", km)?;
                block.km = Some(km);
            }
            _ => {}
        }
    }
    finish(block)?;
    Ok(weights)
}

/// Every `usemtl` name, in order of first use, with the line of that use.
fn used_material_names(text: &str) -> Vec<(String, usize)> {
    let mut seen = HashMap::new();
    let mut names = Vec::new();
    for (number, line) in text.lines().enumerate() {
        let line = line.trim_start();
        if let Some(rest) = line.strip_prefix("usemtl") {
            if rest.starts_with(|c: char| c.is_ascii_whitespace()) {
                let name = rest.trim().to_string();
                if !name.is_empty() && seen.insert(name.clone(), ()).is_none() {
                    names.push((name, number + 1));
                }
            }
        }
    }
    names
}

/// Turns `tobj`'s line-less error kind into an error naming the first line that causes it.
fn locate_obj_error(path: &Path, text: &str, kind: tobj::LoadError) -> LoadError {
    let (mut n_positions, mut n_texcoords, mut n_normals) = (0usize, 0usize, 0usize);
    // `tobj` keeps a colour per `v` line that has one (x y z r g b) and indexes them as the
    // positions: a face using a vertex past the coloured ones fails.
    let mut n_colours = 0usize;
    for line in text.lines() {
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                n_positions += 1;
                n_colours += usize::from(words.count() == 6);
            }
            Some("vt") => n_texcoords += 1,
            Some("vn") => n_normals += 1,
            _ => {}
        }
    }
    let floats_ok = |words: std::str::SplitAsciiWhitespace, n: usize| {
        let values: Vec<_> = words.take(n).map(str::parse::<f32>).collect();
        values.len() == n && values.iter().all(Result::is_ok)
    };
    let resolve = |word: &str, total: usize| -> Result<Option<usize>, String> {
        if word.is_empty() {
            return Ok(None);
        }
        let index: i64 = word
            .parse()
            .map_err(|_| format!("'{word}' is not an index"))?;
        let resolved = if index > 0 {
            index - 1
        } else if index < 0 {
            total as i64 + index
        } else {
            return Err("index 0 (OBJ indices start at 1)".into());
        };
        if resolved < 0 || resolved as usize >= total {
            return Err(format!("index {index} out of range (there are {total})"));
        }
        Ok(Some(resolved as usize))
    };
    let (mut seen_p, mut seen_t, mut seen_n) = (0usize, 0usize, 0usize);
    for (number, line) in text.lines().enumerate() {
        let number = number + 1;
        let mut words = line.split_ascii_whitespace();
        let problem = match words.next() {
            Some("v") => {
                seen_p += 1;
                let rest: Vec<&str> = words.clone().skip(3).collect();
                if !floats_ok(words, 3) {
                    Some("vertex position needs three numbers".to_string())
                } else {
                    match rest[..] {
                        [] => None,
                        [w] => match w.parse::<f32>() {
                            Ok(w) if w != 0.0 => None,
                            Ok(_) => Some("vertex weight w is 0".to_string()),
                            Err(_) => Some(format!("vertex weight '{w}' is not a number")),
                        },
                        [_, _, _] => None,
                        _ => Some(format!(
                            "vertex has {} numbers after x y z: expected a weight w or a colour r g b",
                            rest.len()
                        )),
                    }
                }
            }
            // `tobj` takes the name after the first space.
            Some("usemtl")
                if line
                    .trim()
                    .split_once(' ')
                    .is_none_or(|(_, name)| name.trim().is_empty()) =>
            {
                Some("usemtl needs a name after a space".to_string())
            }
            Some("vt") => {
                seen_t += 1;
                (!floats_ok(words, 2)).then(|| "texture coordinate needs two numbers".to_string())
            }
            Some("vn") => {
                seen_n += 1;
                (!floats_ok(words, 3)).then(|| "normal needs three numbers".to_string())
            }
            Some("f") => {
                let corners: Vec<&str> = words.collect();
                let mut problem =
                    (corners.len() < 3).then(|| format!("face with {} corners", corners.len()));
                for corner in &corners {
                    if problem.is_some() {
                        break;
                    }
                    let mut parts = corner.split('/');
                    // Relative (negative) indices count from what has been read so far.
                    let checks = [
                        (
                            parts.next().unwrap_or(""),
                            if corner.starts_with('-') {
                                seen_p
                            } else {
                                n_positions
                            },
                            "position",
                        ),
                        (
                            parts.next().unwrap_or(""),
                            n_texcoords.max(seen_t),
                            "texcoord",
                        ),
                        (parts.next().unwrap_or(""), n_normals.max(seen_n), "normal"),
                    ];
                    for (i, (word, total, what)) in checks.into_iter().enumerate() {
                        if i == 0 && word.is_empty() {
                            problem = Some(format!("face corner '{corner}' has no position index"));
                            break;
                        }
                        match resolve(word, total) {
                            Err(e) => {
                                problem = Some(format!("face corner '{corner}': {what} {e}"));
                                break;
                            }
                            Ok(Some(index)) if i == 0 && n_colours > 0 && index >= n_colours => {
                                problem = Some(format!(
                                    "face corner '{corner}': vertex {} has no colour, but {n_colours} \
                                     vertices do (r g b on every v line or on none)",
                                    index + 1
                                ));
                                break;
                            }
                            _ => {}
                        }
                    }
                }
                problem
            }
            _ => None,
        };
        if let Some(problem) = problem {
            return LoadError::new(path, Some(number), problem);
        }
    }
    LoadError::new(path, None, format!("OBJ: {kind}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, LoadError> {
        parse_obj(Path::new("/nowhere/test.obj"), text.as_bytes())
    }

    #[test]
    fn non_finite_and_huge_vertices_are_refused_with_the_line() {
        let err = parse("v 0 0 0\n# c\nv inf 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "/nowhere/test.obj:3: vertex 1 is not finite (inf, 0, 0)"
        );
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(err.line, Some(3));
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 -2e20 0\nf 1 2 3\n").unwrap_err();
        assert!(
            err.reason.contains("exceeds the largest coordinate"),
            "{err}"
        );
    }

    #[test]
    fn groups_materials_and_quads() {
        let text = "mtllib missing.mtl\n\
                    v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\n\
                    g floor\nusemtl red\nf 1 2 3 4\n\
                    g wall\nusemtl blue\nf 1 2 5\n\
                    usemtl red\nf -1 -4 -3\n";
        let scene = parse(text).unwrap();
        scene.validate().unwrap();
        assert_eq!(scene.triangle_count(), 4);
        let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(&names[..2], &["red", "blue"]);
        assert_eq!(scene.triangles[0].material, 0);
        assert_eq!(scene.triangles[2].material, 1);
        assert_eq!(scene.triangles[3].material, 0);
        assert_ne!(scene.materials[0].diffuse, scene.materials[1].diffuse);
        assert!((scene.normals[0].length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn usemtl_without_library_and_groups_without_usemtl() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let scene = parse(&format!("{tri}usemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n")).unwrap();
        assert_eq!(
            scene
                .materials
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>(),
            ["a", "b"]
        );
        assert_eq!(scene.triangles[1].material, 1);
        let err = parse(&format!("{tri}usemtl a\nf 1 2 9\n")).unwrap_err();
        assert_eq!(err.line, Some(5), "{err}");

        let scene = parse(&format!(
            "{tri}g one\nf 1 2 3\ng two\nf 1 3 2\ng one\nf 2 3 1\n"
        ))
        .unwrap();
        assert_eq!(
            scene
                .materials
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>(),
            ["one", "two"]
        );
        assert_eq!(
            scene
                .triangles
                .iter()
                .map(|t| t.material)
                .collect::<Vec<_>>(),
            [0, 1, 0]
        );
    }

    #[test]
    fn comments_hold_any_bytes_and_nothing_else_does() {
        let scene = parse_obj(
            Path::new("/nowhere/test.obj"),
            b"# by Ren\xe9\nv 0 0 0\nv 1 0 0 # \xff\xfe\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap();
        assert_eq!(scene.triangles.len(), 1);
        assert_eq!(
            scene.positions[1],
            Vec3::X,
            "the line before the comment is kept"
        );
        let err = parse_obj(
            Path::new("/nowhere/test.obj"),
            b"v 0 0 0\ng caf\xe9 # ok\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        )
        .unwrap_err();
        assert_eq!(
            err.to_string(),
            "/nowhere/test.obj:2: invalid UTF-8 outside a comment"
        );
    }

    #[test]
    fn every_statement_tobj_refuses_names_its_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases = [
            ("v 1 2 3 0\n", "4: vertex weight w is 0"),
            ("v 1 2 3 x\n", "4: vertex weight 'x' is not a number"),
            (
                "v 1 2 3 4 5\n",
                "4: vertex has 2 numbers after x y z: expected a weight w or a colour r g b",
            ),
            ("usemtl\n", "4: usemtl needs a name after a space"),
            ("usemtl\tred\n", "4: usemtl needs a name after a space"),
        ];
        for (line, message) in cases {
            let err = parse(&format!("{tri}{line}f 1 2 3\n")).unwrap_err();
            assert_eq!(
                err.to_string(),
                format!("/nowhere/test.obj:{message}"),
                "{line:?}"
            );
        }
        // Colours on some vertices only: the face that uses one without.
        let err = parse("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(
            err.to_string(),
            "/nowhere/test.obj:4: face corner '2': vertex 2 has no colour, but 1 vertices do \
             (r g b on every v line or on none)"
        );
        // A weight, and colours on every vertex, are fine.
        let scene = parse("v 0 0 0 1 0 0\nv 2 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
        assert_eq!(scene.triangles.len(), 1);
        let scene = parse("v 0 0 0\nv 2 0 0 2\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(scene.positions[1], Vec3::X, "x y z divided by w");
    }

    #[test]
    fn missing_materials_warn_once_naming_them() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let path = Path::new("/nowhere/test.obj");
        let text = format!("{tri}usemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\nusemtl a\nf 2 3 1\n");
        let (_, warnings) = parse_obj_warned(path, text.as_bytes()).unwrap();
        assert_eq!(
            warnings,
            ["warning: /nowhere/test.obj: no material library (mtllib); default colours for a, b"]
        );
        let text = format!("mtllib gone.mtl\n{text}");
        let (_, warnings) = parse_obj_warned(path, text.as_bytes()).unwrap();
        assert_eq!(
            warnings,
            ["warning: /nowhere/test.obj: material library gone.mtl not found; default colours for a, b"]
        );
        // Without any usemtl there is nothing to warn about.
        let (_, warnings) = parse_obj_warned(path, format!("{tri}f 1 2 3\n").as_bytes()).unwrap();
        assert!(warnings.is_empty());
    }

    #[test]
    fn file_normals_are_kept() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nf 1//1 2//1 3//1\n";
        let scene = parse(text).unwrap();
        assert_eq!(scene.materials.len(), 1);
        assert!(scene.normals.iter().all(|n| *n == Vec3::Z));
    }

    #[test]
    fn bad_files_name_file_line_and_reason() {
        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n").unwrap_err();
        assert_eq!(err.line, Some(4), "{err}");
        assert!(err.reason.contains("out of range"), "{err}");
        assert!(err.to_string().starts_with("/nowhere/test.obj:4:"), "{err}");

        let err = parse("v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(err.line, Some(2), "{err}");
        assert!(err.reason.contains("three numbers"), "{err}");

        let err = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n").unwrap_err();
        assert_eq!(err.line, Some(4), "{err}");
    }

    /// `illum 3` makes a material reflective, with `Km` or else `Ks`'s largest channel; a
    /// weight outside [0, 1] is refused naming the library's line.
    #[test]
    fn reflective_materials_come_from_illum_3() {
        let dir = std::env::temp_dir().join(format!("spu-loader-mirror-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let obj = dir.join("s.obj");
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n\
             usemtl c\nf 2 3 1\nusemtl d\nf 2 1 3\n",
        )
        .unwrap();
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl a\nKd 1 0 0\nKs 0.2 0.6 0.4\nillum 3\n\
             newmtl b\nillum 3\nKs 1 1 1\nKm 0.25\n\
             newmtl c\nKs 0.9 0.9 0.9\nillum 2\n\
             newmtl d\nKd 0 0 1\n",
        )
        .unwrap();
        let scene = Scene::load(&obj).unwrap();
        let weight = |name: &str| {
            scene
                .materials
                .iter()
                .find(|m| m.name == name)
                .unwrap()
                .reflectance
        };
        assert_eq!(
            [weight("a"), weight("b"), weight("c"), weight("d")],
            [0.6, 0.25, 0.0, 0.0]
        );
        for (bad, line, message) in [
            ("newmtl a\nillum 3\nKs 0.5 1.5 0\n", 3, "Ks (illum 3) 1.5"),
            ("newmtl a\nKs 2 2 2\nillum 3\n", 2, "Ks (illum 3) 2"),
            ("newmtl a\nillum 1\nKm 1.25\n", 3, "Km 1.25"),
            ("newmtl a\nKm -0.5\n", 2, "Km -0.5"),
        ] {
            std::fs::write(dir.join("m.mtl"), bad).unwrap();
            let err = Scene::load(&obj).unwrap_err();
            assert_eq!(
                err.to_string(),
                format!(
                    "{}:{line}: material library: {message}: a reflectance must be 0 to 1",
                    dir.join("m.mtl").display()
                )
            );
        }
        // Ks above 1 without illum 3 is a specular colour, not a mirror: accepted.
        std::fs::write(dir.join("m.mtl"), "newmtl a\nKs 2 2 2\nillum 2\n").unwrap();
        assert_eq!(Scene::load(&obj).unwrap().materials[0].reflectance, 0.0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn present_material_library_is_used() {
        let dir = std::env::temp_dir().join(format!("spu-loader-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("m.mtl"),
            "newmtl green\nKd 0 1 0\nKs 0.5 0.5 0.5\nNs 20\n",
        )
        .unwrap();
        let obj = dir.join("s.obj");
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl green\nf 1 2 3\n",
        )
        .unwrap();
        let scene = Scene::load(&obj).unwrap();
        assert_eq!(scene.materials[0].name, "green");
        assert_eq!(scene.materials[0].diffuse, [0.0, 1.0, 0.0]);
        assert_eq!(scene.materials[0].shininess, 20.0);
        std::fs::write(dir.join("m.mtl"), "newmtl green\nKd 0 x 0\n").unwrap();
        let err = Scene::load(&obj).unwrap_err();
        assert!(err.path.ends_with("m.mtl"), "{err}");
        assert_eq!(err.line, Some(2), "{err}");
        for bad in ["Kd 0 1", "Kd 0 nan 1", "Kd 0 -1 0", "Ns inf"] {
            std::fs::write(dir.join("m.mtl"), format!("# m\nnewmtl green\n{bad}\n")).unwrap();
            let err = Scene::load(&obj).unwrap_err();
            assert_eq!(err.line, Some(3), "{bad}: {err}");
            assert!(
                err.to_string().contains("m.mtl:3: material library"),
                "{err}"
            );
        }
        // What tobj refuses in a library is located too; comments hold any bytes.
        for (bad, message) in [
            ("newmtl", "newmtl needs a name"),
            ("map_Kd  ", "map_Kd needs a name"),
            (
                "illum x",
                "illum needs an illumination model number 0 to 255",
            ),
        ] {
            std::fs::write(dir.join("m.mtl"), format!("# m\nnewmtl green\n{bad}\n")).unwrap();
            let err = Scene::load(&obj).unwrap_err();
            assert_eq!(
                err.to_string(),
                format!(
                    "{}:3: material library: {message}",
                    dir.join("m.mtl").display()
                )
            );
        }
        std::fs::write(dir.join("m.mtl"), b"# \xe9t\xe9\nnewmtl green\nKd 0 1 0\n").unwrap();
        assert_eq!(
            Scene::load(&obj).unwrap().materials[0].diffuse,
            [0.0, 1.0, 0.0]
        );
        // A name the library does not define: a warning naming it and its first use, once.
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl green\nf 1 2 3\n\
             usemtl blue\nf 1 3 2\nusemtl blue\nf 2 3 1\n",
        )
        .unwrap();
        let bytes = std::fs::read(&obj).unwrap();
        let (scene, warnings) = parse_obj_warned(&obj, &bytes).unwrap();
        assert_eq!(
            warnings,
            [format!(
                "warning: {}:7: usemtl blue: no such material in the library; default colour",
                obj.display()
            )]
        );
        assert_eq!(scene.triangles[1].material, scene.triangles[2].material);
        assert_eq!(
            scene.materials[scene.triangles[1].material as usize],
            Material::default()
        );
        // A missing library is a warning: default colours, one per used name.
        std::fs::write(
            &obj,
            "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl green\nf 1 2 3\n",
        )
        .unwrap();
        std::fs::remove_file(dir.join("m.mtl")).unwrap();
        let scene = Scene::load(&obj).unwrap();
        assert_eq!(scene.materials[0], Material::default_for_name("green"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
