//! Linear radiance -> display sRGB, 8 bits.

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
        rgb.map(|v| {
            let v = (v * scale).clamp(0.0, 1.0);
            let e = if v <= 0.003_130_8 {
                12.92 * v
            } else {
                1.055 * v.powf(1.0 / 2.4) - 0.055
            };
            (e * 255.0 + 0.5) as u8
        })
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
    }
}
