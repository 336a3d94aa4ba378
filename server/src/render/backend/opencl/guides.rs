//! The denoiser's feature sums on the device (`render::features`): a
//! buffer of GUIDE_FLOATS floats per pixel, [albedo rgb, normal rgb],
//! beside the film for jobs that keep features, added to by the kernel
//! built with `FEATURES` and read back with the film. A job without
//! features binds a one-float buffer the kernel never touches.

use super::{call, Access, JobState, OpenClBackend, OpenClError};
use crate::render::film::Film;
use opencl3::memory::Buffer;
use opencl3::types::CL_BLOCKING;
use rayon::prelude::*;
use std::ops::Range;

/// Floats per pixel of the feature sums (`kernels/render.cl`).
pub(super) const GUIDE_FLOATS: usize = 6;

impl OpenClBackend {
    /// The feature buffer of a new state for `film`: zero for a fresh
    /// film, else the host's sums; one float where `guided` is false.
    pub(super) fn guide_buffer(
        &self,
        film: &Film,
        guided: bool,
    ) -> Result<Buffer<f32>, OpenClError> {
        if !guided {
            return self.buffer::<f32>(Access::ReadWrite, 1);
        }
        let floats = film.pixels().len() * GUIDE_FLOATS;
        let host = film.feature_sums();
        if host.is_empty() || (film.total_samples() == 0 && film.slice_start() == 0) {
            let mut b = self.buffer::<f32>(Access::ReadWrite, floats)?;
            fill_zero(self, &mut b, floats)?;
            return Ok(b);
        }
        self.upload(Access::ReadWrite, bytemuck::cast_slice::<_, f32>(host))
    }

    /// Zeroes a state's feature sums (a new block of the same job).
    pub(super) fn clear_guides(&self, s: &mut JobState) -> Result<(), OpenClError> {
        if s.guided {
            fill_zero(self, &mut s.guides, s.pixels * GUIDE_FLOATS)?;
        }
        Ok(())
    }

    /// Copies the device's feature sums of pixels `range` into `film`
    /// (nothing for a job without features).
    pub(super) fn read_guides(
        &mut self,
        film: &mut Film,
        range: Range<usize>,
    ) -> Result<(), OpenClError> {
        let Some(state) = self.states.last().filter(|s| s.guided) else {
            return Ok(());
        };
        if range.is_empty() {
            return Ok(());
        }
        let floats = range.len() * GUIDE_FLOATS;
        let sums = self.staging.get(&self.context, &self.queue, floats);
        let offset = range.start * GUIDE_FLOATS * std::mem::size_of::<f32>();
        #[allow(unsafe_code)]
        // SAFETY: a blocking read into a host slice of `floats` floats that
        // outlives the call, from float range.start x GUIDE_FLOATS of a
        // buffer of `pixels` x GUIDE_FLOATS (range.end <= pixels, as the
        // film read checks); f32 takes any bytes.
        unsafe {
            self.queue
                .enqueue_read_buffer(&state.guides, CL_BLOCKING, offset, sums, &[])
        }
        .map_err(call("feature read"))?;
        let (_, features) = film.parts_mut(true);
        (features[range].par_iter_mut())
            .zip(sums.par_chunks_exact(GUIDE_FLOATS))
            .with_min_len(4096)
            .for_each(|(f, s)| {
                f.albedo.copy_from_slice(&s[..3]);
                f.normal.copy_from_slice(&s[3..]);
            });
        Ok(())
    }
}

/// Fills the first `floats` floats of `b` with zeros.
fn fill_zero(cl: &OpenClBackend, b: &mut Buffer<f32>, floats: usize) -> Result<(), OpenClError> {
    #[allow(unsafe_code)]
    // SAFETY: fills `floats` floats, the buffer's size; the in-order queue
    // runs it before any later launch or read.
    unsafe {
        cl.queue
            .enqueue_fill_buffer(b, &[0f32], 0, floats * std::mem::size_of::<f32>(), &[])
    }
    .map_err(call("feature clear"))?;
    Ok(())
}
