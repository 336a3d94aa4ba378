//! A mesh and one material saved as a `.glb` (for tests and benchmarks of
//! textured models): positions, normals, both UV sets and tangents where the
//! mesh has them, and the material's metallic-roughness factors, emission
//! (`KHR_materials_emissive_strength` above 1) and textures (PNG, embedded in the binary chunk) with their samplers and
//! `KHR_texture_transform`. [`super::load_bytes`] reads it back.

use super::{MeshData, Wrap};
use serde_json::{json, Value};

/// The material written with the mesh.
#[derive(Clone, Debug)]
pub struct GlbMaterial {
    /// RGBA (alpha read where `alpha_mode` is MASK or BLEND).
    pub base_color: [f64; 4],
    /// glTF's `alphaMode` (`OPAQUE`, `MASK`, `BLEND`) and `alphaCutoff`.
    pub alpha_mode: &'static str,
    pub alpha_cutoff: f64,
    pub metallic: f64,
    pub roughness: f64,
    pub base_color_texture: Option<GlbTexture>,
    pub metallic_roughness_texture: Option<GlbTexture>,
    pub normal_texture: Option<GlbTexture>,
    pub normal_scale: f64,
    /// The emissive factor (any size: written as factor and strength).
    pub emissive: [f64; 3],
    pub emissive_texture: Option<GlbTexture>,
}

impl Default for GlbMaterial {
    fn default() -> Self {
        Self {
            base_color: [1.0; 4],
            alpha_mode: "OPAQUE",
            alpha_cutoff: 0.5,
            metallic: 1.0,
            roughness: 1.0,
            base_color_texture: None,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
        }
    }
}

/// An RGBA8 image and how the material reads it.
#[derive(Clone, Debug)]
pub struct GlbTexture {
    pub width: u32,
    pub height: u32,
    /// 4 bytes per texel, rows from the top.
    pub rgba: Vec<u8>,
    pub wrap: [Wrap; 2],
    pub tex_coord: u32,
    /// offset, rotation (radians), scale.
    pub transform: Option<([f64; 2], f64, [f64; 2])>,
}

impl GlbTexture {
    pub fn new(width: u32, height: u32, rgba: Vec<u8>) -> Self {
        Self {
            width,
            height,
            rgba,
            wrap: [Wrap::Repeat; 2],
            tex_coord: 0,
            transform: None,
        }
    }
}

/// A GLB's binary chunk and the buffer views and accessors into it.
#[derive(Default)]
pub(crate) struct Bin {
    pub data: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl Bin {
    /// Appends `bytes` (4-byte aligned) as a buffer view; its index.
    pub fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.data.len().is_multiple_of(4) {
            self.data.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.data.len(), "byteLength": bytes.len()}));
        self.data.extend(bytes);
        self.views.len() - 1
    }

    fn floats<const N: usize>(&mut self, v: &[[f32; N]], ty: &str, bounds: bool) -> usize {
        let bytes: Vec<u8> = v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": v.len(), "type": ty});
        if bounds {
            let min: Vec<f32> = (0..N)
                .map(|k| v.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min))
                .collect();
            let max: Vec<f32> = (0..N)
                .map(|k| v.iter().map(|p| p[k]).fold(f32::NEG_INFINITY, f32::max))
                .collect();
            a["min"] = json!(min);
            a["max"] = json!(max);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

fn png(t: &GlbTexture) -> Vec<u8> {
    let mut out = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    // Writing to a Vec fails only on a size mismatch, which `rgba` rules out
    // for well-formed input; a malformed one writes an empty image.
    let _ = image::ImageEncoder::write_image(
        encoder,
        &t.rgba,
        t.width,
        t.height,
        image::ExtendedColorType::Rgba8,
    );
    out
}

fn gl_wrap(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 10497,
        Wrap::Clamp => 33071,
        Wrap::Mirror => 33648,
    }
}

