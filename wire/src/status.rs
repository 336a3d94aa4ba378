//! What `GET /api/sessions/{id}` reports of a session (also the answer to
//! every change, each item of `GET /api/sessions`, and the body of the
//! stream's stats):
//!
//! ```json
//! {"id": "s1", "scene": "cornell", "width": 640, "height": 480,
//!  "camera": {"position": [0, 1, 3.5], "look_at": [0, 1, 0], "up": [0, 1, 0],
//!             "vfov_deg": 40, "near_clip": 0},
//!  "light": {"index": 7, "position": [0, 1.98, 0], "color": [1, 0.85, 0.6],
//!            "intensity": 17},
//!  "quality": {"max_depth": 6, "rr_depth": 5, "nee": true, "filter": "tent2x2",
//!              "clamp": 0, "seed": 0, "adaptive": false, "spp": 256,
//!              "time_ms": null, "target_error": null},
//!  "state": "rendering", "spp": 12, "spp_spread": {"min": 12, "median": 12, "max": 13},
//!  "tiles_done": 0, "tiles": 76800, "tile_size": 2, "error_estimate": 0.21,
//!  "samples_per_sec": 3.1e6, "elapsed_ms": 812.5, "rejected": 0,
//!  "backend": "cpu", "device": "rayon, 16 threads", "render_ms": 790.2,
//!  "devices": [{"worker": 0, "backend": "cpu", "device": "rayon, 16 threads",
//!               "samples": 3686400, "busy_s": 0.79, "samples_per_sec": 4.6e6}],
//!  "generation": 0}
//! ```
//! `failure` appears only after a device failed, `warnings` only when the
//! scene has some.

use serde::{Deserialize, Serialize};

/// A session's status (`GET /api/sessions/{id}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionStatus {
    /// The session's id (with the server's node name as its prefix, if it
    /// has one).
    pub id: String,
    /// Built-in scene name, or `custom`.
    pub scene: String,
    /// Film width in pixels.
    pub width: u32,
    /// Film height in pixels.
    pub height: u32,
    /// The camera as the scene JSON gives it.
    pub camera: Camera,
    /// The light that `PATCH .../light` changes; None when the scene has none.
    pub light: Option<Light>,
    /// The light from outside the scene, as `PUT .../environment` sets it
    /// (absent from servers before environment maps).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment: Option<Environment>,
    /// The environment map's name (its file's or asset's), if it has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub environment_name: Option<String>,
    /// The quality settings and halt conditions in force.
    pub quality: Quality,
    /// `rendering` or `halted` (also after a device failure, see `failure`).
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
    /// Adaptive tiles of the film: squares of `tile_size` pixels, cut short
    /// at the right and bottom.
    #[serde(default)]
    pub tiles: u64,
    /// Side of an adaptive tile in pixels (0 from servers before it was
    /// reported).
    #[serde(default)]
    pub tile_size: u32,
    /// Estimated relative RMS error of the image (see
    /// [`crate::error_estimate`]); None below 2 samples per pixel.
    pub error_estimate: Option<f64>,
    /// Camera paths per second of the current generation.
    pub samples_per_sec: f64,
    /// Wall time since the last restart, in milliseconds.
    pub elapsed_ms: f64,
    /// Samples rejected as NaN or infinite.
    pub rejected: u64,
    /// `cpu`, `opencl` or `all`, as the session renders now.
    pub backend: String,
    /// The device's name (several, `; `-separated, for `all`).
    pub device: String,
    /// Time the device has spent rendering this session, all generations
    /// (how a worker shares its device among its sessions).
    #[serde(default)]
    pub render_ms: f64,
    /// What each device rendered of this generation (several for a session
    /// on every device, `backend: "all"`).
    #[serde(default)]
    pub devices: Vec<DeviceShare>,
    /// Counts restarts (every change restarts accumulation).
    pub generation: u64,
    /// Why rendering stopped, after a device failure.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// What the scene holds that is not rendered as given (unsupported
    /// material features, a default sky, automatic framing).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

impl SessionStatus {
    /// Whether the session has stopped rendering (a halt condition was met,
    /// or its device failed).
    pub fn halted(&self) -> bool {
        self.state == "halted"
    }
}

