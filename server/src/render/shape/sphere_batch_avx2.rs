//! The nearest sphere hit with all eight lanes of a [`SphereBatch`] at once
//! (AVX2). The arithmetic is `SphereBatch::nearest`'s, operation for
//! operation (no fused multiply-adds: they would lengthen the dependency
//! chain, which is what limits this code), so the two agree bit for bit;
//! only the selects that follow are arranged differently, with the same
//! outcome, so that fewer of them wait on the division.

use crate::render::ray::Ray;
use crate::render::shape::sphere_batch::{Leaving, SphereBatch};
use std::arch::x86_64::*;

/// Nearest sphere hit over `batches`: (distance, object index as f32),
/// distance infinity when there is none. The render loop that calls it is
/// compiled for AVX2 and FMA too, so that it is inlined there.
///
/// # Safety
///
/// The CPU must have AVX2 and FMA (`isa::Avx2` is the proof).
#[target_feature(enable = "avx2,fma")]
#[inline]
pub fn nearest(batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32) {
    let lanes = |a: &[f32; 8]| -> __m256 { bytemuck::cast(*a) };
    let splat = _mm256_set1_ps;
    let (inf, zero, sign) = (splat(f32::INFINITY), _mm256_setzero_ps(), splat(-0.0));
    let (dx, dy, dz) = (splat(ray.dir.x), splat(ray.dir.y), splat(ray.dir.z));
    let (ox, oy, oz) = (
        splat(ray.origin.x),
        splat(ray.origin.y),
        splat(ray.origin.z),
    );
    let (od, oo) = (splat(ray.od), splat(ray.oo));
    let from_id = splat(from.id);
    // The sphere a ray leaves outwards is skipped altogether; NaN matches
    // no lane.
    // (A select on the bits: `entering` is data, not worth a branch.)
    let skip_id = splat(f32::from_bits(
        from.id.to_bits() | (u32::from(from.entering) * 0x7FC0_0000),
    ));
    let (mut best_t, mut best_id) = (inf, splat(-1.0));
    for batch in batches {
        let (cx, cy, cz, k, ids) = (
            lanes(&batch.cx),
            lanes(&batch.cy),
            lanes(&batch.cz),
            lanes(&batch.k),
            lanes(&batch.ids),
        );
        // The sphere the ray starts on: only its far side, and only when
        // the ray goes into it.
        let own = _mm256_cmp_ps::<_CMP_EQ_OQ>(ids, from_id);
        let dot = |x: __m256, y: __m256, z: __m256| {
            _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(x, cx), _mm256_mul_ps(y, cy)),
                _mm256_mul_ps(z, cz),
            )
        };
        let dc = dot(dx, dy, dz);
        let oc = dot(ox, oy, oz);
        let b = _mm256_sub_ps(od, dc);
        let c = _mm256_sub_ps(_mm256_add_ps(oo, k), _mm256_mul_ps(oc, splat(2.0)));
        let disc = _mm256_sub_ps(_mm256_mul_ps(b, b), c);
        // Lanes that can hit at all: real roots, not the sphere the ray
        // leaves outwards. Known before the square root, off the critical
        // path, like `own`.
        let valid = _mm256_andnot_ps(
            _mm256_cmp_ps::<_CMP_EQ_OQ>(ids, skip_id),
            _mm256_cmp_ps::<_CMP_GE_OQ>(disc, zero),
        );
        let near_valid = _mm256_andnot_ps(own, valid);
        let s = _mm256_sqrt_ps(_mm256_max_ps(disc, zero));
        // q = -(b + sign(b) s): the root pair q, c/q without cancellation.
        let s_signed = _mm256_or_ps(_mm256_and_ps(b, sign), _mm256_andnot_ps(sign, s));
        let q = _mm256_xor_ps(sign, _mm256_add_ps(b, s_signed));
        let other = _mm256_div_ps(c, q);
        let t0 = _mm256_min_ps(q, other);
        let t1 = _mm256_max_ps(q, other);
        // The near root if allowed and in front, else the far one if in
        // front, else none: the portable test's selects, with both
        // comparisons made at once.
        let near = _mm256_and_ps(near_valid, _mm256_cmp_ps::<_CMP_GT_OQ>(t0, zero));
        let far = _mm256_and_ps(valid, _mm256_cmp_ps::<_CMP_GT_OQ>(t1, zero));
        let t = _mm256_blendv_ps(_mm256_blendv_ps(inf, t1, far), t0, near);
        let closer = _mm256_cmp_ps::<_CMP_LT_OQ>(t, best_t);
        best_t = _mm256_min_ps(t, best_t);
        best_id = _mm256_blendv_ps(best_id, ids, closer);
    }
    let m = min_all(best_t);
    let id = min_all(_mm256_blendv_ps(
        inf,
        best_id,
        _mm256_cmp_ps::<_CMP_EQ_OQ>(best_t, m),
    ));
    (_mm256_cvtss_f32(m), _mm256_cvtss_f32(id))
}

/// The minimum of the eight lanes, in every lane. No lane may be NaN.
#[target_feature(enable = "avx2,fma")]
#[inline]
fn min_all(v: __m256) -> __m256 {
    let v = _mm256_min_ps(v, _mm256_permute2f128_ps::<1>(v, v));
    let v = _mm256_min_ps(v, _mm256_permute_ps::<0b01_00_11_10>(v));
    _mm256_min_ps(v, _mm256_permute_ps::<0b10_11_00_01>(v))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::shape::sphere_batch::tests::{batches, cases};

    #[test]
    fn agrees_bit_for_bit_with_the_portable_test() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        let (spheres, rays) = cases();
        for n in [1, 4, 5, 8, 9] {
            let batches = batches(&spheres[..n]);
            for (i, ray) in rays.iter().enumerate() {
                let own = spheres[i % n].0 as f32;
                for from in [
                    Leaving {
                        id: -2.0,
                        entering: false,
                    },
                    Leaving {
                        id: own,
                        entering: true,
                    },
                    Leaving {
                        id: own,
                        entering: false,
                    },
                ] {
                    // SAFETY: AVX2 and FMA were detected above.
                    #[allow(unsafe_code)]
                    let wide = unsafe { nearest(&batches, ray, from) };
                    let portable = SphereBatch::nearest(&batches, ray, from);
                    assert_eq!(
                        wide.0.to_bits(),
                        portable.0.to_bits(),
                        "{n} spheres, ray {i} {from:?}"
                    );
                    if wide.0 < f32::INFINITY {
                        assert_eq!(wide.1, portable.1, "{n} spheres, ray {i} {from:?}");
                    }
                }
            }
        }
    }
}
