//! Ray/parallelogram intersection. Two-sided: the normal is only a plane
//! normal; shading faces it towards the incoming ray.

use crate::render::math::{DVec3, Vec3A};
use crate::render::ray::Ray;

#[derive(Clone, Copy, Debug)]
pub struct Quad {
    pub corner: Vec3A,
    pub edge_u: Vec3A,
    pub edge_v: Vec3A,
    /// Unit normal, edge_u x edge_v normalised.
    pub normal: Vec3A,
    /// (u x v) / |u x v|^2: turns cross products into barycentrics.
    pub w: Vec3A,
    pub area: f32,
}

impl Quad {
    /// `corner` is already relative to the render origin.
    pub fn new(corner: DVec3, edge_u: DVec3, edge_v: DVec3) -> Self {
        let n = edge_u.cross(edge_v);
        Self {
            corner: corner.as_vec3().into(),
            edge_u: edge_u.as_vec3().into(),
            edge_v: edge_v.as_vec3().into(),
            normal: n.normalize().as_vec3().into(),
            w: (n / n.length_squared()).as_vec3().into(),
            area: n.length() as f32,
        }
    }

    /// Distance along `ray` to the quad, or infinity.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray) -> f32 {
        self.intersect_before(ray, f32::INFINITY)
    }

    /// Distance along `ray` to the quad if it is below `t_max`, else
    /// infinity: a plane farther than the nearest hit so far skips the
    /// inside test (most of the cost when scanning).
    #[inline(always)]
    pub fn intersect_before(&self, ray: &Ray, t_max: f32) -> f32 {
        let to_corner = self.corner - ray.origin;
        let t = self.normal.dot(to_corner) / self.normal.dot(ray.dir);
        if !(t > 0.0 && t < t_max) {
            return f32::INFINITY;
        }
        let q = ray.dir * t - to_corner;
        let a = self.w.dot(q.cross(self.edge_v));
        let b = self.w.dot(self.edge_u.cross(q));
        if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
            t
        } else {
            f32::INFINITY
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_inside_misses_outside_from_both_sides() {
        let q = Quad::new(DVec3::ZERO, DVec3::X * 2.0, DVec3::Y);
        let down = Ray::new(Vec3A::new(1.0, 0.5, 3.0), -Vec3A::Z);
        assert!((q.intersect(&down) - 3.0).abs() < 1e-6);
        let up = Ray::new(Vec3A::new(1.9, 0.9, -2.0), Vec3A::Z);
        assert!((q.intersect(&up) - 2.0).abs() < 1e-6);
        let outside = Ray::new(Vec3A::new(2.1, 0.5, 3.0), -Vec3A::Z);
        assert_eq!(q.intersect(&outside), f32::INFINITY);
        let parallel = Ray::new(Vec3A::new(1.0, 0.5, 0.0), Vec3A::X);
        assert_eq!(q.intersect(&parallel), f32::INFINITY);
        assert_eq!(q.intersect_before(&down, 3.5), q.intersect(&down));
        assert_eq!(
            q.intersect_before(&down, 3.0),
            f32::INFINITY,
            "not before 3"
        );
        assert!((q.area - 2.0).abs() < 1e-6);
    }
}
