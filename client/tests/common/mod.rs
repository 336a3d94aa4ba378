//! What the command-line tests share: a real `pathstream serve` process
//! (the workspace builds both binaries into the same folder) and the
//! client binary run against it.
#![allow(dead_code)]

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Output, Stdio};

pub struct Server {
    child: Child,
    pub url: String,
    /// Kept open: the server may print more after its first line.
    _stdout: BufReader<std::process::ChildStdout>,
}

impl Server {
    /// Stops the server now (as a crash would).
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.kill();
    }
}

pub fn server_binary() -> PathBuf {
    let cli = PathBuf::from(env!("CARGO_BIN_EXE_pathstream-client"));
    let server = cli.with_file_name("pathstream");
    assert!(
        server.exists(),
        "{} is missing: build the workspace (cargo test --workspace)",
        server.display()
    );
    server
}

/// Starts `pathstream serve --backend cpu` on a free port and reads the URL
/// it prints.
pub fn start_server() -> Server {
    start_server_with("cpu")
}

/// As [`start_server`], with `--backend BACKEND`.
pub fn start_server_with(backend: &str) -> Server {
    let mut child = Command::new(server_binary())
        .args(["serve", "--addr", "127.0.0.1:0", "--backend", backend])
        .env("RUST_LOG", "warn")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("server starts");
    let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut line = String::new();
    stdout.read_line(&mut line).expect("a first line");
    let url = line
        .split_whitespace()
        .find(|w| w.starts_with("http://"))
        .map(|u| u.trim_end_matches('/').to_owned())
        .unwrap_or_else(|| panic!("no URL in: {line}"));
    Server {
        child,
        url,
        _stdout: stdout,
    }
}

/// `pathstream-client --server URL ARGS`, run to its end.
pub fn client(server: &Server, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .arg("--server")
        .arg(&server.url)
        .args(args)
        .output()
        .expect("runs")
}

/// As [`client`], with standard output a pipe whose reader has already
/// gone (`pathstream-client ... | head -0`).
pub fn client_into_closed_pipe(server: &Server, args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .arg("--server")
        .arg(&server.url)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    drop(child.stdout.take());
    child.wait_with_output().expect("ends")
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// That `run` exited with `code` and its message names `named`.
pub fn assert_fails(run: &Output, code: i32, named: &str) {
    let stderr = text(&run.stderr);
    assert_eq!(run.status.code(), Some(code), "{stderr}");
    assert!(stderr.contains(named), "{named:?} not in: {stderr}");
}
