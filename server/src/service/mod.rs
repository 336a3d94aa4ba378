//! The render service's core: sessions on worker threads (one per device,
//! passes shared fairly), their frames, the changes clients make, uploaded
//! assets, load and metrics. It knows nothing of HTTP: the transport
//! (`crate::api`) parses requests into the values taken here and turns
//! [`ApiError`]s into responses. [`AppState`] holds it all.

pub mod assets;
pub mod change;
pub mod config;
mod create;
pub mod density;
pub mod error;
pub mod frame;
pub mod load;
pub mod metrics;
pub mod placement;
pub mod scaled;
pub mod session;
mod worker;

use assets::AssetStore;
use change::SceneRules;
pub use config::{ConnectionLimits, ServeConfig};
pub use create::NewSession;
pub use error::ApiError;
pub use metrics::Metrics;
pub use placement::{BackendInfo, Placement};

use crate::render::backend::CpuBackend;
use crate::render::{Backend, BackendChoice};
use session::Session;
use std::collections::HashMap;
use std::sync::{Arc, RwLock};
use tokio::sync::watch;
use worker::Worker;

/// Shared state of a running service.
pub struct AppState {
    pub config: ServeConfig,
    /// Uploaded model files; the resolver of every scene the API takes.
    pub assets: AssetStore,
    sessions: RwLock<HashMap<String, (Arc<Session>, Placement)>>,
    /// Rayon first; then the OpenCL devices, if the service has any.
    workers: Vec<Worker>,
    default_placement: Placement,
    pub metrics: Arc<Metrics>,
    shutdown: watch::Sender<bool>,
}

impl AppState {
    /// Starts one worker for rayon and, as `config.backend` says, one for
    /// an OpenCL device (the default for new sessions when there is one),
    /// or with `all`, one for every OpenCL device (new sessions render on
    /// every worker at once).
    pub fn new(config: ServeConfig) -> Result<Arc<Self>, String> {
        if let Some(name) = &config.node_name {
            config::check_node_name(name).map_err(|e| e.to_string())?;
        }
        let device = match config.backend {
            BackendChoice::Cpu => None,
            BackendChoice::All => {
                let devices = Backend::opencl_devices();
                tracing::info!(
                    devices = devices.len(),
                    "sessions render on every OpenCL device and rayon at once"
                );
                return Ok(Self::with_devices(config, devices, Placement::All));
            }
            choice => {
                let backend = Backend::choose(choice).map_err(|e| e.to_string())?;
                if backend.name() == "opencl" {
                    Some(backend)
                } else {
                    tracing::info!(device = %backend.device(), "sessions render with rayon");
                    None
                }
            }
        };
        Ok(Self::with_device(config, device))
    }

    /// As [`AppState::new`], with the device backend given (`config.backend`
    /// is not read): new sessions render on it by default.
    pub fn with_device(config: ServeConfig, device: Option<Backend>) -> Arc<Self> {
        let default = Placement::One(usize::from(device.is_some()));
        Self::with_devices(config, device.into_iter().collect(), default)
    }

    /// A worker for rayon (worker 0) and one for each of `devices`; new
    /// sessions go to `default` unless they ask otherwise.
    pub fn with_devices(
        config: ServeConfig,
        devices: Vec<Backend>,
        default: Placement,
    ) -> Arc<Self> {
        let metrics = Arc::new(Metrics::default());
        let cpu = Backend::Cpu(CpuBackend::low_priority(config.render_threads));
        let workers: Vec<Worker> = (std::iter::once(cpu).chain(devices).enumerate())
            .map(|(i, backend)| Worker::start(i, backend, metrics.clone()))
            .collect();
        let (shutdown, _) = watch::channel(false);
        Arc::new(Self {
            assets: AssetStore::new(config.assets),
            config,
            sessions: RwLock::new(HashMap::new()),
            default_placement: default,
            workers,
            metrics,
            shutdown,
        })
    }

