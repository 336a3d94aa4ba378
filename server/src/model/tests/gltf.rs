//! glTF: one document (three meshes, a 2-level node hierarchy, a mesh used
//! by two nodes, cameras, every material rule) written three ways, and cut
//! short (`gltf_variants.rs` has the variants of a one-triangle document).

use super::{assert_guarantees, cube, untextured};
use crate::model::write_glb::{pack as glb, Bin};
use crate::model::Material;
use crate::model::{load_bytes, load_file, Instance, Limits, MeshData, Model, ModelCamera};
use base64::Engine;
use serde_json::{json, Value};
use std::f32::consts::FRAC_1_SQRT_2;

impl Bin {
    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
    }
    fn vec3(&mut self, v: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let min = [0, 1, 2].map(|k| v.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
        let max = [0, 1, 2].map(|k| v.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max));
        self.accessor(json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": "VEC3", "min": min, "max": max}))
    }
    fn indices(&mut self, idx: &[u32], component: u32) -> usize {
        let bytes: Vec<u8> = match component {
            5121 => idx.iter().map(|&i| i as u8).collect(),
            5123 => idx.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
            _ => idx.iter().flat_map(|&i| i.to_le_bytes()).collect(),
        };
        let view = self.view(&bytes);
        self.accessor(json!({"bufferView": view, "componentType": component, "count": idx.len(), "type": "SCALAR"}))
    }
}

const STRIP: [[f32; 3]; 5] = [
    [0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [2.0, 0.0, 0.0],
];
const FAN: [[f32; 3]; 5] = [
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.5, 1.0, 1.0],
    [0.5, 1.5, 1.0],
    [-0.5, 1.0, 1.0],
];
pub(super) const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// The scene document (without `buffers`) and its binary data.
fn scene() -> (Value, Vec<u8>) {
    let g = cube();
    let (tris, mats) = g.triangles();
    let mut b = Bin::default();
    // Mesh 0, the cube: sides indexed (u16), top and bottom unrolled.
    let p0 = b.vec3(&g.positions[..16]);
    let n0 = b.vec3(&g.normals[..16]);
    let side: Vec<u32> = tris
        .iter()
        .zip(&mats)
        .filter(|(_, &m)| m == 0)
        .flat_map(|(t, _)| *t)
        .collect();
    let i0 = b.indices(&side, 5123);
    let caps: Vec<u32> = tris
        .iter()
        .zip(&mats)
        .filter(|(_, &m)| m == 1)
        .flat_map(|(t, _)| *t)
        .collect();
    let p1 = b.vec3(
        &caps
            .iter()
            .map(|&i| g.positions[i as usize])
            .collect::<Vec<_>>(),
    );
    let n1 = b.vec3(
        &caps
            .iter()
            .map(|&i| g.normals[i as usize])
            .collect::<Vec<_>>(),
    );
    // Mesh 1: a strip (u32 indices), a fan from a sparse accessor, points, lines.
    let s = b.vec3(&STRIP);
    let si = b.indices(&[0, 1, 2, 3, 4], 5125);
    let fan_idx = b.view(&[0, 1, 2, 3, 4]);
    let fan_val = b.view(
        &FAN.iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect::<Vec<_>>(),
    );
    let f = b.accessor(json!({"componentType": 5126, "count": 5, "type": "VEC3",
        "sparse": {"count": 5, "indices": {"bufferView": fan_idx, "componentType": 5121},
                   "values": {"bufferView": fan_val}}}));
    // Mesh 2: one shared triangle, four materials.
    let t = b.vec3(&TRI);
    let tri_prims: Vec<Value> = (2..6)
        .map(|m| json!({"attributes": {"POSITION": t}, "material": m}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0", "generator": "pathstream tests"},
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength",
                           "KHR_lights_punctual", "KHR_materials_clearcoat", "KHR_materials_sheen"],
        "extensionsRequired": ["KHR_materials_sheen"],
        "scene": 0,
        "scenes": [{"nodes": [0, 4, 6, 7]}, {"nodes": [8]}],
        "nodes": [
            {"name": "root", "translation": [10, 0, 0], "children": [1, 2, 5]},
            {"name": "cubeA", "mesh": 0, "scale": [2, 2, 2]},
            {"name": "cubeB", "mesh": 0, "rotation": [0, FRAC_1_SQRT_2, 0, FRAC_1_SQRT_2], "children": [3]},
            {"name": "strips", "mesh": 1, "translation": [0, 0, 1]},
            {"name": "tri", "mesh": 2, "matrix": [1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, 5, 0, 1]},
            {"name": "eye", "translation": [0, 1, 5], "rotation": [0, FRAC_1_SQRT_2, 0, FRAC_1_SQRT_2], "camera": 0},
            {"name": "ortho", "camera": 1},
            {"name": "eye2", "camera": 0},
            {"name": "elsewhere", "mesh": 2}
        ],
        "cameras": [
            {"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}},
            {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "zfar": 10, "znear": 0.1}}
        ],
        "meshes": [
            {"name": "cube", "primitives": [
                {"attributes": {"POSITION": p0, "NORMAL": n0}, "indices": i0, "material": 0},
                {"attributes": {"POSITION": p1, "NORMAL": n1}, "material": 1}
            ]},
            {"name": "strips", "primitives": [
                {"attributes": {"POSITION": s}, "indices": si, "mode": 5},
                {"attributes": {"POSITION": f}, "mode": 6},
                {"attributes": {"POSITION": s}, "mode": 0},
                {"attributes": {"POSITION": s}, "indices": si, "mode": 1}
            ]},
            {"primitives": tri_prims}
        ],
        "materials": [
            {"name": "paint", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 1}},
            {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.4},
                "KHR_materials_volume": {"thicknessFactor": 1, "attenuationDistance": 2, "attenuationColor": [0.5, 0.5, 0.5]}}},
            {"name": "chrome", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicFactor": 1, "roughnessFactor": 0}},
            {"name": "lamp", "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
             "emissiveFactor": [1, 0.5, 0.25], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}}},
            {"name": "paint", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0.5,
             "roughnessFactor": 0.5, "baseColorTexture": {"index": 0}}, "normalTexture": {"index": 0}, "alphaMode": "BLEND"},
            {"name": "partial", "pbrMetallicRoughness": {"baseColorFactor": [2, 0.5, 0.5, 1], "metallicFactor": 0, "roughnessFactor": 0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.5},
                "KHR_materials_clearcoat": {"clearcoatFactor": 0.5, "clearcoatRoughnessFactor": 0.2,
                    "clearcoatTexture": {"index": 0}, "clearcoatNormalTexture": {"index": 0, "scale": 0.5}},
                "KHR_materials_specular": {"specularFactor": 0.5, "specularColorFactor": [1, 0.5, 0.25],
                    "specularTexture": {"index": 0, "texCoord": 1}, "specularColorTexture": {"index": 9}}}},
            {"name": "unused", "emissiveTexture": {"index": 0}}
        ],
        "textures": [{"source": 0}],
        "images": [{"uri": grey_png_uri()}],
        "accessors": b.accessors,
        "bufferViews": b.views,
    });
    (doc, b.data)
}