/// `mesh` (its material slots ignored: every triangle gets `material`) as
/// GLB bytes.
pub fn glb(mesh: &MeshData, material: &GlbMaterial) -> Vec<u8> {
    let mut b = Bin::default();
    let mut attributes = json!({"POSITION": b.floats(&mesh.positions, "VEC3", true)});
    if let Some(n) = &mesh.normals {
        attributes["NORMAL"] = json!(b.floats(n, "VEC3", false));
    }
    for (set, uv) in mesh.uvs.iter().enumerate() {
        if let Some(uv) = uv {
            attributes[format!("TEXCOORD_{set}")] = json!(b.floats(uv, "VEC2", false));
        }
    }
    if let Some(t) = &mesh.tangents {
        attributes["TANGENT"] = json!(b.floats(t, "VEC4", false));
    }
    let idx: Vec<u8> = (mesh.triangles.iter().flatten())
        .flat_map(|i| i.to_le_bytes())
        .collect();
    let view = b.view(&idx);
    b.accessors.push(json!({"bufferView": view, "componentType": 5125, "count": mesh.triangles.len() * 3, "type": "SCALAR"}));
    let indices = b.accessors.len() - 1;

    let (mut images, mut samplers, mut textures) = (Vec::new(), Vec::new(), Vec::new());
    let mut info = |t: &GlbTexture, b: &mut Bin| -> Value {
        let view = b.view(&png(t));
        images.push(json!({"bufferView": view, "mimeType": "image/png"}));
        samplers.push(json!({"wrapS": gl_wrap(t.wrap[0]), "wrapT": gl_wrap(t.wrap[1])}));
        textures.push(json!({"source": images.len() - 1, "sampler": samplers.len() - 1}));
        let mut v = json!({"index": textures.len() - 1, "texCoord": t.tex_coord});
        if let Some((offset, rotation, scale)) = t.transform {
            v["extensions"] = json!({"KHR_texture_transform": {"offset": offset, "rotation": rotation, "scale": scale}});
        }
        v
    };
    let m = material;
    let mut pbr = json!({
        "baseColorFactor": m.base_color,
        "metallicFactor": m.metallic,
        "roughnessFactor": m.roughness,
    });
    if let Some(t) = &m.base_color_texture {
        pbr["baseColorTexture"] = info(t, &mut b);
    }
    if let Some(t) = &m.metallic_roughness_texture {
        pbr["metallicRoughnessTexture"] = info(t, &mut b);
    }
    let mut mat = json!({"name": "material", "pbrMetallicRoughness": pbr,
        "alphaMode": m.alpha_mode, "alphaCutoff": m.alpha_cutoff});
    if let Some(t) = &m.normal_texture {
        let mut v = info(t, &mut b);
        v["scale"] = json!(m.normal_scale);
        mat["normalTexture"] = v;
    }
    let strength = m.emissive.iter().fold(1.0f64, |a, &b| a.max(b));
    if m.emissive.iter().any(|&e| e > 0.0) {
        mat["emissiveFactor"] = json!(m.emissive.map(|e| e / strength));
        if strength > 1.0 {
            mat["extensions"] =
                json!({"KHR_materials_emissive_strength": {"emissiveStrength": strength}});
        }
    }
    if let Some(t) = &m.emissive_texture {
        mat["emissiveTexture"] = info(t, &mut b);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "pathstream"},
        "extensionsUsed": ["KHR_texture_transform", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": mesh.name, "primitives": [{"attributes": attributes, "indices": indices, "material": 0}]}],
        "materials": [mat],
        "images": images,
        "samplers": samplers,
        "textures": textures,
        "accessors": b.accessors,
        "bufferViews": b.views,
        "buffers": [{"byteLength": b.data.len()}],
    });
    pack(&doc, &b.data)
}

/// The GLB container of `doc` and `bin` (no BIN chunk when `bin` is empty).
pub(crate) fn pack(doc: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(doc).unwrap_or_default();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
    }
    out
}
