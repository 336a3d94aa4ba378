//! Where next-event estimation aims, written once for one path (`Vec3A`)
//! and for lanes of paths (`V3` of lane arrays, `render::lanes`): points on
//! triangles and quads, the direction towards such a point with its
//! solid-angle weight, directions in a cone (a sphere seen from outside,
//! the sun) and points on a sphere seen from inside. Every lane does the
//! scalar instance's IEEE operations in the same order, so its numbers are
//! the scalar ones bit for bit (`points_tests.rs`).

use crate::render::lanes::{Real, Vector};
use crate::render::math::{basis, sincos_turns};
use std::f32::consts::PI;

/// The point of triangle (p0, p0 + e1, p0 + e2) that uniform numbers
/// `u1`, `u2` map to, uniformly by area.
#[inline(always)]
pub fn triangle_point<V: Vector>(p0: V, e1: V, e2: V, u1: V::R, u2: V::R) -> V {
    let r = u1.sqrt();
    let (b1, b2) = (<V::R as Real>::splat(1.0) - r, u2 * r);
    p0 + e1 * b1 + e2 * b2
}

/// The point `corner + edge_u a + edge_v b` of a parallelogram.
#[inline(always)]
pub fn quad_point<V: Vector>(corner: V, edge_u: V, edge_v: V, a: V::R, b: V::R) -> V {
    corner + edge_u * a + edge_v * b
}

/// The unit direction from `p` to `q`, a point drawn uniformly on a
/// surface of unit normal `n` and area `area`, and 1/pdf of it in solid
/// angle; the mask is zero in the lanes where `q` is `p` (no direction).
#[inline(always)]
pub fn toward_point<V: Vector>(p: V, q: V, n: V, area: V::R) -> (V, V::R, <V::R as Real>::Bits) {
    let w = q - p;
    let dist2 = w.length_squared();
    let dir = w / dist2.sqrt();
    (
        dir,
        flat_weight(n, dir, area, dist2),
        dist2.gt(<V::R as Real>::splat(0.0)),
    )
}

/// 1/pdf in solid angle of unit direction `dir` towards a point `dist2`
/// (squared) away, drawn uniformly by area on a flat emitter of unit
/// normal `n` and area `area`: what sampling returns and what the density
/// for MIS (`Emitter::pdf_direction`) inverts.
#[inline(always)]
pub fn flat_weight<V: Vector>(n: V, dir: V, area: V::R, dist2: V::R) -> V::R {
    n.dot(dir).abs() * area / dist2
}

/// [`flat_weight`] for a point drawn uniformly on a sphere of squared
/// radius `r2`, `m` its unit normal there.
#[inline(always)]
pub fn sphere_weight<V: Vector>(m: V, dir: V, r2: V::R, dist2: V::R) -> V::R {
    let c = <V::R as Real>::splat;
    m.dot(dir).abs() * c(4.0) * c(PI) * r2 / dist2
}

/// A unit direction uniformly within the cone about unit `axis` whose
/// 1 - cos(half-angle) is `one_minus_cos` (1/pdf: 2 pi `one_minus_cos`).
#[inline(always)]
pub fn in_cone<V: Vector>(axis: V, one_minus_cos: V::R, u1: V::R, u2: V::R) -> V {
    let c = <V::R as Real>::splat;
    let a = u1 * one_minus_cos;
    let cos_t = c(1.0) - a;
    let sin_t = (a * (c(2.0) - a)).max(c(0.0)).sqrt();
    let (sin, cos) = sincos_turns(u2);
    let (t, b) = basis(axis);
    t * (sin_t * cos) + b * (sin_t * sin) + axis * cos_t
}

/// From `p` inside the sphere (`center`, radius `radius`, its square
/// `r2`): the unit direction towards a point drawn uniformly on the
/// sphere, and 1/pdf of it in solid angle; the mask is zero in the lanes
/// where that point is `p`.
#[inline(always)]
pub fn toward_sphere_point<V: Vector>(
    (center, radius, r2): (V, V::R, V::R),
    p: V,
    u1: V::R,
    u2: V::R,
) -> (V, V::R, <V::R as Real>::Bits) {
    let c = <V::R as Real>::splat;
    let z = c(1.0) - c(2.0) * u1;
    let rxy = (c(1.0) - z * z).max(c(0.0)).sqrt();
    let (sin, cos) = sincos_turns(u2);
    let m = V::new(rxy * cos, rxy * sin, z);
    let w = center + m * radius - p;
    let dist2 = w.length_squared();
    let dir = w / dist2.sqrt();
    (dir, sphere_weight(m, dir, r2, dist2), dist2.gt(c(0.0)))
}

#[cfg(test)]
#[path = "points_tests.rs"]
mod tests;
