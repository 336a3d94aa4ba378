//! The wide loop (issue 32's second stage): `W` paths whose state is in
//! lanes from the camera to their ends, for the worlds [`World::flat`]
//! serves (meshes without texture maps, lit by emissive triangles,
//! traced by Embree). Rays, surfaces, light samples, throughputs,
//! roulette and spawns are computed over the lanes at once, and so is the
//! plain diffuse BSDF; every other material (mirror, glass, `pbr`, an
//! absorbing solid) is the scalar loop's own description
//! (`material::scatter_with`, `integrator::PbrVertex`, `BsdfVertex`'s
//! weights) evaluated one lane at a time. What else stays one lane at a
//! time is what cannot be computed over lanes: each lane's random numbers
//! (the sampler's, the same numbers the scalar loop draws, in the same
//! order), the emitter pick, and the gathers of each lane's triangle and
//! emitter.
//!
//! The paths are the lane loop's (`lanes`), operation for operation, but
//! for where the surface is computed: here in the Embree scene's frame on
//! the triangles Embree tests (`world::flat`), there in object space and
//! mapped to camera space. The hit point, its error bound and the spawned
//! origins therefore differ in their last bits, and so may a path's
//! later decisions; the image is the same estimate (`tests/wide_loop.rs`
//! holds the two together), bit for bit the same at every width.

use super::pairs::InOrder;
use super::wide_surfaces::{each, lane, mask, mul, next_event, per_lane, select, set};
use super::wide_surfaces::{Surfaces, V};
use super::{Pairs, Segment, Span};
use crate::render::embree::Answers;
use crate::render::integrator::mis::BsdfVertex;
use crate::render::integrator::{clamped, LightSampling, PathSettings, PbrVertex, MAX_SURVIVAL};
use crate::render::job::RenderJob;
use crate::render::lanes::{lanes_where, F32s, Real, Vector};
use crate::render::light::Receiver;
use crate::render::material::{cosine_hemisphere, scatter_with, Bsdf, Lobes, SurfaceMaterial};
use crate::render::math::Vec3A;
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::world::flat::Flat;
use crate::render::world::{Origin, World};

/// The flat triangles of `job`'s world where the wide loop serves it and
/// its settings: next-event estimation on, one emitter picked by power,
/// no denoiser's features (else None: the lane loop serves).
pub(super) fn serves(job: &RenderJob) -> Option<&Flat> {
    let s = &job.settings;
    let plain = s.nee && !s.features && s.light_sampling == LightSampling::Power;
    plain.then(|| job.world.flat()).flatten()
}

/// [`super::span_lanes`] for a world `flat` serves: adds the samples
/// `segments` name to the pixels of `span` (from pixel `first`), in the
/// pair loop's order; returns how many were rejected.
///
/// Lanes whose paths ended are refilled with the next pairs once three
/// quarters of them are idle ([`refills`]); a path's radiance waits until
/// every older path has ended, and reaches the film in the pairs' order,
/// so the image is the same bits whenever lanes are refilled.
#[inline(always)]
pub(super) fn span_wide<const W: usize>(
    job: &RenderJob,
    flat: &Flat,
    first: usize,
    span: Span<'_>,
    segments: &[Segment],
) -> u64 {
    match flat.plain {
        true => span_paths::<W, true>(job, flat, first, span, segments),
        false => span_paths::<W, false>(job, flat, first, span, segments),
    }
}

/// [`span_wide`] for worlds whose every material is plain diffuse
/// (`PLAIN`: the code for the others compiled out) or not.
#[inline(always)]
fn span_paths<const W: usize, const PLAIN: bool>(
    job: &RenderJob,
    flat: &Flat,
    first: usize,
    mut span: Span<'_>,
    segments: &[Segment],
) -> u64 {
    let settings = &job.settings;
    let mut rejected = 0u64;
    let mut all = Pairs::new(segments);
    let mut paths = Paths::<W>::new();
    let mut order = InOrder::default();
    loop {
        let idle = mask::<W>(|k| !paths.live[k]);
        if refills(&idle) {
            for k in lanes_where(&idle) {
                let Some(pair) = all.next() else { break };
                let (ray, sampler) = pair.path(job, first).into_parts();
                paths.start(k, (ray, sampler), flat.shift, order.push(pair));
            }
        }
        if !paths.live.contains(&true) {
            break;
        }
        let ended = paths.step::<PLAIN>(&job.world, flat, settings);
        for k in lanes_where(&ended) {
            order.finish(paths.number[k], lane(&paths.l, k));
        }
        order.flush(|pair, l| {
            rejected += u64::from(!span.add_radiance(pair.i, pair.s, clamped(settings, l)));
        });
    }
    rejected
}

