//! The command line: what each subcommand takes.

use crate::quality::QualityArgs;
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "pathstream-client",
    version,
    about = "Drive a pathstream render server over HTTP and WebSocket"
)]
pub(crate) struct Cli {
    /// Server URL. Given more than once (or as a comma-separated list),
    /// `render` renders one image on all the servers and merges it.
    #[arg(
        long,
        global = true,
        env = "PATHSTREAM_URL",
        default_value = "http://127.0.0.1:8080"
    )]
    pub(crate) server: Vec<String>,
    /// Bearer token, when the server requires one.
    #[arg(long, global = true, env = "PATHSTREAM_TOKEN", hide_env_values = true)]
    pub(crate) token: Option<String>,
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to a file: create a session, wait for its halt, save,
    /// delete it. With several --server: one session on each, merged.
    Render(RenderArgs),
    /// List sessions.
    Sessions,
    /// Create a session and print its status.
    Create(CreateArgs),
    /// Print a session's status.
    Status { id: String },
    /// Move or turn a session's camera.
    Camera(CameraArgs),
    /// Focus a session's lens on the surface under a pixel of its image.
    Focus(crate::focus::FocusArgs),
    /// Replace a session's environment: a map (a file, uploaded; a
    /// built-in map's name; an asset id) or a uniform colour.
    Environment(crate::environment::EnvironmentArgs),
    /// Move, recolour or rescale a session's light.
    Light(LightArgs),
    /// Change a session's quality settings.
    Quality {
        id: String,
        #[command(flatten)]
        quality: QualityArgs,
    },
    /// Save a session's current frame (.png or .pfm).
    Frame {
        id: String,
        /// Wait until the image has this many samples per pixel.
        #[arg(long)]
        min_spp: Option<u64>,
        /// The denoised image (whatever the session's quality says).
        #[arg(long, conflicts_with = "raw")]
        denoise: bool,
        /// The raw image (where the session denoises its frames).
        #[arg(long)]
        raw: bool,
        #[arg(short, long)]
        out: PathBuf,
    },
    /// Delete a session.
    Delete { id: String },
    /// Upload a model file (.obj, .gltf, .glb, .ply) and print its asset id,
    /// which scenes name as `{"type": "model", "asset": ID}`.
    Upload { file: PathBuf },
    /// List uploaded assets.
    Assets,
    /// Delete an uploaded asset.
    DeleteAsset { id: String },
    /// Save frames from a session's stream as they arrive.
    Stream {
        id: String,
        #[arg(long, default_value_t = 10)]
        frames: usize,
        #[arg(long)]
        out_dir: PathBuf,
    },
    /// Render a turntable animation: the camera circles the scene's look-at
    /// point (or --center) about its up axis.
    Orbit {
        #[arg(long, default_value = "cornell-glass")]
        scene: String,
        /// Centre of the orbit, x,y,z (default: the camera's look-at point).
        #[arg(long, value_parser = vec3)]
        center: Option<[f64; 3]>,
        #[arg(long, default_value_t = 24)]
        frames: usize,
        /// Samples per pixel of each frame.
        #[arg(long, default_value_t = 16)]
        spp: u64,
        #[arg(long, default_value_t = 256)]
        width: u32,
        #[arg(long, default_value_t = 256)]
        height: u32,
        #[arg(long)]
        out_dir: PathBuf,
    },
}

#[derive(Args, Debug)]
pub(crate) struct CreateArgs {
    /// Built-in scene name, a scene JSON file (its model files are uploaded),
    /// or a model file (.obj, .gltf, .glb, .ply), uploaded and framed.
    #[arg(long, default_value = "cornell-glass")]
    pub(crate) scene: String,
    #[arg(long, default_value_t = 512)]
    pub(crate) width: u32,
    #[arg(long, default_value_t = 512)]
    pub(crate) height: u32,
    /// auto, opencl, cpu or all (every device of the server at once).
    #[arg(long)]
    pub(crate) backend: Option<String>,
    /// An equirectangular HDR environment map (.hdr or .exr), uploaded and
    /// lighting the scene in place of its own environment (a scene JSON or
    /// model file: built-in scenes are sent by name).
    #[arg(long, value_name = "FILE")]
    pub(crate) environment: Option<PathBuf>,
    /// Scales the --environment map's radiance.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 1.0,
        requires = "environment"
    )]
    pub(crate) env_intensity: f64,
    /// Turns the --environment map about +y, in degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        requires = "environment"
    )]
    pub(crate) env_rotation: f64,
    #[command(flatten)]
    pub(crate) quality: QualityArgs,
}

#[derive(Args, Debug)]
pub(crate) struct RenderArgs {
    #[command(flatten)]
    pub(crate) create: CreateArgs,
    /// Output file: .png or .pfm.
    #[arg(short, long)]
    pub(crate) out: PathBuf,
}

#[derive(Args, Debug)]
pub(crate) struct CameraArgs {
    pub(crate) id: String,
    /// x,y,z
    #[arg(long, value_parser = vec3)]
    pub(crate) position: Option<[f64; 3]>,
    /// x,y,z
    #[arg(long, value_parser = vec3)]
    pub(crate) look_at: Option<[f64; 3]>,
    /// x,y,z
    #[arg(long, value_parser = vec3)]
    pub(crate) up: Option<[f64; 3]>,
    #[arg(long)]
    pub(crate) vfov_deg: Option<f64>,
    /// Thin-lens radius in scene units (depth of field); 0: a pinhole.
    #[arg(long, conflicts_with = "f_number")]
    pub(crate) aperture: Option<f64>,
    /// The lens as an f-number instead (full-frame focal length of the
    /// field of view; scene units read as metres).
    #[arg(long)]
    pub(crate) f_number: Option<f64>,
    /// Distance along the view axis that stays sharp.
    #[arg(long)]
    pub(crate) focus_distance: Option<f64>,
    /// perspective, orthographic or panorama (equirectangular 360 degrees).
    #[arg(long, value_parser = projection)]
    pub(crate) projection: Option<pathstream_client::Projection>,
    /// An orthographic view's height in scene units.
    #[arg(long)]
    pub(crate) ortho_height: Option<f64>,
}

fn projection(s: &str) -> Result<pathstream_client::Projection, String> {
    serde_json::from_value(serde_json::Value::String(s.to_owned()))
        .map_err(|_| format!("'{s}': expected perspective, orthographic or panorama"))
}

#[derive(Args, Debug)]
pub(crate) struct LightArgs {
    pub(crate) id: String,
    /// x,y,z
    #[arg(long, value_parser = vec3)]
    pub(crate) position: Option<[f64; 3]>,
    /// r,g,b in [0, 1]
    #[arg(long, value_parser = vec3)]
    pub(crate) color: Option<[f64; 3]>,
    #[arg(long)]
    pub(crate) intensity: Option<f64>,
}

pub(crate) fn vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<f64> = s
        .split(',')
        .map(|p| p.trim().parse::<f64>().map_err(|e| format!("'{p}': {e}")))
        .collect::<Result<_, _>>()?;
    <[f64; 3]>::try_from(parts)
        .map_err(|_| "expected three comma-separated numbers, e.g. 50,52,295.6".into())
}
