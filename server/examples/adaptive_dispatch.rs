//! How adaptive work reaches the OpenCL kernel, measured: a compacted list
//! of the tiles with work, or an entry for every tile of the image.
//! `cargo run --release --example adaptive_dispatch -- [scene] [width] [height] [mean spp] [pass size in spp]`
//!
//! Renders the same adaptive image (same seed: the same bits either way)
//! with each dispatch and prints the camera paths per second of the
//! adaptive passes, after the uniform warm-up.
use pathstream::render::adaptive::WARMUP_SPP;
use pathstream::render::backend::opencl::{OpenClBackend, TileDispatch};
use pathstream::render::progressive::{self, halted, Progress};
use pathstream::render::{Backend, Film, Quality, RenderJob};
use std::time::{Duration, Instant};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_owned());
    let scene = pathstream::resolve::load_scene(&arg(1, "cornell-glass")).expect("scene");
    let (w, h): (u32, u32) = (
        arg(2, "512").parse().expect("width"),
        arg(3, "512").parse().expect("height"),
    );
    let spp: u64 = arg(4, "128").parse().expect("spp");
    let passes: f64 = arg(5, "1")
        .parse()
        .expect("pass size in samples of the image");
    let q = Quality {
        adaptive: true,
        spp: Some(spp),
        seed: 1,
        ..Quality::default()
    };
    let job = RenderJob::new(&scene, w, h, &q);
    let mut images = Vec::new();
    for dispatch in [TileDispatch::List, TileDispatch::Dense] {
        let mut device = OpenClBackend::new(None).expect("an OpenCL device");
        device.tile_dispatch = dispatch;
        let name = device.device();
        let mut backend = Backend::OpenCl {
            backend: Box::new(device),
            fallback: false,
        };
        backend.prepare(&job).expect("program");
        let mut film = Film::new(w, h);
        // Passes of `passes` samples of the image's pixels.
        let pass = (u64::from(w * h) as f64 * passes) as u64;
        let (mut adaptive_time, mut adaptive_paths) = (Duration::ZERO, 0u64);
        loop {
            let before = film.spp();
            let t = Instant::now();
            let traced = progressive::step(&job, &mut backend, &mut film, &q, pass).expect("step");
            if before >= WARMUP_SPP {
                adaptive_time += t.elapsed();
                adaptive_paths += traced;
            }
            if traced == 0 || halted(&q, &Progress::of(&film, Duration::ZERO)) {
                break;
            }
        }
        println!(
            "{dispatch:?}: {:.2} M paths/s in the adaptive passes ({} rounds, spp {:?}) on {name}",
            adaptive_paths as f64 / adaptive_time.as_secs_f64() / 1e6,
            film.rounds(),
            film.spp_spread()
        );
        images.push(film.pixels().to_vec());
    }
    assert!(
        images.iter().all(|i| *i == images[0]),
        "the dispatches gave different images"
    );
    // Uniform sampling of the same number of samples, for comparison.
    let mut backend = Backend::OpenCl {
        backend: Box::new(OpenClBackend::new(None).expect("an OpenCL device")),
        fallback: false,
    };
    let uniform = Quality {
        adaptive: false,
        ..q
    };
    let job = RenderJob::new(&scene, w, h, &uniform);
    backend.prepare(&job).expect("program");
    let mut film = Film::new(w, h);
    backend
        .render(&job, &mut film, WARMUP_SPP)
        .expect("warm-up");
    let t = Instant::now();
    let pass = ((passes.max(1.0)) as u64).max(1);
    let mut done = WARMUP_SPP;
    while done < spp {
        let n = pass.min(spp - done);
        backend.render(&job, &mut film, n).expect("render");
        done += n;
    }
    println!(
        "uniform: {:.2} M paths/s after the same warm-up, in passes of {pass} spp",
        (spp - WARMUP_SPP) as f64 * f64::from(w * h) / t.elapsed().as_secs_f64() / 1e6
    );
}
