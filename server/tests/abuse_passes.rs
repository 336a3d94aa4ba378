//! The server under abuse, part two: a session whose every sample is
//! expensive does not starve a cheap one on the same device (passes are
//! bounded in time, on every backend), and a canary session keeps its share
//! through a run of hostile requests against the real binary, whose log
//! never says `panicked`. One test function runs the scenarios one after
//! the other, alone in this binary, so that nothing else competes for the
//! cores while rates are measured.

mod http;

use http::{client, config, create, served_url, server};
use pathstream::api::Running;
use pathstream::render::BackendChoice;
use serde_json::{json, Value};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// How long each rate and share is measured.
const WINDOW: Duration = Duration::from_secs(3);
/// The least share of the device's time (`render_ms`, measured within one
/// window, so that other load on the machine slows both sessions alike)
/// that a cheap session must get beside an expensive one. Fair is 1/2; when
/// a pass was at least a whole sample it was about 1/20 with this scene.
const LEAST_SHARE: f64 = 1.0 / 4.0;

/// 4096 emissive spheres closed around the camera, paths of 64 bounces: one
/// sample of the 160x160 image takes about half a second on two cores.
fn expensive_scene() -> Value {
    let n = 4096;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let objects: Vec<Value> = (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (f64::from(i) + 0.5) / f64::from(n);
            let r = (1.0 - y * y).sqrt();
            let phi = golden * f64::from(i);
            let c = [5.0 * r * phi.cos(), 5.0 * y, 5.0 * r * phi.sin()];
            json!({"type": "sphere", "center": c, "radius": 0.3, "material": "glow"})
        })
        .collect();
    json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "up": [0, 1, 0], "vfov_deg": 60},
        "materials": {"glow": {"type": "diffuse", "albedo": [0.9, 0.9, 0.9], "emission": [0.5, 0.5, 0.5]}},
        "objects": objects,
        "light": 0
    })
}

fn expensive_session() -> Value {
    json!({"scene": expensive_scene(), "width": 160, "height": 160,
           "quality": {"max_depth": 64, "rr_depth": 64}})
}

fn cheap_session() -> Value {
    json!({"scene": "cornell", "width": 32, "height": 32})
}

/// Samples per pixel per second that `spp` (read twice) gains over `WINDOW`.
async fn rate<F, Fut>(spp: F) -> f64
where
    F: Fn() -> Fut,
    Fut: std::future::Future<Output = u64>,
{
    let (start, before) = (Instant::now(), spp().await);
    tokio::time::sleep(WINDOW).await;
    (spp().await - before) as f64 / start.elapsed().as_secs_f64()
}

fn spp_of(running: &Running, id: &str) -> u64 {
    running.state.session(id).expect("session").status().spp
}

/// The share of the device's time that `a` got, against `b`, over
/// `WINDOW`; `render_ms` read through `ms`.
async fn share<F, Fut>(ms: F) -> f64
where
    F: Fn() -> Fut,
    Fut: std::future::Future<Output = (f64, f64)>,
{
    let before = ms().await;
    tokio::time::sleep(WINDOW).await;
    let after = ms().await;
    let (a, b) = (after.0 - before.0, after.1 - before.1);
    a / (a + b).max(1e-9)
}

