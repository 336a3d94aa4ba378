//! glTF 2.0 (`.gltf` with `data:` URIs or external buffers, and `.glb`).
//!
//! - The default scene (else scene 0; with no scenes, every root node) is
//!   walked; each node holding a mesh is one [`Instance`] with the node's
//!   world transform (parent * child; TRS or matrix). A mesh used by several
//!   nodes is stored once.
//! - Each mesh is ONE [`MeshData`]: its TRIANGLES, TRIANGLE_STRIP and
//!   TRIANGLE_FAN primitives merged (indexed or not), per-triangle material;
//!   strips as the spec orders them, fans as (v0, vi, vi+1) (the spec's
//!   triangles, corners rotated); POINTS and LINES primitives are skipped
//!   with a warning. A mesh's normals are kept only if every primitive has
//!   them.
//! - Materials: transmission 1 with metallic and roughness 0 and a
//!   KHR_materials_volume thickness (a solid) -> glass, ior from
//!   KHR_materials_ior (1.5 when absent); metallic 1 and roughness 0 -> mirror, metallic 0 and
//!   roughness 1 (no transmission) -> diffuse (the renderer's exact
//!   corners); else the metallic-roughness model (`pbr`) with the file's
//!   factors, ior and transmission (rough glass: a thin wall without a
//!   volume thickness, as glTF defines). A solid's volume attenuation
//!   (colour and distance) is its Beer-Lambert absorption, on glass and
//!   `pbr` alike; a thickness texture is noted. The albedo is the base
//!   colour factor's rgb; emission is the emissive factor
//!   times KHR_materials_emissive_strength. Texture maps (`gltf_maps`):
//!   base colour, metallic-roughness, normal and emissive, the
//!   transmission, clear coat (weight and roughness) and specular (strength
//!   and colour) textures; `alphaMode` MASK and BLEND with the base
//!   colour's alpha (opaque where it is 1 everywhere); occlusion maps,
//!   thickness textures and the clear coat's normal map: noted.
//! - The first camera met in the walk (preorder), perspective or
//!   orthographic (its view 2 ymag tall), becomes the model's camera, in
//!   world space (it looks down -Z, +Y up, in its node's frame); the others
//!   are noted.
//!
//! f32 factors are widened to f64 by their shortest decimal form, so a
//! file's 0.1 reads as 0.1.

use super::common::{self, widen, Ctx, Parts};
use super::gltf_data::{self as data, Buffers};
use super::gltf_maps::Images;
use super::gltf_material::Materials;
use super::{Instance, MeshData, ModelCamera, ModelError};
use ::gltf::camera::Projection;
use ::gltf::mesh::{Mode, Semantic};
use ::gltf::scene::Transform;
use ::gltf::{Document, Node};
use std::path::Path;

type M4 = [[f64; 4]; 4];
const ID4: M4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// Extensions whose content is read.
const SUPPORTED: [&str; 8] = [
    "KHR_materials_clearcoat",
    "KHR_materials_specular",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_mesh_quantization",
];
/// Required extensions without which the geometry cannot be read.
const GEOMETRY: [&str; 2] = ["KHR_draco_mesh_compression", "EXT_meshopt_compression"];

