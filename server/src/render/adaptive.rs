//! Adaptive sampling: after a uniform warm-up, samples go where the error is.
//!
//! The film is cut into [`TILE_SIZE`] squares. Every pixel of a tile holds
//! the same number of samples, and each pixel's value stays the mean of its
//! own samples (indices 0..n in order, as in a uniform film), so the image
//! is the same estimate whatever the counts; only its noise moves.
//!
//! Rendering goes in rounds. A round is planned from the film alone (never
//! from timing), so the same seed and settings give the same rounds and the
//! same image on every thread count and pass size; passes then render the
//! round's work in order, as much of it as fits their time.
//!
//! Planning a round of B camera paths: tile t has P_t pixels of n_t samples
//! and the film's even/odd halves estimate its squared error e_t (summed over
//! its pixels and channels), hence its per-pixel variance v_t = e_t n_t / P_t.
//! The image's error, sum of v_t P_t / n_t, is least for a given total of
//! samples when n_t is proportional to sqrt(v_t) (a Lagrange multiplier), so
//! the round raises every tile towards c sqrt(v_t), with c as large as B
//! allows ("water filling"). A 2x2 tile's own estimate is too noisy to
//! steer by, so v_t is averaged with its eight neighbours' ([`SMOOTHING`]:
//! as if the tile were grown by a pixel on every side). No tile more than
//! doubles in one round and none falls below [`RATE_FLOOR`] of the mean
//! rate (a caustic the warm-up missed still gets found).
//!
//! With a target error e, tile t is done once its (smoothed) error
//! v_t P_t / n_t <= e^2 S P_t / P (S: the image's sum of squared means, P:
//! its pixels): the tiles' shares of the whole image's allowance, so that
//! when every tile is done the whole image is at the target. (Judged by its
//! own four pixels, a tile whose few samples happen to agree would stop,
//! and the image's estimate would read low.) A done tile gets no more
//! samples; a live one gets at most what its estimate says it still needs.

use std::cmp::Reverse;
use std::collections::BTreeMap;
use std::ops::Range;

/// Side of a tile in pixels. Measured at equal samples (64x64, 1024 spp,
/// four seeds, `examples/adaptive_bound.rs`; docs/RENDERER.md), with the
/// neighbours' smoothing: uniform's squared error over adaptive's on
/// cornell-glass is 1.53 with 4x4 tiles, 1.72 with 2x2 and 1.89 per pixel,
/// but per pixel `furnace` (even noise) loses 4% to estimates too noisy to
/// steer by; 2x2 keeps it at 1.00. 8x8 tiles cannot pass 1.39 there (the
/// unevenness of the true variance over them).
pub const TILE_SIZE: u32 = 2;
/// Uniform samples per pixel before the first round: enough for every
/// tile's error estimate to mean something.
pub const WARMUP_SPP: u64 = 16;
/// A round adds this fraction of the samples taken so far.
const ROUND_GROWTH: f64 = 0.5;
/// No live tile's sampling rate (sqrt of its variance) counts as less than
/// this fraction of the image's mean rate.
const RATE_FLOOR: f64 = 0.05;
/// Weights of a tile's own variance, its edge neighbours' and its corner
/// neighbours' in its rate: a 2x2 tile grown by a pixel on every side
/// covers half of each edge neighbour and a quarter of each corner one.
/// Measured against a plain 3x3 average (1, 1, 1): 1.72 against 1.63 on
/// cornell-glass at equal samples, the same on furnace.
const SMOOTHING: [f64; 3] = [1.0, 0.5, 0.25];

/// `count` more samples for every pixel of `tile`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileWork {
    pub tile: u32,
    pub count: u32,
}

/// The film's tiles: row-major, those on the right and bottom edges cut short.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tiles {
    pub width: u32,
    pub height: u32,
    pub cols: u32,
    pub rows: u32,
}

