//! Adaptive work on the device: each tile from its own next sample on.
//!
//! Two ways to tell the kernel which tiles get how many samples (the
//! `mode` argument, [`TileDispatch`]): a compacted list of the tiles in the
//! work, one work-item per pixel of each, or one entry per tile of the
//! image and a launch over every pixel of the rows the work touches, those
//! of tiles without work returning at once. docs/BENCHMARKS.md measures
//! both (`cargo run --release --example adaptive_dispatch`): on PoCL they
//! are within noise of each other for passes of up to one sample of the
//! image, and dense is 10% faster for larger ones, so it is the default.
//! Each tile's count is split into powers of two, one launch per bit: every
//! work-item of a launch loops over the same number of samples. Launches keep one size either way (PoCL compiles a kernel anew
//! for each new size), and the touched rows come back to the host film.

use super::{call, layout, Access, OpenClBackend, OpenClError};
use crate::render::adaptive::{TileWork, TILE_SIZE};
use crate::render::film::Film;
use crate::render::job::RenderJob;
use opencl3::types::CL_BLOCKING;

/// How adaptive work reaches the kernel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TileDispatch {
    /// A compacted list of the tiles with work.
    List,
    /// An entry for every tile of the image.
    #[default]
    Dense,
}

impl OpenClBackend {
    /// Adds adaptive `work` to `film` (see [`Film::adaptive_work`]). On
    /// failure the film is as it was before the call.
    pub fn render_tiles(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        work: &[TileWork],
    ) -> Result<(), OpenClError> {
        let (Some(first), Some(last)) = (work.first(), work.last()) else {
            return Ok(());
        };
        let key = self.ready(job, film)?;
        let tiles = *film.tiles();
        let width = film.width() as usize;
        let row = |w: &TileWork| (w.tile / tiles.cols * TILE_SIZE) as usize;
        let rows = row(first)..(row(last) + TILE_SIZE as usize).min(tiles.height as usize);
        let at: Vec<u64> = work
            .iter()
            .map(|w| film.tile_spp(w.tile as usize))
            .collect();
        // Counts split into powers of two, low bits first: the launch for
        // bit b gives 2^b samples to every tile whose count has it, from
        // after the lower bits' samples (each pixel's stay in order).
        let most = work.iter().map(|w| w.count).max().unwrap_or(0);
        let result = (0..32 - most.leading_zeros())
            .try_for_each(|bit| {
                let below = (1u32 << bit) - 1;
                let entries = work
                    .iter()
                    .zip(&at)
                    .filter(|(w, _)| w.count >> bit & 1 == 1);
                let entries: Vec<(u32, u64)> = entries
                    .map(|(w, &at)| (w.tile, at + u64::from(w.count & below)))
                    .collect();
                self.launch_layer(&key, &tiles, (&rows, width), &entries, 1 << bit)
            })
            .and_then(|()| self.read_range(film, rows.start * width..rows.end * width));
        let rejected = match result {
            Ok(r) => r,
            Err(e) => {
                self.states.pop(); // the device film may be half updated
                return Err(e);
            }
        };
        film.commit_tiles(work, rejected);
        self.note_samples(film);
        Ok(())
    }

    /// Launches `count` samples for each (tile, first sample) of `entries`
    /// (tiles in the image `rows` of `width` pixels).
    fn launch_layer(
        &mut self,
        key: &super::ProgramKey,
        tiles: &crate::render::adaptive::Tiles,
        (rows, width): (&std::ops::Range<usize>, usize),
        entries: &[(u32, u64)],
        count: u64,
    ) -> Result<(), OpenClError> {
        let entry = |&(tile, at): &(u32, u64)| [tile, at as u32, (at >> 32) as u32, 1];
        let (list, base, end, mode) = match self.tile_dispatch {
            TileDispatch::List => {
                let end = entries.len() * (TILE_SIZE * TILE_SIZE) as usize;
                (
                    entries.iter().map(entry).collect(),
                    0,
                    end,
                    layout::WORK_LIST,
                )
            }
            TileDispatch::Dense => {
                let mut all = vec![[0u32; 4]; tiles.count()];
                for e in entries {
                    all[e.0 as usize] = entry(e);
                }
                (
                    all,
                    rows.start * width,
                    rows.end * width,
                    layout::WORK_DENSE,
                )
            }
        };
        self.upload_work(&list)?;
        // The size of the image's uniform launches (one compiled kernel).
        let size = (tiles.width as usize * tiles.height as usize).min(self.launch_pixels);
        (base..end)
            .step_by(size)
            .try_for_each(|offset| self.launch_mode(key, (offset, size, end), count, mode))
    }

    /// Puts `entries` in the current state's work buffer (grown as needed).
    fn upload_work(&mut self, entries: &[[u32; 4]]) -> Result<(), OpenClError> {
        let capacity = self.states.last().map_or(0, |s| s.work_capacity);
        if capacity < entries.len() {
            let grown = entries.len().next_power_of_two();
            let buffer = self.buffer(Access::ReadOnly, grown)?;
            if let Some(s) = self.states.last_mut() {
                (s.work, s.work_capacity) = (buffer, grown);
            }
        }
        let state = self
            .states
            .last_mut()
            .ok_or_else(|| OpenClError::Unavailable("no job".into()))?;
        #[allow(unsafe_code)]
        // SAFETY: a blocking write of `entries.len()` entries into a buffer
        // of at least that many (grown above); the host slice outlives it.
        unsafe {
            self.queue
                .enqueue_write_buffer(&mut state.work, CL_BLOCKING, 0, entries, &[])
                .map_err(call("work upload"))?;
        }
        Ok(())
    }
}
