//! PLY (ASCII, binary little and big endian), read with `ply-rs-bw` one
//! element at a time (so errors name the element, and the line or byte).
//!
//! - `element vertex`: `x`, `y`, `z` (any numeric type), optional `nx`, `ny`,
//!   `nz`, optional colours `red`, `green`, `blue` (or `diffuse_red`, ...;
//!   integers as fractions of their type's largest value, floats as they
//!   are, all sRGB-encoded as scanners and MeshLab write them, decoded to
//!   linear and clamped to [0, 1]); other properties (alpha, uv, ...) are
//!   named in a warning.
//! - `element face`: a `vertex_indices` (or `vertex_index`) list of any
//!   integer type; polygons are fan-triangulated; faces of fewer than 3
//!   vertices are skipped with a warning.
//! - Other elements: skipped with a warning. The file has no materials: one
//!   default diffuse material (albedo 0.8; white where the vertices have
//!   colours, which then are the base colour), with a warning.
//! - Before anything is read, each element's count is checked against the
//!   limits and against the bytes left after the header (every element
//!   needs at least its fixed-size part in binary, two bytes per property in
//!   ASCII, a token and a separator).

use super::common::{self, Ctx, Mat, Parts};
use super::{Instance, MeshData, ModelError};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    BeginList, ElementDef, Encoding, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};
use std::io::{Cursor, ErrorKind};

/// A vertex as read: position, normal and colour components (missing
/// ones 0; the colour as a fraction, still sRGB-encoded).
#[derive(Default)]
struct Vertex {
    p: [f64; 3],
    n: [f64; 3],
    c: [f64; 3],
}

/// The colour properties, each channel's two spellings.
const COLOURS: [[&str; 2]; 3] = [
    ["red", "diffuse_red"],
    ["green", "diffuse_green"],
    ["blue", "diffuse_blue"],
];

impl Vertex {
    /// Property `name` = `v`; `full` is the value of a colour of 1 (an
    /// integer type's largest value, 1 for floats).
    fn set(&mut self, name: &str, v: f64, full: f64) -> PropertyAccessResult {
        let slot = match name {
            "x" => &mut self.p[0],
            "y" => &mut self.p[1],
            "z" => &mut self.p[2],
            "nx" => &mut self.n[0],
            "ny" => &mut self.n[1],
            "nz" => &mut self.n[2],
            _ => match COLOURS.iter().position(|c| c.contains(&name)) {
                Some(k) => {
                    self.c[k] = v / full;
                    return PropertyAccessResult::Set;
                }
                None => return PropertyAccessResult::Ignored,
            },
        };
        *slot = v;
        PropertyAccessResult::Set
    }
}

/// An sRGB-encoded fraction as linear light in [0, 1] (IEC 61966-2-1);
/// None where it is not finite.
fn linear(c: f64) -> Option<f32> {
    if !c.is_finite() {
        return None;
    }
    let c = c.clamp(0.0, 1.0);
    let l = if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    Some(l as f32)
}

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Self::default()
    }
    fn set_char(&mut self, name: &str, v: i8) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(i8::MAX))
    }
    fn set_uchar(&mut self, name: &str, v: u8) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(u8::MAX))
    }
    fn set_short(&mut self, name: &str, v: i16) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(i16::MAX))
    }
    fn set_ushort(&mut self, name: &str, v: u16) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(u16::MAX))
    }
    fn set_int(&mut self, name: &str, v: i32) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(i32::MAX))
    }
    fn set_uint(&mut self, name: &str, v: u32) -> PropertyAccessResult {
        self.set(name, v.into(), f64::from(u32::MAX))
    }
    fn set_float(&mut self, name: &str, v: f32) -> PropertyAccessResult {
        self.set(name, v.into(), 1.0)
    }
    fn set_double(&mut self, name: &str, v: f64) -> PropertyAccessResult {
        self.set(name, v, 1.0)
    }
}