impl Tiles {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            cols: width.div_ceil(TILE_SIZE),
            rows: height.div_ceil(TILE_SIZE),
        }
    }

    pub fn count(&self) -> usize {
        self.cols as usize * self.rows as usize
    }

    /// The tile of pixel (x, y).
    pub fn at(&self, x: u32, y: u32) -> usize {
        (y / TILE_SIZE) as usize * self.cols as usize + (x / TILE_SIZE) as usize
    }

    /// Columns and rows of pixels in tile `t`.
    pub fn rect(&self, t: usize) -> (Range<u32>, Range<u32>) {
        let (tx, ty) = (t as u32 % self.cols, t as u32 / self.cols);
        let (x0, y0) = (tx * TILE_SIZE, ty * TILE_SIZE);
        (
            x0..(x0 + TILE_SIZE).min(self.width),
            y0..(y0 + TILE_SIZE).min(self.height),
        )
    }

    /// Pixels in tile `t`.
    pub fn pixels(&self, t: usize) -> u64 {
        let (xs, ys) = self.rect(t);
        u64::from(xs.len() as u32) * u64::from(ys.len() as u32)
    }
}

/// A tile's estimated squared error (sum over its pixels and channels of
/// the squared error of each mean) and its sum of squared means.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TileError {
    pub err2: f64,
    pub sig2: f64,
}

/// When an adaptive render stops.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Goal {
    /// Relative RMS error of the whole image.
    pub target_error: Option<f64>,
    /// Mean samples per pixel (the budget a uniform render would spend).
    pub spp: Option<u64>,
}

/// A round's work and how far it has got. Work goes layer by layer (one
/// sample of every tile still owed one, then the next), so that every pass
/// spreads over as many tiles as it can: the pixels a device renders in
/// parallel. A tile's samples within a pass are still consecutive.
#[derive(Clone, Debug, Default)]
pub struct Round {
    /// Samples per pixel each tile gets in the round, most first.
    work: Vec<TileWork>,
    /// Where the next pass starts: layer, and entry within it.
    cursor: (u32, usize),
    /// Where the pass handed out last ends.
    pending: (u32, usize),
}

impl Round {
    pub fn new(mut work: Vec<TileWork>) -> Self {
        work.sort_by(|a, b| b.count.cmp(&a.count).then(a.tile.cmp(&b.tile)));
        Self {
            work,
            ..Self::default()
        }
    }

    /// Entries owed a sample in `layer` (a prefix: the most come first).
    fn width(&self, layer: u32) -> usize {
        self.work.partition_point(|w| w.count > layer)
    }

    pub fn is_empty(&self) -> bool {
        self.width(self.cursor.0) == 0
    }

    /// The next work, at most `max_paths` camera paths but at least one
    /// sample of one tile, in tile order (empty when the round is done);
    /// [`Round::commit`] then records it.
    pub fn front(&mut self, tiles: &Tiles, max_paths: u64) -> Vec<TileWork> {
        let (mut layer, mut at) = self.cursor;
        let mut taken = vec![0u32; self.work.len()];
        let (mut paths, mut any) = (0u64, false);
        'layers: loop {
            let width = self.width(layer);
            if width == 0 {
                break;
            }
            while at < width {
                let cost = tiles.pixels(self.work[at].tile as usize);
                if any && paths + cost > max_paths {
                    break 'layers;
                }
                taken[at] += 1;
                (paths, any) = (paths + cost, true);
                at += 1;
            }
            (layer, at) = (layer + 1, 0);
        }
        self.pending = (layer, at);
        let mut out: Vec<TileWork> = (self.work.iter().zip(taken))
            .filter(|(_, n)| *n > 0)
            .map(|(w, count)| TileWork {
                tile: w.tile,
                count,
            })
            .collect();
        out.sort_by_key(|w| w.tile);
        out
    }

    /// Records that the work [`Round::front`] last handed out was rendered.
    pub fn commit(&mut self) {
        self.cursor = self.pending;
    }
}