/// Whether the lanes `idle` names are to take new paths: once three
/// quarters of them are. Paths that start together at neighbouring pixels
/// send their rays from nearby points, their shadow rays towards the same
/// lights, and Embree traverses such a packet for little more than one
/// ray; a lane refilled as soon as its path ends breaks that up. On
/// `cornell-mesh` (docs/BENCHMARKS.md), refilling every idle lane was
/// 0.925x as fast at depth 6 with roulette from 5, where paths end
/// together, and 1.16x at depth 16 from 2; at three quarters, 1.00x and
/// 1.15x.
#[inline(always)]
fn refills<const W: usize>(idle: &[bool; W]) -> bool {
    idle.iter().filter(|&&i| i).count() * 4 >= 3 * W
}

/// `W` paths in lanes, each at its own bounce: what the path loop carries
/// from one bounce to the next.
struct Paths<const W: usize> {
    samplers: [Sampler; W],
    /// The rays to trace next (in the frame), and the surfaces they leave.
    o: V<W>,
    d: V<W>,
    from: [Origin; W],
    /// Whether a lane holds a path, and how many times it has scattered.
    live: [bool; W],
    bounce: [u32; W],
    beta: V<W>,
    l: V<W>,
    /// Whether the next hit counts the emission it finds (`Path::emit`:
    /// not after a diffuse bounce, whose light NEE gathered), and where a
    /// `pbr` bounce's sample left from with its density, for the MIS
    /// weight of that emission (density 0: counted in full).
    counts: [bool; W],
    last: [BsdfVertex; W],
    /// Each path's number in the film's order ([`InOrder`]).
    number: [u64; W],
}

impl<const W: usize> Paths<W> {
    fn new() -> Self {
        let zero = V::<W>::splat_vec(Vec3A::ZERO);
        Paths {
            samplers: [Sampler::new(0, 0, 0); W],
            o: zero,
            d: zero,
            from: [Origin::NONE; W],
            live: [false; W],
            bounce: [0; W],
            beta: zero,
            l: zero,
            counts: [false; W],
            last: [BsdfVertex::NONE; W],
            number: [0; W],
        }
    }

    /// Starts path `number` in lane `k`: the camera ray (in camera
    /// space, `shift` from the frame) and the sampler of its pair.
    #[inline(always)]
    fn start(&mut self, k: usize, (ray, sampler): (Ray, Sampler), shift: Vec3A, number: u64) {
        self.samplers[k] = sampler;
        set(&mut self.o, k, ray.origin + shift);
        set(&mut self.d, k, ray.dir);
        set(&mut self.beta, k, Vec3A::ONE);
        set(&mut self.l, k, Vec3A::ZERO);
        (self.from[k], self.live[k]) = (Origin::NONE, true);
        (self.bounce[k], self.number[k]) = (0, number);
        (self.counts[k], self.last[k].pdf) = (true, 0.0);
    }

    /// The emission `c` (the throughput times the radiance found) of lane
    /// `k` after its last sample along `d`, met at `q` on emitter
    /// `emitter`: weighed by MIS where that sample asks for it
    /// (`Path::emission`).
    #[inline(always)]
    fn weighed(
        &self,
        k: usize,
        world: &World,
        settings: &PathSettings,
        c: Vec3A,
        (emitter, q): (impl FnOnce() -> Option<usize>, Vec3A),
    ) -> Vec3A {
        let how = (settings.light_sampling, settings.combine);
        let dir = lane(&self.d, k);
        c * self.last[k].hit_weight(&world.lights, how, emitter(), dir, q)
    }

