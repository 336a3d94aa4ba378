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
    let health: Value = client().get(format!("{base}/api/health")).send().await.expect("req").json().await.expect("json");
    assert_eq!(health["status"], "ok");
    let scenes: Value = client().get(format!("{base}/api/scenes")).send().await.expect("req").json().await.expect("json");
    assert!(scenes["scenes"].as_array().expect("list").iter().any(|s| s == "cornell-glass"));

    let s = create(&base, json!({"scene": "cornell", "width": 24, "height": 16, "quality": {"spp": 32}})).await;
    let id = s["id"].as_str().expect("id").to_owned();
    for field in ["scene", "width", "height", "camera", "light", "quality", "state", "spp", "error_estimate", "samples_per_sec", "elapsed_ms", "backend", "device"] {
        assert!(s.get(field).is_some(), "status lacks {field}: {s}");
    }
    assert_eq!(s["backend"], "cpu");

    let list: Value = client().get(format!("{base}/api/sessions")).send().await.expect("req").json().await.expect("json");
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

    let metrics = client().get(format!("{base}/metrics")).send().await.expect("req").text().await.expect("text");
    assert!(metrics.contains("pathstream_sessions 1"), "{metrics}");
    assert!(metrics.contains("pathstream_samples_total{backend=\"cpu\"} "), "{metrics}");
    let rendered: u64 = metrics
        .lines()
        .find(|l| l.starts_with("pathstream_samples_total{backend=\"cpu\"}"))
        .and_then(|l| l.rsplit(' ').next()?.parse().ok())
        .expect("a count");
    assert!(rendered >= 32 * 24 * 16, "{rendered} camera paths counted");

    let del = client().delete(format!("{base}/api/sessions/{id}")).send().await.expect("req");
    assert_eq!(del.status(), 204);
    let gone = client().get(format!("{base}/api/sessions/{id}")).send().await.expect("req");
    assert_eq!(gone.status(), 404);
    let body: Value = gone.json().await.expect("json error");
    assert!(body["error"].as_str().expect("message").contains(&id));
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn updates_restart_accumulation_and_change_the_image() {
    let (running, base) = server(config()).await;
    let s = create(&base, json!({"scene": "cornell", "width": 24, "height": 24, "quality": {"spp": 64}})).await;
    let id = s["id"].as_str().expect("id").to_owned();
    let before = pfm(&base, &id, 64).await;

    let r = patch(&base, &id, "camera", json!({"position": [50, 40, 250], "look_at": [20, 20, 0]})).await;
    assert_eq!(r.status(), 200);
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["generation"], 1);
    assert!(st["spp"].as_u64().expect("spp") < 64, "accumulation restarted: {st}");
    assert_eq!(st["camera"]["position"], json!([50.0, 40.0, 250.0]));
    let after = pfm(&base, &id, 64).await;
    let diff: f64 = before.iter().zip(&after).map(|(a, b)| f64::from((a[0] - b[0]).abs())).sum::<f64>() / before.len() as f64;
    assert!(diff > 0.05, "the camera moved but the image did not change ({diff})");

    // Quality and scene changes restart too.
    let st: Value = patch(&base, &id, "quality", json!({"max_depth": 2})).await.json().await.expect("json");
    assert_eq!(st["generation"], 2);
    assert_eq!(st["quality"]["max_depth"], 2);
    assert_eq!(st["quality"]["spp"], 64, "fields not named keep their values");
    // A preset sets the path knobs; fields beside it win; seed and halts stay.
    let st: Value = patch(&base, &id, "quality", json!({"preset": "reference", "rr_depth": 2})).await.json().await.expect("json");
    let reference = pathstream::render::Preset::Reference.apply(pathstream::render::Quality::default());
    assert_eq!(st["quality"]["max_depth"], reference.max_depth);
    assert_eq!(st["quality"]["nee"], reference.nee);
    assert_eq!(st["quality"]["rr_depth"], 2);
    assert_eq!(st["quality"]["spp"], 64);
    assert_eq!(st["generation"], 3);
    let presets: Value = client().get(format!("{base}/api/presets")).send().await.expect("req").json().await.expect("json");
    let names: Vec<&str> = presets["presets"].as_array().expect("list").iter().filter_map(|p| p["name"].as_str()).collect();
    assert_eq!(names, ["preview", "interactive", "final", "reference"]);
    assert_eq!(presets["presets"][3]["quality"]["max_depth"], reference.max_depth);
    let r = client().put(format!("{base}/api/sessions/{id}/scene")).json(&json!("cornell-glass")).send().await.expect("req");
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["scene"], "cornell-glass");
    assert_eq!(st["generation"], 4);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn light_changes_the_image_where_expected() {
    let (running, base) = server(config()).await;
    let s = create(&base, json!({"scene": "cornell", "width": 16, "height": 16, "quality": {"spp": 256, "seed": 1}})).await;
    let id = s["id"].as_str().expect("id").to_owned();
    let base_img = mean(&pfm(&base, &id, 256).await);

    // Twice the intensity: the only light, so every pixel doubles.
    let st: Value = patch(&base, &id, "light", json!({"intensity": 24})).await.json().await.expect("json");
    assert_eq!(st["light"]["intensity"], 24.0);
    let bright = mean(&pfm(&base, &id, 256).await);
    for c in 0..3 {
        let ratio = bright[c] / base_img[c];
        assert!((ratio - 2.0).abs() < 0.1, "channel {c}: ratio {ratio}");
    }
    // A red light: no green or blue at all.
    let st: Value = patch(&base, &id, "light", json!({"color": [1, 0, 0]})).await.json().await.expect("json");
    assert_eq!(st["light"]["color"], json!([1.0, 0.0, 0.0]));
    let red = mean(&pfm(&base, &id, 256).await);
    assert!(red[0] > 0.1 && red[1] == 0.0 && red[2] == 0.0, "{red:?}");
    // Moving the light changes where light falls.
    let r = patch(&base, &id, "light", json!({"position": [20, 60, 100], "color": [1, 1, 1]})).await;
    assert_eq!(r.status(), 200);
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["light"]["position"], json!([20.0, 60.0, 100.0]));
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_gets_a_4xx_with_a_json_error_and_the_server_keeps_serving() {
    let mut cfg = config();
    cfg.max_body_bytes = 64 * 1024;
    cfg.max_pixels = 512 * 512;
    cfg.max_sessions = 2;
    let (running, base) = server(cfg).await;
    let keep = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"].as_str().expect("id").to_owned();
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
        let r = req.header("content-type", "application/json").body(body).send().await.expect("request");
        let status = r.status().as_u16();
        let text = r.text().await.expect("body");
        assert_eq!(status, code, "{method} {path}: {text}");
        let v: Value = serde_json::from_str(&text).unwrap_or_else(|_| panic!("{method} {path}: not JSON: {text}"));
        let msg = v["error"].as_str().unwrap_or_else(|| panic!("{method} {path}: no error field: {text}"));
        assert!(msg.contains(needle), "{method} {path}: '{needle}' not in '{msg}'");
    }
    // The session limit: a second session fits, a third does not.
    create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await;
    let r = c.post(format!("{base}/api/sessions")).json(&json!({"width": 8, "height": 8})).send().await.expect("req");
    assert_eq!(r.status(), 429);
    let v: Value = r.json().await.expect("json");
    assert!(v["error"].as_str().expect("msg").contains("limit of 2 sessions"), "{v}");
    // A WebSocket message that is not JSON: an error message, socket still usable.
    let mut ws = ws_connect(&base, id).await;
    ws.send(Message::Text("not json".into())).await.expect("send");
    ws.send(Message::Text(json!({"zoom": 1}).to_string().into())).await.expect("send");
    ws.send(Message::Text(json!({"camera": {"vfov_deg": 50}}).to_string().into())).await.expect("send");
    let mut errors = Vec::new();
    let until = Instant::now() + Duration::from_secs(5);
    while errors.len() < 2 && Instant::now() < until {
        if let Ok(Some(Ok(Message::Text(t)))) = tokio::time::timeout(Duration::from_secs(5), ws.next()).await {
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
    assert_eq!(st["camera"]["vfov_deg"], 50.0, "the valid message after the bad ones applied");
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
    for (auth, code) in [(None, 401), (Some("Bearer wrong"), 401), (Some("Bearer s3cret"), 200)] {
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
    let id = r.json::<Value>().await.expect("json")["id"].as_str().expect("id").to_owned();
    let ws_base = base.replace("http://", "ws://");
    assert!(tokio_tungstenite::connect_async(format!("{ws_base}/api/sessions/{id}/ws")).await.is_err());
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("{ws_base}/api/sessions/{id}/ws?token=s3cret"))
        .await
        .expect("with the token");
    let (frames, _) = read_frames(&mut ws, Instant::now() + Duration::from_secs(2)).await;
    assert!(frames > 0);
    // The browser client itself needs no token.
    assert_eq!(c.get(format!("{base}/")).send().await.expect("req").status(), 200);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn idle_sessions_expire_but_watched_ones_do_not() {
    let mut cfg = config();
    cfg.idle_timeout = Duration::from_millis(400);
    let (running, base) = server(cfg).await;
    let idle = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"].as_str().expect("id").to_owned();
    let watched = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await["id"].as_str().expect("id").to_owned();
    let mut ws = ws_connect(&base, &watched).await;
    read_frames(&mut ws, Instant::now() + Duration::from_millis(1500)).await;
    let gone = client().get(format!("{base}/api/sessions/{idle}")).send().await.expect("req");
    assert_eq!(gone.status(), 404);
    let kept = client().get(format!("{base}/api/sessions/{watched}")).send().await.expect("req");
    assert_eq!(kept.status(), 200);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn graceful_shutdown_closes_websockets_cleanly() {
    let (running, base) = server(config()).await;
    let id = create(&base, json!({"scene": "cornell", "width": 16, "height": 16})).await["id"].as_str().expect("id").to_owned();
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
    assert!(client().get(format!("{base}/api/health")).send().await.is_err(), "no longer listening");
}
