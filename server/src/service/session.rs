//! A render session: scene, camera, light, quality and film, rendered pass
//! by pass by a worker thread, with the latest frame published through a
//! `watch` channel (newest wins; nobody waits for a slow reader). Changes
//! (camera, light, quality, scene) come in through [`Session::apply`], from
//! HTTP and the WebSocket alike.

use super::change::{patch_quality, Change};
use super::error::ApiError;
pub use super::frame::Frame;
use super::metrics::Metrics;
use super::pass::{Measured, Pass};
use super::worker::{BackendInfo, Waker};
use crate::render::film::SppSpread;
use crate::render::progressive::{self, Progress};
use crate::render::scene::LightInfo;
use crate::render::{Backend, Film, Quality, RenderJob, Scene};
use serde::Serialize;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard, OnceLock};
use std::time::{Duration, Instant};
use tokio::sync::watch;

/// Everything that a change restarts.
struct SessionState {
    pub scene_name: String,
    pub scene: Scene,
    pub width: u32,
    pub height: u32,
    pub quality: Quality,
    pub job: Arc<RenderJob>,
    /// None while a worker is rendering it.
    film: Option<Film>,
    pub generation: u64,
    restarted: Instant,
    halted: bool,
    /// Why rendering stopped early (a device error).
    pub failure: Option<String>,
    /// What the last pass measured (None: no pass yet since the change).
    measured: Option<Measured>,
}

pub struct Session {
    pub id: String,
    state: Mutex<SessionState>,
    /// The state's generation, readable without the lock (a pass in flight
    /// checks it to give up as soon as a change makes it useless).
    current_generation: AtomicU64,
    frames: watch::Sender<Arc<Frame>>,
    seq: AtomicU64,
    last_active: Mutex<Instant>,
    /// Connected WebSocket clients (a session with clients never expires).
    pub clients: AtomicUsize,
    /// Passes rendered, all generations (how the worker shares its device).
    passes: AtomicU64,
    /// Nanoseconds of those passes.
    render_ns: AtomicU64,
    /// Set by the worker that renders this session.
    waker: OnceLock<Waker>,
    /// Becomes true when the session is deleted ([`Session::close`]):
    /// waiting requests and WebSockets are answered at once.
    deleted: watch::Sender<bool>,
}

/// Status as `GET /api/sessions/{id}` reports it.
#[derive(Debug, Serialize)]
pub struct Status {
    pub id: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub camera: crate::render::scene::CameraJson,
    pub light: Option<LightInfo>,
    pub quality: Quality,
    /// `rendering` or `halted` (also after a device failure, see `failure`).
    pub state: &'static str,
    /// Samples per pixel (adaptive: the mean, rounded down).
    pub spp: u64,
    /// The least, median and most samples of a pixel.
    pub spp_spread: SppSpread,
    /// Adaptive tiles at their share of the target error, of `tiles`.
    pub tiles_done: usize,
    pub tiles: usize,
    pub error_estimate: Option<f64>,
    pub samples_per_sec: f64,
    pub elapsed_ms: f64,
    pub rejected: u64,
    pub backend: String,
    pub device: String,
    /// Time the device has spent rendering this session, all generations
    /// (how a worker shares its device among its sessions).
    pub render_ms: f64,
    pub generation: u64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// What the scene holds that is not rendered as given (unsupported
    /// material features, a default sky, automatic framing).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while holding the lock cannot leave the state half-written in a
    // way that matters more than stopping the service: carry on.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Session {
    pub fn new(
        id: String,
        scene_name: String,
        scene: Scene,
        width: u32,
        height: u32,
        quality: Quality,
        backend: BackendInfo,
    ) -> Self {
        let job = Arc::new(RenderJob::new(&scene, width, height, &quality));
        let (frames, _) = watch::channel(Arc::new(Frame::empty(
            0,
            0,
            width,
            height,
            backend.backend,
            backend.device,
        )));
        Self {
            id,
            state: Mutex::new(SessionState {
                scene_name,
                scene,
                width,
                height,
                quality,
                job,
                film: Some(Film::new(width, height)),
                generation: 0,
                restarted: Instant::now(),
                halted: false,
                failure: None,
                measured: None,
            }),
            frames,
            current_generation: AtomicU64::new(0),
            seq: AtomicU64::new(1),
            last_active: Mutex::new(Instant::now()),
            clients: AtomicUsize::new(0),
            passes: AtomicU64::new(0),
            render_ns: AtomicU64::new(0),
            waker: OnceLock::new(),
            deleted: watch::channel(false).0,
        }
    }

