//! Where the BVH starts to beat scanning every object: `cornell` with N
//! extra small diffuse spheres, or quads (random, seeded), rendered at
//! 128x128 for a second each way, on the CPU (default) or OpenCL
//! (`-- opencl`). `cargo run --release --example accel_crossover`.
//! The result sets `render::world::{SCAN_MAX_COST, scan_cost}`.

use pathstream::render::progressive;
use pathstream::render::sampler::Sampler;
use pathstream::render::world::{AccelChoice, World};
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob, Scene};
use serde_json::json;

fn scene(extra: usize, quads: bool) -> Scene {
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene("cornell")
            .expect("built-in")
            .to_json(),
    )
    .expect("json");
    let objects = j["objects"].as_array_mut().expect("objects");
    for i in 0..extra as u64 {
        let mut s = Sampler::new(42, i, 0);
        let c = [
            10.0 + 80.0 * s.next_f32(),
            5.0 + 60.0 * s.next_f32(),
            20.0 + 120.0 * s.next_f32(),
        ];
        let size = 1.0 + 3.0 * s.next_f32();
        objects.push(if quads {
            json!({"type": "quad", "corner": c, "edge_u": [2.0 * size, 0.0, 0.0], "edge_v": [0.0, size, size], "material": "white"})
        } else {
            json!({"type": "sphere", "center": c, "radius": size, "material": "white"})
        });
    }
    Scene::from_json_value(j).expect("valid")
}

fn rate(s: &Scene, choice: AccelChoice, backend: BackendChoice) -> f64 {
    let q = Quality {
        time_ms: Some(1000),
        ..Quality::default()
    };
    let mut job = RenderJob::new(s, 128, 128, &q);
    job.world = World::with_accel(s, s.camera.position, choice);
    let mut b = Backend::choose(backend).expect("the backend");
    // Program build and first launch (PoCL compiles per launch size) first.
    b.prepare(&job).expect("prepare");
    let warm = Quality {
        spp: Some(2),
        time_ms: None,
        ..q
    };
    progressive::render(&job, &mut b, &mut Film::new(128, 128), &warm, |_| {}).expect("warm-up");
    let mut film = Film::new(128, 128);
    progressive::render(&job, &mut b, &mut film, &q, |_| {})
        .expect("render")
        .samples_per_sec
}

fn main() {
    let backend = match std::env::args().nth(1).as_deref() {
        None | Some("cpu") => BackendChoice::Cpu,
        Some("opencl") => BackendChoice::OpenCl { device: None },
        Some(other) => {
            eprintln!("usage: accel_crossover [cpu|opencl] (not {other})");
            std::process::exit(2);
        }
    };
    println!("| extra objects | objects | scan M paths/s | BVH M paths/s | BVH / scan |");
    println!("| --- | ---: | ---: | ---: | ---: |");
    for (quads, counts) in [
        (false, [8usize, 24, 56, 120, 248, 504]),
        (true, [4, 8, 16, 32, 64, 128]),
    ] {
        for extra in counts {
            let s = scene(extra, quads);
            let (scan, bvh) = (
                rate(&s, AccelChoice::Scan, backend),
                rate(&s, AccelChoice::Bvh, backend),
            );
            println!(
                "| {} | {} | {:.2} | {:.2} | {:.2} |",
                if quads { "quads" } else { "spheres" },
                s.objects.len(),
                scan / 1e6,
                bvh / 1e6,
                bvh / scan
            );
        }
    }
}
