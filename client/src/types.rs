//! The JSON contract of the pathstream API, as this client understands it.
//! These types are written from the contract (README "HTTP and WebSocket
//! API"), not imported from the server; `pathstream-tests` checks that the
//! two agree field for field.

use serde::{Deserialize, Serialize};

/// Quality settings and halt conditions.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    pub max_depth: u32,
    pub rr_depth: u32,
    pub nee: bool,
    /// `tent2x2` or `box`.
    pub filter: String,
    pub clamp: f32,
    pub seed: u64,
    /// Adaptive sampling: after a uniform warm-up, samples go to the 8x8
    /// tiles with the most error (`spp` is then the mean). Absent (off) on
    /// servers before it.
    #[serde(default)]
    pub adaptive: bool,
    /// Halt at this many samples per pixel (adaptive: on average).
    pub spp: Option<u64>,
    pub time_ms: Option<u64>,
    pub target_error: Option<f64>,
}

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
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub vfov_deg: f64,
    pub near_clip: f64,
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
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Index of the light object in the scene.
    pub index: usize,
    pub position: [f64; 3],
    pub color: [f64; 3],
    pub intensity: f64,
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

/// A session's status (`GET /api/sessions/{id}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionStatus {
    pub id: String,
    /// Built-in scene name, or `custom`.
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    pub light: Option<Light>,
    pub quality: Quality,
    /// `rendering` or `halted`.
    pub state: String,
    /// Samples per pixel (adaptive: the mean, rounded down).
    pub spp: u64,
    /// The least, median and most samples of a pixel (all 0 from servers
    /// before adaptive sampling).
    #[serde(default)]
    pub spp_spread: SppSpread,
    /// Adaptive tiles at their share of the target error, of `tiles`.
    #[serde(default)]
    pub tiles_done: u64,
    #[serde(default)]
    pub tiles: u64,
    /// Side of an adaptive tile in pixels (0 from servers before it was
    /// reported).
    #[serde(default)]
    pub tile_size: u32,
    pub error_estimate: Option<f64>,
    pub samples_per_sec: f64,
    pub elapsed_ms: f64,
    pub rejected: u64,
    pub backend: String,
    pub device: String,
    /// Time the device has spent on this session, all generations.
    #[serde(default)]
    pub render_ms: f64,
    /// What each device rendered of this generation (several for a session
    /// on every device, `backend: "all"`).
    #[serde(default)]
    pub devices: Vec<DeviceShare>,
    /// Counts restarts (every change restarts accumulation).
    pub generation: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// What the scene holds that is not rendered as given.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl SessionStatus {
    pub fn halted(&self) -> bool {
        self.state == "halted"
    }
}

/// One device's part of a session's samples.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DeviceShare {
    /// The server's worker number (the order of [`Health::backends`]).
    pub worker: usize,
    pub backend: String,
    pub device: String,
    /// Camera paths it traced.
    pub samples: u64,
    /// Seconds it spent rendering.
    pub busy_s: f64,
    pub samples_per_sec: f64,
    /// Why it dropped out of the session, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

/// How the samples spread over the pixels: uniform sampling gives every
/// pixel the same count (or one more, mid-pass); adaptive sampling gives the
/// noisiest tiles the most.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SppSpread {
    pub min: u64,
    pub median: u64,
    pub max: u64,
}

/// An uploaded model file (`POST /api/assets`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct Asset {
    /// SHA-256 of the file: what scenes name as `"asset"`.
    pub id: String,
    pub name: String,
    /// `obj`, `gltf`, `glb` or `ply`.
    pub format: String,
    pub bytes: u64,
    pub memory_bytes: u64,
    pub triangles: u64,
    pub meshes: u64,
    pub instances: u64,
    pub materials: Vec<String>,
    pub has_camera: bool,
    /// What the file holds that the renderer does not model.
    pub warnings: Vec<String>,
}

/// The answer to an upload: the asset, and whether the same bytes were
/// uploaded before (then nothing new was stored).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct Uploaded {
    #[serde(flatten)]
    pub asset: Asset,
    pub deduplicated: bool,
}

/// `GET /api/assets`: the stored assets and the memory they hold.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
pub struct AssetList {
    pub assets: Vec<Asset>,
    pub memory_bytes: u64,
    pub memory_limit_bytes: u64,
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

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BackendInfo {
    pub backend: String,
    pub device: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Health {
    pub status: String,
    pub version: String,
    /// The server's `--node-name`, if it was given one.
    pub node: Option<String>,
    pub sessions: usize,
    pub backends: Vec<BackendInfo>,
    /// Per worker, in the order of `backends`.
    pub load: Vec<WorkerLoad>,
}

/// How loaded one render worker is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorkerLoad {
    pub backend: String,
    pub device: String,
    /// Sessions placed on the worker.
    pub sessions: usize,
    /// Fraction of the last 5 s spent rendering, 0..1.
    pub busy: f64,
    /// Camera paths per second over the last 5 s.
    #[serde(default)]
    pub samples_per_sec: f64,
    /// Camera paths rendered since the server started.
    #[serde(default)]
    pub samples: u64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OpenClDevice {
    pub index: usize,
    pub platform: String,
    pub name: String,
    pub vendor: String,
    pub kind: String,
    pub compute_units: u32,
    pub global_mem_bytes: u64,
    pub fp64: bool,
    pub opencl_c_version: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Devices {
    pub backends: Vec<BackendInfo>,
    pub default: String,
    pub opencl_devices: Option<Vec<OpenClDevice>>,
    pub opencl_error: Option<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scenes {
    pub scenes: Vec<String>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionList {
    pub sessions: Vec<SessionStatus>,
}

/// One frame of the stream: the PNG and the stats sent with it.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamFrame {
    pub png: Vec<u8>,
    pub status: SessionStatus,
    /// The server's frame number (gaps mean frames skipped for being stale).
    pub seq: u64,
}
