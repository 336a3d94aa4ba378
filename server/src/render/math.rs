//! The renderer's one math vocabulary: the glam types it uses and the few
//! helpers that glam does not have.
//!
//! `DVec3` is for the validated scene (world space, f64); `Vec3A` is for the
//! hot path (camera-relative f32, SIMD-aligned).

pub use glam::{Affine3A, BVec4A, DAffine3, DMat3, DVec3, Mat3A, Vec3, Vec3A, Vec4};

use crate::render::lanes::{Bits, F32s, Real, Vector};

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

/// Each coordinate of `p` one float step towards the side the same
/// coordinate of `shift` points to: `f32::next_up` where it is positive,
/// `f32::next_down` where it is negative, unchanged where it is zero (or
/// NaN). On x86-64 the three coordinates go at once, without a branch: the
/// signs of a spawn's shift are as good as random, and three mispredicted
/// branches a spawn cost more than the arithmetic. The same bits as the
/// scalar steps for every input (tested).
#[inline(always)]
pub fn step_toward(p: Vec3A, shift: Vec3A) -> Vec3A {
    #[cfg(target_arch = "x86_64")]
    {
        step_toward_sse2(p, shift)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        step_toward_scalar(p, shift)
    }
}

/// [`step_toward`] a coordinate at a time, with the standard library's
/// steps: the definition the vector form is held to.
#[inline(always)]
pub fn step_toward_scalar(mut p: Vec3A, shift: Vec3A) -> Vec3A {
    for i in 0..3 {
        if shift[i] > 0.0 {
            p[i] = p[i].next_up();
        } else if shift[i] < 0.0 {
            p[i] = p[i].next_down();
        }
    }
    p
}

/// [`step_toward`] in SSE2 integer lanes on the floats' bits. A nonzero
/// finite x steps away from zero by adding one to its bits, towards zero
/// by subtracting one; a zero steps to the smallest subnormal of the
/// shift's sign; NaN stays, and so does an infinity stepped away from
/// zero (towards zero it becomes the largest finite float, its bits less
/// one).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn step_toward_sse2(p: Vec3A, shift: Vec3A) -> Vec3A {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of every x86-64 CPU (the baseline Rust builds
    // for); these intrinsics only compute on values.
    #[allow(unsafe_code)]
    unsafe {
        let (x, s) = (__m128::from(p), __m128::from(shift));
        let zero = _mm_setzero_ps();
        let (up, down) = (
            _mm_castps_si128(_mm_cmpgt_ps(s, zero)),
            _mm_castps_si128(_mm_cmplt_ps(s, zero)),
        );
        let bits = _mm_castps_si128(x);
        let magnitude = _mm_and_si128(bits, _mm_set1_epi32(0x7FFF_FFFF));
        let negative = _mm_srai_epi32::<31>(bits);
        // Away from zero: up from a positive x or down from a negative one.
        let away = _mm_or_si128(
            _mm_andnot_si128(negative, up),
            _mm_and_si128(negative, down),
        );
        // bits + 1 away from zero, bits - 1 towards it (away is all ones or 0).
        let stepped = _mm_sub_epi32(
            _mm_sub_epi32(bits, _mm_slli_epi32::<1>(away)),
            _mm_set1_epi32(1),
        );
        let tiny = _mm_or_si128(
            _mm_set1_epi32(1),
            _mm_and_si128(down, _mm_set1_epi32(i32::MIN)),
        );
        let is_zero = _mm_cmpeq_epi32(magnitude, _mm_setzero_si128());
        let nan = _mm_cmpgt_epi32(magnitude, _mm_set1_epi32(0x7F80_0000));
        let inf = _mm_cmpeq_epi32(magnitude, _mm_set1_epi32(0x7F80_0000));
        let moving = _mm_or_si128(up, down);
        let keep = _mm_or_si128(
            _mm_andnot_si128(moving, _mm_set1_epi32(-1)),
            _mm_or_si128(nan, _mm_and_si128(inf, away)),
        );
        let select = |mask: __m128i, a: __m128i, b: __m128i| {
            _mm_or_si128(_mm_and_si128(mask, a), _mm_andnot_si128(mask, b))
        };
        let out = select(keep, bits, select(is_zero, tiny, stepped));
        Vec3A::from(_mm_castsi128_ps(out))
    }
}