/// `GET /api/sessions`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SessionList {
    /// Every session's status.
    pub sessions: Vec<SessionStatus>,
}

/// A camera, as scene JSON gives it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Where the camera is.
    pub position: [f64; 3],
    /// The point it looks at.
    pub look_at: [f64; 3],
    /// Which way is up in the image.
    pub up: [f64; 3],
    /// Full vertical field of view in degrees.
    pub vfov_deg: f64,
    /// Camera rays start this far from the camera along themselves (a
    /// sphere around it, as smallpt's camera: not a plane).
    pub near_clip: f64,
    /// Thin-lens radius (depth of field); 0: a pinhole.
    #[serde(default)]
    pub aperture: f64,
    /// The lens given as an f-number (`aperture` is then 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub f_number: Option<f64>,
    /// Distance along the view axis that is sharp; absent: look_at's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<f64>,
    /// Absent: perspective.
    #[serde(default, skip_serializing_if = "Projection::is_perspective")]
    pub projection: Projection,
    /// An orthographic view's height in scene units.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ortho_height: Option<f64>,
}

/// How camera rays leave the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// Through a pinhole or a thin lens.
    #[default]
    Perspective,
    /// Parallel rays from a rectangle `ortho_height` tall.
    Orthographic,
    /// Every direction, equirectangular.
    Panorama,
}

impl Projection {
    /// Whether this is the default, perspective.
    pub fn is_perspective(&self) -> bool {
        *self == Projection::Perspective
    }
}

/// The light from outside the scene: a uniform colour, or an HDR map.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
#[allow(clippy::large_enum_variant)] // one per session or request
pub enum Environment {
    /// Uniform radiance.
    Color([f64; 3]),
    /// An equirectangular map.
    Map(EnvironmentMap),
}

/// An environment map and its settings, as scene JSON gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentMap {
    /// An uploaded asset's id (or a file, in a scene file); empty with `sky`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub map: String,
    /// A clear sky and sun computed in place of a map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<crate::Sky>,
    /// Scales the map's radiance.
    #[serde(default = "one")]
    pub intensity: f64,
    /// Turns the map about +y (right-handed); 0: its centre faces -z.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotation_deg: f64,
    /// Whether camera rays that leave the scene see the map.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub visible: bool,
    /// What they see instead when it is hidden (default black).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<[f64; 3]>,
}

fn one() -> f64 {
    1.0
}

fn yes() -> bool {
    true
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_true(v: &bool) -> bool {
    *v
}

/// The scene's light, as `PATCH .../light` changes it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Light {
    /// Index of the light object in the scene's `objects`.
    pub index: usize,
    /// Centre of the sphere or quad, or of the mesh's bounds.
    pub position: [f64; 3],
    /// Emission over intensity: largest component 1 (all 0 when dark).
    pub color: [f64; 3],
    /// Largest emission component.
    pub intensity: f64,
}

/// Quality settings and halt conditions, as the JSON carries them (the
/// server checks them where it reads them; here the filter is its name).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quality {
    /// Most scattering events per path; 0 = unbounded (Russian roulette only).
    pub max_depth: u32,
    /// Scattering events after which Russian roulette may end a path.
    pub rr_depth: u32,
    /// Next-event estimation (shadow rays to emitters).
    pub nee: bool,
    /// Pixel filter: `tent2x2` or `box`.
    pub filter: String,
    /// Which numbers paths draw: `sobol` (low-discrepancy) or `random`.
    /// `random` from servers before `sobol` existed.
    #[serde(default = "random")]
    pub sampler: String,
    /// Largest sample radiance (max component); 0 = off. Biased.
    pub clamp: f32,
    /// Seed of the samples' random numbers.
    pub seed: u64,
    /// Adaptive sampling: after a uniform warm-up, samples go to the tiles
    /// with the most error (`spp` is then the mean). Absent (off) on
    /// servers before it.
    #[serde(default)]
    pub adaptive: bool,
    /// Halt at this many samples per pixel (adaptive: on average).
    pub spp: Option<u64>,
    /// Halt after this much rendering time.
    pub time_ms: Option<u64>,
    /// Halt when the estimated relative RMS error falls below this.
    pub target_error: Option<f64>,
    /// Which frames show a denoised image (`off` on servers before it).
    #[serde(default)]
    pub denoise: Denoise,
}

