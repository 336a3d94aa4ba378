//! A published image and its statistics: what a session's `watch` channel
//! carries to the WebSocket streams and the frame endpoints, and its
//! encodings (PNG, JPEG, WebP, at a width), each made once however many
//! clients want it.

use super::density::Density;
use super::error::ApiError;
use super::scaled::{downscale, Preview};
use crate::render::denoise::{self, DenoiseError, FilterQuality};
use crate::render::features::Features;
use crate::render::film::SppSpread;
use crate::render::output::{encode_jpeg, encode_pfm, encode_png, encode_webp, WEBP_MAX_SIDE};
use crate::render::quality::Denoise;
use crate::render::tonemap::Tonemap;
pub use pathstream_wire::stream::StreamFormat;
use std::borrow::Cow;
use std::sync::{Arc, Mutex, OnceLock};

/// How to encode a frame: the format, a width to scale it down to (None:
/// the film's), and whether to denoise it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Encoding {
    pub format: StreamFormat,
    pub width: Option<u32>,
    pub denoised: bool,
}

/// An encoded frame and its size.
#[derive(Clone, Debug)]
pub struct Encoded {
    pub bytes: Arc<[u8]>,
    pub width: u32,
    pub height: u32,
    /// Whether it shows the denoised image (asked for, and the denoiser
    /// did not fail).
    pub denoised: bool,
}

/// One encoding of a frame, made once.
pub(super) type EncodedOnce = OnceLock<Result<Encoded, String>>;

/// A published image and its statistics.
#[derive(Debug)]
pub struct Frame {
    /// Increases with every frame the session publishes.
    pub seq: u64,
    /// Which restart of the session this frame belongs to.
    pub generation: u64,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel (adaptive: the mean).
    pub spp: u64,
    pub spread: SppSpread,
    /// Samples per tile (None before the first pass).
    pub density: Option<Arc<Density>>,
    pub error_estimate: Option<f64>,
    pub samples_per_sec: f64,
    pub elapsed_ms: f64,
    pub rejected: u64,
    pub halted: bool,
    pub backend: String,
    pub device: String,
    /// Set (to k) when the image shows a 1/k-resolution preview, in whole
    /// or where the film has no sample yet (`session/preview.rs`).
    pub preview: Option<u32>,
    /// The preview itself, for a frame that is nothing else: streams
    /// scale it, not its scaled-up copy in `pixels`.
    pub preview_image: Option<Arc<Preview>>,
    /// Mean radiance, row-major, top row first (empty before the first pass).
    pub pixels: Vec<[f32; 3]>,
    /// The session's `quality.denoise` when the frame was made.
    pub denoise: Denoise,
    /// The denoiser's guides (where the session denoises).
    pub features: Option<Arc<Features>>,
    /// Encodings, by what was asked: each made once however many sockets
    /// want it (a second asker waits for the first's).
    encodings: Mutex<Vec<(Encoding, Arc<EncodedOnce>)>>,
}

