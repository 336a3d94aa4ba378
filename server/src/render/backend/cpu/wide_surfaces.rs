//! The wide loop's surfaces and next-event estimation over lanes
//! (`wide_loop`), and the small helpers that move numbers between lanes
//! and arrays.

use crate::render::embree::Answers;
use crate::render::integrator::nee::SHADOW_EPSILON;
use crate::render::integrator::{Combine, PbrVertex};
use crate::render::lanes::{lanes_where, F32s, Real, Vector, V3};
use crate::render::light::points::{toward_point, triangle_point};
use crate::render::math::{gamma, step_toward_lanes, Vec3A};
use crate::render::sampler::Sampler;
use crate::render::world::flat::{Flat, FlatEmitter, FlatTri};
use crate::render::world::{Origin, World};
use std::f32::consts::FRAC_1_PI;

pub(super) type R<const W: usize> = F32s<W>;
pub(super) type V<const W: usize> = V3<F32s<W>>;

/// Lane `k` of `v`.
#[inline(always)]
pub(super) fn lane<const W: usize>(v: &V<W>, k: usize) -> Vec3A {
    Vec3A::new(v.x.0[k], v.y.0[k], v.z.0[k])
}

/// `f` of every lane, in a plain counted loop, which the compiler turns
/// into vector instructions (`array::from_fn`, with its drop guard, it
/// left one lane at a time).
#[inline(always)]
pub(super) fn per_lane<T: Copy + Default, const W: usize>(f: impl Fn(usize) -> T) -> [T; W] {
    let mut out = [T::default(); W];
    for (k, o) in out.iter_mut().enumerate() {
        *o = f(k);
    }
    out
}

/// A vector per lane from `f`'s.
#[inline(always)]
pub(super) fn gather<const W: usize>(f: impl Fn(usize) -> [f32; 3]) -> V<W> {
    let a: [[f32; 3]; W] = per_lane(f);
    V3 {
        x: F32s(per_lane(|k| a[k][0])),
        y: F32s(per_lane(|k| a[k][1])),
        z: F32s(per_lane(|k| a[k][2])),
    }
}

/// A number per lane from `f`'s.
#[inline(always)]
pub(super) fn each<const W: usize>(f: impl Fn(usize) -> f32) -> R<W> {
    F32s(per_lane(f))
}

/// `a` where `m`, else `b`, lane by lane.
#[inline(always)]
pub(super) fn select<const W: usize>(m: &[bool; W], a: V<W>, b: V<W>) -> V<W> {
    let s = |a: R<W>, b: R<W>| each(|k| if m[k] { a.0[k] } else { b.0[k] });
    V3 {
        x: s(a.x, b.x),
        y: s(a.y, b.y),
        z: s(a.z, b.z),
    }
}

/// Component-wise product.
#[inline(always)]
pub(super) fn mul<const W: usize>(a: V<W>, b: V<W>) -> V<W> {
    V3 {
        x: a.x * b.x,
        y: a.y * b.y,
        z: a.z * b.z,
    }
}

