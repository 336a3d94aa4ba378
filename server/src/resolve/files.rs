//! Model files, environment maps and texture images read from the file
//! system, relative to a directory (the command line's scenes), cached process-wide by path, size and
//! modification time for as long as any scene holds them, so that a scene
//! edited and validated again does not read or rebuild anything.

use crate::model::{self, Limits};
use crate::render::envmap::EnvMap;
use crate::render::scene::{LoadedModel, ModelSource, NoFiles, Resolver};
use crate::render::texture::Texture;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock, Weak};

/// Reads model files relative to a directory.
#[derive(Clone, Debug)]
pub struct FileResolver {
    base: PathBuf,
    limits: Limits,
}

type FileKey = (PathBuf, u64, Option<std::time::SystemTime>);
type Cache<T> = Mutex<HashMap<FileKey, Weak<T>>>;

/// The cache key of a file: where it is, its size and modification time.
fn file_key(path: &Path) -> Result<FileKey, String> {
    let meta =
        std::fs::metadata(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
    Ok((canonical, meta.len(), meta.modified().ok()))
}

/// What `cache` holds for the file at `path`, else `read` of it, kept in
/// `cache` for as long as something holds it.
fn cached<T>(
    cache: &'static OnceLock<Cache<T>>,
    path: &Path,
    read: impl FnOnce() -> Result<T, String>,
) -> Result<Arc<T>, String> {
    let cache = cache.get_or_init(Default::default);
    let key = file_key(path)?;
    let hit = cache
        .lock()
        .ok()
        .and_then(|c| c.get(&key).and_then(Weak::upgrade));
    if let Some(hit) = hit {
        return Ok(hit);
    }
    let value = Arc::new(read()?);
    if let Ok(mut c) = cache.lock() {
        c.retain(|_, w| w.strong_count() > 0);
        c.insert(key, Arc::downgrade(&value));
    }
    Ok(value)
}

static MODELS: OnceLock<Cache<LoadedModel>> = OnceLock::new();
static MAPS: OnceLock<Cache<EnvMap>> = OnceLock::new();
static TEXTURES: OnceLock<Cache<Texture>> = OnceLock::new();

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
        cached(&MODELS, &path, || {
            let model = model::load_file(&path, &self.limits).map_err(|e| e.to_string())?;
            let display = path
                .file_name()
                .map_or_else(|| name.to_owned(), |f| f.to_string_lossy().into_owned());
            super::loaded_model(&display, model)
        })
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        let ModelSource::File(name) = source else {
            return NoFiles.environment(source);
        };
        let path = self.base.join(name);
        cached(&MAPS, &path, || super::env_map_file(&path))
    }

    fn texture(&self, source: ModelSource<'_>) -> Result<Arc<Texture>, String> {
        let ModelSource::File(name) = source else {
            return NoFiles.texture(source);
        };
        let path = self.base.join(name);
        cached(&TEXTURES, &path, || {
            let bytes = std::fs::read(&path)
                .map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
            super::texture_bytes(&bytes, name, &self.limits)
        })
    }
}
