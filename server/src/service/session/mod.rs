//! A render session: scene, camera, light, quality and film, rendered pass
//! by pass by a worker thread, with the latest frame published through a
//! `watch` channel (newest wins; nobody waits for a slow reader). Changes
//! (camera, light, quality, scene) come in through [`Session::apply`], from
//! HTTP and the WebSocket alike.

mod lanes;
mod pick;
mod preview;
mod status;

use super::change::{patch_quality, Change};
use super::error::ApiError;
pub use super::frame::Frame;
use super::metrics::Metrics;
use super::placement::BackendInfo;
use super::scaled::Preview;
use crate::render::features::Features;
use crate::render::pass::{Measured, Pass, Planner};
use crate::render::progressive::{self, Progress};
use crate::render::split::DeviceShare;
use crate::render::{Backend, Film, Quality, RenderJob, Scene};
use lanes::Lanes;
pub use status::Status;
use std::collections::{BTreeMap, HashMap};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
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
    /// What the last pass on each worker measured (none yet since the change).
    measured: HashMap<usize, Measured>,
    /// Set for a session on every device (`backend: "all"`): who has which samples.
    split: Option<Lanes>,
    /// What each worker rendered of this generation.
    devices: BTreeMap<usize, DeviceShare>,
    /// This generation's preview, once rendered (see [`preview`]).
    preview: Option<Arc<Preview>>,
    /// Whether this generation's preview was weighed (rendered or not).
    preview_weighed: bool,
    /// When the last frame with an image was published.
    last_frame: Instant,
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
    /// Set by the workers that render this session.
    wakers: Mutex<Vec<Waker>>,
    /// Becomes true when the session is deleted ([`Session::close`]):
    /// waiting requests and WebSockets are answered at once.
    deleted: watch::Sender<bool>,
}

/// Tells a worker that one of its sessions has work again. Held by the
/// session; it does not keep the worker alive.
pub type Waker = Box<dyn Fn() + Send + Sync>;

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    // A panic while holding the lock cannot leave the state half-written in a
    // way that matters more than stopping the service: carry on.
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// What a frame shows of a film: computed before taking the session's
/// lock (O(pixels)).
struct Image {
    pixels: Vec<[f32; 3]>,
    estimate: Option<f64>,
    density: Arc<super::density::Density>,
    /// Whether the film holds whole samples (else a sample is in progress).
    whole: bool,
    /// The preview factor, where the image shows the preview.
    preview: Option<u32>,
    /// The denoiser's guides, where the film keeps them.
    features: Option<Arc<Features>>,
}

impl Image {
    fn of(film: &Film) -> Self {
        Self {
            features: film.feature_means().map(Arc::new),
            pixels: film.mean(),
            estimate: film.error_estimate(),
            density: Arc::new(super::density::Density::of(film)),
            whole: true,
            preview: None,
        }
    }

    /// The film while a sample is in progress, the preview (if any) where
    /// it has no sample yet; no error estimate (the last frame's stands).
    fn partial(film: &Film, preview: Option<&Preview>) -> Self {
        let mut pixels = film.mean();
        let preview = preview.filter(|_| film.spp() == 0);
        if let Some(p) = preview {
            p.fill(&mut pixels, film.width(), film.slice_start());
        }
        Self {
            pixels,
            estimate: None,
            density: Arc::new(super::density::Density::of(film)),
            whole: false,
            preview: preview.map(|p| p.factor),
            features: film.feature_means().map(Arc::new),
        }
    }
}

impl SessionState {
    /// Records a pass on `worker` of `paths` camera paths on a film of
    /// `pixels` that took `took`: what the next pass there is sized by,
    /// and the worker's share.
    fn record(
        &mut self,
        worker: usize,
        backend: &Backend,
        paths: u64,
        took: Duration,
        pixels: usize,
    ) {
        self.measured
            .insert(worker, Measured::of(paths, took, pixels));
        let share = self
            .devices
            .entry(worker)
            .or_insert_with(|| DeviceShare::of(backend));
        (share.backend, share.device) = (backend.name().to_owned(), backend.device());
        share.add(paths, took);
    }

