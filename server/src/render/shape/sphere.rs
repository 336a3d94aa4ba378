//! Ray/sphere intersection that stays accurate in f32 for spheres far larger
//! than the scene (smallpt's radius-1e5 walls).
//!
//! The naive test solves t^2 + 2bt + |o-c|^2 - r^2 = 0 with o-c rounded to
//! f32: for a radius-1e5 wall that rounding alone is ~4e-3 units, and the
//! cancellation in |o-c|^2 - r^2 (two numbers near 1e10) loses every digit
//! that matters. Here the constant term is evaluated as
//!     C = o.o - 2 o.c + K,   K = |c|^2 - r^2 computed once in f64,
//! whose terms are at most |o||c| in size: with o within the scene (the
//! renderer works camera-relative, so |o| is the scene's size, not its
//! distance from the world origin) the error of C is ~eps |o| |c| and the
//! hit distance C/q is off by ~eps |o| |c| / (2r) ~ eps |o| for a wall: the
//! rounding of the hit point itself. Roots use the stable pair q, C/q.

use crate::render::math::{DVec3, Vec3A};
use crate::render::ray::Ray;

/// Which intersections of a sphere a ray may report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Roots {
    /// The nearest one in front of the origin.
    Any,
    /// Only the far one: the ray starts on this sphere and goes into it.
    FarOnly,
}

#[derive(Clone, Copy, Debug)]
pub struct Sphere {
    pub center: Vec3A,
    pub radius: f32,
    pub inv_radius: f32,
    /// |c|^2 - r^2, evaluated in f64 before rounding.
    pub k: f32,
}

impl Sphere {
    /// `center` is already relative to the render origin.
    pub fn new(center: DVec3, radius: f64) -> Self {
        Self {
            center: center.as_vec3().into(),
            radius: radius as f32,
            inv_radius: (1.0 / radius) as f32,
            k: (center.length_squared() - radius * radius) as f32,
        }
    }

    /// Distance along `ray` to the chosen root, or infinity.
    #[inline]
    pub fn intersect(&self, ray: &Ray, roots: Roots) -> f32 {
        let b = ray.od - ray.dir.dot(self.center);
        let c = (ray.oo + self.k) - 2.0 * ray.origin.dot(self.center);
        let disc = b * b - c;
        if disc < 0.0 {
            return f32::INFINITY;
        }
        let s = disc.sqrt();
        let q = if b > 0.0 { -(b + s) } else { s - b };
        let other = c / q;
        let (t0, t1) = if q < other { (q, other) } else { (other, q) };
        match roots {
            Roots::Any if t0 > 0.0 => t0,
            _ if t1 > 0.0 => t1,
            _ => f32::INFINITY,
        }
    }

