//! The path tracer: iterative (the kernel mirrors it loop for loop), with
//! depth cap, Russian roulette, next-event estimation and clamping.
//!
//! Emission is counted at up to `max_depth + 1` hits: the camera ray's hit
//! and the hit after each scattering event. With NEE on, light reaching a
//! diffuse point is gathered by the shadow rays, so an emitter met by the
//! following diffuse bounce is not counted again; after a specular bounce it
//! is (NEE cannot sample a delta lobe). NEE on and off therefore estimate the
//! same quantity at every depth cap.

use crate::render::camera::CameraRays;
use crate::render::filter::Filter;
use crate::render::isa::Isa;
use crate::render::light;
use crate::render::material::{scatter, Bsdf};
use crate::render::math::{max_component, Vec3A};
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::world::{Origin, World};
use std::f32::consts::FRAC_1_PI;

/// Largest Russian-roulette survival probability: even albedo-1 mirrors end
/// eventually, so unbounded paths terminate with probability 1.
const MAX_SURVIVAL: f32 = 0.99;

/// The quality settings the path loop reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Most scattering events; 0 = unbounded (Russian roulette only).
    pub max_depth: u32,
    /// Scattering events after which Russian roulette may end a path.
    pub rr_depth: u32,
    pub nee: bool,
    /// Largest sample radiance (max component), 0 = off.
    pub clamp: f32,
}

/// Radiance arriving along `ray`; `isa` picks the intersection kernels.
#[inline(always)]
pub fn radiance<I: Isa>(isa: I, world: &World, mut ray: Ray, settings: &PathSettings, sampler: &mut Sampler) -> Vec3A {
    let mut l = Vec3A::ZERO;
    let mut beta = Vec3A::ONE;
    let mut specular = true;
    let mut from = Origin::NONE;
    let mut bounces = 0u32;
    while let Some(hit) = world.intersect(isa, &ray, from) {
        let m = world.material_of(hit.object);
        if m.emissive && (specular || !settings.nee) {
            l += beta * m.emission;
        }
        if settings.max_depth != 0 && bounces >= settings.max_depth {
            break;
        }
        let p = ray.at(hit.t);
        let n = world.normal(hit.object, p);
        if settings.nee && m.bsdf == Bsdf::Diffuse {
            let nl = if ray.dir.dot(n) < 0.0 { n } else { -n };
            let direct = light::direct(isa, world, p, n, nl, hit.object, sampler);
            l += beta * m.albedo * direct * FRAC_1_PI;
            if settings.max_depth != 0 && bounces + 1 >= settings.max_depth {
                break; // the bounce's own hit would not count its emission
            }
        }
        let s = scatter(m, ray.dir, n, sampler);
        beta *= s.weight;
        bounces += 1;
        if bounces > settings.rr_depth || !(max_component(beta) > 0.0) {
            let q = max_component(beta).min(MAX_SURVIVAL);
            if !(sampler.next_f32() < q) {
                break;
            }
            beta /= q;
        }
        specular = s.specular;
        from = Origin {
            object: hit.object,
            entering: s.dir.dot(n) < 0.0,
        };
        ray = Ray::new(p, s.dir);
    }
    if settings.clamp > 0.0 {
        let peak = max_component(l);
        if peak > settings.clamp {
            l *= settings.clamp / peak;
        }
    }
    l
}

/// One camera path: sample `sample` of pixel (x, y).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn sample_pixel<I: Isa>(
    isa: I,
    world: &World,
    camera: &CameraRays,
    settings: &PathSettings,
    filter: Filter,
    seed: u64,
    (x, y): (u32, u32),
    sample: u64,
) -> Vec3A {
    let pixel = u64::from(y) * u64::from(camera.width) + u64::from(x);
    let mut sampler = Sampler::new(seed, pixel, sample);
    let (u1, u2) = sampler.next_2d();
    let (dx, dy) = filter.pixel_offset(sample, u1, u2);
    let ray = camera.ray(x as f32 + dx, y as f32 + dy);
    radiance(isa, world, ray, settings, &mut sampler)
}
