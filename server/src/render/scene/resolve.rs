//! Where the meshes of `mesh` and `model` objects come from: a
//! [`Resolver`] turns a file name or an asset id into a [`LoadedModel`]
//! (meshes with their BVHs built, materials, placements, camera). The
//! renderer reads no files: resolvers that do live above it
//! (`crate::resolve::FileResolver` for the command line, the server's asset
//! store).
//!
//! - [`NoFiles`]: reads nothing (the library's default);
//! - `Reuse`: the models of an existing scene (edits), else another resolver.

use super::Maps;
use super::{CameraJson, ImportJson, MaterialJson, Scene};
use crate::render::envmap::EnvMap;
use crate::render::math::DAffine3;
use crate::render::shape::{Mesh, MeshData};
use crate::render::texture::Texture;
use rayon::prelude::*;
use std::sync::Arc;

/// What a `mesh` or `model` object names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelSource<'a> {
    File(&'a str),
    Asset(&'a str),
}

impl<'a> ModelSource<'a> {
    /// What an environment's `map` string names: an uploaded asset (a
    /// SHA-256 in hex, as `POST /api/assets` answers) or a file.
    pub fn of_map(name: &'a str) -> Self {
        let is_id = name.len() == 64 && name.bytes().all(|b| b.is_ascii_hexdigit());
        if is_id {
            Self::Asset(name)
        } else {
            Self::File(name)
        }
    }

    /// The source an import names, if it names a file or an asset.
    pub fn of(json: &'a ImportJson) -> Option<Self> {
        match (&json.file, &json.asset) {
            (Some(f), None) => Some(Self::File(f)),
            (None, Some(a)) => Some(Self::Asset(a)),
            _ => None,
        }
    }
}

/// Turns file names or asset ids into loaded models. Errors are one line
/// naming the problem (the caller adds the JSON path).
pub trait Resolver: Sync {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String>;

    /// The environment map (`.hdr` or `.exr`) a scene's `environment.map`
    /// names, read and its sampling tables built.
    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        Err(NoFiles::map_refusal(source))
    }

    /// The image (PNG or JPEG) a material's `texture` names, decoded.
    fn texture(&self, source: ModelSource<'_>) -> Result<Arc<Texture>, String> {
        Err(NoFiles::texture_refusal(source))
    }
}

/// A model file read and its meshes built.
#[derive(Debug)]
pub struct LoadedModel {
    /// The file's name (or the asset's), for material names and messages.
    pub name: String,
    pub meshes: Vec<Arc<Mesh>>,
    /// Materials, indexed by the meshes' material slots, with their
    /// texture maps (which scene JSON cannot name: a file's materials are
    /// not written back).
    pub materials: Vec<(String, MaterialJson, Maps)>,
    /// (mesh, world_from_object) per placement.
    pub instances: Vec<(usize, DAffine3)>,
    /// The file's camera in its world space, if it has one.
    pub camera: Option<CameraJson>,
    pub warnings: Vec<String>,
}

impl LoadedModel {
    /// Checks the meshes and builds them (their BVHs in parallel). `camera`
    /// is in the model's world space (its `near_clip` unused).
    pub fn new(
        name: &str,
        meshes: Vec<MeshData>,
        materials: Vec<(String, MaterialJson, Maps)>,
        instances: Vec<(usize, DAffine3)>,
        camera: Option<CameraJson>,
        warnings: Vec<String>,
    ) -> Result<Self, String> {
        let meshes = meshes
            .into_par_iter()
            .map(|m| {
                let mesh_name = m.name.clone();
                Mesh::new(m)
                    .map(Arc::new)
                    .map_err(|e| format!("{name}: mesh '{mesh_name}': {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            name: name.to_owned(),
            meshes,
            materials,
            instances,
            camera,
            warnings,
        })
    }

    /// Triangles over all meshes (each once).
    pub fn triangles(&self) -> u64 {
        self.meshes.iter().map(|m| m.triangles.len() as u64).sum()
    }

    /// Bytes the meshes and textures hold (each texture once).
    pub fn memory_bytes(&self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let textures: usize = (self.materials.iter())
            .flat_map(|m| m.2.slots().map(|(_, s)| s.texture.clone()))
            .filter(|t| seen.insert(Arc::as_ptr(t)))
            .map(|t| t.memory_bytes())
            .sum();
        self.meshes.iter().map(|m| m.memory_bytes()).sum::<usize>() + textures
    }
}

/// Reads nothing: file and asset references are errors.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFiles;

impl NoFiles {
    /// Why a reference to `source` cannot be followed here.
    pub fn refusal(source: ModelSource<'_>) -> String {
        match source {
            ModelSource::File(f) => format!(
                "'{f}': files are read only from scene files on the command line; \
                 over the API upload the file (POST /api/assets) and use \"asset\""
            ),
            ModelSource::Asset(a) => format!("asset '{a}': assets are only known to a server"),
        }
    }

    /// Why an environment map `source` cannot be read here.
    pub fn map_refusal(source: ModelSource<'_>) -> String {
        match source {
            ModelSource::File(f) => format!(
                "'{f}': files are read only from scene files on the command line; over the \
                 API upload the map (POST /api/assets) and give its id as \"map\", or name \
                 a built-in map (GET /api/environments)"
            ),
            ModelSource::Asset(_) => Self::refusal(source),
        }
    }

    /// Why a texture `source` cannot be read here.
    pub fn texture_refusal(source: ModelSource<'_>) -> String {
        match source {
            ModelSource::File(f) => format!(
                "'{f}': files are read only from scene files on the command line; over the \
                 API upload the image (POST /api/assets) and give its id as \"texture\""
            ),
            ModelSource::Asset(_) => Self::refusal(source),
        }
    }
}

impl Resolver for NoFiles {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err(Self::refusal(source))
    }
}

/// The models of an existing scene, by the source its imports name.
pub(super) struct Reuse<'a> {
    scene: &'a Scene,
    fallback: &'a dyn Resolver,
}

impl<'a> Reuse<'a> {
    pub(super) fn new(scene: &'a Scene, fallback: &'a dyn Resolver) -> Self {
        Self { scene, fallback }
    }
}

impl Resolver for Reuse<'_> {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        self.scene
            .imports
            .iter()
            .find(|i| ModelSource::of(&i.json) == Some(source))
            .map(|i| i.model.clone())
            .map_or_else(|| self.fallback.resolve(source), Ok)
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        match &self.scene.environment_map {
            Some(e) if ModelSource::of_map(&e.json.map) == source => Ok(e.map.clone()),
            _ => self.fallback.environment(source),
        }
    }

    fn texture(&self, source: ModelSource<'_>) -> Result<Arc<Texture>, String> {
        let held = (self.scene.materials.iter())
            .flat_map(|m| m.maps.slots().map(|(_, s)| s))
            .find(|s| {
                (s.source.as_ref()).is_some_and(|j| ModelSource::of_map(&j.texture) == source)
            });
        match held {
            Some(s) => Ok(s.texture.clone()),
            None => self.fallback.texture(source),
        }
    }
}