/// Reads a `.gltf` (JSON) or `.glb` (binary). `dir` is the file's directory
/// (`None` for an upload, which cannot refer to external buffers).
pub(super) fn load(ctx: &mut Ctx, bytes: &[u8], dir: Option<&Path>) -> Result<Parts, ModelError> {
    let (json, bin) = if bytes.starts_with(b"glTF") {
        let glb = data::split_glb(ctx, bytes)?;
        (glb.json, glb.bin)
    } else {
        (bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes), None)
    };
    let doc = data::parse_document(ctx, json)?;
    for ext in doc.extensions_required() {
        if GEOMETRY.contains(&ext) {
            return Err(ctx.err_at(
                "extensionsRequired",
                format!("{ext} (compressed geometry) is not supported"),
            ));
        }
    }
    for ext in doc.extensions_used() {
        if ext == "KHR_lights_punctual" {
            ctx.warn("KHR_lights_punctual: lights ignored");
        } else if !SUPPORTED.contains(&ext) {
            ctx.warn(format!("extension {ext} not supported: ignored"));
        }
    }
    if doc.animations().len() > 0 {
        ctx.warn(format!(
            "{} animations ignored (the scene is read at rest)",
            doc.animations().len()
        ));
    }

    let (placed, camera) = walk(ctx, &doc)?;
    let mut bufs = Buffers::new(&doc, bin, dir);
    let mut ids: Vec<usize> = placed.iter().map(|p| p.0).collect();
    ids.sort_unstable();
    ids.dedup();
    let mut mesh_of = vec![0usize; doc.meshes().len()];
    let mut table = Materials {
        of: vec![None; doc.materials().len()],
        default: None,
        list: Vec::new(),
        images: Images::new(&doc),
    };
    let mut meshes = Vec::with_capacity(ids.len());
    let mut totals = (0u64, 0u64);
    for &id in &ids {
        let mesh = doc
            .meshes()
            .nth(id)
            .ok_or_else(|| ctx.err_at(format!("meshes[{id}]"), "no such mesh"))?;
        mesh_of[id] = meshes.len();
        meshes.push(read_mesh(ctx, &mut bufs, &mesh, &mut table, &mut totals)?);
    }
    let images = table.images.decode(ctx, &doc, &mut bufs)?;
    let instances = placed
        .into_iter()
        .map(|(id, m)| Instance {
            mesh: mesh_of[id],
            transform: [m[0], m[1], m[2]],
        })
        .collect();
    Ok(Parts {
        meshes,
        materials: table.list,
        instances,
        camera,
        images,
    })
}

fn mul(a: &M4, b: &M4) -> M4 {
    let mut out = [[0.0; 4]; 4];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, x) in row.iter_mut().enumerate() {
            *x = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    out
}

/// A node's local transform, row-major (a matrix's projective row is
/// ignored: glTF requires it to be 0 0 0 1).
fn local(t: Transform) -> M4 {
    match t {
        Transform::Matrix { matrix } => {
            let mut m = ID4;
            for (r, row) in m.iter_mut().take(3).enumerate() {
                for (c, x) in row.iter_mut().enumerate() {
                    *x = widen(matrix[c][r]);
                }
            }
            m
        }
        Transform::Decomposed {
            translation: t,
            rotation: q,
            scale: s,
        } => {
            let [x, y, z, w] = q.map(widen);
            let n = (x * x + y * y + z * z + w * w).sqrt();
            let (x, y, z, w) = (x / n, y / n, z / n, w / n);
            let r = [
                [
                    1.0 - 2.0 * (y * y + z * z),
                    2.0 * (x * y - z * w),
                    2.0 * (x * z + y * w),
                ],
                [
                    2.0 * (x * y + z * w),
                    1.0 - 2.0 * (x * x + z * z),
                    2.0 * (y * z - x * w),
                ],
                [
                    2.0 * (x * z - y * w),
                    2.0 * (y * z + x * w),
                    1.0 - 2.0 * (x * x + y * y),
                ],
            ];
            let (t, s) = (t.map(widen), s.map(widen));
            let mut m = ID4;
            for i in 0..3 {
                m[i] = [r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]];
            }
            m
        }
    }
}

