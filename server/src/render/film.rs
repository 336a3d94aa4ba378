//! Accumulation: per-pixel f64 sums in two halves (even and odd sample
//! indices), and the error estimate they give.
//!
//! Every pixel holds the same number of samples, indices 0..spp, added in
//! index order, until adaptive sampling ([`crate::render::adaptive`])
//! gives each tile a count of its own; sums are f64 so a pixel keeps its value to ~1e-12 relative
//! after 1e8 samples, and the order of additions (hence the image, bit for
//! bit) does not depend on how samples were split into passes or threads.
//! Non-finite samples are rejected, counted, and contribute nothing.
//!
//! A sample may also be added to a range of pixels at a time (a slice, so
//! that a pass on an expensive scene stays short): pixels `0..next` then
//! hold one sample more than the rest until the last slice commits it.
//!
//! Error estimate: with A and B the means of the even and odd halves (n_a
//! and n_b samples) and M the mean of all n, E[(A - B)^2] = var (1/n_a +
//! 1/n_b) and var(M) = var / n, so (A - B)^2 n_a n_b / n^2 estimates M's
//! squared error without bias (ignoring the renderer's own bias). The film
//! reports the relative RMS error: sqrt(sum of those) / sqrt(sum of M^2)
//! over all pixels and channels, the same measure as [`relative_rms_error`]
//! against a reference.

use crate::render::adaptive::{self, Goal, TileError, TileState, TileWork, Tiles};
use crate::render::features::{FeatureSums, Features};
use crate::render::math::{is_finite3, Vec3A};
use pathstream_wire::error_estimate::relative;
use rayon::prelude::*;

/// The spread of samples per pixel over a film's pixels, as the status
/// reports it (a plain triple: the film fills the contract's own type).
pub use pathstream_wire::SppSpread;

/// Sums of one pixel.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable)]
pub struct PixelSums {
    pub even: [f64; 3],
    pub odd: [f64; 3],
}

impl PixelSums {
    /// Adds another pixel's sums (of other samples) to these.
    #[inline(always)]
    pub fn absorb(&mut self, other: &PixelSums) {
        for c in 0..3 {
            self.even[c] += other.even[c];
            self.odd[c] += other.odd[c];
        }
    }

    /// Adds sample number `sample`; returns false (and adds nothing) when
    /// it is NaN or infinite.
    #[inline(always)]
    pub fn add(&mut self, sample: u64, l: Vec3A) -> bool {
        if !is_finite3(l) {
            return false;
        }
        let half = if sample & 1 == 0 {
            &mut self.even
        } else {
            &mut self.odd
        };
        half[0] += f64::from(l.x);
        half[1] += f64::from(l.y);
        half[2] += f64::from(l.z);
        true
    }
}

