//! The path tracer: iterative (the kernel mirrors it loop for loop), with
//! depth cap, Russian roulette, next-event estimation and clamping.
//!
//! Emission is counted at up to `max_depth + 1` hits: the camera ray's hit
//! and the hit after each scattering event. With NEE on, light reaching a
//! diffuse point is gathered by the shadow rays, so an emitter met by the
//! following diffuse bounce is not counted again; after a specular bounce it
//! is (NEE cannot sample a delta lobe). NEE on and off therefore estimate the
//! same quantity at every depth cap. At a `pbr` surface both find the
//! light, weighted by multiple importance sampling (`mis`): the shadow ray
//! by the power heuristic of its density against the BSDF's, the next hit's
//! emission by the BSDF sample's against the light's.

pub mod mis;
pub mod nee;
pub mod pbr_vertex;

pub use mis::Combine;
pub use nee::{Direct, LightSampling, Shadow};
pub use pbr_vertex::PbrVertex;

use crate::render::camera::CameraRays;
use crate::render::features::{self, Guide};
use crate::render::filter::Filter;
use crate::render::isa::Isa;
use crate::render::material::{scatter_with, Bsdf, Lobes, SurfaceMaterial, NO_MAPS};
use crate::render::math::{max_component, Vec3A};
use crate::render::ray::Ray;
use crate::render::sampler::{Sampler, SamplerKind};
use crate::render::world::{Hit, Origin, World};
use mis::BsdfVertex;
use std::f32::consts::FRAC_1_PI;

/// Largest Russian-roulette survival probability: even albedo-1 mirrors end
/// eventually, so unbounded paths terminate with probability 1.
pub(crate) const MAX_SURVIVAL: f32 = 0.99;

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
    /// How next-event estimation picks emitters (not a quality setting:
    /// `Power` always, except where tests compare the two).
    pub light_sampling: LightSampling,
    /// How a `pbr` vertex weighs its light and BSDF samples (`Mis` always,
    /// except where tests compare the strategies).
    pub combine: Combine,
    /// Find each path's guide for a denoiser (`render::features`).
    pub features: bool,
}

/// A path between bounces: everything the path loop carries, so that the
/// CPU backend can advance two side by side.
#[derive(Clone, Copy, Debug)]
pub struct Path {
    /// The ray to trace next and the surface it leaves.
    pub ray: Ray,
    pub from: Origin,
    sampler: Sampler,
    l: Vec3A,
    beta: Vec3A,
    /// The throughput with which the next hit counts the emission it
    /// finds: `beta`, except zero after a diffuse bounce that NEE gathered.
    emit: Vec3A,
    /// After a `pbr` bounce that NEE gathered: where it left and its
    /// density, for the emission's MIS weight.
    last: BsdfVertex,
    bounces: u32,
    /// The denoiser's guide, once found (`guided`), and the tint of the
    /// mirrors and glass met before it.
    guide: Guide,
    tint: Vec3A,
    guided: bool,
}

impl Path {
    /// A path starting with `ray` (which leaves no surface), drawing its
    /// random numbers from `sampler`.
    #[inline(always)]
    pub fn new(ray: Ray, sampler: Sampler) -> Self {
        Self {
            ray,
            from: Origin::NONE,
            sampler,
            l: Vec3A::ZERO,
            beta: Vec3A::ONE,
            emit: Vec3A::ONE,
            last: BsdfVertex::NONE,
            bounces: 0,
            guide: Guide::default(),
            tint: Vec3A::ONE,
            guided: false,
        }
    }

    /// A path about to start, taken apart: its camera ray and its
    /// sampler (the wide loop keeps each in lanes of its own).
    #[inline(always)]
    pub fn into_parts(self) -> (Ray, Sampler) {
        (self.ray, self.sampler)
    }

    /// The denoiser's guide this path found (zero where it ended before a
    /// surface that is not specular, or when its settings ask for none).
    #[inline(always)]
    pub fn guide(&self) -> &Guide {
        &self.guide
    }

    /// Records the guide at a hit with material `m`, normal `ns` on the
    /// ray's side, unless `m` is a perfect mirror or smooth glass (then the
    /// guide is further on, tinted by it).
    #[inline(always)]
    fn find_guide(&mut self, m: &SurfaceMaterial, ns: Vec3A) {
        if matches!(m.bsdf, Bsdf::Mirror | Bsdf::Glass { .. }) {
            self.tint *= m.albedo;
            return;
        }
        let albedo = if m.emissive {
            features::light_albedo(m.emission)
        } else {
            m.albedo
        };
        self.guide = Guide {
            albedo: self.tint * albedo,
            normal: ns,
        };
        self.guided = true;
    }

    /// What emission `le` found by the last sample along `self.ray` at `q`
    /// adds to the path: weighted by MIS where the last vertex asks for it,
    /// `emitter` finding the emitter (a `world.lights` index) only then.
    #[inline(always)]
    fn emission(
        &self,
        world: &World,
        settings: &PathSettings,
        le: Vec3A,
        emitter: impl FnOnce() -> Option<usize>,
        q: Vec3A,
    ) -> Vec3A {
        let mut c = self.emit * le;
        if self.last.pdf > 0.0 {
            let how = (settings.light_sampling, settings.combine);
            c *= self
                .last
                .hit_weight(&world.lights, how, emitter(), self.ray.dir, q);
        }
        c
    }