/// A film's adaptive state: how far each tile is past the uniform samples,
/// which tiles are done, and the round in progress.
#[derive(Clone, Debug, Default)]
pub struct TileState {
    /// Samples per pixel of each tile beyond the film's uniform count
    /// (empty until the first round).
    pub extra: Vec<u64>,
    /// Pixels at each count of `extra`: the spread of samples and their
    /// total without a pass over the tiles (a 1080p film has half a
    /// million, and progress is reported after every pass).
    pub pixels_at: BTreeMap<u64, u64>,
    /// Tiles at their share of the target error (they stay done).
    pub done: Vec<bool>,
    pub round: Round,
    /// Rounds planned so far.
    pub rounds: u64,
}

impl TileState {
    /// The state when rounds begin: no tile past the uniform samples.
    pub fn start(tiles: &Tiles) -> Self {
        let n = tiles.count();
        Self {
            extra: vec![0; n],
            pixels_at: BTreeMap::from([(0, u64::from(tiles.width) * u64::from(tiles.height))]),
            done: vec![false; n],
            ..Self::default()
        }
    }

    /// Whether rounds have begun.
    pub fn started(&self) -> bool {
        !self.extra.is_empty()
    }

    /// Records that `work` (the round's last front) was rendered.
    pub fn commit(&mut self, tiles: &Tiles, work: &[TileWork]) {
        for w in work {
            let (t, p) = (w.tile as usize, tiles.pixels(w.tile as usize));
            let old = self.extra[t];
            if let Some(at) = self.pixels_at.get_mut(&old) {
                *at -= p;
                if *at == 0 {
                    self.pixels_at.remove(&old);
                }
            }
            self.extra[t] = old + u64::from(w.count);
            *self.pixels_at.entry(self.extra[t]).or_default() += p;
        }
        self.round.commit();
    }
}

