//! Stanford PLY scenes (ASCII, binary little- and big-endian), hand-parsed because the
//! shared dragon is an 871k-face ASCII file that must load in seconds, and because errors
//! must name the line.
//!
//! Supported: a `vertex` element with `x y z` and optional `nx ny nz` and `u v` / `s t`
//! (any scalar types; other properties are skipped), a `face` element with a
//! `vertex_indices` (or `vertex_index`) list of any integer count/index type, polygons
//! triangulated as fans `(0, i, i+1)`, and any other elements, which are skipped. ASCII
//! bodies are read one element instance per line, as every PLY writer emits them.

use std::path::Path;

use glam::{Vec2, Vec3};

use crate::error::LoadError;
use crate::scene::{Scene, Triangle};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLittleEndian,
    BinaryBigEndian,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ScalarType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl ScalarType {
    fn parse(name: &str) -> Option<ScalarType> {
        Some(match name {
            "char" | "int8" => ScalarType::I8,
            "uchar" | "uint8" => ScalarType::U8,
            "short" | "int16" => ScalarType::I16,
            "ushort" | "uint16" => ScalarType::U16,
            "int" | "int32" => ScalarType::I32,
            "uint" | "uint32" => ScalarType::U32,
            "float" | "float32" => ScalarType::F32,
            "double" | "float64" => ScalarType::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            ScalarType::I8 | ScalarType::U8 => 1,
            ScalarType::I16 | ScalarType::U16 => 2,
            ScalarType::I32 | ScalarType::U32 | ScalarType::F32 => 4,
            ScalarType::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, ScalarType::F32 | ScalarType::F64)
    }
}

#[derive(Debug, Clone)]
enum Property {
    Scalar {
        name: String,
        ty: ScalarType,
    },
    List {
        name: String,
        count_ty: ScalarType,
        item_ty: ScalarType,
    },
}

impl Property {
    fn name(&self) -> &str {
        match self {
            Property::Scalar { name, .. } | Property::List { name, .. } => name,
        }
    }
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
    /// The header line that declares it.
    line: usize,
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of header lines (the body's first line is `header_lines + 1`).
    header_lines: usize,
}

/// What a vertex property is used for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum VertexSlot {
    Position(usize),
    Normal(usize),
    Texcoord(usize),
    Ignored,
}

/// The decoded vertex and face data, independent of the body encoding.
struct Mesh {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    texcoords: Vec<Vec2>,
    triangles: Vec<Triangle>,
}

/// Parses PLY data (already decompressed) that was read from `path`.
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<Scene, LoadError> {
    let header = parse_header(path, bytes)?;
    let vertex_element = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| {
            LoadError::new(
                path,
                Some(header.header_lines),
                "no 'vertex' element before end_header",
            )
        })?;
    let slots: Vec<VertexSlot> = vertex_element
        .properties
        .iter()
        .map(|p| match (p, p.name()) {
            (Property::Scalar { .. }, "x") => VertexSlot::Position(0),
            (Property::Scalar { .. }, "y") => VertexSlot::Position(1),
            (Property::Scalar { .. }, "z") => VertexSlot::Position(2),
            (Property::Scalar { .. }, "nx") => VertexSlot::Normal(0),
            (Property::Scalar { .. }, "ny") => VertexSlot::Normal(1),
            (Property::Scalar { .. }, "nz") => VertexSlot::Normal(2),
            (Property::Scalar { .. }, "u" | "s" | "texture_u") => VertexSlot::Texcoord(0),
            (Property::Scalar { .. }, "v" | "t" | "texture_v") => VertexSlot::Texcoord(1),
            _ => VertexSlot::Ignored,
        })
        .collect();
    let has = |slot: VertexSlot| slots.contains(&slot);
    if !(0..3).all(|i| has(VertexSlot::Position(i))) {
        return Err(LoadError::new(
            path,
            Some(vertex_element.line),
            "vertex element lacks x, y or z",
        ));
    }
    let has_normals = (0..3).all(|i| has(VertexSlot::Normal(i)));
    let has_texcoords = (0..2).all(|i| has(VertexSlot::Texcoord(i)));
    if !header.elements.iter().any(|e| e.name == "face") {
        return Err(LoadError::new(
            path,
            Some(header.header_lines),
            "no 'face' element before end_header",
        ));
    }
    check_counts_against_data(path, &header, bytes.len())?;
    let vertex_count = vertex_element.count;
    let mut mesh = Mesh {
        positions: Vec::with_capacity(vertex_count),
        normals: Vec::with_capacity(if has_normals { vertex_count } else { 0 }),
        texcoords: Vec::with_capacity(if has_texcoords { vertex_count } else { 0 }),
        triangles: Vec::new(),
    };
    let context = BodyContext {
        path,
        slots: &slots,
        has_normals,
        has_texcoords,
        vertex_count,
    };
    match header.format {
        Format::Ascii => parse_ascii_body(&context, &header, bytes, &mut mesh)?,
        Format::BinaryLittleEndian => {
            parse_binary_body::<false>(&context, &header, bytes, &mut mesh)?
        }
        Format::BinaryBigEndian => parse_binary_body::<true>(&context, &header, bytes, &mut mesh)?,
    }
    let normals = has_normals.then(|| {
        mesh.normals
            .iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
            .collect()
    });
    Ok(Scene::from_parts(
        mesh.positions,
        normals,
        mesh.texcoords,
        mesh.triangles,
        Vec::new(),
    ))
}

