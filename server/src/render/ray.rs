//! A ray in camera-relative f32 space, with the two dot products that every
//! sphere test needs precomputed once per ray.

use crate::render::math::Vec3A;

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3A,
    /// Unit direction.
    pub dir: Vec3A,
    /// origin . origin
    pub oo: f32,
    /// origin . dir
    pub od: f32,
}

impl Ray {
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        Self {
            origin,
            dir,
            oo: origin.dot(origin),
            od: origin.dot(dir),
        }
    }

    #[inline(always)]
    pub fn at(&self, t: f32) -> Vec3A {
        self.origin + self.dir * t
    }
}