/// Which frames a session denoises (with Open Image Denoise, guided by the
/// first hit's albedo and normal). The raw image, its error estimate and
/// every halt condition are the same whichever it is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Denoise {
    /// No frame (the film keeps no feature buffers).
    #[default]
    Off,
    /// The frames streamed while the render runs; the halted frame is raw.
    Stream,
    /// Those, and the halted frame too.
    Final,
}

impl Denoise {
    /// The setting's name on the wire.
    pub fn name(self) -> &'static str {
        match self {
            Denoise::Off => "off",
            Denoise::Stream => "stream",
            Denoise::Final => "final",
        }
    }

    /// Whether a frame shows a denoised image under this setting (`halted`:
    /// the frame is the render's last).
    pub fn shows(self, halted: bool) -> bool {
        match self {
            Denoise::Off => false,
            Denoise::Stream => !halted,
            Denoise::Final => true,
        }
    }
}

fn random() -> String {
    "random".to_owned()
}

/// How the samples spread over the pixels: uniform sampling gives every
/// pixel the same count (or one more, mid-pass); adaptive sampling gives the
/// noisiest tiles the most.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SppSpread {
    /// The fewest samples of a pixel.
    pub min: u64,
    /// The median pixel's samples.
    pub median: u64,
    /// The most samples of a pixel.
    pub max: u64,
}

/// One device's part of a session's samples.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DeviceShare {
    /// The server's worker number (the order of [`crate::Health::backends`]).
    pub worker: usize,
    /// `cpu` or `opencl`.
    pub backend: String,
    /// The device's name.
    pub device: String,
    /// Camera paths it traced (merged or waiting to be).
    pub samples: u64,
    /// Seconds it spent rendering.
    pub busy_s: f64,
    /// Camera paths per second of its own rendering time.
    pub samples_per_sec: f64,
    /// Why it dropped out of the session, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// A status as servers sent it before adaptive sampling and device
    /// shares: the fields since then absent.
    pub(crate) fn older_status() -> Value {
        json!({
            "id": "s", "scene": "cornell", "width": 4, "height": 2,
            "camera": {"position": [0, 0, 1], "look_at": [0, 0, 0], "up": [0, 1, 0],
                       "vfov_deg": 40, "near_clip": 0},
            "light": null,
            "quality": {"max_depth": 6, "rr_depth": 5, "nee": true, "filter": "box",
                        "clamp": 0.5, "seed": 1, "spp": null, "time_ms": null,
                        "target_error": 0.5},
            "state": "halted", "spp": 3, "error_estimate": 0.25, "samples_per_sec": 0,
            "elapsed_ms": 1, "rejected": 0, "backend": "cpu", "device": "d",
            "generation": 2
        })
    }

    #[test]
    fn fields_a_server_added_later_default_and_optional_ones_stay_off_the_wire() {
        let s: SessionStatus = serde_json::from_value(older_status()).expect("an old status reads");
        assert!(s.halted());
        assert_eq!(
            (s.spp_spread, s.tiles, s.render_ms),
            (SppSpread::default(), 0, 0.0)
        );
        assert!(!s.quality.adaptive && s.devices.is_empty());
        let back = serde_json::to_value(&s).expect("serializes");
        assert!(back.get("failure").is_none() && back.get("warnings").is_none());
        let share = serde_json::to_value(DeviceShare::default()).expect("serializes");
        assert!(share.get("failure").is_none(), "{share}");
    }
}

/// `GET /api/sessions/{id}/pick?x=&y=`: the surface under a point of the
/// image.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pick {
    /// Whether the ray through the point meets a surface.
    pub hit: bool,
    /// Where, in world space.
    #[serde(default)]
    pub point: Option<[f64; 3]>,
    /// How far from the camera, along the ray.
    #[serde(default)]
    pub distance: Option<f64>,
    /// Its depth along the view axis: the focus distance that makes it
    /// sharp (none behind the camera's plane).
    #[serde(default)]
    pub focus_distance: Option<f64>,
}
