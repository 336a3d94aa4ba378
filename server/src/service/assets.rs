//! Uploaded model files, environment maps and texture images (`POST
//! /api/assets`): read once, kept as built meshes, a map with its sampling
//! tables or decoded texels, named by the SHA-256 of their bytes (the same
//! file uploaded twice is one asset). Scenes refer to them as `{"type":
//! "mesh", "asset": ID}`, `"environment": {"map": ID}` or a material's
//! `{"texture": ID}`; the store is the server's [`Resolver`], and it reads
//! no files.
//!
//! Limits: the size of one upload (checked from `Content-Length` before the
//! body is read, by the route), the triangles and vertices of one file, and
//! the memory of all assets together. Deleting an asset frees it once no
//! session's scene holds its meshes any more.

use crate::model::{self, Limits};
use crate::render::envmap::EnvMap;
use crate::render::scene::{LoadedModel, ModelSource, NoFiles, Resolver};
use crate::render::texture::Texture;
use crate::resolve::builtin_map;
use std::collections::HashMap;
use std::sync::{Arc, RwLock};
use std::time::SystemTime;

/// What the store accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AssetLimits {
    /// Largest upload, in bytes.
    pub max_asset_bytes: usize,
    /// Most memory (built meshes) of all assets together, in bytes.
    pub max_total_bytes: usize,
    /// Most triangles (and vertices) in one file.
    pub max_triangles: u64,
}

impl Default for AssetLimits {
    fn default() -> Self {
        Self {
            max_asset_bytes: 256 << 20,
            max_total_bytes: 4 << 30,
            max_triangles: 16_000_000,
        }
    }
}

/// An uploaded model, read and built.
#[derive(Debug)]
pub struct Asset {
    pub id: String,
    /// The name it was uploaded under.
    pub name: String,
    pub format: &'static str,
    /// Size of the uploaded file.
    pub bytes: usize,
    /// Memory of its built meshes (or its map and tables).
    pub memory: usize,
    pub content: AssetContent,
    pub created: SystemTime,
}

/// What an asset holds.
#[derive(Debug, Clone)]
pub enum AssetContent {
    Model(Arc<LoadedModel>),
    Environment(Arc<EnvMap>),
    Image(Arc<Texture>),
}

/// An asset as the API reports it.
pub use pathstream_wire::Asset as AssetInfo;

impl Asset {
    pub fn info(&self) -> AssetInfo {
        let mut info = AssetInfo {
            id: self.id.clone(),
            name: self.name.clone(),
            format: self.format.to_owned(),
            bytes: self.bytes as u64,
            memory_bytes: self.memory as u64,
            triangles: 0,
            meshes: 0,
            instances: 0,
            materials: Vec::new(),
            has_camera: false,
            warnings: Vec::new(),
            map_size: None,
            image_size: None,
        };
        match &self.content {
            AssetContent::Model(m) => {
                info.triangles = m.triangles();
                info.meshes = m.meshes.len() as u64;
                info.instances = m.instances.len() as u64;
                info.materials = m.materials.iter().map(|(n, _, _)| n.clone()).collect();
                info.has_camera = m.camera.is_some();
                info.warnings = m.warnings.clone();
            }
            AssetContent::Environment(e) => {
                info.map_size = Some([e.width, e.height]);
                info.warnings.extend(e.warning.clone());
            }
            AssetContent::Image(t) => info.image_size = Some([t.width, t.height]),
        }
        info
    }

    /// Triangles of a model (0 for a map), for the log.
    pub fn triangles(&self) -> u64 {
        match &self.content {
            AssetContent::Model(m) => m.triangles(),
            AssetContent::Environment(_) | AssetContent::Image(_) => 0,
        }
    }
}

/// Why an upload was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssetError {
    /// The file cannot be read as a model (the message names the problem).
    #[error("{0}")]
    Invalid(String),
    #[error("the file is {0} bytes, more than the limit of {1} bytes (--max-asset-bytes)")]
    TooLarge(usize, usize),
    #[error("the assets would hold {need} bytes, more than the limit of {limit} bytes; delete some (DELETE /api/assets/ID)")]
    Full { need: usize, limit: usize },
}

