//! The renderer's one math vocabulary: the glam types it uses and the few
//! helpers that glam does not have.
//!
//! `DVec3` is for the validated scene (world space, f64); `Vec3A` is for the
//! hot path (camera-relative f32, SIMD-aligned).

pub use glam::{Affine3A, BVec4A, DAffine3, DMat3, DVec3, Mat3A, Vec3, Vec3A, Vec4};

use crate::render::lanes::{Bits, Real, Vector};

/// The largest f32 below 1: where a number stretched from a part of
/// [0, 1) back to all of it rounds up to 1, it becomes this.
pub const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// Largest of the three components.
#[inline(always)]
pub fn max_component(v: Vec3A) -> f32 {
    v.x.max(v.y).max(v.z)
}

/// An orthonormal basis around unit `n` (Duff et al. 2017, branchless and
/// continuous except at n.z = -0), returned as (tangent, bitangent).
#[inline(always)]
pub fn basis<V: Vector>(n: V) -> (V, V) {
    let c = <V::R as Real>::splat;
    let (x, y, z) = (n.x(), n.y(), n.z());
    let sign = c(1.0).copysign(z);
    let a = c(-1.0) / (sign + z);
    let b = x * y * a;
    (
        V::new(c(1.0) + sign * x * x * a, sign * b, -sign * x),
        V::new(b, sign + y * y * a, -y),
    )
}

/// (sin 2 pi u, cos 2 pi u) for u in [0, 1), without a libm call: the
/// quarter turn is found from u, the rest is a degree-7/8 Taylor polynomial
/// around pi/4 (error below 4e-7). Sampling directions needs no more, and the
/// hot loop avoids a call that spills every vector register.
#[inline(always)]
pub fn sincos_turns<R: Real>(u: R) -> (R, R) {
    let c = R::splat;
    let x = u * c(4.0);
    let quarter = x.floor();
    let a = (x - quarter - c(0.5)) * c(std::f32::consts::FRAC_PI_2);
    let a2 = a * a;
    let s = a * (c(1.0) + a2 * (c(-1.0 / 6.0) + a2 * (c(1.0 / 120.0) + a2 * c(-1.0 / 5040.0))));
    let cos = c(1.0)
        + a2 * (c(-0.5) + a2 * (c(1.0 / 24.0) + a2 * (c(-1.0 / 720.0) + a2 * c(1.0 / 40320.0))));
    // sin and cos of (a + pi/4), the angle within the quarter turn.
    let (sin_q, cos_q) = (
        (s + cos) * c(std::f32::consts::FRAC_1_SQRT_2),
        (cos - s) * c(std::f32::consts::FRAC_1_SQRT_2),
    );
    // The quarter turn by sign and swap, on the bits: the quadrant is random,
    // so branches on it would be mispredicted half the time. Same values as
    // (sin, cos) = odd ? (cos_q, -sin_q) : (sin_q, cos_q), negated if q >= 2.
    let b = <R::Bits as Bits>::splat;
    let q = quarter.to_int_bits() & b(3);
    let swap = b(0).wrapping_sub(q & b(1));
    let neg = (q >> 1) << 31;
    let (s_bits, c_bits) = (sin_q.to_bits(), cos_q.to_bits());
    let sin = (c_bits & swap) | (s_bits & !swap);
    let cos = ((s_bits ^ b(1 << 31)) & swap) | (c_bits & !swap);
    (R::from_bits(sin ^ neg), R::from_bits(cos ^ neg))
}

/// atan2(y, x) in turns, in [-1/2, 1/2], without a libm call, so that the
/// kernel's twin (`kernels/rng.h`) gives the same bits: the ratio of the
/// smaller to the larger magnitude is reduced to [0, tan(pi/8)] and Cephes'
/// `atanf` polynomial applied (relative error about 1e-7); octants by
/// symmetry. (0, 0) gives 0.
#[inline(always)]
pub fn atan2_turns(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let steep = ay > ax;
    let (num, den) = if steep { (ax, ay) } else { (ay, ax) };
    if !(den > 0.0) {
        return 0.0;
    }
    let t = num / den;
    let reduce = t > 0.414_213_57;
    let (base, t) = if reduce {
        (std::f32::consts::FRAC_PI_4, (t - 1.0) / (t + 1.0))
    } else {
        (0.0, t)
    };
    let z = t * t;
    let p =
        (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t
            + t;
    let mut a = base + p;
    if steep {
        a = std::f32::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f32::consts::PI - a;
    }
    if y < 0.0 {
        a = -a;
    }
    a * (0.5 * std::f32::consts::FRAC_1_PI)
}

/// pbrt's bound on the relative error of n rounded operations:
/// gamma(n) = n eps / (1 - n eps), eps = 2^-24.
pub const fn gamma(n: u32) -> f32 {
    let e = n as f32 * (f32::EPSILON * 0.5);
    e / (1.0 - e)
}

/// Whether every component is finite.
#[inline(always)]
pub fn is_finite3(v: Vec3A) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sincos_turns_matches_libm() {
        let mut worst = 0.0f32;
        for i in 0..=100_000 {
            let u = (i as f32 / 100_000.0).min(0.999_999_94);
            let (s, c) = sincos_turns(u);
            let (s0, c0) = (std::f32::consts::TAU * u).sin_cos();
            worst = worst.max((s - s0).abs()).max((c - c0).abs());
        }
        assert!(worst < 1e-6, "worst error {worst}");
    }

    #[test]
    fn atan2_turns_matches_libm_in_every_octant() {
        let mut worst = 0.0f64;
        for i in 0..20_000 {
            let a = i as f64 / 20_000.0 * std::f64::consts::TAU - std::f64::consts::PI;
            for r in [1e-30, 1e-3, 1.0, 7.5e3] {
                let (y, x) = ((a.sin() * r) as f32, (a.cos() * r) as f32);
                let exact = f64::from(y).atan2(f64::from(x)) / std::f64::consts::TAU;
                // Turns modulo 1: -1/2 and 1/2 are the same direction.
                let diff = (f64::from(atan2_turns(y, x)) - exact).rem_euclid(1.0);
                worst = worst.max(diff.min(1.0 - diff));
            }
        }
        assert!(worst < 6e-8, "worst error {worst} turns");
        assert_eq!(atan2_turns(0.0, 0.0), 0.0);
        assert_eq!(atan2_turns(0.0, -1.0), 0.5);
        assert_eq!(atan2_turns(1.0, 0.0), 0.25);
    }

    #[test]
    fn basis_is_orthonormal_for_awkward_normals() {
        let normals = [
            Vec3A::Z,
            -Vec3A::Z,
            Vec3A::X,
            Vec3A::new(1e-7, -1e-7, -1.0).normalize(),
            Vec3A::new(0.3, -0.4, 0.5).normalize(),
        ];
        for n in normals {
            let (t, b) = basis(n);
            for (x, y) in [(t, b), (t, n), (b, n)] {
                assert!(x.dot(y).abs() < 1e-6, "{n:?}: not orthogonal");
            }
            for v in [t, b] {
                assert!((v.length() - 1.0).abs() < 1e-6, "{n:?}: not unit");
            }
        }
    }
}
