//! Linear images as the server sends them (`GET /api/sessions/{id}/frame.pfm`):
//! little-endian RGB PFM, header `PF\n<w> <h>\n-1.0\n`, rows bottom to top on
//! the wire, top row first in memory. And the PNG the server would make of
//! one: exposure 0, clipped to [0, 1], the sRGB transfer curve, 8 bits. Both
//! the format and the curve are the contract's (`pathstream_wire::pfm`,
//! `pathstream_wire::tonemap`), the code the server runs too.

use pathstream_wire::pfm;
use pathstream_wire::tonemap::srgb8;

/// What is wrong with an image or a set of images to merge.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("not a PFM image: {0}")]
    Pfm(String),
    #[error("image {index} is {got_width}x{got_height}, the first is {width}x{height}")]
    Size {
        index: usize,
        width: u32,
        height: u32,
        got_width: u32,
        got_height: u32,
    },
    #[error("no samples to merge")]
    NoSamples,
    #[error("PNG encoding failed: {0}")]
    Png(String),
}

/// A linear (radiance) image: row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

/// A session's linear frame and the statistics the server sent with it
/// (`x-pathstream-spp`, `x-pathstream-error-estimate`,
/// `x-pathstream-generation`).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearFrame {
    pub image: LinearImage,
    /// Samples per pixel (adaptive: the mean).
    pub spp: u64,
    /// The server's estimate of the image's relative RMS error.
    pub error_estimate: Option<f64>,
    pub generation: u64,
}

impl LinearImage {
    /// Reads a PFM as the server writes it (colour, little-endian).
    pub fn decode_pfm(data: &[u8]) -> Result<Self, ImageError> {
        let (width, height, pixels) = pfm::decode(data).map_err(|e| ImageError::Pfm(e.0))?;
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// The image as PFM, byte for byte as the server writes it.
    pub fn encode_pfm(&self) -> Vec<u8> {
        pfm::encode(self.width, self.height, &self.pixels)
    }

    /// The image as 8-bit sRGB PNG, the pixels the server's `frame.png`
    /// would hold for it.
    pub fn encode_png(&self) -> Result<Vec<u8>, ImageError> {
        use image::codecs::png::{CompressionType, FilterType, PngEncoder};
        use image::{ExtendedColorType, ImageEncoder};
        let bytes: Vec<u8> = self.pixels.iter().flat_map(|p| p.map(srgb8)).collect();
        let mut out = Vec::with_capacity(bytes.len() / 2 + 64);
        PngEncoder::new_with_quality(&mut out, CompressionType::Fast, FilterType::Adaptive)
            .write_image(&bytes, self.width, self.height, ExtendedColorType::Rgb8)
            .map_err(|e| ImageError::Png(e.to_string()))?;
        Ok(out)
    }

    /// Sum of the squared values over pixels and channels: the signal the
    /// server's relative error estimate divides by, squared.
    pub fn sum_of_squares(&self) -> f64 {
        self.pixels
            .iter()
            .flatten()
            .map(|&v| f64::from(v) * f64::from(v))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_matches_the_servers_tone_map() {
        // The server's own test values (server/src/render/tonemap.rs).
        assert_eq!([0.0, 1.0, 2.0].map(srgb8), [0, 255, 255]);
        assert_eq!([f32::NAN, -1.0, 0.2159].map(srgb8), [0, 0, 128]);
        assert_eq!(srgb8(0.002), 7, "the linear toe: 12.92 * 0.002 * 255");
    }

    #[test]
    fn pfm_round_trips_and_stores_the_bottom_row_first() {
        let image = LinearImage {
            width: 2,
            height: 3,
            pixels: (0..6).map(|i| [i as f32, 0.5, -1.0]).collect(),
        };
        let bytes = image.encode_pfm();
        assert!(bytes.starts_with(b"PF\n2 3\n-1.0\n"));
        // The bottom row (pixels 4 and 5) comes first.
        assert_eq!(bytes[12..16], 4.0f32.to_le_bytes());
        assert_eq!(LinearImage::decode_pfm(&bytes).ok(), Some(image));
    }

    #[test]
    fn bad_pfms_are_refused_with_the_reason() {
        let reason = |bytes: &[u8]| match LinearImage::decode_pfm(bytes) {
            Err(ImageError::Pfm(why)) => why,
            other => panic!("{other:?}"),
        };
        assert_eq!(reason(b"PF\n2"), "truncated header");
        assert_eq!(
            reason(b"Pf\n1 1\n-1.0\n0000"),
            "only colour PFM (PF) is supported"
        );
        assert_eq!(
            reason(b"PF\n1 1\n1.0\n000000000000"),
            "only little-endian PFM is supported"
        );
        assert_eq!(
            reason(b"PF\n1 1\n-1.0\n0000"),
            "data size does not match the header"
        );
        assert_eq!(reason(b"PF\n0 1\n-1.0\n"), "empty image");
    }

    #[test]
    fn png_has_the_size_and_the_tone_mapped_pixels() {
        let image = LinearImage {
            width: 3,
            height: 2,
            pixels: vec![[0.2159, 1.0, 0.0]; 6],
        };
        let png = image.encode_png().expect("png");
        let decoded = image::load_from_memory(&png).expect("decodes").to_rgb8();
        assert_eq!(decoded.dimensions(), (3, 2));
        assert!(decoded.pixels().all(|p| p.0 == [128, 255, 0]));
    }
}
