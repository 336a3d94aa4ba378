//! Linear images as `frame.pfm` carries them (and `.pfm` files): colour,
//! little-endian PFM, header `PF\n<w> <h>\n-1.0\n`, then f32 RGB rows
//! bottom to top; in memory, row-major with the top row first.

/// Why bytes are not a PFM this reads; the reason only (callers say what
/// was being read).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct PfmError(pub String);

/// `rgb` (`width` pixels a row, top row first) as PFM.
pub fn encode(width: u32, height: u32, rgb: &[[f32; 3]]) -> Vec<u8> {
    let mut out = format!("PF\n{width} {height}\n-1.0\n").into_bytes();
    out.reserve(rgb.len() * 12);
    for row in rgb.chunks(width.max(1) as usize).rev() {
        for v in row.iter().flatten() {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// Reads a PFM as [`encode`] writes it: width, height and pixels, top row
/// first. Only colour little-endian PFM is read.
pub fn decode(data: &[u8]) -> Result<(u32, u32, Vec<[f32; 3]>), PfmError> {
    let bad = |why: &str| PfmError(why.to_owned());
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
    // A negative scale means little-endian; NaN means nothing.
    if !(scale < 0.0) {
        return Err(bad("only little-endian PFM is supported"));
    }
    if width == 0 || height == 0 {
        return Err(bad("empty image"));
    }
    let body = data.get(pos..).ok_or_else(|| bad("truncated data"))?;
    // In u64: a header's width times height can pass usize on 32 bits.
    if body.len() as u64 != 12 * u64::from(width) * u64::from(height) {
        return Err(bad("data size does not match the header"));
    }
    let pixel = |px: &[u8]| -> [f32; 3] {
        std::array::from_fn(|c| {
            f32::from_le_bytes([px[4 * c], px[4 * c + 1], px[4 * c + 2], px[4 * c + 3]])
        })
    };
    let rgb = body
        .chunks_exact(12 * width as usize)
        .rev()
        .flat_map(|row| row.chunks_exact(12).map(pixel))
        .collect();
    Ok((width, height, rgb))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_encode_writes_decode_reads_and_nothing_else() {
        let rgb: Vec<[f32; 3]> = (0..6).map(|i| [i as f32, -0.0, f32::MAX]).collect();
        let bytes = encode(3, 2, &rgb);
        assert_eq!(bytes.len(), b"PF\n3 2\n-1.0\n".len() + 6 * 12);
        // The bottom row (pixels 3, 4, 5) first on the wire.
        assert_eq!(bytes[12..16], 3.0f32.to_le_bytes());
        assert_eq!(decode(&bytes), Ok((3, 2, rgb)));
        let refused = [
            (&b"PF\n2"[..], "truncated header"),
            (b"Pf\n1 1\n-1.0\n0000", "only colour PFM (PF) is supported"),
            (b"PF\nx 1\n-1.0\n", "bad width"),
            (b"PF\n1 1\n1.0\n0", "only little-endian PFM is supported"),
            (b"PF\n1 1\nNaN\n0", "only little-endian PFM is supported"),
            (b"PF\n0 1\n-1.0\n", "empty image"),
            (
                b"PF\n1 1\n-1.0\n0000",
                "data size does not match the header",
            ),
        ];
        for (bytes, why) in refused {
            assert_eq!(decode(bytes), Err(PfmError(why.into())));
        }
    }
}
