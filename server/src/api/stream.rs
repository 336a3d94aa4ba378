//! What a WebSocket stream asks of its frames: the format (PNG, exact and
//! the default; JPEG at a quality, several times smaller on a noisy image
//! and the cheapest to encode; or lossy WebP, smaller again) and a width to
//! scale them down to (the client's canvas), without changing the
//! session's film. Asked on the stream's URL
//! (`?format=jpeg&quality=85&width=640&progressive=true`) or by message
//! (`{"stream": {"format": "jpeg", "quality": 85, "width": 640,
//! "progressive": true}}`).

use crate::service::frame::{Encoding, StreamFormat};
use crate::service::ApiError;
use serde::Deserialize;

/// A stream's settings: its frames' encoding, and progressive resolution.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamSettings {
    pub format: StreamFormat,
    /// Scale frames down to this width (None: the film's).
    pub width: Option<u32>,
    /// After a change, send the first frame at a quarter of the width and
    /// the second at half (smaller, so sooner over a slow link).
    pub progressive: bool,
}

impl StreamSettings {
    /// The frame encoding these settings ask for.
    pub fn encoding(self) -> Encoding {
        Encoding {
            format: self.format,
            width: self.width,
        }
    }
}

/// A stream request as the URL or a message gives it.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StreamRequest {
    format: Option<String>,
    quality: Option<u8>,
    width: Option<u32>,
    progressive: Option<bool>,
    /// The bearer token may come on the URL (browsers cannot set headers on
    /// a WebSocket); the auth layer reads it.
    #[serde(default, rename = "token")]
    _token: Option<String>,
}

impl StreamRequest {
    /// The settings asked for; the message names the bad field.
    pub fn settings(&self) -> Result<StreamSettings, ApiError> {
        let bad = |m: String| Err(ApiError::BadRequest(m));
        let format = match (self.format.as_deref(), self.quality) {
            (None | Some("png"), None) => StreamFormat::Png,
            (None | Some("png"), Some(_)) => {
                return bad("stream.quality: only for format jpeg or webp".into())
            }
            (Some(lossy @ ("jpeg" | "webp")), q) => {
                let quality = q.unwrap_or(85);
                if !(1..=100).contains(&quality) {
                    return bad(format!(
                        "stream.quality: must be between 1 and 100 (got {quality})"
                    ));
                }
                match lossy {
                    "jpeg" => StreamFormat::Jpeg { quality },
                    _ => StreamFormat::Webp { quality },
                }
            }
            (Some(other), _) => {
                return bad(format!(
                    "stream.format: must be png, jpeg or webp (got '{other}')"
                ))
            }
        };
        if self.width == Some(0) {
            return bad("stream.width: must be at least 1".into());
        }
        Ok(StreamSettings {
            format,
            width: self.width,
            progressive: self.progressive.unwrap_or(false),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_checked_by_field() {
        let r = |f: Option<&str>, q: Option<u8>, w: Option<u32>| StreamRequest {
            format: f.map(str::to_owned),
            quality: q,
            width: w,
            progressive: None,
            _token: None,
        };
        assert_eq!(
            r(None, None, None).settings().expect("ok"),
            StreamSettings::default()
        );
        assert_eq!(
            r(Some("webp"), Some(60), None)
                .settings()
                .expect("ok")
                .format,
            StreamFormat::Webp { quality: 60 }
        );
        assert_eq!(
            r(Some("jpeg"), None, Some(64)).settings().expect("ok"),
            StreamSettings {
                format: StreamFormat::Jpeg { quality: 85 },
                width: Some(64),
                progressive: false,
            }
        );
        for (req, needle) in [
            (r(Some("gif"), None, None), "stream.format"),
            (
                r(Some("jpeg"), Some(0), None),
                "stream.quality: must be between 1 and 100",
            ),
            (
                r(None, Some(50), None),
                "stream.quality: only for format jpeg or webp",
            ),
            (r(None, None, Some(0)), "stream.width"),
        ] {
            let e = req.settings().expect_err("bad").to_string();
            assert!(e.contains(needle), "{e}");
        }
    }
}
