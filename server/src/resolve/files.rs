//! Model files read from the file system, relative to a directory (the
//! command line's scenes), cached process-wide by path, size and
//! modification time for as long as any scene holds them, so that a scene
//! edited and validated again does not read or rebuild anything.

use crate::model::{self, Limits};
use crate::render::envmap::EnvMap;
use crate::render::scene::{LoadedModel, ModelSource, NoFiles, Resolver};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, Weak};

/// Reads model files relative to a directory.
#[derive(Clone, Debug)]
pub struct FileResolver {
    base: PathBuf,
    limits: Limits,
}

type FileKey = (PathBuf, u64, Option<std::time::SystemTime>);

/// Environment maps read from files, for as long as something holds them.
fn map_cache() -> &'static Mutex<HashMap<FileKey, Weak<EnvMap>>> {
    static CACHE: std::sync::OnceLock<Mutex<HashMap<FileKey, Weak<EnvMap>>>> =
        std::sync::OnceLock::new();
    CACHE.get_or_init(Default::default)
}

/// The cache key of a file: where it is, its size and modification time.
fn file_key(path: &Path) -> Result<FileKey, String> {
    let meta =
        std::fs::metadata(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    Ok((canonical, meta.len(), meta.modified().ok()))
}

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
        let key = file_key(&path)?;
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
        let loaded = Arc::new(super::loaded_model(&display, model)?);
        if let Ok(mut cache) = file_cache().lock() {
            cache.retain(|_, w| w.strong_count() > 0);
            cache.insert(key, Arc::downgrade(&loaded));
        }
        Ok(loaded)
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        let ModelSource::File(name) = source else {
            return NoFiles.environment(source);
        };
        let path = self.base.join(name);
        let key = file_key(&path)?;
        let cached = map_cache().lock().ok();
        if let Some(hit) = cached.and_then(|c| c.get(&key).and_then(Weak::upgrade)) {
            return Ok(hit);
        }
        let map = Arc::new(super::env_map_file(&path)?);
        if let Ok(mut cache) = map_cache().lock() {
            cache.retain(|_, w| w.strong_count() > 0);
            cache.insert(key, Arc::downgrade(&map));
        }
        Ok(map)
    }
}
