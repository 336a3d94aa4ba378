//! The renderer's one math vocabulary: the glam types it uses and the few
//! helpers that glam does not have.
//!
//! `DVec3` is for the validated scene (world space, f64); `Vec3A` is for the
//! hot path (camera-relative f32, SIMD-aligned).

pub use glam::{BVec4A, DVec3, Vec3A, Vec4};

/// Largest of the three components.
#[inline]
pub fn max_component(v: Vec3A) -> f32 {
    v.x.max(v.y).max(v.z)
}

/// An orthonormal basis around unit `n` (Duff et al. 2017, branchless and
/// continuous except at n.z = -0), returned as (tangent, bitangent).
#[inline]
pub fn basis(n: Vec3A) -> (Vec3A, Vec3A) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3A::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3A::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Whether every component is finite.
#[inline]
pub fn is_finite3(v: Vec3A) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

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
