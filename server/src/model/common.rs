//! What every loader shares: the reading context (file name, limits,
//! warnings), material value checks, mesh validation, fan triangulation, and
//! [`finish`], which turns a loader's [`Parts`] into a [`Model`] that keeps
//! the guarantees of the module doc.

use super::{Image, Maps, Material};
use super::{Instance, Limits, MeshData, Model, ModelCamera, ModelError};
use std::collections::HashSet;

/// Albedo of the material given to faces that name none (OBJ, PLY).
pub(super) const DEFAULT_ALBEDO: f64 = 0.8;
/// Index of refraction of glass whose file gives none (or an unusable one).
pub(super) const DEFAULT_IOR: f64 = 1.5;
/// Largest index of refraction the scene accepts.
pub(super) const MAX_IOR: f64 = 10.0;

pub(super) const IDENTITY: [[f64; 4]; 3] = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];

/// The file being read: its name for messages, the limits, the warnings.
pub(super) struct Ctx {
    pub file: String,
    pub limits: Limits,
    warnings: Vec<String>,
    seen: HashSet<String>,
    /// Texels of the images decoded so far.
    texels: u64,
}

impl Ctx {
    pub fn new(file: &str, limits: &Limits) -> Self {
        Self {
            file: file.to_owned(),
            limits: *limits,
            warnings: Vec::new(),
            seen: HashSet::new(),
            texels: 0,
        }
    }

    /// Counts `n` more texels; an error if the images then exceed the limit.
    pub fn charge_texels(&mut self, n: u64, location: &str) -> Result<(), ModelError> {
        self.texels = self.texels.saturating_add(n);
        if self.texels > self.limits.max_texels {
            return Err(self.err_at(
                location,
                format!(
                    "images of {} texels in all, more than the limit of {}",
                    self.texels, self.limits.max_texels
                ),
            ));
        }
        Ok(())
    }

    /// Records a warning once (later duplicates are dropped).
    pub fn warn(&mut self, line: impl Into<String>) {
        let line = line.into();
        if self.seen.insert(line.clone()) {
            self.warnings.push(line);
        }
    }

    pub fn err(&self, reason: impl Into<String>) -> ModelError {
        ModelError {
            file: self.file.clone(),
            location: None,
            reason: reason.into(),
        }
    }

    pub fn err_at(&self, location: impl Into<String>, reason: impl Into<String>) -> ModelError {
        ModelError {
            file: self.file.clone(),
            location: Some(location.into()),
            reason: reason.into(),
        }
    }

    /// An error if `n` vertices are more than the limit.
    pub fn check_vertices(&self, n: u64, location: Option<&str>) -> Result<(), ModelError> {
        if n > self.limits.max_vertices {
            let reason = format!(
                "{n} vertices, more than the limit of {}",
                self.limits.max_vertices
            );
            return Err(match location {
                Some(l) => self.err_at(l, reason),
                None => self.err(reason),
            });
        }
        Ok(())
    }

    /// An error if `n` triangles are more than the limit.
    pub fn check_triangles(&self, n: u64, location: Option<&str>) -> Result<(), ModelError> {
        if n > self.limits.max_triangles {
            let reason = format!(
                "{n} triangles, more than the limit of {}",
                self.limits.max_triangles
            );
            return Err(match location {
                Some(l) => self.err_at(l, reason),
                None => self.err(reason),
            });
        }
        Ok(())
    }

    /// The file's name without directories and extension (a mesh's name for
    /// formats that name none).
    pub fn stem(&self) -> String {
        std::path::Path::new(&self.file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "mesh".to_owned())
    }
}

/// A material as a loader found it, before names are made unique.
#[derive(Clone, Debug)]
pub(super) struct Mat {
    pub name: String,
    pub json: Material,
    pub maps: Maps,
    /// What the file asks of this material that is not modelled, each a
    /// clause; [`finish`] prefixes the material's (final) name. Only the
    /// notes of materials that some triangle uses become warnings.
    pub notes: Vec<String>,
}

impl Mat {
    /// The default: diffuse, albedo [`DEFAULT_ALBEDO`].
    pub fn default_diffuse(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            json: Material::Diffuse {
                albedo: [DEFAULT_ALBEDO; 3],
                emission: None,
            },
            maps: Maps::default(),
            notes: Vec::new(),
        }
    }
}

/// What a loader hands to [`finish`].
#[derive(Default)]
pub(super) struct Parts {
    pub meshes: Vec<MeshData>,
    pub materials: Vec<Mat>,
    pub instances: Vec<Instance>,
    pub camera: Option<ModelCamera>,
    pub images: Vec<Image>,
}

