//! What a job under an environment map costs the OpenCL device before its
//! first sample: the first job of a map uploads its texels and tables, the
//! next jobs of the same map (camera moves, edits) share them.
//!
//! ```text
//! cargo run --release --example map_upload -- MAP.hdr|MAP.exr [--jobs 6]
//! ```
//!
//! The map is scaled up (nearest texel) to 4096 x 2048; each job is a new
//! `RenderJob` of a small scene under it, rendered for one sample at 64 x
//! 64 on OpenCL device 0. Prints each job's upload time and bytes.

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
    let scene =
        Scene::from_json_str_with(&json.to_string(), &OneMap(map)).map_err(|e| e.to_string())?;
    let mut device = OpenClBackend::new(Some(0)).map_err(|e| e.to_string())?;
    println!("{W}x{H} map on {}", device.device());
    for k in 0..jobs {
        let before = device.scene_bytes_uploaded;
        let job = RenderJob::new(
            &scene,
            64,
            64,
            &Quality {
                seed: k,
                ..Quality::default()
            },
        );
        let mut film = Film::new(64, 64);
        device
            .render(&job, &mut film, 1)
            .map_err(|e| e.to_string())?;
        let (took, _) = device.last_upload.unwrap_or_default();
        println!(
            "job {k}: upload {:.1} ms, {:.1} MB of scene arrays",
            took.as_secs_f64() * 1e3,
            (device.scene_bytes_uploaded - before) as f64 / 1e6
        );
    }
    Ok(())
}
