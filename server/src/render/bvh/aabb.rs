//! Axis-aligned boxes in f32.

use crate::render::math::{DAffine3, DVec3, Vec3A};

/// An axis-aligned box; the default (and [`Aabb::EMPTY`]) is inverted, so
/// that growing it by anything gives that thing's box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    pub fn new(min: Vec3A, max: Vec3A) -> Self {
        Self { min, max }
    }

    /// The box of some points.
    pub fn of_points(points: impl IntoIterator<Item = Vec3A>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.with_point(p))
    }

    #[inline]
    pub fn with_point(self, p: Vec3A) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    #[inline]
    pub fn extent(&self) -> Vec3A {
        self.max - self.min
    }

    #[inline]
    pub fn centroid(&self) -> Vec3A {
        (self.min + self.max) * 0.5
    }

    /// Half the surface area (all the heuristic needs); 0 for an empty box.
    #[inline]
    pub fn half_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    /// The box grown by `margin` on every side.
    pub fn padded(&self, margin: f32) -> Self {
        Self {
            min: self.min - Vec3A::splat(margin),
            max: self.max + Vec3A::splat(margin),
        }
    }

    /// Whether `p` lies inside or on the box.
    pub fn contains(&self, p: Vec3A) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

impl Aabb {
    /// The f64 bounds of this box's eight corners mapped by `a` (an
    /// object-space box placed in the world).
    pub fn transformed(&self, a: &DAffine3) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for i in 0..8 {
            let pick = |bit: usize, axis: usize| {
                f64::from(if i >> bit & 1 == 0 {
                    self.min[axis]
                } else {
                    self.max[axis]
                })
            };
            let p = a.transform_point3(DVec3::new(pick(0, 0), pick(1, 1), pick(2, 2)));
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }
}
