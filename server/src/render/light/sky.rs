//! An environment map as an emitter (`render::envmap` holds the image and
//! its tables): scaled by its intensity, turned about +y by its rotation,
//! looked up along world directions, sampled in proportion to its
//! brightness, with the density multiple importance sampling weighs.

use crate::render::envmap::{map_direction, map_uv, EnvMap, TWO_PI2};
use crate::render::math::{DVec3, Vec3A};

/// A map as a scene uses it: scaled, turned about +y, seen or not by the
/// camera.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvLight {
    pub map: std::sync::Arc<EnvMap>,
    pub intensity: f32,
    /// cos and sin of the rotation about +y.
    pub cos_rot: f32,
    pub sin_rot: f32,
    /// Whether camera rays that leave the scene see the map (else
    /// `background`, which lights nothing).
    pub visible: bool,
    pub background: Vec3A,
}

impl EnvLight {
    pub fn new(
        map: std::sync::Arc<EnvMap>,
        intensity: f64,
        rotation_deg: f64,
        visible: bool,
        background: DVec3,
    ) -> Self {
        let turn = rotation_deg.rem_euclid(360.0).to_radians();
        // Quarter turns exactly (a 90-degree map is its texels shifted).
        let snap = |v: f64| if v.abs() < 1e-12 { 0.0 } else { v as f32 };
        Self {
            map,
            intensity: intensity as f32,
            cos_rot: snap(turn.cos()),
            sin_rot: snap(turn.sin()),
            visible,
            background: background.as_vec3().into(),
        }
    }

    /// World direction `d` in the map's frame.
    #[inline(always)]
    fn world_to_map(&self, d: Vec3A) -> Vec3A {
        let (c, s) = (self.cos_rot, self.sin_rot);
        Vec3A::new(c * d.x - s * d.z, d.y, s * d.x + c * d.z)
    }

    /// Map direction `m` in the world.
    #[inline(always)]
    pub fn map_to_world(&self, m: Vec3A) -> Vec3A {
        let (c, s) = (self.cos_rot, self.sin_rot);
        Vec3A::new(c * m.x + s * m.z, m.y, c * m.z - s * m.x)
    }

    /// The radiance arriving from unit direction `d` (towards the map).
    #[inline(always)]
    pub fn radiance(&self, d: Vec3A) -> Vec3A {
        let (u, v) = map_uv(self.world_to_map(d));
        self.map.lookup(u, v) * self.intensity
    }

    /// A direction drawn in proportion to the map's brightness from
    /// `(u1, u2)`, and 1/pdf (solid angle); None where the density vanishes.
    #[inline(always)]
    pub fn sample(&self, u1: f32, u2: f32) -> Option<(Vec3A, f32)> {
        let (x, y, pdf) = self.map.dist.sample(u1, u2);
        let (m, sin_t) = map_direction(x, y);
        let weight = TWO_PI2 * sin_t / pdf;
        (weight > 0.0 && weight.is_finite()).then(|| (self.map_to_world(m), weight))
    }

    /// The density (solid angle) with which [`EnvLight::sample`] gives
    /// unit direction `d`.
    #[inline(always)]
    pub fn pdf(&self, d: Vec3A) -> f32 {
        let m = self.world_to_map(d);
        let (u, v) = map_uv(m);
        let sin_t = (m.x * m.x + m.z * m.z).sqrt();
        let pdf = self.map.dist.pdf(u, v) / (TWO_PI2 * sin_t);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// The solid-angle mean of its radiance, brightness only (for the power
    /// that light selection weighs it by).
    pub fn mean_brightness(&self) -> f64 {
        self.map.mean.iter().sum::<f64>() / 3.0 * f64::from(self.intensity)
    }
}

#[cfg(test)]
#[path = "sky_tests.rs"]
mod tests;
