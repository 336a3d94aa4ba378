//! How sessions and the server end: idle expiry, shutdown, a failed device.

use super::*;

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
    let gone = get(format!("{base}/api/sessions/{idle}")).await;
    assert_eq!(gone.status(), 404);
    let kept = get(format!("{base}/api/sessions/{watched}")).await;
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
    let json_at = |path: &'static str| {
        let url = format!("{base}{path}");
        async move { get_json::<Value>(url).await }
    };
    let devices = json_at("/api/devices").await;
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
        let v = json_at(path).await;
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
    assert_eq!(json_at("/api/devices").await["default"], "cpu");
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
