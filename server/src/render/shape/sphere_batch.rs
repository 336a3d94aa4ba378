//! Four spheres tested against one ray at once (SSE lanes). Same arithmetic
//! as `Sphere::intersect` with `Roots::Any`, lane by lane; the square root
//! and division that dominate the scalar test cost the same for four.

use crate::render::math::{BVec4A, Vec4};
use crate::render::ray::Ray;
use crate::render::shape::Sphere;

#[derive(Clone, Copy, Debug)]
pub struct SphereBatch {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    k: Vec4,
}

impl SphereBatch {
    /// Up to four spheres; missing lanes never hit.
    pub fn new(spheres: &[Sphere]) -> Self {
        let lane = |i: usize| spheres.get(i);
        let get = |f: fn(&Sphere) -> f32, empty: f32| {
            Vec4::from_array(std::array::from_fn(|i| lane(i).map_or(empty, f)))
        };
        Self {
            cx: get(|s| s.center.x, 0.0),
            cy: get(|s| s.center.y, 0.0),
            cz: get(|s| s.center.z, 0.0),
            // C = +inf makes the discriminant negative: an empty lane misses.
            k: get(|s| s.k, f32::INFINITY),
        }
    }

    /// Distance to each sphere's nearest intersection in front of the ray
    /// origin, infinity where there is none; lanes set in `far_only` report
    /// only the far intersection (`Roots::FarOnly`).
    #[inline]
    pub fn intersect(&self, ray: &Ray, far_only: BVec4A) -> Vec4 {
        let (dx, dy, dz) = (Vec4::splat(ray.dir.x), Vec4::splat(ray.dir.y), Vec4::splat(ray.dir.z));
        let (ox, oy, oz) = (
            Vec4::splat(ray.origin.x),
            Vec4::splat(ray.origin.y),
            Vec4::splat(ray.origin.z),
        );
        let dc = dx * self.cx + dy * self.cy + dz * self.cz;
        let oc = ox * self.cx + oy * self.cy + oz * self.cz;
        let b = Vec4::splat(ray.od) - dc;
        let c = (Vec4::splat(ray.oo) + self.k) - oc * 2.0;
        let disc = b * b - c;
        let s = disc.max(Vec4::ZERO).sqrt();
        // q = -(b + sign(b) s): the root pair q, c/q without cancellation.
        let q = -(b + s.copysign(b));
        let other = c / q;
        let t0 = q.min(other);
        let t1 = q.max(other);
        let t = Vec4::select(t0.cmpgt(Vec4::ZERO) & !far_only, t0, t1);
        Vec4::select(t.cmpgt(Vec4::ZERO) & disc.cmpge(Vec4::ZERO), t, Vec4::splat(f32::INFINITY))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::math::{DVec3, Vec3A};
    use crate::render::sampler::Sampler;
    use crate::render::shape::Roots;

    #[test]
    fn agrees_with_the_scalar_test() {
        let spheres = [
            Sphere::new(DVec3::new(0.0, 0.0, -5.0), 1.0),
            Sphere::new(DVec3::new(1e5 + 1.0, 0.0, 0.0), 1e5),
            Sphere::new(DVec3::new(0.5, 0.2, 0.1), 3.0),
        ];
        let batch = SphereBatch::new(&spheres);
        for i in 0..10_000u64 {
            let mut s = Sampler::new(1, i, 0);
            let o = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 4.0;
            let d = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5).normalize();
            let ray = Ray::new(o, d);
            for (mask, roots) in [(BVec4A::FALSE, Roots::Any), (BVec4A::TRUE, Roots::FarOnly)] {
                let t = batch.intersect(&ray, mask).to_array();
                for (lane, sphere) in spheres.iter().enumerate() {
                    let scalar = sphere.intersect(&ray, roots);
                    let close = t[lane] == scalar || (t[lane] - scalar).abs() <= 1e-5 * scalar.abs();
                    assert!(close, "lane {lane} {roots:?}: {} vs {scalar}", t[lane]);
                }
                assert_eq!(t[3], f32::INFINITY);
            }
        }
    }
}