    /// Outward unit normal at a point on the surface.
    #[inline(always)]
    pub fn normal(&self, p: Vec3A) -> Vec3A {
        (p - self.center) * self.inv_radius
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Sampler;

    /// Exact (f64, relative to the true centre) distance to the near root.
    fn reference(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
        let f = o - c;
        let b = f.dot(d);
        let cc = (f.length() - r) * (f.length() + r);
        let disc = b * b - cc;
        if disc < 0.0 {
            return None;
        }
        let q = -b - b.signum() * disc.sqrt();
        let (t0, t1) = (q.min(cc / q), q.max(cc / q));
        [t0, t1].into_iter().find(|t| *t > 0.0)
    }

    /// The textbook f32 test, to show that the check below can tell.
    fn naive(o: Vec3A, d: Vec3A, c: Vec3A, r: f32) -> f32 {
        let f = o - c;
        let b = f.dot(d);
        let disc = b * b - (f.dot(f) - r * r);
        if disc < 0.0 {
            return f32::INFINITY;
        }
        let s = disc.sqrt();
        if -b - s > 0.0 {
            -b - s
        } else {
            -b + s
        }
    }

    /// How far the point at distance `t` along the ray lies from the sphere's
    /// surface, evaluated in f64 with the true centre.
    fn off_surface(o: DVec3, d: DVec3, t: f32, c: DVec3, r: f64) -> f64 {
        ((o + d * f64::from(t) - c).length() - r).abs()
    }

    #[test]
    fn smallpt_wall_hits_lie_within_1e4_of_the_surface() {
        // Rays from random points inside smallpt's box (camera-relative, as the
        // renderer sees them) in random directions, against the six walls.
        let camera = DVec3::new(50.0, 52.0, 295.6);
        let walls = [
            (DVec3::new(1e5 + 1.0, 40.8, 81.6), 1e5),
            (DVec3::new(-1e5 + 99.0, 40.8, 81.6), 1e5),
            (DVec3::new(50.0, 40.8, 1e5), 1e5),
            (DVec3::new(50.0, 40.8, -1e5 + 170.0), 1e5),
            (DVec3::new(50.0, 1e5, 81.6), 1e5),
            (DVec3::new(50.0, -1e5 + 81.6, 81.6), 1e5),
        ];
        let (mut worst, mut naive_errors) = (0.0f64, Vec::new());
        for i in 0..20_000u64 {
            let mut s = Sampler::new(3, i, 0);
            let o = DVec3::new(
                1.0 + 98.0 * f64::from(s.next_f32()),
                81.6 * f64::from(s.next_f32()),
                170.0 * f64::from(s.next_f32()),
            );
            let z = 1.0 - 2.0 * f64::from(s.next_f32());
            let phi = std::f64::consts::TAU * f64::from(s.next_f32());
            let rxy = (1.0 - z * z).sqrt();
            let d = DVec3::new(rxy * phi.cos(), rxy * phi.sin(), z);
            // Round the ray to f32 first so that only the test itself differs.
            let (of, df) = ((o - camera).as_vec3(), d.as_vec3().normalize());
            let (o64, d64) = (of.as_dvec3() + camera, df.as_dvec3());
            for (c, r) in walls {
                let Some(exact) = reference(o64, d64, c, r) else {
                    continue;
                };
                if exact > 1e3 {
                    continue; // beyond the box: another wall is nearer
                }
                let sphere = Sphere::new(c - camera, r);
                let t = sphere.intersect(&Ray::new(of.into(), df.into()), Roots::Any);
                assert!(t.is_finite(), "missed a wall at distance {exact}");
                worst = worst.max(off_surface(o64, d64, t, c, r));
                let tn = naive(
                    of.into(),
                    df.into(),
                    (c - camera).as_vec3().into(),
                    r as f32,
                );
                naive_errors.push(if tn.is_finite() {
                    off_surface(o64, d64, tn, c, r)
                } else {
                    f64::INFINITY
                });
            }
        }
        assert!(worst < 1e-4, "worst error {worst}");
        naive_errors.sort_by(f64::total_cmp);
        let median = naive_errors[naive_errors.len() / 2];
        assert!(
            median > 1e-3,
            "the naive test should be visibly worse, median {median}"
        );
    }

    #[test]
    fn inside_and_outside_and_far_root() {
        let s = Sphere::new(DVec3::ZERO, 2.0);
        let out = Ray::new(Vec3A::new(0.0, 0.0, 5.0), -Vec3A::Z);
        assert!((s.intersect(&out, Roots::Any) - 3.0).abs() < 1e-6);
        assert!((s.intersect(&out, Roots::FarOnly) - 7.0).abs() < 1e-6);
        let inside = Ray::new(Vec3A::ZERO, Vec3A::X);
        assert!((s.intersect(&inside, Roots::Any) - 2.0).abs() < 1e-6);
        let away = Ray::new(Vec3A::new(0.0, 0.0, 5.0), Vec3A::Z);
        assert_eq!(s.intersect(&away, Roots::Any), f32::INFINITY);
        let miss = Ray::new(Vec3A::new(0.0, 3.0, 5.0), -Vec3A::Z);
        assert_eq!(s.intersect(&miss, Roots::Any), f32::INFINITY);
    }
}