/// [`step_toward`] for `W` lanes (each lane of `x` towards the sign of the
/// same lane of `s`), on each lane's bits as masks (all ones or zero) in a
/// counted loop, which the compiler keeps in vector registers: the same
/// bits as the scalar steps (tested).
#[inline(always)]
pub fn step_toward_lanes<const W: usize>(x: F32s<W>, s: F32s<W>) -> F32s<W> {
    let all = |c: bool| 0u32.wrapping_sub(u32::from(c));
    let mut out = [0.0; W];
    for (k, o) in out.iter_mut().enumerate() {
        let (b, s) = (x.0[k].to_bits(), s.0[k]);
        let (up, down) = (all(s > 0.0), all(s < 0.0));
        let magnitude = b & 0x7FFF_FFFF;
        let negative = ((b as i32) >> 31) as u32;
        let away = (up & !negative) | (down & negative);
        // bits + 1 away from zero, bits - 1 towards it.
        let stepped = b.wrapping_sub(1).wrapping_add(away & 2);
        let tiny = 1 | (down & 0x8000_0000);
        let zero = all(magnitude == 0);
        let moved = (zero & tiny) | (!zero & stepped);
        let infinite = all(magnitude == 0x7F80_0000);
        let keep = !(up | down) | all(magnitude > 0x7F80_0000) | (infinite & away);
        *o = f32::from_bits((keep & b) | (!keep & moved));
    }
    F32s(out)
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

    #[test]
    fn step_toward_is_the_scalar_steps_bit_for_bit() {
        let specials = [
            0.0f32,
            -0.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            1.0,
            -1.0,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::from_bits(0x7F80_0001),
            1e5,
            -3.5e-20,
        ];
        let shifts = [1.0f32, -1.0, 0.0, -0.0, f32::NAN, 1e-30, -1e-30];
        let same = |a: Vec3A, b: Vec3A| {
            (0..3).all(|i| a[i].to_bits() == b[i].to_bits() || (a[i].is_nan() && b[i].is_nan()))
        };
        // The lanes' form gives the scalar steps' very bits, NaNs too.
        let lanes = |p: Vec3A, s: Vec3A| {
            let got = step_toward_lanes(F32s([p.x, p.y, p.z, -p.x]), F32s([s.x, s.y, s.z, -s.x]));
            let want = step_toward_scalar(p, s);
            let last = step_toward_scalar(-p, -s).x;
            (0..3).all(|i| got.0[i].to_bits() == want[i].to_bits())
                && got.0[3].to_bits() == last.to_bits()
        };
        let mut n = 0;
        for &x in &specials {
            for &sx in &shifts {
                for &sy in &shifts {
                    let (p, s) = (Vec3A::new(x, -x, x * 0.5), Vec3A::new(sx, sy, -sx));
                    let (got, want) = (step_toward(p, s), step_toward_scalar(p, s));
                    assert!(same(got, want), "{p:?} {s:?}: {got:?} against {want:?}");
                    assert!(lanes(p, s), "lanes: {p:?} {s:?}");
                    n += 1;
                }
            }
        }
        // And a spread of ordinary floats of every magnitude.
        let mut bits = 0x2545_F491u32;
        for _ in 0..100_000 {
            bits = bits.wrapping_mul(0x9E37_79B9).wrapping_add(0x7F4A_7C15);
            let x = f32::from_bits(bits);
            let s = Vec3A::new(f32::from_bits(bits.rotate_left(7)), -x, x);
            let p = Vec3A::new(
                x,
                f32::from_bits(bits ^ 0x8000_0000),
                f32::from_bits(bits >> 3),
            );
            assert!(
                same(step_toward(p, s), step_toward_scalar(p, s)),
                "{p:?} {s:?}"
            );
            assert!(lanes(p, s), "lanes: {p:?} {s:?}");
            n += 1;
        }
        assert!(n > 100_000);
    }
}
