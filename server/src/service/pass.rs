//! What one pass of a session renders: whole samples of every pixel, or,
//! where one sample of the image takes longer than a pass should, a slice
//! of one sample; after an adaptive render's warm-up, the next tiles of its
//! round. Either way a pass takes about [`PASS_TARGET`], so that a
//! worker's sessions share its device by time whatever their scenes cost.

use crate::render::adaptive::{TileWork, WARMUP_SPP};
use crate::render::{Film, Quality};
use std::ops::Range;
use std::time::Duration;

/// How long one pass of one session should take: short enough that a change
/// shows within a frame or two and that a worker's other sessions get their
/// turn soon, long enough to keep the device busy.
pub const PASS_TARGET: Duration = Duration::from_millis(30);
/// Camera paths in a session's first pass (its cost is not measured yet):
/// small, as one path of a deliberately expensive scene may take 50 ms on
/// a slow device. Later passes grow from it in a few steps.
pub const FIRST_PATHS: u64 = 16;
/// A pass traces at most this many times the paths of the one before: the
/// cost measured on one part of the image may not hold for the next.
const GROWTH: u64 = 4;
/// Most whole samples in one pass.
const MOST_SAMPLES: u64 = 1 << 16;

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
    /// The pass for `film` rendered with `quality`, given what the last
    /// pass measured (None before the first). An adaptive render's next
    /// round is planned here when the last one is done.
    pub fn plan(film: &mut Film, last: Option<Measured>, quality: &Quality) -> Pass {
        let (start, pixels) = (film.slice_start(), film.pixels().len());
        let Some(last) = last else {
            return Pass::Slice(start..(start + FIRST_PATHS as usize).min(pixels));
        };
        let most_paths = last.paths.max(1).saturating_mul(GROWTH);
        let (target, p) = (PASS_TARGET.as_secs_f64(), last.per_sample.as_secs_f64());
        let wanted = if p > 0.0 { target / p } else { f64::INFINITY }; // samples
        let adaptive = quality.adaptive && start == 0 && film.spp() >= WARMUP_SPP;
        if adaptive {
            let paths = (wanted * pixels as f64).min(most_paths as f64) as u64;
            return Pass::Tiles(film.adaptive_work(quality.goal(), paths.max(1)));
        }
        if start == 0 && wanted >= 1.0 && pixels as u64 <= most_paths {
            let mut count = whole_samples(pixels, last);
            if let Some(n) = quality.spp {
                count = count.min(n.saturating_sub(film.spp()));
            }
            if quality.adaptive {
                count = count.min(WARMUP_SPP - film.spp());
            }
            return Pass::Samples(count.clamp(1, MOST_SAMPLES));
        }
        let len = (wanted * pixels as f64).min(most_paths as f64) as usize;
        Pass::Slice(start..(start + len.max(1)).min(pixels))
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
}

/// Whole samples per pixel a pass on a film of `pixels` pixels with no
/// sample in progress takes, given what the last pass measured (1 where
/// it would take a slice of one sample instead).
pub fn whole_samples(pixels: usize, last: Measured) -> u64 {
    let most_paths = last.paths.max(1).saturating_mul(GROWTH);
    let p = last.per_sample.as_secs_f64();
    let wanted = if p > 0.0 {
        PASS_TARGET.as_secs_f64() / p
    } else {
        f64::INFINITY
    };
    if wanted < 1.0 || pixels as u64 > most_paths {
        return 1;
    }
    let count = (wanted.min(MOST_SAMPLES as f64) as u64).min(most_paths / pixels.max(1) as u64);
    count.clamp(1, MOST_SAMPLES)
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
            Pass::plan(&mut film, measured(MS, big), &Quality::default()),
            Pass::Samples(30)
        );
        assert_eq!(
            Pass::plan(&mut film, measured(MS, big), &spp(8)),
            Pass::Samples(8)
        );
        let free = measured(Duration::ZERO, big);
        assert_eq!(
            Pass::plan(&mut film, free, &Quality::default()),
            Pass::Samples(MOST_SAMPLES)
        );
        // At most four times the last pass's paths.
        assert_eq!(
            Pass::plan(&mut film, measured(MS, 4096 * 2), &Quality::default()),
            Pass::Samples(8)
        );
    }

    #[test]
    fn an_expensive_image_takes_slices_sized_to_the_pass_target() {
        let mut film = Film::new(100, 100);
        // 10,000 pixels in 300 ms: 1,000 pixels in 30 ms.
        let slow = measured(300 * MS, 1000);
        assert_eq!(
            Pass::plan(&mut film, slow, &Quality::default()),
            Pass::Slice(0..1000)
        );
        assert!(!film.commit_slice(1000, 0));
        assert_eq!(
            Pass::plan(&mut film, slow, &Quality::default()),
            Pass::Slice(1000..2000)
        );
        // A slice in progress continues even if samples have become cheap,
        // growing at most fourfold, and stops at the last pixel.
        assert_eq!(
            Pass::plan(&mut film, measured(MS, 1000), &Quality::default()),
            Pass::Slice(1000..5000)
        );
        assert_eq!(
            Pass::plan(&mut film, measured(MS, 1 << 20), &Quality::default()),
            Pass::Slice(1000..10_000)
        );
        // Never an empty slice, however slow.
        let glacial = measured(Duration::from_secs(1000), 1);
        assert_eq!(
            Pass::plan(&mut film, glacial, &Quality::default()),
            Pass::Slice(1000..1001)
        );
    }

    #[test]
    fn after_a_camera_change_the_first_pass_is_at_most_one_sample() {
        let mut film = Film::new(64, 64);
        let m = measured(MS, 1 << 30).map(|m| m.after_change(4096));
        assert_eq!(
            Pass::plan(&mut film, m, &Quality::default()),
            Pass::Samples(1)
        );
        let slow = measured(300 * MS, 1 << 30).map(|m| m.after_change(4096));
        assert_eq!(
            Pass::plan(&mut film, slow, &Quality::default()),
            Pass::Slice(0..409)
        );
    }

    #[test]
    fn the_first_pass_is_a_short_slice() {
        let mut film = Film::new(1000, 1000);
        assert_eq!(
            Pass::plan(&mut film, None, &Quality::default()),
            Pass::Slice(0..FIRST_PATHS as usize)
        );
        let mut tiny = Film::new(3, 3);
        assert_eq!(
            Pass::plan(&mut tiny, None, &Quality::default()),
            Pass::Slice(0..9)
        );
    }
}