#[derive(Clone, Debug)]
pub struct Film {
    width: u32,
    height: u32,
    pixels: Vec<PixelSums>,
    spp: u64,
    rejected: u64,
    /// Sample `spp` is in pixels `0..next` (0: no sample in progress).
    next: usize,
    /// Rejections among those pixels, counted when the sample completes.
    partial_rejected: u64,
    tiles: Tiles,
    /// Adaptive sampling's counts and round (empty until its first round).
    adaptive: TileState,
    /// The index of the film's first sample: 0, except for a block of
    /// samples rendered on one of several devices ([`Film::block`]).
    first: u64,
    /// Feature sums beside `pixels` for a denoiser (empty: none kept;
    /// see [`Film::parts_mut`]).
    features: Vec<FeatureSums>,
}

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            // Zeroed memory from the allocator: a large film's pages are
            // zeroed as the first pass touches them, not all up front
            // (100 MB at 1920x1080, under the session's lock).
            pixels: bytemuck::zeroed_vec(width as usize * height as usize),
            ..Self::empty(width, height, 0)
        }
    }

    /// A film with no pixel storage (the callers give it some).
    fn empty(width: u32, height: u32, first: u64) -> Self {
        Self {
            width,
            height,
            pixels: Vec::new(),
            spp: 0,
            rejected: 0,
            next: 0,
            partial_rejected: 0,
            tiles: Tiles::new(width, height),
            adaptive: TileState::default(),
            first,
            features: Vec::new(),
        }
    }

    /// An empty film for samples `first..` only: one device's share of a
    /// render split across several, added to the whole with [`Film::absorb`].
    pub fn block(width: u32, height: u32, first: u64) -> Self {
        Self {
            first,
            ..Self::new(width, height)
        }
    }

    /// The index of the film's first sample (0 but for a [`Film::block`]).
    pub fn first_sample(&self) -> u64 {
        self.first
    }

    /// The index of the next whole sample a backend adds: `spp` on a film
    /// that starts at sample 0.
    pub fn next_sample(&self) -> u64 {
        self.first + self.spp
    }

    /// Adds `block`, which holds whole samples `spp()..` of this film's
    /// pixels, as if they had been rendered here: afterwards the film holds
    /// samples `0..spp() + block.spp()`, split into even and odd halves as
    /// ever. Refused (false, nothing added) for a block that does not start
    /// at this film's next sample, that is of another size, holds part of a
    /// sample, or when either film has begun adaptive rounds.
    pub fn absorb(&mut self, block: &Film) -> bool {
        if !self.continued_by(block) {
            return false;
        }
        for (p, b) in self.pixels.iter_mut().zip(&block.pixels) {
            p.absorb(b);
        }
        self.absorb_features(&block.features);
        self.spp += block.spp;
        self.rejected += block.rejected;
        true
    }

    /// As [`Film::absorb`], and leaves `block`'s sums zero (in the same pass
    /// over memory), ready for [`Film::reuse_block`].
    pub fn absorb_emptying(&mut self, block: &mut Film) -> bool {
        if !self.continued_by(block) {
            return false;
        }
        for (p, b) in self.pixels.iter_mut().zip(block.pixels.iter_mut()) {
            p.absorb(b);
            *b = PixelSums::default();
        }
        self.absorb_features(&block.features);
        block.features.fill(FeatureSums::default());
        self.spp += block.spp;
        self.rejected += block.rejected;
        block.spp = 0;
        true
    }

    /// Makes a block emptied by [`Film::absorb_emptying`] an empty block
    /// for samples `first..`, keeping its memory.
    pub fn reuse_block(&mut self, first: u64) {
        debug_assert_eq!(self.spp, 0, "an emptied block");
        let pixels = std::mem::take(&mut self.pixels);
        let features = std::mem::take(&mut self.features);
        *self = Self {
            pixels,
            features,
            ..Self::empty(self.width, self.height, first)
        };
    }

    /// Adds a block's feature sums (keeping some from then on if it does).
    fn absorb_features(&mut self, block: &[FeatureSums]) {
        if block.is_empty() {
            return;
        }
        if self.features.is_empty() {
            self.features = bytemuck::zeroed_vec(self.pixels.len());
        }
        for (f, b) in self.features.iter_mut().zip(block) {
            f.absorb(b);
        }
    }

    /// Whether `block` holds whole samples that continue this film.
    fn continued_by(&self, block: &Film) -> bool {
        block.first == self.next_sample()
            && (block.width, block.height) == (self.width, self.height)
            && block.next == 0
            && self.next == 0
            && !block.adaptive.started()
            && !self.adaptive.started()
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Samples per pixel every pixel holds (once adaptive rounds begin,
    /// those of the warm-up; tiles hold more).
    pub fn spp(&self) -> u64 {
        self.spp
    }

    /// Samples pixel `i` (row-major) holds.
    pub fn pixel_spp(&self, i: usize) -> u64 {
        let w = self.width as usize;
        self.spp + u64::from(i < self.next) + self.extra_at((i % w) as u32, (i / w) as u32)
    }

    /// Adaptive samples of pixel (x, y) beyond the uniform ones.
    fn extra_at(&self, x: u32, y: u32) -> u64 {
        match self.adaptive.started() {
            true => self.adaptive.extra[self.tiles.at(x, y)],
            false => 0,
        }
    }

    /// Samples per pixel of tile `t` (whole samples only).
    pub fn tile_spp(&self, t: usize) -> u64 {
        self.spp + self.adaptive.extra.get(t).copied().unwrap_or(0)
    }

    /// The film's tiles (adaptive sampling's unit).
    pub fn tiles(&self) -> &Tiles {
        &self.tiles
    }

    /// Camera paths the film holds (all pixels' samples).
    pub fn total_samples(&self) -> u64 {
        let uniform = self.spp * self.pixels.len() as u64 + self.next as u64;
        let extra: u64 = (self.adaptive.pixels_at.iter()).map(|(n, p)| n * p).sum();
        uniform + extra
    }

    /// Mean samples per pixel, rounded down (equal to [`Film::spp`] until
    /// adaptive rounds begin).
    pub fn mean_spp(&self) -> u64 {
        self.total_samples() / (self.pixels.len() as u64).max(1)
    }

    /// The least, median and most samples a pixel holds.
    pub fn spp_spread(&self) -> SppSpread {
        if !self.adaptive.started() {
            let top = self.spp + u64::from(self.next > 0);
            let median = self.pixel_spp(self.pixels.len() / 2);
            return SppSpread {
                min: self.spp,
                median: if self.next > 0 { median } else { self.spp },
                max: top,
            };
        }
        let at = &self.adaptive.pixels_at;
        let half = self.pixels.len() as u64 / 2;
        let mut seen = 0;
        let median = at
            .iter()
            .find(|(_, p)| {
                seen += *p;
                seen > half
            })
            .map_or(0, |(n, _)| self.spp + n);
        SppSpread {
            min: at.keys().next().map_or(0, |n| self.spp + n),
            median,
            max: at.keys().next_back().map_or(0, |n| self.spp + n),
        }
    }

    /// Whether adaptive rounds have begun.
    pub fn adaptive_started(&self) -> bool {
        self.adaptive.started()
    }

    /// Whether every tile reached its share of the target error.
    pub fn converged(&self) -> bool {
        self.adaptive.started() && self.adaptive.done.iter().all(|&d| d)
    }

    /// Which tiles reached their share of the target error.
    pub fn tiles_done(&self) -> &[bool] {
        &self.adaptive.done
    }

    /// Adaptive rounds planned so far.
    pub fn rounds(&self) -> u64 {
        self.adaptive.rounds
    }

    /// The next adaptive work for `goal`: the front of the current round,
    /// at most `max_paths` camera paths (at least one sample of one tile),
    /// planning a round first when none is in progress. Empty when there
    /// is nothing left to do. Starts rounds on a film of whole samples.
    pub fn adaptive_work(&mut self, goal: Goal, max_paths: u64) -> Vec<TileWork> {
        self.adaptive_round(goal);
        self.adaptive.round.front(&self.tiles, max_paths)
    }

    /// Plans the next adaptive round for `goal` if none is in progress;
    /// whether there is work left (false: every tile is done, or the
    /// budget spent).
    pub fn adaptive_round(&mut self, goal: Goal) -> bool {
        debug_assert_eq!(self.next, 0, "adaptive rounds start on whole samples");
        if !self.adaptive.started() {
            self.adaptive = TileState::start(&self.tiles);
        }
        if self.adaptive.round.is_empty() {
            let counts: Vec<u64> = (0..self.tiles.count()).map(|t| self.tile_spp(t)).collect();
            let errors = self.tile_errors();
            let taken = self.total_samples();
            let done = &mut self.adaptive.done;
            let round = adaptive::plan_round(&self.tiles, &counts, &errors, done, goal, taken);
            if !round.is_empty() {
                self.adaptive.rounds += 1;
            }
            self.adaptive.round = adaptive::Round::new(round);
        }
        !self.adaptive.round.is_empty()
    }

    /// Records that `work` (what [`Film::adaptive_work`] returned) was
    /// added, `rejected` samples of it refused.
    pub fn commit_tiles(&mut self, work: &[TileWork], rejected: u64) {
        self.adaptive.commit(&self.tiles, work);
        self.rejected += rejected;
    }

    /// Each tile's estimated squared error and squared signal.
    pub fn tile_errors(&self) -> Vec<TileError> {
        let mut out = vec![TileError::default(); self.tiles.count()];
        self.for_each_pixel(|x, y, p, f| {
            let t = &mut out[self.tiles.at(x, y)];
            let (e, s) = f.error(p);
            t.err2 += e;
            t.sig2 += s;
        });
        out
    }

    /// Calls `visit(x, y, sums, factors)` for every pixel, row by row.
    fn for_each_pixel(&self, mut visit: impl FnMut(u32, u32, &PixelSums, &Factors)) {
        let w = self.width as usize;
        for y in 0..self.height {
            let row = &self.pixels[y as usize * w..][..w];
            self.for_each_in_row(y, row, &mut visit);
        }
    }

    /// [`Film::for_each_pixel`] for row `y` (its sums `row`).
    #[inline]
    fn for_each_in_row(
        &self,
        y: u32,
        row: &[PixelSums],
        mut visit: impl FnMut(u32, u32, &PixelSums, &Factors),
    ) {
        let start = y as usize * self.width as usize;
        let mut cached = Factors::of(0);
        for (x, p) in (0u32..).zip(row) {
            let i = start + x as usize;
            let n = self.spp + u64::from(i < self.next) + self.extra_at(x, y);
            if n != cached.n {
                cached = Factors::of(n);
            }
            visit(x, y, p, &cached);
        }
    }

    /// Samples rejected as NaN or infinite.
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// Starts again from sample 0 (a block: from its first sample).
    pub fn clear(&mut self) {
        *self = Film::block(self.width, self.height, self.first);
    }

    /// Pixels `0..n` already hold sample `spp` (0 when no sample is in
    /// progress): where the next slice starts.
    pub fn slice_start(&self) -> usize {
        self.next
    }

    /// Records that sample `spp` was added to pixels `slice_start()..end`,
    /// `rejected` of them refused; the sample counts once it reaches the
    /// last pixel. Returns whether it did.
    pub fn commit_slice(&mut self, end: usize, rejected: u64) -> bool {
        debug_assert!(end >= self.next && end <= self.pixels.len());
        self.next = end;
        self.partial_rejected += rejected;
        if end < self.pixels.len() {
            return false;
        }
        let r = std::mem::take(&mut self.partial_rejected);
        self.next = 0;
        self.commit(1, r);
        true
    }

    /// All sums, row-major.
    pub fn pixels(&self) -> &[PixelSums] {
        &self.pixels
    }

    /// All sums, row-major, for a backend to add to.
    pub fn pixels_mut(&mut self) -> &mut [PixelSums] {
        &mut self.pixels
    }

    /// The radiance sums and, where `features` asks for them, the feature
    /// sums beside them (allocated, zero, the first time: a film keeps
    /// features from the first sample of a job that wants them, as the
    /// service starts a new film for every change of quality). Empty
    /// feature sums when `features` is false.
    pub fn parts_mut(&mut self, features: bool) -> (&mut [PixelSums], &mut [FeatureSums]) {
        if features && self.features.is_empty() {
            self.features = bytemuck::zeroed_vec(self.pixels.len());
        }
        let kept = if features {
            &mut self.features[..]
        } else {
            &mut []
        };
        (&mut self.pixels, kept)
    }

    /// The feature sums (empty where the film keeps none).
    pub fn feature_sums(&self) -> &[FeatureSums] {
        &self.features
    }

    /// The mean albedo and normal of each pixel's samples, where the film
    /// keeps features (None otherwise).
    pub fn feature_means(&self) -> Option<Features> {
        if self.features.is_empty() {
            return None;
        }
        let n = self.pixels.len();
        let (mut albedo, mut normal) = (vec![[0f32; 3]; n], vec![[0f32; 3]; n]);
        let w = self.width as usize;
        (albedo.par_chunks_mut(w).zip(normal.par_chunks_mut(w)))
            .zip(self.features.par_chunks(w))
            .enumerate()
            .for_each(|(y, ((a, nr), row))| {
                let start = y * w;
                let mut cached = Factors::of(0);
                for (x, f) in row.iter().enumerate() {
                    let k = self.pixel_spp(start + x);
                    if k != cached.n {
                        cached = Factors::of(k);
                    }
                    let inv = cached.inv_n as f32;
                    a[x] = f.albedo.map(|v| v * inv);
                    nr[x] = f.normal.map(|v| v * inv);
                }
            });
        Some(Features {
            width: self.width,
            height: self.height,
            albedo,
            normal,
        })
    }

    /// Records that every pixel received `count` more samples, of which
    /// `rejected` (over the whole film) were refused.
    pub fn commit(&mut self, count: u64, rejected: u64) {
        debug_assert_eq!(
            self.next, 0,
            "whole samples added while a slice is in progress"
        );
        debug_assert!(
            !self.adaptive.started(),
            "uniform samples after adaptive rounds"
        );
        self.spp += count;
        self.rejected += rejected;
    }

    /// Mean radiance per pixel (of its own samples), row-major, top row
    /// first. Rows in parallel (a frame of a large film is published often).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; self.pixels.len()];
        let w = self.width as usize;
        (out.par_chunks_mut(w).zip(self.pixels.par_chunks(w)))
            .enumerate()
            .for_each(|(y, (o, row))| {
                self.for_each_in_row(y as u32, row, |x, _, p, f| {
                    o[x as usize] =
                        std::array::from_fn(|c| ((p.even[c] + p.odd[c]) * f.inv_n) as f32);
                });
            });
        out
    }

    /// Estimated relative RMS error of [`Film::mean`]; None below 2 spp.
    /// Rows in parallel, their sums added in row order (the same estimate
    /// on any number of threads).
    pub fn error_estimate(&self) -> Option<f64> {
        if self.spp < 2 {
            return None;
        }
        let mut rows = vec![(0.0f64, 0.0f64); self.height as usize];
        let w = self.width as usize;
        (rows.par_iter_mut().zip(self.pixels.par_chunks(w)))
            .enumerate()
            .for_each(|(y, (sums, row))| {
                self.for_each_in_row(y as u32, row, |_, _, p, f| {
                    let (e, s) = f.error(p);
                    sums.0 += e;
                    sums.1 += s;
                });
            });
        let (err2, sig2) = rows.iter().fold((0.0, 0.0), |a, r| (a.0 + r.0, a.1 + r.1));
        Some(relative(err2, sig2))
    }
}

