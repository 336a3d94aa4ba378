//! A published image and its statistics: what a session's `watch` channel
//! carries to the WebSocket streams and the frame endpoints.

use super::error::ApiError;
use crate::render::output::{encode_jpeg, encode_pfm, encode_png};
use crate::render::tonemap::Tonemap;
use serde::Deserialize;
use std::sync::{Arc, Mutex, OnceLock};

/// How a WebSocket stream encodes its frames: PNG (exact, the default) or
/// JPEG at a quality (lossy, several times smaller on a noisy image).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase", tag = "format", deny_unknown_fields)]
pub enum StreamFormat {
    #[default]
    Png,
    Jpeg {
        #[serde(default = "default_jpeg_quality")]
        quality: u8,
    },
}

fn default_jpeg_quality() -> u8 {
    85
}

impl StreamFormat {
    /// Checks the quality; the message names the field.
    pub fn validate(self) -> Result<Self, ApiError> {
        match self {
            StreamFormat::Jpeg { quality } if !(1..=100).contains(&quality) => {
                Err(ApiError::BadRequest(format!(
                    "stream.quality: must be between 1 and 100 (got {quality})"
                )))
            }
            f => Ok(f),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            StreamFormat::Png => "png",
            StreamFormat::Jpeg { .. } => "jpeg",
        }
    }
}

/// A published image and its statistics.
#[derive(Debug)]
pub struct Frame {
    /// Increases with every frame the session publishes.
    pub seq: u64,
    /// Which restart of the session this frame belongs to.
    pub generation: u64,
    pub width: u32,
    pub height: u32,
    pub spp: u64,
    pub error_estimate: Option<f64>,
    pub samples_per_sec: f64,
    pub elapsed_ms: f64,
    pub rejected: u64,
    pub halted: bool,
    pub backend: String,
    pub device: String,
    /// Mean radiance, row-major, top row first (empty before the first pass).
    pub pixels: Vec<[f32; 3]>,
    pub(super) png: OnceLock<Vec<u8>>,
    /// JPEGs encoded so far, by quality (each once however many sockets).
    pub(super) jpegs: Mutex<Vec<(u8, Arc<[u8]>)>>,
}

impl Frame {
    pub(super) fn empty(
        seq: u64,
        generation: u64,
        width: u32,
        height: u32,
        backend: String,
        device: String,
    ) -> Self {
        Self {
            seq,
            generation,
            width,
            height,
            spp: 0,
            error_estimate: None,
            samples_per_sec: 0.0,
            elapsed_ms: 0.0,
            rejected: 0,
            halted: false,
            backend,
            device,
            pixels: Vec::new(),
            png: OnceLock::new(),
            jpegs: Mutex::new(Vec::new()),
        }
    }

    fn pixels_or_black(&self) -> std::borrow::Cow<'_, [[f32; 3]]> {
        if self.pixels.is_empty() {
            std::borrow::Cow::Owned(vec![[0.0; 3]; self.width as usize * self.height as usize])
        } else {
            std::borrow::Cow::Borrowed(&self.pixels)
        }
    }

    /// The frame as PNG, encoded once however many clients want it. Call off
    /// the async runtime (it takes milliseconds).
    pub fn png(&self) -> Result<&[u8], ApiError> {
        if let Some(png) = self.png.get() {
            return Ok(png);
        }
        let png = encode_png(
            self.width,
            self.height,
            &self.pixels_or_black(),
            &Tonemap::default(),
        )
        .map_err(|e| ApiError::Internal(e.to_string()))?;
        Ok(self.png.get_or_init(|| png))
    }

    /// The frame encoded as `format` asks. Call off the async runtime.
    pub fn encoded(&self, format: StreamFormat) -> Result<Arc<[u8]>, ApiError> {
        let quality = match format {
            StreamFormat::Png => return self.png().map(Arc::from),
            StreamFormat::Jpeg { quality } => quality,
        };
        let cached = |jpegs: &[(u8, Arc<[u8]>)]| {
            jpegs
                .iter()
                .find(|(q, _)| *q == quality)
                .map(|(_, b)| b.clone())
        };
        if let Some(b) = cached(&self.jpegs.lock().unwrap_or_else(|e| e.into_inner())) {
            return Ok(b);
        }
        let jpeg: Arc<[u8]> = encode_jpeg(
            self.width,
            self.height,
            &self.pixels_or_black(),
            &Tonemap::default(),
            quality,
        )
        .map_err(|e| ApiError::Internal(e.to_string()))?
        .into();
        let mut jpegs = self.jpegs.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(b) = cached(&jpegs) {
            return Ok(b);
        }
        jpegs.push((quality, jpeg.clone()));
        Ok(jpeg)
    }

    pub fn pfm(&self) -> Vec<u8> {
        encode_pfm(self.width, self.height, &self.pixels_or_black())
    }
}
