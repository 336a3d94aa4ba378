//! The WebSocket frame stream. The server sends binary frames, PNG at the
//! film's size unless the socket asks otherwise (`api/stream.rs`: JPEG,
//! a smaller width), each followed by a text message with its stats
//! (`format`, `frame_bytes`, `frame_width`, `frame_height` included); the
//! client sends JSON changes: `{"camera": {...}}`, `{"light": {...}}`,
//! `{"quality": {...}}`, `{"scene": ...}`. A bad message gets
//! `{"type": "error", "error": "..."}` and the socket stays open.
//!
//! At most one frame is in flight per client: the stream always sends the
//! newest frame and skips the ones published meanwhile, so a slow or stalled
//! client never slows rendering or anyone else. A client that acknowledges
//! frames (`{"ack": FRAME}`) gets the next only once it has the last, and
//! its stats say how fast frames arrive (`link.rs`). Changes apply as they
//! arrive, even while a frame is going out. With `progressive` the first
//! frame after a change goes at a quarter of the width, the next at half.

use super::link::{progressive_width, Link};
use super::stream::{encoding, StreamRequest, StreamSettings};
use crate::service::change::Change;
use crate::service::frame::Encoded;
use crate::service::session::{Frame, Session, Status};
use crate::service::ApiError;
use crate::service::AppState;
use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::response::Response;
use futures_util::{SinkExt, StreamExt};
use pathstream_wire::{ErrorBody, Stats, StreamMessage};
use serde_json::{json, Value};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;

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

/// The stats of `frame`, just sent as `image`: the session's status with
/// the frame's own figures where it is of the current generation (not
/// those of whatever came after it), and how it went out.
fn stats(
    mut status: Status,
    frame: &Frame,
    settings: StreamSettings,
    image: &Encoded,
    link: &Link,
    now: Instant,
) -> StreamMessage {
    if frame.generation == status.generation {
        status.spp = frame.spp;
        status.spp_spread = frame.spread;
        status.error_estimate = frame.error_estimate;
        status.samples_per_sec = frame.samples_per_sec;
    }
    // The frame's own restart, which may be older than the session's.
    status.generation = frame.generation;
    StreamMessage::Stats(Box::new(Stats {
        status,
        frame: frame.seq,
        format: settings.format.name().to_owned(),
        frame_bytes: image.bytes.len() as u64,
        frame_width: image.width,
        frame_height: image.height,
        progressive: settings.progressive,
        preview: frame.preview,
        delivered_fps: link.fps(now) as u64,
        link_mbps: link.mbps(),
        delivery_ms: link.last_delivery().map(|d| d.as_secs_f64() * 1e3),
    }))
}

/// A text message. Written through a `Value`, as these messages always
/// were: its keys in sorted order and f32 fields (`quality.clamp`) widened
/// to f64, so the bytes on the socket are unchanged.
fn text(message: &StreamMessage) -> Message {
    let json = serde_json::to_value(message).unwrap_or_else(|_| json!({}));
    Message::Text(Utf8Bytes::from(json.to_string()))
}