impl Frame {
    pub fn empty(
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
            spread: SppSpread::default(),
            density: None,
            error_estimate: None,
            samples_per_sec: 0.0,
            elapsed_ms: 0.0,
            rejected: 0,
            halted: false,
            backend,
            device,
            preview: None,
            preview_image: None,
            pixels: Vec::new(),
            denoise: Denoise::Off,
            features: None,
            encodings: Mutex::new(Vec::new()),
        }
    }

    /// Whether the frame shows a denoised image unless asked otherwise:
    /// as the session's `quality.denoise` says for a frame that is (or is
    /// not) its last, and never for a preview or an empty frame.
    pub fn shows_denoised(&self) -> bool {
        self.denoise.shows(self.halted) && self.can_denoise()
    }

    /// Whether the frame has an image a denoiser can take.
    pub fn can_denoise(&self) -> bool {
        !self.pixels.is_empty() && self.preview_image.is_none()
    }

    fn pixels_or_black(&self) -> Cow<'_, [[f32; 3]]> {
        if self.pixels.is_empty() {
            Cow::Owned(vec![[0.0; 3]; self.width as usize * self.height as usize])
        } else {
            Cow::Borrowed(&self.pixels)
        }
    }

    /// The frame as PNG at its own size, denoised or not, encoded once
    /// however many clients want it (the frame endpoints). Call off the
    /// async runtime (it takes milliseconds; denoised, up to seconds).
    pub fn png(&self, denoised: bool) -> Result<Encoded, ApiError> {
        self.encoded(Encoding {
            denoised,
            ..Encoding::default()
        })
    }

    /// The frame encoded as `settings` say, each encoding made once. Call
    /// off the async runtime (it takes milliseconds).
    pub fn encoded(&self, settings: Encoding) -> Result<Encoded, ApiError> {
        // The same encoding however it is asked for: no width at or above
        // the frame's.
        let settings = Encoding {
            width: settings.width.filter(|&w| w < self.width),
            denoised: settings.denoised && self.can_denoise(),
            ..settings
        };
        let cell = {
            let mut encodings = self.encodings.lock().unwrap_or_else(|e| e.into_inner());
            match encodings.iter().find(|(s, _)| *s == settings) {
                Some((_, cell)) => cell.clone(),
                None => {
                    let cell = Arc::new(EncodedOnce::new());
                    encodings.push((settings, cell.clone()));
                    cell
                }
            }
        };
        cell.get_or_init(|| self.encode(settings))
            .clone()
            .map_err(ApiError::Internal)
    }

    /// Encodes the frame as `settings` asks (see [`Frame::encoded`]).
    fn encode(&self, settings: Encoding) -> Result<Encoded, String> {
        let pixels = self.pixels_or_black();
        let mut width = settings.width.unwrap_or(self.width).min(self.width);
        if matches!(settings.format, StreamFormat::Webp { .. }) {
            // WebP's sides are at most 16383 pixels: larger frames go scaled down.
            let tall =
                (u64::from(WEBP_MAX_SIDE) * u64::from(self.width) / u64::from(self.height)) as u32;
            width = width.min(WEBP_MAX_SIDE).min(tall.max(1));
        }
        let (w, h, mut pixels) = match (&self.preview_image, width < self.width) {
            (Some(preview), _) => {
                let (w, h, p) = preview.resized(width);
                (w, h, Cow::Owned(p))
            }
            (None, true) => {
                let (w, h, p) = downscale(&pixels, self.width, self.height, width);
                (w, h, Cow::Owned(p))
            }
            (None, false) => (self.width, self.height, pixels),
        };
        let mut denoised = false;
        if settings.denoised {
            match self.denoise(w, &pixels) {
                Ok(clean) => (pixels, denoised) = (Cow::Owned(clean), true),
                Err(e) => warn_once(&e),
            }
        }
        let t = Tonemap::default();
        let bytes = match settings.format {
            StreamFormat::Png => encode_png(w, h, &pixels, &t),
            StreamFormat::Jpeg { quality } => encode_jpeg(w, h, &pixels, &t, quality),
            StreamFormat::Webp { quality } => encode_webp(w, h, &pixels, &t, quality),
        }
        .map_err(|e| e.to_string())?;
        Ok(Encoded {
            bytes: bytes.into(),
            width: w,
            height: h,
            denoised,
        })
    }

    /// `pixels` (the frame's image at `width`) denoised, guided by the
    /// frame's features scaled the same way: a stream sized to a small
    /// canvas denoises that many pixels, not the film's. A frame that a
    /// newer one will replace is denoised by the faster filter.
    fn denoise(&self, width: u32, pixels: &[[f32; 3]]) -> Result<Vec<[f32; 3]>, DenoiseError> {
        let scaled = |image: &[[f32; 3]]| downscale(image, self.width, self.height, width);
        let features = self.features.as_deref().map(|f| match width < self.width {
            true => {
                let (w, h, albedo) = scaled(&f.albedo);
                let (_, _, normal) = scaled(&f.normal);
                Cow::Owned(Features {
                    width: w,
                    height: h,
                    albedo,
                    normal,
                })
            }
            false => Cow::Borrowed(f),
        });
        let height = (pixels.len() / width.max(1) as usize) as u32;
        let quality = match self.halted {
            true => FilterQuality::High,
            false => FilterQuality::Fast,
        };
        denoise::denoise(width, height, pixels, features.as_deref(), quality)
    }

    /// The frame as PFM (linear float), denoised (by the best filter) or
    /// not. Call off the async runtime.
    pub fn pfm(&self, denoised: bool) -> Result<Vec<u8>, DenoiseError> {
        let pixels = self.pixels_or_black();
        if denoised && self.can_denoise() {
            let features = self.features.as_deref();
            let clean = denoise::denoise(
                self.width,
                self.height,
                &pixels,
                features,
                FilterQuality::High,
            )?;
            return Ok(encode_pfm(self.width, self.height, &clean));
        }
        Ok(encode_pfm(self.width, self.height, &pixels))
    }
}

/// Logs a denoiser's failure once (the frames go out raw meanwhile).
fn warn_once(e: &DenoiseError) {
    static SAID: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    if !SAID.swap(true, std::sync::atomic::Ordering::Relaxed) {
        tracing::warn!(error = %e, "denoising failed; frames go out as rendered");
    }
}