    /// The devices a session on every device renders on, for its frames.
    fn device_list(&self) -> String {
        let names: Vec<&str> = self.devices.values().map(|d| d.device.as_str()).collect();
        names.join("; ")
    }
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
                measured: HashMap::new(),
                split: None,
                devices: BTreeMap::new(),
                preview: None,
                preview_weighed: false,
                last_frame: Instant::now(),
            }),
            frames,
            current_generation: AtomicU64::new(0),
            seq: AtomicU64::new(1),
            last_active: Mutex::new(Instant::now()),
            clients: AtomicUsize::new(0),
            passes: AtomicU64::new(0),
            render_ns: AtomicU64::new(0),
            wakers: Mutex::new(Vec::new()),
            deleted: watch::channel(false).0,
        }
    }

    /// Makes this a session rendered on every one of `workers` (what each
    /// renders with, by worker number) at once; each places it with
    /// [`Session::attach`]. Status lists every device from the start.
    pub fn on_every_device(self, workers: &[BackendInfo]) -> Self {
        {
            let mut st = lock(&self.state);
            st.split = Some(Lanes::new(workers.len(), &st.quality));
            st.devices = (workers.iter().enumerate())
                .map(|(i, w)| (i, DeviceShare::named(&w.backend, &w.device)))
                .collect();
        }
        self
    }

    /// Whether the session renders on every device.
    pub fn is_split(&self) -> bool {
        lock(&self.state).split.is_some()
    }

    /// Called by each worker the session is placed on.
    pub(in crate::service) fn attach(&self, waker: Waker) {
        lock(&self.wakers).push(waker);
    }

    fn wake_workers(&self) {
        for wake in lock(&self.wakers).iter() {
            wake();
        }
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
            Change::Environment { json, map } => {
                st.scene = super::change::with_environment(&st.scene, json, map)?;
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
        (st.preview, st.preview_weighed) = (None, false);
        let pixels = u64::from(st.width) * u64::from(st.height);
        if !keeps_cost {
            st.measured.clear();
        }
        for m in st.measured.values_mut() {
            *m = m.after_change(pixels);
        }
        for share in st.devices.values_mut() {
            share.restart();
        }
        let quality = st.quality;
        if let Some(split) = &mut st.split {
            split.restart(&quality);
        }
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
        self.wake_workers();
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

    /// Whether worker `worker` should give this session a pass.
    pub fn wants_render(&self, worker: usize) -> bool {
        let st = lock(&self.state);
        if st.halted {
            return false;
        }
        match &st.split {
            None => st.film.is_some(),
            Some(split) if split.dropped(worker) => false,
            Some(split) if split.uniform() => split.has_work_for(worker),
            // Adaptive rounds: on the fastest device, one pass at a time.
            Some(split) => st.film.is_some() && split.fastest(&st.devices) == Some(worker),
        }
    }

    /// One pass on `backend` (worker `worker`): about
    /// [`Planner::INTERACTIVE`]'s target of samples, then a frame; or, when one
    /// sample of the whole image takes longer, that long a slice of one
    /// sample (a frame when it completes the sample). A change made
    /// meanwhile wins: the pass's film is thrown away. A session on every
    /// device renders a block of its own here instead (see [`lanes`]).
    /// Returns the camera paths traced.
    pub fn render_pass(&self, worker: usize, backend: &mut Backend, metrics: &Metrics) -> u64 {
        if lock(&self.state).split.as_ref().is_some_and(Lanes::uniform) {
            return self.render_lane(worker, backend, metrics);
        }
        if let Some(plan) = self.plan_preview(worker) {
            return self.render_preview(backend, metrics, plan);
        }
        let (job, mut film, generation, quality, pass, preview, partial_due) = {
            let mut st = lock(&self.state);
            if st.halted {
                return 0;
            }
            let Some(mut film) = st.film.take() else {
                return 0;
            };
            let measured = st.measured.get(&worker).copied();
            let pass = Planner::INTERACTIVE.plan(&mut film, measured, &st.quality);
            let watched = self.clients.load(Ordering::Relaxed) > 0;
            // Due if it will be by the time the pass ends.
            let partial_due = watched
                && st.last_frame.elapsed() + Planner::INTERACTIVE.target >= preview::PARTIAL_EVERY;
            let preview = st.preview.clone();
            (
                st.job.clone(),
                film,
                st.generation,
                st.quality,
                pass,
                preview,
                partial_due,
            )
        };
        let rejected_before = film.rejected();
        let start = Instant::now();
        tracing::debug!(session = %self.id, generation, ?pass, "pass starts");
        let cancelled = || self.current_generation.load(Ordering::Relaxed) != generation;
        let result =
            (backend.prepare(&job)).and_then(|()| pass.run(backend, &job, &mut film, &cancelled));
        // An adaptive render plans its next round now, so that the frame
        // says whether it is done.
        let finished_rounds = matches!(pass, Pass::Tiles(_))
            && matches!(result, Ok(true))
            && !film.adaptive_round(quality.goal());
        let took = self.count_pass(start);
        let (name, device) = (backend.name().to_owned(), backend.device());
        // The O(pixels) work on the film happens before taking the lock, so
        // that status requests and changes never wait for it.
        let finished = matches!(result, Ok(true));
        // A slice that leaves its sample unfinished publishes a frame only
        // while someone watches, and not too often (see [`preview`]).
        let whole = finished && film.slice_start() == 0;
        let partial = finished && !whole && partial_due && matches!(pass, Pass::Slice(_));
        let imaged = Instant::now();
        let image = match (whole, partial) {
            (true, _) => Some(Image::of(&film)),
            (false, true) => Some(Image::partial(&film, preview.as_deref())),
            (false, false) => None,
        };
        let image_ms = imaged.elapsed().as_secs_f64() * 1e3;
        let mut st = lock(&self.state);
        tracing::debug!(
            session = %self.id,
            generation,
            ms = took.as_secs_f64() * 1e3,
            image_ms,
            "pass ends"
        );
        if st.generation != generation || self.is_deleted() {
            return 0; // changed while rendering (that film is stale) or deleted
        }
        if matches!(result, Ok(false)) {
            return 0; // given up for a change; the state has a fresh film
        }
        if let Err(e) = result {
            tracing::error!(session = %self.id, error = %e, "rendering failed");
            st.failure = Some(e.to_string());
            st.halted = true;
            st.film = Some(film);
            drop(st);
            self.publish_status_only(name, device);
            return 0;
        }
        let paths = pass.paths(&film);
        metrics.add_samples(&name, paths);
        metrics
            .rejected_samples
            .fetch_add(film.rejected() - rejected_before, Ordering::Relaxed);
        st.record(worker, backend, paths, took, film.pixels().len());
        let Some(image) = image else {
            st.film = Some(film);
            return paths;
        };
        let (backend, device) = match st.split.is_some() {
            true => (lanes::NAME.to_owned(), st.device_list()),
            false => (name, device),
        };
        let frame = self.frame(&mut st, &film, image, (backend, device), finished_rounds);
        st.film = Some(film);
        drop(st);
        self.frames.send_replace(Arc::new(frame));
        paths
    }

    /// Counts a pass that began at `start`; how long it took.
    fn count_pass(&self, start: Instant) -> Duration {
        let took = start.elapsed();
        self.passes.fetch_add(1, Ordering::Relaxed);
        self.render_ns.fetch_add(
            took.as_nanos().min(u128::from(u64::MAX)) as u64,
            Ordering::Relaxed,
        );
        took
    }

    /// The frame of `film` for generation `st.generation`, rendered with
    /// `by` (backend, device); settles whether the session halts with it
    /// (when the film holds whole samples).
    fn frame(
        &self,
        st: &mut SessionState,
        film: &Film,
        image: Image,
        by: (String, String),
        finished_rounds: bool,
    ) -> Frame {
        let mut estimate = image.estimate;
        if !image.whole {
            // A sample in progress: the last whole frame's estimate stands.
            let last = self.latest();
            estimate = last
                .error_estimate
                .filter(|_| last.generation == st.generation);
        }
        let progress = Progress::with_estimate(film, st.restarted.elapsed(), estimate);
        st.halted = image.whole
            && (finished_rounds
                || (st.quality.halts() && progressive::halted(&st.quality, &progress)));
        st.last_frame = Instant::now();
        let mut frame = Frame::empty(
            self.seq.fetch_add(1, Ordering::Relaxed),
            st.generation,
            film.width(),
            film.height(),
            by.0,
            by.1,
        );
        frame.spp = progress.spp;
        frame.spread = progress.spread;
        frame.density = Some(image.density);
        frame.error_estimate = progress.error_estimate;
        frame.samples_per_sec = progress.samples_per_sec;
        frame.elapsed_ms = progress.elapsed.as_secs_f64() * 1e3;
        frame.rejected = progress.rejected;
        frame.halted = st.halted;
        frame.preview = image.preview;
        frame.pixels = image.pixels;
        frame.features = image.features;
        frame.denoise = st.quality.denoise;
        frame
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
        frame.preview = previous.preview;
        frame.preview_image = previous.preview_image.clone();
        frame.features = previous.features.clone();
        frame.denoise = previous.denoise;
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
