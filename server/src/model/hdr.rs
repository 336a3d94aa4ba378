//! High-dynamic-range images for environment maps: Radiance `.hdr` (RGBE)
//! and OpenEXR `.exr` (half or float; the compressions the `exr` crate
//! reads: none, RLE, ZIP, PIZ, PXR24, B44, DWAA/DWAB), read into linear RGB
//! f32 texels, top row first.
//!
//! The size in the header is checked before any pixel is read, and every
//! texel must be finite and non-negative: an environment is radiance, and a
//! NaN or negative texel would poison every image lit by it. Real maps hold
//! slightly negative texels where lossy compression or filtering rounded
//! below zero: those no larger than [`NEGATIVE_TOLERANCE`] of the map's
//! mean are set to 0 (and counted in [`HdrImage::clamped`]); anything more
//! negative is an error. Errors are one line naming the file and the
//! problem.

use std::io::Cursor;

/// Most texels an environment map may have (8192 x 4096, 400 MB as f32).
pub const MAX_TEXELS: u64 = 8192 * 4096;
/// Longest side an environment map may have.
pub const MAX_SIDE: u32 = 16384;
/// Negative texels down to this fraction of the map's mean brightness are
/// rounding, and read as 0.
pub const NEGATIVE_TOLERANCE: f64 = 0.01;

/// An HDR image: `width * height` linear RGB texels, row by row from the
/// top.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    pub width: u32,
    pub height: u32,
    pub texels: Vec<[f32; 3]>,
    /// Slightly negative texel values that were read as 0.
    pub clamped: u64,
}

impl HdrImage {
    /// An image of these texels (tests, generated maps); None where the
    /// count does not match the size.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 3]>) -> Option<Self> {
        (width as usize * height as usize == texels.len() && width > 0 && height > 0).then_some(
            Self {
                width,
                height,
                texels,
                clamped: 0,
            },
        )
    }
}

/// Whether `name` is an HDR image file by its extension.
pub fn is_hdr_name(name: &str) -> bool {
    pathstream_wire::is_environment_name(name)
}

/// The format of an HDR image file by its first bytes (else its name):
/// `hdr` or `exr`, or None if it is neither.
pub fn detect(name: &str, bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(&EXR_MAGIC) {
        Some("exr")
    } else if bytes.starts_with(b"#?") {
        Some("hdr")
    } else if is_hdr_name(name) {
        let lower = name.to_ascii_lowercase();
        Some(if lower.ends_with(".exr") {
            "exr"
        } else {
            "hdr"
        })
    } else {
        None
    }
}

/// OpenEXR's first four bytes.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// Reads an HDR image from `bytes`; `name` (a file name) is used in
/// messages. The format is told by the file's first bytes.
pub fn read_hdr(bytes: &[u8], name: &str) -> Result<HdrImage, String> {
    let fail = |what: String| format!("{name}: {what}");
    let format = if bytes.starts_with(&EXR_MAGIC) {
        check_exr_header(bytes).map_err(fail)?;
        image::ImageFormat::OpenExr
    } else if bytes.starts_with(b"#?") {
        image::ImageFormat::Hdr
    } else {
        return Err(fail(
            "not a Radiance .hdr or OpenEXR .exr image (its first bytes are neither's)".into(),
        ));
    };
    let (w, h) = image::ImageReader::with_format(Cursor::new(bytes), format)
        .into_dimensions()
        .map_err(|e| fail(describe(e)))?;
    check_size(w, h).map_err(fail)?;
    let mut reader = image::ImageReader::with_format(Cursor::new(bytes), format);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    limits.max_alloc = Some(MAX_TEXELS * 16 + (1 << 20));
    reader.limits(limits);
    let decoded = reader.decode().map_err(|e| fail(describe(e)))?;
    let (width, height) = (decoded.width(), decoded.height());
    check_size(width, height).map_err(fail)?;
    let rgb = decoded.into_rgb32f();
    let mut sum = 0.0f64;
    for (x, y, p) in rgb.enumerate_pixels() {
        if let Some(bad) = p.0.iter().find(|v| !v.is_finite()) {
            return Err(fail(format!(
                "texel ({x}, {y}) is {bad}: an environment's radiance must be finite"
            )));
        }
        sum += p.0.iter().map(|&v| f64::from(v.max(0.0))).sum::<f64>();
    }
    let floor = -(NEGATIVE_TOLERANCE * sum / (3.0 * f64::from(width) * f64::from(height)));
    let mut clamped = 0;
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for (x, y, p) in rgb.enumerate_pixels() {
        let mut t = p.0;
        for v in &mut t {
            if *v < 0.0 {
                if f64::from(*v) < floor {
                    return Err(fail(format!(
                        "texel ({x}, {y}) is {v}: an environment's radiance must be non-negative"
                    )));
                }
                *v = 0.0;
                clamped += 1;
            }
        }
        texels.push(t);
    }
    Ok(HdrImage {
        width,
        height,
        texels,
        clamped,
    })
}