    /// Takes every live path one bounce further: its ray's hit, the
    /// light NEE gathers there, the bounce and the roulette; the lanes
    /// whose paths ended.
    #[inline(always)]
    fn step<const PLAIN: bool>(
        &mut self,
        world: &World,
        flat: &Flat,
        settings: &PathSettings,
    ) -> [bool; W] {
        let started = self.live;
        let camera = mask::<W>(|k| self.bounce[k] == 0);
        // Camera rays go in a packet of their own: coherent rays cost
        // Embree a fraction of what scattered ones do, but only together.
        let (new, old) = (
            mask(|k| started[k] & camera[k]),
            mask(|k| started[k] & !camera[k]),
        );
        let rays = (&self.o, &self.d);
        let hits = match (new.contains(&true), old.contains(&true)) {
            (true, true) => {
                let seen = world.framed_nearest(rays, &self.from, &new, true);
                seen.select(&new, &world.framed_nearest(rays, &self.from, &old, false))
            }
            (fresh, _) => world.framed_nearest(rays, &self.from, &started, fresh),
        };
        let mut live: [bool; W] = mask(|k| started[k] & (hits.t[k] < f32::INFINITY));
        // Left the scene: the environment, counted as an emitter's hit
        // where the last bounce counts emission.
        // (Where every material is plain diffuse, camera rays alone.)
        let counts = match PLAIN {
            true => camera,
            false => self.counts,
        };
        for k in lanes_where::<W>(&mask(|k| started[k] & !live[k] & counts[k])) {
            let mut c = lane(&self.beta, k) * world.sky(lane(&self.d, k));
            if self.last[k].pdf > 0.0 {
                let sky = || world.lights.environment();
                c = self.weighed(k, world, settings, c, (sky, Vec3A::ZERO));
            }
            let sum = lane(&self.l, k) + c;
            set(&mut self.l, k, sum);
        }
        if live.contains(&true) {
            self.scatter::<PLAIN>(world, flat, settings, &hits, (&mut live, &counts));
        }
        self.live = live;
        mask(|k| started[k] & !live[k])
    }

