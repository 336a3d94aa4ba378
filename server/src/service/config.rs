//! What `pathstream serve` is started with.

use super::assets::AssetLimits;
use super::listen::ConnectionLimits;
use crate::render::BackendChoice;
use std::net::SocketAddr;
use std::time::Duration;

#[derive(Clone, Debug)]
pub struct ServeConfig {
    pub addr: SocketAddr,
    /// Where new sessions render unless they ask otherwise.
    pub backend: BackendChoice,
    /// Required bearer token on every /api route and the WebSocket.
    pub token: Option<String>,
    pub max_sessions: usize,
    /// Most pixels (width x height) of one session.
    pub max_pixels: u64,
    /// Sessions with no client and no request for this long are deleted.
    pub idle_timeout: Duration,
    pub max_body_bytes: usize,
    /// Allow cross-origin requests (off by default).
    pub cors: bool,
    /// Serve the browser client from this folder instead of the copy built
    /// into the binary (for working on the page without rebuilding).
    pub static_dir: Option<std::path::PathBuf>,
    /// Uploaded model files: largest upload, all assets' memory, triangles
    /// of one file.
    pub assets: AssetLimits,
    /// Most triangles one session's scene may hold (each mesh counted once).
    pub max_triangles: u64,
    /// Open connections (in total, per client address) and the deadline
    /// for a request head.
    pub connections: ConnectionLimits,
}

impl Default for ServeConfig {
    fn default() -> Self {
        Self {
            addr: SocketAddr::from(([127, 0, 0, 1], 8080)),
            backend: BackendChoice::Auto,
            token: None,
            max_sessions: 16,
            max_pixels: 3840 * 2160,
            idle_timeout: Duration::from_secs(600),
            max_body_bytes: 2 << 20,
            cors: false,
            static_dir: None,
            assets: AssetLimits::default(),
            max_triangles: 16_000_000,
            connections: ConnectionLimits::default(),
        }
    }
}
