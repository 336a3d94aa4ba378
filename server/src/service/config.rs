//! What `pathstream serve` is started with: the service's limits and the
//! transport's (address, token, connections), in one place.

use super::assets::AssetLimits;
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
    /// This box's name behind a proxy that routes by it (see `deploy/`):
    /// session ids start with `NAME-`, and every response carries
    /// `x-pathstream-node: NAME`. Checked by [`check_node_name`].
    pub node_name: Option<String>,
    /// Threads of the CPU (rayon) worker; None: one per core.
    pub render_threads: Option<usize>,
}

/// How many connections, and how long a request head may take.
#[derive(Clone, Copy, Debug)]
pub struct ConnectionLimits {
    /// Open connections in total; more are closed at once.
    pub max_connections: usize,
    /// Open connections from one client address.
    pub max_per_address: usize,
    /// A request head not read completely in this time ends the connection
    /// (also the time an idle keep-alive connection is kept).
    pub header_timeout: Duration,
}

impl Default for ConnectionLimits {
    fn default() -> Self {
        Self {
            max_connections: 4096,
            max_per_address: 256,
            header_timeout: Duration::from_secs(10),
        }
    }
}

/// Most characters of a node name.
pub const MAX_NODE_NAME: usize = 32;

/// A `--node-name` that [`check_node_name`] refuses.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not a node name: 1 to {MAX_NODE_NAME} characters of a-z, 0-9 and _")]
pub struct BadNodeName(pub String);

/// A node name is 1 to [`MAX_NODE_NAME`] of `a-z`, `0-9` and `_`: it is the
/// prefix of session ids (up to the first `-`) that a proxy matches, and a
/// header value.
pub fn check_node_name(name: &str) -> Result<(), BadNodeName> {
    let ok = (1..=MAX_NODE_NAME).contains(&name.len())
        && name
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_');
    if ok {
        Ok(())
    } else {
        Err(BadNodeName(name.to_owned()))
    }
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
            node_name: None,
            render_threads: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn node_names_are_short_lowercase_words() {
        for good in ["box1", "a", "gpu_7", &"x".repeat(MAX_NODE_NAME)] {
            assert_eq!(check_node_name(good), Ok(()), "{good}");
        }
        for bad in [
            "",
            "Box1",
            "box-1",
            "box 1",
            "bö",
            &"x".repeat(MAX_NODE_NAME + 1),
        ] {
            let e = check_node_name(bad).expect_err(bad).to_string();
            assert!(e.contains("not a node name"), "{e}");
        }
    }
}
