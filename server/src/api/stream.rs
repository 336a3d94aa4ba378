//! What a WebSocket stream asks of its frames (a format, PNG, JPEG or
//! WebP; a width to scale them down to, the client's canvas; progressive
//! resolution), asked on the stream's URL
//! (`?format=jpeg&quality=85&width=640&progressive=true`) or by message
//! (`{"stream": {...}}`). The request and its checks are the contract's
//! (`pathstream_wire::stream`, re-exported here); a frame's encoding for
//! them (without changing the session's film) is [`encoding`].

use crate::service::frame::Encoding;
pub use pathstream_wire::stream::{StreamRequest, StreamSettings};

/// The frame encoding `settings` ask for (progressive resolution is the
/// stream's own business).
pub fn encoding(settings: StreamSettings) -> Encoding {
    Encoding {
        format: settings.format,
        width: settings.width,
    }
}
