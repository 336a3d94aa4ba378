//! What texture maps cost: paths per second of a model with base colour,
//! metallic-roughness and normal maps against the same model with its
//! material's factors only, on each backend (the CPU, and the first OpenCL
//! device where there is one), and the textures' memory.
//!
//! ```text
//! cargo run --release --example texture_bench -- [--repeat 5] \
//!   [--triangles 100000] [--texture 1024] [--seconds 2]
//! ```
//!
//! The model is the benchmark's bumpy sphere with latitude-longitude UVs
//! and radial normals (MikkTSpace tangents from the loader), a rough metal-and-paint
//! material, lit by a quad light under a dim sky. The two variants are
//! measured in turn, `--repeat` times; the medians and the spread (min to
//! max) are printed.

use pathstream::model::generate::bumpy_sphere;
use pathstream::model::write_glb::{glb, GlbMaterial, GlbTexture};
use pathstream::model::MeshData;
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob, Scene};
use std::f32::consts::PI;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> Result<T, String> {
    match args.iter().position(|a| a == name) {
        Some(i) => (args.get(i + 1).and_then(|v| v.parse().ok())).ok_or(format!("{name}: a value")),
        None => Ok(default),
    }
}

/// The bumpy sphere with UVs and normals from each vertex's direction
/// (smooth, as a real model's: MikkTSpace then splits only the UV seam).
fn model(triangles: usize) -> MeshData {
    let mut mesh = bumpy_sphere(triangles);
    let normals = mesh
        .positions
        .iter()
        .map(|p| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt().max(1e-9);
            p.map(|x| x / l)
        })
        .collect();
    mesh.normals = Some(normals);
    let uv = mesh
        .positions
        .iter()
        .map(|p| {
            let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt().max(1e-9);
            [
                0.5 + p[0].atan2(p[2]) / (2.0 * PI),
                (p[1] / l).clamp(-1.0, 1.0).acos() / PI,
            ]
        })
        .collect();
    mesh.uvs[0] = Some(uv);
    mesh
}

/// Procedural maps `n` texels square: painted stripes, metal bands, bumps.
fn maps(n: u32) -> (GlbTexture, GlbTexture, GlbTexture) {
    let (mut base, mut mr, mut normal) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..n {
        for x in 0..n {
            let (u, v) = (x as f32 / n as f32, y as f32 / n as f32);
            let stripe = ((u * 24.0).floor() as u32 + (v * 12.0).floor() as u32) % 2;
            base.extend(if stripe == 0 {
                [200, 60, 40, 255]
            } else {
                [230, 220, 200, 255]
            });
            let metal = if (v * 6.0).fract() < 0.5 { 255 } else { 0 };
            let rough = (64.0 + 128.0 * (u * 40.0).sin().abs()) as u8;
            mr.extend([0, rough, metal, 255]);
            let (sx, sy) = ((u * 60.0 * PI).sin() * 0.3, (v * 30.0 * PI).cos() * 0.3);
            let l = (sx * sx + sy * sy + 1.0).sqrt();
            let byte = |c: f32| ((c / l * 0.5 + 0.5) * 255.0).round() as u8;
            normal.extend([byte(sx), byte(sy), byte(1.0), 255]);
        }
    }
    let t = |rgba| GlbTexture::new(n, n, rgba);
    (t(base), t(mr), t(normal))
}

fn scene(dir: &std::path::Path, name: &str, bytes: &[u8]) -> Result<Scene, String> {
    std::fs::write(dir.join(name), bytes).map_err(|e| e.to_string())?;
    let doc = serde_json::json!({
        "camera": {"position": [0, 0.5, 3.2], "look_at": [0, 0, 0], "vfov_deg": 45},
        "environment": [0.1, 0.1, 0.12],
        "materials": {"lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [12, 12, 12]}},
        "objects": [
            {"type": "model", "file": name},
            {"type": "quad", "corner": [-1, 2.5, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "lamp"}
        ]
    });
    let file = dir.join(format!("{name}.json"));
    std::fs::write(&file, doc.to_string()).map_err(|e| e.to_string())?;
    pathstream::resolve::load_scene(&file.to_string_lossy()).map_err(|e| e.to_string())
}

fn paths_per_sec(backend: &mut Backend, scene: &Scene, seconds: f64) -> Result<f64, String> {
    let q = Quality {
        time_ms: Some((seconds * 1000.0) as u64),
        ..Quality::default()
    };
    let (w, h) = (256, 256);
    let job = RenderJob::new(scene, w, h, &q);
    backend.prepare(&job).map_err(|e| e.to_string())?;
    let mut film = Film::new(w, h);
    let done = pathstream::render::progressive::render(&job, backend, &mut film, &q, |_| {})
        .map_err(|e| e.to_string())?;
    Ok(done.samples_per_sec)
}

fn median_spread(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let repeat: usize = arg(&args, "--repeat", 5)?;
    let triangles: usize = arg(&args, "--triangles", 100_000)?;
    let size: u32 = arg(&args, "--texture", 1024)?;
    let seconds: f64 = arg(&args, "--seconds", 2.0)?;
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let mesh = model(triangles);
    let (base, mr, normal) = maps(size);
    let textured = GlbMaterial {
        base_color: [1.0; 4],
        metallic: 1.0,
        roughness: 1.0,
        base_color_texture: Some(base),
        metallic_roughness_texture: Some(mr),
        normal_texture: Some(normal),
        ..GlbMaterial::default()
    };
    let plain = GlbMaterial {
        base_color: [0.8, 0.5, 0.4, 1.0],
        metallic: 0.5,
        roughness: 0.5,
        ..GlbMaterial::default()
    };
    let scenes = [
        (
            "factors",
            scene(dir.path(), "plain.glb", &glb(&mesh, &plain))?,
        ),
        (
            "maps",
            scene(dir.path(), "textured.glb", &glb(&mesh, &textured))?,
        ),
    ];
    let model_bytes = |s: &Scene| s.imports[0].model.memory_bytes();
    println!(
        "{} triangles; model memory: factors {:.1} MB, maps {:.1} MB (three {size}x{size} RGBA8 textures: {:.1} MB)",
        mesh.triangles.len(),
        model_bytes(&scenes[0].1) as f64 / 1e6,
        model_bytes(&scenes[1].1) as f64 / 1e6,
        3.0 * f64::from(size * size) * 4.0 / 1e6
    );
    let mut backends = vec![(
        "cpu",
        Backend::choose(BackendChoice::Cpu).map_err(|e| e.to_string())?,
    )];
    if let Ok(b) = Backend::choose(BackendChoice::OpenCl { device: None }) {
        backends.push(("opencl", b));
    }
    println!("backend  variant  M paths/s median (min-max) of {repeat}, 256x256, {seconds} s each");
    for (name, backend) in &mut backends {
        let mut rates = vec![Vec::new(), Vec::new()];
        for _ in 0..repeat {
            for (i, (_, s)) in scenes.iter().enumerate() {
                rates[i].push(paths_per_sec(backend, s, seconds)? / 1e6);
            }
        }
        let mut medians = Vec::new();
        for ((variant, _), r) in scenes.iter().zip(rates) {
            let (m, lo, hi) = median_spread(r);
            medians.push(m);
            println!("{name:8} {variant:8} {m:.3} ({lo:.3}-{hi:.3})");
        }
        println!("{name:8} maps / factors: {:.3}", medians[1] / medians[0]);
    }
    Ok(())
}
