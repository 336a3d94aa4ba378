//! What this client sends: the bodies of `POST /api/sessions` and of the
//! changes (only the fields set go out), and the frames it hands on. What
//! the server answers is the contract's (`pathstream_wire`, re-exported at
//! the crate's root).

use crate::SessionStatus;
use serde::Serialize;

/// A change of quality: only the fields set are sent. `Some(None)` clears a
/// halt condition.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct QualityPatch {
    /// A named preset (`GET /api/presets`), applied before the other fields.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub preset: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_depth: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rr_depth: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub nee: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub filter: Option<String>,
    /// `sobol` or `random`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clamp: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spp: Option<Option<u64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub time_ms: Option<Option<u64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_error: Option<Option<f64>>,
    /// Which frames the server denoises.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub denoise: Option<pathstream_wire::Denoise>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CameraPatch {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub look_at: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vfov_deg: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub near_clip: Option<f64>,
    /// Thin-lens radius (depth of field); 0: a pinhole.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aperture: Option<f64>,
    /// The lens as an f-number (full-frame focal length, metres).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f_number: Option<f64>,
    /// Distance along the view axis that stays sharp.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projection: Option<pathstream_wire::Projection>,
    /// An orthographic view's height in scene units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ortho_height: Option<f64>,
}

#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct LightPatch {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub color: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub intensity: Option<f64>,
}

/// A scene: a built-in name, or scene JSON.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum SceneSpec {
    Name(String),
    Json(serde_json::Value),
}

/// `POST /api/sessions`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CreateSession {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scene: Option<SceneSpec>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub quality: Option<QualityPatch>,
    /// `auto`, `opencl`, `cpu` or `all` (every device at once).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub backend: Option<String>,
}

/// One frame of the stream: the PNG and the stats sent with it.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamFrame {
    pub png: Vec<u8>,
    pub status: SessionStatus,
    /// The server's frame number (gaps mean frames skipped for being stale).
    pub seq: u64,
}
