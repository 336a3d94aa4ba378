//! The frame stream: a `Stream` of frames with their stats, and a way to
//! send changes on the same socket.

use crate::error::{message_of, ClientError, Result};
use crate::types::StreamFrame;
use futures_util::{SinkExt, Stream, StreamExt};
use pathstream_wire::StreamMessage;
use serde_json::Value;
use std::pin::Pin;
use std::task::{Context, Poll};
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

type Socket = WebSocketStream<MaybeTlsStream<tokio::net::TcpStream>>;

/// Frames as the server sends them (a PNG, then its stats). Server error
/// messages (a rejected change) come out as `Err(ClientError::Server)`; the
/// stream goes on after them.
pub struct FrameStream {
    socket: Socket,
    png: Option<Vec<u8>>,
}

impl FrameStream {
    pub(crate) async fn connect(url: &str) -> Result<Self> {
        // Without Nagle (as browsers do): small messages (changes) go out at
        // once instead of waiting for the server's delayed TCP ACK.
        let (socket, _) = tokio_tungstenite::connect_async_with_config(url, None, true)
            .await
            .map_err(|e| match e {
                tokio_tungstenite::tungstenite::Error::Http(r) => ClientError::Server {
                    status: r.status().as_u16(),
                    message: (r.body().as_deref())
                        .and_then(message_of)
                        .unwrap_or_else(|| "WebSocket upgrade refused".into()),
                },
                other => ClientError::Unreachable(other.to_string()),
            })?;
        Ok(Self { socket, png: None })
    }

    /// Sends a change: `{"camera": {...}}`, `{"light": {...}}`,
    /// `{"quality": {...}}` or `{"scene": ...}`.
    pub async fn send(&mut self, change: &Value) -> Result<()> {
        self.socket
            .send(Message::Text(change.to_string().into()))
            .await
            .map_err(|e| ClientError::Unreachable(e.to_string()))
    }

    pub async fn close(mut self) -> Result<()> {
        self.socket
            .close(None)
            .await
            .map_err(|e| ClientError::Unreachable(e.to_string()))
    }
}

impl Stream for FrameStream {
    type Item = Result<StreamFrame>;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Self::Item>> {
        loop {
            let message = match self.socket.poll_next_unpin(cx) {
                Poll::Pending => return Poll::Pending,
                Poll::Ready(None) => return Poll::Ready(None),
                Poll::Ready(Some(Err(e))) => {
                    return Poll::Ready(Some(Err(ClientError::Unreachable(e.to_string()))))
                }
                Poll::Ready(Some(Ok(m))) => m,
            };
            match message {
                Message::Binary(png) => self.png = Some(png.to_vec()),
                Message::Text(text) => {
                    let stats = match serde_json::from_str::<StreamMessage>(text.as_str()) {
                        Ok(StreamMessage::Error(e)) => {
                            return Poll::Ready(Some(Err(ClientError::Server {
                                status: 400,
                                message: e.error,
                            })))
                        }
                        Ok(StreamMessage::Stats(stats)) => Ok(*stats),
                        Err(e) => Err(ClientError::Protocol(e.to_string())),
                    };
                    // Stats with no frame before them are not a frame.
                    let Some(png) = self.png.take() else { continue };
                    return Poll::Ready(Some(stats.map(|s| StreamFrame {
                        png,
                        status: s.status,
                        seq: s.frame,
                    })));
                }
                Message::Close(_) => return Poll::Ready(None),
                _ => {}
            }
        }
    }
}
