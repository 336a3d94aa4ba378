//! Watertight ray/triangle intersection (Woop, Benthin and Wald 2013) and
//! the error bound of the hit point (pbrt-v4, after Pharr, Jakob and
//! Humphreys, "Physically Based Rendering", 4th ed., 6.8).
//!
//! The ray is turned into a frame where it runs along +z from the origin:
//! axes permuted so that z is its largest direction component, then sheared.
//! A vertex's 2-D position there depends only on the vertex and the ray, so
//! two triangles that share an edge compute that edge's function from the
//! same numbers, with opposite signs exactly: a ray through the edge is
//! inside one of them (or on the edge of both, which both accept). No ray
//! slips between them.
//!
//! Edge functions that come out zero are recomputed in f64 (the paper's
//! fallback): far from a small triangle, f32 products can cancel to an
//! exact zero that would accept a ray passing nowhere near it.
//!
//! The shear is written as three dot products with rows that hold one or
//! two non-zero entries (the other products are exact zeros), so it rounds
//! exactly as the paper's `A[kx] - Sx * A[kz]`.

use crate::render::bvh::Aabb;
use crate::render::math::{gamma, Vec3A};
use bytemuck::{Pod, Zeroable};

/// A triangle's vertices as a mesh stores them in leaf order; `v0[3]`
/// holds the triangle's index in the mesh (as bits).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TriVerts {
    pub v0: [f32; 4],
    pub v1: [f32; 4],
    pub v2: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<TriVerts>() == 48);

impl TriVerts {
    pub fn new(index: u32, [a, b, c]: [[f32; 3]; 3]) -> Self {
        Self {
            v0: [a[0], a[1], a[2], f32::from_bits(index)],
            v1: [b[0], b[1], b[2], 0.0],
            v2: [c[0], c[1], c[2], 0.0],
        }
    }

    /// The triangle's index in its mesh.
    #[inline(always)]
    pub fn index(&self) -> u32 {
        self.v0[3].to_bits()
    }

    #[inline(always)]
    pub fn vertices(&self) -> [Vec3A; 3] {
        let v = |a: &[f32; 4]| Vec3A::new(a[0], a[1], a[2]);
        [v(&self.v0), v(&self.v1), v(&self.v2)]
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::of_points(self.vertices())
    }
}

/// A ray prepared for the watertight test.
#[derive(Clone, Copy, Debug)]
pub struct TriRay {
    pub origin: Vec3A,
    /// Rows of the permute-and-shear map: x' = row_x . v, y' = row_y . v,
    /// z' = row_z . v for v relative to the origin.
    pub(super) row_x: Vec3A,
    pub(super) row_y: Vec3A,
    pub(super) row_z: Vec3A,
}