fn is_index(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

/// A face as read: its index list, by the list's item type.
#[derive(Default)]
struct Face {
    unsigned: Vec<u32>,
    signed: Vec<i32>,
    small: Vec<i64>,
}

impl Face {
    /// The indices as u32; `Err` with the first negative one.
    fn indices(&self, out: &mut Vec<u32>) -> Result<(), i64> {
        out.clear();
        out.extend_from_slice(&self.unsigned);
        for &i in &self.signed {
            out.push(u32::try_from(i).map_err(|_| i64::from(i))?);
        }
        for &i in &self.small {
            out.push(u32::try_from(i).map_err(|_| i)?);
        }
        Ok(())
    }

    fn small(&mut self, name: &str, v: impl IntoIterator<Item = i64>) -> PropertyAccessResult {
        if !is_index(name) {
            return PropertyAccessResult::Ignored;
        }
        self.small = v.into_iter().collect();
        PropertyAccessResult::Set
    }
}

impl PropertyAccess for Face {
    fn new() -> Self {
        Self::default()
    }
    fn begin_list_uint(&mut self, name: &str, _len: usize) -> BeginList<'_, u32> {
        if is_index(name) {
            BeginList::Fill(&mut self.unsigned)
        } else {
            BeginList::UseSetter
        }
    }
    fn begin_list_int(&mut self, name: &str, _len: usize) -> BeginList<'_, i32> {
        if is_index(name) {
            BeginList::Fill(&mut self.signed)
        } else {
            BeginList::UseSetter
        }
    }
    fn set_list_char(&mut self, name: &str, v: Vec<i8>) -> PropertyAccessResult {
        self.small(name, v.into_iter().map(i64::from))
    }
    fn set_list_uchar(&mut self, name: &str, v: Vec<u8>) -> PropertyAccessResult {
        self.small(name, v.into_iter().map(i64::from))
    }
    fn set_list_short(&mut self, name: &str, v: Vec<i16>) -> PropertyAccessResult {
        self.small(name, v.into_iter().map(i64::from))
    }
    fn set_list_ushort(&mut self, name: &str, v: Vec<u16>) -> PropertyAccessResult {
        self.small(name, v.into_iter().map(i64::from))
    }
}

/// An element of no interest (read to step over it).
struct Skip;

impl PropertyAccess for Skip {
    fn new() -> Self {
        Skip
    }
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

enum Failed {
    Eof,
    Bad(String),
}

/// The payload, read element by element.
struct Src<'a> {
    cursor: Cursor<&'a [u8]>,
    encoding: Encoding,
    /// ASCII: the number of the last line read.
    line: usize,
}

impl Src<'_> {
    /// Reads one element; `Ok` and `Err` both carry where it starts.
    fn read<E: PropertyAccess>(
        &mut self,
        parser: &Parser<E>,
        def: &ElementDef,
    ) -> (String, Result<E, Failed>) {
        match self.encoding {
            Encoding::Ascii => {
                let bytes = *self.cursor.get_ref();
                let line = loop {
                    let pos = (self.cursor.position() as usize).min(bytes.len());
                    if pos >= bytes.len() {
                        return (format!("line {}", self.line + 1), Err(Failed::Eof));
                    }
                    let rest = &bytes[pos..];
                    let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
                    self.cursor.set_position((pos + end + 1) as u64);
                    self.line += 1;
                    let line = rest[..end].strip_suffix(b"\r").unwrap_or(&rest[..end]);
                    if !line.trim_ascii().is_empty() {
                        break line;
                    }
                };
                let at = format!("line {}", self.line);
                let Ok(text) = std::str::from_utf8(line) else {
                    return (at, Err(Failed::Bad("not text".to_owned())));
                };
                let r = parser.read_ascii_element(text, def).map_err(|e| {
                    // The crate's message quotes the line, then "Error: why".
                    let msg = e.to_string();
                    let why = msg.rsplit("Error: ").next().unwrap_or(&msg);
                    Failed::Bad(format!("cannot read {:?} ({})", text.trim(), one_line(why)))
                });
                (at, r)
            }
            _ => {
                let at = format!("byte {}", self.cursor.position());
                let r = match self.encoding {
                    Encoding::BinaryBigEndian => {
                        parser.read_big_endian_element(&mut self.cursor, def)
                    }
                    _ => parser.read_little_endian_element(&mut self.cursor, def),
                };
                let r = r.map_err(|e| match e.kind() {
                    ErrorKind::UnexpectedEof => Failed::Eof,
                    _ => Failed::Bad(one_line(&e.to_string())),
                });
                (at, r)
            }
        }
    }
}

fn scalar_size(t: &ScalarType) -> u128 {
    match t {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    }
}

fn is_float(t: &ScalarType) -> bool {
    matches!(t, ScalarType::Float | ScalarType::Double)
}

