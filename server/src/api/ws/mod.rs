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
//!
//! Each message is parsed once ([`ClientMessage`]). The socket's two halves
//! are written against `Stream`/`Sink` of messages (`read.rs`, `write.rs`),
//! so that their logic is tested over channels (`tests.rs`) as well as over
//! real sockets (`server/tests/stream*.rs`).

mod message;
mod read;
#[cfg(test)]
mod tests;
mod write;

use message::ClientMessage;

use super::stream::{StreamRequest, StreamSettings};
use crate::service::session::Session;
use crate::service::ApiError;
use crate::service::AppState;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::response::Response;
use futures_util::{Sink, Stream, StreamExt};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;
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

/// What the reading half of a socket tells the writing half.
#[derive(Debug)]
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
    let (sink, stream) = socket.split();
    serve_halves(sink, stream, state, session, settings).await;
}

/// Serves one client over its two halves until either ends: the reader
/// applies the client's messages as they arrive (even while a large frame
/// is going out) and tells the writer what concerns it.
async fn serve_halves<K, S, E>(
    sink: K,
    stream: S,
    state: Arc<AppState>,
    session: Arc<Session>,
    settings: StreamSettings,
) where
    K: Sink<Message> + Unpin,
    S: Stream<Item = Result<Message, E>> + Unpin + Send + 'static,
    E: Send + 'static,
{
    session.clients.fetch_add(1, Ordering::Relaxed);
    let (to_writer, inbound) = mpsc::channel(16);
    let reader = tokio::spawn(read::read(
        stream,
        state.clone(),
        session.clone(),
        to_writer,
    ));
    write::write(sink, &state, &session, settings, inbound).await;
    reader.abort();
    session.clients.fetch_sub(1, Ordering::Relaxed);
    session.touch();
}