    /// Called once by the worker the session is placed on.
    pub(super) fn attach(&self, waker: Waker) {
        let _ = self.waker.set(waker);
    }

    /// Passes rendered so far, all generations included.
    pub fn passes(&self) -> u64 {
        self.passes.load(Ordering::Relaxed)
    }

    pub fn touch(&self) {
        *lock(&self.last_active) = Instant::now();
    }

    pub fn idle_for(&self) -> Duration {
        if self.clients.load(Ordering::Relaxed) > 0 {
            return Duration::ZERO;
        }
        lock(&self.last_active).elapsed()
    }

    pub fn subscribe(&self) -> watch::Receiver<Arc<Frame>> {
        self.frames.subscribe()
    }

    pub fn latest(&self) -> Arc<Frame> {
        self.frames.borrow().clone()
    }

    pub fn generation(&self) -> u64 {
        lock(&self.state).generation
    }

    pub fn status(&self) -> Status {
        let st = lock(&self.state);
        let frame = self.latest();
        let current = frame.generation == st.generation;
        // Only the camera, not the whole scene (this runs for every frame sent).
        let c = st.scene.camera.to_json();
        Status {
            id: self.id.clone(),
            scene: st.scene_name.clone(),
            width: st.width,
            height: st.height,
            camera: c,
            light: st.scene.light_info(),
            quality: st.quality,
            state: if st.halted { "halted" } else { "rendering" },
            spp: if current { frame.spp } else { 0 },
            spp_spread: if current {
                frame.spread
            } else {
                SppSpread::default()
            },
            tiles_done: match (&frame.density, current) {
                (Some(d), true) => d.done.iter().filter(|&&d| d).count(),
                _ => 0,
            },
            tiles: crate::render::adaptive::Tiles::new(st.width, st.height).count(),
            error_estimate: if current { frame.error_estimate } else { None },
            samples_per_sec: if current { frame.samples_per_sec } else { 0.0 },
            elapsed_ms: st.restarted.elapsed().as_secs_f64() * 1e3,
            rejected: if current { frame.rejected } else { 0 },
            backend: frame.backend.clone(),
            device: frame.device.clone(),
            render_ms: self.render_ns.load(Ordering::Relaxed) as f64 / 1e6,
            generation: st.generation,
            failure: st.failure.clone(),
            warnings: st.scene.warnings.clone(),
        }
    }

