//! Timed renders: throughput, and error-against-time traces.
//!
//! Only the backend's rendering is timed; building the OpenCL program, the
//! warm-up and measuring the error are not.

use super::fit::{corrected, TracePoint};
use super::settings::Setting;
use crate::render::film::relative_rms_error;
use crate::render::progressive::{self, Progress};
use crate::render::{Backend, BackendError, Film, Quality, RenderJob, Scene};
use std::time::{Duration, Instant};

/// Seed of the measured renders (the references use another); the
/// adaptive section's further seeds count on from it.
pub const TRACE_SEED: u64 = 1;

/// Camera paths and samples per pixel per second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Throughput {
    pub spp: u64,
    pub seconds: f64,
    pub paths_per_sec: f64,
    pub spp_per_sec: f64,
}

/// Renders `scene` at `width` x `height` for about `seconds` after a warm-up
/// sample, and reports the rate.
pub fn throughput(
    backend: &mut Backend,
    scene: &Scene,
    (width, height): (u32, u32),
    quality: &Quality,
    seconds: f64,
) -> Result<Throughput, BackendError> {
    let job = RenderJob::new(scene, width, height, quality);
    backend.prepare(&job)?;
    let mut warm = Film::new(width, height);
    backend.render(&job, &mut warm, 1)?;
    let timed = Quality {
        spp: None,
        target_error: None,
        time_ms: Some(((seconds * 1000.0).ceil() as u64).max(1)),
        ..*quality
    };
    let mut film = Film::new(width, height);
    let done: Progress = progressive::render(&job, backend, &mut film, &timed, |_| {})?;
    let secs = done.elapsed.as_secs_f64();
    Ok(Throughput {
        spp: done.spp,
        seconds: secs,
        paths_per_sec: done.samples_per_sec,
        spp_per_sec: if secs > 0.0 {
            done.spp as f64 / secs
        } else {
            0.0
        },
    })
}

/// Renders with `setting` (seed `seed`) for `seconds` of rendering
/// time, measuring the error against `reference` (whose own error estimate
/// is `reference_error`) at sample counts growing by half each time.
pub fn trace(
    backend: &mut Backend,
    scene: &Scene,
    (width, height): (u32, u32),
    setting: &Setting,
    reference: (&[[f32; 3]], f64),
    seconds: f64,
    seed: u64,
) -> Result<Vec<TracePoint>, BackendError> {
    let q = Quality {
        seed,
        ..setting.quality
    };
    let job = RenderJob::with_sky_probe(scene, width, height, &q, setting.sky_probe);
    backend.prepare(&job)?;
    let mut film = Film::new(width, height);
    let budget = Duration::from_secs_f64(seconds);
    let pixels = u64::from(width) * u64::from(height);
    // No spp halt: an adaptive render spends as long as it is given.
    let endless = Quality {
        spp: Some(u64::MAX),
        time_ms: None,
        target_error: None,
        ..q
    };
    let mut rendering = Duration::ZERO;
    let mut points = Vec::new();
    let mut paths = pixels;
    loop {
        let start = Instant::now();
        progressive::step(&job, backend, &mut film, &endless, paths)?;
        rendering += start.elapsed();
        let error = relative_rms_error(&film.mean(), reference.0);
        let point = TracePoint {
            seconds: rendering.as_secs_f64(),
            spp: film.mean_spp(),
            true_error: corrected(error, reference.1),
            estimate: film.error_estimate(),
        };
        // An adaptive step short of a whole image's paths may leave the
        // mean spp (rounded down) where it was: that point replaces the last.
        if points
            .last()
            .is_some_and(|p: &TracePoint| p.spp == point.spp)
        {
            points.pop();
        }
        points.push(point);
        if rendering >= budget {
            return Ok(points);
        }
        // Next checkpoint at 1.5x the samples, but not far past the budget.
        let taken = film.total_samples();
        let per_path = rendering.as_secs_f64() / taken as f64;
        let left = (budget - rendering).as_secs_f64();
        let wanted = (taken / 2).max(pixels);
        let fits = if per_path > 0.0 {
            (left / per_path).ceil() as u64
        } else {
            wanted
        };
        paths = wanted.min(fits).max(pixels);
    }
}

/// Renders the reference: `quality` until its error estimate is at most
/// `target_error` or `max_seconds` have passed; `on_progress` sees each pass.
pub fn render_reference(
    backend: &mut Backend,
    job: &RenderJob,
    target_error: f64,
    max_seconds: f64,
    on_progress: impl FnMut(&Progress),
) -> Result<(Film, Progress), BackendError> {
    backend.prepare(job)?;
    let mut film = Film::new(job.width(), job.height());
    let halt = Quality {
        spp: None,
        time_ms: Some(((max_seconds * 1000.0).ceil() as u64).max(1)),
        target_error: Some(target_error),
        ..Quality::default()
    };
    let done = progressive::render(job, backend, &mut film, &halt, on_progress)?;
    Ok((film, done))
}
