//! What the server runs on and how busy it is: `GET /api/health`,
//! `GET /api/devices` and `GET /api/scenes`.
//!
//! ```json
//! {"status": "ok", "version": "0.1.0", "node": null, "sessions": 1,
//!  "backends": [{"backend": "cpu", "device": "rayon, 16 threads"}],
//!  "load": [{"backend": "cpu", "device": "rayon, 16 threads", "sessions": 1,
//!            "busy": 0.982, "samples_per_sec": 4.6e6, "samples": 92160000}]}
//! ```

use serde::{Deserialize, Serialize};

/// `GET /api/health`: liveness and load.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Health {
    /// Always `ok`.
    pub status: String,
    /// The server's version.
    pub version: String,
    /// The server's `--node-name`, if it was given one.
    pub node: Option<String>,
    /// Sessions open on the server.
    pub sessions: usize,
    /// What each render worker renders with, by worker number.
    pub backends: Vec<BackendInfo>,
    /// Per worker, in the order of `backends`.
    pub load: Vec<WorkerLoad>,
}

/// What a worker renders with.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BackendInfo {
    /// `cpu` or `opencl` (`all` for a session on every worker).
    pub backend: String,
    /// The device's name.
    pub device: String,
}

/// How loaded one render worker is, so that a proxy or an operator can see
/// which box has room.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct WorkerLoad {
    /// `cpu` or `opencl`, as the worker renders now.
    pub backend: String,
    /// The device's name.
    pub device: String,
    /// Sessions placed on the worker (rendering or halted).
    pub sessions: usize,
    /// Fraction of the last 5 s spent rendering, 0..1 to 3 decimals.
    pub busy: f64,
    /// Camera paths per second over the last 5 s (all its sessions).
    #[serde(default)]
    pub samples_per_sec: f64,
    /// Camera paths rendered since the server started.
    #[serde(default)]
    pub samples: u64,
}

/// `GET /api/devices`: the workers, and the OpenCL devices the machine lists.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Devices {
    /// What each worker renders with now (after an OpenCL device failed,
    /// rayon).
    pub backends: Vec<BackendInfo>,
    /// The backend new sessions render with unless they ask otherwise.
    pub default: String,
    /// The OpenCL devices, numbered across platforms; None when listing
    /// them failed.
    pub opencl_devices: Option<Vec<OpenClDevice>>,
    /// Why listing the OpenCL devices failed.
    pub opencl_error: Option<String>,
    /// The denoiser (absent on servers before it).
    #[serde(default)]
    pub denoiser: Option<Denoiser>,
}

/// Open Image Denoise, as the server found it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Denoiser {
    /// Whether sessions can denoise.
    pub available: bool,
    /// Why not, and what to install, when not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    /// The library file loaded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub library: Option<String>,
    /// Its version (`2.5.1`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub version: Option<String>,
    /// The device it denoises on (an index into `devices`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub device: Option<usize>,
    /// The devices the library can denoise on.
    #[serde(default)]
    pub devices: Vec<DenoiserDevice>,
}

/// One device Open Image Denoise lists (`PATHSTREAM_OIDN_DEVICE` picks one
/// by `index` or by `kind`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DenoiserDevice {
    /// Its number in the library's list.
    pub index: usize,
    /// `cpu`, `cuda`, `hip`, `sycl` or `metal`.
    pub kind: String,
    /// The device's name.
    pub name: String,
}

/// One OpenCL device (`--device N` picks it by `index`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OpenClDevice {
    /// Its number across all platforms.
    pub index: usize,
    /// The platform's name.
    pub platform: String,
    /// The device's name.
    pub name: String,
    /// Its vendor.
    pub vendor: String,
    /// `gpu`, `cpu`, `accelerator` or `other`.
    pub kind: String,
    /// Compute units.
    pub compute_units: u32,
    /// Global memory in bytes.
    pub global_mem_bytes: u64,
    /// Largest single buffer the device allocates, in bytes (0 where a
    /// server does not report it).
    #[serde(default)]
    pub max_alloc_bytes: u64,
    /// Whether it has double precision.
    pub fp64: bool,
    /// The OpenCL C version it compiles.
    pub opencl_c_version: String,
}

/// `GET /api/scenes`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scenes {
    /// The built-in scene names.
    pub scenes: Vec<String>,
}
