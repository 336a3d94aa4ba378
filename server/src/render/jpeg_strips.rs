//! A large JPEG encoded on every core: the image cut into strips of whole
//! MCU rows, each strip encoded by `jpeg-encoder` with the same settings (so
//! the same quantisation and Huffman tables), and the strips' entropy-coded
//! scans joined with restart markers into one baseline JPEG whose restart
//! interval is a strip's MCU count. A restart resets the DC predictions
//! (ITU T.81, F.1.2.3), which is exactly how each strip was encoded on its
//! own, so the file decodes to the pixels of a one-piece encoding. A 1080p
//! frame took ~45 ms on one core (the stream's frame rate and a change's
//! latency on a GPU box, docs/BENCHMARKS.md).

use crate::render::png_strips::PARALLEL_FROM;
use rayon::prelude::*;

/// Height of a 4:2:0 MCU.
const MCU: usize = 16;

/// RGB8 `rgb` (w x h, row-major) as a 4:2:0 baseline JPEG at `quality`.
pub fn encode(rgb: &[u8], w: u16, h: u16, quality: u8) -> Result<Vec<u8>, String> {
    let (wu, hu) = (usize::from(w), usize::from(h));
    let rows = strip_rows(wu, hu, rayon::current_num_threads());
    if wu * hu < PARALLEL_FROM || rows >= hu {
        return encode_one(rgb, w, h, quality);
    }
    let strips: Vec<Vec<u8>> = rgb
        .par_chunks(rows * wu * 3)
        .map(|strip| encode_one(strip, w, (strip.len() / (wu * 3)) as u16, quality))
        .collect::<Result<_, _>>()?;
    let interval = (wu.div_ceil(MCU) * rows / MCU) as u16;
    join(&strips, h, interval)
}

/// Rows per strip: whole MCU rows, about two strips per thread, at least
/// four MCU rows, and a restart interval that fits 16 bits.
fn strip_rows(w: usize, h: usize, threads: usize) -> usize {
    let wanted = h
        .div_ceil(2 * threads.max(1))
        .next_multiple_of(MCU)
        .max(4 * MCU);
    let most = (usize::from(u16::MAX) / w.div_ceil(MCU)).max(1) * MCU;
    wanted.min(most)
}

fn encode_one(rgb: &[u8], w: u16, h: u16, quality: u8) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(rgb.len() / 8 + 1024);
    let mut encoder = jpeg_encoder::Encoder::new(&mut out, quality.clamp(1, 100));
    encoder.set_sampling_factor(jpeg_encoder::SamplingFactor::R_4_2_0);
    encoder
        .encode(rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .map_err(|e| e.to_string())?;
    Ok(out)
}

/// Where a one-scan JPEG's parts are: the SOF segment, the SOS segment,
/// and its entropy-coded data (up to the EOI).
struct Parts {
    sof: usize,
    sos: usize,
    data: std::ops::Range<usize>,
}

fn parts(jpeg: &[u8]) -> Result<Parts, String> {
    let bad = || "jpeg-encoder wrote an unexpected stream".to_owned();
    if jpeg.get(..2) != Some(&[0xFF, 0xD8])
        || jpeg.get(jpeg.len().saturating_sub(2)..) != Some(&[0xFF, 0xD9])
    {
        return Err(bad());
    }
    let (mut i, mut sof) = (2, None);
    while i + 4 <= jpeg.len() {
        if jpeg[i] != 0xFF {
            return Err(bad());
        }
        let marker = jpeg[i + 1];
        let len = usize::from(u16::from_be_bytes([jpeg[i + 2], jpeg[i + 3]]));
        match marker {
            0xC0 => sof = Some(i),
            0xC1..=0xCF if marker != 0xC4 && marker != 0xC8 && marker != 0xCC => return Err(bad()),
            0xDA => {
                return Ok(Parts {
                    sof: sof.ok_or_else(bad)?,
                    sos: i,
                    data: i + 2 + len..jpeg.len() - 2,
                })
            }
            _ => {}
        }
        i += 2 + len;
    }
    Err(bad())
}

/// One JPEG of height `h` from strips encoded alike: the first strip's
/// headers (its height made `h`), a DRI of `interval`, and every strip's
/// scan, RST0..RST7 in turn between them.
fn join(strips: &[Vec<u8>], h: u16, interval: u16) -> Result<Vec<u8>, String> {
    let first = &strips[0];
    let p = parts(first)?;
    let total: usize = strips.iter().map(Vec::len).sum();
    let mut out = Vec::with_capacity(total + 2 * strips.len() + 16);
    out.extend_from_slice(&first[..p.sos]);
    // SOF0: FF C0, length (2), precision (1), then the height.
    out[p.sof + 5..p.sof + 7].copy_from_slice(&h.to_be_bytes());
    out.extend_from_slice(&[0xFF, 0xDD, 0x00, 0x04]);
    out.extend_from_slice(&interval.to_be_bytes());
    out.extend_from_slice(&first[p.sos..p.data.start]);
    for (k, strip) in strips.iter().enumerate() {
        if k > 0 {
            out.extend_from_slice(&[0xFF, 0xD0 + ((k - 1) % 8) as u8]);
        }
        let range = if k == 0 {
            p.data.clone()
        } else {
            parts(strip)?.data
        };
        out.extend_from_slice(&strip[range]);
    }
    out.extend_from_slice(&[0xFF, 0xD9]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::png_strips::tests::image;

    fn decode(jpeg: &[u8]) -> image::RgbImage {
        image::load_from_memory_with_format(jpeg, image::ImageFormat::Jpeg)
            .expect("decodes")
            .to_rgb8()
    }

    #[test]
    fn strips_decode_to_the_pixels_of_one_piece() {
        // Heights that are and are not whole MCU rows; a width that is not.
        for (w, h) in [(1000usize, 700usize), (1001, 653), (640, 512)] {
            let rgb = image(w, h);
            let one = encode_one(&rgb, w as u16, h as u16, 85).expect("one piece");
            let strips = encode(&rgb, w as u16, h as u16, 85).expect("strips");
            assert!(
                strips.windows(2).any(|m| m == [0xFF, 0xDD]),
                "{w}x{h}: no restart interval"
            );
            assert_ne!(one, strips, "{w}x{h} was encoded in one piece");
            // Restart markers RST0..RST7 in turn (a 0xFF in the scans is
            // followed by 0x00, so these are markers).
            let rst: Vec<u8> = strips
                .windows(2)
                .filter(|m| m[0] == 0xFF && (0xD0..=0xD7).contains(&m[1]))
                .map(|m| m[1] - 0xD0)
                .collect();
            assert!(!rst.is_empty());
            let in_turn = rst
                .iter()
                .enumerate()
                .all(|(k, &n)| usize::from(n) == k % 8);
            assert!(in_turn, "{w}x{h}: restart markers {rst:?}");
            let (a, b) = (decode(&one), decode(&strips));
            assert_eq!(b.dimensions(), (w as u32, h as u32));
            assert!(a == b, "{w}x{h}: the strips decode to other pixels");
        }
    }

    #[test]
    fn small_images_stay_one_piece_and_intervals_fit() {
        let rgb = image(64, 48);
        assert_eq!(encode(&rgb, 64, 48, 70), encode_one(&rgb, 64, 48, 70));
        assert_eq!(strip_rows(1920, 1080, 16), 64);
        assert_eq!(strip_rows(1920, 1080, 2), 272);
        // 65,535 pixels wide: 4,096 MCUs a row, so 15 MCU rows an interval.
        assert_eq!(strip_rows(65_535, 10_000, 1), 240);
    }
}
