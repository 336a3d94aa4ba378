//! Wavefront OBJ, read with `tobj` (faces triangulated as fans, one index per
//! vertex so `vn` normals line up with positions), materials from `mtllib`
//! files read by [`super::mtl`]. The whole file becomes ONE mesh (every
//! object and group; per-triangle materials) placed once, untransformed.
//!
//! `tobj` reports errors without a line; [`locate`] finds the line by
//! scanning the text again (only on the error path).

use super::common::{self, Ctx, Mat, Parts};
use super::{mtl, Instance, MeshData, ModelError};
use std::cell::RefCell;
use std::collections::HashSet;
use std::path::Path;

/// What a quick pass over the text finds before `tobj` runs.
#[derive(Default)]
struct Scan {
    /// `v`, `vt` and `vn` statements.
    counts: [usize; 3],
    faces: u64,
    lines_and_points: u64,
    free_form: bool,
    /// Smoothing groups other than `s off` / `s 0`.
    smoothing: bool,
    usemtl: Vec<String>,
    /// `f` lines with a negative (relative) or very long index, whose
    /// arithmetic in tobj can overflow: (line, its text, counts so far).
    unusual: Vec<(usize, String, [usize; 3])>,
}

fn scan(bytes: &[u8]) -> Scan {
    let mut s = Scan::default();
    let mut seen = HashSet::new();
    for (i, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let line = line.trim_ascii();
        let end = line
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(line.len());
        match &line[..end] {
            b"v" => s.counts[0] += 1,
            b"vt" => s.counts[1] += 1,
            b"vn" => s.counts[2] += 1,
            b"f" => {
                s.faces += 1;
                let long = line
                    .split(|b| !b.is_ascii_digit())
                    .any(|run| run.len() > 15);
                if long || line.contains(&b'-') {
                    s.unusual
                        .push((i + 1, String::from_utf8_lossy(line).into_owned(), s.counts));
                }
            }
            b"l" | b"p" => s.lines_and_points += 1,
            b"curv" | b"curv2" | b"surf" | b"cstype" | b"vp" => s.free_form = true,
            b"s" => s.smoothing |= !matches!(line[end..].trim_ascii(), b"off" | b"0" | b""),
            b"usemtl" => {
                let name = String::from_utf8_lossy(line[end..].trim_ascii()).into_owned();
                if seen.insert(name.clone()) {
                    s.usemtl.push(name);
                }
            }
            _ => {}
        }
    }
    s
}

const KINDS: [(&str, &str); 3] = [
    ("vertex", "vertices"),
    ("texture coordinate", "texture coordinates"),
    ("normal", "normals"),
];

/// The references of an `f` (or `l`) statement checked as tobj resolves
/// them: `Err` when one is not a reference, `Ok(Some(why))` when one is out
/// of range (`vt` and `vn` only where the file has some, as tobj checks).
fn face_refs(
    key: &str,
    args: &[&str],
    counts: [usize; 3],
    totals: [usize; 3],
) -> Result<Option<String>, String> {
    for word in args {
        let parts: Vec<&str> = word.split('/').collect();
        let not_ref =
            || format!("{key}: {word:?} is not a vertex reference (v, v/vt, v//vn or v/vt/vn)");
        if parts.len() > 3 {
            return Err(not_ref());
        }
        for (slot, part) in parts.iter().enumerate().filter(|(_, p)| !p.is_empty()) {
            let resolved = resolve(part, counts[slot], totals[slot]).map_err(|_| not_ref())?;
            if resolved.is_none() && (slot == 0 || totals[slot] > 0) {
                let (one, many) = KINDS[slot];
                return Ok(Some(format!(
                    "face: {one} index {part} out of range ({} {many})",
                    totals[slot]
                )));
            }
        }
    }
    Ok(None)
}