/// Walks the scene's node hierarchy: (mesh, world transform) per node with a
/// mesh, in preorder, and the first perspective camera.
#[allow(clippy::type_complexity)]
fn walk(
    ctx: &mut Ctx,
    doc: &Document,
) -> Result<(Vec<(usize, M4)>, Option<ModelCamera>), ModelError> {
    let scenes = doc.scenes().len();
    let roots: Vec<Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => {
            if scenes > 1 {
                ctx.warn(format!(
                    "{} other scenes ignored (scene {} is read)",
                    scenes - 1,
                    scene.index()
                ));
            }
            scene.nodes().collect()
        }
        None => {
            let mut child = vec![false; doc.nodes().len()];
            for c in doc.nodes().flat_map(|n| n.children()) {
                child[c.index()] = true;
            }
            let roots: Vec<Node> = doc.nodes().filter(|n| !child[n.index()]).collect();
            if !roots.is_empty() {
                ctx.warn("no scene: every root node is placed");
            }
            roots
        }
    };
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(Node, M4)> = roots.into_iter().rev().map(|n| (n, ID4)).collect();
    let (mut placed, mut camera) = (Vec::new(), None);
    let (mut more_cameras, mut skinned) = (0, false);
    while let Some((node, parent)) = stack.pop() {
        let i = node.index();
        if std::mem::replace(&mut visited[i], true) {
            return Err(ctx.err_at(
                format!("nodes[{i}]"),
                "is reached twice in the scene's node hierarchy (a cycle, or a node with two parents)",
            ));
        }
        let world = mul(&parent, &local(node.transform()));
        if !world.iter().flatten().all(|x| x.is_finite()) {
            return Err(ctx.err_at(format!("nodes[{i}]"), "transform is not finite"));
        }
        if let Some(mesh) = node.mesh() {
            placed.push((mesh.index(), world));
            skinned |= node.skin().is_some();
        }
        if let Some(cam) = node.camera() {
            if camera.is_some() {
                more_cameras += 1;
            } else {
                let placed = match cam.projection() {
                    Projection::Perspective(p) => view(&world, widen(p.yfov()), None),
                    Projection::Orthographic(o) => {
                        view(&world, 40f64.to_radians(), Some(2.0 * widen(o.ymag())))
                    }
                };
                match placed {
                    Ok(c) => camera = Some(c),
                    Err(why) => ctx.warn(format!(
                        "cameras[{}] on nodes[{i}] ignored: {why}",
                        cam.index()
                    )),
                }
            }
        }
        let children: Vec<Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    if skinned {
        ctx.warn("skins ignored (skinned meshes are placed by their node's transform)");
    }
    if more_cameras > 0 {
        ctx.warn(format!(
            "{more_cameras} more cameras ignored (the first one is used)"
        ));
    }
    Ok((placed, camera))
}

/// A camera at `world`'s origin looking down its -Z, +Y up: perspective
/// (`yfov` radians), or orthographic `ortho_height` tall (in the node's
/// units, scaled by its transform along +Y).
fn view(world: &M4, yfov: f64, ortho_height: Option<f64>) -> Result<ModelCamera, String> {
    let position = [world[0][3], world[1][3], world[2][3]];
    let unit = |v: [f64; 3]| {
        let len = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        (len > 0.0 && len.is_finite()).then(|| v.map(|x| x / len))
    };
    let forward = unit([-world[0][2], -world[1][2], -world[2][2]])
        .ok_or("its node's transform has no view direction")?;
    let y_axis = [world[0][1], world[1][1], world[2][1]];
    let up = unit(y_axis).ok_or("its node's transform has no up direction")?;
    if !(yfov > 0.0 && yfov < std::f64::consts::PI) {
        return Err(format!("yfov {yfov} is not between 0 and pi"));
    }
    let scale = y_axis.iter().map(|x| x * x).sum::<f64>().sqrt();
    let ortho_height = match ortho_height {
        Some(h) if !(h > 0.0 && (h * scale).is_finite()) => {
            return Err(format!("ymag {} is not > 0", h / 2.0));
        }
        h => h.map(|h| h * scale),
    };
    Ok(ModelCamera {
        position,
        look_at: [0, 1, 2].map(|k| position[k] + forward[k]),
        up,
        vfov_deg: yfov.to_degrees(),
        ortho_height,
    })
}

