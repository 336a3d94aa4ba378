//! Where the meshes of `mesh` and `model` objects come from: a
//! [`Resolver`] turns a file name or an asset id into a [`LoadedModel`]
//! (meshes with their BVHs built, materials, placements, camera).
//!
//! - [`NoFiles`]: reads nothing (the library's default; what the server
//!   uses for scenes, with its asset store in front);
//! - [`FileResolver`]: reads files relative to a directory (the command
//!   line), cached process-wide by path, size and modification time for as
//!   long as any scene holds them, so that a scene edited and validated
//!   again does not read or rebuild anything;
//! - `Reuse`: the models of an existing scene (edits), else another resolver.

use super::{ImportJson, MaterialJson, Scene};
use crate::model::{self, Limits, Model, ModelCamera};
use crate::render::math::{DAffine3, DMat3, DVec3};
use crate::render::shape::Mesh;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

/// What a `mesh` or `model` object names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelSource<'a> {
    File(&'a str),
    Asset(&'a str),
}

impl<'a> ModelSource<'a> {
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
}

/// A model file read and its meshes built.
#[derive(Debug)]
pub struct LoadedModel {
    /// The file's name (or the asset's), for material names and messages.
    pub name: String,
    pub meshes: Vec<Arc<Mesh>>,
    /// Materials, indexed by the meshes' material slots.
    pub materials: Vec<(String, MaterialJson)>,
    /// (mesh, world_from_object) per placement.
    pub instances: Vec<(usize, DAffine3)>,
    pub camera: Option<ModelCamera>,
    pub warnings: Vec<String>,
}

impl LoadedModel {
    /// Builds the meshes (their BVHs in parallel) of a model read by a loader.
    pub fn new(name: &str, model: Model) -> Result<Self, String> {
        let meshes = model
            .meshes
            .into_par_iter()
            .map(|m| {
                let mesh_name = m.name.clone();
                Mesh::new(m)
                    .map(Arc::new)
                    .map_err(|e| format!("{name}: mesh '{mesh_name}': {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let instances = model
            .instances
            .iter()
            .map(|i| {
                let [r0, r1, r2] = i.transform;
                let matrix3 = DMat3::from_cols(
                    DVec3::new(r0[0], r1[0], r2[0]),
                    DVec3::new(r0[1], r1[1], r2[1]),
                    DVec3::new(r0[2], r1[2], r2[2]),
                );
                (
                    i.mesh,
                    DAffine3 {
                        matrix3,
                        translation: DVec3::new(r0[3], r1[3], r2[3]),
                    },
                )
            })
            .collect();
        Ok(Self {
            name: name.to_owned(),
            meshes,
            materials: model.materials,
            instances,
            camera: model.camera,
            warnings: model.warnings,
        })
    }

    /// Triangles over all meshes (each once).
    pub fn triangles(&self) -> u64 {
        self.meshes.iter().map(|m| m.triangles.len() as u64).sum()
    }

    /// Bytes the meshes hold.
    pub fn memory_bytes(&self) -> usize {
        self.meshes.iter().map(|m| m.memory_bytes()).sum()
    }
}

/// Reads nothing: file and asset references are errors.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoFiles;

impl Resolver for NoFiles {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err(match source {
            ModelSource::File(f) => format!(
                "'{f}': files are read only from scene files on the command line; \
                 over the API upload the file (POST /api/assets) and use \"asset\""
            ),
            ModelSource::Asset(a) => format!("asset '{a}': assets are only known to a server"),
        })
    }
}

/// Reads model files relative to a directory.
#[derive(Clone, Debug)]
pub struct FileResolver {
    base: PathBuf,
    limits: Limits,
}

type FileKey = (PathBuf, u64, Option<std::time::SystemTime>);

/// Models read from files, for as long as something holds them.
fn file_cache() -> &'static Mutex<HashMap<FileKey, Weak<LoadedModel>>> {
    static CACHE: std::sync::OnceLock<Mutex<HashMap<FileKey, Weak<LoadedModel>>>> =
        std::sync::OnceLock::new();
    CACHE.get_or_init(Default::default)
}

impl FileResolver {
    pub fn new(base: &Path) -> Self {
        Self {
            base: base.to_path_buf(),
            limits: Limits::default(),
        }
    }

    pub fn with_limits(self, limits: Limits) -> Self {
        Self { limits, ..self }
    }
}

impl Resolver for FileResolver {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        let ModelSource::File(name) = source else {
            return NoFiles.resolve(source);
        };
        let path = self.base.join(name);
        let meta = std::fs::metadata(&path)
            .map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        let key = (canonical, meta.len(), meta.modified().ok());
        if let Some(hit) = file_cache()
            .lock()
            .ok()
            .and_then(|c| c.get(&key).and_then(Weak::upgrade))
        {
            return Ok(hit);
        }
        let model = model::load_file(&path, &self.limits).map_err(|e| e.to_string())?;
        let display = path
            .file_name()
            .map_or_else(|| name.to_owned(), |f| f.to_string_lossy().into_owned());
        let loaded = Arc::new(LoadedModel::new(&display, model)?);
        if let Ok(mut cache) = file_cache().lock() {
            cache.retain(|_, w| w.strong_count() > 0);
            cache.insert(key, Arc::downgrade(&loaded));
        }
        Ok(loaded)
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
}
