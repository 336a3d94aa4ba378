//! Progressive rendering until a halt condition: passes sized to take about
//! `PASS_TARGET`, progress reported after each.

use crate::render::backend::{Backend, BackendError};
use crate::render::film::Film;
use crate::render::job::RenderJob;
use crate::render::quality::Quality;
use std::time::{Duration, Instant};

/// How long one pass should take (keeps progress and halts responsive).
const PASS_TARGET: Duration = Duration::from_millis(100);
/// The error estimate is too noisy to stop on below this many samples.
pub const MIN_SPP_FOR_TARGET_ERROR: u64 = 8;
/// Samples per pixel when no halt condition is given.
pub const DEFAULT_SPP: u64 = 64;

/// Where a render stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub spp: u64,
    pub elapsed: Duration,
    pub error_estimate: Option<f64>,
    /// Camera paths per second.
    pub samples_per_sec: f64,
    pub rejected: u64,
}

impl Progress {
    pub fn of(film: &Film, elapsed: Duration) -> Self {
        Self::with_estimate(film, elapsed, film.error_estimate())
    }

    /// As [`Progress::of`], with the error estimate (an O(pixels) pass over
    /// the film) already computed.
    pub fn with_estimate(film: &Film, elapsed: Duration, error_estimate: Option<f64>) -> Self {
        let paths = film.spp() as f64 * f64::from(film.width()) * f64::from(film.height());
        let secs = elapsed.as_secs_f64();
        Self {
            spp: film.spp(),
            elapsed,
            error_estimate,
            samples_per_sec: if secs > 0.0 { paths / secs } else { 0.0 },
            rejected: film.rejected(),
        }
    }
}

/// Whether `quality`'s halt conditions are met (spp default when none set).
pub fn halted(quality: &Quality, p: &Progress) -> bool {
    let spp_target = match quality.halts() {
        true => quality.spp,
        false => Some(DEFAULT_SPP),
    };
    spp_target.is_some_and(|n| p.spp >= n)
        || quality
            .time_ms
            .is_some_and(|t| p.elapsed >= Duration::from_millis(t))
        || quality.target_error.is_some_and(|e| {
            p.spp >= MIN_SPP_FOR_TARGET_ERROR && p.error_estimate.is_some_and(|est| est <= e)
        })
}

/// Renders into `film` until `quality` halts, calling `on_progress` after
/// every pass.
pub fn render(
    job: &RenderJob,
    backend: &mut Backend,
    film: &mut Film,
    quality: &Quality,
    mut on_progress: impl FnMut(&Progress),
) -> Result<Progress, BackendError> {
    let start = Instant::now();
    let spp_target = if quality.halts() {
        quality.spp
    } else {
        Some(DEFAULT_SPP)
    };
    let mut count = 1u64;
    loop {
        if let Some(n) = spp_target {
            count = count.min(n.saturating_sub(film.spp())).max(1);
        }
        let pass_start = Instant::now();
        backend.render(job, film, count)?;
        let pass = pass_start.elapsed();
        let progress = Progress::of(film, start.elapsed());
        on_progress(&progress);
        if halted(quality, &progress) {
            return Ok(progress);
        }
        // Next pass: aim at PASS_TARGET, grow at most 4x, and do not run far
        // past a time limit.
        let per_sample = pass.as_secs_f64() / count as f64;
        let mut budget = PASS_TARGET.as_secs_f64();
        if let Some(t) = quality.time_ms {
            let left = Duration::from_millis(t).saturating_sub(progress.elapsed);
            budget = budget.min(left.as_secs_f64());
        }
        let wanted = if per_sample > 0.0 {
            (budget / per_sample) as u64
        } else {
            count * 4
        };
        count = wanted.clamp(1, count * 4);
    }
}