    /// [`Paths::step`] at the surfaces that the `live` lanes' rays met:
    /// ends the paths that end there.
    #[inline(always)]
    fn scatter<const PLAIN: bool>(
        &mut self,
        world: &World,
        flat: &Flat,
        settings: &PathSettings,
        hits: &Answers<W>,
        (live, counts): (&mut [bool; W], &[bool; W]),
    ) {
        let zero = V::<W>::splat_vec(Vec3A::ZERO);
        let s = Surfaces::of(flat, hits, live, &self.d);
        // The lanes whose material is shaded one lane at a time, if any.
        let other = match PLAIN {
            true => [false; W],
            false => mask::<W>(|k| live[k] & !s.tris[k].plain),
        };
        let mut others = other.contains(&true).then(|| Others::new(world, &s, other));
        if let Some(o) = &others {
            o.absorb(&mut self.beta, &s, hits);
        }
        // Only emitters count: a zero emission times a throughput that
        // overflowed would be NaN, where the scalar path adds nothing. (Where
        // every material is diffuse, camera rays alone count, their
        // throughput one.)
        let counted = match PLAIN {
            true => mask::<W>(|k| live[k] & counts[k]),
            false => mask::<W>(|k| live[k] & counts[k] & (s.tris[k].emission != [0.0; 3])),
        };
        if counted.contains(&true) {
            let mut c = match PLAIN {
                true => s.emission(),
                false => mul(self.beta, s.emission()),
            };
            let weighed = mask::<W>(|k| !PLAIN & counted[k] & (self.last[k].pdf > 0.0));
            for k in lanes_where(&weighed) {
                let (object, prim) = s.at[k];
                let emitter = || world.lights.index_of(object, prim);
                let ck = self.weighed(k, world, settings, lane(&c, k), (emitter, lane(&s.p, k)));
                set(&mut c, k, ck);
            }
            self.l = self.l + select(&counted, c, zero);
        }
        let depth = settings.max_depth;
        let bounce = self.bounce;
        *live = mask(|k| live[k] & !(depth != 0 && bounce[k] >= depth));
        if !live.contains(&true) {
            return;
        }
        // Next-event estimation, where the material gathers light.
        let diffuse = match &mut others {
            None => [true; W],
            Some(o) => {
                o.build(&s, (&self.d, live), (&mut self.samplers, &bounce));
                mask(|k| !o.lanes[k] | matches!(o.mats[k].bsdf, Bsdf::Diffuse))
            }
        };
        let pbr = others.as_ref().map(|o| &o.pbr);
        let gathers = mask::<W>(|k| live[k] & (diffuse[k] | pbr.is_some_and(|p| p[k].is_some())));
        if gathers.contains(&true) {
            let how = (pbr, settings.combine);
            let samplers = (&mut self.samplers, &bounce);
            let light = next_event(world, flat, samplers, &s, &gathers, self.beta, how);
            self.l = self.l + light;
        }
        // A diffuse vertex's next hit would count no emission.
        *live = mask(|k| live[k] & !(depth != 0 && bounce[k] + 1 >= depth && diffuse[k]));
        // The bounce: a cosine-weighted direction about the shading normal
        // for plain diffuse lanes; the material's own sample for the rest.
        let mut u = [(0.0f32, 0.0f32); W];
        for k in lanes_where(&mask::<W>(|k| live[k] & !other[k])) {
            u[k] = self.samplers[k].bsdf_2d();
        }
        let mut nd = cosine_hemisphere(s.ns, each::<W>(|k| u[k].0), each::<W>(|k| u[k].1));
        let mut weight = s.albedo;
        let mut sampled = Sampled::NONE;
        if let Some(o) = &others {
            sampled = o.scatter(
                &mut self.samplers,
                &s,
                (&self.d, live),
                (&mut nd, &mut weight),
            );
        }
        // A shading normal can send a direction to the wrong side of the
        // actual surface: such a sample carries nothing.
        let above = nd.dot(s.nl);
        let through = sampled.transmitted;
        *live = mask(|k| live[k] & !(s.smooth[k] & ((above.0[k] > 0.0) == through[k])));
        let mut beta = mul(self.beta, weight);
        // Russian roulette, `Path::step`'s.
        let peak = beta.x.max(beta.y).max(beta.z);
        let rr = settings.rr_depth;
        let roulette = mask(|k| live[k] & (bounce[k] + 1 > rr || !(peak.0[k] > 0.0)));
        let mut survive = F32s([1.0; W]);
        for k in lanes_where(&roulette) {
            let q = peak.0[k].min(MAX_SURVIVAL);
            if self.samplers[k].roulette() < q {
                survive.0[k] = q;
            } else {
                live[k] = false;
            }
        }
        if roulette.contains(&true) {
            beta = select(&roulette, beta / survive, beta);
        }
        self.beta = beta;
        self.bounce = per_lane(|k| bounce[k] + u32::from(live[k]));
        // What the next hit counts: after a diffuse bounce nothing (NEE
        // gathered it: the density of `last` is then never read); after a
        // `pbr` reflection its MIS share; after a mirror, glass or a `pbr`
        // transmission all of it.
        if !PLAIN {
            self.counts = mask(|k| !diffuse[k]);
        }
        if let Some(o) = &others {
            o.leave(&mut self.last, &s, live, &sampled);
        }
        (self.o, self.from) = (s.origin(&nd), s.from(&nd));
        self.d = nd;
    }
}

/// What the lanes shaded one at a time drew ([`Others::scatter`]).
struct Sampled<const W: usize> {
    transmitted: [bool; W],
    pdf: [f32; W],
}

impl<const W: usize> Sampled<W> {
    const NONE: Self = Sampled {
        transmitted: [false; W],
        pdf: [0.0; W],
    };
}

/// The lanes of a vertex whose material is shaded one lane at a time
/// (anything but plain diffuse): the scalar loop's descriptions, a lane
/// at a time.
struct Others<'w, const W: usize> {
    lanes: [bool; W],
    mats: [&'w SurfaceMaterial; W],
    /// The `pbr` lanes' vertices, once built ([`Others::build`]).
    pbr: [Option<PbrVertex>; W],
}