/// A 1x1 grey PNG as a `data:` URI.
fn grey_png_uri() -> String {
    let mut png = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut png),
        &[128, 128, 255, 255],
        1,
        1,
        image::ExtendedColorType::Rgba8,
    )
    .expect("png");
    format!(
        "data:image/png;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(png)
    )
}

fn with_buffer(mut doc: Value, len: usize, uri: Option<String>) -> Value {
    doc["buffers"] = match uri {
        Some(uri) => json!([{"byteLength": len, "uri": uri}]),
        None => json!([{"byteLength": len}]),
    };
    doc
}

fn diffuse(albedo: [f64; 3], emission: Option<[f64; 3]>) -> Material {
    Material::Diffuse { albedo, emission }
}

/// glTF's metallic-roughness model with the default ior and no emission.
pub(super) fn pbr(base_color: [f64; 3], metallic: f64, roughness: f64) -> Material {
    Material::Pbr {
        base_color,
        metallic,
        roughness,
        ior: 1.5,
        transmission: 0.0,
        thin: false,
        attenuation: None,
        clearcoat: 0.0,
        clearcoat_roughness: 0.0,
        specular: 1.0,
        specular_color: [1.0; 3],
        emission: None,
    }
}

/// What every encoding of [`scene`] must load as.
fn expected() -> Model {
    let g = cube();
    let (tris, mats) = g.triangles();
    let side: Vec<[u32; 3]> = tris
        .iter()
        .zip(&mats)
        .filter(|(_, &m)| m == 0)
        .map(|(t, _)| *t)
        .collect();
    let caps: Vec<u32> = tris
        .iter()
        .zip(&mats)
        .filter(|(_, &m)| m == 1)
        .flat_map(|(t, _)| *t)
        .collect();
    let mut cube_mesh = MeshData {
        name: "cube".into(),
        positions: g.positions[..16].to_vec(),
        normals: Some(g.normals[..16].to_vec()),
        triangles: side,
        materials: vec![0; 8],
        ..MeshData::default()
    };
    cube_mesh
        .positions
        .extend(caps.iter().map(|&i| g.positions[i as usize]));
    if let Some(n) = cube_mesh.normals.as_mut() {
        n.extend(caps.iter().map(|&i| g.normals[i as usize]));
    }
    cube_mesh
        .triangles
        .extend((0..4).map(|t| [16 + 3 * t, 17 + 3 * t, 18 + 3 * t]));
    cube_mesh.materials.extend([1; 4]);
    let strips = MeshData {
        name: "strips".into(),
        positions: STRIP.iter().chain(&FAN).copied().collect(),
        normals: None,
        triangles: vec![
            [0, 1, 2],
            [1, 3, 2],
            [2, 3, 4],
            [5, 6, 7],
            [5, 7, 8],
            [5, 8, 9],
        ],
        materials: vec![2; 6],
        ..MeshData::default()
    };
    let tri = MeshData {
        name: "mesh2".into(),
        positions: TRI.repeat(4),
        normals: None,
        triangles: (0..4).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        materials: vec![3, 4, 5, 6],
        ..MeshData::default()
    };
    // The volume's absorption: half of the light left after 2 units.
    let glass = |ior, albedo| Material::Glass {
        ior,
        albedo: Some(albedo),
        attenuation: Some(crate::model::Attenuation {
            color: [0.5; 3],
            distance: 2.0,
        }),
        emission: None,
    };
    let r = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]];
    let rt = |t: [f64; 3]| [0, 1, 2].map(|i| [r[i][0], r[i][1], r[i][2], t[i]]);
    let mut model = Model {
        meshes: vec![cube_mesh, strips, tri],
        materials: untextured([
            ("paint", diffuse([0.8, 0.2, 0.1], None)),
            ("glass", glass(1.4, [1.0; 3])),
            ("default", diffuse([1.0; 3], None)),
            ("chrome", Material::Mirror { albedo: [0.9; 3], emission: None }),
            ("lamp", diffuse([0.0; 3], Some([4.0, 2.0, 1.0]))),
            ("paint-2", pbr([0.5; 3], 0.5, 0.5)),
            // Half transmission: rough glass's share of the dielectric
            // (at roughness 0 a near-mirror lobe), no longer whole glass.
            (
                "partial",
                Material::Pbr {
                    base_color: [1.0, 0.5, 0.5],
                    metallic: 0.0,
                    roughness: 0.0,
                    ior: 1.5,
                    transmission: 0.5,
                    // No KHR_materials_volume: a thin wall.
                    thin: true,
                    attenuation: None,
                    clearcoat: 0.5,
                    clearcoat_roughness: 0.2,
                    specular: 0.5,
                    specular_color: [1.0, 0.5, 0.25],
                    emission: None,
                },
            ),
        ]),
        images: vec![crate::model::Image {
            name: "images[0]".into(),
            width: 1,
            height: 1,
            rgba: vec![128, 128, 255, 255],
        }],
        instances: vec![
            Instance {
                mesh: 0,
                transform: [[2.0, 0.0, 0.0, 10.0], [0.0, 2.0, 0.0, 0.0], [0.0, 0.0, 2.0, 0.0]],
            },
            Instance {
                mesh: 0,
                transform: rt([10.0, 0.0, 0.0]),
            },
            Instance {
                mesh: 1,
                transform: rt([11.0, 0.0, 0.0]),
            },
            Instance {
                mesh: 2,
                transform: [[1.0, 0.0, 0.0, 0.0], [0.0, 2.0, 0.0, 5.0], [0.0, 0.0, 1.0, 0.0]],
            },
        ],
        camera: Some(ModelCamera {
            position: [10.0, 1.0, 5.0],
            look_at: [9.0, 1.0, 5.0],
            up: [0.0, 1.0, 0.0],
            vfov_deg: 0.8f64.to_degrees(),
            ortho_height: None,
        }),
        warnings: [
            "KHR_lights_punctual: lights ignored",
            "extension KHR_materials_sheen not supported: ignored",
            "1 other scenes ignored (scene 0 is read)",
            "2 more cameras ignored (the first one is used)",
            "primitives without a material use the glTF default material: white diffuse (albedo 1)",
            "meshes[1].primitives[2] (mesh \"strips\"): POINTS primitive skipped (only triangles are rendered)",
            "meshes[1].primitives[3] (mesh \"strips\"): LINES primitive skipped (only triangles are rendered)",
            "mesh \"mesh2\": a normal map without TEXCOORD_0 to orient it: the map is not applied",
            "material \"partial\": specular colour texture: texture 9 does not exist: not rendered",
            "material \"partial\": base colour [2, 0.5, 0.5] is outside [0, 1]: clamped to [1, 0.5, 0.5]",
        ]
        .map(str::to_owned)
        .to_vec(),
    };
    // paint-2's base colour and normal maps read the one image (mesh2 has no
    // UVs to orient the normal map: no tangents, as the warning says); it
    // is alpha-blended by its base colour texture's alpha.
    let plain = Some(crate::model::TextureRef::plain(0));
    model.materials[5].2 = crate::model::Maps {
        base_color: plain,
        normal: plain,
        alpha_mode: crate::model::AlphaMode::Blend,
        ..Default::default()
    };
    // partial's clear coat (its own normal map too) and specular textures
    // (its specular colour texture names no texture: a warning).
    model.materials[6].2 = crate::model::Maps {
        clearcoat: plain,
        clearcoat_normal: plain,
        clearcoat_normal_scale: 0.5,
        specular: Some(crate::model::TextureRef {
            uv: 1,
            ..crate::model::TextureRef::plain(0)
        }),
        ..Default::default()
    };
    model
}

