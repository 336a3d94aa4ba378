//! One sample of a range of pixels (a slice), so that a pass on a scene
//! whose every sample is expensive still ends within its time.
//!
//! Launches keep the size of whole-image launches (drivers such as PoCL
//! compile a kernel anew for each new size); work-items past the slice's
//! end return at once. After the launches, the slice's pixels are read back
//! to the host film, so that the host always has what the device has and a
//! device state evicted mid-sample is rebuilt from the host exactly.

use super::{call, OpenClBackend, OpenClError, FILM_FLOATS};
use crate::render::film::Film;
use crate::render::job::RenderJob;
use opencl3::types::CL_BLOCKING;
use rayon::prelude::*;
use std::ops::Range;

impl OpenClBackend {
    /// Adds sample `film.next_sample()` to pixels `film.slice_start()..end`. On
    /// failure the film is as it was before the call.
    pub fn render_slice(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        end: usize,
    ) -> Result<(), OpenClError> {
        let key = self.ready(job, film)?;
        let (start, pixels) = (film.slice_start(), film.pixels().len());
        let tile = pixels.min(self.launch_pixels);
        let result = (start..end)
            .step_by(tile)
            .try_for_each(|offset| self.launch(&key, offset, tile, end, 1))
            .and_then(|()| self.read_range(film, start..end));
        let rejected = match result {
            Ok(r) => r,
            Err(e) => {
                self.states.pop(); // the device film may be half updated
                return Err(e);
            }
        };
        if let Some(s) = self.states.last_mut() {
            if end == pixels {
                (s.spp, s.next) = (s.spp + 1, 0);
            } else {
                s.next = end;
            }
        }
        film.commit_slice(end, rejected);
        self.note_samples(film);
        Ok(())
    }

    /// Copies the device film's pixels `range` into `film` and returns the
    /// rejections counted on the device since the last read.
    pub(super) fn read_range(
        &mut self,
        film: &mut Film,
        range: Range<usize>,
    ) -> Result<u64, OpenClError> {
        let state = self
            .states
            .last_mut()
            .ok_or_else(|| OpenClError::Unavailable("no job".into()))?;
        debug_assert!(range.end <= state.pixels);
        let floats = range.len() * FILM_FLOATS;
        let sums = self.staging.get(&self.context, &self.queue, floats);
        let mut rejected = [0u32];
        #[allow(unsafe_code)]
        // SAFETY: blocking reads into host slices that outlive the calls:
        // `range.len()` x FILM_FLOATS floats from float `range.start` x
        // FILM_FLOATS of a buffer of `pixels` x FILM_FLOATS (range.end <=
        // pixels), and one u32 of a one-u32 buffer; f32 and u32 take any
        // bytes.
        unsafe {
            if !range.is_empty() {
                let offset = range.start * FILM_FLOATS * std::mem::size_of::<f32>();
                self.queue
                    .enqueue_read_buffer(&state.film, CL_BLOCKING, offset, sums, &[])
                    .map_err(call("film read"))?;
            }
            self.queue
                .enqueue_read_buffer(&state.rejected, CL_BLOCKING, 0, &mut rejected, &[])
                .map_err(call("film read"))?;
        }
        let odd = FILM_FLOATS / 2;
        film.pixels_mut()[range.clone()]
            .par_iter_mut()
            .zip(sums.par_chunks_exact(FILM_FLOATS))
            .with_min_len(4096)
            .for_each(|(px, s)| {
                for c in 0..3 {
                    px.even[c] = f64::from(s[c]) + f64::from(s[3 + c]);
                    px.odd[c] = f64::from(s[odd + c]) + f64::from(s[odd + 3 + c]);
                }
            });
        // The device counter holds the rejections since the film was uploaded.
        let total = u64::from(rejected[0]);
        let new = total - state.rejected_reported.min(total);
        state.rejected_reported = total;
        self.read_guides(film, range)?;
        Ok(new)
    }
}
