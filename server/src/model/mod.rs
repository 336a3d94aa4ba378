//! Model files (OBJ + MTL, glTF 2.0 `.gltf`/`.glb`, PLY ASCII and binary)
//! read into one plain form, [`Model`], that the scene turns into meshes,
//! instances and materials. Nothing here knows about rendering.
//!
//! What a loader guarantees of a `Model` it returns:
//! - every position is finite; every normal is finite and unit length (or the
//!   mesh has none);
//! - every triangle's indices are in range; a mesh has at least one triangle;
//! - every triangle's material index is in range of `Model::materials`;
//! - every instance's mesh index is in range, its transform finite;
//! - whatever the file holds that the renderer cannot show (textures,
//!   roughness, normal maps, lights, animation, ...) is named in `warnings`,
//!   never dropped in silence.
//!
//! Errors name the file and, where known, the line, byte offset or JSON
//! element: `bunny.ply: line 12: vertex 3: x is not a number`.
//!
//! Entry points: [`load_file`], [`load_bytes`], [`detect`]; [`write`] saves
//! meshes as PLY or OBJ (tests, benchmarks). The mapping of each format's
//! materials is in its module's doc (`obj`/`mtl`, `gltf`, `ply`). Shared
//! rules: albedo is clamped to [0, 1] and emission made finite and
//! non-negative (with a warning naming the material); an ior outside
//! [1, 10] becomes 1.5 (with a warning); normals that are not finite or zero
//! drop the whole mesh's normals with a warning (the mesh is flat shaded),
//! other normals are normalised; zero-area triangles are kept (a warning
//! says how many). Limits are checked against what a header or a scan says
//! before the data is read.

use std::path::Path;

mod common;
mod gltf;
mod gltf_data;
mod gltf_maps;
mod gltf_material;
mod image;
mod mtl;
mod obj;
mod obj_maps;
mod ply;
mod tangents;
#[cfg(test)]
mod tests;
mod uri;
pub mod write;
pub mod write_glb;

pub mod generate;
pub mod hdr;

/// A model file, read.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Triangle meshes in their own (object) space.
    pub meshes: Vec<MeshData>,
    /// Materials the meshes' triangles refer to, by index, with the names the
    /// file gives them (unique within the model) and their texture maps.
    pub materials: Vec<(String, Material, Maps)>,
    /// The images the materials' maps read (`TextureRef::image`).
    pub images: Vec<Image>,
    /// Placements of meshes: one per mesh for OBJ and PLY (identity), one per
    /// glTF node that holds a mesh (its world transform, hierarchy applied).
    pub instances: Vec<Instance>,
    /// The file's camera, if it has one (glTF: the first perspective camera
    /// in the default scene, in world space).
    pub camera: Option<ModelCamera>,
    /// What the file holds that the renderer does not use, one line each.
    pub warnings: Vec<String>,
}

/// A material as a loader maps it (each format's rules are in its module's
/// doc): one of the kinds the renderer models. Glass is smooth, with the
/// exact dielectric Fresnel equations; `Pbr` is glTF's metallic-roughness
/// model.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    Diffuse {
        albedo: [f64; 3],
        emission: Option<[f64; 3]>,
    },
    Mirror {
        albedo: [f64; 3],
        emission: Option<[f64; 3]>,
    },
    Glass {
        ior: f64,
        /// Tint of light passing through (None: clear).
        albedo: Option<[f64; 3]>,
        /// Absorption inside the solid (None: clear).
        attenuation: Option<Attenuation>,
        emission: Option<[f64; 3]>,
    },
    Pbr {
        base_color: [f64; 3],
        metallic: f64,
        roughness: f64,
        ior: f64,
        /// `KHR_materials_transmission`: the dielectric's share that is
        /// rough glass.
        transmission: f64,
        /// That glass is a thin wall (glTF: no `KHR_materials_volume`, or
        /// thickness 0).
        thin: bool,
        /// Absorption inside the solid (None: clear; never on a thin wall).
        attenuation: Option<Attenuation>,
        /// `KHR_materials_clearcoat`: the coat's weight and roughness.
        clearcoat: f64,
        clearcoat_roughness: f64,
        /// `KHR_materials_specular`: strength and F0 colour (1, white).
        specular: f64,
        specular_color: [f64; 3],
        emission: Option<[f64; 3]>,
    },
}

/// `KHR_materials_volume`'s Beer-Lambert absorption inside a solid: light
/// that travels `distance` (in world units) through it keeps `color` of
/// itself (each component in (0, 1]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    pub color: [f64; 3],
    pub distance: f64,
}

/// A material's texture maps (each format's module says which it reads),
/// each slot a reference to one of the model's images.
pub type Maps = crate::material_maps::Maps<TextureRef>;
pub use crate::material_maps::AlphaMode;

/// How a material reads one of [`Model::images`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub image: usize,
    /// The UV set (0 or 1).
    pub uv: u32,
    /// Along u, along v.
    pub wrap: [Wrap; 2],
    /// `KHR_texture_transform`: offset, rotation (radians), scale.
    pub offset: [f64; 2],
    pub rotation: f64,
    pub scale: [f64; 2],
}