/// Triangles of one primitive's vertex list; the count of indices left over.
fn triangles(mode: Mode, idx: &[u32], out: &mut Vec<[u32; 3]>) -> usize {
    match mode {
        Mode::TriangleStrip => {
            for i in 0..idx.len().saturating_sub(2) {
                out.push(if i % 2 == 0 {
                    [idx[i], idx[i + 1], idx[i + 2]]
                } else {
                    [idx[i], idx[i + 2], idx[i + 1]]
                });
            }
            0
        }
        Mode::TriangleFan => {
            common::fan(idx, out);
            0
        }
        _ => {
            out.extend(idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
            idx.len() % 3
        }
    }
}

fn read_mesh(
    ctx: &mut Ctx,
    bufs: &mut Buffers,
    mesh: &::gltf::Mesh,
    table: &mut Materials,
    totals: &mut (u64, u64),
) -> Result<MeshData, ModelError> {
    let mi = mesh.index();
    let name = mesh
        .name()
        .map(str::to_owned)
        .unwrap_or_else(|| format!("mesh{mi}"));
    let mut out = MeshData {
        name: name.clone(),
        ..Default::default()
    };
    let (mut normals, mut with_normals, mut without_normals) = (Vec::new(), 0, 0);
    let mut uvs: [Vec<[f32; 2]>; 2] = [Vec::new(), Vec::new()];
    let mut with_uvs = [0usize; 2];
    let (mut tangents, mut with_tangents) = (Vec::new(), 0usize);
    let (mut colors, mut with_colors) = (Vec::new(), 0usize);
    let mut primitives = 0usize;
    // The UV set of the first normal map that the mesh's materials use.
    let mut normal_uv = None;
    for prim in mesh.primitives() {
        let path = format!("meshes[{mi}].primitives[{}]", prim.index());
        let mode = prim.mode();
        if !matches!(
            mode,
            Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
        ) {
            let mode = match mode {
                Mode::Points => "POINTS",
                Mode::Lines => "LINES",
                Mode::LineLoop => "LINE_LOOP",
                _ => "LINE_STRIP",
            };
            ctx.warn(format!(
                "{path} (mesh {name:?}): {mode} primitive skipped (only triangles are rendered)"
            ));
            continue;
        }
        let Some(pos) = prim.get(&Semantic::Positions) else {
            ctx.warn(format!("{path} (mesh {name:?}): no POSITION: skipped"));
            continue;
        };
        if prim.morph_targets().len() > 0 {
            ctx.warn(format!(
                "mesh {name:?}: morph targets ignored (the base shape is used)"
            ));
        }
        let n = pos.count();
        ctx.check_vertices(totals.0 + n as u64, Some(&path))?;
        let positions = data::read_vec3(ctx, bufs, &pos, &format!("{path}.attributes.POSITION"))?;
        if let Some(v) = common::first_non_finite(&positions) {
            return Err(ctx.err_at(
                &path,
                format!(
                    "vertex {v}: position {} is not finite",
                    common::fmt3(positions[v].map(f64::from))
                ),
            ));
        }
        let vertex_count = u32::try_from(n).map_err(|_| ctx.err_at(&path, "too many vertices"))?;
        let indices = match prim.indices() {
            Some(acc) => {
                let most = match mode {
                    Mode::Triangles => acc.count() / 3,
                    _ => acc.count().saturating_sub(2),
                };
                ctx.check_triangles(totals.1 + most as u64, Some(&path))?;
                data::read_indices(ctx, bufs, &acc, &format!("{path}.indices"))?
            }
            None => (0..vertex_count).collect(),
        };
        let mut tris = Vec::new();
        let left = triangles(mode, &indices, &mut tris);
        if left > 0 {
            ctx.warn(format!(
                "{path} (mesh {name:?}): {left} indices after the last whole triangle ignored"
            ));
        }
        ctx.check_triangles(totals.1 + tris.len() as u64, Some(&path))?;
        if let Some((t, i)) = common::first_bad_index(&tris, n) {
            return Err(ctx.err_at(
                &path,
                format!("triangle {t}: vertex index {i} out of range ({n} vertices)"),
            ));
        }
        match prim.get(&Semantic::Normals) {
            Some(acc) if acc.count() == n => {
                normals.extend(data::read_vec3(
                    ctx,
                    bufs,
                    &acc,
                    &format!("{path}.attributes.NORMAL"),
                )?);
                with_normals += 1;
            }
            _ => without_normals += 1,
        }
        for (set, (uv, with)) in uvs.iter_mut().zip(&mut with_uvs).enumerate() {
            match prim.get(&Semantic::TexCoords(set as u32)) {
                Some(acc) if acc.count() == n => {
                    let at = format!("{path}.attributes.TEXCOORD_{set}");
                    uv.resize(out.positions.len(), [0.0; 2]);
                    uv.extend(data::read_vec2(ctx, bufs, &acc, &at)?);
                    *with += 1;
                }
                _ => {}
            }
        }
        if let Some(acc) = prim.get(&Semantic::Colors(0)).filter(|a| a.count() == n) {
            // Primitives without colours are white, as glTF defines.
            colors.resize(out.positions.len(), [1.0; 3]);
            colors.extend(vertex_colors(
                ctx,
                bufs,
                &acc,
                &format!("{path}.attributes.COLOR_0"),
            )?);
            with_colors += 1;
        }
        if let Some(acc) = prim.get(&Semantic::Tangents).filter(|a| a.count() == n) {
            let at = format!("{path}.attributes.TANGENT");
            tangents.resize(out.positions.len(), [0.0; 4]);
            tangents.extend(data::read_vec4(ctx, bufs, &acc, &at)?);
            with_tangents += 1;
        }
        primitives += 1;
        let material = table.index(ctx, &prim.material());
        if let Some(r) = &table.list[material as usize].maps.normal {
            normal_uv.get_or_insert(r.uv as usize);
        }
        let offset = out.positions.len() as u32;
        u32::try_from(out.positions.len() + n)
            .map_err(|_| ctx.err_at(&path, "too many vertices"))?;
        out.positions.extend(positions);
        out.triangles
            .extend(tris.iter().map(|t| t.map(|i| i + offset)));
        out.materials.resize(out.triangles.len(), material);
        *totals = (totals.0 + n as u64, totals.1 + tris.len() as u64);
    }
    let vertices = out.positions.len();
    for (set, (mut uv, with)) in uvs.into_iter().zip(with_uvs).enumerate() {
        if with > 0 {
            // Primitives without this set read texel (0, 0).
            uv.resize(vertices, [0.0; 2]);
            if let Some(i) = uv.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
                return Err(ctx.err_at(
                    format!("meshes[{mi}]"),
                    format!("TEXCOORD_{set} of vertex {i} is not finite"),
                ));
            }
            out.uvs[set] = Some(uv);
        }
    }
    if with_colors > 0 {
        colors.resize(vertices, [1.0; 3]);
        out.colors = Some(colors);
    }
    let tangents_ok = tangents.iter().all(|t| t.iter().all(|x| x.is_finite()));
    if with_tangents == primitives && primitives > 0 && tangents_ok {
        out.tangents = Some(tangents);
    } else if with_tangents > 0 {
        ctx.warn(format!(
            "mesh {name:?}: TANGENT missing on some primitives or not finite: tangents generated (MikkTSpace)"
        ));
    }
    out.normals = match (with_normals, without_normals) {
        (0, _) => None,
        (_, 0) => common::clean_normals(ctx, &name, normals, out.positions.len()),
        _ => {
            ctx.warn(format!(
                "mesh {name:?}: some primitives have no normals: normals dropped (flat shading)"
            ));
            None
        }
    };
    if let (None, Some(set)) = (&out.tangents, normal_uv) {
        if !super::tangents::generate(&mut out, set) {
            ctx.warn(format!(
                "mesh {name:?}: a normal map without TEXCOORD_{set} to orient it: the map is not applied"
            ));
        }
    }
    Ok(out)
}

/// COLOR_0 (VEC3 or VEC4, its alpha unused): linear RGB clamped to [0, 1];
/// a component that is not finite is an error naming the vertex.
fn vertex_colors(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &::gltf::Accessor,
    path: &str,
) -> Result<Vec<[f32; 3]>, ModelError> {
    let rgb = match acc.dimensions() {
        ::gltf::accessor::Dimensions::Vec4 => (data::read_vec4(ctx, bufs, acc, path)?.into_iter())
            .map(|[r, g, b, _]| [r, g, b])
            .collect(),
        _ => data::read_vec3(ctx, bufs, acc, path)?,
    };
    if let Some(i) = common::first_non_finite(&rgb) {
        return Err(ctx.err_at(path, format!("colour of vertex {i} is not finite")));
    }
    Ok(rgb
        .into_iter()
        .map(|c| c.map(|x| x.clamp(0.0, 1.0)))
        .collect())
}
