//! One render on several devices at once (`--backend all`).
//!
//! Samples are handed out in blocks of consecutive sample indices
//! ([`Ledger::claim`]), each sized to what its device renders in one pass.
//! A device renders its block into a film of its own ([`Film::block`]),
//! with the same per-(seed, pixel, sample index) random numbers any device
//! would use, and finished blocks join the render's film in index order
//! ([`Film::absorb`]). So the film always holds samples `0..spp` exactly as
//! on one device: the mean, the even/odd error estimate and the halt
//! conditions are unchanged, and which device took which block changes a
//! pixel only by the devices' own rounding (and f64 summation order).
//!
//! A device that fails gives its block back; the lowest indices given back
//! are handed out again before new ones, and nothing already merged is
//! touched: no accumulated sample is lost. The others go on.
//!
//! Adaptive sampling splits only its uniform warm-up; its rounds (tile
//! counts planned from the whole film) run on one device at a time.

use crate::render::adaptive::WARMUP_SPP;
use crate::render::backend::{Backend, BackendError};
use crate::render::film::Film;
use crate::render::job::RenderJob;
use crate::render::pass::{Measured, Planner};
use crate::render::progressive::{self, Progress};
use crate::render::quality::Quality;
use std::collections::BTreeMap;
use std::ops::Range;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Who has which samples of a split render.
#[derive(Debug, Default)]
pub struct Ledger {
    /// The lowest index never handed out.
    next: u64,
    /// Claims stop here (None: no end).
    limit: Option<u64>,
    /// Blocks given back by failed devices, lowest first.
    returned: Vec<Range<u64>>,
    /// Finished blocks waiting for the ones before them, by first index.
    finished: BTreeMap<u64, Film>,
    /// Merged blocks, emptied, for the next ones (a 1080p block film is
    /// 100 MB: allocating and zeroing one per block cost 10-15%, measured).
    spare: Vec<Film>,
}

impl Ledger {
    /// A ledger for a film that holds samples `0..start`, handing out
    /// indices below `limit`.
    pub fn new(start: u64, limit: Option<u64>) -> Self {
        Self {
            next: start,
            limit,
            ..Self::default()
        }
    }

    /// Hands out indices up to `limit` (never lower than those handed out).
    pub fn set_limit(&mut self, limit: Option<u64>) {
        self.limit = limit;
    }

    /// The next block of at most `want` (at least one) sample indices: a
    /// failed device's before new ones. None when every index below the
    /// limit is handed out.
    pub fn claim(&mut self, want: u64) -> Option<Range<u64>> {
        let want = want.max(1);
        if let Some(r) = self.returned.first_mut() {
            let block = r.start..(r.start + want).min(r.end);
            r.start = block.end;
            if r.is_empty() {
                self.returned.remove(0);
            }
            return Some(block);
        }
        let end = match self.limit {
            Some(limit) => (self.next + want).min(limit),
            None => self.next + want,
        };
        let block = self.next..end;
        self.next = end;
        (!block.is_empty()).then_some(block)
    }

    /// Whether [`Ledger::claim`] would hand out anything.
    pub fn can_claim(&self) -> bool {
        !self.returned.is_empty() || self.limit.is_none_or(|l| self.next < l)
    }

    /// Takes back a block that was not rendered (its device failed).
    pub fn give_back(&mut self, block: Range<u64>) {
        if !block.is_empty() {
            self.returned.push(block);
            self.returned.sort_by_key(|r| r.start);
        }
    }

    /// A device's finished block; it joins the film once the blocks before
    /// it have ([`Ledger::merge_into`]).
    pub fn finish(&mut self, block: Film) {
        self.finished.insert(block.first_sample(), block);
    }

    /// Adds to `film` every finished block that continues it, in index
    /// order; the samples per pixel added.
    pub fn merge_into(&mut self, film: &mut Film) -> u64 {
        let blocks = self.take_ready(film.next_sample());
        let mut added = 0;
        for mut b in blocks {
            let n = b.spp();
            if film.absorb_emptying(&mut b) {
                added += n;
                self.recycle(b);
            }
        }
        added
    }