/// Reads a PLY file.
pub(super) fn load(ctx: &mut Ctx, bytes: &[u8]) -> Result<Parts, ModelError> {
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Skip>::new()
        .read_header(&mut reader)
        .map_err(|e| {
            let text = e.to_string();
            let text = text
                .split_once(": ")
                .filter(|_| e.line().is_some())
                .map_or(text.as_str(), |(_, m)| m);
            let reason = format!("bad header: {}", one_line(text));
            match e.line() {
                Some(line) => ctx.err_at(format!("line {line}"), reason),
                None => ctx.err(reason),
            }
        })?;
    let payload = reader.get_ref().position() as usize;
    let header_lines = bytes[..payload.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    let binary = header.encoding != Encoding::Ascii;

    // What the header declares: checked before anything is read.
    let scalar = |def: &ElementDef, name: &str| matches!(def.properties.get(name), Some(p) if matches!(p.data_type, PropertyType::Scalar(_)));
    let (mut has_vertices, mut has_faces, mut has_normals) = (false, false, false);
    // Which spelling of the colours the vertices use, if they have all three.
    let mut colours: Option<usize> = None;
    let remaining = bytes.len().saturating_sub(payload) as u128;
    let mut need = 0u128;
    for (name, def) in &header.elements {
        let count = def.count as u64;
        match name.as_str() {
            "vertex" => {
                if !["x", "y", "z"].iter().all(|p| scalar(def, p)) {
                    return Err(ctx.err_at("header", "element vertex has no x, y and z properties"));
                }
                has_normals = ["nx", "ny", "nz"].iter().all(|p| scalar(def, p));
                colours = (0..2).find(|&k| COLOURS.iter().all(|c| scalar(def, c[k])));
                let colour = |p: &str| colours.is_some_and(|k| COLOURS.iter().any(|c| c[k] == p));
                let other: Vec<&str> = def
                    .properties
                    .keys()
                    .map(String::as_str)
                    .filter(|p| {
                        !(["x", "y", "z"].contains(p)
                            || has_normals && ["nx", "ny", "nz"].contains(p)
                            || colour(p))
                    })
                    .collect();
                if !other.is_empty() {
                    ctx.warn(format!("vertex properties ignored: {}", other.join(", ")));
                }
                ctx.check_vertices(count, Some("header: element vertex"))?;
                has_vertices = true;
            }
            "face" => {
                let index: Vec<_> = def
                    .properties
                    .values()
                    .filter(|p| is_index(&p.name))
                    .collect();
                let [prop] = index[..] else {
                    return Err(ctx.err_at(
                        "header",
                        "element face needs one vertex_indices (or vertex_index) list property",
                    ));
                };
                match &prop.data_type {
                    PropertyType::List(c, t) if !is_float(c) && !is_float(t) => {}
                    _ => {
                        return Err(ctx.err_at(
                            "header",
                            format!("face property {} is not a list of integers", prop.name),
                        ))
                    }
                }
                let other: Vec<&str> = def
                    .properties
                    .keys()
                    .map(String::as_str)
                    .filter(|p| !is_index(p))
                    .collect();
                if !other.is_empty() {
                    ctx.warn(format!("face properties ignored: {}", other.join(", ")));
                }
                ctx.check_triangles(count, Some("header: element face"))?;
                has_faces = true;
            }
            _ => {
                let most = ctx.limits.max_vertices.max(ctx.limits.max_triangles);
                if count > most {
                    return Err(ctx.err_at(
                        "header",
                        format!("element {name}: {count} entries, more than the limit of {most}"),
                    ));
                }
                ctx.warn(format!("element {name} ({count} entries) ignored"));
            }
        }
        let each: u128 = def
            .properties
            .values()
            .map(|p| match (&p.data_type, binary) {
                (PropertyType::Scalar(t) | PropertyType::List(t, _), true) => scalar_size(t),
                (_, false) => 2,
            })
            .sum();
        need += each * u128::from(count);
        // ASCII: the last line may lack its newline.
        if need > remaining + u128::from(!binary) {
            return Err(ctx.err_at(
                format!("byte {payload}"),
                format!(
                    "truncated (or a wrong count): element {name} with {count} entries needs at least {need} bytes after the header, the file has {remaining}"
                ),
            ));
        }
    }
    if !has_vertices || !has_faces {
        return Err(ctx.err("no triangles (the file needs a vertex and a face element)"));
    }

    let mut src = Src {
        cursor: Cursor::new(bytes),
        encoding: header.encoding,
        line: header_lines,
    };
    src.cursor.set_position(payload as u64);
    let mut mesh = MeshData {
        name: ctx.stem(),
        ..Default::default()
    };
    let mut normals = Vec::new();
    let mut colors = Vec::new();
    let mut vertices_read = false;
    let mut short_faces = 0usize;
    for (name, def) in &header.elements {
        let count = def.count;
        let fail = |ctx: &Ctx, at: String, i: usize, e: Failed| match e {
            Failed::Eof => ctx.err_at(
                at,
                format!("truncated: the file ends in {name} {i} of {count}"),
            ),
            Failed::Bad(why) => ctx.err_at(at, format!("{name} {i}: {why}")),
        };
        match name.as_str() {
            "vertex" => {
                let parser = Parser::<Vertex>::new();
                mesh.positions.reserve(count);
                for i in 0..count {
                    let (at, r) = src.read(&parser, def);
                    let v = r.map_err(|e| fail(ctx, at.clone(), i, e))?;
                    let p = v.p.map(|x| x as f32);
                    if !p.iter().all(|x| x.is_finite()) {
                        return Err(ctx.err_at(
                            at,
                            format!("vertex {i}: position {} is not finite", common::fmt3(v.p)),
                        ));
                    }
                    mesh.positions.push(p);
                    if has_normals {
                        normals.push(v.n.map(|x| x as f32));
                    }
                    if colours.is_some() {
                        let [Some(r), Some(g), Some(b)] = v.c.map(linear) else {
                            return Err(ctx.err_at(
                                at,
                                format!("vertex {i}: colour {} is not finite", common::fmt3(v.c)),
                            ));
                        };
                        colors.push([r, g, b]);
                    }
                }
                vertices_read = true;
            }
            "face" => {
                let parser = Parser::<Face>::new();
                let mut poly = Vec::new();
                for i in 0..count {
                    let (at, r) = src.read(&parser, def);
                    let face = r.map_err(|e| fail(ctx, at.clone(), i, e))?;
                    face.indices(&mut poly).map_err(|bad| {
                        ctx.err_at(
                            at.clone(),
                            format!("face {i}: vertex index {bad} out of range"),
                        )
                    })?;
                    if poly.len() < 3 {
                        short_faces += 1;
                        continue;
                    }
                    let n = mesh.positions.len();
                    if let Some(&bad) = poly.iter().find(|&&x| vertices_read && x as usize >= n) {
                        return Err(ctx.err_at(
                            at,
                            format!("face {i}: vertex index {bad} out of range ({n} vertices)"),
                        ));
                    }
                    ctx.check_triangles((mesh.triangles.len() + poly.len() - 2) as u64, Some(&at))?;
                    common::fan(&poly, &mut mesh.triangles);
                }
            }
            _ => {
                let parser = Parser::<Skip>::new();
                for i in 0..count {
                    let (at, r) = src.read(&parser, def);
                    r.map_err(|e| fail(ctx, at, i, e))?;
                }
            }
        }
    }
    if let Some((t, index)) = common::first_bad_index(&mesh.triangles, mesh.positions.len()) {
        return Err(ctx.err(format!(
            "triangle {t}: vertex index {index} out of range ({} vertices)",
            mesh.positions.len()
        )));
    }
    if short_faces > 0 {
        ctx.warn(format!(
            "{short_faces} faces with fewer than 3 vertices skipped"
        ));
    }
    mesh.materials = vec![0; mesh.triangles.len()];
    if has_normals {
        mesh.normals = common::clean_normals(ctx, &mesh.name, normals, mesh.positions.len());
    }
    let mut material = Mat::default_diffuse("default");
    if colours.is_some() {
        mesh.colors = Some(colors);
        material.json = super::Material::Diffuse {
            albedo: [1.0; 3],
            emission: None,
        };
        ctx.warn("no materials: white diffuse, coloured by the vertex colours");
    } else {
        ctx.warn(format!(
            "no materials: default diffuse (albedo {})",
            common::DEFAULT_ALBEDO
        ));
    }
    Ok(Parts {
        meshes: vec![mesh],
        materials: vec![material],
        instances: vec![Instance {
            mesh: 0,
            transform: common::IDENTITY,
        }],
        camera: None,
        images: Vec::new(),
    })
}
