//! Helpers for the tests that drive a real server over HTTP and WebSocket.
#![allow(dead_code)]

use futures_util::StreamExt;
use pathstream::api::{start, Running};
use pathstream::render::BackendChoice;
use pathstream::service::ServeConfig;
use serde_json::Value;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

pub type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

pub fn config() -> ServeConfig {
    ServeConfig {
        addr: "127.0.0.1:0".parse().expect("addr"),
        backend: BackendChoice::Cpu,
        ..ServeConfig::default()
    }
}

pub async fn server(config: ServeConfig) -> (Running, String) {
    let running = start(config).await.expect("server starts");
    let base = format!("http://{}", running.addr);
    (running, base)
}

pub fn client() -> reqwest::Client {
    reqwest::Client::new()
}

/// The answer to GET `url` (there must be one).
pub async fn get(url: impl reqwest::IntoUrl) -> reqwest::Response {
    client().get(url).send().await.expect("an answer to GET")
}

/// The JSON answer to GET `url`.
pub async fn get_json<T: serde::de::DeserializeOwned>(url: impl reqwest::IntoUrl) -> T {
    get(url).await.json().await.expect("a JSON answer to GET")
}

/// The answer to DELETE `url` (there must be one).
pub async fn delete(url: impl reqwest::IntoUrl) -> reqwest::Response {
    client()
        .delete(url)
        .send()
        .await
        .expect("an answer to DELETE")
}

pub async fn create(base: &str, body: Value) -> Value {
    let r = client()
        .post(format!("{base}/api/sessions"))
        .json(&body)
        .send()
        .await
        .expect("request");
    assert_eq!(r.status(), 201, "{:?}", r.text().await);
    r.json().await.expect("json")
}

pub async fn status(base: &str, id: &str) -> Value {
    get_json(format!("{base}/api/sessions/{id}")).await
}

/// The server's `/metrics` text.
pub async fn metrics(base: &str) -> String {
    get(format!("{base}/metrics"))
        .await
        .text()
        .await
        .expect("text")
}

/// The value of the `/metrics` line `name` (labels included, as written).
pub fn metric(text: &str, name: &str) -> u64 {
    (text.lines())
        .find_map(|l| l.strip_prefix(name)?.strip_prefix(' '))
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or_else(|| panic!("no {name} line: {text}"))
}

/// Linear image after at least `min_spp` samples.
pub async fn pfm(base: &str, id: &str, min_spp: u64) -> Vec<[f32; 3]> {
    let r = get(format!(
        "{base}/api/sessions/{id}/frame.pfm?min_spp={min_spp}&timeout_ms=60000"
    ))
    .await;
    assert_eq!(r.status(), 200);
    let spp: u64 = r.headers()["x-pathstream-spp"]
        .to_str()
        .expect("header")
        .parse()
        .expect("number");
    assert!(spp >= min_spp, "waited for {min_spp} spp, got {spp}");
    let bytes = r.bytes().await.expect("body");
    pathstream::render::output::decode_pfm(&bytes)
        .expect("pfm")
        .2
}

pub fn mean(img: &[[f32; 3]]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in img {
        for c in 0..3 {
            m[c] += f64::from(p[c]) / img.len() as f64;
        }
    }
    m
}

pub async fn patch(base: &str, id: &str, what: &str, body: Value) -> reqwest::Response {
    client()
        .patch(format!("{base}/api/sessions/{id}/{what}"))
        .json(&body)
        .send()
        .await
        .expect("request")
}

pub async fn ws_connect(base: &str, id: &str) -> Ws {
    ws_connect_with(base, id, "").await
}

/// The session's WebSocket with `query` (e.g. `?format=jpeg`) on its URL.
pub async fn ws_connect_with(base: &str, id: &str, query: &str) -> Ws {
    let url = format!(
        "{}/api/sessions/{id}/ws{query}",
        base.replace("http://", "ws://")
    );
    tokio_tungstenite::connect_async(url)
        .await
        .expect("ws connects")
        .0
}

/// The next frame and the stats that follow it (at most 60 s); an error
/// message on the way fails the test.
pub async fn next_frame(ws: &mut Ws) -> (Vec<u8>, Value) {
    let until = Instant::now() + Duration::from_secs(60);
    let mut image = None;
    loop {
        let msg = tokio::time::timeout(until.saturating_duration_since(Instant::now()), ws.next())
            .await
            .expect("a frame in time")
            .expect("open")
            .expect("message");
        match msg {
            Message::Binary(b) => image = Some(b.to_vec()),
            Message::Text(t) => {
                let v: Value = serde_json::from_str(t.as_str()).expect("json");
                assert_ne!(v["type"], "error", "{v}");
                if let Some(image) = image.take() {
                    return (image, v);
                }
            }
            _ => {}
        }
    }
}

