//! Uploaded model files, environment maps and texture images: which file
//! names are which, and what `POST /api/assets`, `GET /api/assets` and
//! `GET /api/assets/{id}` answer (a map: `"format": "hdr"` or `"exr"`, its
//! `map_size`, no triangles; an image: `"png"` or `"jpeg"`, its
//! `image_size`).
//!
//! ```json
//! {"id": "9f86d0…", "name": "bunny.obj", "format": "obj", "bytes": 3021416,
//!  "memory_bytes": 7340032, "triangles": 69451, "meshes": 1, "instances": 1,
//!  "materials": ["default"], "has_camera": false, "warnings": []}
//! ```

use serde::{Deserialize, Serialize};

/// How the names of the model files the server reads end (in any case):
/// what a client uploads as an asset rather than sends as a scene.
pub const MODEL_EXTENSIONS: [&str; 4] = [".obj", ".gltf", ".glb", ".ply"];

/// Whether a file name has a model file's extension ([`MODEL_EXTENSIONS`],
/// any case).
pub fn is_model_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    MODEL_EXTENSIONS.iter().any(|e| lower.ends_with(e))
}

/// How the names of environment map files end (in any case).
pub const ENVIRONMENT_EXTENSIONS: [&str; 2] = [".hdr", ".exr"];

/// Whether a file name has an environment map's extension (any case).
pub fn is_environment_name(name: &str) -> bool {
    let lower = name.to_ascii_lowercase();
    ENVIRONMENT_EXTENSIONS.iter().any(|e| lower.ends_with(e))
}

/// An uploaded model file (read and built) or environment map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Asset {
    /// SHA-256 of the file: what scenes name as `"asset"`.
    pub id: String,
    /// The name it was uploaded under.
    pub name: String,
    /// `obj`, `gltf`, `glb` or `ply`; `hdr` or `exr` for an environment
    /// map; `png` or `jpeg` for a texture image.
    pub format: String,
    /// Size of the uploaded file.
    pub bytes: u64,
    /// Memory of its built meshes.
    pub memory_bytes: u64,
    /// Triangles of all its meshes.
    pub triangles: u64,
    /// Meshes it holds.
    pub meshes: u64,
    /// Placements of those meshes.
    pub instances: u64,
    /// The names of its materials.
    pub materials: Vec<String>,
    /// Whether the file has a camera of its own.
    pub has_camera: bool,
    /// What the file holds that the renderer does not model.
    pub warnings: Vec<String>,
    /// An environment map's width and height in texels (a scene uses it
    /// as `"environment": {"map": ID}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub map_size: Option<[u32; 2]>,
    /// A texture image's width and height in texels (a scene's material
    /// uses it as `{"texture": ID}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub image_size: Option<[u32; 2]>,
}

/// The answer to an upload: the asset, and whether the same bytes were
/// uploaded before (then nothing new was stored).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Uploaded {
    /// The asset, its fields at the top level.
    #[serde(flatten)]
    pub asset: Asset,
    /// True when the same bytes were already stored.
    pub deduplicated: bool,
}

/// `GET /api/assets`: the stored assets and the memory they hold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AssetList {
    /// Every stored asset.
    pub assets: Vec<Asset>,
    /// Memory of all their built meshes.
    pub memory_bytes: u64,
    /// The most that `memory_bytes` may reach.
    pub memory_limit_bytes: u64,
}

#[cfg(test)]
mod tests {
    #[test]
    fn model_names_by_extension_in_any_case() {
        for name in ["a.obj", "b.GLTF", "dir/c.Glb", "d.ply"] {
            assert!(super::is_model_name(name), "{name}");
        }
        for name in ["cornell", "a.objx", "scene.json", "ply"] {
            assert!(!super::is_model_name(name), "{name}");
        }
    }
}
