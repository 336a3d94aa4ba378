//! What a WebSocket stream asks of its frames: the format (PNG, exact and
//! the default; JPEG at a quality, several times smaller on a noisy image
//! and the cheapest to encode; or lossy WebP, smaller again) and a width to scale them down to (the client's canvas), without
//! changing the session's film. Asked on the stream's URL
//! (`?format=jpeg&quality=85&width=640&progressive=true`) or by message
//! (`{"stream": {"format": "jpeg", "quality": 85, "width": 640,
//! "progressive": true}}`).

use super::error::ApiError;
use serde::Deserialize;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StreamFormat {
    #[default]
    Png,
    Jpeg {
        quality: u8,
    },
    Webp {
        quality: u8,
    },
}

impl StreamFormat {
    pub fn name(self) -> &'static str {
        match self {
            StreamFormat::Png => "png",
            StreamFormat::Jpeg { .. } => "jpeg",
            StreamFormat::Webp { .. } => "webp",
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StreamSettings {
    pub format: StreamFormat,
    /// Scale frames down to this width (None: the film's).
    pub width: Option<u32>,
    /// After a change, send the first frame at a quarter of the width and
    /// the second at half (smaller, so sooner over a slow link).
    pub progressive: bool,
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

/// `pixels` (w x h, row-major) averaged down to `width` columns and the
/// rows that keep the aspect ratio: each output pixel is the mean of the
/// input pixels whose indices fall in its footprint (in linear radiance,
/// before tone mapping).
pub fn downscale(pixels: &[[f32; 3]], w: u32, h: u32, width: u32) -> (u32, u32, Vec<[f32; 3]>) {
    let width = width.clamp(1, w);
    let height = ((u64::from(h) * u64::from(width)).div_ceil(u64::from(w)) as u32).clamp(1, h);
    let span = |o: u32, out: u32, n: u32| {
        let a = (u64::from(o) * u64::from(n) / u64::from(out)) as usize;
        let b = (u64::from(o + 1) * u64::from(n)).div_ceil(u64::from(out)) as usize;
        a..b.max(a + 1)
    };
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for oy in 0..height {
        let ys = span(oy, height, h);
        for ox in 0..width {
            let xs = span(ox, width, w);
            let mut sum = [0f64; 3];
            for y in ys.clone() {
                for x in xs.clone() {
                    let p = pixels[y * w as usize + x];
                    for c in 0..3 {
                        sum[c] += f64::from(p[c]);
                    }
                }
            }
            let n = (ys.len() * xs.len()) as f64;
            out.push(sum.map(|v| (v / n) as f32));
        }
    }
    (width, height, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscaling_keeps_the_mean_and_the_aspect() {
        let (w, h) = (10u32, 6u32);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [i as f32, 1.0, (i % 3) as f32])
            .collect();
        let (dw, dh, small) = downscale(&pixels, w, h, 5);
        assert_eq!((dw, dh), (5, 3));
        // 2x2 blocks: the first is pixels 0, 1, 10, 11.
        assert_eq!(small[0], [5.5, 1.0, (0.0 + 1.0 + 1.0 + 2.0) / 4.0]);
        let mean = |p: &[[f32; 3]]| p.iter().map(|v| f64::from(v[0])).sum::<f64>() / p.len() as f64;
        assert!((mean(&small) - mean(&pixels)).abs() < 1e-9);
        let (_, _, same) = downscale(&pixels, w, h, 10);
        assert_eq!(same, pixels);
        assert_eq!(downscale(&pixels, w, h, 1).0, 1);
    }

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
