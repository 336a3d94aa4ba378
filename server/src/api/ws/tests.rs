//! The stream's logic over channels instead of a socket: what the client
//! sends goes in through a channel-backed `Stream`, what the server sends
//! comes out of a channel-backed `Sink`.

use super::serve_halves;
use crate::api::stream::StreamSettings;
use crate::service::{AppState, NewSession, ServeConfig};
use axum::extract::ws::{Message, Utf8Bytes};
use pathstream_wire::StreamMessage;
use serde_json::json;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;

/// The client's end of a stream served over channels.
struct Client {
    to_server: mpsc::UnboundedSender<Message>,
    from_server: mpsc::UnboundedReceiver<Message>,
}

impl Client {
    fn send(&self, text: &str) {
        self.to_server
            .send(Message::Text(Utf8Bytes::from(text.to_owned())))
            .expect("the reader is there");
    }

    async fn next(&mut self) -> Message {
        tokio::time::timeout(Duration::from_secs(30), self.from_server.recv())
            .await
            .expect("a message within 30 s")
            .expect("the writer is there")
    }

    /// The next frame's bytes and its stats.
    async fn frame(&mut self) -> (Vec<u8>, serde_json::Value) {
        loop {
            let Message::Binary(bytes) = self.next().await else {
                continue; // an error message from an earlier step
            };
            let Message::Text(stats) = self.next().await else {
                panic!("a frame is followed by its stats");
            };
            let stats: serde_json::Value = serde_json::from_str(stats.as_str()).expect("JSON");
            return (bytes.to_vec(), stats);
        }
    }

    /// The next error message's text.
    async fn error(&mut self) -> String {
        loop {
            if let Message::Text(t) = self.next().await {
                if let Ok(StreamMessage::Error(e)) = serde_json::from_str(t.as_str()) {
                    return e.error;
                }
            }
        }
    }
}

/// A service with rayon only, one small session of `spp` samples, and a
/// client streaming it over channels.
async fn streaming(spp: u64) -> (Arc<AppState>, Arc<crate::service::session::Session>, Client) {
    let state = AppState::with_device(ServeConfig::default(), None);
    let session = state
        .create_session(NewSession {
            scene: json!("cornell"),
            width: 16,
            height: 12,
            quality: Some(json!({"spp": spp})),
            backend: Some("cpu".into()),
        })
        .expect("session");
    let (to_server, inbox) = mpsc::unbounded_channel::<Message>();
    let (outbox, from_server) = mpsc::unbounded_channel::<Message>();
    let stream = Box::pin(futures_util::stream::unfold(inbox, |mut rx| async move {
        rx.recv().await.map(|m| (Ok::<_, ()>(m), rx))
    }));
    let sink = Box::pin(futures_util::sink::unfold(
        outbox,
        |tx, m: Message| async move { tx.send(m).map(|()| tx).map_err(|_| ()) },
    ));
    tokio::spawn(serve_halves(
        sink,
        stream,
        state.clone(),
        session.clone(),
        StreamSettings::default(),
    ));
    let client = Client {
        to_server,
        from_server,
    };
    (state, session, client)
}

#[tokio::test]
async fn frames_go_out_with_their_stats_and_messages_change_the_stream() {
    let (state, session, mut client) = streaming(4).await;
    // Until the frame of the last sample (the status may say halted while
    // an earlier frame is still going out).
    let (mut png, mut stats) = client.frame().await;
    while stats["spp"] != 4 {
        (png, stats) = client.frame().await;
    }
    assert!(png.starts_with(b"\x89PNG"), "PNG by default");
    assert_eq!(stats["type"], "stats");
    assert_eq!(stats["format"], "png");
    assert_eq!(stats["id"], json!(session.id));

    // New stream settings: the newest frame again, as now asked for (the
    // session has halted: it publishes no more).
    client.send(r#"{"stream": {"format": "jpeg", "quality": 70}}"#);
    let (jpeg, stats) = client.frame().await;
    assert!(jpeg.starts_with(&[0xFF, 0xD8]), "then JPEG");
    assert_eq!(stats["format"], "jpeg");

    // A refused message: an error, nothing applied, the socket open.
    let generation = session.status().generation;
    client.send(r#"{"ack": 1, "quality": {"spp": 8}, "camera": {"zoom": 2}}"#);
    let e = client.error().await;
    assert!(e.starts_with("camera.zoom: unknown field `zoom`"), "{e}");
    assert_eq!(session.status().generation, generation, "nothing applied");

    // A change applies: a new generation, whose frames follow.
    client.send(r#"{"ack": 2, "quality": {"spp": 8}}"#);
    let mut after = client.frame().await.1;
    while after["generation"] == json!(generation) {
        after = client.frame().await.1;
    }
    assert_eq!(after["generation"], json!(generation + 1));
    assert_eq!(after["quality"]["spp"], 8);

    client
        .to_server
        .send(Message::Binary(vec![1, 2, 3].into()))
        .expect("send");
    assert_eq!(
        client.error().await,
        "message: expected JSON text, got binary"
    );

    // Deleting the session closes the stream with its code.
    state.remove_session(&session.id).expect("removed");
    loop {
        if let Message::Close(Some(close)) = client.next().await {
            assert_eq!(close.code, super::SESSION_DELETED);
            break;
        }
    }
    state.stop();
}

#[tokio::test]
async fn a_client_that_closes_ends_the_stream_and_its_count() {
    let (state, session, mut client) = streaming(2).await;
    client.frame().await;
    assert_eq!(
        session.clients.load(std::sync::atomic::Ordering::Relaxed),
        1
    );
    drop(client.to_server);
    // The reader ends; the writer ends when the client's side is gone.
    drop(client.from_server);
    for _ in 0..300 {
        if session.clients.load(std::sync::atomic::Ordering::Relaxed) == 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    assert_eq!(
        session.clients.load(std::sync::atomic::Ordering::Relaxed),
        0
    );
    state.stop();
}