/// An f32 as the f64 of its shortest decimal form (a file's 0.1 reads as
/// 0.1).
pub(super) fn widen(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::from(x))
}

/// An albedo in [0, 1]: components outside (or not numbers) are clamped
/// (NaN to 0) with a note.
pub(super) fn albedo(what: &str, c: [f64; 3], notes: &mut Vec<String>) -> [f64; 3] {
    let clamped = c.map(|x| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) });
    if clamped != c {
        notes.push(format!(
            "{what} {} is outside [0, 1]: clamped to {}",
            fmt3(c),
            fmt3(clamped)
        ));
    }
    clamped
}

/// An emission: `None` when black; negative or non-finite components become
/// 0 with a note.
pub(super) fn emission(what: &str, c: [f64; 3], notes: &mut Vec<String>) -> Option<[f64; 3]> {
    let fixed = c.map(|x| if x.is_finite() && x > 0.0 { x } else { 0.0 });
    if fixed != c && c.iter().any(|x| !(x.is_finite() && *x >= 0.0)) {
        notes.push(format!(
            "{what} {} is negative or not finite: those components are 0",
            fmt3(c)
        ));
    }
    (fixed != [0.0; 3]).then_some(fixed)
}

/// An index of refraction in [1, [`MAX_IOR`]]; [`DEFAULT_IOR`] with a note
/// when missing or outside.
pub(super) fn ior(what: &str, value: Option<f64>, notes: &mut Vec<String>) -> f64 {
    match value {
        Some(v) if (1.0..=MAX_IOR).contains(&v) => v,
        Some(v) => {
            notes.push(format!(
                "{what} {v} is not an index of refraction in [1, {MAX_IOR}]: ior {DEFAULT_IOR}"
            ));
            DEFAULT_IOR
        }
        None => {
            notes.push(format!("no {what}: ior {DEFAULT_IOR}"));
            DEFAULT_IOR
        }
    }
}

/// A factor in [0, 1] (roughness, metallic): clamped with a note when
/// outside, 0 with a note when not finite.
pub(super) fn unit(what: &str, v: f64, notes: &mut Vec<String>) -> f64 {
    if !v.is_finite() {
        notes.push(format!("{what} {v} is not finite: 0"));
        return 0.0;
    }
    let c = v.clamp(0.0, 1.0);
    if c != v {
        notes.push(format!("{what} {v} is outside [0, 1]: clamped to {c}"));
    }
    c
}

pub(super) fn fmt3(c: [f64; 3]) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

/// Triangulates a convex polygon as a fan around its first vertex:
/// (p0, p1, p2), (p0, p2, p3), ... Fewer than 3 vertices give nothing.
pub(super) fn fan(poly: &[u32], out: &mut Vec<[u32; 3]>) {
    if let Some((&first, rest)) = poly.split_first() {
        for pair in rest.windows(2) {
            out.push([first, pair[0], pair[1]]);
        }
    }
}

/// The first vertex with a coordinate that is not finite.
pub(super) fn first_non_finite(positions: &[[f32; 3]]) -> Option<usize> {
    positions
        .iter()
        .position(|p| !p.iter().all(|x| x.is_finite()))
}

/// The first triangle with an index `>= n`, and that index.
pub(super) fn first_bad_index(triangles: &[[u32; 3]], n: usize) -> Option<(usize, u32)> {
    triangles
        .iter()
        .enumerate()
        .find_map(|(t, tri)| tri.iter().find(|&&i| i as usize >= n).map(|&i| (t, i)))
}

/// Per-vertex normals, checked: `None` (with a warning naming the first bad
/// vertex) when their count differs from the positions' or one is zero or not
/// finite; otherwise normalised (those within 1e-6 of unit length are kept
/// as they are, so unit normals read back bit for bit).
pub(super) fn clean_normals(
    ctx: &mut Ctx,
    mesh: &str,
    normals: Vec<[f32; 3]>,
    n_positions: usize,
) -> Option<Vec<[f32; 3]>> {
    if normals.len() != n_positions {
        ctx.warn(format!(
            "mesh {mesh:?}: {} normals for {n_positions} vertices: normals dropped (flat shading)",
            normals.len()
        ));
        return None;
    }
    let mut normals = normals;
    for (i, n) in normals.iter_mut().enumerate() {
        let len2 = n.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>();
        if !len2.is_finite() || !n.iter().all(|x| x.is_finite()) || len2 == 0.0 {
            ctx.warn(format!(
                "mesh {mesh:?}: the normal of vertex {i} is {} (zero or not finite): the mesh's normals are dropped (flat shading)",
                fmt3(n.map(f64::from))
            ));
            return None;
        }
        if (len2 - 1.0).abs() > 2e-6 {
            let len = len2.sqrt();
            *n = n.map(|x| (f64::from(x) / len) as f32);
        }
    }
    Some(normals)
}

