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
use crate::render::light::{Emitter, EmitterShape};
use crate::render::material::NO_MAPS;
use crate::render::math::Vec3A;
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::world::{Hit, Origin, Surface, World, NO_PRIM};

/// How next-event estimation chooses its emitters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSampling {
    /// One emitter per shading point, picked in proportion to its power.
    #[default]
    Power,
    /// Every emitter at every shading point (the thesis's way).
    All,
}

/// What next-event estimation found at a vertex.
#[derive(Clone, Copy, Debug)]
pub enum Direct {
    /// No light to look for (no emitter, or none the point can see).
    None,
    /// The sum over every emitter, each shadow ray traced already
    /// (`LightSampling::All`).
    Traced(Vec3A),
    /// One shadow ray, still to be traced: the caller traces it when it
    /// likes (at once, or with other paths' shadow rays in a packet).
    Shadow(Shadow),
}

/// A shadow ray towards emitter `emitter`, and what its light adds to the
/// path's radiance if nothing blocks it: `pre * (Le * fw / pmf) * post`,
/// the scalar loop's operations in its order, so that tracing it later
/// gives the same bits as tracing it at once.
#[derive(Clone, Copy, Debug)]
pub struct Shadow {
    /// Along the sampled direction, from where `World::spawn` starts it.
    pub ray: Ray,
    pub from: Origin,
    /// A `world.lights.emitters` index.
    emitter: u32,
    /// f(dir, pdf) times 1/pdf: what the surface makes of unit light.
    fw: Vec3A,
    /// The probability with which the emitter was picked.
    pmf: f32,
    /// The path's factors before and after (throughput and albedo, 1/pi).
    pre: Vec3A,
    post: f32,
}

impl Shadow {
    /// The same ray, its light scaled by the path's factors `pre` (first)
    /// and `post` (last).
    #[inline(always)]
    pub fn scaled(self, pre: Vec3A, post: f32) -> Shadow {
        Shadow { pre, post, ..self }
    }

    /// The radiance the ray brings where its nearest hit is `hit`, or
    /// None where that is not its emitter.
    #[inline(always)]
    pub fn arriving(&self, world: &World, hit: Option<Hit>) -> Option<Vec3A> {
        arriving(
            world,
            &world.lights.emitters[self.emitter as usize],
            &self.ray,
            hit,
        )
    }

    /// Where an occlusion test answers for this ray: the distance before
    /// which anything blocks it (a thousandth short of the emitter's
    /// point; infinite for a distant emitter) and the radiance it brings
    /// if nothing does. None where the emitter must be identified by the
    /// nearest hit: an emission map (read at the hit) or a sphere.
    #[inline(always)]
    pub fn unblocked(&self, world: &World) -> Option<(f32, Vec3A)> {
        let e = &world.lights.emitters[self.emitter as usize];
        if e.maps != NO_MAPS {
            return None;
        }
        // The distance to the emitter's plane (a grazing or degenerate
        // ray's is no distance: the nearest hit decides there).
        let reach = |corner: Vec3A, n: Vec3A| {
            let t = (corner - self.ray.origin).dot(n) / self.ray.dir.dot(n);
            (t > 0.0 && t < f32::INFINITY).then_some((t * (1.0 - SHADOW_EPSILON), e.emission))
        };
        match &e.shape {
            EmitterShape::Triangle(t) => reach(t.p0, t.n),
            EmitterShape::Quad(q) => reach(q.corner, q.normal),
            EmitterShape::Sphere(_) => None,
            _ => Some((f32::INFINITY, e.radiance(self.ray.dir))),
        }
    }

    /// What the ray adds to the path's radiance, `le` arriving.
    #[inline(always)]
    pub fn light(&self, le: Vec3A) -> Vec3A {
        self.pre * ((le * self.fw) / self.pmf) * self.post
    }

    /// Traces the ray now; what it adds (None: blocked).
    #[inline(always)]
    pub fn trace<I: Isa>(&self, isa: I, world: &World) -> Option<Vec3A> {
        let hit = world.intersect(isa, &self.ray, self.from);
        self.arriving(world, hit).map(|le| self.light(le))
    }
}