/// What a pixel of n samples divides by: n_even and n_odd samples, and
/// n_even n_odd / n^2 (see the module's note on the estimate).
#[derive(Clone, Copy, Debug)]
struct Factors {
    n: u64,
    inv_n: f64,
    n_even: f64,
    n_odd: f64,
    scale: f64,
}

impl Factors {
    fn of(n: u64) -> Self {
        let (e, o, nf) = (n.div_ceil(2) as f64, (n / 2) as f64, n as f64);
        Self {
            n,
            inv_n: if n == 0 { 0.0 } else { 1.0 / nf },
            n_even: e,
            n_odd: o,
            scale: if n == 0 { 0.0 } else { e * o / (nf * nf) },
        }
    }

    /// The pixel's estimated squared error and squared mean, summed over
    /// channels (zero below two samples).
    #[inline]
    fn error(&self, p: &PixelSums) -> (f64, f64) {
        if self.n < 2 {
            return (0.0, 0.0);
        }
        let (mut err2, mut sig2) = (0.0, 0.0);
        for c in 0..3 {
            let d = p.even[c] / self.n_even - p.odd[c] / self.n_odd;
            let m = (p.even[c] + p.odd[c]) * self.inv_n;
            err2 += d * d * self.scale;
            sig2 += m * m;
        }
        (err2, sig2)
    }
}

/// Relative RMS error of `image` against `reference`:
/// sqrt(sum (image - reference)^2) / sqrt(sum reference^2).
pub fn relative_rms_error(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let (mut err2, mut sig2) = (0.0f64, 0.0f64);
    for (a, r) in image.iter().zip(reference) {
        for c in 0..3 {
            let d = f64::from(a[c]) - f64::from(r[c]);
            err2 += d * d;
            sig2 += f64::from(r[c]) * f64::from(r[c]);
        }
    }
    relative(err2, sig2)
}

#[cfg(test)]
#[path = "film_tests.rs"]
mod tests;