/// Compares exactly, except transforms and the camera (rotations from a
/// quaternion in f32): within 1e-12.
fn assert_model(got: &Model, want: &Model) {
    assert_guarantees(got);
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12)
    };
    assert_eq!(got.instances.len(), want.instances.len());
    for (g, w) in got.instances.iter().zip(&want.instances) {
        assert_eq!(g.mesh, w.mesh);
        assert!(
            close(g.transform.as_flattened(), w.transform.as_flattened()),
            "{g:?} != {w:?}"
        );
    }
    let (gc, wc) = (got.camera.expect("camera"), want.camera.expect("camera"));
    let flat = |c: ModelCamera| [c.position, c.look_at, c.up].concat();
    assert!(close(&flat(gc), &flat(wc)), "{gc:?} != {wc:?}");
    assert_eq!(gc.vfov_deg, wc.vfov_deg);
    let strip = |m: &Model| Model {
        instances: vec![],
        camera: None,
        ..m.clone()
    };
    assert_eq!(strip(got), strip(want));
}

#[test]
fn gltf_with_a_data_uri_loads_exactly() {
    let (doc, bin) = scene();
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let text = serde_json::to_vec(&with_buffer(doc, bin.len(), Some(uri))).expect("json");
    let m = load_bytes(&text, "scene.gltf", &Limits::default()).expect("loads");
    assert_model(&m, &expected());
    // Told by its content: the name does not matter.
    assert_eq!(load_bytes(&text, "upload", &Limits::default()), Ok(m));
}

