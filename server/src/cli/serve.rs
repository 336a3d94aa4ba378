//! `pathstream serve` (the default command): the render service.

use super::render::BackendArg;
use super::CliError;
use pathstream::service::{self, ServeConfig};
use std::io::Write;
use std::net::SocketAddr;
use std::time::Duration;

#[derive(clap::Args, Debug, Default)]
pub struct ServeArgs {
    /// Address to listen on.
    #[arg(
        long,
        env = "PATHSTREAM_ADDR",
        value_name = "HOST:PORT",
        help = "Address to listen on [default: 127.0.0.1:8080]"
    )]
    addr: Option<SocketAddr>,
    /// Where sessions render by default (a session may ask for another).
    #[arg(long, value_enum)]
    backend: Option<BackendArg>,
    /// OpenCL device number (see `pathstream devices`); implies --backend opencl.
    /// Default: the GPU with the most compute units, else device 0.
    #[arg(long, value_name = "N")]
    device: Option<usize>,
    /// Require this bearer token on every /api route and the WebSocket.
    #[arg(long, env = "PATHSTREAM_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// Most sessions at once.
    #[arg(long, value_name = "N")]
    max_sessions: Option<usize>,
    /// Most pixels (width x height) per session.
    #[arg(long, value_name = "N")]
    max_pixels: Option<u64>,
    /// Delete sessions that had no client and no request for this many seconds.
    #[arg(long, value_name = "S")]
    idle_timeout_s: Option<u64>,
    /// Allow cross-origin requests from any site (off by default).
    #[arg(long)]
    cors: bool,
    /// Serve the browser client from this folder instead of the built-in copy.
    #[arg(long, env = "PATHSTREAM_STATIC_DIR", value_name = "DIR")]
    static_dir: Option<std::path::PathBuf>,
    /// Largest model file accepted by POST /api/assets, in bytes [default: 268435456 (256 MiB)].
    #[arg(long, value_name = "BYTES")]
    max_asset_bytes: Option<usize>,
    /// Most memory all uploaded assets' meshes may hold, in bytes [default: 4294967296 (4 GiB)].
    #[arg(long, value_name = "BYTES")]
    max_asset_memory: Option<usize>,
    /// Most triangles in one session's scene (and in one uploaded file) [default: 16000000].
    #[arg(long, value_name = "N")]
    max_triangles: Option<u64>,
    /// Most open connections; more are closed at once [default: 4096].
    #[arg(long, value_name = "N")]
    max_connections: Option<usize>,
    /// Most open connections from one client address [default: 256].
    #[arg(long, value_name = "N")]
    max_connections_per_ip: Option<usize>,
    /// Seconds a client may take to send a request head (and an idle
    /// keep-alive connection is kept) [default: 10].
    #[arg(long, value_name = "S")]
    header_timeout_s: Option<u64>,
    /// This box's name behind a proxy that routes by it (deploy/pathstream.conf):
    /// session ids become NAME-..., and every response carries
    /// `x-pathstream-node: NAME`. 1 to 32 of a-z, 0-9 and _.
    #[arg(long, env = "PATHSTREAM_NODE_NAME", value_name = "NAME")]
    node_name: Option<String>,
    /// Threads that render on the CPU (sessions on rayon, and rayon's share
    /// of `--backend all`), to leave cores to other work [default: one per
    /// core].
    #[arg(long, value_name = "N")]
    render_threads: Option<usize>,
}

pub fn run(args: ServeArgs) -> Result<(), CliError> {
    let defaults = ServeConfig::default();
    let backend = match (args.backend.unwrap_or(BackendArg::Auto), args.device) {
        (BackendArg::Cpu | BackendArg::All, Some(_)) => {
            return Err(CliError::Usage(
                "--device: only with --backend opencl or auto".into(),
            ))
        }
        (BackendArg::Auto, Some(_)) => BackendArg::Opencl,
        (b, _) => b,
    };
    if args.max_sessions == Some(0) {
        return Err(CliError::Usage("--max-sessions: must be at least 1".into()));
    }
    for (flag, v) in [
        ("--max-asset-bytes", args.max_asset_bytes.map(|v| v as u64)),
        (
            "--max-asset-memory",
            args.max_asset_memory.map(|v| v as u64),
        ),
        ("--max-triangles", args.max_triangles),
        ("--max-connections", args.max_connections.map(|v| v as u64)),
        (
            "--max-connections-per-ip",
            args.max_connections_per_ip.map(|v| v as u64),
        ),
        ("--header-timeout-s", args.header_timeout_s),
        ("--render-threads", args.render_threads.map(|v| v as u64)),
    ] {
        if v == Some(0) {
            return Err(CliError::Usage(format!("{flag}: must be at least 1")));
        }
    }
    if let Some(name) = &args.node_name {
        service::config::check_node_name(name)
            .map_err(|e| CliError::Usage(format!("--node-name: {e}")))?;
    }
    let max_triangles = args.max_triangles.unwrap_or(defaults.max_triangles);
    let assets = service::assets::AssetLimits {
        max_asset_bytes: args
            .max_asset_bytes
            .unwrap_or(defaults.assets.max_asset_bytes),
        max_total_bytes: args
            .max_asset_memory
            .unwrap_or(defaults.assets.max_total_bytes),
        max_triangles,
    };
    let config = ServeConfig {
        addr: args.addr.unwrap_or(defaults.addr),
        backend: backend.choice(args.device),
        token: args.token.filter(|t| !t.is_empty()),
        max_sessions: args.max_sessions.unwrap_or(defaults.max_sessions),
        max_pixels: args.max_pixels.unwrap_or(defaults.max_pixels),
        idle_timeout: args
            .idle_timeout_s
            .map_or(defaults.idle_timeout, Duration::from_secs),
        max_body_bytes: defaults.max_body_bytes,
        cors: args.cors,
        static_dir: args.static_dir,
        assets,
        max_triangles,
        connections: service::ConnectionLimits {
            max_connections: args
                .max_connections
                .unwrap_or(defaults.connections.max_connections),
            max_per_address: args
                .max_connections_per_ip
                .unwrap_or(defaults.connections.max_per_address),
            header_timeout: args
                .header_timeout_s
                .map_or(defaults.connections.header_timeout, Duration::from_secs),
        },
        node_name: args.node_name,
        render_threads: args.render_threads,
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::Failed(format!("cannot start the async runtime: {e}")))?;
    runtime.block_on(async move {
        let running = pathstream::api::start(config)
            .await
            .map_err(CliError::Failed)?;
        let backends: Vec<String> = running
            .state
            .backends()
            .iter()
            .map(|b| format!("{} ({})", b.backend, b.device))
            .collect();
        // A closed stdout must not stop a server: write, and ignore failures.
        let mut out = std::io::stdout();
        let _ = writeln!(
            out,
            "pathstream serving on http://{}/  - open it in a browser",
            running.addr
        );
        let _ = writeln!(out, "render workers: {}", backends.join("; "));
        if let Some(name) = &running.state.config.node_name {
            let _ = writeln!(out, "node name: {name} (session ids start with {name}-)");
        }
        if running.state.config.token.is_some() {
            let _ = writeln!(
                out,
                "a bearer token is required on /api (Authorization: Bearer ..., or ?token=...)"
            );
        }
        let _ = out.flush();
        running
            .until_signal()
            .await
            .map_err(|e| CliError::Failed(e.to_string()))
    })
}
