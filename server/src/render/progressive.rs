//! Progressive rendering until a halt condition: passes sized to take about
//! `PASS_TARGET`, progress reported after each.

use crate::render::adaptive::{Goal, WARMUP_SPP};
use crate::render::backend::{Backend, BackendError};
use crate::render::film::{Film, SppSpread};
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
    /// Samples per pixel (adaptive: the mean, rounded down).
    pub spp: u64,
    /// The least, median and most samples of a pixel.
    pub spread: SppSpread,
    /// Camera paths traced in all.
    pub samples: u64,
    pub pixels: u64,
    /// Adaptive: every tile reached its share of the target error.
    pub converged: bool,
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
        let samples = film.total_samples();
        let secs = elapsed.as_secs_f64();
        Self {
            spp: film.mean_spp(),
            spread: film.spp_spread(),
            samples,
            pixels: film.pixels().len() as u64,
            converged: film.converged(),
            elapsed,
            error_estimate,
            samples_per_sec: if secs > 0.0 {
                samples as f64 / secs
            } else {
                0.0
            },
            rejected: film.rejected(),
        }
    }
}

/// Samples per pixel `quality` halts at (the default when it sets no halt).
pub fn spp_target(quality: &Quality) -> Option<u64> {
    match quality.halts() {
        true => quality.spp,
        false => Some(DEFAULT_SPP),
    }
}

/// Whether `quality`'s halt conditions are met (spp default when none set).
/// An spp target is met by the mean (an adaptive render whose last round
/// cannot spend the few paths left over ends when [`step`] finds nothing
/// to do).
pub fn halted(quality: &Quality, p: &Progress) -> bool {
    spp_target(quality).is_some_and(|n| p.samples >= n.saturating_mul(p.pixels))
        || quality
            .time_ms
            .is_some_and(|t| p.elapsed >= Duration::from_millis(t))
        || p.converged
        || quality.target_error.is_some_and(|e| {
            p.spp >= MIN_SPP_FOR_TARGET_ERROR && p.error_estimate.is_some_and(|est| est <= e)
        })
}

/// One pass of about `max_paths` camera paths: whole samples of every pixel
/// (at least one; during an adaptive render's warm-up, up to its end), or
/// after the warm-up, the next adaptive work. Returns the camera paths it
/// traced: 0 when an adaptive render has nothing left to do.
pub fn step(
    job: &RenderJob,
    backend: &mut Backend,
    film: &mut Film,
    quality: &Quality,
    max_paths: u64,
) -> Result<u64, BackendError> {
    let pixels = film.pixels().len() as u64;
    let target = spp_target(quality);
    if quality.adaptive && film.spp() >= WARMUP_SPP {
        let goal = Goal {
            spp: target,
            ..quality.goal()
        };
        let work = film.adaptive_work(goal, max_paths);
        let before = film.total_samples();
        backend.render_tiles(job, film, &work, &|| false)?;
        return Ok(film.total_samples() - before);
    }
    let mut count = (max_paths / pixels.max(1)).max(1);
    if let Some(n) = target {
        count = count.min(n.saturating_sub(film.spp())).max(1);
    }
    if quality.adaptive {
        count = count.min(WARMUP_SPP - film.spp());
    }
    backend.render(job, film, count)?;
    Ok(count * pixels)
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
    let pixels = film.pixels().len() as u64;
    let mut paths = pixels;
    loop {
        let pass_start = Instant::now();
        let traced = step(job, backend, film, quality, paths)?;
        let pass = pass_start.elapsed();
        let progress = Progress::of(film, start.elapsed());
        on_progress(&progress);
        if traced == 0 || halted(quality, &progress) {
            return Ok(progress);
        }
        // Next pass: aim at PASS_TARGET, grow at most 4x, and do not run far
        // past a time limit.
        let per_path = pass.as_secs_f64() / traced as f64;
        let mut budget = PASS_TARGET.as_secs_f64();
        if let Some(t) = quality.time_ms {
            let left = Duration::from_millis(t).saturating_sub(progress.elapsed);
            budget = budget.min(left.as_secs_f64());
        }
        let wanted = if per_path > 0.0 {
            (budget / per_path) as u64
        } else {
            traced * 4
        };
        paths = wanted.clamp(1, traced * 4);
    }
}
