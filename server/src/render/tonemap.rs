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

/// The sRGB transfer curve of a linear value clipped to [0, 1], before
/// any rounding (what `Tonemap` rounds to 8 bits at exposure 0).
#[inline]
pub fn srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The relative RMS error of `image` against `reference` as a viewer sees
/// both ([`srgb`] of each channel): the measure of a denoiser, whose work
/// is the picture, and which the radiance's own error (dominated by a
/// light's few pixels, tens of times brighter than the rest) hides.
pub fn displayed_error(image: &[[f32; 3]], reference: &[[f32; 3]]) -> f64 {
    let shown = |px: &[[f32; 3]]| px.iter().map(|p| p.map(srgb)).collect::<Vec<_>>();
    crate::render::film::relative_rms_error(&shown(image), &shown(reference))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_float_curve_rounds_to_the_bytes() {
        for v in [0.0f32, 0.002, 0.2159, 0.5, 0.99, 3.0] {
            let byte = (srgb(v) * 255.0 + 0.5) as u8;
            assert_eq!(byte, pathstream_wire::tonemap::srgb8(v), "{v}");
        }
        let a = [[0.5f32; 3]; 4];
        assert_eq!(displayed_error(&a, &a), 0.0);
        let b = [[9.0f32; 3]; 4];
        // Both clip to white: no error as displayed.
        assert_eq!(displayed_error(&b, &[[1.0f32; 3]; 4]), 0.0);
    }

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