/// The radiance a shadow ray `ray` towards `e` brings where its nearest
/// hit is `hit`, or None where that is not `e`.
#[inline(always)]
fn arriving(world: &World, e: &Emitter, ray: &Ray, hit: Option<Hit>) -> Option<Vec3A> {
    match hit {
        None if e.shape.is_distant() => Some(e.radiance(ray.dir)),
        Some(h) if h.object == e.object && (e.prim == NO_PRIM || h.prim == e.prim) => {
            Some(match e.maps {
                NO_MAPS => e.emission,
                _ => world.emitted(e, &h, ray),
            })
        }
        _ => None,
    }
}

/// How much shorter than the distance to its emitter's point an occlusion
/// test looks (Mitsuba's and pbrt's shadow epsilon): surfaces in the last
/// thousandth, the emitter itself among them, do not block.
pub const SHADOW_EPSILON: f32 = 1e-3;

/// Next-event estimation at surface `s`, whose geometric normal `nl` and
/// shading normal `ns` face the side the path came from: the sum over the
/// sampled emitters of Le * V * f(dir, pdf) / pdf, `f` what the surface
/// makes of light from a unit direction drawn with density `pdf` (the
/// pick's probability times the emitter's solid-angle density): for
/// diffuse, cos(theta_s), the caller multiplying by albedo / pi; for
/// `pbr`, BSDF cos weighted against BSDF sampling (`mis`). With one
/// emitter picked and `LATER`, the shadow ray is returned untraced (and
/// `f` evaluated whether or not it will be blocked); else traced at once,
/// `f` evaluated only where it is not. `isa` picks the intersection
/// kernels.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn direct<const LATER: bool, I: Isa>(
    isa: I,
    world: &World,
    s: &Surface,
    nl: Vec3A,
    ns: Vec3A,
    sampling: LightSampling,
    sampler: &mut Sampler,
    f: impl Fn(Vec3A, f32) -> Vec3A,
) -> Direct {
    let lights = &world.lights;
    match sampling {
        LightSampling::Power => match lights.emitters.as_slice() {
            [] => Direct::None,
            // One emitter (the thesis's scenes): picked with probability 1,
            // no random number spent on the pick.
            [only] => {
                let u = sampler.light_2d(0);
                one::<LATER, I>(isa, world, (only, 0, 1.0), s, (nl, ns), u, &f)
            }
            _ => {
                let Some(table) = &lights.table else {
                    return Direct::None;
                };
                let (x, u2) = sampler.light_pick_2d();
                let (i, pmf, u1) = table.pick_point(x);
                let e = (&lights.emitters[i], i, pmf);
                one::<LATER, I>(isa, world, e, s, (nl, ns), (u1, u2), &f)
            }
        },
        LightSampling::All => {
            let mut sum = Vec3A::ZERO;
            for (k, e) in lights.emitters.iter().enumerate() {
                let u = sampler.light_2d(k as u32);
                if let Direct::Traced(light) =
                    one::<false, I>(isa, world, (e, k, 1.0), s, (nl, ns), u, &f)
                {
                    sum += light;
                }
            }
            Direct::Traced(sum)
        }
    }
}

/// The shadow ray towards `e` (emitter number `index`), picked with
/// probability `pmf`: untraced with `LATER`, else traced (what it brings,
/// Le * f * 1/pdf / pmf, or nothing where blocked).
#[inline(always)]
fn one<const LATER: bool, I: Isa>(
    isa: I,
    world: &World,
    (e, index, pmf): (&Emitter, usize, f32),
    s: &Surface,
    (nl, ns): (Vec3A, Vec3A),
    (u1, u2): (f32, f32),
    f: &impl Fn(Vec3A, f32) -> Vec3A,
) -> Direct {
    let Some((dir, weight)) = e.sample_direction(&s.receiver(nl, ns), u1, u2) else {
        return Direct::None;
    };
    let cos_s = ns.dot(dir);
    if !(cos_s > 0.0 && nl.dot(dir) > 0.0) {
        return Direct::None;
    }
    let from = Origin {
        object: s.object,
        prim: s.prim,
        entering: dir.dot(s.ng) < 0.0,
    };
    let ray = world.spawn(s, dir);
    if LATER {
        return Direct::Shadow(Shadow {
            ray,
            from,
            emitter: index as u32,
            fw: f(dir, pmf / weight) * weight,
            pmf,
            pre: Vec3A::ONE,
            post: 1.0,
        });
    }
    let hit = world.intersect(isa, &ray, from);
    match arriving(world, e, &ray, hit) {
        Some(le) => Direct::Traced((le * (f(dir, pmf / weight) * weight)) / pmf),
        None => Direct::None,
    }
}
