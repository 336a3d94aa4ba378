//! The wide loop (issue 32's second stage): `W` paths whose state and
//! shading are in lanes from the camera to their ends, for the worlds
//! [`World::flat`] serves (meshes of plain diffuse materials lit by
//! emissive triangles, traced by Embree). Rays, surfaces, light samples,
//! BSDF samples, throughputs and spawns are computed over the lanes at
//! once; what stays one lane at a time is what cannot be computed there:
//! each lane's random numbers (the sampler's, the same numbers the scalar
//! loop draws, in the same order), the emitter pick, and the gathers of
//! each lane's triangle and emitter.
//!
//! The paths are the lane loop's (`lanes`), operation for operation, but
//! for where the surface is computed: here in the Embree scene's frame on
//! the triangles Embree tests (`world::flat`), there in object space and
//! mapped to camera space. The hit point, its error bound and the spawned
//! origins therefore differ in their last bits, and so may a path's
//! later decisions; the image is the same estimate (`tests/lane_loop.rs`
//! holds the two together), bit for bit the same at every width.

use super::pairs::InOrder;
use super::{Pairs, Segment, Span};
use crate::render::embree::Answers;
use crate::render::integrator::nee::SHADOW_EPSILON;
use crate::render::integrator::{clamped, LightSampling, PathSettings, MAX_SURVIVAL};
use crate::render::job::RenderJob;
use crate::render::lanes::{lanes_where, F32s, Real, Vector, V3};
use crate::render::light::points::{toward_point, triangle_point};
use crate::render::material::cosine_hemisphere;
use crate::render::math::{gamma, step_toward_lanes, Vec3A};
use crate::render::ray::Ray;
use crate::render::sampler::Sampler;
use crate::render::world::flat::{Flat, FlatEmitter, FlatTri};
use crate::render::world::{Origin, World};
use std::f32::consts::FRAC_1_PI;

