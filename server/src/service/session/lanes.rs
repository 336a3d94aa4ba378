//! A session on every device (`backend: "all"`): each worker renders
//! blocks of sample indices of its own, sized to its measured speed, into
//! films of its own, and finished blocks join the session's film in index
//! order ([`crate::render::split`]). A worker whose device fails drops out
//! of the session and its block goes back to the others; nothing merged is
//! lost. An adaptive render splits its warm-up this way, then its rounds
//! run on the fastest device.

use super::{lock, Image, Session, SessionState};
use crate::render::adaptive::WARMUP_SPP;
use crate::render::pass::{Pass, Planner};
use crate::render::split::{DeviceShare, Ledger};
use crate::render::{Backend, Film, Quality};
use crate::service::metrics::Metrics;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ops::Range;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

/// The backend name a session on every device reports.
pub const NAME: &str = "all";

/// Who has which samples of a session on every device.
#[derive(Debug)]
pub struct Lanes {
    workers: usize,
    ledger: Ledger,
    /// Each worker's block in progress: a one-sample block whose slices
    /// take several passes.
    blocks: HashMap<usize, (Film, Range<u64>)>,
    /// Workers whose device failed on this session.
    dropped: BTreeSet<usize>,
    /// The uniform part is over: adaptive rounds go on on one device.
    rounds: bool,
}

/// Where the session's uniform samples end: its spp (none: no end), or
/// an adaptive render's warm-up.
fn limit(quality: &Quality) -> Option<u64> {
    match quality.adaptive {
        true => Some(quality.spp.map_or(WARMUP_SPP, |n| n.min(WARMUP_SPP))),
        false => quality.spp,
    }
}

impl Lanes {
    pub fn new(workers: usize, quality: &Quality) -> Self {
        Self {
            workers,
            ledger: Ledger::new(0, limit(quality)),
            blocks: HashMap::new(),
            dropped: BTreeSet::new(),
            rounds: false,
        }
    }

    /// Starts again from sample 0 (after a change). Dropped devices stay out.
    pub fn restart(&mut self, quality: &Quality) {
        *self = Self {
            dropped: std::mem::take(&mut self.dropped),
            ..Self::new(self.workers, quality)
        };
    }

    /// Whether the samples are still split across devices.
    pub fn uniform(&self) -> bool {
        !self.rounds
    }

    pub fn dropped(&self, worker: usize) -> bool {
        self.dropped.contains(&worker)
    }

    /// Whether `worker` has a block to go on with or one to take.
    pub fn has_work_for(&self, worker: usize) -> bool {
        self.blocks.contains_key(&worker) || self.ledger.can_claim()
    }

    /// The device that renders fastest of those still in (adaptive rounds
    /// go there).
    pub fn fastest(&self, devices: &BTreeMap<usize, DeviceShare>) -> Option<usize> {
        (0..self.workers)
            .filter(|w| !self.dropped(*w))
            .max_by(|a, b| {
                let speed = |w| devices.get(w).map_or(0.0, |d| d.samples_per_sec);
                speed(a).total_cmp(&speed(b))
            })
    }
}

impl Session {
    /// One pass of worker `worker` on a session on every device: its block
    /// in progress, or a new one sized to its last pass; then whatever
    /// finished blocks continue the film join it, and a frame goes out.
    pub(super) fn render_lane(
        &self,
        worker: usize,
        backend: &mut Backend,
        metrics: &Metrics,
    ) -> u64 {
        let Some(BlockPass {
            job,
            mut block,
            range,
            generation,
            pass,
        }) = self.take_block(worker)
        else {
            return 0;
        };
        let start = Instant::now();
        let cancelled = || self.current_generation.load(Ordering::Relaxed) != generation;
        // Never tiles: blocks are planned without adaptive sampling.
        let result =
            (backend.prepare(&job)).and_then(|()| pass.run(backend, &job, &mut block, &cancelled));
        let took = self.count_pass(start);
        let mut st = lock(&self.state);
        if st.generation != generation || self.is_deleted() || matches!(result, Ok(false)) {
            return 0; // a change made the block stale; the ledger restarted
        }
        let Some(split) = st.split.as_mut() else {
            return 0;
        };
        if let Err(e) = result {
            let device = backend.device();
            tracing::warn!(session = %self.id, %device, error = %e, "a device dropped out of the session; the others take its samples");
            split.ledger.give_back(range);
            split.dropped.insert(worker);
            let all_out = split.dropped.len() >= split.workers;
            let share = st
                .devices
                .entry(worker)
                .or_insert_with(|| DeviceShare::of(backend));
            share.failure = Some(e.to_string());
            if all_out {
                st.failure = Some(format!("every device failed; the last: {e}"));
                st.halted = true;
                drop(st);
                self.publish_status_only(NAME.to_owned(), device);
            } else {
                drop(st);
                self.wake_workers();
            }
            return 0;
        }
        let paths = pass.paths(&block);
        metrics.add_samples(backend.name(), paths);
        st.record(worker, backend, paths, took, block.pixels().len());
        if block.slice_start() != 0 || block.spp() < range.end - range.start {
            split_of(&mut st).blocks.insert(worker, (block, range));
            return paths;
        }
        metrics
            .rejected_samples
            .fetch_add(block.rejected(), Ordering::Relaxed);
        split_of(&mut st).ledger.finish(block);
        drop(st);
        self.merge(generation);
        paths
    }

