//! The rayon backend: rows in parallel, each pixel's samples in index order.

use crate::render::film::Film;
use crate::render::job::RenderJob;
use rayon::prelude::*;

#[derive(Debug, Default)]
pub struct CpuBackend;

impl CpuBackend {
    pub fn device(&self) -> String {
        format!("rayon, {} threads", rayon::current_num_threads())
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