#[test]
fn gltf_with_an_external_bin_loads_exactly_from_a_file_only() {
    let (doc, bin) = scene();
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("scene data.bin"), &bin).expect("write");
    let text = serde_json::to_vec(&with_buffer(
        doc,
        bin.len(),
        Some("scene%20data.bin".into()),
    ))
    .expect("json");
    let path = dir.path().join("scene.gltf");
    std::fs::write(&path, &text).expect("write");
    assert_model(
        &load_file(&path, &Limits::default()).expect("loads"),
        &expected(),
    );
    let e = load_bytes(&text, "scene.gltf", &Limits::default()).expect_err("an upload");
    assert_eq!(
        e.to_string(),
        "scene.gltf: buffers[0]: refers to the external file \"scene%20data.bin\", which an upload cannot include: upload a .glb instead (or embed the buffer as a data: URI)"
    );
    std::fs::remove_file(dir.path().join("scene data.bin")).expect("rm");
    let e = load_file(&path, &Limits::default()).expect_err("no bin");
    assert!(
        e.to_string()
            .contains("buffers[0]: cannot read \"scene data.bin\": "),
        "{e}"
    );
}

#[test]
fn glb_loads_exactly() {
    let (doc, bin) = scene();
    let bytes = glb(&with_buffer(doc, bin.len(), None), &bin);
    let m = load_bytes(&bytes, "scene.glb", &Limits::default()).expect("loads");
    assert_model(&m, &expected());
}

#[test]
fn truncated_glb() {
    let (doc, bin) = scene();
    let mut bytes = glb(&with_buffer(doc, bin.len(), None), &bin);
    let n = bytes.len();
    let e = load_bytes(&bytes[..n - 10], "s.glb", &Limits::default()).expect_err("cut");
    assert_eq!(
        e.to_string(),
        format!(
            "s.glb: byte 8: truncated: the GLB header says {n} bytes, the file has {}",
            n - 10
        )
    );
    // The header fixed to the cut length: the BIN chunk is cut.
    bytes.truncate(n - 10);
    bytes[8..12].copy_from_slice(&((n - 10) as u32).to_le_bytes());
    let json_len = u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize;
    let e = load_bytes(&bytes, "s.glb", &Limits::default()).expect_err("cut");
    let bin_len = bin.len().div_ceil(4) * 4;
    assert_eq!(
        e.to_string(),
        format!(
            "s.glb: byte {}: truncated: chunk 1 says {bin_len} bytes, {} remain",
            20 + json_len,
            bin_len - 10
        )
    );
    bytes[4] = 1;
    let e = load_bytes(&bytes, "s.glb", &Limits::default()).expect_err("v1");
    assert_eq!(
        e.to_string(),
        "s.glb: byte 4: GLB version 1 (only version 2 is read)"
    );
}
