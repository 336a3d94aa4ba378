//! Linear radiance -> display sRGB, 8 bits: clipped to [0, 1], the sRGB
//! transfer curve, rounded; NaN maps to 0. What `frame.png` holds of
//! `frame.pfm` at exposure 0, so a client that tone-maps linear frames
//! (merged renders) writes the bytes the server would.
//!
//! The curve is evaluated through a table (a 1920x1080 frame is six million
//! values: `powf` for each took 45-70 ms, more than encoding the JPEG), with
//! the same result as the formula for every input: the table holds the
//! output at the start of each of 32,512 buckets of the f32 range [0, 1),
//! and each bucket holds at most one step of the output, found by comparing
//! with the exact threshold of that step (computed from the formula by
//! bisection on the float's bits).

use std::sync::OnceLock;

/// One linear value to 8-bit sRGB (see the module's note).
#[inline]
pub fn srgb8(v: f32) -> u8 {
    curve().apply(v)
}

/// The sRGB curve of a linear value, 8 bits: the definition.
fn formula(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    // `as` saturates and maps NaN to 0.
    (e * 255.0 + 0.5) as u8
}

/// Low bits of an f32 dropped to find its bucket.
const BUCKET_SHIFT: u32 = 15;

/// The curve as a table, built once ([`curve`]); for loops over many
/// values, which fetch it once.
pub struct Curve {
    /// Output at the first value of each bucket of [0, 1).
    start: Vec<u8>,
    /// `step[k]`: the least value whose output is k or more (`step[256]`: never).
    step: [f32; 257],
}

/// The table, built on first use (under a millisecond).
pub fn curve() -> &'static Curve {
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
                if usize::from(formula(f32::from_bits(mid))) >= k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *s = f32::from_bits(lo);
        }
        let start = (0..=one >> BUCKET_SHIFT)
            .map(|b| formula(f32::from_bits(b << BUCKET_SHIFT)))
            .collect();
        Curve { start, step }
    })
}

impl Curve {
    /// One linear value to 8-bit sRGB, exactly as the formula gives it.
    #[inline(always)]
    pub fn apply(&self, v: f32) -> u8 {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_output_has_one_threshold_and_mid_grey_is_128() {
        let c = curve();
        assert!(c.step.windows(2).all(|pair| pair[0] < pair[1]));
        assert!(c.step[255] < 1.0 && c.step[256] == f32::INFINITY);
        // sRGB's mid grey, and the linear toe: 12.92 * 0.002 * 255 = 6.6.
        assert_eq!((srgb8(0.2159), srgb8(0.002)), (128, 7));
        assert_eq!((srgb8(f32::NAN), srgb8(-0.0), srgb8(7.0)), (0, 0, 255));
    }

    #[test]
    fn the_table_equals_the_formula_for_every_value() {
        let c = curve();
        // Around every step exactly, then a dense sweep of [0, 1].
        for k in 1..=255 {
            let s = c.step[k].to_bits();
            for b in s.saturating_sub(3)..=s + 3 {
                let v = f32::from_bits(b);
                assert_eq!(c.apply(v), formula(v), "{v:e} near step {k}");
            }
        }
        for b in (0..=1.0f32.to_bits()).step_by(101) {
            let v = f32::from_bits(b);
            assert_eq!(c.apply(v), formula(v), "{v:e}");
        }
        for v in [
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
            1e30,
            f32::MIN_POSITIVE,
        ] {
            assert_eq!(c.apply(v), formula(v), "{v:e}");
        }
    }
}