    /// Keeps a block emptied by [`Film::absorb_emptying`] for [`Ledger::block_film`].
    pub fn recycle(&mut self, emptied: Film) {
        if emptied.spp() == 0 && self.spare.len() < 4 {
            self.spare.push(emptied);
        }
    }

    /// An empty film for the block `block` of a `width` x `height` render
    /// (a recycled one when there is one).
    pub fn block_film(&mut self, width: u32, height: u32, block: &Range<u64>) -> Film {
        let fits = |f: &Film| (f.width(), f.height()) == (width, height);
        match self.spare.iter().position(fits) {
            Some(i) => {
                let mut film = self.spare.swap_remove(i);
                film.reuse_block(block.start);
                film
            }
            None => Film::block(width, height, block.start),
        }
    }

    /// Takes out the finished blocks that continue a film whose next sample
    /// is `next`, in order.
    pub fn take_ready(&mut self, mut next: u64) -> Vec<Film> {
        let mut out = Vec::new();
        while let Some(block) = self.finished.remove(&next) {
            next = block.next_sample();
            out.push(block);
        }
        out
    }

    /// Whether `film` holds every sample below the limit (never, without one).
    pub fn all_in(&self, film: &Film) -> bool {
        self.returned.is_empty() && self.limit.is_some_and(|l| film.next_sample() >= l)
    }

    /// Finished blocks not yet merged.
    pub fn waiting(&self) -> usize {
        self.finished.len()
    }
}

/// What one device did in a split render.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct DeviceShare {
    /// `cpu` or `opencl`.
    pub backend: String,
    pub device: String,
    /// Camera paths it traced (merged or waiting to be).
    pub samples: u64,
    /// Time it spent rendering, in seconds.
    pub busy_s: f64,
    /// Camera paths per second of its own rendering time.
    pub samples_per_sec: f64,
    /// Why it dropped out, if it did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
}

impl DeviceShare {
    pub fn of(backend: &Backend) -> Self {
        Self::named(backend.name(), &backend.device())
    }

    /// A device that has rendered nothing yet.
    pub fn named(backend: &str, device: &str) -> Self {
        Self {
            backend: backend.to_owned(),
            device: device.to_owned(),
            ..Self::default()
        }
    }

    /// Counts from zero again (a new generation); a failure stays.
    pub fn restart(&mut self) {
        (self.samples, self.busy_s, self.samples_per_sec) = (0, 0.0, 0.0);
    }

    /// Counts a pass of `paths` camera paths that took `took`.
    pub fn add(&mut self, paths: u64, took: Duration) {
        self.samples += paths;
        self.busy_s += took.as_secs_f64();
        self.samples_per_sec = if self.busy_s > 0.0 {
            self.samples as f64 / self.busy_s
        } else {
            0.0
        };
    }
}

struct Shared<'a, F> {
    ledger: Ledger,
    film: &'a mut Film,
    shares: Vec<DeviceShare>,
    progress: Option<Progress>,
    stop: bool,
    on_progress: F,
    /// The lane whose turn it is to claim, where lanes take turns (see
    /// [`render_split_taking_turns`]); None: whoever comes first.
    turn: Option<usize>,
    /// Which lanes have claimed a block: every lane's first block comes
    /// before any lane's second (for up to [`FIRST_ROUND_WAIT`]), so that
    /// a device slow to start (a program to build) still renders a share
    /// of a short render instead of finding it all taken.
    started: Vec<bool>,
}

/// Longest a lane waits for the others' first claims.
const FIRST_ROUND_WAIT: Duration = Duration::from_secs(5);

/// The lane after `i`, round the list, that has not failed (`i` if none).
fn next_live(shares: &[DeviceShare], i: usize) -> usize {
    let n = shares.len();
    (1..=n)
        .map(|k| (i + k) % n)
        .find(|&j| shares[j].failure.is_none())
        .unwrap_or(i)
}

