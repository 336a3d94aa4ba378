//! Image files: PNG (tone-mapped sRGB, fast compression) and PFM (linear
//! little-endian f32 RGB, header `PF\n<w> <h>\n-1.0\n`, rows bottom to top; the
//! format is the contract's, `pathstream_wire::pfm`).

use crate::render::tonemap::Tonemap;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use std::path::Path;

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("unsupported output format '{0}' (use .png or .pfm)")]
    Format(String),
    #[error("image encoding failed: {0}")]
    Png(#[from] image::ImageError),
    #[error("cannot write {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("not a PFM file: {0}")]
    Pfm(String),
    #[error("JPEG encoding failed: {0}")]
    Jpeg(String),
    #[error("WebP encoding failed: {0}")]
    Webp(String),
}

/// Output format by file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Pfm,
}

impl ImageFormat {
    pub fn from_path(path: &Path) -> Result<Self, OutputError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match ext.as_str() {
            "png" => Ok(Self::Png),
            "pfm" => Ok(Self::Pfm),
            _ => Err(OutputError::Format(path.display().to_string())),
        }
    }
}

/// Tone-mapped 8-bit sRGB PNG of a linear image (row-major, top row
/// first); large images on machines of four or more threads are encoded in
/// strips on every core (`png_strips`).
pub fn encode_png(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    tonemap: &Tonemap,
) -> Result<Vec<u8>, OutputError> {
    let bytes = tonemap.bytes(rgb);
    if let Some(png) = crate::render::png_strips::encode(&bytes, width, height) {
        return Ok(png);
    }
    let mut out = Vec::with_capacity(bytes.len() / 2 + 64);
    PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Adaptive)
        .write_image(&bytes, width, height, ExtendedColorType::Rgb8)?;
    Ok(out)
}

/// Tone-mapped 8-bit sRGB JPEG of a linear image at `quality` (1-100),
/// chroma subsampled 4:2:0: lossy, for streams over slow links (noise makes
/// PNGs large). At most 65,535 pixels a side. Large images are encoded
/// in strips on every core (`jpeg_strips`).
pub fn encode_jpeg(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    tonemap: &Tonemap,
    quality: u8,
) -> Result<Vec<u8>, OutputError> {
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(OutputError::Jpeg(format!(
            "{width}x{height}: each side must be at most 65535"
        )));
    };
    crate::render::jpeg_strips::encode(&tonemap.bytes(rgb), w, h, quality)
        .map_err(OutputError::Jpeg)
}

/// Most pixels a side of a WebP image.
pub const WEBP_MAX_SIDE: u32 = 16_383;

/// Tone-mapped lossy WebP (libwebp, its fastest method) of a linear image
/// at `quality` (1-100): 3-10% smaller than JPEG at the same quality
/// setting on noisy frames, for 2-4x the encode time. At most
/// [`WEBP_MAX_SIDE`] pixels a side.
pub fn encode_webp(
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    tonemap: &Tonemap,
    quality: u8,
) -> Result<Vec<u8>, OutputError> {
    if width == 0 || height == 0 || width > WEBP_MAX_SIDE || height > WEBP_MAX_SIDE {
        return Err(OutputError::Webp(format!(
            "{width}x{height}: each side must be between 1 and {WEBP_MAX_SIDE}"
        )));
    }
    let bytes = tonemap.bytes(rgb);
    let mut config = webp::WebPConfig::new().map_err(|()| OutputError::Webp("no config".into()))?;
    config.lossless = 0;
    config.quality = f32::from(quality.clamp(1, 100));
    config.method = 0;
    let encoded = webp::Encoder::from_rgb(&bytes, width, height)
        .encode_advanced(&config)
        .map_err(|e| OutputError::Webp(format!("{e:?}")))?;
    Ok(encoded.to_vec())
}

/// Linear PFM of an image (row-major, top row first; PFM stores bottom
/// first), byte for byte what `frame.pfm` carries.
pub fn encode_pfm(width: u32, height: u32, rgb: &[[f32; 3]]) -> Vec<u8> {
    pathstream_wire::pfm::encode(width, height, rgb)
}

/// Reads a PFM written by [`encode_pfm`] (little-endian RGB only).
pub fn decode_pfm(data: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>), OutputError> {
    pathstream_wire::pfm::decode(data).map_err(|e| OutputError::Pfm(e.0))
}

/// Writes PNG or PFM by the path's extension.
pub fn write_image(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[[f32; 3]],
    tonemap: &Tonemap,
) -> Result<(), OutputError> {
    let bytes = match ImageFormat::from_path(path)? {
        ImageFormat::Png => encode_png(width, height, rgb, tonemap)?,
        ImageFormat::Pfm => encode_pfm(width, height, rgb),
    };
    std::fs::write(path, bytes).map_err(|source| OutputError::Io {
        path: path.display().to_string(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_round_trips_and_stores_the_bottom_row_first() {
        let rgb: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, 0.5, -1.0]).collect();
        let bytes = encode_pfm(2, 3, &rgb);
        assert!(bytes.starts_with(b"PF\n2 3\n-1.0\n"));
        let first = f32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes"));
        assert_eq!(first, 4.0, "bottom-left pixel comes first");
        let (w, h, back) = decode_pfm(&bytes).expect("decode");
        assert_eq!((w, h), (2, 3));
        assert_eq!(back, rgb);
    }

    #[test]
    fn png_is_a_valid_image_of_the_right_size() {
        let rgb = vec![[0.5f32, 0.25, 1.0]; 12];
        let png = encode_png(4, 3, &rgb, &Tonemap::default()).expect("png");
        let img = image::load_from_memory(&png).expect("decodes");
        assert_eq!((img.width(), img.height()), (4, 3));
    }

    #[test]
    fn format_follows_the_extension() {
        assert_eq!(
            ImageFormat::from_path(Path::new("a.PNG")).ok(),
            Some(ImageFormat::Png)
        );
        assert_eq!(
            ImageFormat::from_path(Path::new("a.pfm")).ok(),
            Some(ImageFormat::Pfm)
        );
        assert!(ImageFormat::from_path(Path::new("a.jpg")).is_err());
    }
}