    /// Continues the path at `hit`, the nearest hit along `self.ray`
    /// (`world.intersect(isa, &self.ray, self.from)`), tracing its shadow
    /// ray at once (before the BSDF is evaluated for it, which a blocked
    /// ray spares); false once the path has ended (it must not be advanced
    /// again then).
    #[inline(always)]
    pub fn advance<I: Isa>(
        &mut self,
        isa: I,
        world: &World,
        settings: &PathSettings,
        hit: Option<Hit>,
    ) -> bool {
        self.step::<false, I>(isa, world, settings, hit, &mut None)
    }

    /// Adds what a shadow ray of this path's last [`Path::step`] brought
    /// ([`Shadow::light`]).
    #[inline(always)]
    pub fn add_light(&mut self, light: Vec3A) {
        self.l += light;
    }

    /// [`Path::advance`], with `LATER` without its shadow ray: that is
    /// left in `shadow` (if the vertex sent one) for the caller to trace
    /// before the path's next step, and to add what it brings
    /// ([`Path::add_light`]); the path's radiance is the same as if it had
    /// been traced at once. Without `LATER`, `shadow` stays None.
    #[inline(always)]
    pub fn step<const LATER: bool, I: Isa>(
        &mut self,
        isa: I,
        world: &World,
        settings: &PathSettings,
        hit: Option<Hit>,
        shadow: &mut Option<Shadow>,
    ) -> bool {
        let Some(hit) = hit else {
            // Left the scene: the environment, counted as an emitter's hit
            // (what a camera ray sees of a map it may not see is no light).
            if settings.features && !self.guided {
                let seen = match &world.env_map {
                    Some(m) if self.bounces == 0 && !m.visible => m.background,
                    _ => world.sky(self.ray.dir),
                };
                self.guide.albedo = self.tint * features::light_albedo(seen);
                self.guided = true;
            }
            match &world.env_map {
                Some(m) if self.bounces == 0 && !m.visible => self.l += m.background,
                _ => {
                    let le = world.sky(self.ray.dir);
                    let sky = || world.lights.environment();
                    self.l += self.emission(world, settings, le, sky, Vec3A::ZERO);
                    if let Some((_, le)) = world.sun.filter(|(s, _)| s.covers(self.ray.dir)) {
                        let emitter = || world.lights.sun();
                        self.l += self.emission(world, settings, le, emitter, Vec3A::ZERO);
                    }
                }
            }
            return false;
        };
        let ray = &self.ray;
        self.sampler.at_vertex(self.bounces);
        let mut s = world.surface(&hit, ray);
        let untextured = world.material(s.material);
        let textured;
        let m = if untextured.maps == NO_MAPS && !world.vertex_colors {
            untextured
        } else {
            textured = world.shade(untextured, &hit, &mut s);
            &textured
        };
        // A ray that reaches a solid's surface from inside has crossed it:
        // what it carries is absorbed on the way (Beer-Lambert).
        let entering = ray.dir.dot(s.ng) < 0.0;
        if !entering && m.absorb != Vec3A::ZERO {
            let kept = (-m.absorb * hit.t).exp();
            self.beta *= kept;
            self.emit *= kept;
            if !self.guided {
                self.tint *= kept;
            }
        }
        if m.emissive {
            let emitter = || world.lights.index_of(s.object, s.prim);
            self.l += self.emission(world, settings, m.emission, emitter, s.p);
        }
        // Geometric and shading normals on the side the ray came from.
        let nl = if entering { s.ng } else { -s.ng };
        let ns = if !s.smooth {
            nl
        } else if s.ns.dot(nl) < 0.0 {
            -s.ns
        } else {
            s.ns
        };
        // A clear coat's own normal, on the same side.
        let nc = (s.nc != Vec3A::ZERO).then(|| if s.nc.dot(nl) < 0.0 { -s.nc } else { s.nc });
        if settings.features && !self.guided {
            self.find_guide(m, ns);
        }
        if settings.max_depth != 0 && self.bounces >= settings.max_depth {
            return false;
        }
        let ray = &self.ray;
        let gathered = settings.nee && m.bsdf.gathers_light();
        // A `pbr` surface's lobes, built for NEE, serve the scatter too.
        let mut lobes = Lobes::Build(nc);
        let lobes_built;
        if gathered {
            let sampling = settings.light_sampling;
            // What NEE found, and the path's factors before and after it.
            let (direct, pre, post) = if let Bsdf::Pbr(p) = &m.bsdf {
                lobes_built = PbrVertex::new(p, m.albedo, ray.dir, (ns, entering), nc);
                let built = &lobes_built;
                let f = |dir: Vec3A, light_pdf: f32| built.light(settings.combine, dir, light_pdf);
                let direct =
                    nee::direct::<LATER, I>(isa, world, &s, nl, ns, sampling, &mut self.sampler, f);
                lobes = Lobes::Built(&built.lobes);
                (direct, self.beta, 1.0)
            } else if world.diffuse_mis() {
                let f = |dir: Vec3A, light_pdf: f32| {
                    let cos = ns.dot(dir);
                    let w = mis::light_weight(settings.combine, light_pdf, cos * FRAC_1_PI);
                    Vec3A::splat(cos * w)
                };
                let direct =
                    nee::direct::<LATER, I>(isa, world, &s, nl, ns, sampling, &mut self.sampler, f);
                (direct, self.beta * m.albedo, FRAC_1_PI)
            } else {
                let f = |dir: Vec3A, _pdf: f32| Vec3A::splat(ns.dot(dir));
                let direct =
                    nee::direct::<LATER, I>(isa, world, &s, nl, ns, sampling, &mut self.sampler, f);
                (direct, self.beta * m.albedo, FRAC_1_PI)
            };
            match direct {
                Direct::None => {}
                Direct::Traced(sum) => self.l += pre * sum * post,
                Direct::Shadow(ray) => *shadow = Some(ray.scaled(pre, post)),
            }
            if settings.max_depth != 0 && self.bounces + 1 >= settings.max_depth {
                // The bounce's own hit would count no emission after a
                // diffuse surface lit by NEE alone; after one weighed by
                // MIS, its share.
                if !matches!(m.bsdf, Bsdf::Pbr(_)) && !world.diffuse_mis() {
                    return false;
                }
            }
        }
        let sc = scatter_with(m, ray.dir, entering, ns, &mut self.sampler, lobes);
        // A shading normal can send a direction to the wrong side of the
        // actual surface: such a sample has no contribution (the same
        // integral NEE estimates, so NEE on and off still agree).
        if s.smooth && (sc.dir.dot(nl) > 0.0) == sc.transmitted {
            return false;
        }
        self.beta *= sc.weight;
        self.bounces += 1;
        if self.bounces > settings.rr_depth || !(max_component(self.beta) > 0.0) {
            let q = max_component(self.beta).min(MAX_SURVIVAL);
            if !(self.sampler.roulette() < q) {
                return false;
            }
            self.beta /= q;
        }
        (self.emit, self.last) = match (gathered, &m.bsdf) {
            (false, _) => (self.beta, BsdfVertex::NONE),
            // Light through the surface is BSDF sampling's alone: next-
            // event estimation gathers what the surface reflects.
            (true, Bsdf::Pbr(_)) if sc.transmitted => (self.beta, BsdfVertex::NONE),
            (true, Bsdf::Pbr(_)) => (
                self.beta,
                BsdfVertex {
                    from: s.receiver(nl, ns),
                    pdf: sc.pdf,
                },
            ),
            (true, _) if world.diffuse_mis() => (
                self.beta,
                BsdfVertex {
                    from: s.receiver(nl, ns),
                    pdf: ns.dot(sc.dir) * FRAC_1_PI,
                },
            ),
            (true, _) => (Vec3A::ZERO, BsdfVertex::NONE),
        };
        self.from = Origin {
            object: hit.object,
            prim: hit.prim,
            entering: sc.dir.dot(s.ng) < 0.0,
        };
        self.ray = world.spawn(&s, sc.dir);
        true
    }