/// Reads an OBJ. `dir` is the file's directory (`None` for an upload, whose
/// `mtllib` cannot be followed).
pub(super) fn load(ctx: &mut Ctx, bytes: &[u8], dir: Option<&Path>) -> Result<Parts, ModelError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        ctx.err_at(format!("line {line}"), "not UTF-8 text")
    })?;
    let scan = scan(bytes);
    ctx.check_vertices(scan.counts[0] as u64, None)?;
    ctx.check_triangles(scan.faces, None)?;
    for (line, text, counts) in &scan.unusual {
        let args: Vec<&str> = text.split_whitespace().skip(1).collect();
        if let Ok(Some(why)) = face_refs("f", &args, *counts, scan.counts) {
            return Err(ctx.err_at(format!("line {line}"), why));
        }
    }

    let libs: RefCell<Vec<mtl::MtlMaterial>> = RefCell::new(Vec::new());
    let notes: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let mtl_error: RefCell<Option<ModelError>> = RefCell::new(None);
    let loader = |lib: &Path| -> tobj::MTLLoadResult {
        let shown = lib.display().to_string();
        let Some(dir) = dir else {
            notes.borrow_mut().push(format!(
                "mtllib {shown:?}: an upload cannot refer to other files: its materials fall back to the default"
            ));
            return Err(tobj::LoadError::OpenFileFailed);
        };
        // `mtllib a.mtl b.mtl` names two files; `tobj` passes the whole rest.
        let whole = dir.join(lib);
        let names: Vec<String> = if whole.is_file() || !shown.contains(char::is_whitespace) {
            vec![shown.clone()]
        } else {
            shown.split_whitespace().map(str::to_owned).collect()
        };
        let mut found = Vec::new();
        for name in names {
            if Path::new(&name).is_absolute() || name.contains("://") {
                notes.borrow_mut().push(format!(
                    "mtllib {name:?}: only paths relative to the OBJ file are followed: its materials fall back to the default"
                ));
                continue;
            }
            let text = match std::fs::read(dir.join(&name)) {
                Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
                Err(e) => {
                    notes.borrow_mut().push(format!(
                        "mtllib {name:?}: cannot be read ({e}): its materials fall back to the default"
                    ));
                    continue;
                }
            };
            match mtl::parse(&text) {
                Ok(mats) => found.extend(mats),
                Err(e) => {
                    mtl_error.borrow_mut().get_or_insert(ModelError {
                        file: ctx.file.clone(),
                        location: Some(format!("{name}: line {}", e.line)),
                        reason: e.reason,
                    });
                    return Err(tobj::LoadError::MaterialParseError);
                }
            }
        }
        // tobj maps `usemtl` names to indices into the concatenation of what
        // the loader returns; `libs` is that same concatenation.
        let map = found
            .iter()
            .enumerate()
            .map(|(i, m)| (m.name.clone(), i))
            .collect();
        let stubs = found
            .iter()
            .map(|m| tobj::Material {
                name: m.name.clone(),
                ..Default::default()
            })
            .collect();
        libs.borrow_mut().extend(found);
        Ok((stubs, map))
    };

    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let result = tobj::load_obj_buf(&mut text.as_bytes(), &options, loader);
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    for note in notes.into_inner() {
        ctx.warn(note);
    }
    let (models, _) = result.map_err(|e| match locate(text, &e) {
        Some((line, reason)) => ctx.err_at(format!("line {line}"), reason),
        None => ctx.err(e.to_string()),
    })?;

    let libs = libs.into_inner();
    let mut materials: Vec<Mat> = libs.iter().map(mtl::to_material).collect();
    let loaded: HashSet<&str> = libs.iter().map(|m| m.name.as_str()).collect();
    for name in &scan.usemtl {
        if !loaded.contains(name.as_str()) {
            ctx.warn(format!(
                "usemtl {name:?}: no material of that name was loaded: default material"
            ));
        }
    }
    if scan.lines_and_points > 0 {
        ctx.warn(format!(
            "{} line and point statements (l, p) ignored",
            scan.lines_and_points
        ));
    }
    if scan.free_form {
        ctx.warn("free-form curves and surfaces (curv, surf) ignored");
    }

    let default_material = materials.len();
    let mut mesh = MeshData {
        name: ctx.stem(),
        ..Default::default()
    };
    let mut normals = Vec::new();
    let (mut with_normals, mut without_normals) = (0usize, 0usize);
    // `vt` coordinates, v flipped to glTF's top-left origin.
    let mut uvs: Vec<[f32; 2]> = Vec::new();
    let mut untyped = 0usize;
    for model in &models {
        let m = &model.mesh;
        let offset = mesh.positions.len() as u32;
        u32::try_from(mesh.positions.len() + m.positions.len() / 3)
            .map_err(|_| ctx.err("too many vertices"))?;
        ctx.check_vertices((mesh.positions.len() + m.positions.len() / 3) as u64, None)?;
        ctx.check_triangles((mesh.triangles.len() + m.indices.len() / 3) as u64, None)?;
        mesh.positions
            .extend(m.positions.chunks_exact(3).map(|p| [p[0], p[1], p[2]]));
        if !m.positions.is_empty() && m.normals.len() == m.positions.len() {
            normals.extend(m.normals.chunks_exact(3).map(|n| [n[0], n[1], n[2]]));
            with_normals += 1;
        } else {
            without_normals += 1;
        }
        if !m.positions.is_empty() && m.texcoords.len() / 2 == m.positions.len() / 3 {
            uvs.resize(mesh.positions.len() - m.positions.len() / 3, [0.0; 2]);
            uvs.extend(m.texcoords.chunks_exact(2).map(|t| [t[0], 1.0 - t[1]]));
        }
        if !m.vertex_color.is_empty() {
            ctx.warn("vertex colours ignored");
        }
        let material = match m.material_id {
            Some(id) if id < default_material => id as u32,
            _ => {
                untyped += m.indices.len() / 3;
                default_material as u32
            }
        };
        for t in m.indices.chunks_exact(3) {
            mesh.triangles
                .push([t[0] + offset, t[1] + offset, t[2] + offset]);
            mesh.materials.push(material);
        }
    }
    if untyped > 0 {
        materials.push(Mat::default_diffuse("default"));
        ctx.warn(format!(
            "{untyped} triangles have no material: default diffuse (albedo {})",
            common::DEFAULT_ALBEDO
        ));
    }

    if let Some(v) = common::first_non_finite(&mesh.positions) {
        let bad = mesh.positions[v];
        return Err(match find_vertex_line(text, bad) {
            Some((line, k)) => ctx.err_at(
                format!("line {line}"),
                format!(
                    "vertex {k}: position {} is not finite",
                    common::fmt3(bad.map(f64::from))
                ),
            ),
            None => ctx.err(format!(
                "a vertex position {} is not finite",
                common::fmt3(bad.map(f64::from))
            )),
        });
    }
    mesh.normals = match (with_normals, without_normals) {
        (0, _) => {
            if scan.smoothing {
                ctx.warn(
                    "smoothing groups (s) ignored: without vn normals the mesh is flat shaded",
                );
            }
            None
        }
        (_, 0) => common::clean_normals(ctx, &mesh.name, normals, mesh.positions.len()),
        _ => {
            ctx.warn(format!(
                "mesh {:?}: some faces have no vn normals: normals dropped (flat shading)",
                mesh.name
            ));
            None
        }
    };
    // Maps of the materials some triangle uses (the others are dropped).
    let mut used = vec![false; libs.len()];
    for &m in &mesh.materials {
        if let Some(u) = used.get_mut(m as usize) {
            *u = true;
        }
    }
    let images = super::obj_maps::read(ctx, &libs, &mut materials, dir, &used)?;
    let textured = |m: &Mat| !m.maps.is_empty();
    if !uvs.is_empty() {
        uvs.resize(mesh.positions.len(), [0.0; 2]);
        if uvs.iter().flatten().any(|x| !x.is_finite()) {
            return Err(ctx.err("a vt texture coordinate is not finite"));
        }
        mesh.uvs[0] = Some(uvs);
        if materials.iter().any(|m| m.maps.normal.is_some())
            && !super::tangents::generate(&mut mesh, 0)
        {
            ctx.warn("normal maps without usable vt coordinates: not applied");
        }
    } else if materials.iter().any(textured) {
        ctx.warn("texture maps without vt coordinates read one texel everywhere");
    }
    Ok(Parts {
        meshes: vec![mesh],
        materials,
        instances: vec![Instance {
            mesh: 0,
            transform: common::IDENTITY,
        }],
        camera: None,
        images,
    })
}