impl<'w, const W: usize> Others<'w, W> {
    #[inline(never)]
    fn new(world: &'w World, s: &Surfaces<'_, W>, lanes: [bool; W]) -> Self {
        Others {
            lanes,
            mats: std::array::from_fn(|k| world.material(s.tris[k].material)),
            pbr: [None; W],
        }
    }

    /// Beer-Lambert: a solid's surface met from inside (at distance
    /// `hits.t`) has absorbed part of what the path carries.
    #[inline(never)]
    fn absorb(&self, beta: &mut V<W>, s: &Surfaces<'_, W>, hits: &Answers<W>) {
        for k in lanes_where(&self.lanes) {
            let m = self.mats[k];
            if !s.entering[k] && m.absorb != Vec3A::ZERO {
                let kept = lane(beta, k) * (-m.absorb * hits.t[k]).exp();
                set(beta, k, kept);
            }
        }
    }

    /// Sets the live lanes' samplers to their vertices (`bounce`), and
    /// builds the `pbr` vertices (rays along `d`): their lobes serve both
    /// next-event estimation and the scatter.
    #[inline(never)]
    fn build(
        &mut self,
        s: &Surfaces<'_, W>,
        (d, live): (&V<W>, &[bool; W]),
        (samplers, bounce): (&mut [Sampler; W], &[u32; W]),
    ) {
        for k in lanes_where(&mask::<W>(|k| self.lanes[k] & live[k])) {
            samplers[k].at_vertex(bounce[k]);
            if let Bsdf::Pbr(p) = &self.mats[k].bsdf {
                let side = (lane(&s.ns, k), s.entering[k]);
                self.pbr[k] = Some(PbrVertex::new(
                    p,
                    self.mats[k].albedo,
                    lane(d, k),
                    side,
                    None,
                ));
            }
        }
    }

    /// Each live lane's sample (`material::scatter_with`), its direction
    /// and weight written into `nd` and `weight`.
    #[inline(never)]
    fn scatter(
        &self,
        samplers: &mut [Sampler; W],
        s: &Surfaces<'_, W>,
        (d, live): (&V<W>, &[bool; W]),
        (nd, weight): (&mut V<W>, &mut V<W>),
    ) -> Sampled<W> {
        let mut out = Sampled::NONE;
        for k in lanes_where(&mask::<W>(|k| live[k] & self.lanes[k])) {
            let lobes = match &self.pbr[k] {
                Some(v) => Lobes::Built(&v.lobes),
                None => Lobes::Build(None),
            };
            let (dk, ns, entering) = (lane(d, k), lane(&s.ns, k), s.entering[k]);
            let sc = scatter_with(self.mats[k], dk, entering, ns, &mut samplers[k], lobes);
            set(nd, k, sc.dir);
            set(weight, k, sc.weight);
            (out.transmitted[k], out.pdf[k]) = (sc.transmitted, sc.pdf);
        }
        out
    }

    /// Where each live lane's sample left from, for the MIS weight of the
    /// emission its next hit finds: a `pbr` reflection's point and
    /// density; any other's density 0 (counted in full).
    #[inline(never)]
    fn leave(
        &self,
        last: &mut [BsdfVertex; W],
        s: &Surfaces<'_, W>,
        live: &[bool; W],
        sampled: &Sampled<W>,
    ) {
        for k in lanes_where(&mask::<W>(|k| live[k] & self.lanes[k])) {
            last[k].pdf = 0.0;
            if self.pbr[k].is_some() && !sampled.transmitted[k] {
                let (object, prim) = s.at[k];
                let (p, nl, ns) = (lane(&s.p, k), lane(&s.nl, k), lane(&s.ns, k));
                let from = Receiver {
                    p,
                    object,
                    prim,
                    nl,
                    ns,
                };
                last[k] = BsdfVertex {
                    from,
                    pdf: sampled.pdf[k],
                };
            }
        }
    }
}
