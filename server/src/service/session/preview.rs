//! What a session shows before its film holds a whole sample, and between
//! whole samples when one takes long (a large image on a slow device):
//!
//! - a *preview*: after a change, when one sample of the image would take
//!   more than [`PREVIEW_ABOVE`] passes, the first pass renders the view at
//!   1/k of the resolution (k = 2, 4, 8 or 16: one sample of it fits a
//!   pass), and the frame shows it scaled up (each of its pixels covers
//!   k x k of the image), as interactive viewports start at a coarse pixel
//!   size. Its paths are paths of a smaller image (their own seeds), not
//!   samples of the film: the film starts at sample 0 after it.
//! - *partial frames*: while a sample is rendered in slices, at most every
//!   [`PARTIAL_EVERY`] while a client watches, a frame of the film as it
//!   stands: each pixel the mean of its own samples (one more for the rows
//!   done), the preview where a pixel has none yet.

use super::{lock, Frame, Session};
use crate::render::camera::CameraRays;
use crate::render::pass::Planner;
use crate::render::{Backend, Film, RenderJob, Scene};
use crate::service::metrics::Metrics;
use crate::service::scaled::Preview;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A preview is rendered when one sample of the image takes more than this
/// many pass targets (when a sample is rendered in slices).
pub const PREVIEW_ABOVE: f64 = 1.0;
/// The coarsest preview: 1/16 of the width and of the height.
const MOST_FACTOR: u32 = 16;
/// Partial frames (of a sample in progress) are published at most this often.
pub const PARTIAL_EVERY: Duration = Duration::from_millis(60);

/// The preview factor for an image one sample of which takes `per_sample`:
/// the smallest power of two that brings a sample of the preview within a
/// pass; None when a sample of the image is quick enough by itself.
pub fn factor(per_sample: Duration) -> Option<u32> {
    let passes = per_sample.as_secs_f64() / Planner::INTERACTIVE.target.as_secs_f64();
    if passes <= PREVIEW_ABOVE {
        return None;
    }
    let mut k = 2;
    while f64::from(k * k) < passes && k < MOST_FACTOR {
        k *= 2;
    }
    Some(k)
}

/// The job that renders the preview of `job` (the view of `scene`) at
/// 1/`factor` of its resolution: the same world, a smaller camera.
pub fn job(job: &RenderJob, scene: &Scene, factor: u32) -> RenderJob {
    let (w, h) = (job.width().div_ceil(factor), job.height().div_ceil(factor));
    RenderJob {
        camera: CameraRays::new(&scene.camera, w, h),
        ..job.with_new_id()
    }
}

/// A preview to render: its job, for which generation and film size.
pub(super) struct PreviewPlan {
    job: RenderJob,
    factor: u32,
    generation: u64,
    width: u32,
    height: u32,
}

impl Session {
    /// The preview worker `worker` should render now: once per generation,
    /// before the film's first sample, when the last pass measured one
    /// sample of the image at more than [`PREVIEW_ABOVE`] passes. Not for
    /// a session split across devices.
    pub(super) fn plan_preview(&self, worker: usize) -> Option<PreviewPlan> {
        let mut st = lock(&self.state);
        let fresh =
            (st.film.as_ref()).is_some_and(|f| f.total_samples() == 0 && f.slice_start() == 0);
        if st.preview_weighed || st.halted || st.split.is_some() || !fresh {
            return None;
        }
        st.preview_weighed = true;
        let factor = factor(st.measured.get(&worker)?.per_sample)?;
        Some(PreviewPlan {
            job: job(&st.job, &st.scene, factor),
            factor,
            generation: st.generation,
            width: st.width,
            height: st.height,
        })
    }

