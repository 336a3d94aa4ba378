//! The writing half of a stream socket: the newest frame whenever there is
//! one and the link is ready for it (`api/link.rs`), each followed by its
//! stats; errors from the reader; the close when the session is deleted or
//! the server shuts down.

use super::super::link::{progressive_width, Link};
use super::super::stream::{encoding, StreamSettings};
use super::{Inbound, SEND_TIMEOUT, SESSION_DELETED};
use crate::service::frame::Encoded;
use crate::service::session::{Frame, Session, Status};
use crate::service::AppState;
use axum::extract::ws::{CloseFrame, Message, Utf8Bytes};
use futures_util::{Sink, SinkExt};
use pathstream_wire::{ErrorBody, Stats, StreamMessage};
use serde_json::json;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::mpsc;

/// Sends the newest frame whenever there is one and the link is ready for
/// it (see `link.rs`), each followed by its stats; errors from the reader;
/// the close when the session is deleted or the server shuts down.
pub(super) async fn write<K: Sink<Message> + Unpin>(
    mut sink: K,
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
    // After a denoised frame, the next waits its turn (`denoise::next_turn`),
    // unless it is the last of its render.
    let mut paced: Option<Instant> = None;
    loop {
        let ack_wait = link.ack_deadline();
        let turn = paced.is_none() || frames.borrow().halted;
        tokio::select! {
            changed = ahead.changed(), if !link.ready() && !encoding_ahead.load(Ordering::Acquire) => {
                if changed.is_err() {
                    break;
                }
                let frame = ahead.borrow_and_update().clone();
                if !frame.pixels.is_empty() && !encoding(settings, &frame).denoised {
                    // (A denoised frame is made when it is its turn, not ahead.)
                    let n = if frame.generation == generation { nth } else { 0 };
                    let wanted = wanted(settings, &frame, n);
                    let busy = encoding_ahead.clone();
                    busy.store(true, Ordering::Release);
                    tokio::task::spawn_blocking(move || {
                        let _ = frame.encoded(encoding(wanted, &frame));
                        busy.store(false, Ordering::Release);
                    });
                }
            }
            () = sleep_until(paced), if paced.is_some() => paced = None,
            changed = frames.changed(), if link.ready() && turn => {
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
                let image = match tokio::task::spawn_blocking(move || f.encoded(encoding(wanted, &f))).await {
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
                if image.denoised {
                    paced = crate::render::denoise::next_turn();
                }
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
                let _ = sink.send(Message::Close(Some(CloseFrame {
                    code: SESSION_DELETED,
                    reason: Utf8Bytes::from(reason),
                }))).await;
                break;
            }
            _ = shutdown.changed() => {
                let _ = sink.send(Message::Close(Some(CloseFrame {
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
        denoised: image.denoised,
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
