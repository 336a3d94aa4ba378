//! Placeholder until the loaders land: every file is refused.

use super::{Format, Limits, Model, ModelError};

pub fn load_file(path: &std::path::Path, _limits: &Limits) -> Result<Model, ModelError> {
    Err(ModelError { file: path.display().to_string(), location: None, reason: "model files cannot be read yet".into() })
}

pub fn load_bytes(_bytes: &[u8], name: &str, _limits: &Limits) -> Result<Model, ModelError> {
    Err(ModelError { file: name.into(), location: None, reason: "model files cannot be read yet".into() })
}

pub fn detect(_name: &str, _bytes: &[u8]) -> Option<Format> {
    None
}
