//! A wide node's eight boxes against one ray in one pass of AVX
//! registers: [`super::test_portable`]'s arithmetic lane for lane, in the
//! same order (no fused multiply-adds), so the two agree bit for bit.

use super::traverse::{BoxRay, ROBUST};
use super::wide::{WideNode, WIDTH};
use std::arch::x86_64::*;

/// Entry distances of the node's boxes and the mask of those `ray` meets
/// between 0 and `t_max`. The render loop that calls it is compiled for
/// AVX2 and FMA too, so it is inlined there.
///
/// # Safety
///
/// The CPU must have AVX2 and FMA (`isa::Avx2` is the proof).
#[target_feature(enable = "avx2,fma")]
#[inline]
pub fn test(ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
    let b = &node.bounds;
    let splat = _mm256_set1_ps;
    let mut t_near = _mm256_setzero_ps();
    let mut t_far = splat(t_max);
    for axis in 0..3 {
        let (o, inv) = (splat(ray.org[axis].x), splat(ray.inv[axis].x));
        let near: __m256 = bytemuck::cast(b[ray.near[axis]]);
        let far: __m256 = bytemuck::cast(b[ray.far[axis]]);
        let near = _mm256_mul_ps(_mm256_sub_ps(near, o), inv);
        let far = _mm256_mul_ps(_mm256_sub_ps(far, o), inv);
        // maxps and minps return their second operand where either is
        // NaN: a slab the ray lies in does not constrain it.
        t_near = _mm256_max_ps(near, t_near);
        t_far = _mm256_min_ps(far, t_far);
    }
    let t_far = _mm256_mul_ps(t_far, splat(ROBUST));
    let met = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(t_near, t_far));
    (bytemuck::cast(t_near), met as u32)
}