/// A lane mask from a test of each lane.
#[inline(always)]
pub(super) fn mask<const W: usize>(f: impl Fn(usize) -> bool) -> [bool; W] {
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
pub(super) struct Surfaces<'a, const W: usize> {
    /// The hit point (in the frame), its geometric normal and how far
    /// off it a ray starts (the point's rounding bound along the normal).
    pub(super) p: V<W>,
    pub(super) ng: V<W>,
    pub(super) dist: R<W>,
    /// The geometric and shading normals on the side the ray came from.
    pub(super) nl: V<W>,
    pub(super) ns: V<W>,
    /// Whether the ray met the surface from outside (by the geometric
    /// normal), and whether the shading normal is interpolated (not `nl`).
    pub(super) entering: [bool; W],
    pub(super) smooth: [bool; W],
    pub(super) albedo: V<W>,
    /// Each lane's triangle, as `Origin` and the emitters name it, and
    /// its record.
    pub(super) at: [(u32, u32); W],
    pub(super) tris: [&'a FlatTri; W],
}

impl<'a, const W: usize> Surfaces<'a, W> {
    /// The surfaces of `hits` (along directions `d`), gathered from the
    /// flat triangles: `Instance::surface`'s steps, in the frame.
    #[inline(always)]
    pub(super) fn of(flat: &'a Flat, hits: &Answers<W>, live: &[bool; W], d: &V<W>) -> Self {
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
        let entering = mask(|k| dn.0[k] < 0.0);
        let nl = select(&entering, ng, -ng);
        let sn = ns.dot(nl);
        let ns = select(&mask(|k| sn.0[k] < 0.0), -ns, ns);
        Surfaces {
            p: t0 + t1 + t2,
            ng,
            dist: abs(ng).dot(err),
            nl,
            ns: select(&smooth, ns, nl),
            entering,
            smooth,
            albedo: gather::<W>(|k| tris[k].albedo),
            at: std::array::from_fn(|k| (hits.id[k], hits.prim[k])),
            tris,
        }
    }

    /// The emission of each lane's triangle (zero where it emits none).
    #[inline(always)]
    pub(super) fn emission(&self) -> V<W> {
        gather::<W>(|k| self.tris[k].emission)
    }

    /// Where rays leaving along `dir` start.
    #[inline(always)]
    pub(super) fn origin(&self, dir: &V<W>) -> V<W> {
        spawn(self.p, self.ng, self.dist, *dir)
    }

    /// The surfaces rays leaving along `dir` leave, for a query that must
    /// not meet them again.
    #[inline(always)]
    pub(super) fn from(&self, dir: &V<W>) -> [Origin; W] {
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

/// Next-event estimation at the surfaces `s` of the lanes `gathers` names
/// (paths of throughput `beta`, their samplers set to vertex `bounce`): an emitter
/// and a point on it per lane (`nee::direct`'s draws), the shadow rays
/// traced together; the light that reaches each lane, `Shadow::light`'s
/// operations in its order. A diffuse lane's BSDF is computed over the
/// lanes; a `pbr` lane's (where `pbr` holds its vertex) one lane at a
/// time, weighed as `combine` says.
#[inline(always)]
pub(super) fn next_event<const W: usize>(
    world: &World,
    flat: &Flat,
    (samplers, bounce): (&mut [Sampler; W], &[u32; W]),
    s: &Surfaces<'_, W>,
    gathers: &[bool; W],
    beta: V<W>,
    (pbr, combine): (Option<&[Option<PbrVertex>; W]>, Combine),
) -> V<W> {
    let lights = &world.lights;
    let (mut index, mut pmf) = ([0usize; W], [1.0f32; W]);
    let (mut u1, mut u2) = ([0.0f32; W], [0.0f32; W]);
    let table = lights.table.as_ref().filter(|_| lights.emitters.len() > 1);
    for k in lanes_where(gathers) {
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
        gathers[k] & (sampled.0[k] != 0) & !under & (cos_s.0[k] > 0.0) & (toward.0[k] > 0.0)
    });
    // pre * ((Le * fw) / pmf) * post: for a diffuse lane, pre the
    // throughput times the albedo, fw cos times 1/pdf, post 1/pi; for a
    // `pbr` lane, pre the throughput, fw its BSDF's light times 1/pdf,
    // post 1.
    let mut fw = V3 {
        x: cos_s * weight,
        y: cos_s * weight,
        z: cos_s * weight,
    };
    let le = gather::<W>(|k| es[k].emission);
    let light = match pbr {
        None => mul(mul(beta, s.albedo), mul(le, fw) / F32s(pmf)) * R::<W>::splat(FRAC_1_PI),
        Some(pbr) => {
            let glossy = mask(|k| pbr[k].is_some());
            for k in lanes_where(&mask::<W>(|k| lit[k] & glossy[k])) {
                if let Some(v) = &pbr[k] {
                    let w = weight.0[k];
                    set(&mut fw, k, v.light(combine, lane(&dir, k), pmf[k] / w) * w);
                }
            }
            let pre = select(&glossy, beta, mul(beta, s.albedo));
            let post = each::<W>(|k| if glossy[k] { 1.0 } else { FRAC_1_PI });
            mul(pre, mul(le, fw) / F32s(pmf)) * post
        }
    };
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

/// Sets lane `k` of `v` to `x`.
#[inline(always)]
pub(super) fn set<const W: usize>(v: &mut V<W>, k: usize, x: Vec3A) {
    (v.x.0[k], v.y.0[k], v.z.0[k]) = (x.x, x.y, x.z);
}
