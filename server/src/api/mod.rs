//! The render service's transport: HTTP routes (`app(state)` builds the
//! whole router), the WebSocket frame stream and its encodings, the bearer
//! token, request guards, connection limits, the static browser client.
//! [`start`] binds and serves it until shut down. Everything here parses
//! requests into the service core's values (`crate::service`) and answers
//! with its results.

mod assets_routes;
mod auth;
mod guard;
mod link;
pub mod listen;
mod response;
mod routes;
mod static_files;
mod stream;
mod ws;

pub use routes::{app, NODE_HEADER};
pub use static_files::embedded_names as embedded_static_files;
pub use ws::SESSION_DELETED;

use crate::render::Backend;
use crate::service::{AppState, Placement, ServeConfig};
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::oneshot;

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
    // Loads the denoiser now, so the log says at start whether there is
    // one (and why not); the server runs either way.
    let _ = tokio::task::spawn_blocking(crate::render::denoise::status).await;
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
        let metrics = serve_state.metrics.clone();
        let result = listen::serve(
            listener,
            app(serve_state.clone()),
            limits,
            metrics,
            async move {
                let _ = stopped.await;
                // Closing WebSockets first lets the connections drain.
                signal_state.begin_shutdown();
            },
        )
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
