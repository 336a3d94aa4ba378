//! Real processes for the proxy test: `pathstream serve` boxes, and Debian's
//! nginx running `deploy/pathstream.conf` with its addresses and `listen`
//! replaced by loopback ones. Each process is stopped when its guard drops,
//! also when an assertion fails.
#![allow(dead_code)]

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Where Debian's package puts nginx.
pub const NGINX: &str = "/usr/sbin/nginx";

/// The addresses and listen line of `deploy/pathstream.conf`, in box order.
const DEPLOY_BOXES: [&str; 3] = ["10.0.0.11:8080", "10.0.0.12:8080", "10.0.0.13:8080"];
const DEPLOY_LISTEN: &str = "listen 80;";

/// nginx, if installed; where `CI` is set its absence is a failure, so that
/// a suite cannot pass by skipping.
pub fn nginx_binary() -> Option<PathBuf> {
    let path = PathBuf::from(NGINX);
    if path.is_file() {
        return Some(path);
    }
    if std::env::var_os("CI").is_some() {
        panic!("CI is set but {NGINX} is missing (scripts/test.sh installs Debian's nginx)");
    }
    eprintln!("skipping: {NGINX} is missing (apt-get install nginx)");
    None
}

/// The deploy configuration's text.
pub fn deploy_conf() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy/pathstream.conf");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A loopback port that was free a moment ago.
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// One `pathstream serve --node-name NAME` process on loopback.
pub struct Node {
    pub name: String,
    pub addr: SocketAddr,
    log: PathBuf,
    /// More `serve` arguments (at first `--max-sessions 200`).
    extra: Vec<String>,
    child: Option<Child>,
}

impl Node {
    /// Starts a box on a port of its choosing, logging to `dir/NAME.log`.
    pub fn start(name: &str, dir: &Path) -> Node {
        let mut node = Node {
            name: name.to_owned(),
            addr: "127.0.0.1:0".parse().expect("addr"),
            log: dir.join(format!("{name}.log")),
            extra: vec!["--max-sessions".into(), "200".into()],
            child: None,
        };
        node.spawn();
        node
    }

    fn spawn(&mut self) {
        let log = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&self.log)
            .expect("log file");
        let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream"))
            .args(["serve", "--backend", "cpu"])
            .args(["--addr", &self.addr.to_string(), "--node-name", &self.name])
            .args(&self.extra)
            .stdout(Stdio::piped())
            .stderr(log)
            .spawn()
            .expect("pathstream serve starts");
        let url = crate::http::served_url(&mut child);
        self.addr = url
            .trim_start_matches("http://")
            .parse()
            .expect("the URL's address");
        self.child = Some(child);
    }

    pub fn base(&self) -> String {
        format!("http://{}", self.addr)
    }

    /// Kills the process at once (a box that dies).
    pub fn kill(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }

    /// Starts it again with the same name on the same address, with
    /// `extra` arguments instead of the ones it had.
    pub fn restart(&mut self, extra: &[&str]) {
        self.kill();
        self.extra = extra.iter().map(|s| (*s).to_owned()).collect();
        self.spawn();
    }
}

impl Drop for Node {
    fn drop(&mut self) {
        self.kill();
    }
}

/// nginx in the foreground, its prefix, logs and temp files in a temp dir.
pub struct Nginx {
    pub base: String,
    pub dir: tempfile::TempDir,
    child: Option<Child>,
}

/// The main configuration around the deploy file: what Debian's
/// /etc/nginx/nginx.conf would hold, with every path inside `prefix`.
fn main_conf(prefix: &Path) -> String {
    let p = prefix.display();
    format!(
        "worker_processes 1;
error_log {p}/error.log;
pid {p}/nginx.pid;
events {{ worker_connections 1024; }}
http {{
    access_log {p}/access.log;
    client_body_temp_path {p}/temp/body;
    proxy_temp_path {p}/temp/proxy;
    fastcgi_temp_path {p}/temp/fastcgi;
    uwsgi_temp_path {p}/temp/uwsgi;
    scgi_temp_path {p}/temp/scgi;
    include {p}/pathstream.conf;
}}
"
    )
}

/// `deploy/pathstream.conf` with the three example addresses replaced by
/// `boxes` and `listen 80;` by `listen`.
pub fn site_conf(boxes: &[SocketAddr], listen: SocketAddr) -> String {
    let mut conf = deploy_conf();
    assert_eq!(
        boxes.len(),
        DEPLOY_BOXES.len(),
        "the deploy file has three boxes"
    );
    for (example, addr) in DEPLOY_BOXES.iter().zip(boxes) {
        assert_eq!(
            conf.matches(example).count(),
            2,
            "{example}: in the name map and in the pool"
        );
        conf = conf.replace(example, &addr.to_string());
    }
    assert_eq!(
        conf.matches(DEPLOY_LISTEN).count(),
        1,
        "one {DEPLOY_LISTEN}"
    );
    conf.replace(DEPLOY_LISTEN, &format!("listen {listen};"))
}

impl Nginx {
    /// Starts nginx in front of `boxes` on a free loopback port and waits
    /// until it answers.
    pub fn start(binary: &Path, boxes: &[SocketAddr]) -> Nginx {
        let dir = tempfile::tempdir().expect("tempdir");
        // Run as root, nginx's workers switch to `nobody`: they must be
        // able to reach the temp paths (nginx creates and chowns them).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(dir.path(), std::fs::Permissions::from_mode(0o755))
                .expect("chmod");
        }
        std::fs::create_dir(dir.path().join("temp")).expect("temp dir");
        let port = free_port();
        let listen: SocketAddr = ([127, 0, 0, 1], port).into();
        std::fs::write(dir.path().join("pathstream.conf"), site_conf(boxes, listen))
            .expect("write site");
        let conf = dir.path().join("nginx.conf");
        std::fs::write(&conf, main_conf(dir.path())).expect("write conf");
        let startup_log = dir.path().join("startup.log");
        let child = Command::new(binary)
            .arg("-p")
            .arg(dir.path())
            .arg("-c")
            .arg(&conf)
            .arg("-e")
            .arg(&startup_log)
            .args(["-g", "daemon off;"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("nginx starts");
        let mut nginx = Nginx {
            base: format!("http://{listen}"),
            dir,
            child: Some(child),
        };
        nginx.wait_listening(listen);
        nginx
    }

    fn wait_listening(&mut self, listen: SocketAddr) {
        let until = Instant::now() + Duration::from_secs(20);
        loop {
            if std::net::TcpStream::connect(listen).is_ok() {
                return;
            }
            let exited = self
                .child
                .as_mut()
                .and_then(|c| c.try_wait().ok().flatten());
            if exited.is_some() || Instant::now() > until {
                panic!(
                    "nginx is not listening on {listen} ({exited:?}); its log:\n{}",
                    self.log()
                );
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Everything nginx has logged (startup and error log).
    pub fn log(&self) -> String {
        ["startup.log", "error.log"]
            .iter()
            .map(|f| std::fs::read_to_string(self.dir.path().join(f)).unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl Drop for Nginx {
    /// A fast shutdown (SIGTERM) lets the master stop its workers; SIGKILL
    /// only if it has not ended within 10 s.
    fn drop(&mut self) {
        let Some(mut child) = self.child.take() else {
            return;
        };
        let _ = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
        let until = Instant::now() + Duration::from_secs(10);
        while Instant::now() < until {
            if let Ok(Some(_)) = child.try_wait() {
                return;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        let _ = child.kill();
        let _ = child.wait();
    }
}
