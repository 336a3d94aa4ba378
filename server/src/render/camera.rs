//! Pinhole camera in the camera-relative frame (the camera sits at the
//! origin; see `render::world`).
//!
//! Raster (x right, y down, in pixels) maps to a direction
//!     forward + right * (x/w - 1/2) + up * (1/2 - y/h)
//! where |up| = 2 tan(vfov/2) and |right| = |up| * w/h; the ray starts
//! `near_clip` along itself (on a sphere around the camera, not a plane),
//! as smallpt's camera does: it normalises the direction, then pushes the
//! origin 140 units out along it. (A plane would start the top row of
//! smallpt's image above its ceiling, seeing the light.)

use crate::render::math::{DVec3, Vec3A};
use crate::render::ray::Ray;
use crate::render::scene::Camera;

#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    pub width: u32,
    pub height: u32,
    /// Unit view direction.
    pub forward: Vec3A,
    /// Spans the image plane's width at distance 1.
    pub right: Vec3A,
    /// Spans the image plane's height at distance 1.
    pub up: Vec3A,
    pub near_clip: f32,
    inv_width: f32,
    inv_height: f32,
}

impl CameraRays {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.look_at - camera.position).normalize();
        let right_unit = forward.cross(camera.up).normalize();
        let up_unit = right_unit.cross(forward);
        let extent = 2.0 * (camera.vfov_deg.to_radians() * 0.5).tan();
        let aspect = f64::from(width) / f64::from(height);
        let f = |v: DVec3| -> Vec3A { v.as_vec3().into() };
        Self {
            width,
            height,
            forward: f(forward),
            right: f(right_unit * (extent * aspect)),
            up: f(up_unit * extent),
            near_clip: camera.near_clip as f32,
            inv_width: 1.0 / width as f32,
            inv_height: 1.0 / height as f32,
        }
    }

    /// The ray through raster position (`x`, `y`).
    #[inline(always)]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let d = (self.forward
            + self.right * (x * self.inv_width - 0.5)
            + self.up * (0.5 - y * self.inv_height))
            .normalize();
        Ray::new(d * self.near_clip, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_and_corners_follow_the_field_of_view() {
        let cam = Camera {
            position: DVec3::new(1.0, 2.0, 3.0),
            look_at: DVec3::new(1.0, 2.0, 2.0),
            up: DVec3::Y,
            vfov_deg: 90.0,
            near_clip: 0.0,
        };
        let rays = CameraRays::new(&cam, 200, 100);
        let centre = rays.ray(100.0, 50.0);
        assert!((centre.dir - -Vec3A::Z).length() < 1e-6);
        assert_eq!(centre.origin, Vec3A::ZERO);
        // Top edge: 45 degrees up. Right edge: atan(2) to the right (+x).
        let top = rays.ray(100.0, 0.0);
        assert!((top.dir.y - top.dir.z.abs()).abs() < 1e-6 && top.dir.y > 0.0);
        let right = rays.ray(200.0, 50.0);
        assert!((right.dir.x / -right.dir.z - 2.0).abs() < 1e-5);
    }

    #[test]
    fn near_clip_starts_rays_that_far_along_themselves() {
        let cam = Camera {
            position: DVec3::ZERO,
            look_at: DVec3::new(0.0, 0.0, -1.0),
            up: DVec3::Y,
            vfov_deg: 60.0,
            near_clip: 140.0,
        };
        let rays = CameraRays::new(&cam, 64, 64);
        for (x, y) in [(0.0, 0.0), (63.0, 10.0), (32.0, 32.0)] {
            let r = rays.ray(x, y);
            assert!((r.origin.length() - 140.0).abs() < 1e-3, "{:?}", r.origin);
            assert!((r.origin.normalize() - r.dir).length() < 1e-6);
        }
    }
}
