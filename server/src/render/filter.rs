//! Where inside its pixel a camera sample lands.

use serde::{Deserialize, Serialize};

/// Pixel reconstruction filter (each sample counts for its own pixel only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Filter {
    /// smallpt's and the thesis's: the pixel split into 2x2 sub-pixels, each
    /// sample tent-distributed (width 2 sub-pixels) around a sub-pixel centre.
    #[default]
    Tent2x2,
    /// Uniform over the pixel.
    Box,
}

impl Filter {
    pub const NAMES: [&'static str; 2] = ["tent2x2", "box"];

    pub fn name(self) -> &'static str {
        match self {
            Filter::Tent2x2 => "tent2x2",
            Filter::Box => "box",
        }
    }

    pub fn parse(s: &str) -> Option<Filter> {
        match s {
            "tent2x2" => Some(Filter::Tent2x2),
            "box" => Some(Filter::Box),
            _ => None,
        }
    }

    /// Offset from the pixel's top-left corner, in pixels, for sample number
    /// `sample` given two uniform numbers. Samples 2k and 2k+1 share a
    /// sub-pixel so that the even and odd halves of the film (the error
    /// estimate) see the same sub-pixel pattern.
    #[inline(always)]
    pub fn pixel_offset(self, sample: u64, u1: f32, u2: f32) -> (f32, f32) {
        match self {
            Filter::Box => (u1, u2),
            Filter::Tent2x2 => {
                let sub = (sample >> 1) & 3;
                let (sx, sy) = ((sub & 1) as f32, (sub >> 1) as f32);
                ((sx + 0.5 + tent(u1)) * 0.5, (sy + 0.5 + tent(u2)) * 0.5)
            }
        }
    }
}

impl Filter {
    /// As [`Filter::pixel_offset`], for a low-discrepancy point: the
    /// sub-pixel from each coordinate's top bit and the tent from the rest
    /// (exact in f32), so that the point set's stratification carries over
    /// to the pixel. The same distribution as `pixel_offset`'s.
    #[inline(always)]
    pub fn pixel_offset_stratified(self, u1: f32, u2: f32) -> (f32, f32) {
        match self {
            Filter::Box => (u1, u2),
            Filter::Tent2x2 => {
                let (sx, r1) = halves(u1);
                let (sy, r2) = halves(u2);
                ((sx + 0.5 + tent(r1)) * 0.5, (sy + 0.5 + tent(r2)) * 0.5)
            }
        }
    }
}

/// Which half of [0, 1) `u` is in (0 or 1), and where in it, rescaled to
/// [0, 1).
#[inline(always)]
fn halves(u: f32) -> (f32, f32) {
    let t = 2.0 * u;
    if t >= 1.0 {
        (1.0, t - 1.0)
    } else {
        (0.0, t)
    }
}

/// smallpt's tent: maps uniform [0, 1) to [-1, 1) with a triangular density.
#[inline(always)]
fn tent(u: f32) -> f32 {
    let r = 2.0 * u;
    // sqrt(r) - 1 below r = 1, 1 - sqrt(2 - r) above (the same number as
    // -(sqrt(2 - r) - 1)), with one square root and a select: which half
    // a sample falls in is random, so a branch would be mispredicted half
    // the time.
    let d = r.min(2.0 - r).sqrt() - 1.0;
    if r < 1.0 {
        d
    } else {
        -d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tent_is_triangular() {
        // Mean 0, variance 1/6 for the triangle on [-1, 1].
        let n = 100_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let t = f64::from(tent((i as f32 + 0.5) / n as f32));
            assert!((-1.0..=1.0).contains(&t));
            s += t;
            s2 += t * t;
        }
        assert!((s / n as f64).abs() < 1e-4);
        assert!((s2 / n as f64 - 1.0 / 6.0).abs() < 1e-4);
    }

    #[test]
    fn tent2x2_visits_each_subpixel_once_in_eight_samples_per_half() {
        let mut even = [0; 4];
        let mut odd = [0; 4];
        for s in 0..8u64 {
            let (x, y) = Filter::Tent2x2.pixel_offset(s, 0.5, 0.5);
            let sub = usize::from(x > 0.5) + 2 * usize::from(y > 0.5);
            if s % 2 == 0 {
                even[sub] += 1;
            } else {
                odd[sub] += 1;
            }
        }
        assert_eq!(even, [1; 4]);
        assert_eq!(odd, [1; 4]);
    }
}