impl TextureRef {
    /// Image `image`, UV set 0, repeating, untransformed.
    pub fn plain(image: usize) -> Self {
        Self {
            image,
            uv: 0,
            wrap: [Wrap::Repeat; 2],
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
        }
    }
}

/// A sampler's wrap mode along one axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    Clamp,
    Mirror,
}

/// An image decoded to 8-bit RGBA, rows from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Where it came from (`model.glb: images[2]`, `wood.png`).
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// A mesh placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub mesh: usize,
    /// world_from_object, row-major 3x4 (the last row of the 4x4 is 0 0 0 1).
    pub transform: [[f64; 4]; 3],
}

/// A perspective or orthographic camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelCamera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    /// Full vertical field of view in degrees (a perspective camera's).
    pub vfov_deg: f64,
    /// An orthographic camera's view height (glTF's 2 ymag), in the
    /// model's units.
    pub ortho_height: Option<f64>,
}

/// Largest width or height of a texture image (the renderer's own limit).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// Limits checked while reading, before anything large is allocated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    pub max_triangles: u64,
    pub max_vertices: u64,
    /// Texels over all of a model's images.
    pub max_texels: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_triangles: 16_000_000,
            max_vertices: 16_000_000,
            max_texels: 128 << 20,
        }
    }
}

/// A file that cannot be read as a model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}: {}{reason}", location.as_deref().map(|l| format!("{l}: ")).unwrap_or_default())]
pub struct ModelError {
    /// The file's name as the user gave it (a path, or an upload's name).
    pub file: String,
    /// `line 12`, `byte 4096`, `meshes[2].primitives[0]`, ...
    pub location: Option<String>,
    pub reason: String,
}

/// The formats read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Obj,
    Gltf,
    Glb,
    Ply,
}

/// Whether a file name has a model file's extension (`.obj`, `.gltf`,
/// `.glb`, `.ply`, any case): the contract's, which clients use too.
pub use pathstream_wire::asset::is_model_name;

pub use crate::mesh_data::MeshData;
pub use image::{image_format, load_image};

/// Reads a model file; references to other files (OBJ's `mtllib`, a
/// `.gltf`'s external buffers) resolve relative to its directory (absolute
/// paths and URLs are not followed).
pub fn load_file(path: &Path, limits: &Limits) -> Result<Model, ModelError> {
    let shown = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| ModelError {
        file: shown.clone(),
        location: None,
        reason: format!("cannot read: {e}"),
    })?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let dir = path.parent().map(|d| {
        if d.as_os_str().is_empty() {
            Path::new(".")
        } else {
            d
        }
    });
    load(&shown, &name, &bytes, dir, limits)
}

/// Reads a model from bytes (an upload). `name` is the upload's name, used
/// to tell the format when the bytes do not, and in messages. References to
/// other files cannot be followed: an OBJ's `mtllib` becomes a warning (its
/// materials fall back to the default), a `.gltf` with an external buffer is
/// an error that says to upload a `.glb` (`data:` URIs work).
pub fn load_bytes(bytes: &[u8], name: &str, limits: &Limits) -> Result<Model, ModelError> {
    load(name, name, bytes, None, limits)
}

fn load(
    shown: &str,
    name: &str,
    bytes: &[u8],
    dir: Option<&Path>,
    limits: &Limits,
) -> Result<Model, ModelError> {
    let mut ctx = common::Ctx::new(shown, limits);
    let parts = match detect(name, bytes) {
        Some(Format::Obj) => obj::load(&mut ctx, bytes, dir)?,
        Some(Format::Gltf | Format::Glb) => gltf::load(&mut ctx, bytes, dir)?,
        Some(Format::Ply) => ply::load(&mut ctx, bytes)?,
        None => return Err(ctx.err("unknown format: expected an .obj, .gltf, .glb or .ply file")),
    };
    common::finish(ctx, parts)
}

/// The format, from magic bytes first (`glTF` -> GLB; `ply\n` or `ply\r\n`
/// -> PLY; a JSON object with an `"asset"` member -> glTF), then from the
/// name's extension (`.obj`, `.gltf`, `.glb`, `.ply`, any case); `None` when
/// neither tells.
pub fn detect(name: &str, bytes: &[u8]) -> Option<Format> {
    if bytes.starts_with(b"glTF") {
        return Some(Format::Glb);
    }
    if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
        return Some(Format::Ply);
    }
    let text = bytes
        .strip_prefix(b"\xEF\xBB\xBF")
        .unwrap_or(bytes)
        .trim_ascii_start();
    if text.starts_with(b"{") && text.windows(7).any(|w| w == b"\"asset\"") {
        return Some(Format::Gltf);
    }
    let ext = Path::new(name).extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "obj" => Some(Format::Obj),
        "gltf" => Some(Format::Gltf),
        "glb" => Some(Format::Glb),
        "ply" => Some(Format::Ply),
        _ => None,
    }
}
