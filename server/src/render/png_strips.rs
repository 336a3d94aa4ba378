//! A large PNG encoded on every core: rows filtered and deflated in strips
//! at once, the strips' raw deflate streams ended with a sync flush (an
//! empty stored block, byte-aligned) and concatenated into the one zlib
//! stream of one IDAT, as parallel encoders such as pigz and mtpng do. Each
//! row's filter is the adaptive choice libpng and the `png` crate make
//! (least sum of absolute filtered bytes); a row's filters read the row
//! above from the image itself, so strips need nothing from each other.
//! Deflate comes from `flate2` (its zlib-rs backend at level 1: zlib's
//! quick strategy, 5x faster here than miniz at the same level), checksums
//! from `crc32fast` and `simd-adler32`; only the container and the filters
//! are written here.

use flate2::{Compress, Compression, FlushCompress, Status};
use rayon::prelude::*;

/// Images with fewer pixels are encoded in one piece (PNG by the `png`
/// crate; JPEG too, `jpeg_strips`).
pub const PARALLEL_FROM: usize = 1 << 18;
/// Rows per strip: at least this many.
const MIN_STRIP_ROWS: usize = 32;

/// RGB8 `rgb` (w x h, row-major) as a PNG, or None when it is small
/// enough (or the machine narrow enough) for one piece.
pub fn encode(rgb: &[u8], w: u32, h: u32) -> Option<Vec<u8>> {
    let (wu, hu) = (w as usize, h as usize);
    let threads = rayon::current_num_threads();
    if wu * hu < PARALLEL_FROM || threads < 4 {
        return None;
    }
    let rows = hu.div_ceil(2 * threads).max(MIN_STRIP_ROWS);
    let stride = wu * 3;
    let strips: Vec<usize> = (0..hu).step_by(rows).collect();
    let parts: Vec<(Vec<u8>, u32, usize)> = strips
        .par_iter()
        .map(|&y0| {
            let y1 = (y0 + rows).min(hu);
            let filtered = filter_rows(rgb, stride, y0..y1);
            let mut adler = simd_adler32::Adler32::new();
            adler.write(&filtered);
            let last = y1 == hu;
            (deflate(&filtered, last), adler.finish(), filtered.len())
        })
        .collect();
    let adler = parts
        .iter()
        .fold(1u32, |acc, (_, a, len)| adler32_combine(acc, *a, *len));
    let mut zlib = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum::<usize>() + 6);
    zlib.extend_from_slice(&[0x78, 0x01]);
    for (deflated, _, _) in &parts {
        zlib.extend_from_slice(deflated);
    }
    zlib.extend_from_slice(&adler.to_be_bytes());
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 2, 0, 0, 0]); // 8 bits, RGB, deflate, adaptive, no interlace
    let mut out = Vec::with_capacity(zlib.len() + 64);
    out.extend_from_slice(b"\x89PNG\r\n\x1a\n");
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &zlib);
    chunk(&mut out, b"IEND", &[]);
    Some(out)
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let start = out.len();
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let crc = crc32fast::hash(&out[start..]);
    out.extend_from_slice(&crc.to_be_bytes());
}

/// Raw deflate of `data`, ended by a sync flush (more follows) or, for the
/// last strip, by the final block.
fn deflate(data: &[u8], last: bool) -> Vec<u8> {
    let mut c = Compress::new(Compression::fast(), false);
    let mut out = Vec::with_capacity(data.len() / 2 + 1024);
    let flush = if last {
        FlushCompress::Finish
    } else {
        FlushCompress::Sync
    };
    loop {
        let consumed = c.total_in() as usize;
        if out.len() == out.capacity() {
            out.reserve(out.capacity() / 2 + 1024);
        }
        let status = c
            .compress_vec(&data[consumed..], &mut out, flush)
            .expect("deflate into a growing buffer cannot fail");
        let done = c.total_in() as usize == data.len() && out.len() < out.capacity();
        if status == Status::StreamEnd || (!last && done) {
            return out;
        }
    }
}

/// Adler-32 of A followed by B (len_b bytes) from their own checksums
/// (zlib's adler32_combine).
fn adler32_combine(a: u32, b: u32, len_b: usize) -> u32 {
    const BASE: u64 = 65_521;
    let rem = len_b as u64 % BASE;
    let (a1, a2) = (u64::from(a & 0xFFFF), u64::from(a >> 16));
    let (b1, b2) = (u64::from(b & 0xFFFF), u64::from(b >> 16));
    let sum1 = (a1 + b1 + BASE - 1) % BASE;
    let sum2 = (rem * a1 % BASE + a2 + b2 + BASE - rem) % BASE;
    ((sum2 as u32) << 16) | sum1 as u32
}

