//! The rayon backend: rows in parallel, each pixel's samples in index order.

use crate::render::film::Film;
use crate::render::job::RenderJob;
use rayon::prelude::*;

#[derive(Debug, Default)]
pub struct CpuBackend {
    /// Why `auto` (or a failing device) left OpenCL, if it did.
    fallback_reason: Option<String>,
}

impl CpuBackend {
    /// The rayon backend standing in for OpenCL, and why.
    pub fn fallback(reason: String) -> Self {
        Self {
            fallback_reason: Some(reason),
        }
    }

    pub fn device(&self) -> String {
        let threads = rayon::current_num_threads();
        match &self.fallback_reason {
            Some(why) => format!("rayon, {threads} threads; {why}"),
            None => format!("rayon, {threads} threads"),
        }
    }

    /// Adds samples `film.spp() .. film.spp() + count` to every pixel.
    pub fn render(&mut self, job: &RenderJob, film: &mut Film, count: u64) {
        let first = film.spp();
        let width = film.width() as usize;
        let rejected: u64 = film
            .pixels_mut()
            .par_chunks_mut(width)
            .enumerate()
            .map(|(y, row)| {
                let mut rejected = 0u64;
                for (x, px) in row.iter_mut().enumerate() {
                    for s in first..first + count {
                        if !px.add(s, job.sample(x as u32, y as u32, s)) {
                            rejected += 1;
                        }
                    }
                }
                rejected
            })
            .sum();
        film.commit(count, rejected);
    }
}
