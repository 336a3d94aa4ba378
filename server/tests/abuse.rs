//! The server under a hostile client (issue: the server under abuse): every
//! error under `/api` is JSON, JSON bodies need their content type (no
//! cross-site simple requests), WebSocket messages are capped at the body
//! limit. A real server on 127.0.0.1:0 and real clients; every loop bounded.

mod http;

use futures_util::{SinkExt, StreamExt};
use http::{
    client, config, create, delete, get, get_json, metric, metrics, raw, server, status, ws_connect,
};
use serde_json::{json, Value};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::Message;

fn error_of(body: &str, what: &str) -> String {
    let v: Value =
        serde_json::from_str(body).unwrap_or_else(|_| panic!("{what}: not JSON: {body:?}"));
    v["error"]
        .as_str()
        .unwrap_or_else(|| panic!("{what}: no error field: {body}"))
        .to_owned()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_api_error_is_json_with_allow_on_405() {
    let (running, _) = server(config()).await;
    let addr = running.addr;
    let cases: [(&str, &[u8], u16, &str); 6] = [
        ("GET", b"/api/sessions/%ff%fe", 400, "utf-8"),
        ("GET", b"/api/sessions/%ff%fe/ws", 400, "utf-8"),
        ("DELETE", b"/api/health", 405, "not allowed"),
        ("PUT", b"/api/sessions", 405, "not allowed"),
        ("PATCH", b"/api/presets", 405, "not allowed"),
        ("GET", b"/api/no/such/route", 404, "no route"),
    ];
    for (method, target, code, needle) in cases {
        let what = format!("{method} {}", String::from_utf8_lossy(target));
        let (got, head, body) = raw(
            &addr,
            method,
            target,
            "content-type: application/json\r\n",
            b"",
        )
        .await;
        assert_eq!(got, code, "{what}: {head}\n{body}");
        assert!(
            head.contains("content-type: application/json"),
            "{what}: {head}"
        );
        let message = error_of(&body, &what).to_ascii_lowercase();
        assert!(
            message.contains(needle),
            "{what}: {needle:?} not in {message:?}"
        );
        if code == 405 {
            assert!(
                head.contains("\r\nallow: get"),
                "{what}: no Allow header: {head}"
            );
        }
    }
    // A raw non-ASCII byte after a broken escape in the token: no panic.
    let (running_t, _) = server(pathstream::service::ServeConfig {
        token: Some("t".into()),
        ..config()
    })
    .await;
    let (code, _, body) = raw(
        &running_t.addr,
        "GET",
        b"/api/sessions?token=%a\xc3\xa9",
        "",
        b"",
    )
    .await;
    assert_eq!(code, 401, "{body}");
    error_of(&body, "bad token");
    running_t.shutdown().await.expect("shutdown");
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bodies_a_web_page_could_send_cross_site_are_refused() {
    let (running, base) = server(config()).await;
    let addr = running.addr;
    let create_body = br#"{"scene": "furnace", "width": 8, "height": 8}"#;
    // A browser sends these without asking the server first (no preflight).
    for (headers, shown) in [
        ("content-type: text/plain\r\n", "text/plain"),
        (
            "content-type: application/x-www-form-urlencoded\r\n",
            "application/x-www-form-urlencoded",
        ),
        (
            "content-type: multipart/form-data; boundary=x\r\n",
            "multipart/form-data",
        ),
        ("", "none"),
    ] {
        let (code, _, body) = raw(&addr, "POST", b"/api/sessions", headers, create_body).await;
        assert_eq!(code, 415, "{shown}: {body}");
        let message = error_of(&body, shown);
        assert!(
            message.contains("application/json") && message.contains(shown),
            "{message}"
        );
    }
    let list: Value = get_json(format!("{base}/api/sessions")).await;
    assert_eq!(
        list["sessions"].as_array().map(Vec::len),
        Some(0),
        "no session was created"
    );

    // A change as text/plain: refused, the camera stays.
    let s = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await;
    let id = s["id"].as_str().expect("id");
    let target = format!("/api/sessions/{id}/camera");
    let (code, _, body) = raw(
        &addr,
        "PATCH",
        target.as_bytes(),
        "content-type: text/plain\r\n",
        br#"{"vfov_deg": 10}"#,
    )
    .await;
    assert_eq!(code, 415, "{body}");
    assert_eq!(
        status(&base, id).await["camera"],
        s["camera"],
        "the camera did not change"
    );
    let (code, _, body) = raw(
        &addr,
        "PATCH",
        target.as_bytes(),
        "content-type: application/json; charset=utf-8\r\n",
        br#"{"vfov_deg": 10}"#,
    )
    .await;
    assert_eq!(code, 200, "{body}");

    // Uploads: any type but the cross-site ones.
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    for headers in [
        "content-type: text/plain\r\n",
        "content-type: application/x-www-form-urlencoded\r\n",
        "",
    ] {
        let (code, _, body) = raw(&addr, "POST", b"/api/assets?name=t.obj", headers, obj).await;
        assert_eq!(code, 415, "{headers:?}: {body}");
        assert!(
            error_of(&body, headers).contains("application/octet-stream"),
            "{body}"
        );
    }
    let (code, _, body) = raw(
        &addr,
        "POST",
        b"/api/assets?name=t.obj",
        "content-type: application/octet-stream\r\n",
        obj,
    )
    .await;
    assert_eq!(code, 201, "{body}");
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn websocket_messages_are_capped_at_the_body_limit() {
    let limit = 64 << 10;
    let (running, base) = server(pathstream::service::ServeConfig {
        max_body_bytes: limit,
        ..config()
    })
    .await;
    let s = create(&base, json!({"scene": "furnace", "width": 8, "height": 8})).await;
    let id = s["id"].as_str().expect("id");
    let mut ws = ws_connect(&base, id).await;
    // Just over the limit: the server closes the socket (1009, too big).
    let big = format!(
        "{{\"camera\": {{\"vfov_deg\": 40}}, \"pad\": \"{}\"}}",
        "x".repeat(limit)
    );
    let _ = ws.send(Message::text(big)).await;
    let mut closed = false;
    for _ in 0..200 {
        match tokio::time::timeout(Duration::from_secs(10), ws.next()).await {
            Ok(Some(Ok(Message::Close(frame)))) => {
                if let Some(f) = frame {
                    assert_eq!(u16::from(f.code), 1009, "{f:?}");
                }
                closed = true;
                break;
            }
            Ok(Some(Ok(_))) => {}
            Ok(Some(Err(_)) | None) => {
                closed = true;
                break;
            }
            Err(_) => break,
        }
    }
    assert!(closed, "the socket was closed");
    // Under the limit on a new socket: taken as usual.
    let mut ws = ws_connect(&base, id).await;
    ws.send(Message::text(
        json!({"camera": {"vfov_deg": 33}}).to_string(),
    ))
    .await
    .expect("send");
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    while status(&base, id).await["camera"]["vfov_deg"] != json!(33.0) {
        assert!(std::time::Instant::now() < deadline, "the change arrived");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_delete_answers_every_waiter_and_closes_every_socket_at_once() {
    let (running, base) = server(config()).await;
    // Large enough that nothing reaches 1e6 samples per pixel meanwhile.
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 256, "height": 256}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let waiters: Vec<_> = (0..3)
        .map(|_| {
            let url =
                format!("{base}/api/sessions/{id}/frame.png?min_spp=1000000&timeout_ms=600000");
            tokio::spawn(async move {
                let r = get(url).await;
                (r.status().as_u16(), r.text().await.unwrap_or_default())
            })
        })
        .collect();
    let mut ws = ws_connect(&base, &id).await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    let deleted_at = std::time::Instant::now();
    let r = delete(format!("{base}/api/sessions/{id}")).await;
    assert_eq!(r.status().as_u16(), 204);
    for w in waiters {
        let (code, body) = tokio::time::timeout(Duration::from_secs(10), w)
            .await
            .expect("answered at once")
            .expect("task");
        assert_eq!(code, 410, "{body}");
        assert!(error_of(&body, "waiter").contains("was deleted"), "{body}");
    }
    let mut close = None;
    for _ in 0..1000 {
        match tokio::time::timeout(Duration::from_secs(10), ws.next())
            .await
            .expect("the socket is told in time")
        {
            Some(Ok(Message::Close(frame))) => {
                close = frame;
                break;
            }
            Some(Ok(_)) => {}
            other => panic!("the socket ended without a close frame: {other:?}"),
        }
    }
    let close = close.expect("a close frame with a code");
    assert_eq!(u16::from(close.code), 4404);
    assert!(close.reason.contains("deleted"), "{}", close.reason);
    // Seconds, not the waiters' ten minutes (a loaded machine keeps this).
    assert!(deleted_at.elapsed() < Duration::from_secs(10));
    let r = get(format!("{base}/api/sessions/{id}/frame.png")).await;
    assert_eq!(r.status().as_u16(), 404);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_and_excess_connections_are_dropped_and_health_keeps_answering() {
    use pathstream::service::ConnectionLimits;
    let limits = ConnectionLimits {
        max_connections: 100_000,
        max_per_address: 64,
        header_timeout: Duration::from_secs(2),
    };
    let (running, base) = server(pathstream::service::ServeConfig {
        connections: limits,
        ..config()
    })
    .await;
    let addr = running.addr;
    // A canary session renders through all of it (with no halt in reach:
    // the default 64 spp would be done before the attack began).
    let s = create(
        &base,
        json!({"scene": "furnace", "width": 16, "height": 16,
               "quality": {"spp": 1_000_000_000u64}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    // 150 clients sending a request head a byte at a time: 64 are taken,
    // the rest are closed at once; the taken ones are closed after 2 s.
    let canary_before = status(&base, &id).await["spp"].as_u64().expect("spp");
    let mut slow = Vec::new();
    for _ in 0..150 {
        slow.push(tokio::net::TcpStream::connect(addr).await.expect("connect"));
    }
    let started = std::time::Instant::now();
    let dribble: Vec<_> = slow
        .into_iter()
        .map(|mut tcp| {
            tokio::spawn(async move {
                // Until the server closes the connection, or 12 s at most.
                for b in b"GET /api/health HTTP/1.1\r\nhost: slow\r\nx-pad: aaaaaaaaaaaaaaaaaaaaaa"
                    .iter()
                    .cycle()
                    .take(24)
                {
                    if tcp.write_all(&[*b]).await.is_err() {
                        return started.elapsed();
                    }
                    let mut buf = [0u8; 64];
                    if let Ok(Ok(0) | Err(_)) =
                        tokio::time::timeout(Duration::from_millis(500), tcp.read(&mut buf)).await
                    {
                        return started.elapsed();
                    }
                }
                Duration::MAX
            })
        })
        .collect();
    // Health answers (a new connection once slots free up) within the head
    // deadline plus a loaded machine's margin.
    let mut healthy = None;
    for _ in 0..60 {
        let r = tokio::time::timeout(
            Duration::from_secs(2),
            client().get(format!("{base}/api/health")).send(),
        )
        .await;
        if let Ok(Ok(r)) = r {
            if r.status().as_u16() == 200 {
                healthy = Some(started.elapsed());
                break;
            }
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    }
    let healthy = healthy.expect("/api/health answered under the attack");
    assert!(healthy < Duration::from_secs(10), "health took {healthy:?}");
    let mut ended = Vec::new();
    for d in dribble {
        ended.push(d.await.expect("task"));
    }
    assert!(
        ended.iter().all(|&t| t != Duration::MAX),
        "every slow client was dropped: {ended:?}"
    );
    // What the server says it did (its counts, not wall-clock buckets): the
    // address's 64 slots were held until their heads timed out, the rest
    // (and health checks while the slots were full) refused at once. A
    // few slots may have gone to the test's own earlier requests.
    let text = metrics(&base).await;
    let count = |name: &str| metric(&text, name);
    let timed_out = count("pathstream_request_head_timeouts_total");
    let refused = count("pathstream_connections_refused_total{limit=\"per_address\"}");
    assert!(
        (64 - 5..=64).contains(&timed_out),
        "slow heads timed out: {timed_out}"
    );
    assert!(
        refused >= 150 - timed_out,
        "excess connections refused: {refused} ({timed_out} timed out)"
    );
    assert_eq!(
        count("pathstream_connections_refused_total{limit=\"max_connections\"}"),
        0
    );
    // The canary kept rendering: it went on from where the attack found it.
    let canary = status(&base, &id).await;
    let spp = canary["spp"].as_u64().expect("spp");
    assert_eq!(canary["state"], "rendering", "{canary}");
    assert!(
        spp > canary_before,
        "the canary rendered under the attack: {canary_before} spp before, {spp} after"
    );
    running.shutdown().await.expect("shutdown");
}