/// The uploaded assets, by id.
#[derive(Debug, Default)]
pub struct AssetStore {
    pub limits: AssetLimits,
    assets: RwLock<HashMap<String, Arc<Asset>>>,
}

pub use crate::resolve::asset_id;

impl AssetStore {
    pub fn new(limits: AssetLimits) -> Self {
        Self {
            limits,
            assets: RwLock::default(),
        }
    }

    /// Reads and stores an upload (slow: call it off the async runtime).
    /// Returns the asset and whether it is new (false: the same bytes were
    /// uploaded before).
    pub fn add(&self, name: &str, bytes: &[u8]) -> Result<(Arc<Asset>, bool), AssetError> {
        if bytes.len() > self.limits.max_asset_bytes {
            return Err(AssetError::TooLarge(
                bytes.len(),
                self.limits.max_asset_bytes,
            ));
        }
        let id = asset_id(bytes);
        if let Some(a) = self.get(&id) {
            return Ok((a, false));
        }
        let name = if name.trim().is_empty() {
            "upload"
        } else {
            name.trim()
        };
        let (format, content, memory) = if let Some(format) = model::hdr::detect(name, bytes) {
            let map = crate::resolve::env_map_bytes(bytes, name).map_err(AssetError::Invalid)?;
            let memory = map.memory_bytes();
            (format, AssetContent::Environment(Arc::new(map)), memory)
        } else if let Some(format) = model::image_format(bytes) {
            let texture = crate::resolve::texture_bytes(bytes, name, &Limits::default())
                .map_err(AssetError::Invalid)?;
            let memory = texture.memory_bytes();
            (format, AssetContent::Image(Arc::new(texture)), memory)
        } else {
            let format = match model::detect(name, bytes) {
                Some(model::Format::Obj) => "obj",
                Some(model::Format::Gltf) => "gltf",
                Some(model::Format::Glb) => "glb",
                Some(model::Format::Ply) => "ply",
                None => {
                    return Err(AssetError::Invalid(format!(
                        "{name}: not a model file (OBJ, glTF 2.0 .gltf/.glb, PLY), an environment \
                         map (.hdr, .exr) or a texture image (PNG, JPEG) this server reads; name \
                         the upload with ?name=FILE.ext if its content does not say"
                    )))
                }
            };
            let limits = Limits {
                max_triangles: self.limits.max_triangles,
                max_vertices: self.limits.max_triangles,
                ..Limits::default()
            };
            let read = model::load_bytes(bytes, name, &limits)
                .map_err(|e| AssetError::Invalid(e.to_string()))?;
            let loaded = crate::resolve::loaded_model(name, read).map_err(AssetError::Invalid)?;
            let memory = loaded.memory_bytes();
            (format, AssetContent::Model(Arc::new(loaded)), memory)
        };
        let asset = Arc::new(Asset {
            id: id.clone(),
            name: name.to_owned(),
            format,
            bytes: bytes.len(),
            memory,
            content,
            created: SystemTime::now(),
        });
        let mut assets = self.assets.write().unwrap_or_else(|e| e.into_inner());
        if let Some(a) = assets.get(&id) {
            return Ok((a.clone(), false));
        }
        let need = assets.values().map(|a| a.memory).sum::<usize>() + memory;
        if need > self.limits.max_total_bytes {
            return Err(AssetError::Full {
                need,
                limit: self.limits.max_total_bytes,
            });
        }
        assets.insert(id, asset.clone());
        Ok((asset, true))
    }

    pub fn get(&self, id: &str) -> Option<Arc<Asset>> {
        self.assets
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .get(id)
            .cloned()
    }

    /// Forgets an asset; false if there was none.
    pub fn remove(&self, id: &str) -> bool {
        self.assets
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .remove(id)
            .is_some()
    }