/// Plans the next round. `counts[t]` is tile t's samples per pixel,
/// `errors[t]` its error; marks tiles done in `done` and returns the
/// round's work in tile order (empty: nothing left to do, every tile done
/// or no budget left). `taken` is the camera paths traced so far.
pub fn plan_round(
    tiles: &Tiles,
    counts: &[u64],
    errors: &[TileError],
    done: &mut [bool],
    goal: Goal,
    taken: u64,
) -> Vec<TileWork> {
    let pixels = u64::from(tiles.width) * u64::from(tiles.height);
    let mut budget = ((taken as f64 * ROUND_GROWTH) as u64).max(pixels);
    if let Some(spp) = goal.spp {
        budget = budget.min(spp.saturating_mul(pixels).saturating_sub(taken));
    }
    let size: Vec<f64> = (0..tiles.count()).map(|t| tiles.pixels(t) as f64).collect();
    let var = smoothed_variances(tiles, counts, errors);
    // A pixel's allowance of squared error, with a target.
    let signal: f64 = errors.iter().map(|t| t.sig2).sum();
    let allowance = goal.target_error.map(|e| e * e * signal / pixels as f64);
    if let Some(a) = allowance {
        for (t, d) in done.iter_mut().enumerate() {
            *d |= var[t] / counts[t] as f64 <= a;
        }
    }
    let live: Vec<usize> = (0..tiles.count()).filter(|&t| !done[t]).collect();
    if live.is_empty() || budget == 0 {
        return Vec::new();
    }
    let rate: Vec<f64> = var.iter().map(|v| v.sqrt()).collect();
    let weight: f64 = live.iter().map(|&t| size[t]).sum();
    let mean_rate = live.iter().map(|&t| rate[t] * size[t]).sum::<f64>() / weight;
    let rates: Vec<f64> = live
        .iter()
        .map(|&t| match mean_rate > 0.0 {
            true => rate[t].max(RATE_FLOOR * mean_rate),
            false => 1.0,
        })
        .collect();
    // At most double; with a target, at most what the estimate says is missing.
    let caps: Vec<f64> = live
        .iter()
        .map(|&t| {
            let n = counts[t] as f64;
            let needed = allowance.map_or(f64::INFINITY, |a| (var[t] / a - n).ceil().max(1.0));
            n.min(needed)
        })
        .collect();
    // Tile i's samples for a given c, and the round's paths (the live
    // tiles' counts and sizes side by side: this runs ~40 times).
    let had: Vec<f64> = live.iter().map(|&t| counts[t] as f64).collect();
    let px: Vec<f64> = live.iter().map(|&t| size[t]).collect();
    let want = |i: usize, c: f64| (c * rates[i] - had[i]).clamp(0.0, caps[i]);
    let paths = |c: f64| -> f64 { (0..live.len()).map(|i| want(i, c) * px[i]).sum() };
    // The largest c whose round fits the budget, to 1e-12 of itself (about
    // 40 halvings; no allocation: a 1080p film has half a million tiles).
    let (mut lo, mut hi) = (0.0f64, 0.0f64);
    for i in 0..live.len() {
        hi = hi.max((had[i] + caps[i]) / rates[i]);
    }
    if paths(hi) > budget as f64 {
        for _ in 0..200 {
            if hi - lo <= 1e-12 * hi {
                break;
            }
            let mid = 0.5 * (lo + hi);
            if paths(mid) <= budget as f64 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    } else {
        lo = hi;
    }
    let want: Vec<f64> = (0..live.len()).map(|i| want(i, lo)).collect();
    let mut counts_out: Vec<u64> = want.iter().map(|w| w.floor() as u64).collect();
    let mut left = budget as f64
        - (px.iter().zip(&counts_out))
            .map(|(p, &n)| n as f64 * p)
            .sum::<f64>();
    // What flooring left over: one sample more for the tiles that lost the
    // most, then (when the round would be empty) for the noisiest ones.
    // (Fractions in [0, 1) order as their bits do.)
    let mut order: Vec<(Reverse<u64>, usize)> = (want.iter().enumerate())
        .filter(|(_, w)| w.fract() > 0.0)
        .map(|(i, w)| (Reverse(w.fract().to_bits()), i))
        .collect();
    order.sort_unstable();
    for (_, i) in order {
        if px[i] <= left {
            counts_out[i] += 1;
            left -= px[i];
        }
    }
    if counts_out.iter().all(|&n| n == 0) {
        let noisiest = (0..live.len())
            .filter(|&i| size[live[i]] <= budget as f64)
            .max_by(|&a, &b| {
                let per = |i: usize| rates[i] / (counts[live[i]] as f64).sqrt();
                per(a).total_cmp(&per(b)).then(b.cmp(&a))
            });
        if let Some(i) = noisiest {
            counts_out[i] = 1;
        }
    }
    live.iter()
        .zip(counts_out)
        .filter(|(_, n)| *n > 0)
        .map(|(&t, n)| TileWork {
            tile: t as u32,
            count: n.min(u64::from(u32::MAX)) as u32,
        })
        .collect()
}

/// Each tile's per-pixel variance averaged with its eight neighbours'
/// (weights [`SMOOTHING`], by pixels): what its rate and its error are
/// judged by.
fn smoothed_variances(tiles: &Tiles, counts: &[u64], errors: &[TileError]) -> Vec<f64> {
    let (cols, rows) = (tiles.cols as i64, tiles.rows as i64);
    // Per tile: variance times pixels (err2 n), and pixels.
    let own: Vec<(f64, f64)> = (0..tiles.count())
        .map(|t| {
            (
                errors[t].err2.max(0.0) * counts[t] as f64,
                tiles.pixels(t) as f64,
            )
        })
        .collect();
    (0..tiles.count())
        .map(|t| {
            let (x, y) = (t as i64 % cols, t as i64 / cols);
            let (mut v, mut p) = (0.0, 0.0);
            for dy in -1..=1i64 {
                for dx in -1..=1i64 {
                    let (nx, ny) = (x + dx, y + dy);
                    if nx >= 0 && ny >= 0 && nx < cols && ny < rows {
                        let k = SMOOTHING[(dx.abs() + dy.abs()) as usize];
                        let (vn, pn) = own[(ny * cols + nx) as usize];
                        v += k * vn;
                        p += k * pn;
                    }
                }
            }
            v / p
        })
        .collect()
}

#[cfg(test)]
#[path = "adaptive_tests.rs"]
mod tests;
