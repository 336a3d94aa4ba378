//! Next-event estimation: at a diffuse (or `pbr`) point, one shadow ray to one
//! emitter picked in proportion to its power (an alias table), weighted by
//! 1 / the probability of the pick; or, for comparison, one shadow ray to
//! every emitter. Both are unbiased and converge to the same image; the
//! first costs one ray however many emitters there are.
//!
//! Random numbers: the sampler's light position of this vertex, a 2-D
//! sample (`Sampler::light_2d`); among several emitters, its first
//! coordinate picks one and what is left of it places the point with the
//! second (`Sampler::light_pick_2d`, `PickTable::pick_point`).

use crate::render::isa::Isa;
use crate::render::light::Emitter;
use crate::render::material::NO_MAPS;
use crate::render::math::Vec3A;
use crate::render::sampler::Sampler;
use crate::render::world::{Origin, Surface, World, NO_PRIM};

/// How next-event estimation chooses its emitters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampling {
    /// One emitter per shading point, picked in proportion to its power.
    #[default]
    Power,
    /// Every emitter at every shading point (the thesis's way).
    All,
}

/// Sum over the sampled emitters of Le * V * f(dir, pdf) / pdf for surface
/// `s`, whose geometric normal `nl` and shading normal `ns` face the side
/// the path came from; `f` is what the surface makes of light from a unit
/// direction drawn with density `pdf` (the pick's probability times the
/// emitter's solid-angle density): for diffuse, cos(theta_s), the caller
/// multiplying by albedo / pi; for `pbr`, BSDF cos weighted against BSDF
/// sampling (`mis`). `isa` picks the intersection kernels.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn direct<I: Isa>(
    isa: I,
    world: &World,
    s: &Surface,
    nl: Vec3A,
    ns: Vec3A,
    sampling: LightSampling,
    sampler: &mut Sampler,
    f: impl Fn(Vec3A, f32) -> Vec3A,
) -> Vec3A {
    let lights = &world.lights;
    match sampling {
        LightSampling::Power => match lights.emitters.as_slice() {
            [] => Vec3A::ZERO,
            // One emitter (the thesis's scenes): picked with probability 1,
            // no random number spent on the pick.
            [only] => one(isa, world, (only, 1.0), s, nl, ns, sampler.light_2d(0), &f),
            _ => {
                let Some(table) = &lights.table else {
                    return Vec3A::ZERO;
                };
                let (x, u2) = sampler.light_pick_2d();
                let (i, pmf, u1) = table.pick_point(x);
                let e = (&lights.emitters[i], pmf);
                one(isa, world, e, s, nl, ns, (u1, u2), &f) / pmf
            }
        },
        LightSampling::All => {
            let mut sum = Vec3A::ZERO;
            for (k, e) in lights.emitters.iter().enumerate() {
                sum += one(
                    isa,
                    world,
                    (e, 1.0),
                    s,
                    nl,
                    ns,
                    sampler.light_2d(k as u32),
                    &f,
                );
            }
            sum
        }
    }
}

/// One shadow ray towards `e`, picked with probability `pmf`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn one<I: Isa>(
    isa: I,
    world: &World,
    (e, pmf): (&Emitter, f32),
    s: &Surface,
    nl: Vec3A,
    ns: Vec3A,
    (u1, u2): (f32, f32),
    f: &impl Fn(Vec3A, f32) -> Vec3A,
) -> Vec3A {
    let Some((dir, weight)) = e.sample_direction(&s.receiver(nl, ns), u1, u2) else {
        return Vec3A::ZERO;
    };
    let cos_s = ns.dot(dir);
    if !(cos_s > 0.0 && nl.dot(dir) > 0.0) {
        return Vec3A::ZERO;
    }
    let from = Origin {
        object: s.object,
        prim: s.prim,
        entering: dir.dot(s.ng) < 0.0,
    };
    let ray = world.spawn(s, dir);
    let hit = world.intersect(isa, &ray, from);
    let le = match hit {
        None if e.shape.is_distant() => e.radiance(dir),
        Some(h) if h.object == e.object && (e.prim == NO_PRIM || h.prim == e.prim) => {
            match e.maps {
                NO_MAPS => e.emission,
                _ => world.emitted(e, &h, &ray),
            }
        }
        _ => return Vec3A::ZERO,
    };
    le * (f(dir, pmf / weight) * weight)
}