    /// Applies a change and restarts accumulation at sample 0; the status
    /// after it. A refused change (an error naming the field) changes nothing.
    pub fn apply(&self, change: Change) -> Result<Status, ApiError> {
        let mut st = lock(&self.state);
        // A new view of the same scene costs about what the old one did; a
        // new scene or quality may cost anything.
        let keeps_cost = matches!(change, Change::Camera(_) | Change::Light(_));
        match change {
            Change::Camera(edit) => st.scene = st.scene.edit_camera(&edit)?,
            Change::Light(edit) => st.scene = st.scene.edit_light(&edit)?,
            Change::Quality(patch) => st.quality = patch_quality(&st.quality, &patch)?,
            Change::Scene { name, scene } => {
                st.scene_name = name;
                st.scene = *scene;
            }
        }
        st.job = Arc::new(RenderJob::new(&st.scene, st.width, st.height, &st.quality));
        st.film = Some(Film::new(st.width, st.height));
        st.generation += 1;
        self.current_generation
            .store(st.generation, Ordering::Relaxed);
        tracing::debug!(session = %self.id, generation = st.generation, "changed");
        st.restarted = Instant::now();
        st.halted = false;
        st.failure = None;
        let pixels = u64::from(st.width) * u64::from(st.height);
        st.measured = st
            .measured
            .filter(|_| keeps_cost)
            .map(|m| m.after_change(pixels));
        let previous = self.latest();
        let frame = Frame::empty(
            self.seq.fetch_add(1, Ordering::Relaxed),
            st.generation,
            st.width,
            st.height,
            previous.backend.clone(),
            previous.device.clone(),
        );
        drop(st);
        self.frames.send_replace(Arc::new(frame));
        if let Some(waker) = self.waker.get() {
            waker.wake();
        }
        Ok(self.status())
    }

    /// Ends the session (it was deleted or expired): the pass in flight is
    /// cancelled, the film is freed, and everyone waiting on the session is
    /// told at once.
    pub fn close(&self) {
        self.current_generation.fetch_add(1, Ordering::Relaxed);
        {
            let mut st = lock(&self.state);
            st.halted = true;
            st.film = None;
        }
        self.deleted.send_replace(true);
    }

    pub fn is_deleted(&self) -> bool {
        *self.deleted.borrow()
    }

    /// Resolves once the session is deleted.
    pub async fn deleted(&self) {
        let mut rx = self.deleted.subscribe();
        let _ = rx.wait_for(|d| *d).await;
    }

    /// Whether a worker should give this session a pass.
    pub fn wants_render(&self) -> bool {
        let st = lock(&self.state);
        !st.halted && st.film.is_some()
    }

