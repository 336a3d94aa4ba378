//! Passes: what one call to a backend renders, and one planner that sizes
//! them. A pass is whole samples of every pixel, or, where one sample of
//! the image takes longer than a pass should, a slice of one sample; after
//! an adaptive render's warm-up, the next tiles of its round. The
//! [`Planner`] sizes each from what the last one measured, to take about
//! its target: `pathstream render` ([`Planner::OFFLINE`]), a service
//! session ([`Planner::INTERACTIVE`], so that a worker's sessions share its
//! device by time whatever their scenes cost) and each device's block of a
//! render split across devices ([`Planner::BLOCK`]) all plan with it.

use crate::render::adaptive::{TileWork, WARMUP_SPP};
use crate::render::backend::{Backend, BackendError};
use crate::render::{Film, Quality, RenderJob};
use std::ops::Range;
use std::time::Duration;

/// Camera paths in a session's first pass (its cost is not measured yet):
/// small, as one path of a deliberately expensive scene may take 50 ms on
/// a slow device. Later passes grow from it in a few steps.
pub const FIRST_PATHS: u64 = 16;
/// A pass traces at most this many times the paths of the one before: the
/// cost measured on one part of the image may not hold for the next.
const GROWTH: u64 = 4;
/// Most whole samples in one pass.
const MOST_SAMPLES: u64 = 1 << 16;

/// Sizes passes to take about `target` each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Planner {
    pub target: Duration,
    /// Camera paths of the first pass, before anything is measured (None:
    /// one sample of the whole image).
    pub first_paths: Option<u64>,
}

impl Planner {
    /// A service session's passes: short enough that a change shows within
    /// a frame or two and that a worker's other sessions get their turn
    /// soon, long enough to keep the device busy.
    pub const INTERACTIVE: Planner = Planner {
        target: Duration::from_millis(30),
        first_paths: Some(FIRST_PATHS),
    };
    /// `pathstream render`'s passes: progress and halts stay responsive.
    pub const OFFLINE: Planner = Planner {
        target: Duration::from_millis(100),
        first_paths: None,
    };
    /// One device's block of samples in a render split across devices:
    /// each block costs a film of its own and a merge, O(pixels) each (at
    /// 100 ms, 10-16% of a 1080p render on one device, measured; at 250 ms,
    /// a few per cent).
    pub const BLOCK: Planner = Planner {
        target: Duration::from_millis(250),
        first_paths: None,
    };

    /// This planner aiming at `target` instead.
    pub fn aiming_at(self, target: Duration) -> Planner {
        Planner { target, ..self }
    }

    /// The pass for `film` rendered with `quality`, given what the last
    /// pass measured (None before the first). An adaptive render's next
    /// round is planned here when the last one is done.
    pub fn plan(&self, film: &mut Film, last: Option<Measured>, quality: &Quality) -> Pass {
        let (start, pixels) = (film.slice_start(), film.pixels().len());
        let Some(last) = last else {
            return match self.first_paths {
                Some(n) => Pass::Slice(start..(start + n as usize).min(pixels)),
                None => Pass::for_paths(film, quality, pixels as u64),
            };
        };
        let most_paths = last.paths.max(1).saturating_mul(GROWTH);
        let wanted = self.samples_in_target(last);
        let adaptive = quality.adaptive && start == 0 && film.spp() >= WARMUP_SPP;
        if adaptive {
            let paths = (wanted * pixels as f64).min(most_paths as f64) as u64;
            return Pass::Tiles(film.adaptive_work(quality.goal(), paths.max(1)));
        }
        if start == 0 && wanted >= 1.0 && pixels as u64 <= most_paths {
            return Pass::Samples(whole_samples_for(
                film,
                quality,
                self.whole_samples(pixels, last),
            ));
        }
        let len = (wanted * pixels as f64).min(most_paths as f64) as usize;
        Pass::Slice(start..(start + len.max(1)).min(pixels))
    }

    /// Whole samples per pixel a pass on a film of `pixels` pixels with no
    /// sample in progress takes, given what the last pass measured (1
    /// where it would take a slice of one sample instead).
    pub fn whole_samples(&self, pixels: usize, last: Measured) -> u64 {
        let most_paths = last.paths.max(1).saturating_mul(GROWTH);
        let wanted = self.samples_in_target(last);
        if wanted < 1.0 || pixels as u64 > most_paths {
            return 1;
        }
        let count = (wanted.min(MOST_SAMPLES as f64) as u64).min(most_paths / pixels.max(1) as u64);
        count.clamp(1, MOST_SAMPLES)
    }

    /// Samples of the whole image that fit in the target.
    fn samples_in_target(&self, last: Measured) -> f64 {
        let p = last.per_sample.as_secs_f64();
        if p > 0.0 {
            self.target.as_secs_f64() / p
        } else {
            f64::INFINITY
        }
    }
}

/// `count` whole samples, no more than `quality`'s spp halt or an adaptive
/// warm-up leaves to do, at least one.
fn whole_samples_for(film: &Film, quality: &Quality, mut count: u64) -> u64 {
    if let Some(n) = quality.spp {
        count = count.min(n.saturating_sub(film.spp()));
    }
    if quality.adaptive {
        count = count.min(WARMUP_SPP.saturating_sub(film.spp()));
    }
    count.clamp(1, MOST_SAMPLES)
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Pass {
    /// This many samples of every pixel.
    Samples(u64),
    /// The film's next sample, for these pixels.
    Slice(Range<usize>),
    /// Adaptive work (empty: the render has nothing left to do).
    Tiles(Vec<TileWork>),
}

/// What the last pass measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Measured {
    /// Time of one sample of the whole image.
    pub per_sample: Duration,
    /// Camera paths the last pass traced.
    pub paths: u64,
}