/// How many triangles have zero area (a repeated index, or collinear corners).
pub(super) fn degenerate_count(mesh: &MeshData) -> usize {
    let p = |i: u32| {
        mesh.positions
            .get(i as usize)
            .map(|v| v.map(f64::from))
            .unwrap_or_default()
    };
    mesh.triangles
        .iter()
        .filter(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            cross == [0.0; 3]
        })
        .count()
}

/// A name not yet in `used` (`name`, else `name-2`, `name-3`, ...), recorded.
fn unique(used: &mut HashSet<String>, name: &str) -> String {
    let name = if name.trim().is_empty() {
        "material"
    } else {
        name
    };
    let mut candidate = name.to_owned();
    let mut k = 2;
    while used.contains(&candidate) {
        candidate = format!("{name}-{k}");
        k += 1;
    }
    used.insert(candidate.clone());
    candidate
}

/// Checks a loader's parts and assembles the model: drops meshes without
/// triangles (with a warning) and materials no triangle uses, makes material
/// names unique, turns the used materials' notes into warnings, counts
/// degenerate triangles, and re-checks every guarantee of the module doc
/// (loaders check first, where they can name a line or an element).
pub(super) fn finish(mut ctx: Ctx, parts: Parts) -> Result<Model, ModelError> {
    let Parts {
        meshes,
        materials,
        instances,
        camera,
        images,
    } = parts;

    let total: u64 = meshes.iter().map(|m| m.triangles.len() as u64).sum();
    if total == 0 {
        return Err(ctx.err("no triangles"));
    }
    ctx.check_triangles(total, None)?;
    ctx.check_vertices(meshes.iter().map(|m| m.positions.len() as u64).sum(), None)?;

    // Meshes: keep those with triangles; check each.
    let mut mesh_map = vec![None; meshes.len()];
    let mut kept = Vec::with_capacity(meshes.len());
    for (i, mesh) in meshes.into_iter().enumerate() {
        if mesh.triangles.is_empty() {
            ctx.warn(format!("mesh {:?} has no triangles: skipped", mesh.name));
            continue;
        }
        let name = &mesh.name;
        if let Some(v) = first_non_finite(&mesh.positions) {
            return Err(ctx.err(format!("mesh {name:?}: vertex {v}: position is not finite")));
        }
        if let Some((t, index)) = first_bad_index(&mesh.triangles, mesh.positions.len()) {
            return Err(ctx.err(format!(
                "mesh {name:?}: triangle {t}: vertex index {index} out of range ({} vertices)",
                mesh.positions.len()
            )));
        }
        if mesh.materials.len() != mesh.triangles.len()
            || mesh
                .materials
                .iter()
                .any(|&m| m as usize >= materials.len())
        {
            return Err(ctx.err(format!(
                "mesh {name:?}: triangle materials do not match (a loader bug)"
            )));
        }
        if let Some(n) = &mesh.normals {
            let ok = n.len() == mesh.positions.len()
                && n.iter().all(|v| {
                    let l = v.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>();
                    (l - 1.0).abs() < 1e-5
                });
            if !ok {
                return Err(ctx.err(format!(
                    "mesh {name:?}: normals are not unit vectors (a loader bug)"
                )));
            }
        }
        let n = mesh.positions.len();
        let uvs_ok = mesh
            .uvs
            .iter()
            .flatten()
            .all(|u| u.len() == n && u.iter().flatten().all(|x| x.is_finite()));
        let tangents_ok = mesh
            .tangents
            .as_ref()
            .is_none_or(|t| t.len() == n && t.iter().flatten().all(|x| x.is_finite()));
        let colors_ok = (mesh.colors.as_ref())
            .is_none_or(|c| c.len() == n && c.iter().flatten().all(|x| (0.0..=1.0).contains(x)));
        if !uvs_ok || !tangents_ok || !colors_ok {
            return Err(ctx.err(format!(
                "mesh {name:?}: texture coordinates, tangents or colours do not match its vertices (a loader bug)"
            )));
        }
        let degenerate = degenerate_count(&mesh);
        if degenerate > 0 {
            ctx.warn(format!(
                "mesh {name:?}: {degenerate} of {} triangles have zero area (kept)",
                mesh.triangles.len()
            ));
        }
        mesh_map[i] = Some(kept.len());
        kept.push(mesh);
    }

    let image_count = images.len();
    let bad_image = (materials.iter())
        .flat_map(|m| m.maps.by_slot().into_iter().flatten())
        .any(|r| r.image >= image_count || r.uv > 1);
    if bad_image {
        return Err(ctx.err("a material refers to an image the model does not have (a loader bug)"));
    }

    // Materials: keep the used ones, in the loader's order; unique names.
    let mut used = vec![false; materials.len()];
    for m in kept.iter().flat_map(|m| m.materials.iter()) {
        used[*m as usize] = true;
    }
    let mut mat_map = vec![0u32; materials.len()];
    let mut names = HashSet::new();
    let mut out_materials = Vec::new();
    for (i, mat) in materials.into_iter().enumerate() {
        if !used[i] {
            continue;
        }
        let name = unique(&mut names, &mat.name);
        for note in &mat.notes {
            ctx.warn(format!("material {name:?}: {note}"));
        }
        mat_map[i] = out_materials.len() as u32;
        out_materials.push((name, mat.json, mat.maps));
    }
    for mesh in &mut kept {
        for m in &mut mesh.materials {
            *m = mat_map[*m as usize];
        }
    }

    let mut out_instances = Vec::with_capacity(instances.len());
    for inst in instances {
        let Some(mesh) = mesh_map.get(inst.mesh).copied().flatten() else {
            continue;
        };
        if !inst.transform.iter().flatten().all(|x| x.is_finite()) {
            return Err(ctx.err(format!(
                "an instance of mesh {:?} has a transform that is not finite",
                kept[mesh].name
            )));
        }
        out_instances.push(Instance { mesh, ..inst });
    }
    if out_instances.is_empty() {
        return Err(ctx.err("no triangles (no mesh is placed in the scene)"));
    }

    Ok(Model {
        meshes: kept,
        materials: out_materials,
        instances: out_instances,
        camera,
        images,
        warnings: ctx.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fan_triangulates_around_the_first_vertex() {
        let mut out = Vec::new();
        fan(&[7, 8, 9, 10, 11], &mut out);
        assert_eq!(out, vec![[7, 8, 9], [7, 9, 10], [7, 10, 11]]);
        out.clear();
        fan(&[1, 2], &mut out);
        fan(&[], &mut out);
        assert!(out.is_empty());
    }

    #[test]
    fn values_are_clamped_with_notes() {
        let mut notes = Vec::new();
        assert_eq!(
            albedo("Kd", [0.5, 1.5, f64::NAN], &mut notes),
            [0.5, 1.0, 0.0]
        );
        assert_eq!(albedo("Kd", [0.0, 0.5, 1.0], &mut notes), [0.0, 0.5, 1.0]);
        assert_eq!(emission("Ke", [0.0; 3], &mut notes), None);
        assert_eq!(
            emission("Ke", [2.0, -1.0, f64::INFINITY], &mut notes),
            Some([2.0, 0.0, 0.0])
        );
        assert_eq!(ior("Ni", Some(1.33), &mut notes), 1.33);
        assert_eq!(ior("Ni", Some(0.5), &mut notes), DEFAULT_IOR);
        assert_eq!(ior("Ni", None, &mut notes), DEFAULT_IOR);
        assert_eq!(
            notes,
            vec![
                "Kd [0.5, 1.5, NaN] is outside [0, 1]: clamped to [0.5, 1, 0]",
                "Ke [2, -1, inf] is negative or not finite: those components are 0",
                "Ni 0.5 is not an index of refraction in [1, 10]: ior 1.5",
                "no Ni: ior 1.5",
            ]
        );
    }

    #[test]
    fn normals_are_checked_and_normalised() {
        let mut ctx = Ctx::new("f", &Limits::default());
        let n = clean_normals(&mut ctx, "m", vec![[0.0, 0.0, 1.0], [0.0, 3.0, 4.0]], 2);
        assert_eq!(n, Some(vec![[0.0, 0.0, 1.0], [0.0, 0.6, 0.8]]));
        assert_eq!(
            clean_normals(&mut ctx, "m", vec![[0.0; 3], [1.0, 0.0, 0.0]], 2),
            None
        );
        assert_eq!(clean_normals(&mut ctx, "m", vec![[1.0, 0.0, 0.0]], 2), None);
        assert_eq!(
            ctx.warnings,
            vec![
                "mesh \"m\": the normal of vertex 0 is [0, 0, 0] (zero or not finite): the mesh's normals are dropped (flat shading)",
                "mesh \"m\": 1 normals for 2 vertices: normals dropped (flat shading)",
            ]
        );
    }

    #[test]
    fn names_are_made_unique() {
        let mut used = HashSet::new();
        assert_eq!(unique(&mut used, "a"), "a");
        assert_eq!(unique(&mut used, "a"), "a-2");
        assert_eq!(unique(&mut used, "a-2"), "a-2-2");
        assert_eq!(unique(&mut used, ""), "material");
    }
}
