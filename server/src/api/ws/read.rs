//! The reading half of a stream socket: the client's messages, each parsed
//! once ([`ClientMessage`]); acknowledgements and stream settings go to
//! the writer, changes apply to the session at once; until the socket
//! closes.

use super::{ClientMessage, Inbound};
use crate::service::session::Session;
use crate::service::AppState;
use axum::extract::ws::Message;
use futures_util::{Stream, StreamExt};
use std::sync::Arc;
use tokio::sync::mpsc;

pub(super) async fn read<S, E>(
    mut stream: S,
    state: Arc<AppState>,
    session: Arc<Session>,
    to_writer: mpsc::Sender<Inbound>,
) where
    S: Stream<Item = Result<Message, E>> + Unpin,
{
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
        let message = ClientMessage::parse(text.as_str(), &state.scene_rules());
        if let Some(seq) = message.ack {
            // Never blocks the reader: a full channel drops the ack, which
            // the writer's timeout then covers.
            let _ = to_writer.try_send(Inbound::Ack(seq));
        }
        let applied = message.request.and_then(|request| {
            for change in request.changes {
                session.apply(change)?;
            }
            Ok(request.stream)
        });
        let news = match applied {
            Ok(Some(settings)) => Inbound::Settings(settings),
            Ok(None) => continue,
            Err(e) => Inbound::Error(e.to_string()),
        };
        if to_writer.send(news).await.is_err() {
            return;
        }
    }
}
