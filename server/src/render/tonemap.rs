//! Linear radiance -> display sRGB, 8 bits, at an exposure: the scale, then
//! the sRGB curve of `pathstream_wire::tonemap` (an exact table, the one
//! the client uses too, so both make the same bytes of the same pixels).

use pathstream_wire::tonemap::curve;
use rayon::prelude::*;

/// Tone mapping parameters: exposure in stops, then clip to [0, 1] and the
/// sRGB transfer curve (what smallpt's gamma 2.2 approximates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tonemap {
    pub exposure: f32,
}

impl Default for Tonemap {
    fn default() -> Self {
        Self { exposure: 0.0 }
    }
}

impl Tonemap {
    /// One pixel to 8-bit sRGB. NaN maps to 0.
    #[inline]
    pub fn apply(&self, rgb: [f32; 3]) -> [u8; 3] {
        let scale = self.exposure.exp2();
        let curve = curve();
        rgb.map(|v| curve.apply(v * scale))
    }

    /// An image (row-major pixels) to 8-bit sRGB bytes, RGB (on every
    /// core: a 1080p frame is 6 M values).
    pub fn bytes(&self, rgb: &[[f32; 3]]) -> Vec<u8> {
        const CHUNK: usize = 16_384;
        let scale = self.exposure.exp2();
        let curve = curve();
        let mut out = vec![0u8; rgb.len() * 3];
        out.par_chunks_mut(CHUNK * 3)
            .zip(rgb.par_chunks(CHUNK))
            .for_each(|(o, px)| {
                for (o, &v) in o.iter_mut().zip(px.iter().flatten()) {
                    *o = curve.apply(v * scale);
                }
            });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints_and_midpoint() {
        let t = Tonemap::default();
        assert_eq!(t.apply([0.0, 1.0, 2.0]), [0, 255, 255]);
        assert_eq!(t.apply([f32::NAN, -1.0, 0.2159]), [0, 0, 128]);
        let bright = Tonemap { exposure: 1.0 };
        assert_eq!(bright.apply([0.5, 0.5, 0.5]), [255, 255, 255]);
        assert_eq!(
            t.bytes(&[[0.0, 1.0, 2.0], [f32::NAN, -1.0, 0.2159]]),
            [0, 255, 255, 0, 0, 128]
        );
    }
}
