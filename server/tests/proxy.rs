//! Several boxes behind a real reverse proxy: three `pathstream serve
//! --node-name boxN` processes behind Debian's nginx running
//! `deploy/pathstream.conf` (tests/nginx/mod.rs). Sessions spread over the
//! boxes, every request and WebSocket of a session reaches the box its id
//! names, a dead box's sessions answer a JSON error through the proxy while
//! the others render on and new sessions avoid it, and a restarted box takes
//! sessions again. Also, without nginx: node names in ids and headers,
//! `--node-name` checked, and `/api/health`'s busy fraction.

mod http;
mod nginx;

use futures_util::SinkExt;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::{self, Message};

const NODE: &str = "x-pathstream-node";
const BOXES: [&str; 3] = ["box1", "box2", "box3"];

fn small() -> Value {
    json!({"scene": "cornell", "width": 32, "height": 32, "quality": {"spp": 4}})
}

/// The box a session id names.
fn node_of(id: &str) -> &str {
    id.split_once('-').map_or("", |(node, _)| node)
}

fn node_header(r: &reqwest::Response) -> String {
    r.headers()
        .get(NODE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
        .to_owned()
}

/// Creates a session through `base`; its id and the box that answered,
/// which must be the box the id names.
async fn create(client: &reqwest::Client, base: &str) -> (String, String) {
    let r = client
        .post(format!("{base}/api/sessions"))
        .json(&small())
        .send()
        .await
        .expect("request");
    assert_eq!(r.status(), 201, "{:?}", r.text().await);
    let node = node_header(&r);
    let body: Value = r.json().await.expect("json");
    let id = body["id"].as_str().expect("an id").to_owned();
    assert_eq!(node_of(&id), node, "the id names the box that made it");
    (id, node)
}

/// A request through the proxy for session `id`: answered 200 by its box.
async fn on_its_box(req: reqwest::RequestBuilder, id: &str, what: &str) -> reqwest::Response {
    let r = req.send().await.expect("request");
    assert_eq!(r.status(), 200, "{what} of {id}");
    assert_eq!(node_header(&r), node_of(id), "{what} of {id}: answered by");
    r
}

fn spp(r: &reqwest::Response) -> u64 {
    r.headers()["x-pathstream-spp"]
        .to_str()
        .ok()
        .and_then(|s| s.parse().ok())
        .expect("x-pathstream-spp")
}

/// Status, a quality change and a frame with its samples, through the proxy.
async fn check_requests(client: &reqwest::Client, base: &str, id: &str) {
    let url = format!("{base}/api/sessions/{id}");
    let r = on_its_box(client.get(&url), id, "status").await;
    assert_eq!(r.json::<Value>().await.expect("json")["id"], id);
    let patch = client
        .patch(format!("{url}/quality"))
        .json(&json!({"spp": 8}));
    on_its_box(patch, id, "quality").await;
    let frame = client.get(format!("{url}/frame.png?min_spp=8&timeout_ms=60000"));
    let r = on_its_box(frame, id, "frame.png").await;
    assert!(spp(&r) >= 8);
    assert!(r.bytes().await.expect("png").starts_with(b"\x89PNG"));
}

/// The WebSocket through the proxy: the upgrade answered by the session's
/// box, a change sent, a frame received.
async fn check_websocket(base: &str, id: &str) {
    let url = format!("{}/api/sessions/{id}/ws", base.replace("http://", "ws://"));
    let (mut ws, response) = tokio_tungstenite::connect_async(url)
        .await
        .unwrap_or_else(|e| panic!("{id}: the WebSocket connects through the proxy: {e}"));
    let node = response.headers().get(NODE).and_then(|v| v.to_str().ok());
    assert_eq!(node, Some(node_of(id)), "the upgrade of {id} answered by");
    ws.send(Message::Text(
        json!({"quality": {"spp": 12}}).to_string().into(),
    ))
    .await
    .expect("send a change");
    let png = http::first_frame(&mut ws, Duration::from_secs(60)).await;
    assert!(png.starts_with(b"\x89PNG"), "{id}: a PNG frame");
    let _ = ws.close(None).await;
}

/// A session on a dead box: a JSON error naming the box, from the proxy.
async fn check_box_down(client: &reqwest::Client, base: &str, id: &str) {
    let node = node_of(id);
    for path in ["", "/frame.png?min_spp=1"] {
        let r = client
            .get(format!("{base}/api/sessions/{id}{path}"))
            .send()
            .await
            .expect("an answer from the proxy");
        assert!(
            [502, 503].contains(&r.status().as_u16()),
            "{id}{path}: {}",
            r.status()
        );
        let kind = r
            .headers()
            .get("content-type")
            .and_then(|v| v.to_str().ok());
        assert_eq!(kind, Some("application/json"), "{id}{path}");
        let body: Value = r.json().await.expect("a JSON body");
        let error = body["error"].as_str().expect("an error message");
        assert!(
            error.contains(&format!("node {node}")) && error.contains("not reachable"),
            "{id}{path}: {error}"
        );
    }
    let url = format!("{}/api/sessions/{id}/ws", base.replace("http://", "ws://"));
    match tokio_tungstenite::connect_async(url).await {
        Err(tungstenite::Error::Http(r)) => {
            assert!([502, 503].contains(&r.status().as_u16()), "{id}/ws");
            let body = String::from_utf8_lossy(r.body().as_deref().unwrap_or_default());
            assert!(body.contains(&format!("node {node}")), "{id}/ws: {body}");
        }
        other => panic!(
            "{id}/ws on a dead box: {:?}",
            other.map(|(_, r)| r.status())
        ),
    }
}

fn count_by_node<'a>(nodes: impl Iterator<Item = &'a str>) -> BTreeMap<String, usize> {
    let mut counts = BTreeMap::new();
    for n in nodes {
        *counts.entry(n.to_owned()).or_insert(0) += 1;
    }
    counts
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_boxes_behind_nginx_route_by_session_and_outlive_a_dead_box() {
    let Some(binary) = nginx::nginx_binary() else {
        return;
    };
    let logs = tempfile::tempdir().expect("tempdir");
    let mut boxes: Vec<nginx::Node> = BOXES
        .iter()
        .map(|name| nginx::Node::start(name, logs.path()))
        .collect();
    let addrs: Vec<_> = boxes.iter().map(|b| b.addr).collect();
    let proxy = nginx::Nginx::start(&binary, &addrs);
    let base = proxy.base.clone();
    let client = reqwest::Client::new();

    // Creation spreads over the boxes.
    let mut sessions = Vec::new();
    for _ in 0..30 {
        sessions.push(create(&client, &base).await.0);
    }
    let counts = count_by_node(sessions.iter().map(|id| node_of(id)));
    for name in BOXES {
        let n = counts.get(name).copied().unwrap_or(0);
        assert!(n >= 5, "{name} got {n} of 30 sessions: {counts:?}");
    }

    // Every request and the WebSocket of a session reach its box.
    for id in &sessions {
        check_requests(&client, &base, id).await;
        check_websocket(&base, id).await;
    }
    let r = client
        .get(format!("{base}/api/health"))
        .send()
        .await
        .expect("health");
    let answered_by = node_header(&r);
    let health: Value = r.json().await.expect("json");
    assert_eq!(health["node"], answered_by.as_str(), "{health}");
    assert!(health["load"][0]["busy"].as_f64().is_some(), "{health}");

    // One box dies.
    let dead = "box2";
    boxes[1].kill();
    let (lost, alive): (Vec<&String>, Vec<&String>) =
        sessions.iter().partition(|id| node_of(id) == dead);
    for id in &lost {
        check_box_down(&client, &base, id).await;
    }
    // The others render on: a camera change, then a frame of it.
    for id in &alive {
        let url = format!("{base}/api/sessions/{id}");
        let change = client
            .patch(format!("{url}/camera"))
            .json(&json!({"vfov_deg": 35}));
        let status: Value = on_its_box(change, id, "camera")
            .await
            .json()
            .await
            .expect("json");
        let frame = client.get(format!("{url}/frame.png?min_spp=8&timeout_ms=60000"));
        let r = on_its_box(frame, id, "frame after the box died").await;
        assert!(spp(&r) >= 8);
        let generation = r.headers()["x-pathstream-generation"].to_str().ok();
        assert_eq!(
            generation.map(str::to_owned),
            Some(status["generation"].to_string()),
            "{id}: a frame of the changed camera"
        );
    }
    // New sessions land on live boxes only, every one of them created.
    let more: Vec<String> = {
        let mut v = Vec::new();
        for _ in 0..10 {
            v.push(create(&client, &base).await.1);
        }
        v
    };
    assert!(!more.iter().any(|n| n == dead), "{more:?}");

    // The box comes back (same name, same address) with room for one
    // session: it takes one again once nginx tries it (at most
    // fail_timeout, 10 s, later), and then, full, answers 429, which nginx
    // passes on to another box.
    boxes[1].restart(&["--max-sessions", "1"]);
    assert_eq!(boxes[1].addr, addrs[1], "restarted on its address");
    let r = client
        .get(format!("{base}/api/sessions/{}", lost[0]))
        .send()
        .await
        .expect("request");
    assert_eq!(r.status(), 404, "its sessions went with the process");
    assert_eq!(node_header(&r), dead);
    let until = Instant::now() + Duration::from_secs(60);
    loop {
        let (_, node) = create(&client, &base).await;
        if node == dead {
            break;
        }
        assert!(
            Instant::now() < until,
            "the restarted box took no session in 60 s; nginx log:\n{}",
            proxy.log()
        );
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    for _ in 0..6 {
        let (_, node) = create(&client, &base).await;
        assert_ne!(node, dead, "{dead} is full");
    }
}

#[test]
fn the_readme_shows_the_tested_configuration() {
    let readme_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../README.md");
    let readme = std::fs::read_to_string(readme_path).expect("README.md");
    let conf = nginx::deploy_conf();
    assert!(
        readme.contains(&format!("```nginx\n{conf}```\n")),
        "README.md must show deploy/pathstream.conf exactly, in a ```nginx block"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_node_name_starts_every_session_id_and_names_every_response() {
    let (running, base) = http::server(pathstream::service::ServeConfig {
        node_name: Some("box7".into()),
        ..http::config()
    })
    .await;
    let client = reqwest::Client::new();
    let (id, node) = create(&client, &base).await;
    assert_eq!(node, "box7");
    let hex = id.strip_prefix("box7-").expect("box7-...");
    assert!(
        hex.len() == 16 && hex.bytes().all(|b| b.is_ascii_hexdigit()),
        "{id}"
    );
    for (path, code) in [
        ("/api/health", 200),
        (&format!("/api/sessions/{id}") as &str, 200),
        ("/api/sessions/box7-nope", 404),
        ("/api/nope", 404),
        ("/", 200),
        ("/metrics", 200),
    ] {
        let r = client
            .get(format!("{base}{path}"))
            .send()
            .await
            .expect("request");
        assert_eq!(r.status(), code, "{path}");
        assert_eq!(node_header(&r), "box7", "{path}");
    }
    assert_eq!(health(&base).await["node"], "box7");
    running.shutdown().await.expect("shutdown");

    // Without a name: plain ids, no header, a null node.
    let (running, base) = http::server(http::config()).await;
    let r = client
        .post(format!("{base}/api/sessions"))
        .json(&small())
        .send()
        .await
        .expect("request");
    assert!(r.headers().get(NODE).is_none());
    let id = r.json::<Value>().await.expect("json")["id"]
        .as_str()
        .expect("id")
        .to_owned();
    assert!(id.len() == 16 && !id.contains('-'), "{id}");
    let answer = health(&base).await;
    assert_eq!(answer["node"], Value::Null, "{answer}");
    running.shutdown().await.expect("shutdown");
}

#[test]
fn serve_refuses_a_bad_node_name_with_exit_code_2() {
    for bad in ["Box1", "box-1", "", &"x".repeat(33)] {
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
            .args(["serve", "--addr", "127.0.0.1:0", "--backend", "cpu"])
            .args(["--node-name", bad])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("starts");
        let until = Instant::now() + Duration::from_secs(20);
        let status = loop {
            if let Some(status) = child.try_wait().expect("wait") {
                break status;
            }
            if Instant::now() > until {
                let _ = child.kill();
                let _ = child.wait();
                panic!("--node-name '{bad}': still serving");
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let mut err = String::new();
        if let Some(mut pipe) = child.stderr.take() {
            use std::io::Read;
            let _ = pipe.read_to_string(&mut err);
        }
        assert_eq!(status.code(), Some(2), "'{bad}': {err}");
        assert!(
            err.contains("--node-name") && !err.contains("panicked"),
            "'{bad}': {err}"
        );
    }
}

async fn health(base: &str) -> Value {
    let r = reqwest::get(format!("{base}/api/health"))
        .await
        .expect("request");
    assert_eq!(r.status(), 200);
    r.json().await.expect("json")
}

/// The busy fraction of the only worker, from `/api/health`.
async fn busy(base: &str) -> f64 {
    let answer = health(base).await;
    answer["load"][0]["busy"]
        .as_f64()
        .unwrap_or_else(|| panic!("load[0].busy in {answer}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn health_reports_a_rendering_worker_busy_and_a_halted_one_idle() {
    let (running, base) = http::server(http::config()).await;
    let idle = busy(&base).await;
    assert!(idle < 0.1, "no session yet: {idle}");
    let s = http::create(
        &base,
        json!({"scene": "cornell", "width": 64, "height": 64}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    // Rendering with no halt: the worker has no pause but between passes.
    tokio::time::sleep(Duration::from_millis(2500)).await;
    let rendering = busy(&base).await;
    assert!(rendering > 0.5, "while rendering: {rendering}");
    let answer = health(&base).await;
    assert_eq!(answer["load"][0]["sessions"], 1, "{answer}");

    // Halted: after a window (5 s) of idling, next to nothing.
    let r = http::patch(&base, &id, "quality", json!({"spp": 1})).await;
    assert_eq!(r.status(), 200);
    let until = Instant::now() + Duration::from_secs(30);
    while http::status(&base, &id).await["state"] != "halted" {
        assert!(Instant::now() < until, "the session never halted");
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    tokio::time::sleep(Duration::from_millis(6500)).await;
    let halted = busy(&base).await;
    assert!(halted < 0.1, "halted for 6.5 s: {halted}");
    running.shutdown().await.expect("shutdown");
}
