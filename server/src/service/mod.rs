//! The render service: sessions on worker threads, the HTTP API, the
//! WebSocket frame stream. `app(state)` builds the whole router; `start`
//! binds and serves it until shut down.

pub mod assets;
mod assets_routes;
mod auth;
pub mod change;
pub mod config;
mod density;
pub mod error;
mod frame;
mod guard;
mod link;
pub mod listen;
pub mod load;
mod metrics;
mod routes;
pub mod session;
mod static_files;
mod stream;
mod worker;
mod ws;

use assets::AssetStore;
use change::SceneRules;
pub use config::ServeConfig;
pub use error::ApiError;
pub use metrics::Metrics;
pub use routes::app;
pub use static_files::embedded_names as embedded_static_files;
pub use worker::BackendInfo;

use crate::render::backend::CpuBackend;
use crate::render::{Backend, BackendChoice};
use session::Session;
use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::{Arc, RwLock};
use std::time::Duration;
use tokio::sync::{oneshot, watch};
use worker::Worker;

/// Where a session renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// On this worker.
    One(usize),
    /// On every worker at once (`backend: "all"`).
    All,
}

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
        let cpu = Backend::Cpu(CpuBackend::low_priority());
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

    pub fn shutdown_signal(&self) -> watch::Receiver<bool> {
        self.shutdown.subscribe()
    }

    fn expire_idle(&self) {
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

    fn stop(&self) {
        let _ = self.shutdown.send(true);
        for w in &self.workers {
            w.stop();
        }
    }
}

/// A service bound to its address and serving.
pub struct Running {
    pub addr: SocketAddr,
    pub state: Arc<AppState>,
    stop: Option<oneshot::Sender<()>>,
    task: tokio::task::JoinHandle<std::io::Result<()>>,
}

impl Running {
    /// Graceful shutdown: stop accepting, close WebSockets, stop workers.
    pub async fn shutdown(mut self) -> std::io::Result<()> {
        if let Some(tx) = self.stop.take() {
            let _ = tx.send(());
        }
        self.task.await.map_err(std::io::Error::other)?
    }

    /// Runs until the process gets SIGINT or SIGTERM, then shuts down.
    pub async fn until_signal(self) -> std::io::Result<()> {
        shutdown_signal().await;
        tracing::info!("shutting down");
        self.shutdown().await
    }
}

/// Binds `config.addr` (port 0 picks one) and serves in the background.
pub async fn start(config: ServeConfig) -> Result<Running, String> {
    let listener = bind(&config).await?;
    serve(listener, AppState::new(config)?)
}

/// As [`start`], with the device backend given instead of chosen by
/// `config.backend` (tests: a device that fails on purpose).
pub async fn start_with_device(
    config: ServeConfig,
    device: Option<Backend>,
) -> Result<Running, String> {
    let listener = bind(&config).await?;
    serve(listener, AppState::with_device(config, device))
}

/// As [`start`], with the device backends and where new sessions go given
/// (tests: several devices, one that fails on purpose).
pub async fn start_with_devices(
    config: ServeConfig,
    devices: Vec<Backend>,
    default: Placement,
) -> Result<Running, String> {
    let listener = bind(&config).await?;
    serve(listener, AppState::with_devices(config, devices, default))
}

async fn bind(config: &ServeConfig) -> Result<tokio::net::TcpListener, String> {
    tokio::net::TcpListener::bind(config.addr)
        .await
        .map_err(|e| format!("cannot listen on {}: {e}", config.addr))
}

fn serve(listener: tokio::net::TcpListener, state: Arc<AppState>) -> Result<Running, String> {
    let addr = listener.local_addr().map_err(|e| e.to_string())?;
    let (stop, stopped) = oneshot::channel::<()>();
    let janitor_state = state.clone();
    let janitor = tokio::spawn(async move {
        let period = (janitor_state.config.idle_timeout / 4)
            .clamp(Duration::from_millis(50), Duration::from_secs(5));
        loop {
            tokio::time::sleep(period).await;
            janitor_state.expire_idle();
        }
    });
    let serve_state = state.clone();
    let signal_state = state.clone();
    let limits = state.config.connections;
    if let Some(n) = listen::raise_file_limit() {
        tracing::debug!(open_files = n, "open-file limit");
    }
    let task = tokio::spawn(async move {
        let result = listen::serve(listener, app(serve_state.clone()), limits, async move {
            let _ = stopped.await;
            // Closing WebSockets first lets the connections drain.
            let _ = signal_state.shutdown.send(true);
        })
        .await;
        janitor.abort();
        let s = serve_state.clone();
        let _ = tokio::task::spawn_blocking(move || s.stop()).await;
        result
    });
    Ok(Running {
        addr,
        state,
        stop: Some(stop),
        task,
    })
}

async fn shutdown_signal() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
}