/// Polls the session until it halts (in `generation`, when given); fails
/// the test after a minute.
pub async fn halted(base: &str, id: &str, generation: Option<u64>) -> Value {
    let until = Instant::now() + Duration::from_secs(60);
    loop {
        let s = status(base, id).await;
        let current = generation.is_none_or(|g| s["generation"] == g);
        if s["state"] == "halted" && current {
            return s;
        }
        assert!(Instant::now() < until, "never halted: {s}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// Reads `ws` until an error message comes (at most 30 s); its text.
pub async fn next_error(ws: &mut Ws) -> String {
    let until = Instant::now() + Duration::from_secs(30);
    loop {
        let msg = tokio::time::timeout(until.saturating_duration_since(Instant::now()), ws.next())
            .await
            .expect("an answer")
            .expect("open")
            .expect("message");
        if let Message::Text(t) = msg {
            let v: Value = serde_json::from_str(t.as_str()).expect("json");
            if v["type"] == "error" {
                return v["error"].as_str().unwrap_or("").to_owned();
            }
        }
    }
}

/// Reads frames until `deadline`; returns (frames, last stats).
pub async fn read_frames(ws: &mut Ws, until: Instant) -> (usize, Value) {
    let (mut frames, mut stats) = (0, Value::Null);
    while let Ok(Some(Ok(msg))) =
        tokio::time::timeout(until.saturating_duration_since(Instant::now()), ws.next()).await
    {
        match msg {
            Message::Binary(_) => frames += 1,
            Message::Text(t) => stats = serde_json::from_str(t.as_str()).expect("json stats"),
            _ => {}
        }
    }
    (frames, stats)
}

/// The first binary (PNG) frame, waiting at most `timeout`.
pub async fn first_frame(ws: &mut Ws, timeout: Duration) -> Vec<u8> {
    let until = Instant::now() + timeout;
    loop {
        match tokio::time::timeout(until.saturating_duration_since(Instant::now()), ws.next()).await
        {
            Ok(Some(Ok(Message::Binary(png)))) => return png.to_vec(),
            Ok(Some(Ok(_))) => {}
            other => panic!("no frame within {timeout:?}: {other:?}"),
        }
    }
}

/// A request written byte for byte (paths no client library would send):
/// status, headers (lower case) and body.
pub async fn raw(
    addr: &std::net::SocketAddr,
    method: &str,
    target: &[u8],
    headers: &str,
    body: &[u8],
) -> (u16, String, String) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut tcp = tokio::net::TcpStream::connect(addr).await.expect("connect");
    let mut request = format!("{method} ").into_bytes();
    request.extend_from_slice(target);
    request.extend_from_slice(
        format!(
            " HTTP/1.1\r\nhost: test\r\nconnection: close\r\ncontent-length: {}\r\n{headers}\r\n",
            body.len()
        )
        .as_bytes(),
    );
    request.extend_from_slice(body);
    tcp.write_all(&request).await.expect("write");
    let mut response = Vec::new();
    tokio::time::timeout(Duration::from_secs(20), tcp.read_to_end(&mut response))
        .await
        .expect("an answer in time")
        .expect("read");
    let text = String::from_utf8_lossy(&response).into_owned();
    let code = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    (code, head.to_ascii_lowercase(), body.to_owned())
}

/// The URL a `pathstream serve` child prints on its first line of stdout
/// (without a trailing slash). The pipe is dropped afterwards.
pub fn served_url(child: &mut std::process::Child) -> String {
    use std::io::BufRead;
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().expect("stdout piped"))
        .read_line(&mut line)
        .expect("a line");
    line.split_whitespace()
        .find(|w| w.starts_with("http://"))
        .expect("a URL")
        .trim_end_matches('/')
        .to_owned()
}

/// Sends `message` as a WebSocket text message.
pub async fn ws_send(ws: &mut Ws, message: Value) {
    use futures_util::SinkExt;
    ws.send(Message::text(message.to_string()))
        .await
        .expect("ws send");
}

/// The session's status once `done` holds for it (at most 30 s).
pub async fn wait_status(base: &str, id: &str, done: impl Fn(&Value) -> bool) -> Value {
    let until = Instant::now() + Duration::from_secs(30);
    loop {
        let st = status(base, id).await;
        if done(&st) {
            return st;
        }
        assert!(Instant::now() < until, "status never came: {st}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}