/// In process, on `backend`: the cheap session's rate alone, then beside
/// the expensive one.
async fn cheap_keeps_its_share(backend: BackendChoice) {
    let (running, base) = server(pathstream::service::ServeConfig {
        backend,
        ..config()
    })
    .await;
    let cheap = create(&base, cheap_session()).await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    tokio::time::sleep(Duration::from_millis(500)).await;
    let alone = rate(|| async { spp_of(&running, &cheap) }).await;
    let heavy = create(&base, expensive_session()).await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let heavy_session = running.state.session(&heavy).expect("session");
    // Let the expensive session measure itself.
    let deadline = Instant::now() + Duration::from_secs(60);
    while heavy_session.passes() < 3 {
        assert!(
            Instant::now() < deadline,
            "the expensive session got no passes"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    let passes_before = heavy_session.passes();
    let cheap_session = running.state.session(&cheap).expect("session");
    let ms = || async {
        (
            cheap_session.status().render_ms,
            heavy_session.status().render_ms,
        )
    };
    let (beside, cheap_share) =
        tokio::join!(rate(|| async { spp_of(&running, &cheap) }), share(ms));
    let heavy_passes = heavy_session.passes() - passes_before;
    eprintln!(
        "{backend:?}: cheap session {alone:.0} spp/s alone, {beside:.0} spp/s beside \
         the expensive one ({:.2}), {:.0}% of the device; the expensive one had \
         {heavy_passes} passes, now {} spp",
        beside / alone,
        cheap_share * 100.0,
        heavy_session.status().spp
    );
    assert!(alone > 0.0 && beside > 0.0, "the cheap session rendered");
    assert!(
        cheap_share >= LEAST_SHARE,
        "{backend:?}: starved: {:.0}% of the device beside the expensive session",
        cheap_share * 100.0
    );
    // The expensive session had its turns too (slices of ~30 ms each).
    assert!(
        heavy_passes >= 10,
        "{backend:?}: expensive session had {heavy_passes} passes"
    );
    running.shutdown().await.expect("shutdown");
}

/// The release binary, serving with a token, its log in a file.
struct Binary {
    child: Child,
    base: String,
    log: tempfile::NamedTempFile,
}

impl Drop for Binary {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

const TOKEN: &str = "s3cret";

fn start_binary() -> Binary {
    let log = tempfile::NamedTempFile::new().expect("log file");
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--backend",
            "cpu",
            "--token",
            TOKEN,
        ])
        .stdout(Stdio::piped())
        .stderr(log.reopen().expect("log"))
        .spawn()
        .expect("starts");
    let base = served_url(&mut child);
    Binary { child, base, log }
}

async fn send(
    base: &str,
    method: reqwest::Method,
    path: &str,
    body: Option<Value>,
) -> (u16, String) {
    let mut r = client()
        .request(method, format!("{base}{path}"))
        .bearer_auth(TOKEN);
    if let Some(b) = body {
        r = r.json(&b);
    }
    let r = r.send().await.expect("an answer");
    (r.status().as_u16(), r.text().await.unwrap_or_default())
}

/// A raw request (bytes no HTTP client would send); the status code.
async fn raw_status(base: &str, head: &[u8]) -> u16 {
    let addr = base.trim_start_matches("http://");
    let mut s = tokio::net::TcpStream::connect(addr).await.expect("connect");
    s.write_all(head).await.expect("write");
    let mut answer = Vec::new();
    let _ = tokio::time::timeout(Duration::from_secs(10), s.read_to_end(&mut answer)).await;
    let text = String::from_utf8_lossy(&answer);
    assert!(
        text.starts_with("HTTP/1.1 "),
        "no answer to {:?}: {text}",
        String::from_utf8_lossy(head)
    );
    text[9..12].parse().expect("status code")
}

async fn canary_through_hostile_requests() {
    let bin = start_binary();
    let base = bin.base.clone();
    let (code, body) = send(
        &base,
        reqwest::Method::POST,
        "/api/sessions",
        Some(cheap_session()),
    )
    .await;
    assert_eq!(code, 201, "{body}");
    let canary = serde_json::from_str::<Value>(&body).expect("json")["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let spp = || {
        let (base, path) = (base.clone(), format!("/api/sessions/{canary}"));
        async move {
            let (code, body) = send(&base, reqwest::Method::GET, &path, None).await;
            assert_eq!(code, 200, "{body}");
            serde_json::from_str::<Value>(&body).expect("json")["spp"]
                .as_u64()
                .expect("spp")
        }
    };
    tokio::time::sleep(Duration::from_millis(500)).await;
    let alone = rate(spp).await;
    // The attacks, while the canary renders: an expensive session...
    let (code, body) = send(
        &base,
        reqwest::Method::POST,
        "/api/sessions",
        Some(expensive_session()),
    )
    .await;
    assert_eq!(code, 201, "{body}");
    let heavy = serde_json::from_str::<Value>(&body).expect("json")["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let attacks = async {
        let auth = format!("Authorization: Bearer {TOKEN}\r\n");
        let host = "Host: x\r\nConnection: close\r\n";
        for _ in 0..20 {
            // ...a token that splits a character, invalid UTF-8 in a path,
            // wrong methods, a cross-site body...
            assert_eq!(
                raw_status(
                    &base,
                    format!("GET /api/health?token=%a\u{e9} HTTP/1.1\r\n{host}\r\n").as_bytes()
                )
                .await,
                401
            );
            let bad_path = [
                b"GET /api/sessions/%ff%fe HTTP/1.1\r\n".as_slice(),
                auth.as_bytes(),
                host.as_bytes(),
                b"\r\n",
            ]
            .concat();
            assert_eq!(raw_status(&base, &bad_path).await, 400);
            assert_eq!(
                send(&base, reqwest::Method::DELETE, "/api/health", None)
                    .await
                    .0,
                405
            );
            let text = client()
                .post(format!("{base}/api/sessions"))
                .bearer_auth(TOKEN)
                .header("content-type", "text/plain")
                .body(cheap_session().to_string())
                .send()
                .await
                .expect("answer");
            assert_eq!(text.status().as_u16(), 415);
            // ...and a frame waiter on the expensive session.
            let path = format!("/api/sessions/{heavy}/frame.png?min_spp=1000000&timeout_ms=100");
            assert_eq!(send(&base, reqwest::Method::GET, &path, None).await.0, 200);
        }
    };
    let render_ms = |id: String| {
        let base = base.clone();
        async move {
            let (code, body) = send(
                &base,
                reqwest::Method::GET,
                &format!("/api/sessions/{id}"),
                None,
            )
            .await;
            assert_eq!(code, 200, "{body}");
            serde_json::from_str::<Value>(&body).expect("json")["render_ms"]
                .as_f64()
                .expect("render_ms")
        }
    };
    let ms = || async {
        (
            render_ms(canary.clone()).await,
            render_ms(heavy.clone()).await,
        )
    };
    let (beside, canary_share, ()) = tokio::join!(rate(spp), share(ms), attacks);
    let (code, body) = send(
        &base,
        reqwest::Method::DELETE,
        &format!("/api/sessions/{heavy}"),
        None,
    )
    .await;
    assert_eq!(code, 204, "{body}");
    let log = std::fs::read_to_string(bin.log.path()).expect("log");
    eprintln!(
        "canary: {alone:.0} spp/s alone, {beside:.0} spp/s through the attacks, {:.0}% of the device",
        canary_share * 100.0
    );
    assert!(!log.contains("panicked"), "the server panicked:\n{log}");
    assert!(alone > 0.0 && beside > 0.0, "the canary rendered");
    assert!(
        canary_share >= LEAST_SHARE,
        "the canary starved: {:.0}% of the device through the attacks",
        canary_share * 100.0
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn passes_are_bounded_in_time_and_the_canary_keeps_its_share() {
    cheap_keeps_its_share(BackendChoice::Cpu).await;
    match pathstream::render::Backend::choose(BackendChoice::OpenCl { device: None }) {
        Ok(_) => cheap_keeps_its_share(BackendChoice::OpenCl { device: None }).await,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => eprintln!("OpenCL skipped: {e}"),
    }
    canary_through_hostile_requests().await;
}
