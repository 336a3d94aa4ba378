//! The WebSocket frame stream (`GET /api/sessions/{id}/ws`): what a stream
//! asks of its frames, and the text messages the server sends.
//!
//! A stream asks for a format (PNG, exact and the default; JPEG at a
//! quality, several times smaller on a noisy image and the cheapest to
//! encode; or lossy WebP, smaller again) and a width to scale frames down
//! to (the client's canvas), without changing the session's film, and
//! whether to show the raw image where the session denoises; on the
//! stream's URL (`?format=jpeg&quality=85&width=640&progressive=true`) or
//! by message (`{"stream": {"format": "jpeg", "quality": 85, "width": 640,
//! "progressive": true, "raw": false}}`).
//!
//! Each binary frame is followed by its stats, the session's status with
//! the frame's own figures and how it went out:
//! ```json
//! {"type": "stats", "id": "s1", ..., "spp": 12, "generation": 0,
//!  "frame": 31, "format": "jpeg", "frame_bytes": 48211, "frame_width": 640,
//!  "frame_height": 480, "progressive": false, "preview": null,
//!  "delivered_fps": 24, "link_mbps": 81.5, "delivery_ms": 4.7}
//! ```
//! A bad client message gets `{"type": "error", "error": "..."}` and the
//! socket stays open.

use crate::error::ErrorBody;
use crate::status::SessionStatus;
use serde::{Deserialize, Serialize};

/// JPEG and WebP quality when the stream names none.
pub const DEFAULT_QUALITY: u8 = 85;

/// How frames are encoded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StreamFormat {
    /// PNG: exact.
    #[default]
    Png,
    /// JPEG at this quality (1-100).
    Jpeg {
        /// 1 (smallest) to 100 (best).
        quality: u8,
    },
    /// Lossy WebP at this quality (1-100).
    Webp {
        /// 1 (smallest) to 100 (best).
        quality: u8,
    },
}

impl StreamFormat {
    /// The format's name on the wire: `png`, `jpeg` or `webp`.
    pub fn name(self) -> &'static str {
        match self {
            StreamFormat::Png => "png",
            StreamFormat::Jpeg { .. } => "jpeg",
            StreamFormat::Webp { .. } => "webp",
        }
    }
}

/// A stream's settings, checked ([`StreamRequest::settings`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamSettings {
    /// How frames are encoded.
    pub format: StreamFormat,
    /// Scale frames down to this width (None: the film's).
    pub width: Option<u32>,
    /// After a change, send the first frame at a quarter of the width and
    /// the second at half (smaller, so sooner over a slow link).
    pub progressive: bool,
    /// The raw image even where the session denoises its frames.
    pub raw: bool,
}

/// A stream request as the URL's query or a `stream` message gives it;
/// every field is optional and unknown fields are refused.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamRequest {
    /// `png`, `jpeg` or `webp`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// 1-100, for `jpeg` and `webp` only (default 85).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quality: Option<u8>,
    /// Scale frames down to this width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// Narrower first frames after a change.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub progressive: Option<bool>,
    /// The raw image even where the session denoises (default false).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw: Option<bool>,
    /// The bearer token, on the URL (browsers cannot set headers on a
    /// WebSocket); the server's auth layer reads it, the settings do not.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub token: Option<String>,
}

/// A stream request that cannot be honoured; the message names the field.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StreamError {
    /// A quality for PNG, which has none.
    #[error("stream.quality: only for format jpeg or webp")]
    QualityWithoutLossy,
    /// A quality outside 1-100.
    #[error("stream.quality: must be between 1 and 100 (got {0})")]
    Quality(u8),
    /// A format other than png, jpeg or webp.
    #[error("stream.format: must be png, jpeg or webp (got '{0}')")]
    Format(String),
    /// Width 0.
    #[error("stream.width: must be at least 1")]
    Width,
}

impl StreamRequest {
    /// The settings asked for.
    pub fn settings(&self) -> Result<StreamSettings, StreamError> {
        let format = match (self.format.as_deref(), self.quality) {
            (None | Some("png"), None) => StreamFormat::Png,
            (None | Some("png"), Some(_)) => return Err(StreamError::QualityWithoutLossy),
            (Some(lossy @ ("jpeg" | "webp")), q) => {
                let quality = q.unwrap_or(DEFAULT_QUALITY);
                if !(1..=100).contains(&quality) {
                    return Err(StreamError::Quality(quality));
                }
                match lossy {
                    "jpeg" => StreamFormat::Jpeg { quality },
                    _ => StreamFormat::Webp { quality },
                }
            }
            (Some(other), _) => return Err(StreamError::Format(other.to_owned())),
        };
        if self.width == Some(0) {
            return Err(StreamError::Width);
        }
        Ok(StreamSettings {
            format,
            width: self.width,
            progressive: self.progressive.unwrap_or(false),
            raw: self.raw.unwrap_or(false),
        })
    }
}

/// A text message the server sends on the stream's socket.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum StreamMessage {
    /// The stats of the binary frame just sent.
    Stats(Box<Stats>),
    /// A client message was refused; the socket stays open.
    Error(ErrorBody),
}

/// The stats sent after each frame. The status's `spp`, `spp_spread`,
/// `error_estimate`, `samples_per_sec` and `generation` are the frame's own
/// where it is of the session's current generation (`generation` always),
/// not of whatever came after it.
///
/// The fields after the status are `#[serde(default)]`: servers added them
/// one by one, and a client reads the stats of any of them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// The session's status, its fields at the top level.
    #[serde(flatten)]
    pub status: SessionStatus,
    /// The server's frame number (gaps mean frames skipped for being stale).
    #[serde(default)]
    pub frame: u64,
    /// `png`, `jpeg` or `webp`.
    #[serde(default)]
    pub format: String,
    /// Size of the encoded frame.
    #[serde(default)]
    pub frame_bytes: u64,
    /// Width of the frame as sent (scaled down, or narrower while progressive).
    #[serde(default)]
    pub frame_width: u32,
    /// Height of the frame as sent.
    #[serde(default)]
    pub frame_height: u32,
    /// Whether the stream asked for progressive resolution.
    #[serde(default)]
    pub progressive: bool,
    /// k when the image shows the 1/k-resolution preview (spp 0).
    #[serde(default)]
    pub preview: Option<u32>,
    /// Whether the frame shows the denoised image (the session denoises,
    /// the stream did not ask for the raw one, and the denoiser did not
    /// fail). The status's error estimate is the raw image's either way.
    #[serde(default)]
    pub denoised: bool,
    /// Frames that arrived in the second before this one was sent.
    #[serde(default)]
    pub delivered_fps: u64,
    /// Delivery rate in Mbit/s, from the client's acknowledgements; None
    /// before the first.
    #[serde(default)]
    pub link_mbps: Option<f64>,
    /// Sent-to-acknowledged time of the last acknowledged frame.
    #[serde(default)]
    pub delivery_ms: Option<f64>,
}

#[cfg(test)]
#[path = "stream_tests.rs"]
mod tests;
