//! What `GET /api/sessions/{id}` reports of a session.

use super::{lock, Session};
use crate::render::film::SppSpread;
use crate::render::scene::LightInfo;
use crate::render::split::DeviceShare;
use crate::render::Quality;
use serde::Serialize;
use std::sync::atomic::Ordering;

/// Status as `GET /api/sessions/{id}` reports it.
#[derive(Debug, Serialize)]
pub struct Status {
    pub id: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub camera: crate::render::scene::CameraJson,
    pub light: Option<LightInfo>,
    pub quality: Quality,
    /// `rendering` or `halted` (also after a device failure, see `failure`).
    pub state: &'static str,
    /// Samples per pixel (adaptive: the mean, rounded down).
    pub spp: u64,
    /// The least, median and most samples of a pixel.
    pub spp_spread: SppSpread,
    /// Adaptive tiles at their share of the target error, of `tiles`
    /// (squares of `tile_size` pixels, cut short at the right and bottom).
    pub tiles_done: usize,
    pub tiles: usize,
    pub tile_size: u32,
    pub error_estimate: Option<f64>,
    pub samples_per_sec: f64,
    pub elapsed_ms: f64,
    pub rejected: u64,
    pub backend: String,
    pub device: String,
    /// Time the device has spent rendering this session, all generations
    /// (how a worker shares its device among its sessions).
    pub render_ms: f64,
    /// What each device rendered of this generation (several for a session
    /// on every device).
    pub devices: Vec<WorkerShare>,
    pub generation: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// What the scene holds that is not rendered as given (unsupported
    /// material features, a default sky, automatic framing).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

/// One worker's share of a session's samples.
#[derive(Debug, Serialize)]
pub struct WorkerShare {
    /// The worker's number (the order of `/api/health`'s `backends`).
    pub worker: usize,
    #[serde(flatten)]
    pub share: DeviceShare,
}

impl Session {
    pub fn status(&self) -> Status {
        let st = lock(&self.state);
        let frame = self.latest();
        let current = frame.generation == st.generation;
        // Only the camera, not the whole scene (this runs for every frame sent).
        let c = st.scene.camera.to_json();
        Status {
            id: self.id.clone(),
            scene: st.scene_name.clone(),
            width: st.width,
            height: st.height,
            camera: c,
            light: st.scene.light_info(),
            quality: st.quality,
            state: if st.halted { "halted" } else { "rendering" },
            spp: if current { frame.spp } else { 0 },
            spp_spread: if current {
                frame.spread
            } else {
                SppSpread::default()
            },
            tiles_done: match (&frame.density, current) {
                (Some(d), true) => d.done_count(),
                _ => 0,
            },
            tiles: crate::render::adaptive::Tiles::new(st.width, st.height).count(),
            tile_size: crate::render::adaptive::TILE_SIZE,
            error_estimate: if current { frame.error_estimate } else { None },
            samples_per_sec: if current { frame.samples_per_sec } else { 0.0 },
            elapsed_ms: st.restarted.elapsed().as_secs_f64() * 1e3,
            rejected: if current { frame.rejected } else { 0 },
            backend: frame.backend.clone(),
            device: frame.device.clone(),
            render_ms: self.render_ns.load(Ordering::Relaxed) as f64 / 1e6,
            devices: (st.devices.iter())
                .map(|(&worker, share)| WorkerShare {
                    worker,
                    share: share.clone(),
                })
                .collect(),
            generation: st.generation,
            failure: st.failure.clone(),
            warnings: st.scene.warnings.clone(),
        }
    }
}
