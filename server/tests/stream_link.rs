//! The stream over a slow or stalled link: changes apply while a frame is
//! stuck going out, an acknowledging client has one frame in flight (so a
//! change is not queued behind old frames), the stats measure the link, and
//! progressive resolution sends the first frames after a change smaller.

mod http;

use futures_util::SinkExt;
use http::{config, create, next_frame, server, status, ws_connect_with as connect};
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

type Ws = http::Ws;

/// The next frame's stats (the image before them is skipped).
async fn next_stats(ws: &mut Ws) -> Value {
    next_frame(ws).await.1
}

async fn send(ws: &mut Ws, v: Value) {
    ws.send(Message::Text(v.to_string().into()))
        .await
        .expect("send");
}

async fn generation(base: &str, id: &str) -> u64 {
    status(base, id).await["generation"]
        .as_u64()
        .expect("generation")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_change_applies_while_a_stalled_client_blocks_the_frame_going_out() {
    let (_server, base) = server(config()).await;
    // Noisy 640x480 PNGs (~1 MB each) fill the socket's buffers in moments.
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 640, "height": 480, "quality": {"spp": 2}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let mut ws = connect(&base, &id, "").await;
    let before = generation(&base, &id).await;
    // The client reads nothing: after a few seconds the server's send is
    // stuck on full buffers (the session halts at 2 spp, but each change
    // below publishes new frames).
    for spp in 3..6 {
        send(&mut ws, json!({"quality": {"spp": spp}})).await;
        tokio::time::sleep(Duration::from_millis(700)).await;
    }
    let stuck = generation(&base, &id).await;
    assert_eq!(stuck, before + 3, "changes before the buffers filled");
    // Now the socket is blocked; this change must still apply at once.
    send(&mut ws, json!({"camera": {"vfov_deg": 35}})).await;
    let until = Instant::now() + Duration::from_secs(5);
    while generation(&base, &id).await == stuck {
        assert!(
            Instant::now() < until,
            "a change waited behind a frame the client does not read"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_acknowledging_client_gets_the_newest_frame_after_a_change_not_a_backlog() {
    let (_server, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 320, "height": 240}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let mut ws = connect(&base, &id, "").await;
    // A few acknowledged frames: pacing by acknowledgement is on.
    let mut last = Value::Null;
    for _ in 0..5 {
        last = next_stats(&mut ws).await;
        send(&mut ws, json!({"ack": last["frame"]})).await;
    }
    assert!(
        last["link_mbps"].as_f64().is_some_and(|r| r > 0.0),
        "{last}"
    );
    assert!(last["delivery_ms"].as_f64().is_some(), "{last}");
    assert!(
        last["delivered_fps"].as_u64().is_some_and(|n| n >= 1),
        "{last}"
    );
    // Stall for a second without reading or acknowledging, while the
    // session renders on: at most the one unacknowledged frame is queued.
    tokio::time::sleep(Duration::from_secs(1)).await;
    send(&mut ws, json!({"camera": {"vfov_deg": 33}})).await;
    let after = generation(&base, &id).await;
    let mut old = 0;
    loop {
        let stats = next_stats(&mut ws).await;
        send(&mut ws, json!({"ack": stats["frame"]})).await;
        if stats["generation"].as_u64() >= Some(after) {
            break;
        }
        old += 1;
    }
    assert!(old <= 1, "{old} old frames came before the change showed");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn progressive_resolution_sends_a_quarter_then_half_then_the_whole_width() {
    let (_server, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 256, "height": 128}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let mut ws = connect(&base, &id, "?progressive=true").await;
    send(&mut ws, json!({"camera": {"vfov_deg": 30}})).await;
    let after = generation(&base, &id).await;
    let mut widths = Vec::new();
    while widths.len() < 4 {
        let stats = next_stats(&mut ws).await;
        if stats["generation"].as_u64() >= Some(after) {
            assert_eq!(stats["progressive"], true);
            widths.push(stats["frame_width"].as_u64().expect("width"));
        }
    }
    assert_eq!(widths, [64, 128, 256, 256]);
    // A socket that did not ask gets whole frames from the first.
    let mut plain = connect(&base, &id, "").await;
    send(&mut plain, json!({"camera": {"vfov_deg": 31}})).await;
    let after = generation(&base, &id).await;
    loop {
        let stats = next_stats(&mut plain).await;
        if stats["generation"].as_u64() >= Some(after) {
            assert_eq!(stats["frame_width"], 256, "{stats}");
            break;
        }
    }
    // A bad acknowledgement is refused by name; the socket stays open.
    send(&mut plain, json!({"ack": "soon"})).await;
    let e = http::next_error(&mut plain).await;
    assert!(e.starts_with("ack:"), "{e}");
}
