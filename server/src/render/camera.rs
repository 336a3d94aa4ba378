//! Pinhole or thin-lens camera in the camera-relative frame (the camera
//! sits at the origin; see `render::world`).
//!
//! Raster (x right, y down, in pixels) maps to a direction
//!     forward + right * (x/w - 1/2) + up * (1/2 - y/h)
//! where |up| = 2 tan(vfov/2) and |right| = |up| * w/h; the ray starts
//! `near_clip` along itself (on a sphere around the camera, not a plane),
//! as smallpt's camera does: it normalises the direction, then pushes the
//! origin 140 units out along it. (A plane would start the top row of
//! smallpt's image above its ceiling, seeing the light.)
//!
//! A thin lens (`aperture` > 0, its radius) starts each ray at a point
//! of the lens disc, drawn uniformly (r = sqrt(u1), angle u2 turns) in the
//! plane of `right` and `up`, and aims it at the point the pinhole ray meets
//! on the plane in focus (`focus_distance` along `forward`): points on that
//! plane stay sharp, others blur into discs of the thin-lens circle of
//! confusion. Aperture 0 draws no numbers and gives the pinhole's rays bit
//! for bit.
//!
//! An orthographic camera starts parallel rays along `forward` from the
//! point `right * (x/w - 1/2) + up * (1/2 - y/h)` (|up| is the view's
//! height), moved `near_clip` along them. A panorama maps raster (x, y) to
//! the direction that an environment map's point (x/w, y/h) has
//! ([`map_direction`]) in the frame of `right`, `up` and `-forward` (unit
//! vectors here): its centre column looks along `forward`, its top row up.

use crate::render::envmap::map_direction;
use crate::render::lanes::{Real, Vector};
use crate::render::math::{sincos_turns, DVec3, Vec3A};
use crate::render::ray::Ray;
use crate::render::scene::{Camera, Projection};

/// How [`CameraRays`] makes rays (the kernel's `PROJ_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum RayProjection {
    Perspective = 0,
    Orthographic = 1,
    Panorama = 2,
}

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
    /// The lens radius over |right| and over |up| (0: a pinhole): a lens
    /// point is `right * (lens_x * a) + up * (lens_y * b)` for (a, b) in the
    /// unit disc.
    pub lens_x: f32,
    pub lens_y: f32,
    /// Distance along `forward` of the plane in focus.
    pub focus: f32,
    pub projection: RayProjection,
    inv_width: f32,
    inv_height: f32,
}

