//! Progressive rendering until a halt condition: passes planned by
//! [`Planner::OFFLINE`], progress reported after each.

use crate::render::backend::{Backend, BackendError};
use crate::render::film::{Film, SppSpread};
use crate::render::job::RenderJob;
use crate::render::pass::{Measured, Pass, Planner};
use crate::render::quality::Quality;
use std::time::{Duration, Instant};
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
    let quality = with_spp_target(quality);
    let pass = Pass::for_paths(film, &quality, max_paths);
    let before = film.total_samples();
    pass.run(backend, job, film, &|| false)?;
    Ok(film.total_samples() - before)
}

/// `quality` with its spp halt made explicit (the default when it sets no
/// halt), so that passes stop there.
fn with_spp_target(quality: &Quality) -> Quality {
    Quality {
        spp: spp_target(quality),
        ..*quality
    }
}

/// Renders into `film` until `quality` halts, calling `on_progress` after
/// every pass. Passes are planned by [`Planner::OFFLINE`], never to run far
/// past a time limit.
pub fn render(
    job: &RenderJob,
    backend: &mut Backend,
    film: &mut Film,
    quality: &Quality,
    mut on_progress: impl FnMut(&Progress),
) -> Result<Progress, BackendError> {
    let start = Instant::now();
    let planned = with_spp_target(quality);
    let pixels = film.pixels().len();
    let mut last = None;
    loop {
        let mut planner = Planner::OFFLINE;
        if let Some(t) = quality.time_ms {
            let left = Duration::from_millis(t).saturating_sub(start.elapsed());
            planner = planner.aiming_at(planner.target.min(left));
        }
        let pass = planner.plan(film, last, &planned);
        let paths = pass.paths(film);
        let pass_start = Instant::now();
        pass.run(backend, job, film, &|| false)?;
        last = Some(Measured::of(paths, pass_start.elapsed(), pixels));
        let progress = Progress::of(film, start.elapsed());
        on_progress(&progress);
        if paths == 0 || halted(quality, &progress) {
            return Ok(progress);
        }
    }
}
