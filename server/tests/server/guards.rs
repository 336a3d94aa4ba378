//! Bad input, the token and what either may not do to the server.

use super::*;

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