fn error_message(e: &str) -> Message {
    text(&StreamMessage::Error(ErrorBody::new(e)))
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

/// What the reading half of a socket tells the writing half.
enum Inbound {
    Settings(StreamSettings),
    Ack(u64),
    Error(String),
}

async fn serve(
    socket: WebSocket,
    state: Arc<AppState>,
    session: Arc<Session>,
    settings: StreamSettings,
) {
    session.clients.fetch_add(1, Ordering::Relaxed);
    let (sink, stream) = socket.split();
    // Changes apply as they arrive, even while a large frame is going out.
    let (to_writer, inbound) = mpsc::channel(16);
    let reader = tokio::spawn(read(stream, state.clone(), session.clone(), to_writer));
    write(sink, &state, &session, settings, inbound).await;
    reader.abort();
    session.clients.fetch_sub(1, Ordering::Relaxed);
    session.touch();
}

/// The client's messages: acknowledgements, stream settings and changes
/// (applied at once); until the socket closes.
async fn read(
    mut stream: futures_util::stream::SplitStream<WebSocket>,
    state: Arc<AppState>,
    session: Arc<Session>,
    to_writer: mpsc::Sender<Inbound>,
) {
    while let Some(Ok(message)) = stream.next().await {
        let text = match message {
            Message::Text(t) => t,
            Message::Binary(_) => {
                let e = "message: expected JSON text, got binary".to_owned();
                if to_writer.send(Inbound::Error(e)).await.is_err() {
                    return;
                }
                continue;
            }
            Message::Close(_) => return,
            _ => continue,
        };
        session.touch();
        tracing::trace!(session = %session.id, bytes = text.len(), "message in");
        let result = take_ack(text.as_str()).and_then(|(ack, rest)| {
            if let Some(seq) = ack {
                // Never blocks the reader: a full channel drops the ack,
                // which the writer's timeout then covers.
                let _ = to_writer.try_send(Inbound::Ack(seq));
            }
            let Some(rest) = rest else { return Ok(None) };
            let (stream, rest) = take_stream(&rest)?;
            match rest {
                Some(rest) => Change::parse_message(&rest, &state.scene_rules())
                    .and_then(|changes| {
                        changes
                            .into_iter()
                            .try_for_each(|c| session.apply(c).map(|_| ()))
                    })
                    .map(|()| stream),
                None => Ok(stream),
            }
        });
        let news = match result {
            Ok(Some(settings)) => Inbound::Settings(settings),
            Ok(None) => continue,
            Err(e) => Inbound::Error(e.to_string()),
        };
        if to_writer.send(news).await.is_err() {
            return;
        }
    }
}

/// Sends the newest frame whenever there is one and the link is ready for
/// it (see `link.rs`), each followed by its stats; errors from the reader;
/// the close when the session is deleted or the server shuts down.
async fn write(
    mut sink: futures_util::stream::SplitSink<WebSocket, Message>,
    state: &AppState,
    session: &Session,
    mut settings: StreamSettings,
    mut inbound: mpsc::Receiver<Inbound>,
) {
    let mut frames = session.subscribe();
    frames.mark_changed();
    // Frames encoded while the one before is in flight, so that the next
    // goes out as soon as the link is ready (one at a time).
    let mut ahead = session.subscribe();
    let encoding_ahead = Arc::new(AtomicBool::new(false));
    let mut shutdown = state.shutdown_signal();
    let mut last_seq = 0u64;
    let mut link = Link::default();
    // Frames sent of the current generation (progressive resolution).
    let (mut generation, mut nth) = (u64::MAX, 0u64);
    loop {
        let ack_wait = link.ack_deadline();
        tokio::select! {
            changed = ahead.changed(), if !link.ready() && !encoding_ahead.load(Ordering::Acquire) => {
                if changed.is_err() {
                    break;
                }
                let frame = ahead.borrow_and_update().clone();
                if !frame.pixels.is_empty() {
                    let n = if frame.generation == generation { nth } else { 0 };
                    let wanted = wanted(settings, &frame, n);
                    let busy = encoding_ahead.clone();
                    busy.store(true, Ordering::Release);
                    tokio::task::spawn_blocking(move || {
                        let _ = frame.encoded(encoding(wanted));
                        busy.store(false, Ordering::Release);
                    });
                }
            }
            changed = frames.changed(), if link.ready() => {
                if changed.is_err() {
                    break;
                }
                let frame = frames.borrow_and_update().clone();
                // Restarts publish an empty frame; wait for the first image.
                if frame.pixels.is_empty() && !frame.halted {
                    continue;
                }
                if last_seq != 0 && frame.seq > last_seq + 1 {
                    state.metrics.frames_dropped.fetch_add(frame.seq - last_seq - 1, Ordering::Relaxed);
                }
                last_seq = frame.seq;
                if frame.generation != generation {
                    (generation, nth) = (frame.generation, 0);
                }
                let wanted = wanted(settings, &frame, nth);
                nth += 1;
                let f = frame.clone();
                let encode = Instant::now();
                let image = match tokio::task::spawn_blocking(move || f.encoded(encoding(wanted))).await {
                    Ok(Ok(image)) => image,
                    _ => break,
                };
                let start = Instant::now();
                tracing::trace!(
                    frame = frame.seq,
                    generation = frame.generation,
                    width = image.width,
                    encode_ms = (start - encode).as_secs_f64() * 1e3,
                    "frame out"
                );
                link.sending(frame.seq, image.bytes.len(), start);
                let stats = text(&stats(session.status(), &frame, settings, &image, &link, start));
                let send = async {
                    sink.send(Message::Binary(image.bytes.to_vec().into())).await?;
                    sink.send(stats).await
                };
                match tokio::time::timeout(SEND_TIMEOUT, send).await {
                    Ok(Ok(())) => {
                        link.accepted(Instant::now());
                        state.metrics.frames_sent.fetch_add(1, Ordering::Relaxed);
                    }
                    _ => break,
                }
            }
            () = sleep_until(ack_wait), if ack_wait.is_some() => link.give_up(),
            news = inbound.recv() => match news {
                Some(Inbound::Ack(seq)) => link.acked(seq, Instant::now()),
                Some(Inbound::Settings(new)) => {
                    // The newest frame again, as now asked for (a halted
                    // session publishes no more).
                    settings = new;
                    frames.mark_changed();
                }
                Some(Inbound::Error(e)) => {
                    if sink.send(error_message(&e)).await.is_err() {
                        break;
                    }
                }
                None => break, // the client closed the socket
            },
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
}

/// What `frame` goes out as, the `nth` of its generation on this socket:
/// with progressive resolution, narrower for the first two.
fn wanted(settings: StreamSettings, frame: &Frame, nth: u64) -> StreamSettings {
    let mut wanted = StreamSettings {
        progressive: false,
        ..settings
    };
    if settings.progressive {
        let full = settings.width.unwrap_or(frame.width).min(frame.width);
        wanted.width = Some(progressive_width(full, nth, frame.halted));
    }
    wanted
}

/// Sleeps until `at` (forever when None; the branch is off then).
async fn sleep_until(at: Option<Instant>) {
    match at {
        Some(at) => tokio::time::sleep_until(at.into()).await,
        None => std::future::pending().await,
    }
}

/// Takes an acknowledgement (`"ack": SEQ`) out of a client message; the
/// rest of the message, if any.
fn take_ack(text: &str) -> Result<(Option<u64>, Option<String>), ApiError> {
    let Ok(Value::Object(mut m)) = serde_json::from_str::<Value>(text) else {
        return Ok((None, Some(text.to_owned())));
    };
    let Some(ack) = m.remove("ack") else {
        return Ok((None, Some(text.to_owned())));
    };
    let seq = ack
        .as_u64()
        .ok_or_else(|| ApiError::BadRequest(format!("ack: must be a frame number (got {ack})")))?;
    let rest = (!m.is_empty()).then(|| Value::Object(m).to_string());
    Ok((Some(seq), rest))
}
