//! The render service end to end: a real server on 127.0.0.1:0, real HTTP
//! and WebSocket clients.

mod http;

use futures_util::{SinkExt, StreamExt};
use http::*;
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn session_lifecycle() {
    let (running, base) = server(config()).await;
    let health: Value = client()
        .get(format!("{base}/api/health"))
        .send()
        .await
        .expect("req")
        .json()
        .await
        .expect("json");
    assert_eq!(health["status"], "ok");
    let scenes: Value = client()
        .get(format!("{base}/api/scenes"))
        .send()
        .await
        .expect("req")
        .json()
        .await
        .expect("json");
    assert!(scenes["scenes"]
        .as_array()
        .expect("list")
        .iter()
        .any(|s| s == "cornell-glass"));

    let s = create(
        &base,
        json!({"scene": "cornell", "width": 24, "height": 16, "quality": {"spp": 32}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    for field in [
        "scene",
        "width",
        "height",
        "camera",
        "light",
        "quality",
        "state",
        "spp",
        "error_estimate",
        "samples_per_sec",
        "elapsed_ms",
        "backend",
        "device",
    ] {
        assert!(s.get(field).is_some(), "status lacks {field}: {s}");
    }
    assert_eq!(s["backend"], "cpu");

    let list: Value = client()
        .get(format!("{base}/api/sessions"))
        .send()
        .await
        .expect("req")
        .json()
        .await
        .expect("json");
    assert_eq!(list["sessions"][0]["id"], id.as_str());

    // min_spp waits; the halt at 32 spp stops the session.
    let png = client()
        .get(format!("{base}/api/sessions/{id}/frame.png?min_spp=32"))
        .send()
        .await
        .expect("req");
    assert_eq!(png.headers()["content-type"], "image/png");
    let img = image::load_from_memory(&png.bytes().await.expect("body")).expect("a PNG");
    assert_eq!((img.width(), img.height()), (24, 16));
    let st = status(&base, &id).await;
    assert_eq!(st["spp"], 32);
    assert_eq!(st["state"], "halted");
    let pixels = pfm(&base, &id, 32).await;
    assert_eq!(pixels.len(), 24 * 16);

    let metrics = client()
        .get(format!("{base}/metrics"))
        .send()
        .await
        .expect("req")
        .text()
        .await
        .expect("text");
    assert!(metrics.contains("pathstream_sessions 1"), "{metrics}");
    assert!(
        metrics.contains("pathstream_worker_sessions{worker=\"0\",backend=\"cpu\"} 1"),
        "{metrics}"
    );
    assert!(
        metrics.contains("pathstream_worker_busy_ratio{worker=\"0\",backend=\"cpu\"} "),
        "{metrics}"
    );
    assert!(
        metrics.contains("pathstream_samples_total{backend=\"cpu\"} "),
        "{metrics}"
    );
    let rendered: u64 = metrics
        .lines()
        .find(|l| l.starts_with("pathstream_samples_total{backend=\"cpu\"}"))
        .and_then(|l| l.rsplit(' ').next()?.parse().ok())
        .expect("a count");
    assert!(rendered >= 32 * 24 * 16, "{rendered} camera paths counted");

    let del = client()
        .delete(format!("{base}/api/sessions/{id}"))
        .send()
        .await
        .expect("req");
    assert_eq!(del.status(), 204);
    let gone = client()
        .get(format!("{base}/api/sessions/{id}"))
        .send()
        .await
        .expect("req");
    assert_eq!(gone.status(), 404);
    let body: Value = gone.json().await.expect("json error");
    assert!(body["error"].as_str().expect("message").contains(&id));
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn updates_restart_accumulation_and_change_the_image() {
    let (running, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 24, "height": 24, "quality": {"spp": 64}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let before = pfm(&base, &id, 64).await;

    let r = patch(
        &base,
        &id,
        "camera",
        json!({"position": [50, 40, 250], "look_at": [20, 20, 0]}),
    )
    .await;
    assert_eq!(r.status(), 200);
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["generation"], 1);
    assert!(
        st["spp"].as_u64().expect("spp") < 64,
        "accumulation restarted: {st}"
    );
    assert_eq!(st["camera"]["position"], json!([50.0, 40.0, 250.0]));
    let after = pfm(&base, &id, 64).await;
    let diff: f64 = before
        .iter()
        .zip(&after)
        .map(|(a, b)| f64::from((a[0] - b[0]).abs()))
        .sum::<f64>()
        / before.len() as f64;
    assert!(
        diff > 0.05,
        "the camera moved but the image did not change ({diff})"
    );

    // Quality and scene changes restart too.
    let st: Value = patch(&base, &id, "quality", json!({"max_depth": 2}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["generation"], 2);
    assert_eq!(st["quality"]["max_depth"], 2);
    assert_eq!(
        st["quality"]["spp"], 64,
        "fields not named keep their values"
    );
    // A preset sets the path knobs; fields beside it win; seed and halts stay.
    let st: Value = patch(
        &base,
        &id,
        "quality",
        json!({"preset": "reference", "rr_depth": 2}),
    )
    .await
    .json()
    .await
    .expect("json");
    let reference =
        pathstream::render::Preset::Reference.apply(pathstream::render::Quality::default());
    assert_eq!(st["quality"]["max_depth"], reference.max_depth);
    assert_eq!(st["quality"]["nee"], reference.nee);
    assert_eq!(st["quality"]["rr_depth"], 2);
    assert_eq!(st["quality"]["spp"], 64);
    assert_eq!(st["generation"], 3);
    let presets: Value = client()
        .get(format!("{base}/api/presets"))
        .send()
        .await
        .expect("req")
        .json()
        .await
        .expect("json");
    let names: Vec<&str> = presets["presets"]
        .as_array()
        .expect("list")
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    assert_eq!(names, ["preview", "interactive", "final", "reference"]);
    assert_eq!(
        presets["presets"][3]["quality"]["max_depth"],
        reference.max_depth
    );
    let r = client()
        .put(format!("{base}/api/sessions/{id}/scene"))
        .json(&json!("cornell-glass"))
        .send()
        .await
        .expect("req");
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["scene"], "cornell-glass");
    assert_eq!(st["generation"], 4);
    running.shutdown().await.expect("shutdown");
}

/// Luminance-weighted mean column of an image `width` pixels wide: where
/// the light falls, left to right.
fn centroid_x(img: &[[f32; 3]], width: usize) -> f64 {
    let (mut sum, mut weighted) = (0.0, 0.0);
    for (i, p) in img.iter().enumerate() {
        let l = f64::from(p[0] + p[1] + p[2]);
        sum += l;
        weighted += l * (i % width) as f64;
    }
    weighted / sum
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn light_changes_the_image_where_expected() {
    let (running, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 16, "height": 16, "quality": {"spp": 256, "seed": 1}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let base_img = pfm(&base, &id, 256).await;

    // Twice the intensity, same seed: every sample's path is the same and
    // its radiance exactly doubles, so every pixel does, to f32 rounding.
    let st: Value = patch(&base, &id, "light", json!({"intensity": 24}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["light"]["intensity"], 24.0);
    let bright = pfm(&base, &id, 256).await;
    for (i, (b, a)) in bright.iter().zip(&base_img).enumerate() {
        for c in 0..3 {
            let (b, a) = (f64::from(b[c]), f64::from(a[c]));
            assert!(
                (b - 2.0 * a).abs() <= 2e-6 * a,
                "pixel {i} channel {c}: {b} vs 2 x {a}"
            );
        }
    }
    assert!(mean(&base_img)[1] > 0.1, "the room is lit");
    // A red light: no green or blue at all.
    let st: Value = patch(&base, &id, "light", json!({"color": [1, 0, 0]}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["light"]["color"], json!([1.0, 0.0, 0.0]));
    let red = mean(&pfm(&base, &id, 256).await);
    assert!(red[0] > 0.1 && red[1] == 0.0 && red[2] == 0.0, "{red:?}");
    // Moving the light toward a wall moves the light in the image with it.
    let centre = centroid_x(&bright, 16);
    let mut seen = Vec::new();
    for (x, side) in [(15.0, -1.0), (85.0, 1.0)] {
        let r = patch(
            &base,
            &id,
            "light",
            json!({"position": [x, 60, 81.6], "color": [1, 1, 1]}),
        )
        .await;
        assert_eq!(r.status(), 200);
        let st: Value = r.json().await.expect("json");
        assert_eq!(st["light"]["position"], json!([x, 60.0, 81.6]));
        let moved = centroid_x(&pfm(&base, &id, 256).await, 16);
        seen.push(moved);
        assert!(
            (moved - centre) * side > 1.5,
            "light at x = {x}: the image's centroid {moved:.2} vs {centre:.2} in the middle"
        );
    }
    eprintln!(
        "centroid column: light in the middle {centre:.2}, left {:.2}, right {:.2}",
        seen[0], seen[1]
    );
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_gets_a_4xx_with_a_json_error_and_the_server_keeps_serving() {
    let mut cfg = config();
    cfg.max_body_bytes = 64 * 1024;
    cfg.max_pixels = 512 * 512;
    cfg.max_sessions = 2;
    let (running, base) = server(cfg).await;
    let keep = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let id = keep.as_str();
    let huge = "x".repeat(100 * 1024);
    let cases: Vec<(&str, String, String, u16, &str)> = vec![
        ("POST", "/api/sessions".into(), "{\"scene\": ".into(), 400, "EOF while parsing"),
        ("POST", "/api/sessions".into(), json!({"width": "wide"}).to_string(), 400, "width: invalid type"),
        ("POST", "/api/sessions".into(), json!({"width": -4}).to_string(), 400, "width: invalid value"),
        ("POST", "/api/sessions".into(), json!({"width": 100000, "height": 100000}).to_string(), 400, "width"),
        ("POST", "/api/sessions".into(), json!({"width": 1000, "height": 1000}).to_string(), 400, "limit of 262144"),
        ("POST", "/api/sessions".into(), json!({"width": 0}).to_string(), 400, "width: must be between 1"),
        ("POST", "/api/sessions".into(), json!({"scene": "nope"}).to_string(), 400, "unknown scene 'nope'"),
        ("POST", "/api/sessions".into(), json!({"scene": 3}).to_string(), 400, "scene: must be"),
        ("POST", "/api/sessions".into(), json!({"colour": 1}).to_string(), 400, "unknown field `colour`"),
        ("POST", "/api/sessions".into(), json!({"quality": {"max_depth": -1}}).to_string(), 400, "quality.max_depth"),
        ("POST", "/api/sessions".into(), json!({"quality": {"clamp": -1}}).to_string(), 400, "quality.clamp"),
        ("POST", "/api/sessions".into(), json!({"backend": "quantum"}).to_string(), 400, "backend: unknown backend"),
        ("POST", "/api/sessions".into(), json!({"scene": {"camera": {}}}).to_string(), 400, "scene: camera"),
        ("POST", "/api/sessions".into(), huge.clone(), 413, "larger than the limit"),
        ("GET", "/api/sessions/nope".into(), String::new(), 404, "no session 'nope'"),
        ("PATCH", "/api/sessions/nope/camera".into(), "{}".into(), 404, "no session 'nope'"),
        ("PATCH", format!("/api/sessions/{id}/camera"), json!({"vfov_deg": 200}).to_string(), 400, "camera.vfov_deg"),
        ("PATCH", format!("/api/sessions/{id}/camera"), json!({"up": [0, 0, 0]}).to_string(), 400, "camera.up"),
        ("PATCH", format!("/api/sessions/{id}/camera"), json!({"zoom": 2}).to_string(), 400, "unknown field `zoom`"),
        ("PATCH", format!("/api/sessions/{id}/light"), json!({"intensity": -1}).to_string(), 400, "light.intensity"),
        ("PATCH", format!("/api/sessions/{id}/light"), json!({"color": [2, 0, 0]}).to_string(), 400, "light.color"),
        ("PATCH", format!("/api/sessions/{id}/quality"), json!({"filter": "gauss"}).to_string(), 400, "quality.filter"),
        ("PATCH", format!("/api/sessions/{id}/quality"), json!([1, 2]).to_string(), 400, "quality: must be a JSON object"),
        ("PATCH", format!("/api/sessions/{id}/quality"), json!({"preset": "fast"}).to_string(), 400, "quality.preset: unknown preset \"fast\" (one of preview, interactive, final, reference)"),
        ("POST", "/api/sessions".into(), json!({"quality": {"preset": 3}}).to_string(), 400, "quality.preset: must be one of"),
        ("PUT", format!("/api/sessions/{id}/scene"), json!("nope").to_string(), 400, "unknown scene"),
        ("GET", format!("/api/sessions/{id}/frame.png?min_spp=abc"), String::new(), 400, "min_spp"),
        ("GET", "/api/nothing".into(), String::new(), 404, "no route"),
    ];
    let c = client();
    for (method, path, body, code, needle) in cases {
        let url = format!("{base}{path}");
        let req = match method {
            "POST" => c.post(&url),
            "PATCH" => c.patch(&url),
            "PUT" => c.put(&url),
            _ => c.get(&url),
        };
        let r = req
            .header("content-type", "application/json")
            .body(body)
            .send()
            .await
            .expect("request");
        let status = r.status().as_u16();
        let text = r.text().await.expect("body");
        assert_eq!(status, code, "{method} {path}: {text}");
        let v: Value = serde_json::from_str(&text)
            .unwrap_or_else(|_| panic!("{method} {path}: not JSON: {text}"));
        let msg = v["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{method} {path}: no error field: {text}"));
        assert!(
            msg.contains(needle),
            "{method} {path}: '{needle}' not in '{msg}'"
        );
    }
    // The session limit: a second session fits, a third does not.
    create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await;
    let r = c
        .post(format!("{base}/api/sessions"))
        .json(&json!({"width": 8, "height": 8}))
        .send()
        .await
        .expect("req");
    assert_eq!(r.status(), 429);
    let v: Value = r.json().await.expect("json");
    assert!(
        v["error"]
            .as_str()
            .expect("msg")
            .contains("limit of 2 sessions"),
        "{v}"
    );
    // A WebSocket message that is not JSON: an error message, socket still usable.
    let mut ws = ws_connect(&base, id).await;
    ws.send(Message::Text("not json".into()))
        .await
        .expect("send");
    ws.send(Message::Text(json!({"zoom": 1}).to_string().into()))
        .await
        .expect("send");
    ws.send(Message::Text(
        json!({"camera": {"vfov_deg": 50}}).to_string().into(),
    ))
    .await
    .expect("send");
    let mut errors = Vec::new();
    let until = Instant::now() + Duration::from_secs(5);
    while errors.len() < 2 && Instant::now() < until {
        if let Ok(Some(Ok(Message::Text(t)))) =
            tokio::time::timeout(Duration::from_secs(5), ws.next()).await
        {
            let v: Value = serde_json::from_str(t.as_str()).expect("json");
            if v["type"] == "error" {
                errors.push(v["error"].as_str().expect("msg").to_owned());
            }
        }
    }
    assert!(errors[0].contains("invalid JSON"), "{errors:?}");
    assert!(errors[1].contains("unknown key 'zoom'"), "{errors:?}");
    // The socket applies messages in order, but the error replies can arrive
    // before the third message is applied: wait for it (bounded).
    let until = Instant::now() + Duration::from_secs(5);
    let mut st = status(&base, id).await;
    while st["camera"]["vfov_deg"] != 50.0 && Instant::now() < until {
        tokio::time::sleep(Duration::from_millis(20)).await;
        st = status(&base, id).await;
    }
    assert_eq!(
        st["camera"]["vfov_deg"], 50.0,
        "the valid message after the bad ones applied"
    );
    // And the server still serves the session.
    assert_eq!(pfm(&base, id, 4).await.len(), 64);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_token_guards_every_api_route_and_the_websocket() {
    let mut cfg = config();
    cfg.token = Some("s3cret".into());
    let (running, base) = server(cfg).await;
    let c = client();
    for (auth, code) in [
        (None, 401),
        (Some("Bearer wrong"), 401),
        (Some("Bearer s3cret"), 200),
    ] {
        let mut req = c.get(format!("{base}/api/sessions"));
        if let Some(a) = auth {
            req = req.header("authorization", a);
        }
        let r = req.send().await.expect("request");
        assert_eq!(r.status().as_u16(), code, "{auth:?}");
        if code == 401 {
            let v: Value = r.json().await.expect("json");
            assert!(v["error"].as_str().expect("msg").contains("token"));
        }
    }
    let r = c
        .post(format!("{base}/api/sessions"))
        .header("authorization", "Bearer s3cret")
        .json(&json!({"scene": "furnace", "width": 8, "height": 8}))
        .send()
        .await
        .expect("req");
    let id = r.json::<Value>().await.expect("json")["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let ws_base = base.replace("http://", "ws://");
    assert!(
        tokio_tungstenite::connect_async(format!("{ws_base}/api/sessions/{id}/ws"))
            .await
            .is_err()
    );
    let (mut ws, _) =
        tokio_tungstenite::connect_async(format!("{ws_base}/api/sessions/{id}/ws?token=s3cret"))
            .await
            .expect("with the token");
    let frame = first_frame(&mut ws, Duration::from_secs(60)).await;
    assert!(
        frame.starts_with(b"\x89PNG"),
        "a PNG frame through the guarded socket"
    );
    // The browser client itself needs no token.
    assert_eq!(
        c.get(format!("{base}/"))
            .send()
            .await
            .expect("req")
            .status(),
        200
    );
    // A query that is not valid percent-encoding, even with raw non-ASCII
    // bytes, is a wrong token (401 with a JSON error), not a dropped request.
    for query in [
        &b"token=%a\xc3\xa9"[..],
        b"token=%",
        b"token=%zz",
        b"token=s3cret%ff",
        b"token=%e9%",
    ] {
        let (code, body) = raw_get(&running.addr, b"/api/sessions?", query).await;
        assert_eq!(code, 401, "{}: {body}", String::from_utf8_lossy(query));
        assert!(body.contains("\"error\""), "{body}");
    }
    let (code, _) = raw_get(&running.addr, b"/api/sessions?", b"token=s3%63ret").await;
    assert_eq!(code, 200, "a percent-encoded right token");
    running.shutdown().await.expect("shutdown");
}

/// A GET of `path` + `query` written byte for byte (no client library
/// would send raw non-ASCII bytes): the status code and the body.
async fn raw_get(addr: &std::net::SocketAddr, path: &[u8], query: &[u8]) -> (u16, String) {
    let target = [path, query].concat();
    let (code, _, body) = http::raw(addr, "GET", &target, "", b"").await;
    (code, body)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idle_sessions_expire_but_watched_ones_do_not() {
    let timeout = Duration::from_millis(1000);
    let mut cfg = config();
    cfg.idle_timeout = timeout;
    let (running, base) = server(cfg).await;
    // The watched session gets its client at once; then the idle one is made.
    let watched = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let mut ws = ws_connect(&base, &watched).await;
    let created = Instant::now();
    let idle = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    // The idle one goes, however slow this machine is (bounded)...
    let state = running.state.clone();
    let gone = async {
        // `sessions()` lists without touching (a `session(id)` lookup would
        // count as activity).
        while state.sessions().iter().any(|s| s.id == idle) {
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    };
    tokio::select! {
        () = gone => {}
        _ = read_frames(&mut ws, Instant::now() + Duration::from_secs(60)) => panic!("the idle session outlived 60 s"),
    }
    let lived = created.elapsed();
    assert!(
        lived >= timeout,
        "expired after {lived:?}, before its timeout of {timeout:?}"
    );
    // ... and the watched one, idle for HTTP as long, stays while its
    // client keeps reading, for several timeouts more.
    read_frames(&mut ws, Instant::now() + 3 * timeout).await;
    let gone = client()
        .get(format!("{base}/api/sessions/{idle}"))
        .send()
        .await
        .expect("req");
    assert_eq!(gone.status(), 404);
    let kept = client()
        .get(format!("{base}/api/sessions/{watched}"))
        .send()
        .await
        .expect("req");
    assert_eq!(kept.status(), 200, "a watched session does not expire");
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn graceful_shutdown_closes_websockets_cleanly() {
    let (running, base) = server(config()).await;
    let id = create(
        &base,
        json!({"scene": "cornell", "width": 16, "height": 16}),
    )
    .await["id"]
        .as_str()
        .expect("id")
        .to_owned();
    let mut ws = ws_connect(&base, &id).await;
    read_frames(&mut ws, Instant::now() + Duration::from_millis(300)).await;
    let done = tokio::spawn(running.shutdown());
    let mut closed = None;
    while let Ok(Some(Ok(msg))) = tokio::time::timeout(Duration::from_secs(5), ws.next()).await {
        if let Message::Close(frame) = msg {
            closed = frame;
            break;
        }
    }
    let frame = closed.expect("a close frame");
    assert_eq!(u16::from(frame.code), 1001, "going away");
    tokio::time::timeout(Duration::from_secs(10), done)
        .await
        .expect("shutdown finishes")
        .expect("task")
        .expect("clean");
    assert!(
        client()
            .get(format!("{base}/api/health"))
            .send()
            .await
            .is_err(),
        "no longer listening"
    );
}

/// Every file under `static/`, `/`-separated, relative to it, sorted.
fn static_files(dir: &std::path::Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).expect("read_dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path
                    .strip_prefix(dir)
                    .expect("below")
                    .to_str()
                    .expect("utf-8")
                    .replace('\\', "/");
                out.push(rel);
            }
        }
    }
    out.sort();
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_file_under_static_is_served_built_in_and_from_a_folder() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../static");
    let files = static_files(&dir);
    assert!(
        files.iter().any(|f| f.starts_with("js/")),
        "the page's modules live in static/js: {files:?}"
    );
    let mut embedded: Vec<String> = pathstream::api::embedded_static_files().collect();
    embedded.sort();
    assert_eq!(
        embedded, files,
        "the binary carries exactly the files under static/"
    );
    for static_dir in [None, Some(dir.clone())] {
        let from = if static_dir.is_some() {
            "--static-dir"
        } else {
            "built in"
        };
        let mut cfg = config();
        cfg.static_dir = static_dir;
        let (running, base) = server(cfg).await;
        let c = client();
        for file in files.iter().map(String::as_str).chain(["/"]) {
            let url = format!("{base}/{}", file.trim_start_matches('/'));
            let r = c.get(&url).send().await.expect("req");
            assert_eq!(r.status(), 200, "{from}: {url}");
            let headers = r.headers().clone();
            let on_disk = std::fs::read(dir.join(if file == "/" { "index.html" } else { file }))
                .expect("file");
            assert_eq!(
                r.bytes().await.expect("body").to_vec(),
                on_disk,
                "{from}: {url}"
            );
            let kind = headers["content-type"].to_str().expect("ascii").to_owned();
            let want = match file.rsplit('.').next() {
                Some("js") => "javascript",
                Some("css") => "text/css",
                _ => "text/html",
            };
            assert!(kind.contains(want), "{from}: {url} is {kind}");
            assert_eq!(headers["cache-control"], "no-cache", "{from}: {url}");
            // Revalidation: an unchanged file is not sent again.
            let (name, value) = match (headers.get("etag"), headers.get("last-modified")) {
                (Some(tag), _) => ("if-none-match", tag.clone()),
                (None, Some(date)) => ("if-modified-since", date.clone()),
                (None, None) => panic!("{from}: {url} has neither ETag nor Last-Modified"),
            };
            let again = c.get(&url).header(name, value).send().await.expect("req");
            assert_eq!(again.status(), 304, "{from}: {url} with {name}");
        }
        for (method, path, code) in [
            ("GET", "/nope.js", 404),
            ("GET", "/js/nope.js", 404),
            ("POST", "/app.js", 405),
        ] {
            let url = format!("{base}{path}");
            let r = if method == "GET" {
                c.get(&url)
            } else {
                c.post(&url)
            }
            .send()
            .await
            .expect("req");
            assert_eq!(r.status(), code, "{from}: {method} {path}");
            let v: Value = r
                .json()
                .await
                .unwrap_or_else(|e| panic!("{from}: {method} {path}: not JSON: {e}"));
            assert!(
                v["error"].as_str().is_some_and(|e| e.contains(path)),
                "{from}: {v}"
            );
        }
        running.shutdown().await.expect("shutdown");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_the_opencl_device_fails_the_service_reports_rayon() {
    use pathstream::render::backend::OpenClBackend;
    use pathstream::render::Backend;
    let mut device = match OpenClBackend::new(None) {
        Ok(d) => d,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => return eprintln!("skipping: {e}"),
    };
    device.fail_launches = true;
    let chosen_by_auto = Backend::OpenCl {
        backend: Box::new(device),
        fallback: true,
    };
    let running = pathstream::api::start_with_device(config(), Some(chosen_by_auto))
        .await
        .expect("starts");
    let base = format!("http://{}", running.addr);
    let get = |path: &'static str| {
        let url = format!("{base}{path}");
        async move {
            client()
                .get(url)
                .send()
                .await
                .expect("req")
                .json::<Value>()
                .await
                .expect("json")
        }
    };
    let devices = get("/api/devices").await;
    assert_eq!(
        (
            devices["default"].as_str(),
            devices["backends"][1]["backend"].as_str()
        ),
        (Some("opencl"), Some("opencl")),
        "{devices}"
    );

    let s = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await;
    let id = s["id"].as_str().expect("id").to_owned();
    assert_eq!(s["backend"], "opencl", "placed on the device");
    assert_eq!(
        pfm(&base, &id, 4).await.len(),
        64,
        "renders on after the failure"
    );
    let st = status(&base, &id).await;
    assert_eq!(st["backend"], "cpu", "{st}");
    assert!(
        st["device"]
            .as_str()
            .expect("device")
            .contains("OpenCL failed"),
        "{st}"
    );
    for path in ["/api/devices", "/api/health"] {
        let v = get(path).await;
        let worker = &v["backends"][1];
        assert_eq!(worker["backend"], "cpu", "{path}: {v}");
        assert!(
            worker["device"]
                .as_str()
                .expect("device")
                .contains("OpenCL failed"),
            "{path}: {v}"
        );
    }
    assert_eq!(get("/api/devices").await["default"], "cpu");
    // A new session says where it will render before its first pass.
    let fresh = create(
        &base,
        json!({"scene": "furnace", "width": 8, "height": 8, "quality": {"spp": 1}}),
    )
    .await;
    assert_eq!(fresh["backend"], "cpu", "{fresh}");
    let r = client()
        .post(format!("{base}/api/sessions"))
        .json(&json!({"backend": "opencl"}))
        .send()
        .await
        .expect("req");
    assert_eq!(r.status(), 400);
    let v: Value = r.json().await.expect("json");
    assert!(
        v["error"]
            .as_str()
            .expect("msg")
            .starts_with("backend: the OpenCL device is no longer in use"),
        "{v}"
    );
    running.shutdown().await.expect("shutdown");
}
