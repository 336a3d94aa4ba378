//! Linear radiance -> display sRGB, 8 bits.
//!
//! The curve is evaluated through a table (a 1920x1080 frame is six million
//! values: `powf` for each took 45-70 ms, more than encoding the JPEG), with
//! the same result as the formula for every input: the table holds the
//! output at the start of each of 32,512 buckets of the f32 range [0, 1),
//! and each bucket holds at most one step of the output, found by comparing
//! with the exact threshold of that step (computed from the formula by
//! bisection on the float's bits).

use std::sync::OnceLock;

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

/// The sRGB curve of a linear value, 8 bits: the definition.
fn srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (e * 255.0 + 0.5) as u8
}

/// Low bits of an f32 dropped to find its bucket.
const BUCKET_SHIFT: u32 = 15;

struct Curve {
    /// Output at the first value of each bucket of [0, 1).
    start: Vec<u8>,
    /// `step[k]`: the least value whose output is k or more (`step[256]`: never).
    step: [f32; 257],
}

fn curve() -> &'static Curve {
    static CURVE: OnceLock<Curve> = OnceLock::new();
    CURVE.get_or_init(|| {
        let one = 1.0f32.to_bits();
        let mut step = [f32::INFINITY; 257];
        step[0] = 0.0;
        for (k, s) in step.iter_mut().enumerate().take(256).skip(1) {
            // The output is monotone in the value's bits on [0, 1].
            let (mut lo, mut hi) = (0u32, one);
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if usize::from(srgb8(f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *s = f32::from_bits(lo);
        }
        let start = (0..=one >> BUCKET_SHIFT)
            .map(|b| srgb8(f32::from_bits(b << BUCKET_SHIFT)))
            .collect();
        Curve { start, step }
    })
}

impl Curve {
    #[inline(always)]
    fn apply(&self, v: f32) -> u8 {
        if v.is_nan() || v <= 0.0 {
            return 0;
        }
        if v >= 1.0 {
            return 255;
        }
        let k = self.start[(v.to_bits() >> BUCKET_SHIFT) as usize];
        k + u8::from(v >= self.step[usize::from(k) + 1])
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

    /// An image (row-major pixels) to 8-bit sRGB bytes, RGB.
    pub fn bytes(&self, rgb: &[[f32; 3]]) -> Vec<u8> {
        let scale = self.exposure.exp2();
        let curve = curve();
        let mut out = Vec::with_capacity(rgb.len() * 3);
        out.extend(rgb.iter().flatten().map(|&v| curve.apply(v * scale)));
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

    #[test]
    fn the_table_equals_the_formula_for_every_value() {
        let c = curve();
        // Around every step exactly, then a dense sweep of [0, 1].
        for k in 1..=255 {
            let s = c.step[k].to_bits();
            for b in s.saturating_sub(3)..=s + 3 {
                let v = f32::from_bits(b);
                assert_eq!(c.apply(v), srgb8(v), "{v:e} near step {k}");
            }
        }
        for b in (0..=1.0f32.to_bits()).step_by(101) {
            let v = f32::from_bits(b);
            assert_eq!(c.apply(v), srgb8(v), "{v:e}");
        }
        for v in [
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            1e30,
            f32::MIN_POSITIVE,
        ] {
            assert_eq!(c.apply(v), srgb8(v), "{v:e}");
        }
    }
}