type R<const W: usize> = F32s<W>;
type V<const W: usize> = V3<F32s<W>>;

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
pub(super) fn span_diffuse<const W: usize>(
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
        let refill = refills(&idle);
        for k in lanes_where(&idle).filter(|_| refill) {
            let Some(pair) = all.next() else { break };
            let (ray, sampler) = pair.path(job, first).into_parts();
            paths.start(k, (ray, sampler), flat.shift, order.push(pair));
        }
        if !paths.live.contains(&true) {
            break;
        }
        let ended = paths.step(&job.world, flat, settings);
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

/// Lane `k` of `v`.
#[inline(always)]
fn lane<const W: usize>(v: &V<W>, k: usize) -> Vec3A {
    Vec3A::new(v.x.0[k], v.y.0[k], v.z.0[k])
}

/// `f` of every lane, in a plain counted loop, which the compiler turns
/// into vector instructions (`array::from_fn`, with its drop guard, it
/// left one lane at a time).
#[inline(always)]
fn per_lane<T: Copy + Default, const W: usize>(f: impl Fn(usize) -> T) -> [T; W] {
    let mut out = [T::default(); W];
    for (k, o) in out.iter_mut().enumerate() {
        *o = f(k);
    }
    out
}

/// A vector per lane from `f`'s.
#[inline(always)]
fn gather<const W: usize>(f: impl Fn(usize) -> [f32; 3]) -> V<W> {
    let a: [[f32; 3]; W] = per_lane(f);
    V3 {
        x: F32s(per_lane(|k| a[k][0])),
        y: F32s(per_lane(|k| a[k][1])),
        z: F32s(per_lane(|k| a[k][2])),
    }
}

/// A number per lane from `f`'s.
#[inline(always)]
fn each<const W: usize>(f: impl Fn(usize) -> f32) -> R<W> {
    F32s(per_lane(f))
}

/// `a` where `m`, else `b`, lane by lane.
#[inline(always)]
fn select<const W: usize>(m: &[bool; W], a: V<W>, b: V<W>) -> V<W> {
    let s = |a: R<W>, b: R<W>| each(|k| if m[k] { a.0[k] } else { b.0[k] });
    V3 {
        x: s(a.x, b.x),
        y: s(a.y, b.y),
        z: s(a.z, b.z),
    }
}

/// Component-wise product.
#[inline(always)]
fn mul<const W: usize>(a: V<W>, b: V<W>) -> V<W> {
    V3 {
        x: a.x * b.x,
        y: a.y * b.y,
        z: a.z * b.z,
    }
}

/// A lane mask from a test of each lane.
#[inline(always)]
fn mask<const W: usize>(f: impl Fn(usize) -> bool) -> [bool; W] {
    per_lane(f)
}

/// Where a ray leaving a surface starts (`world::spawn`'s rule in the
/// frame): the hit point `p` moved `dist` along the unit normal `ng` to
/// the side `dir` leaves by, each coordinate then one float further
/// (`math::step_toward`).
#[inline(always)]
fn spawn<const W: usize>(p: V<W>, ng: V<W>, dist: R<W>, dir: V<W>) -> V<W> {
    let side = dir.dot(ng);
    let d = each(|k| f32::from_bits(dist.0[k].to_bits() ^ (u32::from(!(side.0[k] > 0.0)) << 31)));
    let shift = ng * d;
    let q = p + shift;
    V3 {
        x: step_toward_lanes(q.x, shift.x),
        y: step_toward_lanes(q.y, shift.y),
        z: step_toward_lanes(q.z, shift.z),
    }
}

/// The surfaces that `W` rays met (in the live lanes), over lanes.
struct Surfaces<'a, const W: usize> {
    /// The hit point (in the frame), its geometric normal and how far
    /// off it a ray starts (the point's rounding bound along the normal).
    p: V<W>,
    ng: V<W>,
    dist: R<W>,
    /// The geometric and shading normals on the side the ray came from.
    nl: V<W>,
    ns: V<W>,
    /// Whether the shading normal is interpolated (not `nl`).
    smooth: [bool; W],
    albedo: V<W>,
    /// Each lane's triangle, as `Origin` and the emitters name it, and
    /// its record.
    at: [(u32, u32); W],
    tris: [&'a FlatTri; W],
}

impl<'a, const W: usize> Surfaces<'a, W> {
    /// The surfaces of `hits` (along directions `d`), gathered from the
    /// flat triangles: `Instance::surface`'s steps, in the frame.
    #[inline(always)]
    fn of(flat: &'a Flat, hits: &Answers<W>, live: &[bool; W], d: &V<W>) -> Self {
        let c = R::<W>::splat;
        let tris: [&'a FlatTri; W] = std::array::from_fn(|k| match live[k] {
            true => &flat.tris[(flat.first[hits.id[k] as usize] + hits.prim[k]) as usize],
            false => &flat.tris[0],
        });
        // Embree's barycentrics as the world's (`as_hit`).
        let (u, v) = (F32s(hits.u), F32s(hits.v));
        let b = [c(1.0) - u - v, u, v];
        let v = [0, 1, 2].map(|j| gather::<W>(|k| tris[k].v[j]));
        let (t0, t1, t2) = (v[0] * b[0], v[1] * b[1], v[2] * b[2]);
        let err = (abs(t0) + abs(t1) + abs(t2)) * c(gamma(7));
        let ng = gather::<W>(|k| tris[k].ng);
        let n = [0, 1, 2].map(|j| gather::<W>(|k| tris[k].normals[j]));
        let interp = n[0] * b[0] + n[1] * b[1] + n[2] * b[2];
        let len = interp.length_squared().sqrt();
        let r = c(1.0) / len;
        let smooth = mask(|k| tris[k].smooth & (r.0[k] < f32::INFINITY) & (r.0[k] > 0.0));
        let ns = interp / len;
        let dn = d.dot(ng);
        let nl = select(&mask(|k| dn.0[k] < 0.0), ng, -ng);
        let sn = ns.dot(nl);
        let ns = select(&mask(|k| sn.0[k] < 0.0), -ns, ns);
        Surfaces {
            p: t0 + t1 + t2,
            ng,
            dist: abs(ng).dot(err),
            nl,
            ns: select(&smooth, ns, nl),
            smooth,
            albedo: gather::<W>(|k| tris[k].albedo),
            at: std::array::from_fn(|k| (hits.id[k], hits.prim[k])),
            tris,
        }
    }

    /// The emission of each lane's triangle (the camera's hits alone
    /// count it: NEE gathers the light a diffuse bounce would meet).
    #[inline(always)]
    fn emission(&self) -> V<W> {
        gather::<W>(|k| self.tris[k].emission)
    }

    /// Where rays leaving along `dir` start.
    #[inline(always)]
    fn origin(&self, dir: &V<W>) -> V<W> {
        spawn(self.p, self.ng, self.dist, *dir)
    }

    /// The surfaces rays leaving along `dir` leave, for a query that must
    /// not meet them again.
    #[inline(always)]
    fn from(&self, dir: &V<W>) -> [Origin; W] {
        let side = dir.dot(self.ng);
        std::array::from_fn(|k| Origin {
            object: self.at[k].0,
            prim: self.at[k].1,
            entering: side.0[k] < 0.0,
        })
    }
}