    /// The block worker `worker` renders next and its pass: the one it has
    /// in progress, or a new one from the ledger.
    fn take_block(&self, worker: usize) -> Option<BlockPass> {
        let mut st = lock(&self.state);
        if st.halted {
            return None;
        }
        let measured = st.measured.get(&worker).copied();
        // Block passes never stop for spp (the ledger does) nor go adaptive.
        let quality = Quality {
            spp: None,
            adaptive: false,
            ..st.quality
        };
        let (width, height) = (st.width, st.height);
        let split = st.split.as_mut()?;
        let (mut film, range) = match split.blocks.remove(&worker) {
            Some(b) => b,
            None => {
                let pixels = width as usize * height as usize;
                let want = measured.map_or(1, |m| Planner::INTERACTIVE.whole_samples(pixels, m));
                let range = split.ledger.claim(want)?;
                (split.ledger.block_film(width, height, &range), range)
            }
        };
        let pass = match Planner::INTERACTIVE.plan(&mut film, measured, &quality) {
            Pass::Samples(n) => Pass::Samples(n.min(range.end - range.start - film.spp())),
            pass => pass,
        };
        Some(BlockPass {
            job: st.job.clone(),
            block: film,
            range,
            generation: st.generation,
            pass,
        })
    }

    /// Joins finished blocks that continue the film to it and publishes a
    /// frame, while any do. The O(pixels) work runs outside the lock with
    /// the film taken out of the state; a worker that finishes a block
    /// meanwhile leaves it in the ledger for this loop.
    fn merge(&self, generation: u64) {
        loop {
            let mut st = lock(&self.state);
            if st.generation != generation || self.is_deleted() {
                return;
            }
            let Some(mut film) = st.film.take() else {
                return; // another worker is merging: it will take ours too
            };
            let split = split_of(&mut st);
            let blocks = split.ledger.take_ready(film.next_sample());
            if blocks.is_empty() {
                st.film = Some(film);
                return;
            }
            drop(st);
            let mut emptied = Vec::with_capacity(blocks.len());
            for mut b in blocks {
                if film.absorb_emptying(&mut b) {
                    emptied.push(b);
                }
            }
            let image = Image::of(&film);
            let mut st = lock(&self.state);
            if st.generation != generation || self.is_deleted() {
                return; // the state has a fresh film
            }
            for b in emptied {
                split_of(&mut st).ledger.recycle(b);
            }
            let by = (NAME.to_owned(), st.device_list());
            let frame = self.frame(&mut st, &film, image, by, false);
            let quality = st.quality;
            if quality.adaptive && film.spp() >= WARMUP_SPP && !st.halted {
                split_of(&mut st).rounds = true;
            }
            st.film = Some(film);
            drop(st);
            self.frames.send_replace(Arc::new(frame));
            self.wake_workers();
        }
    }
}

/// What a worker renders of a session on every device in one pass.
struct BlockPass {
    job: Arc<crate::render::RenderJob>,
    /// The block's own film (samples `range.start..`).
    block: Film,
    range: Range<u64>,
    generation: u64,
    pass: Pass,
}

fn split_of(st: &mut SessionState) -> &mut Lanes {
    st.split.as_mut().expect("a session on every device")
}