    /// Every asset, oldest first.
    pub fn list(&self) -> Vec<Arc<Asset>> {
        let mut all: Vec<_> = self
            .assets
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .values()
            .cloned()
            .collect();
        all.sort_by(|a, b| a.created.cmp(&b.created).then_with(|| a.id.cmp(&b.id)));
        all
    }

    /// Memory of all assets' meshes.
    pub fn memory(&self) -> usize {
        self.assets
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .values()
            .map(|a| a.memory)
            .sum()
    }
}

impl Resolver for AssetStore {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        match source {
            ModelSource::Asset(id) => match self.get(id).map(|a| a.content.clone()) {
                Some(AssetContent::Model(m)) => Ok(m),
                Some(AssetContent::Environment(_)) => Err(format!(
                    "asset '{id}' is an environment map: use it as \"environment\": {{\"map\": ID}}"
                )),
                Some(AssetContent::Image(_)) => Err(image_misused(id)),
                None => Err(missing(id)),
            },
            ModelSource::File(_) => NoFiles.resolve(source),
        }
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        match source {
            ModelSource::Asset(id) => match self.get(id).map(|a| a.content.clone()) {
                Some(AssetContent::Environment(e)) => Ok(e),
                Some(AssetContent::Model(_)) => Err(format!(
                    "asset '{id}' is a model, not an environment map (.hdr or .exr)"
                )),
                Some(AssetContent::Image(_)) => Err(image_misused(id)),
                // The maps built into the server answer to their ids too.
                None => match builtin_map(id) {
                    Some(m) => m.map(),
                    None => Err(missing(id)),
                },
            },
            // A built-in map by name ("sunset"): no file is read.
            ModelSource::File(name) => match builtin_map(name) {
                Some(m) => m.map(),
                None => NoFiles.environment(source),
            },
        }
    }

    fn texture(&self, source: ModelSource<'_>) -> Result<Arc<Texture>, String> {
        self.image(source)
    }
}

impl AssetStore {
    /// The texture image asset `id`.
    fn image(&self, source: ModelSource<'_>) -> Result<Arc<Texture>, String> {
        let ModelSource::Asset(id) = source else {
            return NoFiles.texture(source);
        };
        match self.get(id).map(|a| a.content.clone()) {
            Some(AssetContent::Image(t)) => Ok(t),
            Some(AssetContent::Model(_)) => Err(format!(
                "asset '{id}' is a model, not a texture image (PNG or JPEG)"
            )),
            Some(AssetContent::Environment(_)) => Err(format!(
                "asset '{id}' is an environment map, not a texture image (PNG or JPEG)"
            )),
            None => Err(missing(id)),
        }
    }
}

/// Why an image asset cannot be a model or a map.
fn image_misused(id: &str) -> String {
    format!("asset '{id}' is a texture image: use it as a material's {{\"texture\": ID}}")
}

/// Why a scene cannot use asset `id`.
fn missing(id: &str) -> String {
    format!("no asset '{id}' on this server (upload the file with POST /api/assets)")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_the_sha256_of_the_bytes() {
        assert_eq!(
            asset_id(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn oversized_and_unknown_uploads_are_refused_by_name() {
        let store = AssetStore::new(AssetLimits {
            max_asset_bytes: 8,
            ..AssetLimits::default()
        });
        assert_eq!(
            store.add("x.obj", &[0; 9]).expect_err("refused"),
            AssetError::TooLarge(9, 8)
        );
        let e = store.add("notes.txt", b"hello").expect_err("refused");
        assert!(e.to_string().contains("not a model file"), "{e}");
        assert!(store.list().is_empty());
        let missing = store
            .resolve(ModelSource::Asset("feed"))
            .expect_err("refused");
        assert!(missing.contains("no asset 'feed'"), "{missing}");
        assert!(store.resolve(ModelSource::File("/etc/passwd")).is_err());
    }
}
