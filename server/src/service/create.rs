//! A new session from its request (`POST /api/sessions`): size, quality,
//! scene and backend checked against this server's limits, the session
//! made, placed on its workers and started.

use super::change::{patch_quality, Change};
use super::error::ApiError;
use super::session::Session;
use super::{AppState, Placement};
use crate::render::job::check_size;
use crate::render::Quality;
use serde::Deserialize;
use serde_json::Value;
use std::sync::Arc;

/// What a new session asks for (the JSON body of `POST /api/sessions`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewSession {
    /// A built-in scene's name or scene JSON (default `cornell-glass`).
    #[serde(default = "default_scene")]
    pub scene: Value,
    #[serde(default = "default_side")]
    pub width: u64,
    #[serde(default = "default_side")]
    pub height: u64,
    /// Quality fields, over the defaults.
    #[serde(default)]
    pub quality: Option<Value>,
    /// `auto`, `opencl`, `cpu` or `all`.
    #[serde(default)]
    pub backend: Option<String>,
}

fn default_scene() -> Value {
    Value::String("cornell-glass".into())
}

fn default_side() -> u64 {
    512
}

/// A fresh session id: 16 hex digits, after `NODE-` when the box has a
/// node name (what a proxy routes by).
fn new_id(node: Option<&str>) -> String {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_nanos() as u64);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let id = crate::render::sampler::mix64(
        nanos ^ crate::render::sampler::mix64(n ^ u64::from(std::process::id())),
    );
    match node {
        Some(node) => format!("{node}-{id:016x}"),
        None => format!("{id:016x}"),
    }
}

impl AppState {
    /// Makes the session `req` asks for, registers and starts it; errors
    /// name the field at fault, or the limit reached.
    pub fn create_session(&self, req: NewSession) -> Result<Arc<Session>, ApiError> {
        let (width, height) = (
            u32::try_from(req.width)
                .map_err(|_| ApiError::BadRequest(format!("width: {} is too large", req.width)))?,
            u32::try_from(req.height).map_err(|_| {
                ApiError::BadRequest(format!("height: {} is too large", req.height))
            })?,
        );
        check_size(width, height).map_err(ApiError::BadRequest)?;
        let pixels = u64::from(width) * u64::from(height);
        if pixels > self.config.max_pixels {
            return Err(ApiError::BadRequest(format!(
                "width x height: {pixels} pixels is more than this server's limit of {}",
                self.config.max_pixels
            )));
        }
        let quality = match &req.quality {
            Some(q) => patch_quality(&Quality::default(), q)?,
            None => Quality::default(),
        };
        let Change::Scene { name, scene } = Change::scene(req.scene, &self.scene_rules())? else {
            return Err(ApiError::Internal(
                "Change::scene made another change".into(),
            ));
        };
        let placement = self.placement_for(req.backend.as_deref())?;
        let mut session = Session::new(
            new_id(self.config.node_name.as_deref()),
            name,
            *scene,
            width,
            height,
            quality,
            self.placement_info(placement),
        );
        if placement == Placement::All {
            session = session.on_every_device(&self.backends());
        }
        let session = Arc::new(session);
        self.add_session(session.clone(), placement)?;
        tracing::info!(session = %session.id, width, height, "session created");
        Ok(session)
    }
}