/// Rows `rows` of the image filtered, each behind its filter type byte.
fn filter_rows(rgb: &[u8], stride: usize, rows: std::ops::Range<usize>) -> Vec<u8> {
    let mut out = Vec::with_capacity(rows.len() * (stride + 1));
    let zero = vec![0u8; stride];
    let mut trial: [Vec<u8>; 5] = std::array::from_fn(|_| vec![0u8; stride]);
    for y in rows {
        let row = &rgb[y * stride..(y + 1) * stride];
        let above = if y == 0 {
            &zero[..]
        } else {
            &rgb[(y - 1) * stride..y * stride]
        };
        for (kind, t) in trial.iter_mut().enumerate() {
            filter(kind as u8, row, above, t);
        }
        let cost = |t: &Vec<u8>| {
            t.iter()
                .map(|&v| u64::from((v as i8).unsigned_abs()))
                .sum::<u64>()
        };
        let (best, _) = (trial.iter().enumerate())
            .min_by_key(|(_, t)| cost(t))
            .expect("five filters");
        out.push(best as u8);
        out.extend_from_slice(&trial[best]);
    }
    out
}

/// PNG filter `kind` (0 none, 1 sub, 2 up, 3 average, 4 Paeth) of `row`
/// with 3 bytes a pixel (the first pixel's left neighbours are 0). One
/// loop per filter, over zipped slices, so that the compiler vectorises.
fn filter(kind: u8, row: &[u8], above: &[u8], out: &mut [u8]) {
    const BPP: usize = 3;
    let n = row.len();
    let (head, tail) = out.split_at_mut(BPP);
    let (left, up_left) = (&row[..n - BPP], &above[..n - BPP]);
    let (x, up) = (&row[BPP..], &above[BPP..]);
    match kind {
        0 => out.copy_from_slice(row),
        1 => {
            head.copy_from_slice(&row[..BPP]);
            for ((o, &x), &a) in tail.iter_mut().zip(x).zip(left) {
                *o = x.wrapping_sub(a);
            }
        }
        2 => {
            for ((o, &x), &b) in out.iter_mut().zip(row).zip(above) {
                *o = x.wrapping_sub(b);
            }
        }
        3 => {
            for i in 0..BPP {
                head[i] = row[i].wrapping_sub(above[i] / 2);
            }
            for (((o, &x), &a), &b) in tail.iter_mut().zip(x).zip(left).zip(up) {
                *o = x.wrapping_sub(((u16::from(a) + u16::from(b)) / 2) as u8);
            }
        }
        _ => {
            for i in 0..BPP {
                head[i] = row[i].wrapping_sub(above[i]); // Paeth(0, b, 0) = b
            }
            for ((((o, &x), &a), &b), &c) in tail.iter_mut().zip(x).zip(left).zip(up).zip(up_left) {
                *o = x.wrapping_sub(paeth(a, b, c));
            }
        }
    }
}

#[inline(always)]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let (ia, ib, ic) = (i16::from(a), i16::from(b), i16::from(c));
    let p = ia + ib - ic;
    let (pa, pb, pc) = ((p - ia).abs(), (p - ib).abs(), (p - ic).abs());
    let b_or_c = if pb <= pc { b } else { c };
    if pa <= pb && pa <= pc {
        a
    } else {
        b_or_c
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Noise over smooth gradients and flat areas (every PNG filter wins
    /// somewhere; every JPEG block has edges or noise).
    pub(crate) fn image(w: usize, h: usize) -> Vec<u8> {
        let mut x = 0x2545_F491u32;
        (0..w * h * 3)
            .map(|i| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                let (px, py) = ((i / 3) % w, (i / 3) / w);
                match (px / 64 + py / 48) % 3 {
                    0 => 30,
                    1 => (px + py + i % 3) as u8,
                    _ => (x >> 24) as u8,
                }
            })
            .collect()
    }

    #[test]
    fn strips_decode_to_the_image() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .expect("pool");
        for (w, h) in [(800usize, 600usize), (1001, 333), (513, 1024)] {
            let rgb = image(w, h);
            let png = pool
                .install(|| encode(&rgb, w as u32, h as u32))
                .expect("in strips");
            let decoded = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
                .expect("decodes")
                .to_rgb8();
            assert_eq!(decoded.dimensions(), (w as u32, h as u32));
            assert!(decoded.as_raw() == &rgb, "{w}x{h}: other pixels");
            // Several strips, and every filter type used.
            let filtered = filter_rows(&rgb, w * 3, 0..h);
            let used: std::collections::BTreeSet<u8> =
                filtered.chunks(w * 3 + 1).map(|r| r[0]).collect();
            assert!(used.len() >= 3, "{used:?}");
        }
    }

    #[test]
    fn checksums_combine_as_one() {
        let data: Vec<u8> = (0..200_000u32).map(|i| (i * 7 % 251) as u8).collect();
        let whole = simd_adler32::adler32(&data.as_slice());
        let (a, b) = data.split_at(70_001);
        let combined = adler32_combine(
            simd_adler32::adler32(&a),
            simd_adler32::adler32(&b),
            b.len(),
        );
        assert_eq!(combined, whole);
        assert_eq!(adler32_combine(1, whole, data.len()), whole);
    }

    #[test]
    fn small_images_and_narrow_machines_use_one_piece() {
        let rgb = image(64, 64);
        assert!(encode(&rgb, 64, 64).is_none());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("pool");
        let big = image(800, 600);
        assert!(pool.install(|| encode(&big, 800, 600)).is_none());
    }
}
