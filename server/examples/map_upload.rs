//! What a job under an environment map, or of a textured scene, costs the
//! OpenCL device before its first sample: the first job of a map (or of a
//! set of textures) uploads its texels, the next jobs of the same map or
//! textures (camera moves, edits) share them.
//!
//! ```text
//! cargo run --release --example map_upload -- MAP.hdr|MAP.exr [--jobs 6]
//! cargo run --release --example map_upload -- --scene cornell-mesh-textured [--jobs 6]
//! ```
//!
//! The map is scaled up (nearest texel) to 4096 x 2048; each job is a new
//! `RenderJob` of a small scene under it; a scene by name (a bench scene
//! or a file) gets a camera move per job. Each is rendered for one sample
//! at 64 x 64 on OpenCL device 0. Prints each job's upload time and bytes.

use pathstream::render::backend::opencl::OpenClBackend;
use pathstream::render::envmap::EnvMap;
use pathstream::render::scene::{LoadedModel, ModelSource, Resolver};
use pathstream::render::{Film, Quality, RenderJob, Scene};
use std::sync::Arc;

const W: u32 = 4096;
const H: u32 = 2048;

/// The one map, by any name.
struct OneMap(Arc<EnvMap>);

impl Resolver for OneMap {
    fn resolve(&self, _: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err("no models here".into())
    }

    fn environment(&self, _: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        Ok(self.0.clone())
    }
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let source = args
        .first()
        .ok_or("usage: map_upload MAP.hdr|MAP.exr [--jobs N]")?;
    let jobs: u64 = match args.iter().position(|a| a == "--jobs") {
        Some(i) => args
            .get(i + 1)
            .and_then(|n| n.parse().ok())
            .ok_or("--jobs N")?,
        None => 6,
    };
    let (scene, what) = match source.as_str() {
        "--scene" => {
            let name = args.get(1).ok_or("--scene NAME")?;
            let scene = pathstream::bench::scenes::load(name).map_err(|e| e.to_string())?;
            (scene, name.clone())
        }
        _ => (under_map(source)?, format!("{W}x{H} map")),
    };
    let mut device = OpenClBackend::new(Some(0)).map_err(|e| e.to_string())?;
    println!("{what} on {}", device.device());
    for k in 0..jobs {
        let before = device.scene_bytes_uploaded;
        let mut moved = scene.clone();
        if source == "--scene" {
            moved.camera.position.x += k as f64 * 0.5;
        }
        let job = RenderJob::new(
            &moved,
            64,
            64,
            &Quality {
                seed: k,
                ..Quality::default()
            },
        );
        let mut film = Film::new(64, 64);
        let start = std::time::Instant::now();
        device
            .render(&job, &mut film, 1)
            .map_err(|e| e.to_string())?;
        let whole = start.elapsed();
        let (took, _) = device.last_upload.unwrap_or_default();
        println!(
            "job {k}: {:.1} ms to the first sample, upload {:.1} ms, {:.1} MB of scene arrays",
            whole.as_secs_f64() * 1e3,
            took.as_secs_f64() * 1e3,
            (device.scene_bytes_uploaded - before) as f64 / 1e6
        );
    }
    Ok(())
}

/// A small scene under `source`'s map scaled up to [`W`] x [`H`].
fn under_map(source: &str) -> Result<Scene, String> {
    let bytes = std::fs::read(source).map_err(|e| format!("{source}: {e}"))?;
    let small = pathstream::model::hdr::read_hdr(&bytes, source)?;
    let texels = (0..W * H)
        .map(|k| {
            let (x, y) = (k % W, k / W);
            small.texels[(y * small.height / H * small.width + x * small.width / W) as usize]
        })
        .collect();
    let map = Arc::new(EnvMap::new("map", W, H, texels));
    let json = serde_json::json!({
        "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "vfov_deg": 40},
        "materials": {"white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}},
        "objects": [{"type": "sphere", "center": [0, 0.6, 0], "radius": 0.6, "material": "white"}],
        "environment": {"map": "map.hdr"}
    });
    Scene::from_json_str_with(&json.to_string(), &OneMap(map)).map_err(|e| e.to_string())
}