fn parse_header(path: &Path, bytes: &[u8]) -> Result<Header, LoadError> {
    let mut offset = 0usize;
    let mut line_number = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(length) = bytes[offset..].iter().position(|&b| b == b'\n') else {
            return Err(LoadError::new(
                path,
                Some(line_number + 1),
                "header ends without 'end_header'",
            ));
        };
        line_number += 1;
        let raw = &bytes[offset..offset + length];
        offset += length + 1;
        // A comment may hold any bytes (a Latin-1 author's name, say).
        let is_comment = raw.starts_with(b"comment") || raw.starts_with(b"obj_info");
        let line = match std::str::from_utf8(raw) {
            Ok(line) => line,
            Err(_) if is_comment => "comment",
            Err(_) => {
                return Err(LoadError::new(
                    path,
                    Some(line_number),
                    "header line is not text",
                ))
            }
        }
        .trim_end_matches('\r');
        let error = |reason: String| LoadError::new(path, Some(line_number), reason);
        let words: Vec<&str> = line.split_ascii_whitespace().collect();
        if line_number == 1 {
            if line.trim() != "ply" {
                return Err(error("missing 'ply' magic".into()));
            }
            continue;
        }
        match words.first().copied() {
            None | Some("comment") | Some("obj_info") => {}
            Some("format") => {
                format = Some(match words.get(1).copied() {
                    Some("ascii") => Format::Ascii,
                    Some("binary_little_endian") => Format::BinaryLittleEndian,
                    Some("binary_big_endian") => Format::BinaryBigEndian,
                    other => return Err(error(format!("unknown format {other:?}"))),
                });
            }
            Some("element") => {
                let (Some(name), Some(count)) = (words.get(1), words.get(2)) else {
                    return Err(error("element needs a name and a count".into()));
                };
                let count = count
                    .parse::<usize>()
                    .map_err(|_| error(format!("bad element count '{count}'")))?;
                if elements.iter().any(|e| e.name == *name) {
                    return Err(error(format!("element '{name}' declared twice")));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: line_number,
                });
            }
            Some("property") => {
                let Some(element) = elements.last_mut() else {
                    return Err(error("property before any element".into()));
                };
                let type_of = |name: &str| {
                    ScalarType::parse(name).ok_or_else(|| error(format!("unknown type '{name}'")))
                };
                let property = if words.get(1) == Some(&"list") {
                    let [_, _, count_ty, item_ty, name] = words[..] else {
                        return Err(error(
                            "list property needs: property list <count type> <item type> <name>"
                                .into(),
                        ));
                    };
                    let count_ty = type_of(count_ty)?;
                    let item_ty = type_of(item_ty)?;
                    if !count_ty.is_integer() {
                        return Err(error("list count type must be an integer type".into()));
                    }
                    Property::List {
                        name: name.to_string(),
                        count_ty,
                        item_ty,
                    }
                } else {
                    let [_, ty, name] = words[..] else {
                        return Err(error("property needs: property <type> <name>".into()));
                    };
                    Property::Scalar {
                        name: name.to_string(),
                        ty: type_of(ty)?,
                    }
                };
                element.properties.push(property);
            }
            Some("end_header") => break,
            Some(other) => return Err(error(format!("unknown header keyword '{other}'"))),
        }
    }
    // What the whole header lacks is reported at its end.
    let format = format.ok_or_else(|| {
        LoadError::new(
            path,
            Some(line_number),
            "header has no 'format' line before end_header",
        )
    })?;
    for element in &elements {
        if element.name == "face" {
            let ok = element.properties.iter().any(|p| {
                matches!(p, Property::List { name, item_ty, .. }
                    if (name == "vertex_indices" || name == "vertex_index") && item_ty.is_integer())
            });
            if !ok {
                return Err(LoadError::new(
                    path,
                    Some(element.line),
                    "face element has no integer 'vertex_indices' list",
                ));
            }
        }
    }
    Ok(Header {
        format,
        elements,
        body_start: offset,
        header_lines: line_number,
    })
}

