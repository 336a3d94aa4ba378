//! One worker thread per device: it round-robins passes across the sessions
//! placed on it, so N busy sessions each get about 1/N of the device.
//! Rendering never runs on the async runtime.

use super::metrics::Metrics;
use super::session::Session;
use crate::render::Backend;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

pub struct WorkerShared {
    /// `cpu` or `opencl`: what the worker started as.
    pub backend: String,
    pub device: String,
    sessions: Mutex<Vec<Arc<Session>>>,
    wake: Condvar,
    stop: AtomicBool,
}

pub struct Worker {
    pub shared: Arc<WorkerShared>,
    handle: Option<JoinHandle<()>>,
}

impl Worker {
    pub fn start(mut backend: Backend, metrics: Arc<Metrics>) -> Worker {
        let shared = Arc::new(WorkerShared {
            backend: backend.name().to_owned(),
            device: backend.device(),
            sessions: Mutex::new(Vec::new()),
            wake: Condvar::new(),
            stop: AtomicBool::new(false),
        });
        let s = shared.clone();
        let handle = std::thread::Builder::new()
            .name(format!("render-{}", shared.backend))
            .spawn(move || run(&mut backend, &s, &metrics))
            .ok();
        if handle.is_none() {
            tracing::error!("could not start a render thread");
        }
        Worker { shared, handle }
    }

    pub fn add(&self, session: Arc<Session>) {
        self.shared.sessions.lock().unwrap_or_else(|e| e.into_inner()).push(session);
        self.wake();
    }

    pub fn remove(&self, id: &str) {
        self.shared
            .sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .retain(|s| s.id != id);
    }

    /// Tells the worker that a session has work again.
    pub fn wake(&self) {
        self.shared.wake.notify_all();
    }

    pub fn stop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        self.wake();
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

fn run(backend: &mut Backend, shared: &WorkerShared, metrics: &Metrics) {
    let mut next = 0usize;
    while !shared.stop.load(Ordering::Relaxed) {
        let session = {
            let sessions = shared.sessions.lock().unwrap_or_else(|e| e.into_inner());
            let n = sessions.len();
            let found = (0..n).map(|k| (next + k) % n.max(1)).find(|&i| sessions[i].wants_render());
            match found {
                Some(i) => {
                    next = i + 1;
                    Some(sessions[i].clone())
                }
                None => {
                    // Idle: sleep until a session changes (or check again soon).
                    let _ = shared.wake.wait_timeout(sessions, Duration::from_millis(200));
                    None
                }
            }
        };
        if let Some(session) = session {
            session.render_pass(backend, metrics);
        }
    }
}