impl Measured {
    /// A pass of `paths` camera paths on a film of `pixels` that took `took`.
    pub fn of(paths: u64, took: Duration, pixels: usize) -> Measured {
        Measured {
            per_sample: took.mul_f64(pixels as f64 / paths.max(1) as f64),
            paths,
        }
    }

    /// The measurement to plan a restarted film with: the same cost, but a
    /// first pass of at most one sample of the image's `pixels`.
    pub fn after_change(self, pixels: u64) -> Measured {
        Measured {
            paths: self.paths.min(pixels / GROWTH).max(1),
            ..self
        }
    }
}

impl Pass {
    /// A pass of about `max_paths` camera paths on a film with no slice in
    /// progress: whole samples of every pixel (at least one; during an
    /// adaptive render's warm-up, up to its end), or after the warm-up, the
    /// next adaptive work.
    pub fn for_paths(film: &mut Film, quality: &Quality, max_paths: u64) -> Pass {
        if quality.adaptive && film.spp() >= WARMUP_SPP {
            return Pass::Tiles(film.adaptive_work(quality.goal(), max_paths));
        }
        let pixels = film.pixels().len() as u64;
        Pass::Samples(whole_samples_for(
            film,
            quality,
            (max_paths / pixels.max(1)).max(1),
        ))
    }

    /// Camera paths the pass traces on `film`.
    pub fn paths(&self, film: &Film) -> u64 {
        match self {
            Pass::Samples(n) => n * film.pixels().len() as u64,
            Pass::Slice(r) => r.len() as u64,
            Pass::Tiles(work) => work
                .iter()
                .map(|w| u64::from(w.count) * film.tiles().pixels(w.tile as usize))
                .sum(),
        }
    }

    /// Renders the pass into `film` on `backend`. Ok(false) when a CPU pass
    /// gave up for `cancelled`; the film must then be thrown away.
    pub fn run(
        &self,
        backend: &mut Backend,
        job: &RenderJob,
        film: &mut Film,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, BackendError> {
        match self {
            Pass::Samples(count) => backend.render_unless(job, film, *count, cancelled),
            Pass::Slice(range) => backend.render_slice(job, film, range.end, cancelled),
            Pass::Tiles(work) => backend.render_tiles(job, film, work, cancelled),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: Duration = Duration::from_millis(1);

    fn spp(n: u64) -> Quality {
        Quality {
            spp: Some(n),
            ..Quality::default()
        }
    }

    fn measured(per_sample: Duration, paths: u64) -> Option<Measured> {
        Some(Measured { per_sample, paths })
    }

    #[test]
    fn a_cheap_image_takes_whole_samples_for_the_pass_target() {
        let mut film = Film::new(64, 64);
        let big = 1 << 40;
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, measured(MS, big), &Quality::default()),
            Pass::Samples(30)
        );
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, measured(MS, big), &spp(8)),
            Pass::Samples(8)
        );
        let free = measured(Duration::ZERO, big);
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, free, &Quality::default()),
            Pass::Samples(MOST_SAMPLES)
        );
        // At most four times the last pass's paths.
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, measured(MS, 4096 * 2), &Quality::default()),
            Pass::Samples(8)
        );
    }

    #[test]
    fn an_expensive_image_takes_slices_sized_to_the_pass_target() {
        let mut film = Film::new(100, 100);
        // 10,000 pixels in 300 ms: 1,000 pixels in 30 ms.
        let slow = measured(300 * MS, 1000);
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, slow, &Quality::default()),
            Pass::Slice(0..1000)
        );
        assert!(!film.commit_slice(1000, 0));
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, slow, &Quality::default()),
            Pass::Slice(1000..2000)
        );
        // A slice in progress continues even if samples have become cheap,
        // growing at most fourfold, and stops at the last pixel.
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, measured(MS, 1000), &Quality::default()),
            Pass::Slice(1000..5000)
        );
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, measured(MS, 1 << 20), &Quality::default()),
            Pass::Slice(1000..10_000)
        );
        // Never an empty slice, however slow.
        let glacial = measured(Duration::from_secs(1000), 1);
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, glacial, &Quality::default()),
            Pass::Slice(1000..1001)
        );
    }

    #[test]
    fn after_a_camera_change_the_first_pass_is_at_most_one_sample() {
        let mut film = Film::new(64, 64);
        let m = measured(MS, 1 << 30).map(|m| m.after_change(4096));
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, m, &Quality::default()),
            Pass::Samples(1)
        );
        let slow = measured(300 * MS, 1 << 30).map(|m| m.after_change(4096));
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, slow, &Quality::default()),
            Pass::Slice(0..409)
        );
    }

    #[test]
    fn the_first_pass_is_a_short_slice() {
        let mut film = Film::new(1000, 1000);
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut film, None, &Quality::default()),
            Pass::Slice(0..FIRST_PATHS as usize)
        );
        let mut tiny = Film::new(3, 3);
        assert_eq!(
            Planner::INTERACTIVE.plan(&mut tiny, None, &Quality::default()),
            Pass::Slice(0..9)
        );
    }
}
