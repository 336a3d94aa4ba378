//! The WebSocket frame stream. The server sends binary frames, PNG unless
//! the socket asks for JPEG (`?format=jpeg&quality=85` on the URL, or the
//! message `{"stream": {"format": "jpeg", "quality": 85}}`), each followed by
//! a text message with its stats (`format`, `frame_bytes` included); the
//! client sends JSON changes: `{"camera": {...}}`, `{"light": {...}}`,
//! `{"quality": {...}}`, `{"scene": ...}`. A bad message gets
//! `{"type": "error", "error": "..."}` and the socket stays open.
//!
//! At most one frame is in flight per client: the stream always sends the
//! newest frame and skips the ones published meanwhile, so a slow or stalled
//! client never slows rendering or anyone else.

use super::change::Change;
use super::error::ApiError;
use super::frame::StreamFormat;
use super::session::{Frame, Session, Status};
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

/// `?format=png|jpeg&quality=1..100` on the stream's URL.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamQuery {
    format: Option<String>,
    quality: Option<u8>,
    /// The bearer token may come as a query parameter (browsers cannot set
    /// headers on a WebSocket); the auth layer reads it.
    #[allow(dead_code)]
    token: Option<String>,
}

impl StreamQuery {
    fn format(&self) -> Result<StreamFormat, ApiError> {
        match (self.format.as_deref(), self.quality) {
            (None | Some("png"), None) => Ok(StreamFormat::Png),
            (None | Some("png"), Some(_)) => {
                Err(ApiError::BadRequest("quality: only for format=jpeg".into()))
            }
            (Some("jpeg"), q) => StreamFormat::Jpeg {
                quality: q.unwrap_or(85),
            }
            .validate(),
            (Some(other), _) => Err(ApiError::BadRequest(format!(
                "format: must be png or jpeg (got '{other}')"
            ))),
        }
    }
}

pub async fn upgrade(
    State(state): State<Arc<AppState>>,
    Path(id): Path<String>,
    Query(query): Query<StreamQuery>,
    ws: WebSocketUpgrade,
) -> Result<Response, ApiError> {
    let session = state.session(&id)?;
    let format = query.format()?;
    // Messages from the client are changes: no larger than an HTTP body.
    let limit = state.config.max_body_bytes;
    Ok(ws
        .max_message_size(limit)
        .max_frame_size(limit)
        .on_upgrade(move |socket| serve(socket, state, session, format)))
}

fn stats(status: &Status, frame: &Frame, format: StreamFormat, bytes: usize) -> Value {
    let mut v = serde_json::to_value(status).unwrap_or_else(|_| json!({}));
    if let Value::Object(m) = &mut v {
        m.insert("type".into(), json!("stats"));
        m.insert("format".into(), json!(format.name()));
        m.insert("frame_bytes".into(), json!(bytes));
        // The stats of the frame just sent, not of whatever came after it.
        if frame.generation == status.generation {
            m.insert("spp".into(), json!(frame.spp));
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
fn take_stream(text: &str) -> Result<(Option<StreamFormat>, Option<String>), ApiError> {
    let Ok(Value::Object(mut m)) = serde_json::from_str::<Value>(text) else {
        return Ok((None, Some(text.to_owned())));
    };
    let Some(stream) = m.remove("stream") else {
        return Ok((None, Some(text.to_owned())));
    };
    let format = serde_json::from_value::<StreamFormat>(stream)
        .map_err(|e| ApiError::BadRequest(format!("stream: {e}")))?
        .validate()?;
    let rest = (!m.is_empty()).then(|| Value::Object(m).to_string());
    Ok((Some(format), rest))
}

async fn serve(
    socket: WebSocket,
    state: Arc<AppState>,
    session: Arc<Session>,
    mut format: StreamFormat,
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
                let image = match tokio::task::spawn_blocking(move || f.encoded(format)).await {
                    Ok(Ok(image)) => image,
                    _ => break,
                };
                let text = stats(&session.status(), &frame, format, image.len()).to_string();
                let send = async {
                    sink.send(Message::Binary(image.to_vec().into())).await?;
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
                    if let Some(f) = stream {
                        format = f;
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