impl CameraRays {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.look_at - camera.position).normalize();
        let right_unit = forward.cross(camera.up).normalize();
        let up_unit = right_unit.cross(forward);
        let aspect = f64::from(width) / f64::from(height);
        // The image plane's height: at distance 1, or the orthographic
        // view's own; a panorama keeps unit vectors.
        let (extent, aspect, projection) = match camera.projection {
            Projection::Perspective => (
                2.0 * (camera.vfov_deg.to_radians() * 0.5).tan(),
                aspect,
                RayProjection::Perspective,
            ),
            Projection::Orthographic { height } => (height, aspect, RayProjection::Orthographic),
            Projection::Panorama => (1.0, 1.0, RayProjection::Panorama),
        };
        let f = |v: DVec3| -> Vec3A { v.as_vec3().into() };
        let (lens_x, lens_y) =
            match camera.aperture > 0.0 && projection == RayProjection::Perspective {
                true => (
                    (camera.aperture / (extent * aspect)) as f32,
                    (camera.aperture / extent) as f32,
                ),
                false => (0.0, 0.0),
            };
        Self {
            width,
            height,
            forward: f(forward),
            right: f(right_unit * (extent * aspect)),
            up: f(up_unit * extent),
            near_clip: camera.near_clip as f32,
            lens_x,
            lens_y,
            focus: camera.focus() as f32,
            projection,
            inv_width: 1.0 / width as f32,
            inv_height: 1.0 / height as f32,
        }
    }

    /// Whether rays leave a lens (they need [`CameraRays::lens_ray`]).
    #[inline(always)]
    pub fn has_lens(&self) -> bool {
        self.lens_x > 0.0
    }

    /// The pinhole's direction (not unit) through raster (`x`, `y`): its
    /// component along `forward` is 1.
    #[inline(always)]
    fn through<V: Vector>(&self, x: V::R, y: V::R) -> V {
        let c = <V::R as Real>::splat;
        V::splat_vec(self.forward)
            + V::splat_vec(self.right) * (x * c(self.inv_width) - c(0.5))
            + V::splat_vec(self.up) * (c(0.5) - y * c(self.inv_height))
    }

    /// A perspective camera's ray through raster (`x`, `y`) and its
    /// pinhole: (origin, unit direction), for one path or for lanes.
    #[inline(always)]
    pub fn pinhole<V: Vector>(&self, x: V::R, y: V::R) -> (V, V) {
        let d = self.through::<V>(x, y).normalize();
        (d * <V::R as Real>::splat(self.near_clip), d)
    }

    /// A perspective camera's ray through raster (`x`, `y`) from the lens
    /// point drawn with (`u1`, `u2`) in [0, 1): (origin, unit direction).
    #[inline(always)]
    pub fn through_lens<V: Vector>(&self, x: V::R, y: V::R, u1: V::R, u2: V::R) -> (V, V) {
        let c = <V::R as Real>::splat;
        let r = u1.sqrt();
        let (sin, cos) = sincos_turns(u2);
        let o = V::splat_vec(self.right) * (c(self.lens_x) * (r * cos))
            + V::splat_vec(self.up) * (c(self.lens_y) * (r * sin));
        let d = (self.through::<V>(x, y) * c(self.focus) - o).normalize();
        (o + d * c(self.near_clip), d)
    }

    /// The ray through raster position (`x`, `y`) (a perspective
    /// camera's through its pinhole).
    #[inline(always)]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        match self.projection {
            RayProjection::Perspective => {
                let (o, d) = self.pinhole(x, y);
                Ray::new(o, d)
            }
            RayProjection::Orthographic => {
                let o =
                    self.right * (x * self.inv_width - 0.5) + self.up * (0.5 - y * self.inv_height);
                Ray::new(o + self.forward * self.near_clip, self.forward)
            }
            RayProjection::Panorama => {
                let (m, _) = map_direction(x * self.inv_width, y * self.inv_height);
                let d = (self.right * m.x + self.up * m.y - self.forward * m.z).normalize();
                Ray::new(d * self.near_clip, d)
            }
        }
    }

    /// The ray through raster (`x`, `y`) from the lens point drawn with
    /// (`u1`, `u2`) in [0, 1) (the pinhole's where there is no lens).
    #[inline(always)]
    pub fn lens_ray(&self, x: f32, y: f32, (u1, u2): (f32, f32)) -> Ray {
        if !self.has_lens() {
            return self.ray(x, y);
        }
        let (o, d) = self.through_lens(x, y, u1, u2);
        Ray::new(o, d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::lanes::{F32s, V3};
    use crate::render::sampler::Sampler;

    /// Every lane of the perspective rays (pinhole and lens) is the scalar
    /// ray, bit for bit, for cameras looking every way.
    #[test]
    fn every_lane_of_the_camera_rays_is_the_scalar_one() {
        fn check<const N: usize>(rays: &CameraRays, s: &mut Sampler) {
            let mut lanes = || F32s::<N>(std::array::from_fn(|_| s.next_f32()));
            let (x, y) = (lanes() * F32s([640.0; N]), lanes() * F32s([480.0; N]));
            let (u1, u2) = (lanes(), lanes());
            let (o, d): (V3<F32s<N>>, V3<F32s<N>>) = rays.pinhole(x, y);
            let (lo, ld): (V3<F32s<N>>, V3<F32s<N>>) = rays.through_lens(x, y, u1, u2);
            let bits = |v: Vec3A| v.to_array().map(f32::to_bits);
            let lane = |v: V3<F32s<N>>, k: usize| bits(Vec3A::new(v.x.0[k], v.y.0[k], v.z.0[k]));
            for k in 0..N {
                let one = rays.ray(x.0[k], y.0[k]);
                assert_eq!((lane(o, k), lane(d, k)), (bits(one.origin), bits(one.dir)));
                let (o1, d1) = rays.through_lens(x.0[k], y.0[k], u1.0[k], u2.0[k]);
                assert_eq!((lane(lo, k), lane(ld, k)), (bits(o1), bits(d1)), "lane {k}");
            }
        }
        let mut s = Sampler::new(11, 0, 0);
        for _ in 0..2_000 {
            let mut v = || {
                DVec3::new(
                    s.next_f32().into(),
                    s.next_f32().into(),
                    s.next_f32().into(),
                ) * 20.0
                    - 10.0
            };
            let cam = Camera {
                aperture: 0.2,
                near_clip: 0.5,
                focus_distance: Some(4.0),
                ..Camera::pinhole(v(), v(), 20.0 + 100.0 * f64::from(s.next_f32()))
            };
            let rays = CameraRays::new(&cam, 640, 480);
            check::<8>(&rays, &mut s);
            check::<16>(&rays, &mut s);
        }
    }

    #[test]
    fn centre_and_corners_follow_the_field_of_view() {
        let cam = Camera::pinhole(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 2.0, 2.0), 90.0);
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
            near_clip: 140.0,
            ..Camera::pinhole(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 60.0)
        };
        let rays = CameraRays::new(&cam, 64, 64);
        for (x, y) in [(0.0, 0.0), (63.0, 10.0), (32.0, 32.0)] {
            let r = rays.ray(x, y);
            assert!((r.origin.length() - 140.0).abs() < 1e-3, "{:?}", r.origin);
            assert!((r.origin.normalize() - r.dir).length() < 1e-6);
        }
    }

    #[test]
    fn a_lens_keeps_the_plane_in_focus_sharp_and_blurs_the_rest_by_the_circle_of_confusion() {
        let cam = Camera {
            aperture: 0.1,
            focus_distance: Some(3.0),
            ..Camera::pinhole(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 40.0)
        };
        let rays = CameraRays::new(&cam, 64, 48);
        let pinhole = CameraRays::new(
            &Camera {
                aperture: 0.0,
                ..cam
            },
            64,
            48,
        );
        for (x, y) in [(32.0, 24.0), (3.5, 40.25), (60.0, 2.0)] {
            let p = pinhole.ray(x, y);
            // Where the pinhole ray meets the plane in focus (z = -3).
            let focus_point = p.origin + p.dir * (3.0 / -p.dir.z);
            let mut widest = 0.0f32;
            for i in 0..64 {
                let u = ((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0);
                let r = rays.lens_ray(x, y, u);
                assert!(
                    r.origin.z.abs() < 1e-6,
                    "starts on the lens: {:?}",
                    r.origin
                );
                assert!(r.origin.length() <= 0.1 + 1e-6, "within the aperture");
                let at = r.origin + r.dir * ((3.0 - -r.origin.z) / -r.dir.z);
                assert!(
                    (at - focus_point).length() < 1e-5,
                    "sharp at the focus: {at} vs {focus_point}"
                );
                // At depth 6 the rays spread over the circle of confusion:
                // radius aperture * |6 - 3| / 3 around the pinhole's point.
                let far = r.origin + r.dir * (6.0 / -r.dir.z);
                let centre = p.origin + p.dir * (6.0 / -p.dir.z);
                widest = widest.max((far - centre).length());
            }
            assert!(
                (widest - 0.1).abs() < 0.01,
                "circle of confusion radius {widest}, expected 0.1"
            );
        }
        // Aperture 0: the pinhole, bit for bit, whatever the numbers.
        for (x, y) in [(1.0, 2.0), (31.5, 7.25)] {
            let (a, b) = (pinhole.lens_ray(x, y, (0.3, 0.7)), pinhole.ray(x, y));
            assert_eq!((a.origin, a.dir), (b.origin, b.dir));
        }
    }

    #[test]
    fn orthographic_rays_are_parallel_and_span_the_height() {
        let cam = Camera {
            projection: Projection::Orthographic { height: 4.0 },
            near_clip: 0.5,
            ..Camera::pinhole(DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -1.0), 40.0)
        };
        let rays = CameraRays::new(&cam, 200, 100);
        for (x, y, ox, oy) in [
            (100.0, 50.0, 0.0, 0.0),
            (0.0, 0.0, -4.0, 2.0),
            (200.0, 100.0, 4.0, -2.0),
        ] {
            let r = rays.ray(x, y);
            assert_eq!(r.dir, -Vec3A::Z);
            let want = Vec3A::new(ox, oy, -0.5);
            assert!(
                (r.origin - want).length() < 1e-6,
                "{x}, {y}: {:?}",
                r.origin
            );
        }
    }

    #[test]
    fn a_panorama_looks_everywhere_from_the_centre_column_forward() {
        let cam = Camera {
            projection: Projection::Panorama,
            ..Camera::pinhole(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), 40.0)
        };
        let rays = CameraRays::new(&cam, 64, 32);
        let at = |x: f32, y: f32| rays.ray(x, y).dir;
        for (x, y, want) in [
            (32.0, 16.0, -Vec3A::Z), // centre: forward
            (48.0, 16.0, Vec3A::X),  // a quarter turn right
            (16.0, 16.0, -Vec3A::X), // a quarter turn left
            (0.0, 16.0, Vec3A::Z),   // the seam: behind
            (20.0, 0.0, Vec3A::Y),   // top row: up
            (20.0, 32.0, -Vec3A::Y), // bottom: down
        ] {
            assert!((at(x, y) - want).length() < 1e-6, "{x}, {y}: {}", at(x, y));
        }
        for i in 0..100 {
            let d = at(i as f32 * 0.64, i as f32 * 0.32);
            assert!((d.length() - 1.0).abs() < 1e-6);
        }
    }
}