/// Renders `job` into `film` on every backend at once until `quality`
/// halts (an adaptive render's rounds then go on on the fastest device),
/// calling `on_progress` whenever the film grows. Fails only when every
/// device has failed; a device that fails drops out and its block is
/// rendered by the others. Returns the last progress and each device's
/// share, in the order of `backends`.
pub fn render_split(
    job: &RenderJob,
    backends: &mut [Backend],
    film: &mut Film,
    quality: &Quality,
    on_progress: impl FnMut(&Progress) + Send,
) -> Result<(Progress, Vec<DeviceShare>), BackendError> {
    split(job, backends, film, quality, on_progress, false)
}

/// [`render_split`] where the lanes that have not failed claim blocks in
/// turn, round the list: a test hook, so that a test of the merge certainly
/// merges blocks of every device, interleaved (left to the race, the lanes'
/// later blocks of a small render may all be one lane's).
#[doc(hidden)]
pub fn render_split_taking_turns(
    job: &RenderJob,
    backends: &mut [Backend],
    film: &mut Film,
    quality: &Quality,
    on_progress: impl FnMut(&Progress) + Send,
) -> Result<(Progress, Vec<DeviceShare>), BackendError> {
    split(job, backends, film, quality, on_progress, true)
}

fn split(
    job: &RenderJob,
    backends: &mut [Backend],
    film: &mut Film,
    quality: &Quality,
    on_progress: impl FnMut(&Progress) + Send,
    taking_turns: bool,
) -> Result<(Progress, Vec<DeviceShare>), BackendError> {
    let start = Instant::now();
    let target = progressive::spp_target(quality);
    let limit = match quality.adaptive {
        true => Some(target.map_or(WARMUP_SPP, |n| n.min(WARMUP_SPP))),
        false => target,
    };
    let shared = Mutex::new(Shared {
        ledger: Ledger::new(film.spp(), limit),
        film,
        shares: backends.iter().map(DeviceShare::of).collect(),
        progress: None,
        stop: false,
        on_progress,
        turn: taking_turns.then_some(0),
        started: vec![false; backends.len()],
    });
    let errors: Vec<Option<BackendError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (backends.iter_mut().enumerate())
            .map(|(i, backend)| {
                let shared = &shared;
                scope.spawn(move || device_loop(i, job, backend, shared, quality, start))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or(None))
            .collect()
    });
    let mut shared = shared.into_inner().unwrap_or_else(|e| e.into_inner());
    if errors.iter().all(Option::is_some) {
        if let Some(e) = errors.into_iter().flatten().next() {
            return Err(e);
        }
    }
    let mut progress = shared
        .progress
        .unwrap_or_else(|| Progress::of(shared.film, start.elapsed()));
    let halted = progressive::halted(quality, &progress);
    if quality.adaptive && !halted {
        // Rounds on the fastest device that did not fail.
        let fastest = (0..backends.len())
            .filter(|&i| shared.shares[i].failure.is_none())
            .max_by(|&a, &b| {
                let speed = |i: usize| shared.shares[i].samples_per_sec;
                speed(a).total_cmp(&speed(b))
            });
        if let Some(i) = fastest {
            let before = shared.film.total_samples();
            let t = Instant::now();
            let on = &mut shared.on_progress;
            progress = progressive::render(job, &mut backends[i], shared.film, quality, |p| {
                on(p);
            })?;
            let added = shared.film.total_samples() - before;
            shared.shares[i].add(added, t.elapsed());
            progress.elapsed = start.elapsed();
        }
    }
    Ok((progress, shared.shares))
}