    /// Renders the preview and publishes its frame; the paths traced. A
    /// preview that fails or is overtaken by a change shows nothing (the
    /// film's own passes report a device's failure).
    pub(super) fn render_preview(
        &self,
        backend: &mut Backend,
        metrics: &Metrics,
        plan: PreviewPlan,
    ) -> u64 {
        let PreviewPlan {
            job,
            factor,
            generation,
            width,
            height,
        } = plan;
        let cancelled = || self.current_generation.load(Ordering::Relaxed) != generation;
        let mut film = Film::new(job.width(), job.height());
        let start = Instant::now();
        let result = backend
            .prepare(&job)
            .and_then(|()| backend.render_unless(&job, &mut film, 1, &cancelled));
        let took = self.count_pass(start);
        match result {
            Ok(true) => {}
            Ok(false) => return 0,
            Err(e) => {
                tracing::warn!(session = %self.id, error = %e, "preview failed");
                return 0;
            }
        }
        let preview = Preview::of(&film, factor);
        let pixels = preview.scaled_up(width, height);
        let paths = film.total_samples();
        let mut st = lock(&self.state);
        if st.generation != generation || self.is_deleted() {
            return 0;
        }
        metrics.add_samples(backend.name(), paths);
        st.preview = Some(preview.clone());
        st.last_frame = Instant::now();
        let mut frame = Frame::empty(
            self.seq.fetch_add(1, Ordering::Relaxed),
            generation,
            width,
            height,
            backend.name().to_owned(),
            backend.device(),
        );
        frame.elapsed_ms = st.restarted.elapsed().as_secs_f64() * 1e3;
        (frame.preview, frame.preview_image) = (Some(factor), Some(preview));
        frame.pixels = pixels;
        drop(st);
        tracing::debug!(session = %self.id, generation, factor, ms = took.as_secs_f64() * 1e3, "preview");
        self.frames.send_replace(Arc::new(frame));
        paths
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factor_brings_a_preview_sample_within_a_pass() {
        let pass = Planner::INTERACTIVE.target.as_secs_f64();
        assert_eq!(factor(Planner::INTERACTIVE.target), None);
        assert_eq!(
            factor(Planner::INTERACTIVE.target.mul_f64(PREVIEW_ABOVE)),
            None
        );
        assert_eq!(factor(Planner::INTERACTIVE.target.mul_f64(1.5)), Some(2));
        assert_eq!(factor(Planner::INTERACTIVE.target.mul_f64(3.0)), Some(2));
        assert_eq!(factor(Planner::INTERACTIVE.target.mul_f64(4.0)), Some(2));
        assert_eq!(factor(Planner::INTERACTIVE.target.mul_f64(4.5)), Some(4));
        // 1920x1080 on two cores: about 0.42 s a sample, 14 passes.
        assert_eq!(factor(Duration::from_secs_f64(0.42)), Some(4));
        assert_eq!(factor(Duration::from_secs(1000)), Some(MOST_FACTOR));
        for ms in [40u64, 70, 130, 500, 2000, 7000] {
            let k = factor(Duration::from_millis(ms)).expect("slow") as f64;
            assert!(ms as f64 / 1e3 / (k * k) <= pass || k == f64::from(MOST_FACTOR));
            assert!(
                ms as f64 / 1e3 / (k * k / 4.0) > pass,
                "{ms} ms: {k} is coarser than needed"
            );
        }
    }

    #[test]
    fn a_preview_fills_what_the_film_lacks() {
        let preview = Preview {
            factor: 2,
            width: 2,
            height: 2,
            pixels: vec![[1.0; 3], [2.0; 3], [3.0; 3], [4.0; 3]],
        };
        // A 3x3 image: the last row and column map to the last preview pixels.
        let up = preview.scaled_up(3, 3);
        let firsts: Vec<f32> = up.iter().map(|p| p[0]).collect();
        assert_eq!(firsts, [1.0, 1.0, 2.0, 1.0, 1.0, 2.0, 3.0, 3.0, 4.0]);
        let mut mean = vec![[9.0; 3]; 9];
        preview.fill(&mut mean, 3, 4);
        let firsts: Vec<f32> = mean.iter().map(|p| p[0]).collect();
        assert_eq!(firsts, [9.0, 9.0, 9.0, 9.0, 1.0, 2.0, 3.0, 3.0, 4.0]);
        // Resized for a stream: repeated up, averaged down.
        let (w, h, up) = preview.resized(4);
        assert_eq!((w, h), (4, 4));
        assert_eq!(
            up[0..4].iter().map(|p| p[0]).collect::<Vec<_>>(),
            [1.0, 1.0, 2.0, 2.0]
        );
        assert_eq!(up[12][0], 3.0);
        let (w, h, down) = preview.resized(1);
        assert_eq!((w, h, down[0][0]), (1, 1, 2.5));
    }
}
