//! The stream over a slow or stalled link: changes apply while a frame is
//! stuck going out, an acknowledging client has one frame in flight (so a
//! change is not queued behind old frames), the stats measure the link, and
//! progressive resolution sends the first frames after a change smaller.

mod http;

use futures_util::SinkExt;
use http::{
    config, create, metric, metrics, next_frame, server, status, ws_connect_with as connect,
};
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::MaybeTlsStream;

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

/// A WebSocket of PNG frames on a socket that takes a few KB before the
/// sender must wait (a receive buffer set before connecting fixes the window
/// it offers).
async fn connect_small_window(base: &str, id: &str) -> Ws {
    let addr: std::net::SocketAddr = base
        .trim_start_matches("http://")
        .parse()
        .expect("server address");
    let socket = tokio::net::TcpSocket::new_v4().expect("socket");
    socket.set_recv_buffer_size(4096).expect("receive buffer");
    let stream = socket.connect(addr).await.expect("connects");
    // PNG: the default format follows the link, and a fast one gets small
    // JPEGs that the kernel's buffers swallow by the dozen.
    let url = format!("ws://{addr}/api/sessions/{id}/ws?format=png");
    tokio_tungstenite::client_async(url, MaybeTlsStream::Plain(stream))
        .await
        .expect("ws connects")
        .0
}

/// Frames the server has finished sending, from `/metrics`.
async fn frames_sent(base: &str) -> u64 {
    metric(&metrics(base).await, "pathstream_frames_sent_total")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_change_applies_while_a_stalled_client_blocks_the_frame_going_out() {
    let (_server, base) = server(config()).await;
    // Noisy 640x480 PNGs (up to ~0.8 MB each) fill the socket's buffers.
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 640, "height": 480, "quality": {"spp": 2}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let mut ws = connect_small_window(&base, &id).await;
    let before = generation(&base, &id).await;
    // The client reads nothing. Each change below publishes new frames
    // (the session halts at 2 spp, then renders one more sample); once the
    // socket's buffers are full, no frame finishes going out however many
    // are published: the send is stuck. Checked, not assumed: previews and
    // partial frames compress well, so how many changes it takes varies.
    let mut changes = 0;
    let mut sent = frames_sent(&base).await;
    let stuck = loop {
        changes += 1;
        assert!(
            changes <= 30,
            "the server's send never got stuck ({sent} frames went out)"
        );
        send(&mut ws, json!({"quality": {"spp": 2 + changes}})).await;
        tokio::time::sleep(Duration::from_millis(600)).await;
        let now = frames_sent(&base).await;
        if now == sent && changes > 1 {
            break generation(&base, &id).await;
        }
        sent = now;
    };
    assert_eq!(stuck, before + changes, "every change applied");
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
    // The precondition, checked: no frame finished going out meanwhile (the
    // new generation's frames would have, had the send not been stuck).
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert_eq!(
        frames_sent(&base).await,
        sent,
        "the server's send was not stuck: this test proved nothing"
    );
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
