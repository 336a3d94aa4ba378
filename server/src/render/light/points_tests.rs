//! Every lane of the emitter points and directions against the scalar
//! instance, bit for bit (and the masks against the scalar tests).

use super::*;
use crate::render::lanes::{F32s, V3};
use crate::render::math::Vec3A;
use crate::render::sampler::Sampler;

/// `N` draws of `f`, as lanes and as the scalar values.
fn lanes<const N: usize, T: Copy>(mut f: impl FnMut() -> T) -> [T; N] {
    std::array::from_fn(|_| f())
}

fn wide<const N: usize>(v: [Vec3A; N]) -> V3<F32s<N>> {
    V3 {
        x: F32s(v.map(|a| a.x)),
        y: F32s(v.map(|a| a.y)),
        z: F32s(v.map(|a| a.z)),
    }
}

fn lane<const N: usize>(v: V3<F32s<N>>, k: usize) -> Vec3A {
    Vec3A::new(v.x.0[k], v.y.0[k], v.z.0[k])
}

/// The same bits (NaN payloads included).
fn same(a: Vec3A, b: Vec3A) -> bool {
    a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)
}

/// A point in a 200-unit box, a unit vector, a number in [0, 1).
struct Draw(Sampler);

impl Draw {
    fn point(&mut self) -> Vec3A {
        let s = &mut self.0;
        Vec3A::new(s.next_f32(), s.next_f32(), s.next_f32()) * 200.0 - Vec3A::splat(100.0)
    }
    fn unit(&mut self) -> Vec3A {
        (self.point() + Vec3A::splat(1e-3)).normalize()
    }
    fn u(&mut self) -> f32 {
        self.0.next_f32()
    }
}

fn check<const N: usize>(key: u64) {
    let mut d = Draw(Sampler::new(7, key, 0));
    let (p, q, e1, e2) = (
        lanes::<N, _>(|| d.point()),
        lanes::<N, _>(|| d.point()),
        lanes::<N, _>(|| d.point()),
        lanes::<N, _>(|| d.point()),
    );
    let mut q = q;
    q[0] = p[0]; // a point on the receiver itself: no direction
    let (n, axis) = (lanes::<N, _>(|| d.unit()), lanes::<N, _>(|| d.unit()));
    let (u1, u2, s) = (
        lanes::<N, _>(|| d.u()),
        lanes::<N, _>(|| d.u()),
        lanes::<N, _>(|| d.u() * 50.0),
    );
    let (wp, wq, we1, we2, wn, wa) = (wide(p), wide(q), wide(e1), wide(e2), wide(n), wide(axis));
    let (wu1, wu2, ws) = (F32s(u1), F32s(u2), F32s(s));

    let tri = triangle_point(wp, we1, we2, wu1, wu2);
    let quad = quad_point(wp, we1, we2, wu1, wu2);
    let (dir, weight, found) = toward_point(wp, wq, wn, ws);
    let cone = in_cone(wa, wu1, wu1, wu2);
    let (sdir, sweight, sfound) = toward_sphere_point((wq, ws, ws * ws), wp, wu1, wu2);
    for k in 0..N {
        let at = format!("lane {k} of {N}, key {key}");
        let one = triangle_point(p[k], e1[k], e2[k], u1[k], u2[k]);
        assert!(same(lane(tri, k), one), "triangle point, {at}");
        let one = quad_point(p[k], e1[k], e2[k], u1[k], u2[k]);
        assert!(same(lane(quad, k), one), "quad point, {at}");
        let (d1, w1, f1) = toward_point(p[k], q[k], n[k], s[k]);
        assert_eq!(found.0[k], f1, "toward_point's mask, {at}");
        assert_eq!(f1 != 0, k != 0, "toward_point's mask, {at}");
        if f1 != 0 {
            assert!(same(lane(dir, k), d1), "toward_point's direction, {at}");
            assert_eq!(weight.0[k].to_bits(), w1.to_bits(), "toward_point, {at}");
        }
        let one = in_cone(axis[k], u1[k], u1[k], u2[k]);
        assert!(same(lane(cone, k), one), "in_cone, {at}");
        let (d1, w1, f1) = toward_sphere_point((q[k], s[k], s[k] * s[k]), p[k], u1[k], u2[k]);
        assert_eq!(sfound.0[k], f1, "toward_sphere_point's mask, {at}");
        if f1 != 0 {
            assert!(same(lane(sdir, k), d1), "toward_sphere_point, {at}");
            assert_eq!(
                sweight.0[k].to_bits(),
                w1.to_bits(),
                "toward_sphere_point, {at}"
            );
        }
    }
}

#[test]
fn every_lane_of_the_emitter_points_is_the_scalar_one() {
    for key in 0..5_000u64 {
        check::<8>(key);
        check::<16>(key);
    }
}

#[test]
fn the_points_lie_where_they_should() {
    let mut d = Draw(Sampler::new(9, 0, 0));
    for _ in 0..10_000 {
        let (p0, e1, e2, u1, u2) = (d.point(), d.point(), d.point(), d.u(), d.u());
        // Barycentric weights of the triangle point are in [0, 1] and sum
        // to at most 1: it lies in the triangle.
        let r = u1.sqrt();
        let (b1, b2) = (1.0 - r, u2 * r);
        assert!((0.0..=1.0).contains(&b1) && (0.0..=1.0).contains(&b2) && b1 + b2 <= 1.0 + 1e-6);
        let t = triangle_point(p0, e1, e2, u1, u2);
        assert!((t - (p0 + e1 * b1 + e2 * b2)).length() < 1e-3);
        // A cone direction is a unit vector within the cone's angle.
        let (axis, omc) = (d.unit(), d.u() * 2.0);
        let w = in_cone(axis, omc, u1, u2);
        assert!((w.length() - 1.0).abs() < 1e-5, "{w}");
        assert!(
            1.0 - w.dot(axis) <= omc + 1e-5,
            "1 - cos {} > {omc}",
            1.0 - w.dot(axis)
        );
        // A sphere point from its centre is one radius away, and its
        // weight is the sphere's area over r^2 (cos 1): 4 pi.
        let (c, radius) = (d.point(), 1.0 + d.u() * 10.0);
        let (dir, weight, found) = toward_sphere_point((c, radius, radius * radius), c, u1, u2);
        assert_ne!(found, 0);
        assert!((dir.length() - 1.0).abs() < 1e-5);
        assert!((weight / (4.0 * PI) - 1.0).abs() < 1e-4, "weight {weight}");
    }
}
