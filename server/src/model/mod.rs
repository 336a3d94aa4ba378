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

use crate::render::scene::MaterialJson;

pub mod generate;

/// A model file, read.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Triangle meshes in their own (object) space.
    pub meshes: Vec<MeshData>,
    /// Materials the meshes' triangles refer to, by index, with the names the
    /// file gives them (unique within the model).
    pub materials: Vec<(String, MaterialJson)>,
    /// Placements of meshes: one per mesh for OBJ and PLY (identity), one per
    /// glTF node that holds a mesh (its world transform, hierarchy applied).
    pub instances: Vec<Instance>,
    /// The file's camera, if it has one (glTF: the first perspective camera
    /// in the default scene, in world space).
    pub camera: Option<ModelCamera>,
    /// What the file holds that the renderer does not use, one line each.
    pub warnings: Vec<String>,
}

/// An indexed triangle mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    pub name: String,
    pub positions: Vec<[f32; 3]>,
    /// Per-vertex unit shading normals (same length as `positions`), if any.
    pub normals: Option<Vec<[f32; 3]>>,
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: index into [`Model::materials`].
    pub materials: Vec<u32>,
}

/// A mesh placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    pub mesh: usize,
    /// world_from_object, row-major 3x4 (the last row of the 4x4 is 0 0 0 1).
    pub transform: [[f64; 4]; 3],
}

/// A perspective camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelCamera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    /// Full vertical field of view in degrees.
    pub vfov_deg: f64,
}

/// Limits checked while reading, before anything large is allocated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    pub max_triangles: u64,
    pub max_vertices: u64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_triangles: 16_000_000,
            max_vertices: 16_000_000,
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
/// `.glb`, `.ply`, any case).
pub fn is_model_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    [".obj", ".gltf", ".glb", ".ply"].iter().any(|e| lower.ends_with(e))
}

mod pending;
pub use pending::{detect, load_bytes, load_file};