/// Parses `v` arguments as tobj does (f32; `x y z [w]` or `x y z r g b`).
fn vertex(args: &[&str]) -> Result<[f32; 3], String> {
    let mut p = [0f32; 3];
    for (k, slot) in p.iter_mut().enumerate() {
        let word = args.get(k).ok_or("v: expected three numbers x y z")?;
        *slot = word
            .parse()
            .map_err(|_| format!("v: {word:?} is not a number"))?;
    }
    match args.len() {
        3 | 6 => Ok(p),
        4 => {
            let w: f32 = args[3]
                .parse()
                .map_err(|_| format!("v: w {:?} is not a number", args[3]))?;
            if w == 0.0 {
                return Err("v: w is 0".to_owned());
            }
            Ok(p.map(|x| x / w))
        }
        _ => Err("v: expected x y z, x y z w, or x y z r g b".to_owned()),
    }
}

/// The line and 1-based number of the `v` statement that gives `bad`
/// (bit for bit), else of the first one that is not finite.
fn find_vertex_line(text: &str, bad: [f32; 3]) -> Option<(usize, usize)> {
    let mut k = 0;
    let mut first = None;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        k += 1;
        let args: Vec<&str> = words.collect();
        let Ok(p) = vertex(&args) else { continue };
        if p.map(f32::to_bits) == bad.map(f32::to_bits) {
            return Some((i + 1, k));
        }
        if first.is_none() && !p.iter().all(|x| x.is_finite()) {
            first = Some((i + 1, k));
        }
    }
    first
}

