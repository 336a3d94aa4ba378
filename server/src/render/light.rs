//! Next-event estimation: one shadow ray to every emitter per shading point.
//!
//! Spheres seen from outside are sampled uniformly in the cone of directions
//! they subtend (no wasted samples on the far side, exact for tiny lights);
//! from inside (or from a point on their inner surface, as in the furnace)
//! uniformly by area, since every point is then visible. Quads are sampled
//! by area. A point on a light's outer surface receives nothing from that
//! light. Each emitter consumes exactly two sampler dimensions, whatever
//! branch it takes, so the CPU and the kernel stay in step.

use crate::render::isa::Isa;
use crate::render::math::{basis, sincos_turns, Vec3A};
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::world::{Geometry, Origin, World};
use std::f32::consts::{PI, TAU};

/// Sum over emitters of Le * V * cos(theta_s) / pdf(direction), for a
/// shading point `p` on object `at` with outward normal `n`, facing `nl`.
/// Multiply by the BRDF (albedo / pi for diffuse) to get reflected radiance.
/// `isa` picks the intersection kernels.
#[inline(always)]
pub fn direct<I: Isa>(isa: I, world: &World, p: Vec3A, n: Vec3A, nl: Vec3A, at: u32, sampler: &mut Sampler) -> Vec3A {
    let mut sum = Vec3A::ZERO;
    for &light in &world.lights {
        let (u1, u2) = sampler.next_2d();
        let Some((dir, weight)) = sample_direction(world, light, p, nl, at, u1, u2) else {
            continue;
        };
        let cos_s = nl.dot(dir);
        if !(cos_s > 0.0) {
            continue;
        }
        let from = Origin {
            object: at,
            entering: dir.dot(n) < 0.0,
        };
        if let Some(hit) = world.intersect(isa, &Ray::new(p, dir), from) {
            if hit.object == light {
                sum += world.material_of(light).emission * (cos_s * weight);
            }
        }
    }
    sum
}

/// A direction towards `light` and 1/pdf (solid angle) of choosing it.
#[inline(always)]
fn sample_direction(
    world: &World,
    light: u32,
    p: Vec3A,
    nl: Vec3A,
    at: u32,
    u1: f32,
    u2: f32,
) -> Option<(Vec3A, f32)> {
    match &world.objects[light as usize].geometry {
        Geometry::Sphere(s) => {
            let to_center = s.center - p;
            let d2 = to_center.length_squared();
            let r2 = s.radius * s.radius;
            let inside = if light == at {
                // On the light itself: inside when facing its interior.
                nl.dot(to_center) > 0.0
            } else {
                d2 < r2
            };
            if light == at && !inside {
                return None;
            }
            if inside {
                let z = 1.0 - 2.0 * u1;
                let rxy = (1.0 - z * z).max(0.0).sqrt();
                let (sin, cos) = sincos_turns(u2);
                let m = Vec3A::new(rxy * cos, rxy * sin, z);
                let w = s.center + m * s.radius - p;
                let dist2 = w.length_squared();
                if !(dist2 > 0.0) {
                    return None;
                }
                let dir = w / dist2.sqrt();
                let cos_l = m.dot(dir).abs();
                Some((dir, cos_l * 4.0 * PI * r2 / dist2))
            } else {
                // 1 - cos(theta_max) without cancellation for small lights.
                let sin2 = r2 / d2;
                let cos_max = (1.0 - sin2).max(0.0).sqrt();
                let one_minus_cos_max = sin2 / (1.0 + cos_max);
                let a = u1 * one_minus_cos_max;
                let cos_t = 1.0 - a;
                let sin_t = (a * (2.0 - a)).max(0.0).sqrt();
                let (sin, cos) = sincos_turns(u2);
                let axis = to_center / d2.sqrt();
                let (t, b) = basis(axis);
                let dir = t * (sin_t * cos) + b * (sin_t * sin) + axis * cos_t;
                Some((dir, TAU * one_minus_cos_max))
            }
        }
        Geometry::Quad(q) => {
            if light == at {
                return None;
            }
            let w = q.point(u1, u2) - p;
            let dist2 = w.length_squared();
            if !(dist2 > 0.0) {
                return None;
            }
            let dir = w / dist2.sqrt();
            let cos_l = q.normal.dot(dir).abs();
            Some((dir, cos_l * q.area / dist2))
        }
    }
}