    /// Runs the path to its end (`isa` picks the intersection kernels);
    /// its radiance.
    #[inline(always)]
    pub fn trace<I: Isa>(mut self, isa: I, world: &World, settings: &PathSettings) -> Vec3A {
        while self.advance(
            isa,
            world,
            settings,
            world.intersect(isa, &self.ray, self.from),
        ) {}
        self.radiance(settings)
    }

    /// The radiance the path has gathered, clamped as `settings` say.
    #[inline(always)]
    pub fn radiance(&self, settings: &PathSettings) -> Vec3A {
        clamped(settings, self.l)
    }
}

/// A path's radiance `l` clamped as `settings` say: scaled down to the
/// clamp where its largest component is above it.
#[inline(always)]
pub fn clamped(settings: &PathSettings, mut l: Vec3A) -> Vec3A {
    if settings.clamp > 0.0 {
        let peak = max_component(l);
        if peak > settings.clamp {
            l *= settings.clamp / peak;
        }
    }
    l
}

/// Sample `sample` of pixel (x, y): its camera ray, as a path about to start.
#[inline(always)]
pub fn camera_path(
    camera: &CameraRays,
    filter: Filter,
    (kind, seed): (SamplerKind, u64),
    (x, y): (u32, u32),
    sample: u64,
) -> Path {
    let pixel = u64::from(y) * u64::from(camera.width) + u64::from(x);
    let mut sampler = Sampler::of_kind(kind, seed, pixel, sample);
    let (u1, u2) = sampler.camera_2d();
    let (dx, dy) = if sampler.is_sobol() {
        filter.pixel_offset_stratified(u1, u2)
    } else {
        filter.pixel_offset(sample, u1, u2)
    };
    let (px, py) = (x as f32 + dx, y as f32 + dy);
    let ray = match camera.has_lens() {
        true => camera.lens_ray(px, py, sampler.lens_2d()),
        false => camera.ray(px, py),
    };
    Path::new(ray, sampler)
}