/// Whether a map of this size may be read.
fn check_size(width: u32, height: u32) -> Result<(), String> {
    if width == 0 || height == 0 {
        return Err(format!("the image is {width}x{height}: it has no texels"));
    }
    if width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_TEXELS {
        return Err(format!(
            "the image is {width}x{height}, more than an environment map may be \
             ({MAX_SIDE} on a side, {MAX_TEXELS} texels)"
        ));
    }
    Ok(())
}

/// An EXR's header: its size within the limits, its compression one that
/// can be read, before any pixel is.
fn check_exr_header(bytes: &[u8]) -> Result<(), String> {
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
        .map_err(|e| format!("not a readable OpenEXR header: {e}"))?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| "the OpenEXR file has no image".to_owned())?;
    let size = header.layer_size;
    let (w, h) = (size.width(), size.height());
    check_size(
        u32::try_from(w).unwrap_or(u32::MAX),
        u32::try_from(h).unwrap_or(u32::MAX),
    )?;
    use exr::compression::Compression as C;
    match header.compression {
        C::Uncompressed
        | C::RLE
        | C::ZIP1
        | C::ZIP16
        | C::PIZ
        | C::PXR24
        | C::B44
        | C::B44A
        | C::DWAA(_)
        | C::DWAB(_) => Ok(()),
        other => Err(format!(
            "its compression ({other}) cannot be read; save it with ZIP, PIZ or no compression"
        )),
    }
}

/// An image crate error as one line.
fn describe(e: image::ImageError) -> String {
    match e {
        image::ImageError::Limits(l) => format!("too large to read as an environment map: {l}"),
        other => format!("cannot be read: {other}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Radiance file of `w` x `h` texels, flat RGBE, all `rgbe`.
    fn radiance(w: u32, h: u32, rgbe: [u8; 4]) -> Vec<u8> {
        let mut b = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
        for _ in 0..w * h {
            b.extend_from_slice(&rgbe);
        }
        b
    }

    #[test]
    fn a_small_radiance_file_reads_to_its_values() {
        // RGBE (128, 64, 32, 129): mantissas / 256 * 2^(129-128).
        let img = read_hdr(&radiance(3, 2, [128, 64, 32, 129]), "t.hdr").expect("reads");
        assert_eq!((img.width, img.height, img.texels.len()), (3, 2, 6));
        for t in &img.texels {
            assert!(
                (t[0] - 1.0).abs() < 0.01 && (t[1] - 0.5).abs() < 0.01,
                "{t:?}"
            );
            assert!((t[2] - 0.25).abs() < 0.01, "{t:?}");
        }
    }

    #[test]
    fn bad_files_are_named_errors() {
        let truncated = radiance(64, 64, [1, 2, 3, 128]);
        let e = read_hdr(&truncated[..truncated.len() / 2], "cut.hdr").expect_err("truncated");
        assert!(e.starts_with("cut.hdr: "), "{e}");
        let huge = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 50000 +X 100000\n".to_vec();
        let e = read_hdr(&huge, "huge.hdr").expect_err("too large");
        assert!(e.contains("huge.hdr") && e.contains("100000x50000"), "{e}");
        let e = read_hdr(b"P6 1 1 255\n", "x.hdr").expect_err("not hdr");
        assert!(e.contains("not a Radiance"), "{e}");
        assert!(HdrImage::new(2, 2, vec![[0.0; 3]; 3]).is_none());
    }
}
