//! Launching the `render` kernel: whole samples of the image in launches
//! of about [`super::LAUNCH_TARGET`], one launch of a range of pixels or of
//! adaptive tiles, and the read-back that makes the host film equal the
//! device's.

use super::{buffers, call, layout, OpenClBackend, OpenClError, ProgramKey};
use crate::render::film::Film;
use crate::render::job::RenderJob;
use opencl3::types::cl_uint;
use std::ptr;
use std::time::{Duration, Instant};

impl OpenClBackend {
    /// Adds `count` samples per pixel to `film`.
    pub fn render(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        count: u64,
    ) -> Result<(), OpenClError> {
        self.render_unless(job, film, count, &|| false).map(|_| ())
    }

    /// As [`Self::render`], but gives up between launches once `cancelled`
    /// says so (a change of view makes the pass useless): Ok(false), the
    /// film as it was and the device's state of this job dropped (rebuilt
    /// from the host's film if it is rendered again).
    pub fn render_unless(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        count: u64,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, OpenClError> {
        let start = Instant::now();
        let key = self.ready(job, film)?;
        let ready = start.elapsed();
        let result = self.launch_all(&key, count, film.pixels().len(), cancelled);
        if !matches!(result, Ok(true)) {
            // Given up, or failed: the device film may be half updated.
            self.states.pop();
        }
        if !result? {
            return Ok(false);
        }
        let launched = start.elapsed();
        self.read_back(film, count)?;
        // Where a pass's time goes (the latency example's breakdown).
        tracing::debug!(
            count,
            ready_ms = ready.as_secs_f64() * 1e3,
            launch_ms = (launched - ready).as_secs_f64() * 1e3,
            read_back_ms = (start.elapsed() - launched).as_secs_f64() * 1e3,
            "opencl render"
        );
        Ok(true)
    }

    /// Renders `count` samples of every pixel in launches of about
    /// `launch_target` (true), or stops before a launch once `cancelled`
    /// (false). Every launch has the same size (the whole image, or
    /// `launch_pixels` and the image in several launches): drivers such as
    /// PoCL compile a kernel anew for every new launch size. The number of
    /// samples per launch adapts to the measured time instead.
    fn launch_all(
        &mut self,
        key: &ProgramKey,
        count: u64,
        pixels: usize,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, OpenClError> {
        let target = self.launch_target.as_secs_f64();
        let tile = pixels.min(self.launch_pixels);
        let mut done = 0u64;
        while done < count {
            if cancelled() {
                return Ok(false);
            }
            let per_sample = self
                .states
                .last()
                .and_then(|s| s.per_sample)
                .map(|d| d.as_secs_f64());
            let n = match per_sample {
                Some(p) if p > 0.0 => ((target / p) as u64).clamp(1, count - done),
                Some(_) => count - done,
                None => 1,
            }
            .min(u64::from(u32::MAX));
            let mut slowest = Duration::ZERO;
            for offset in (0..pixels).step_by(tile) {
                let start = Instant::now();
                self.launch(key, offset, tile, pixels, n)?;
                slowest = slowest.max(start.elapsed());
            }
            if let Some(s) = self.states.last_mut() {
                s.spp += n;
                s.per_sample = Some(slowest / n as u32);
            }
            done += n;
        }
        Ok(true)
    }

    /// One launch of `size` work-items: samples `spp .. spp + n` of pixels
    /// `offset .. min(offset + size, pixels)`.
    pub(super) fn launch(
        &mut self,
        key: &ProgramKey,
        offset: usize,
        size: usize,
        pixels: usize,
        n: u64,
    ) -> Result<(), OpenClError> {
        self.launch_mode(key, (offset, size, pixels), n, layout::WORK_UNIFORM)
    }

    /// One launch of `size` work-items from `offset`, those from `end` on
    /// idle: uniform samples `spp .. spp + n`, or adaptive work by `mode`.
    pub(super) fn launch_mode(
        &mut self,
        key: &ProgramKey,
        (offset, size, end): (usize, usize, usize),
        n: u64,
        mode: u32,
    ) -> Result<(), OpenClError> {
        match &mut self.fail_after_launches {
            Some(0) => self.fail_launches = true,
            Some(n) => *n -= 1,
            None => {}
        }
        if self.fail_launches {
            return Err(OpenClError::Call {
                what: "kernel launch",
                code: "CL_OUT_OF_RESOURCES (injected)".into(),
            });
        }
        let state = self
            .states
            .last()
            .ok_or_else(|| OpenClError::Unavailable("no job".into()))?;
        let kernel = &self
            .programs
            .get(key)
            .ok_or_else(|| OpenClError::Unavailable("program cache".into()))?
            .1;
        let args = buffers::LaunchArgs {
            film: &state.film,
            guides: &state.guides,
            rejected: &state.rejected,
            first: state.first + state.spp,
            count: n as cl_uint,
            pixel_base: offset as cl_uint,
            pixel_end: (offset + size).min(end) as cl_uint,
            work: &state.work,
            mode,
        };
        #[allow(unsafe_code)]
        // SAFETY: `kernel` is a `render` kernel (programs are built from
        // kernels/render.cl and hold that kernel only).
        unsafe {
            state.scene.set_args(kernel, &args)?;
        }
        // Work-groups of a fixed size: an adaptive launch's busy work-items
        // sit at the start of the range, and a driver free to choose would
        // put them all in one large group, on one core or one SM.
        let local = [self.local_size];
        let global = [size.next_multiple_of(self.local_size)];
        #[allow(unsafe_code)]
        // SAFETY: every argument is set and the buffers live in `state` past
        // the `finish` below. The kernel reads as many objects, materials and
        // lights as `layout::pack` counted into the params with them, BVH
        // nodes and slots only as the nodes it uploaded reach (and only when
        // the params say the BVH is used), mesh nodes, triangles, normals
        // and slots only from the bases and within the counts `meshes::pack`
        // put in each instance, and
        // work-items at or past `pixel_end` return before touching the
        // film of `pixels` x FILM_FLOATS floats: uniform launches end at the
        // film's pixels; adaptive ones (`tiles.rs`) read entries only below
        // the count uploaded and name pixels inside the image.
        unsafe {
            self.queue.enqueue_nd_range_kernel(
                kernel.get(),
                1,
                ptr::null(),
                global.as_ptr(),
                local.as_ptr(),
                &[],
            )
        }
        .map_err(call("kernel launch"))?;
        self.queue.finish().map_err(call("kernel execution"))
    }

    fn read_back(&mut self, film: &mut Film, count: u64) -> Result<(), OpenClError> {
        let rejected = self.read_range(film, 0..film.pixels().len())?;
        film.commit(count, rejected);
        self.note_samples(film);
        Ok(())
    }

    /// Records what the device film now holds (the host film equals it).
    pub(super) fn note_samples(&mut self, film: &Film) {
        if let Some(s) = self.states.last_mut() {
            s.samples = film.total_samples();
        }
    }
}