impl TriRay {
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let a = dir.abs();
        let kz = if a.x > a.y && a.x > a.z {
            0
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (mut kx, mut ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Keep the frame's handedness, so that the edge functions' signs
        // keep their meaning.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        const UNIT: [Vec3A; 3] = [Vec3A::X, Vec3A::Y, Vec3A::Z];
        // One vector division: the same bits as three scalar ones.
        let d = dir.to_array();
        let s = Vec3A::new(d[kx], d[ky], 1.0) / Vec3A::splat(d[kz]);
        Self {
            origin,
            row_x: UNIT[kx] - UNIT[kz] * s.x,
            row_y: UNIT[ky] - UNIT[kz] * s.y,
            row_z: UNIT[kz] * s.z,
        }
    }

    /// The same ray (direction) from `origin`: what a ray becomes in the
    /// space of a mesh placed by a translation alone, without redoing the
    /// direction's permutation, shear and divisions.
    #[inline(always)]
    pub fn from_origin(&self, origin: Vec3A) -> Self {
        Self { origin, ..*self }
    }

    /// Distance to the triangle (in units of the ray's direction) if the
    /// ray meets it after 0 and not beyond `t_max` (a hit at `t_max` itself
    /// counts, so that [`crate::render::world::Hit`]'s tie rule sees it), with the barycentric
    /// weights of its three vertices at the hit.
    #[inline(always)]
    pub fn intersect(&self, [p0, p1, p2]: [Vec3A; 3], t_max: f32) -> Option<(f32, [f32; 3])> {
        let (a, b, c) = (p0 - self.origin, p1 - self.origin, p2 - self.origin);
        let (ax, ay) = (self.row_x.dot(a), self.row_y.dot(a));
        let (bx, by) = (self.row_x.dot(b), self.row_y.dot(b));
        let (cx, cy) = (self.row_x.dot(c), self.row_y.dot(c));
        let (mut u, mut v, mut w) = (cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax);
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Cancellation may have made a non-zero edge function zero
            // (which would accept a ray far from the triangle): recompute
            // in f64, where products of f32s are exact. Shared edges still
            // get exactly opposite values.
            let e = |p: f32, q: f32, r: f32, s: f32| {
                (f64::from(p) * f64::from(q) - f64::from(r) * f64::from(s)) as f32
            };
            (u, v, w) = (e(cx, by, cy, bx), e(ax, cy, ay, cx), e(bx, ay, by, ax));
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * self.row_z.dot(a) + v * self.row_z.dot(b) + w * self.row_z.dot(c);
        let t = t_scaled / det;
        if !(t > 0.0 && t <= t_max) {
            return None;
        }
        let inv = 1.0 / det;
        Some((t, [u * inv, v * inv, w * inv]))
    }
}

/// The point with barycentric weights `b` and a bound on its distance from
/// the true intersection, per axis (pbrt-v4: gamma(7) times the sum of
/// the terms' magnitudes).
#[inline(always)]
pub fn hit_point([p0, p1, p2]: [Vec3A; 3], b: [f32; 3]) -> (Vec3A, Vec3A) {
    let (t0, t1, t2) = (p0 * b[0], p1 * b[1], p2 * b[2]);
    let p = t0 + t1 + t2;
    let err = (t0.abs() + t1.abs() + t2.abs()) * gamma(7);
    (p, err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Sampler;

    fn tri() -> [Vec3A; 3] {
        [
            Vec3A::new(0.0, 0.0, 0.0),
            Vec3A::new(2.0, 0.0, 0.0),
            Vec3A::new(0.0, 2.0, 0.0),
        ]
    }

    #[test]
    fn hits_from_both_sides_and_reports_barycentrics() {
        for (o, d) in [
            (Vec3A::new(0.5, 0.5, 3.0), -Vec3A::Z),
            (Vec3A::new(0.5, 0.5, -3.0), Vec3A::Z),
        ] {
            let (t, b) = TriRay::new(o, d)
                .intersect(tri(), f32::INFINITY)
                .expect("hit");
            assert!((t - 3.0).abs() < 1e-6);
            assert!(
                (b[0] - 0.5).abs() < 1e-6
                    && (b[1] - 0.25).abs() < 1e-6
                    && (b[2] - 0.25).abs() < 1e-6,
                "{b:?}"
            );
        }
        let r = TriRay::new(Vec3A::new(1.5, 1.5, 3.0), -Vec3A::Z);
        assert!(
            r.intersect(tri(), f32::INFINITY).is_none(),
            "outside the hypotenuse"
        );
        let r = TriRay::new(Vec3A::new(0.5, 0.5, 3.0), -Vec3A::Z);
        assert!(r.intersect(tri(), 2.9).is_none(), "beyond t_max");
        let r = TriRay::new(Vec3A::new(0.5, 0.5, 3.0), Vec3A::Z);
        assert!(
            r.intersect(tri(), f32::INFINITY).is_none(),
            "behind the origin"
        );
        let r = TriRay::new(Vec3A::new(-1.0, 0.5, 0.0), Vec3A::X);
        assert!(
            r.intersect(tri(), f32::INFINITY).is_none(),
            "in the triangle's plane"
        );
    }

    #[test]
    fn a_far_ray_whose_edge_functions_cancel_to_zero_in_f32_misses() {
        // Found by the BVH test: 2e4 away, the f32 edge functions of this
        // triangle cancel to 0, 0, -2, which the sign rule alone accepts.
        let o = Vec3A::new(2424.916, 6097.2104, -2434.6968);
        let d = Vec3A::new(-0.117406696, 0.06857674, -0.0013892017);
        let v = [
            Vec3A::new(0.0, 0.27326652, 0.9619384),
            Vec3A::new(0.26286554, 0.16245985, 0.95105654),
            Vec3A::new(0.25989193, 0.43388855, 0.86266845),
        ];
        assert_eq!(TriRay::new(o, d).intersect(v, f32::INFINITY), None);
    }

    #[test]
    fn rays_through_a_shared_edge_hit_one_of_the_two_triangles() {
        // Two triangles sharing the edge (a, c) of a planar quad at an odd
        // angle, and rays aimed at points of that edge from random origins.
        // (Off the plane every such ray sees the two on either side of the
        // edge; a fold would have silhouettes that rays may rightly graze.)
        let (a, b, c) = (
            Vec3A::new(0.1, 0.2, 0.3),
            Vec3A::new(3.7, -0.4, 1.1),
            Vec3A::new(2.9, 3.3, -0.7),
        );
        let d = a + (c - b) * 0.9 + (a - b) * 0.3;
        let (first, second) = ([a, b, c], [a, c, d]);
        for i in 0..100_000u64 {
            let mut s = Sampler::new(5, i, 0);
            let on_edge = a + (c - a) * s.next_f32();
            let o = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 40.0;
            let r = TriRay::new(o, (on_edge - o).normalize());
            let hits = [first, second]
                .iter()
                .filter(|t| r.intersect(**t, f32::INFINITY).is_some())
                .count();
            let plane = (b - a).cross(c - a);
            if plane.dot(o - a).abs() > 1e-3 {
                assert!(hits >= 1, "ray {i} slipped through the shared edge");
            }
        }
    }

    #[test]
    fn hit_point_error_bound_covers_the_exact_point() {
        let t = [
            Vec3A::new(1e3, 2e3, -5e2),
            Vec3A::new(1e3 + 1.0, 2e3, -5e2),
            Vec3A::new(1e3, 2e3 + 1.0, -5e2 + 0.5),
        ];
        for i in 0..10_000u64 {
            let mut s = Sampler::new(9, i, 0);
            let (u, v) = (s.next_f32(), s.next_f32());
            let (u, v) = if u + v > 1.0 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let b = [1.0 - u - v, u, v];
            let (p, err) = hit_point(t, b);
            for k in 0..3 {
                let exact: f64 = (0..3).map(|j| f64::from(t[j][k]) * f64::from(b[j])).sum();
                assert!(
                    (f64::from(p[k]) - exact).abs() <= f64::from(err[k]),
                    "axis {k}"
                );
            }
        }
    }
}
