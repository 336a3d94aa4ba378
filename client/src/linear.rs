//! Linear images as the server sends them (`GET /api/sessions/{id}/frame.pfm`):
//! little-endian RGB PFM, header `PF\n<w> <h>\n-1.0\n`, rows bottom to top on
//! the wire, top row first in memory. And the PNG the server would make of
//! one: exposure 0, clipped to [0, 1], the sRGB transfer curve, 8 bits (the
//! server's `render/tonemap.rs`, which this client does not depend on).

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
        let bad = |why: &str| ImageError::Pfm(why.to_owned());
        let mut fields = Vec::with_capacity(4);
        let mut pos = 0;
        while fields.len() < 4 {
            while data.get(pos).is_some_and(u8::is_ascii_whitespace) {
                pos += 1;
            }
            let start = pos;
            while data.get(pos).is_some_and(|b| !b.is_ascii_whitespace()) {
                pos += 1;
            }
            let field = data.get(start..pos).filter(|f| !f.is_empty());
            let field = field.ok_or_else(|| bad("truncated header"))?;
            fields.push(std::str::from_utf8(field).map_err(|_| bad("header is not text"))?);
        }
        pos += 1; // the one whitespace byte after the scale
        if fields[0] != "PF" {
            return Err(bad("only colour PFM (PF) is supported"));
        }
        let width: u32 = fields[1].parse().map_err(|_| bad("bad width"))?;
        let height: u32 = fields[2].parse().map_err(|_| bad("bad height"))?;
        let scale: f32 = fields[3].parse().map_err(|_| bad("bad scale"))?;
        if !(scale < 0.0) {
            return Err(bad("only little-endian PFM is supported"));
        }
        if width == 0 || height == 0 {
            return Err(bad("empty image"));
        }
        let body = data.get(pos..).ok_or_else(|| bad("truncated data"))?;
        let row_bytes = 12 * width as usize;
        if body.len() as u64 != 12 * u64::from(width) * u64::from(height) {
            return Err(bad("data size does not match the header"));
        }
        let pixel = |px: &[u8]| -> [f32; 3] {
            std::array::from_fn(|c| {
                f32::from_le_bytes([px[4 * c], px[4 * c + 1], px[4 * c + 2], px[4 * c + 3]])
            })
        };
        let pixels = body
            .chunks_exact(row_bytes)
            .rev()
            .flat_map(|row| row.chunks_exact(12).map(pixel))
            .collect();
        Ok(Self {
            width,
            height,
            pixels,
        })
    }

    /// The image as PFM, byte for byte as the server writes it.
    pub fn encode_pfm(&self) -> Vec<u8> {
        let mut out = format!("PF\n{} {}\n-1.0\n", self.width, self.height).into_bytes();
        out.reserve(self.pixels.len() * 12);
        for row in self.pixels.chunks(self.width.max(1) as usize).rev() {
            for v in row.iter().flatten() {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        out
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

/// Linear radiance to 8-bit sRGB at exposure 0: clipped to [0, 1], the sRGB
/// curve, rounded; NaN maps to 0. The same f32 arithmetic as the server's
/// tone map, so the same bytes.
pub fn srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    // `as` saturates and maps NaN to 0.
    (e * 255.0 + 0.5) as u8
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
