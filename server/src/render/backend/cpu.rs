//! The rayon backend: rows in parallel, each pixel's samples in index order.

use crate::render::film::Film;
use crate::render::job::RenderJob;
use rayon::prelude::*;
use std::sync::Arc;

#[derive(Debug, Default)]
pub struct CpuBackend {
    /// Why `auto` (or a failing device) left OpenCL, if it did.
    fallback_reason: Option<String>,
    /// A pool of its own (the server's, at low priority); None: rayon's global pool.
    pool: Option<Arc<rayon::ThreadPool>>,
}

impl CpuBackend {
    /// The rayon backend standing in for OpenCL, and why.
    pub fn fallback(reason: String) -> Self {
        Self {
            fallback_reason: Some(reason),
            pool: None,
        }
    }

    /// A backend whose render threads run at lower scheduling priority, so
    /// that on a busy machine the service's own threads (requests, frame
    /// encoding, WebSockets) still get the cores at once. Rendering takes
    /// whatever they leave, which is nearly everything.
    pub fn low_priority() -> Self {
        let pool = rayon::ThreadPoolBuilder::new()
            .thread_name(|i| format!("render-cpu-{i}"))
            .start_handler(|_| super::priority::lower_current_thread())
            .build()
            .map(Arc::new)
            .map_err(|e| tracing::warn!("no low-priority render pool ({e}); using the global one"))
            .ok();
        Self {
            fallback_reason: None,
            pool,
        }
    }

    pub fn device(&self) -> String {
        let threads = self.pool.as_ref().map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
        match &self.fallback_reason {
            Some(why) => format!("rayon, {threads} threads; {why}"),
            None => format!("rayon, {threads} threads"),
        }
    }

    /// Adds samples `film.spp() .. film.spp() + count` to every pixel.
    pub fn render(&mut self, job: &RenderJob, film: &mut Film, count: u64) {
        self.render_unless(job, film, count, &|| false);
    }

    /// As [`CpuBackend::render`], but gives up between rows once `cancelled`
    /// says so; returns false then, and the film is left half-updated (the
    /// caller throws it away).
    pub fn render_unless(&mut self, job: &RenderJob, film: &mut Film, count: u64, cancelled: &(dyn Fn() -> bool + Sync)) -> bool {
        let first = film.spp();
        let width = film.width() as usize;
        let work = |film: &mut Film| -> Option<u64> {
            film.pixels_mut()
                .par_chunks_mut(width)
                .enumerate()
                .map(|(y, row)| {
                    if cancelled() {
                        return None;
                    }
                    let mut rejected = 0u64;
                    for (x, px) in row.iter_mut().enumerate() {
                        for s in first..first + count {
                            if !px.add(s, job.sample(x as u32, y as u32, s)) {
                                rejected += 1;
                            }
                        }
                    }
                    Some(rejected)
                })
                .sum()
        };
        let rejected = match &self.pool {
            Some(pool) => pool.install(|| work(film)),
            None => work(film),
        };
        match rejected {
            Some(r) => {
                film.commit(count, r);
                true
            }
            None => false,
        }
    }
}