/// The fewest body bytes one instance of `element` can take: its scalars and list counts
/// in binary (lists may be empty), one character and a separator per property in ASCII.
fn min_instance_bytes(format: Format, element: &Element) -> usize {
    element
        .properties
        .iter()
        .map(|p| match (format, p) {
            (Format::Ascii, _) => 2,
            (_, Property::Scalar { ty, .. }) => ty.size(),
            (_, Property::List { count_ty, .. }) => count_ty.size(),
        })
        .sum()
}

/// Rejects element counts the body cannot hold before anything is reserved for them (a
/// header that declares 4,000,000,000 vertices in a small file fails here, at once).
fn check_counts_against_data(path: &Path, header: &Header, len: usize) -> Result<(), LoadError> {
    let body = len.saturating_sub(header.body_start);
    let mut needed = 0usize;
    for element in &header.elements {
        if element.count > 0 && element.properties.is_empty() {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "element '{}' has {} instances but no properties",
                    element.name, element.count
                ),
            ));
        }
        if element.name == "vertex" && element.count > u32::MAX as usize {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "{} vertices: more than 32-bit indices can name",
                    element.count
                ),
            ));
        }
        let per_instance = min_instance_bytes(header.format, element);
        needed = needed.saturating_add(element.count.saturating_mul(per_instance));
        // The last ASCII line needs no newline.
        if needed.saturating_sub(usize::from(header.format == Format::Ascii)) > body {
            return Err(LoadError::new(
                path,
                None,
                format!(
                    "header declares {} '{}' elements but the {} body bytes can hold at most {}",
                    element.count,
                    element.name,
                    body,
                    (body + 1) / per_instance.max(1)
                ),
            ));
        }
    }
    Ok(())
}

struct BodyContext<'a> {
    path: &'a Path,
    slots: &'a [VertexSlot],
    has_normals: bool,
    has_texcoords: bool,
    vertex_count: usize,
}

impl BodyContext<'_> {
    /// Adds a vertex; a position that is not finite, or so large that the kernel's products
    /// of coordinates would overflow, is refused.
    fn push_vertex(&self, mesh: &mut Mesh, values: &[f32; 8]) -> Result<(), String> {
        let position = Vec3::new(values[0], values[1], values[2]);
        crate::scene::check_position(mesh.positions.len(), position)?;
        mesh.positions.push(position);
        if self.has_normals {
            mesh.normals
                .push(Vec3::new(values[3], values[4], values[5]));
        }
        if self.has_texcoords {
            mesh.texcoords.push(Vec2::new(values[6], values[7]));
        }
        Ok(())
    }

    fn slot_index(slot: VertexSlot) -> Option<usize> {
        match slot {
            VertexSlot::Position(i) => Some(i),
            VertexSlot::Normal(i) => Some(3 + i),
            VertexSlot::Texcoord(i) => Some(6 + i),
            VertexSlot::Ignored => None,
        }
    }

    /// Fan-triangulates one face; `corners` are validated vertex indices.
    fn push_face(&self, mesh: &mut Mesh, corners: &[u32]) {
        for i in 1..corners.len() - 1 {
            mesh.triangles.push(Triangle {
                v: [corners[0], corners[i], corners[i + 1]],
                material: 0,
            });
        }
    }

    fn check_index(&self, index: i64) -> Result<u32, String> {
        if index < 0 || index as usize >= self.vertex_count {
            Err(format!(
                "face vertex index {index} out of range (there are {} vertices)",
                self.vertex_count
            ))
        } else {
            Ok(index as u32)
        }
    }
}

