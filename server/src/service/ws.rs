//! The WebSocket frame stream. The server sends binary frames, PNG at the
//! film's size unless the socket asks otherwise (`service/stream.rs`: JPEG,
//! a smaller width), each followed by a text message with its stats
//! (`format`, `frame_bytes`, `frame_width`, `frame_height` included); the
//! client sends JSON changes: `{"camera": {...}}`, `{"light": {...}}`,
//! `{"quality": {...}}`, `{"scene": ...}`. A bad message gets
//! `{"type": "error", "error": "..."}` and the socket stays open.
//!
//! At most one frame is in flight per client: the stream always sends the
//! newest frame and skips the ones published meanwhile, so a slow or stalled
//! client never slows rendering or anyone else.

use super::change::Change;
use super::error::ApiError;
use super::frame::Encoded;
use super::session::{Frame, Session, Status};
use super::stream::{StreamRequest, StreamSettings};
use super::AppState;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::response::Response;
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

/// A client that takes longer than this to accept one frame is dropped.
const SEND_TIMEOUT: Duration = Duration::from_secs(30);
/// Close code of a socket whose session was deleted (application range).
pub const SESSION_DELETED: u16 = 4404;

pub async fn upgrade(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    Query(query): Query<StreamRequest>,
    ws: WebSocketUpgrade,
) -> Result<Response, ApiError> {
    let session = state.session(&id)?;
    let settings = query.settings()?;
    // Messages from the client are changes: no larger than an HTTP body.
    let limit = state.config.max_body_bytes;
    Ok(ws
        .max_message_size(limit)
        .max_frame_size(limit)
        .on_upgrade(move |socket| serve(socket, state, session, settings)))
}

fn stats(status: &Status, frame: &Frame, settings: StreamSettings, image: &Encoded) -> Value {
    let mut v = serde_json::to_value(status).unwrap_or_else(|_| json!({}));
    if let Value::Object(m) = &mut v {
        m.insert("type".into(), json!("stats"));
        m.insert("format".into(), json!(settings.format.name()));
        m.insert("frame_bytes".into(), json!(image.bytes.len()));
        m.insert("frame_width".into(), json!(image.width));
        m.insert("frame_height".into(), json!(image.height));
        // The stats of the frame just sent, not of whatever came after it.
        if frame.generation == status.generation {
            m.insert("spp".into(), json!(frame.spp));
            m.insert("spp_spread".into(), json!(frame.spread));
            m.insert("error_estimate".into(), json!(frame.error_estimate));
            m.insert("samples_per_sec".into(), json!(frame.samples_per_sec));
        }
        m.insert("frame".into(), json!(frame.seq));
    }
    v
}

fn error_message(e: &str) -> Message {
    Message::Text(Utf8Bytes::from(
        json!({"type": "error", "error": e}).to_string(),
    ))
}

/// Takes a `stream` setting out of a client message, if it has one; the
/// rest of the message (if any) is changes.
fn take_stream(text: &str) -> Result<(Option<StreamSettings>, Option<String>), ApiError> {
    let Ok(Value::Object(mut m)) = serde_json::from_str::<Value>(text) else {
        return Ok((None, Some(text.to_owned())));
    };
    let Some(stream) = m.remove("stream") else {
        return Ok((None, Some(text.to_owned())));
    };
    let settings = serde_json::from_value::<StreamRequest>(stream)
        .map_err(|e| ApiError::BadRequest(format!("stream: {e}")))?
        .settings()?;
    let rest = (!m.is_empty()).then(|| Value::Object(m).to_string());
    Ok((Some(settings), rest))
}

async fn serve(
    socket: WebSocket,
    state: Arc<AppState>,
    session: Arc<Session>,
    mut settings: StreamSettings,
) {
    session.clients.fetch_add(1, Ordering::Relaxed);
    let (mut sink, mut stream) = socket.split();
    let mut frames = session.subscribe();
    frames.mark_changed();
    let mut shutdown = state.shutdown_signal();
    let mut last_seq = 0u64;
    loop {
        tokio::select! {
            changed = frames.changed() => {
                if changed.is_err() {
                    break;
                }
                let frame = frames.borrow_and_update().clone();
                // Restarts publish an empty frame; wait for the first pass.
                if frame.spp == 0 && !frame.halted {
                    continue;
                }
                if last_seq != 0 && frame.seq > last_seq + 1 {
                    state.metrics.frames_dropped.fetch_add(frame.seq - last_seq - 1, Ordering::Relaxed);
                }
                last_seq = frame.seq;
                let f = frame.clone();
                let image = match tokio::task::spawn_blocking(move || f.encoded(settings)).await {
                    Ok(Ok(image)) => image,
                    _ => break,
                };
                let text = stats(&session.status(), &frame, settings, &image).to_string();
                let send = async {
                    sink.send(Message::Binary(image.bytes.to_vec().into())).await?;
                    sink.send(Message::Text(Utf8Bytes::from(text))).await
                };
                match tokio::time::timeout(SEND_TIMEOUT, send).await {
                    Ok(Ok(())) => {
                        state.metrics.frames_sent.fetch_add(1, Ordering::Relaxed);
                    }
                    _ => break,
                }
            }
            message = stream.next() => {
                let text = match message {
                    Some(Ok(Message::Text(t))) => t,
                    Some(Ok(Message::Binary(_))) => {
                        if sink.send(error_message("message: expected JSON text, got binary")).await.is_err() {
                            break;
                        }
                        continue;
                    }
                    Some(Ok(Message::Close(_))) | None | Some(Err(_)) => break,
                    Some(Ok(_)) => continue,
                };
                session.touch();
                let result = take_stream(text.as_str()).and_then(|(stream, rest)| {
                    if let Some(new) = stream {
                        settings = new;
                    }
                    match rest {
                        Some(rest) => Change::parse_message(&rest, &state.scene_rules())
                            .and_then(|changes| changes.into_iter().try_for_each(|c| session.apply(c).map(|_| ()))),
                        None => Ok(()),
                    }
                });
                if let Err(e) = result {
                    if sink.send(error_message(&e.to_string())).await.is_err() {
                        break;
                    }
                }
            }
            () = session.deleted() => {
                let reason = format!("session '{}' was deleted", session.id);
                let _ = sink.send(Message::Close(Some(axum::extract::ws::CloseFrame {
                    code: SESSION_DELETED,
                    reason: Utf8Bytes::from(reason),
                }))).await;
                break;
            }
            _ = shutdown.changed() => {
                let _ = sink.send(Message::Close(Some(axum::extract::ws::CloseFrame {
                    code: axum::extract::ws::close_code::AWAY,
                    reason: Utf8Bytes::from_static("server shutting down"),
                }))).await;
                break;
            }
        }
    }
    session.clients.fetch_sub(1, Ordering::Relaxed);
    session.touch();
}
