//! One worker thread per device: it round-robins passes across the sessions
//! placed on it, so N busy sessions each get about 1/N of the device.
//! Rendering never runs on the async runtime.

use super::load::BusyMeter;
use super::metrics::Metrics;
use super::placement::{backend_info, BackendInfo};
use super::session::Session;
use crate::render::Backend;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

struct WorkerShared {
    /// What the worker renders with now: an OpenCL backend chosen by `auto`
    /// becomes rayon if its device fails, and this follows.
    info: Mutex<BackendInfo>,
    sessions: Mutex<Vec<Arc<Session>>>,
    wake: Condvar,
    stop: AtomicBool,
    /// Wall time spent rendering, for `/api/health`.
    busy: BusyMeter,
    /// Camera paths rendered, for `/metrics`.
    samples: AtomicU64,
}

fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl WorkerShared {
    fn notify(&self) {
        // Taking the lock orders this after a worker's check for work and
        // its wait (which holds the lock between them): no wake-up is lost.
        let _sessions = lock(&self.sessions);
        self.wake.notify_all();
    }
}

pub struct Worker {
    shared: Arc<WorkerShared>,
    handle: Mutex<Option<JoinHandle<()>>>,
}

impl Worker {
    /// Starts worker number `index` (its place in the service's list).
    pub fn start(index: usize, mut backend: Backend, metrics: Arc<Metrics>) -> Worker {
        let shared = Arc::new(WorkerShared {
            info: Mutex::new(backend_info(&backend)),
            sessions: Mutex::new(Vec::new()),
            wake: Condvar::new(),
            stop: AtomicBool::new(false),
            busy: BusyMeter::new(Instant::now()),
            samples: AtomicU64::new(0),
        });
        let s = shared.clone();
        let handle = std::thread::Builder::new()
            .name(format!("render-{}", backend.name()))
            .spawn(move || run(index, &mut backend, &s, &metrics))
            .ok();
        if handle.is_none() {
            tracing::error!("could not start a render thread");
        }
        Worker {
            shared,
            handle: Mutex::new(handle),
        }
    }

    /// What the worker renders with now.
    pub fn info(&self) -> BackendInfo {
        lock(&self.shared.info).clone()
    }

    /// The fraction of the last few seconds this worker spent rendering
    /// (see [`super::load`]).
    pub fn busy(&self) -> f64 {
        self.shared.busy.fraction(Instant::now())
    }

    /// Camera paths per second over the last few seconds.
    pub fn rate(&self) -> f64 {
        self.shared.busy.rate(Instant::now())
    }

    /// Camera paths this worker has rendered.
    pub fn samples(&self) -> u64 {
        self.shared.samples.load(Ordering::Relaxed)
    }

    /// How many sessions are placed on this worker.
    pub fn session_count(&self) -> usize {
        lock(&self.shared.sessions).len()
    }

    /// Places a session on this worker, which starts rendering it.
    pub fn add(&self, session: Arc<Session>) {
        let worker = Arc::downgrade(&self.shared);
        session.attach(Box::new(move || {
            if let Some(shared) = worker.upgrade() {
                shared.notify();
            }
        }));
        lock(&self.shared.sessions).push(session);
        self.shared.notify();
    }

    pub fn remove(&self, id: &str) {
        lock(&self.shared.sessions).retain(|s| s.id != id);
    }

    /// Stops the thread after its current pass and waits for it.
    pub fn stop(&self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.shared.notify();
        if let Some(h) = lock(&self.handle).take() {
            let _ = h.join();
        }
    }
}

fn run(index: usize, backend: &mut Backend, shared: &WorkerShared, metrics: &Metrics) {
    let mut next = 0usize;
    let mut rendering_with = backend.name();
    while !shared.stop.load(Ordering::Relaxed) {
        let session = {
            let sessions = lock(&shared.sessions);
            let n = sessions.len();
            let found = (0..n)
                .map(|k| (next + k) % n.max(1))
                .find(|&i| sessions[i].wants_render(index));
            match found {
                Some(i) => {
                    next = i + 1;
                    Some(sessions[i].clone())
                }
                None => {
                    // Idle: sleep until a session changes (or check again soon).
                    let _ = shared
                        .wake
                        .wait_timeout(sessions, Duration::from_millis(200));
                    None
                }
            }
        };
        if let Some(session) = session {
            shared.busy.begin(Instant::now());
            let paths = session.render_pass(index, backend, metrics);
            shared.busy.end(Instant::now());
            shared.samples.fetch_add(paths, Ordering::Relaxed);
            shared.busy.count(Instant::now(), paths);
            if backend.name() != rendering_with {
                rendering_with = backend.name();
                let info = backend_info(backend);
                tracing::warn!(backend = %info.backend, device = %info.device, "the worker now renders elsewhere");
                *lock(&shared.info) = info;
            }
        }
    }
}