/// One device's part: claim a block sized to its speed, render it, hand it
/// in, until the ledger is empty or the render halts. Returns the error
/// that made it drop out.
fn device_loop<F: FnMut(&Progress) + Send>(
    i: usize,
    job: &RenderJob,
    backend: &mut Backend,
    shared: &Mutex<Shared<'_, F>>,
    quality: &Quality,
    start: Instant,
) -> Option<BackendError> {
    let lock = || shared.lock().unwrap_or_else(|e| e.into_inner());
    let (width, height) = (job.width(), job.height());
    let pixels = u64::from(width) * u64::from(height);
    let mut want = 1u64;
    let drop_out = |s: &mut Shared<'_, F>, e: &BackendError| {
        s.shares[i].failure = Some(e.to_string());
        if s.turn == Some(i) {
            s.turn = Some(next_live(&s.shares, i));
        }
    };
    if let Err(e) = backend.prepare(job) {
        drop_out(&mut lock(), &e);
        return Some(e);
    }
    loop {
        let (block, mut film) = {
            let mut s = lock();
            if s.stop {
                return None;
            }
            let others_to_start = s.started[i]
                && start.elapsed() < FIRST_ROUND_WAIT
                && (s.shares.iter().zip(&s.started)).any(|(sh, &st)| !st && sh.failure.is_none());
            if (s.turn.is_some_and(|t| t != i) || others_to_start) && s.ledger.can_claim() {
                drop(s);
                std::thread::sleep(Duration::from_millis(2));
                continue;
            }
            match s.ledger.claim(want) {
                Some(b) => {
                    s.started[i] = true;
                    if s.turn.is_some() {
                        s.turn = Some(next_live(&s.shares, i));
                    }
                    let film = s.ledger.block_film(width, height, &b);
                    (b, film)
                }
                // All handed out: done once all is in, but a device that
                // fails may yet give its block back.
                None if s.ledger.all_in(s.film) => return None,
                None => {
                    drop(s);
                    std::thread::sleep(Duration::from_millis(2));
                    continue;
                }
            }
        };
        let t = Instant::now();
        let count = block.end - block.start;
        if let Err(e) = backend.render(job, &mut film, count) {
            let mut s = lock();
            tracing::warn!(device = %s.shares[i].device, error = %e, "a device dropped out of the render; the others take its samples");
            s.ledger.give_back(block);
            drop_out(&mut s, &e);
            return Some(e);
        }
        let took = t.elapsed();
        let mut s = lock();
        s.shares[i].add(count * pixels, took);
        // The backend may have fallen back to rayon: say what renders now.
        (s.shares[i].backend, s.shares[i].device) = (backend.name().to_owned(), backend.device());
        s.ledger.finish(film);
        let s = &mut *s;
        if s.ledger.merge_into(s.film) > 0 {
            let p = Progress::of(s.film, start.elapsed());
            (s.on_progress)(&p);
            s.stop = progressive::halted(quality, &p) && !quality.adaptive;
            s.progress = Some(p);
        }
        let measured = Measured::of(count * pixels, took, pixels as usize);
        want = Planner::BLOCK.whole_samples(pixels as usize, measured);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn claims_run_in_order_up_to_the_limit_and_given_back_blocks_come_first() {
        let mut l = Ledger::new(0, Some(10));
        assert_eq!(l.claim(4), Some(0..4));
        assert_eq!(l.claim(4), Some(4..8));
        l.give_back(0..4);
        assert_eq!(l.claim(3), Some(0..3));
        assert_eq!(l.claim(5), Some(3..4));
        assert_eq!(l.claim(5), Some(8..10));
        assert!(!l.can_claim());
        assert_eq!(l.claim(5), None);
        let mut open = Ledger::new(3, None);
        assert_eq!(open.claim(0), Some(3..4));
        assert!(open.can_claim());
    }

    #[test]
    fn blocks_join_the_film_in_index_order_only() {
        let mut film = Film::new(2, 2);
        let mut l = Ledger::new(0, None);
        let block = |first, n| {
            let mut f = Film::block(2, 2, first);
            for (i, p) in f.pixels_mut().iter_mut().enumerate() {
                for s in first..first + n {
                    p.add(
                        s,
                        crate::render::math::Vec3A::splat((i as u64 * 100 + s) as f32),
                    );
                }
            }
            f.commit(n, 0);
            f
        };
        l.finish(block(3, 2));
        assert_eq!(l.merge_into(&mut film), 0, "samples 0..3 are missing");
        l.finish(block(0, 3));
        assert_eq!(l.merge_into(&mut film), 5);
        assert_eq!(l.waiting(), 0);
        let mut one = Film::new(2, 2);
        let all = block(0, 5);
        assert!(one.absorb(&all));
        assert_eq!(film.pixels(), one.pixels());
        assert_eq!(film.spp(), 5);
        // A block that does not continue the film is refused.
        assert!(!film.absorb(&block(7, 1)));
        assert!(!film.absorb(&Film::block(3, 2, 5)));
        assert_eq!(film.spp(), 5);
    }
}
