//! What a WebSocket stream asks of its frames (a format, PNG, JPEG or
//! WebP; a width to scale them down to, the client's canvas; progressive
//! resolution), asked on the stream's URL
//! (`?format=jpeg&quality=85&width=640&progressive=true&raw=true`) or by
//! message (`{"stream": {...}}`). The request and its checks are the
//! contract's (`pathstream_wire::stream`, re-exported here); a frame's
//! encoding for them (without changing the session's film) is [`encoding`].

use crate::service::frame::{Encoding, Frame};
pub use pathstream_wire::stream::{StreamRequest, StreamSettings};

/// The encoding of `frame` that `settings` ask for (progressive resolution
/// is the stream's own business): denoised where the session's quality
/// says so, unless the stream asks for the raw image.
pub fn encoding(settings: StreamSettings, frame: &Frame) -> Encoding {
    Encoding {
        format: settings.format,
        width: settings.width,
        denoised: frame.shows_denoised() && !settings.raw,
    }
}