fn is_face_list(property: &Property) -> bool {
    matches!(property, Property::List { name, .. } if name == "vertex_indices" || name == "vertex_index")
}

fn parse_ascii_body(
    context: &BodyContext,
    header: &Header,
    bytes: &[u8],
    mesh: &mut Mesh,
) -> Result<(), LoadError> {
    let path = context.path;
    let body = std::str::from_utf8(&bytes[header.body_start..]).map_err(|e| {
        let line = header.header_lines
            + 1
            + bytes[header.body_start..header.body_start + e.valid_up_to()]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
        LoadError::new(path, Some(line), "ASCII body is not valid text")
    })?;
    let mut lines = body
        .lines()
        .enumerate()
        .map(|(i, line)| (header.header_lines + 1 + i, line));
    let mut corners: Vec<u32> = Vec::with_capacity(16);
    let mut last_line = header.header_lines;
    for element in &header.elements {
        for instance in 0..element.count {
            let (number, line) = loop {
                match lines.next() {
                    Some((number, line)) if line.trim().is_empty() => last_line = number,
                    Some(found) => break found,
                    None => {
                        return Err(LoadError::new(
                            path,
                            Some(last_line + 1),
                            format!(
                                "unexpected end of file: '{}' element {} of {} missing",
                                element.name, instance, element.count
                            ),
                        ))
                    }
                }
            };
            last_line = number;
            let error = |reason: String| LoadError::new(path, Some(number), reason);
            let mut tokens = line.split_ascii_whitespace();
            let mut next = |what: &str| {
                tokens
                    .next()
                    .ok_or_else(|| error(format!("missing {what}")))
            };
            if element.name == "vertex" {
                let mut values = [0.0f32; 8];
                for (property, &slot) in element.properties.iter().zip(context.slots) {
                    match property {
                        Property::Scalar { name, .. } => {
                            let token = next(&format!("vertex property '{name}'"))?;
                            if let Some(index) = BodyContext::slot_index(slot) {
                                values[index] = token.parse::<f32>().map_err(|_| {
                                    error(format!(
                                        "vertex property '{name}': '{token}' is not a number"
                                    ))
                                })?;
                            }
                        }
                        Property::List { name, .. } => {
                            let count = next(&format!("count of list '{name}'"))?;
                            let count = count
                                .parse::<usize>()
                                .map_err(|_| error(format!("bad list count '{count}'")))?;
                            for _ in 0..count {
                                next(&format!("item of list '{name}'"))?;
                            }
                        }
                    }
                }
                context.push_vertex(mesh, &values).map_err(error)?;
            } else {
                for property in &element.properties {
                    match property {
                        Property::Scalar { name, .. } => {
                            next(&format!("property '{name}'"))?;
                        }
                        Property::List { name, .. } => {
                            let count_token = next(&format!("count of list '{name}'"))?;
                            let count = count_token
                                .parse::<usize>()
                                .map_err(|_| error(format!("bad list count '{count_token}'")))?;
                            let is_face = element.name == "face" && is_face_list(property);
                            corners.clear();
                            for _ in 0..count {
                                let token = next(&format!("item of list '{name}'"))?;
                                if is_face {
                                    let index = token.parse::<i64>().map_err(|_| {
                                        error(format!(
                                            "face vertex index '{token}' is not an integer"
                                        ))
                                    })?;
                                    corners.push(context.check_index(index).map_err(error)?);
                                }
                            }
                            if is_face {
                                if count < 3 {
                                    return Err(error(format!("face with {count} vertices")));
                                }
                                context.push_face(mesh, &corners);
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(())
}

/// A bounds-checked reader of big- or little-endian scalars.
struct BinaryCursor<'a, const BIG: bool> {
    data: &'a [u8],
    offset: usize,
}

impl<const BIG: bool> BinaryCursor<'_, BIG> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let bytes: [u8; N] = self
            .data
            .get(self.offset..self.offset + N)?
            .try_into()
            .ok()?;
        self.offset += N;
        Some(if BIG { bytes } else { reverse(bytes) })
    }

    /// Reads one scalar as f64 (exact for every PLY type).
    fn read(&mut self, ty: ScalarType) -> Option<f64> {
        // `take` yields big-endian byte order.
        Some(match ty {
            ScalarType::I8 => i8::from_be_bytes(self.take::<1>()?) as f64,
            ScalarType::U8 => u8::from_be_bytes(self.take::<1>()?) as f64,
            ScalarType::I16 => i16::from_be_bytes(self.take::<2>()?) as f64,
            ScalarType::U16 => u16::from_be_bytes(self.take::<2>()?) as f64,
            ScalarType::I32 => i32::from_be_bytes(self.take::<4>()?) as f64,
            ScalarType::U32 => u32::from_be_bytes(self.take::<4>()?) as f64,
            ScalarType::F32 => f32::from_be_bytes(self.take::<4>()?) as f64,
            ScalarType::F64 => f64::from_be_bytes(self.take::<8>()?),
        })
    }

    fn skip(&mut self, bytes: usize) -> Option<()> {
        let end = self.offset.checked_add(bytes)?;
        (end <= self.data.len()).then(|| self.offset = end)
    }
}

fn reverse<const N: usize>(mut bytes: [u8; N]) -> [u8; N] {
    bytes.reverse();
    bytes
}

fn parse_binary_body<const BIG: bool>(
    context: &BodyContext,
    header: &Header,
    bytes: &[u8],
    mesh: &mut Mesh,
) -> Result<(), LoadError> {
    let path = context.path;
    let mut cursor = BinaryCursor::<BIG> {
        data: bytes,
        offset: header.body_start,
    };
    let mut corners: Vec<u32> = Vec::with_capacity(16);
    for element in &header.elements {
        for instance in 0..element.count {
            let at = cursor.offset;
            let truncated = || {
                LoadError::new(
                    path,
                    None,
                    format!(
                        "unexpected end of data in '{}' element {} of {} (byte offset {})",
                        element.name, instance, element.count, at
                    ),
                )
            };
            let mut values = [0.0f32; 8];
            for (index, property) in element.properties.iter().enumerate() {
                match property {
                    Property::Scalar { ty, .. } => {
                        let slot = if element.name == "vertex" {
                            context.slots[index]
                        } else {
                            VertexSlot::Ignored
                        };
                        match BodyContext::slot_index(slot) {
                            Some(i) => values[i] = cursor.read(*ty).ok_or_else(truncated)? as f32,
                            None => cursor.skip(ty.size()).ok_or_else(truncated)?,
                        }
                    }
                    Property::List {
                        count_ty, item_ty, ..
                    } => {
                        let count = cursor.read(*count_ty).ok_or_else(truncated)?;
                        if count < 0.0 {
                            return Err(LoadError::new(
                                path,
                                None,
                                format!(
                                    "negative list count in '{}' element {instance}",
                                    element.name
                                ),
                            ));
                        }
                        let count = count as usize;
                        if element.name == "face" && is_face_list(property) {
                            if count < 3 {
                                return Err(LoadError::new(
                                    path,
                                    None,
                                    format!("face {instance} has {count} vertices"),
                                ));
                            }
                            corners.clear();
                            for _ in 0..count {
                                let index = cursor.read(*item_ty).ok_or_else(truncated)? as i64;
                                let index = context.check_index(index).map_err(|reason| {
                                    LoadError::new(path, None, format!("face {instance}: {reason}"))
                                })?;
                                corners.push(index);
                            }
                            context.push_face(mesh, &corners);
                        } else {
                            cursor
                                .skip(count.saturating_mul(item_ty.size()))
                                .ok_or_else(truncated)?;
                        }
                    }
                }
            }
            if element.name == "vertex" {
                context.push_vertex(mesh, &values).map_err(|reason| {
                    LoadError::new(path, None, format!("{reason} (byte offset {at})"))
                })?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII_SQUARE: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 5\n\
        property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 255\n1 0 0 255\n1 1 0 255\n0 1 0 255\n0.5 0.5 1 0\n4 0 1 2 3\n3 0 1 4\n";

    fn parse(bytes: &[u8]) -> Result<Scene, LoadError> {
        parse_ply(Path::new("/nowhere/test.ply"), bytes)
    }

    #[test]
    fn header_errors_name_their_line_and_comments_hold_any_bytes() {
        let latin1 = ASCII_SQUARE.replace("comment test", "comment caf\u{e9}");
        let latin1 = latin1.replace('\u{e9}', "\u{1}");
        let mut bytes = latin1.into_bytes();
        let at = bytes.iter().position(|&b| b == 1).unwrap();
        bytes[at] = 0xe9; // Latin-1, not UTF-8
        assert_eq!(parse(&bytes).unwrap().triangles.len(), 3);
        let cases = [
            (
                ASCII_SQUARE.replace(
                    "element face 2\nproperty list uchar int vertex_indices\n",
                    "",
                ),
                "/nowhere/test.ply:9: no 'face' element before end_header",
            ),
            (
                ASCII_SQUARE.replace("property float z\n", ""),
                "/nowhere/test.ply:4: vertex element lacks x, y or z",
            ),
            (
                ASCII_SQUARE.replace("format ascii 1.0\n", ""),
                "/nowhere/test.ply:10: header has no 'format' line before end_header",
            ),
            (
                ASCII_SQUARE.replace(
                    "list uchar int vertex_indices",
                    "list uchar float vertex_indices",
                ),
                "/nowhere/test.ply:9: face element has no integer 'vertex_indices' list",
            ),
        ];
        for (text, message) in cases {
            assert_eq!(parse(text.as_bytes()).unwrap_err().to_string(), message);
        }
        let mut bytes = ASCII_SQUARE
            .replace("property uchar red", "property uchar r\u{1}d")
            .into_bytes();
        let at = bytes.iter().position(|&b| b == 1).unwrap();
        bytes[at] = 0xe9;
        assert_eq!(
            parse(&bytes).unwrap_err().to_string(),
            "/nowhere/test.ply:8: header line is not text"
        );
    }

    #[test]
    fn ascii_quads_become_fans() {
        let scene = parse(ASCII_SQUARE.as_bytes()).unwrap();
        scene.validate().unwrap();
        assert_eq!(scene.positions.len(), 5);
        assert_eq!(
            scene.triangles.iter().map(|t| t.v).collect::<Vec<_>>(),
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]
        );
        assert!((scene.normals[2] - Vec3::Z).length() < 1e-6);
    }

    fn binary_square(big: bool) -> Vec<u8> {
        let format = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut data = format!(
            "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty double extra\n\
             element face 1\nproperty list int uint vertex_index\nproperty uchar flags\nend_header\n"
        )
        .into_bytes();
        let mut put = |bytes: &[u8]| {
            if big {
                data.extend(bytes.iter().rev())
            } else {
                data.extend(bytes)
            }
        };
        for p in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for x in p {
                put(&x.to_le_bytes());
            }
            for x in [0.0f32, 0.0, 1.0] {
                put(&x.to_le_bytes());
            }
            put(&7.5f64.to_le_bytes());
        }
        put(&4i32.to_le_bytes());
        for i in [3u32, 2, 1, 0] {
            put(&i.to_le_bytes());
        }
        put(&[9u8]);
        data
    }

    #[test]
    fn binary_both_endiannesses() {
        for big in [false, true] {
            let scene = parse(&binary_square(big)).unwrap();
            assert_eq!(scene.positions[2], Vec3::new(1.0, 1.0, 0.0));
            assert_eq!(scene.normals[0], Vec3::Z);
            assert_eq!(
                scene.triangles.iter().map(|t| t.v).collect::<Vec<_>>(),
                vec![[3, 2, 1], [3, 1, 0]]
            );
        }
    }

    #[test]
    fn truncated_binary_fails_cleanly() {
        let data = binary_square(false);
        for cut in [data.len() - 1, data.len() - 10, data.len() - 60] {
            let err = parse(&data[..cut]).unwrap_err();
            // Cut into the faces' lists: found while reading; cut into the vertices: the
            // declared counts no longer fit, found before reading.
            assert!(
                err.reason.contains("unexpected end of data")
                    || err.reason.contains("body bytes can hold at most"),
                "{err}"
            );
        }
    }

    #[test]
    fn huge_declared_counts_fail_before_reserving() {
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
            property float x\nproperty float y\nproperty float z\nelement face 1\n\
            property list uchar int vertex_indices\nend_header\n0123456789";
        let err = parse(text.as_bytes()).unwrap_err();
        assert_eq!(
            err.reason,
            "header declares 4000000000 'vertex' elements but the 10 body bytes can hold at most 0"
        );
        let ascii = ASCII_SQUARE.replace("element face 2", "element face 99999999999");
        let err = parse(ascii.as_bytes()).unwrap_err();
        assert!(err.reason.contains("99999999999 'face' elements"), "{err}");
        let empty = ASCII_SQUARE.replace("element face 2", "element edge 5\nelement face 2");
        let err = parse(empty.as_bytes()).unwrap_err();
        assert_eq!(
            err.reason,
            "element 'edge' has 5 instances but no properties"
        );
    }

    #[test]
    fn non_finite_and_huge_vertices_are_refused_with_the_line() {
        let inf = ASCII_SQUARE.replace("1 1 0 255", "1 inf 0 255");
        let err = parse(inf.as_bytes()).unwrap_err();
        assert_eq!(err.line, Some(14), "{err}");
        assert_eq!(err.reason, "vertex 2 is not finite (1, inf, 0)");
        let nan = ASCII_SQUARE.replace("0 1 0 255", "0 1 NaN 255");
        assert!(parse(nan.as_bytes())
            .unwrap_err()
            .reason
            .contains("not finite"));
        let huge = ASCII_SQUARE.replace("0 1 0 255", "0 1e30 0 255");
        let err = parse(huge.as_bytes()).unwrap_err();
        assert!(
            err.reason.contains("exceeds the largest coordinate"),
            "{err}"
        );
        // Binary: a double that overflows single precision.
        let mut data = binary_square(false);
        let header_end = data.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        data[header_end..header_end + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
        let err = parse(&data).unwrap_err();
        assert!(
            err.reason.starts_with("vertex 0 is not finite (inf, 0, 0)"),
            "{err}"
        );
    }

    #[test]
    fn broken_ascii_files_name_line_and_reason() {
        let truncated = &ASCII_SQUARE[..ASCII_SQUARE.len() - 8];
        let err = parse(truncated.as_bytes()).unwrap_err();
        assert_eq!(err.line, Some(18), "{err}");
        assert!(
            err.reason.contains("end of file") || err.reason.contains("missing"),
            "{err}"
        );

        let bad_index = ASCII_SQUARE.replace("3 0 1 4", "3 0 1 5");
        let err = parse(bad_index.as_bytes()).unwrap_err();
        assert_eq!(err.line, Some(18), "{err}");
        assert!(err.reason.contains("out of range"), "{err}");
        assert!(
            err.to_string().starts_with("/nowhere/test.ply:18:"),
            "{err}"
        );

        let non_numeric = ASCII_SQUARE.replace("1 1 0 255", "1 one 0 255");
        let err = parse(non_numeric.as_bytes()).unwrap_err();
        assert_eq!(err.line, Some(14), "{err}");
        assert!(err.reason.contains("not a number"), "{err}");

        let err =
            parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").unwrap_err();
        assert!(err.reason.contains("end_header"), "{err}");
        let err = parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty floot x\nend_header\n")
            .unwrap_err();
        assert_eq!(err.line, Some(4), "{err}");
        let two_corners = ASCII_SQUARE.replace("3 0 1 4", "2 0 1");
        assert!(parse(two_corners.as_bytes())
            .unwrap_err()
            .reason
            .contains("2 vertices"));
    }
}