    /// What scenes sent to this server may use: its assets, its triangle limit.
    pub fn scene_rules(&self) -> SceneRules<'_> {
        SceneRules {
            resolver: &self.assets,
            max_triangles: self.config.max_triangles,
        }
    }

    pub fn session(&self, id: &str) -> Result<Arc<Session>, ApiError> {
        let sessions = self.sessions.read().unwrap_or_else(|e| e.into_inner());
        let (s, _) = sessions
            .get(id)
            .ok_or_else(|| ApiError::unknown_session(id))?;
        s.touch();
        Ok(s.clone())
    }

    pub fn sessions(&self) -> Vec<Arc<Session>> {
        let sessions = self.sessions.read().unwrap_or_else(|e| e.into_inner());
        let mut list: Vec<_> = sessions.values().map(|(s, _)| s.clone()).collect();
        list.sort_by(|a, b| a.id.cmp(&b.id));
        list
    }

    pub fn session_count(&self) -> usize {
        self.sessions
            .read()
            .unwrap_or_else(|e| e.into_inner())
            .len()
    }

    /// Where a new session asking for `backend` renders.
    pub fn placement_for(&self, backend: Option<&str>) -> Result<Placement, ApiError> {
        match backend {
            None => Ok(self.default_placement),
            Some("auto") => Ok(match self.default_placement {
                Placement::All => Placement::One(self.workers.len() - 1),
                one => one,
            }),
            Some("all") => Ok(Placement::All),
            Some("cpu") => Ok(Placement::One(0)),
            Some("opencl") => self
                .workers
                .iter()
                .position(|w| w.info().backend == "opencl")
                .ok_or_else(|| {
                    let why = match self.workers.get(1) {
                        // A device that failed: its worker renders with rayon and says why.
                        Some(fell_back) => format!(
                            "the OpenCL device is no longer in use ({})",
                            fell_back.info().device
                        ),
                        None => "this server has no OpenCL device".to_owned(),
                    };
                    ApiError::BadRequest(format!("backend: {why}"))
                })
                .map(Placement::One),
            Some(other) => Err(ApiError::BadRequest(format!(
                "backend: unknown backend '{other}' (expected auto, opencl, cpu or all)"
            ))),
        }
    }

    /// What each worker renders with now.
    pub fn backends(&self) -> Vec<BackendInfo> {
        self.workers.iter().map(Worker::info).collect()
    }

    /// Each worker's sessions and busy fraction, in the order of
    /// [`AppState::backends`].
    pub fn load(&self) -> Vec<load::WorkerLoad> {
        self.workers
            .iter()
            .map(|w| {
                let info = w.info();
                load::WorkerLoad {
                    backend: info.backend,
                    device: info.device,
                    sessions: w.session_count(),
                    busy: (w.busy() * 1000.0).round() / 1000.0,
                    samples_per_sec: w.rate().round(),
                    samples: w.samples(),
                }
            })
            .collect()
    }

    /// What new sessions render with unless they ask otherwise.
    pub fn default_backend(&self) -> BackendInfo {
        self.placement_info(self.default_placement)
    }

    /// What a session placed so renders with.
    pub fn placement_info(&self, placement: Placement) -> BackendInfo {
        match placement {
            Placement::One(worker) => self.workers[worker].info(),
            Placement::All => BackendInfo {
                backend: "all".into(),
                device: (self.workers.iter())
                    .map(|w| w.info().device)
                    .collect::<Vec<_>>()
                    .join("; "),
            },
        }
    }

    /// The workers a session placed so renders on.
    fn placed_on(&self, placement: Placement) -> std::ops::Range<usize> {
        match placement {
            Placement::One(w) => w..w + 1,
            Placement::All => 0..self.workers.len(),
        }
    }

    /// Registers and starts a session, unless the session limit is reached.
    pub fn add_session(&self, session: Arc<Session>, placement: Placement) -> Result<(), ApiError> {
        {
            let mut sessions = self.sessions.write().unwrap_or_else(|e| e.into_inner());
            if sessions.len() >= self.config.max_sessions {
                return Err(ApiError::TooMany(format!(
                    "the server already holds its limit of {} sessions",
                    self.config.max_sessions
                )));
            }
            sessions.insert(session.id.clone(), (session.clone(), placement));
        }
        self.metrics
            .sessions_created
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        for w in self.placed_on(placement) {
            self.workers[w].add(session.clone());
        }
        Ok(())
    }

    pub fn remove_session(&self, id: &str) -> Result<(), ApiError> {
        let removed = self
            .sessions
            .write()
            .unwrap_or_else(|e| e.into_inner())
            .remove(id);
        let (session, placement) = removed.ok_or_else(|| ApiError::unknown_session(id))?;
        for w in self.placed_on(placement) {
            self.workers[w].remove(id);
        }
        session.close();
        Ok(())
    }

    /// Becomes true when the service shuts down (streams close).
    pub fn shutdown_signal(&self) -> watch::Receiver<bool> {
        self.shutdown.subscribe()
    }

    /// Deletes the sessions nobody has used for the idle timeout.
    pub fn expire_idle(&self) {
        let idle: Vec<String> = self
            .sessions()
            .into_iter()
            .filter(|s| s.idle_for() > self.config.idle_timeout)
            .map(|s| s.id.clone())
            .collect();
        for id in idle {
            tracing::info!(session = %id, "expired (idle)");
            let _ = self.remove_session(&id);
        }
    }

    /// Says to every stream that the service shuts down (they close, and
    /// their connections drain).
    pub fn begin_shutdown(&self) {
        let _ = self.shutdown.send(true);
    }

    /// Closes the streams and stops the workers.
    pub fn stop(&self) {
        self.begin_shutdown();
        for w in &self.workers {
            w.stop();
        }
    }
}