/// Component-wise magnitude.
#[inline(always)]
fn abs<const W: usize>(v: V<W>) -> V<W> {
    V3 {
        x: v.x.abs(),
        y: v.y.abs(),
        z: v.z.abs(),
    }
}

/// Next-event estimation at the live lanes' surfaces `s` (vertex `bounce`
/// of paths of throughput `beta`, lane by lane): an emitter and a point on it per lane
/// (`nee::direct`'s draws), the shadow rays traced together; the light
/// that reaches each lane, `Shadow::light`'s operations in its order.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn next_event<const W: usize>(
    world: &World,
    flat: &Flat,
    samplers: &mut [Sampler; W],
    bounce: &[u32; W],
    s: &Surfaces<'_, W>,
    live: &[bool; W],
    beta: V<W>,
) -> V<W> {
    let lights = &world.lights;
    let (mut index, mut pmf) = ([0usize; W], [1.0f32; W]);
    let (mut u1, mut u2) = ([0.0f32; W], [0.0f32; W]);
    let table = lights.table.as_ref().filter(|_| lights.emitters.len() > 1);
    for k in lanes_where(live) {
        let sampler = &mut samplers[k];
        sampler.at_vertex(bounce[k]);
        (u1[k], u2[k]) = match table {
            Some(t) => {
                let (x, u2) = sampler.light_pick_2d();
                let (i, p, u1) = t.pick_point(x);
                (index[k], pmf[k]) = (i, p);
                (u1, u2)
            }
            None => sampler.light_2d(0),
        };
    }
    let es: [&FlatEmitter; W] = std::array::from_fn(|k| &flat.emitters[index[k]]);
    let p0 = gather::<W>(|k| es[k].p0);
    let (e1, e2) = (gather::<W>(|k| es[k].e1), gather::<W>(|k| es[k].e2));
    let q = triangle_point(p0, e1, e2, F32s(u1), F32s(u2));
    let en = gather::<W>(|k| es[k].n);
    let (dir, weight, sampled) = toward_point(s.p, q, en, each::<W>(|k| es[k].area));
    let cos_s = s.ns.dot(dir);
    let toward = s.nl.dot(dir);
    let lit: [bool; W] = mask(|k| {
        let (object, prim) = s.at[k];
        let under = ((es[k].object ^ object) | (es[k].prim ^ prim)) == 0;
        live[k] & (sampled.0[k] != 0) & !under & (cos_s.0[k] > 0.0) & (toward.0[k] > 0.0)
    });
    // pre * ((Le * fw) / pmf) * post: pre the throughput times the
    // albedo, fw cos times 1/pdf, post 1/pi.
    let fw = V3 {
        x: cos_s * weight,
        y: cos_s * weight,
        z: cos_s * weight,
    };
    let le = gather::<W>(|k| es[k].emission);
    let light = mul(mul(beta, s.albedo), mul(le, fw) / F32s(pmf)) * R::<W>::splat(FRAC_1_PI);
    let so = s.origin(&dir);
    // An occlusion test up to a thousandth short of the emitter's plane;
    // a grazing ray, which reaches no plane, asks for its nearest hit.
    let reach = (p0 - so).dot(en) / dir.dot(en);
    let planar: [bool; W] = mask(|k| (reach.0[k] > 0.0) & (reach.0[k] < f32::INFINITY));
    let tmax = reach.0.map(|t| t * (1.0 - SHADOW_EPSILON));
    let tested = mask(|k| lit[k] & planar[k]);
    let mut reached = [false; W];
    if tested.contains(&true) {
        let blocked = world.framed_occluded((&so, &dir, &tmax), &tested);
        reached = mask(|k| tested[k] & !blocked[k]);
    }
    let named = mask(|k| lit[k] & !planar[k]);
    if named.contains(&true) {
        let seen = world.framed_nearest((&so, &dir), &s.from(&dir), &named, false);
        for k in lanes_where(&named) {
            let (object, prim) = (seen.id[k], seen.prim[k]);
            let hit = seen.t[k] < f32::INFINITY;
            reached[k] = hit & (object == es[k].object) & (prim == es[k].prim);
        }
    }
    select(&reached, light, V::<W>::splat_vec(Vec3A::ZERO))
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
    /// Each path's number in the film's order ([`InOrder`]).
    number: [u64; W],
}