/// Resolves one OBJ index (1-based, or negative: relative to `so_far`)
/// against `total`, as tobj does; `None` when out of range.
fn resolve(word: &str, so_far: usize, total: usize) -> Result<Option<usize>, ()> {
    let x: isize = word.parse().map_err(|_| ())?;
    let i = if x < 0 { so_far as isize + x } else { x - 1 };
    Ok(usize::try_from(i).ok().filter(|&i| i < total))
}

/// The line of the statement that makes tobj fail with `e`, and why.
pub(super) fn locate(text: &str, e: &tobj::LoadError) -> Option<(usize, String)> {
    use tobj::LoadError as E;
    let mut totals = [0usize; 3];
    for line in text.lines() {
        match line.split_whitespace().next() {
            Some("v") => totals[0] += 1,
            Some("vt") => totals[1] += 1,
            Some("vn") => totals[2] += 1,
            _ => {}
        }
    }
    let mut counts = [0usize; 3];
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next();
        let args: Vec<&str> = words.collect();
        let found = |reason: String| Some((i + 1, reason));
        match key {
            Some("v") => {
                counts[0] += 1;
                if matches!(
                    e,
                    E::PositionParseError | E::ScalingByZeroError | E::ColorParseError
                ) {
                    if let Err(reason) = vertex(&args) {
                        return found(reason);
                    }
                }
            }
            Some(k @ ("vt" | "vn")) => {
                let (slot, n, err) = if k == "vt" {
                    (1, 2, E::TexcoordParseError)
                } else {
                    (2, 3, E::NormalParseError)
                };
                counts[slot] += 1;
                let ok = args.len() >= n && args[..n].iter().all(|w| w.parse::<f32>().is_ok());
                if *e == err && !ok {
                    return found(format!("{k}: expected {n} numbers"));
                }
            }
            Some(k @ ("f" | "l")) => {
                match face_refs(k, &args, counts, totals) {
                    Err(why) => return found(why),
                    Ok(Some(why)) if k == "f" && !matches!(e, E::FaceParseError) => {
                        return found(why)
                    }
                    _ => {}
                }
                if k == "f" && args.is_empty() && matches!(e, E::InvalidPolygon) {
                    return found("f: a face without vertices".to_owned());
                }
            }
            Some("usemtl") if args.is_empty() && matches!(e, E::MaterialParseError) => {
                return found("usemtl without a name".to_owned());
            }
            _ => {}
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use crate::model::Material;
    use crate::model::{load_bytes, Limits};

    fn err(text: &str) -> String {
        match load_bytes(text.as_bytes(), "t.obj", &Limits::default()) {
            Ok(_) => panic!("{text:?} loads"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn errors_name_the_line() {
        let head = "# test\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert_eq!(
            err(&format!("{head}f 1 2 9\n")),
            "t.obj: line 5: face: vertex index 9 out of range (3 vertices)"
        );
        assert_eq!(
            err(&format!("{head}f 1 2 -4\n")),
            "t.obj: line 5: face: vertex index -4 out of range (3 vertices)"
        );
        assert_eq!(
            err(&format!("{head}f 0 1 2\n")),
            "t.obj: line 5: face: vertex index 0 out of range (3 vertices)"
        );
        assert_eq!(
            err(&format!("{head}f 1 2 x\n")),
            "t.obj: line 5: f: \"x\" is not a vertex reference (v, v/vt, v//vn or v/vt/vn)"
        );
        assert_eq!(
            err(&format!("{head}vn 0 0 1\nf 1//1 2//1 3//2\n")),
            "t.obj: line 6: face: normal index 2 out of range (1 normals)"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0\nf 1 1 1\n"),
            "t.obj: line 2: v: expected three numbers x y z"
        );
        assert_eq!(err("v 0 0 0\nv 1 0 0 0\n"), "t.obj: line 2: v: w is 0");
        assert_eq!(
            err("v 0 0 0\nvn 1 0\n"),
            "t.obj: line 2: vn: expected 3 numbers"
        );
        assert_eq!(
            err("v 0 0 0\nv nan 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 4\nf 2 3 4\n"),
            "t.obj: line 2: vertex 2: position [NaN, 0, 0] is not finite"
        );
        assert_eq!(
            err("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n"),
            "t.obj: line 2: vertex 2: position [inf, 0, 0] is not finite"
        );
        assert_eq!(
            err("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n"),
            "t.obj: no triangles"
        );
        // Indices whose arithmetic overflows in tobj are caught first.
        assert_eq!(
            err(&format!("{head}vt 0 0\nf 1/1 2/1 3/9223372036854775807\n")),
            "t.obj: line 6: face: texture coordinate index 9223372036854775807 out of range (1 texture coordinates)"
        );
        assert_eq!(
            err(&format!(
                "{head}vn 0 0 1\nf 1//1 2//1 3//-9223372036854775807\n"
            )),
            "t.obj: line 6: face: normal index -9223372036854775807 out of range (1 normals)"
        );
        let e = load_bytes(b"v 0 0 0\n\xff\n", "t.obj", &Limits::default()).expect_err("not text");
        assert_eq!(e.to_string(), "t.obj: line 2: not UTF-8 text");
    }

    #[test]
    fn polygons_shared_vertices_and_relative_indices() {
        // A pentagon (fan), and a triangle by relative indices sharing vertices.
        let text =
            "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\ns 1\nf 1 2 3 4 5\nf -5 -4 -1\np 1\n";
        let m = load_bytes(text.as_bytes(), "pent.obj", &Limits::default()).expect("loads");
        let mesh = &m.meshes[0];
        assert_eq!(mesh.name, "pent");
        assert_eq!(
            mesh.positions,
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 1.0, 0.0],
                [1.0, 2.0, 0.0],
                [0.0, 1.0, 0.0]
            ]
        );
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 1, 4]]
        );
        assert_eq!(mesh.normals, None);
        assert_eq!(mesh.materials, vec![0; 4]);
        assert_eq!(
            m.materials,
            vec![(
                "default".to_owned(),
                Material::Diffuse {
                    albedo: [0.8; 3],
                    emission: None
                },
                crate::model::Maps::default()
            )]
        );
        assert_eq!(
            m.warnings,
            vec![
                "1 line and point statements (l, p) ignored",
                "4 triangles have no material: default diffuse (albedo 0.8)",
                "smoothing groups (s) ignored: without vn normals the mesh is flat shaded",
            ]
        );
    }

    #[test]
    fn limits_are_checked_before_reading() {
        let limits = Limits {
            max_vertices: 2,
            max_triangles: 10,
            ..Limits::default()
        };
        let e = load_bytes(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "t.obj", &limits)
            .expect_err("over the limit");
        assert_eq!(e.to_string(), "t.obj: 3 vertices, more than the limit of 2");
    }
}