    /// One pass on `backend`: about [`super::pass::PASS_TARGET`] of samples, then a
    /// frame; or, when one sample of the whole image takes longer, that
    /// long a slice of one sample (a frame when it completes the sample).
    /// A change made meanwhile wins: the pass's film is thrown away.
    pub fn render_pass(&self, backend: &mut Backend, metrics: &Metrics) {
        let (job, mut film, generation, quality, pass) = {
            let mut st = lock(&self.state);
            if st.halted {
                return;
            }
            let Some(mut film) = st.film.take() else {
                return;
            };
            let pass = Pass::plan(&mut film, st.measured, &st.quality);
            (st.job.clone(), film, st.generation, st.quality, pass)
        };
        let rejected_before = film.rejected();
        let start = Instant::now();
        tracing::debug!(session = %self.id, generation, ?pass, "pass starts");
        let cancelled = || self.current_generation.load(Ordering::Relaxed) != generation;
        let result = backend.prepare(&job).and_then(|()| match pass.clone() {
            Pass::Samples(count) => backend.render_unless(&job, &mut film, count, &cancelled),
            Pass::Slice(range) => backend.render_slice(&job, &mut film, range.end, &cancelled),
            Pass::Tiles(work) => backend.render_tiles(&job, &mut film, &work, &cancelled),
        });
        // An adaptive render plans its next round now, so that the frame
        // says whether it is done.
        let finished_rounds = matches!(pass, Pass::Tiles(_))
            && matches!(result, Ok(true))
            && !film.adaptive_round(quality.goal());
        let took = start.elapsed();
        self.passes.fetch_add(1, Ordering::Relaxed);
        self.render_ns.fetch_add(
            took.as_nanos().min(u128::from(u64::MAX)) as u64,
            Ordering::Relaxed,
        );
        let (name, device) = (backend.name().to_owned(), backend.device());
        // The O(pixels) work on the film happens before taking the lock, so
        // that status requests and changes never wait for it.
        let finished = matches!(result, Ok(true));
        // A slice that leaves its sample unfinished publishes no frame.
        let whole = finished && film.slice_start() == 0;
        let (pixels, estimate, density) = if whole {
            let density = Arc::new(super::density::Density::of(&film));
            (film.mean(), film.error_estimate(), Some(density))
        } else {
            (Vec::new(), None, None)
        };
        let mut st = lock(&self.state);
        tracing::debug!(session = %self.id, generation, ms = took.as_secs_f64() * 1e3, "pass ends");
        if st.generation != generation || self.is_deleted() {
            return; // changed while rendering (that film is stale) or deleted
        }
        if matches!(result, Ok(false)) {
            return; // given up for a change; the state has a fresh film
        }
        if let Err(e) = result {
            tracing::error!(session = %self.id, error = %e, "rendering failed");
            st.failure = Some(e.to_string());
            st.halted = true;
            st.film = Some(film);
            drop(st);
            self.publish_status_only(name, device);
            return;
        }
        let paths = pass.paths(&film);
        metrics.add_samples(&name, paths);
        metrics
            .rejected_samples
            .fetch_add(film.rejected() - rejected_before, Ordering::Relaxed);
        let full = film.pixels().len() as f64 / paths.max(1) as f64;
        st.measured = Some(Measured {
            per_sample: took.mul_f64(full),
            paths,
        });
        if !whole {
            st.film = Some(film);
            return;
        }
        let progress = Progress::with_estimate(&film, st.restarted.elapsed(), estimate);
        st.halted =
            finished_rounds || (quality.halts() && progressive::halted(&quality, &progress));
        let frame = Frame {
            seq: self.seq.fetch_add(1, Ordering::Relaxed),
            generation,
            width: film.width(),
            height: film.height(),
            spp: progress.spp,
            spread: progress.spread,
            density,
            error_estimate: progress.error_estimate,
            samples_per_sec: progress.samples_per_sec,
            elapsed_ms: progress.elapsed.as_secs_f64() * 1e3,
            rejected: progress.rejected,
            halted: st.halted,
            backend: name,
            device,
            pixels,
            png: OnceLock::new(),
            encodings: Mutex::new(Vec::new()),
        };
        st.film = Some(film);
        drop(st);
        self.frames.send_replace(Arc::new(frame));
    }

    fn publish_status_only(&self, backend: String, device: String) {
        let previous = self.latest();
        let mut frame = Frame::empty(
            self.seq.fetch_add(1, Ordering::Relaxed),
            previous.generation,
            previous.width,
            previous.height,
            backend,
            device,
        );
        frame.halted = true;
        frame.spp = previous.spp;
        frame.spread = previous.spread;
        frame.density = previous.density.clone();
        frame.error_estimate = previous.error_estimate;
        frame.pixels = previous.pixels.clone();
        self.frames.send_replace(Arc::new(frame));
    }

    /// The first frame of the current generation with at least `min_spp`
    /// samples (or a halted one), waiting at most `timeout`; on timeout, the
    /// latest frame.
    pub async fn frame_with(
        &self,
        min_spp: u64,
        timeout: Duration,
    ) -> Result<Arc<Frame>, ApiError> {
        let mut rx = self.subscribe();
        let ready = |f: &Frame, generation: u64| {
            f.generation == generation && (f.spp >= min_spp || f.halted)
        };
        let wait = async {
            loop {
                let generation = self.generation();
                {
                    let f = rx.borrow_and_update();
                    if ready(&f, generation) {
                        return f.clone();
                    }
                }
                if rx.changed().await.is_err() {
                    return self.latest();
                }
            }
        };
        let gone = || ApiError::Gone(format!("session '{}' was deleted", self.id));
        if self.is_deleted() {
            return Err(gone());
        }
        tokio::select! {
            frame = tokio::time::timeout(timeout, wait) => Ok(frame.unwrap_or_else(|_| self.latest())),
            () = self.deleted() => Err(gone()),
        }
    }
}