/// Sets lane `k` of `v` to `x`.
#[inline(always)]
fn set<const W: usize>(v: &mut V<W>, k: usize, x: Vec3A) {
    (v.x.0[k], v.y.0[k], v.z.0[k]) = (x.x, x.y, x.z);
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
    }

    /// Takes every live path one bounce further: its ray's hit, the
    /// light NEE gathers there, the bounce and the roulette; the lanes
    /// whose paths ended.
    #[inline(always)]
    fn step(&mut self, world: &World, flat: &Flat, settings: &PathSettings) -> [bool; W] {
        let started = self.live;
        let camera = mask(|k| self.bounce[k] == 0);
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
        // Left the scene: the environment, which camera rays alone count
        // (after a diffuse bounce, NEE has gathered the emitters).
        for k in lanes_where::<W>(&mask(|k| started[k] & !live[k] & camera[k])) {
            let le = world.sky(lane(&self.d, k));
            self.l.x.0[k] += le.x;
            self.l.y.0[k] += le.y;
            self.l.z.0[k] += le.z;
        }
        if live.contains(&true) {
            self.scatter(world, flat, settings, &hits, &mut live, &camera);
        }
        self.live = live;
        mask(|k| started[k] & !live[k])
    }

    /// [`Paths::step`] at the surfaces that the `live` lanes' rays met,
    /// `camera` the lanes of camera rays: ends the paths that end there.
    #[inline(always)]
    fn scatter(
        &mut self,
        world: &World,
        flat: &Flat,
        settings: &PathSettings,
        hits: &Answers<W>,
        live: &mut [bool; W],
        camera: &[bool; W],
    ) {
        let zero = V::<W>::splat_vec(Vec3A::ZERO);
        let s = Surfaces::of(flat, hits, live, &self.d);
        let seen = mask(|k| live[k] & camera[k]);
        if seen.contains(&true) {
            self.l = self.l + select(&seen, s.emission(), zero);
        }
        let depth = settings.max_depth;
        let bounce = self.bounce;
        *live = mask(|k| live[k] & !(depth != 0 && bounce[k] >= depth));
        if !live.contains(&true) {
            return;
        }
        let light = next_event(
            world,
            flat,
            &mut self.samplers,
            &bounce,
            &s,
            live,
            self.beta,
        );
        self.l = self.l + light;
        *live = mask(|k| live[k] & !(depth != 0 && bounce[k] + 1 >= depth));
        // The bounce: a cosine-weighted direction about the shading normal.
        let mut u = [(0.0f32, 0.0f32); W];
        for k in lanes_where(live) {
            u[k] = self.samplers[k].bsdf_2d();
        }
        let nd = cosine_hemisphere(s.ns, each::<W>(|k| u[k].0), each::<W>(|k| u[k].1));
        // A shading normal's direction below the surface carries nothing.
        let below = nd.dot(s.nl);
        *live = mask(|k| live[k] & !(s.smooth[k] & !(below.0[k] > 0.0)));
        let mut beta = mul(self.beta, s.albedo);
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
        (self.o, self.from) = (s.origin(&nd), s.from(&nd));
        self.d = nd;
    }
}
