//! Prototype for issue 32, not the renderer: `cornell-mesh`'s paths sixteen
//! at a time, Mitsuba's megakernel shape. A pixel's sixteen samples run in
//! step, their state (ray, throughput, radiance, random numbers) in lanes
//! from the camera to their ends; the random numbers, the light samples,
//! the BSDF samples, the throughputs and roulette are computed over the
//! sixteen lanes at once. Lanes whose paths ended stay masked (no
//! compaction: in a closed box they end together). By default the rays
//! (path and shadow), the surfaces and the spawned origins stay one per
//! lane, through the renderer's own `World::intersect`, `World::surface`
//! and `World::spawn`.
//!
//! cornell-mesh only (diffuse meshes, triangle emitters, no environment),
//! its near clip at 0 as `scripts/mitsuba-compare.py` renders it. Its own
//! random numbers (a hash per lane and dimension), so its image agrees
//! with `pathstream render --sampler random` in expectation, not bit for
//! bit (`pathstream diff` against a long render says how far).
//!
//! ```text
//! apt-get install -y libembree-dev        # Debian: Embree 3.13.5
//! cargo run --release -p pathstream --features embree --example wide_paths -- \
//!     [SPP] [ROUNDS] [--embree] [--simd-surface [--robust-spawn[=camera]]] [--sobol]
//! ```
//!
//! - `--embree`: the lanes' rays go through Embree in packets of sixteen
//!   (one flat scene of every placed triangle, `RTC_BUILD_QUALITY_HIGH`,
//!   default flags: Mitsuba's set-up): path rays by `rtcIntersect16`,
//!   shadow rays by `rtcOccluded16` up to 0.999 of the light point's
//!   distance; origins moved off the surface as Mitsuba moves them.
//! - `--simd-surface`: the surfaces over lanes too, Mitsuba's way (the
//!   hit point from the ray, the vertex normals interpolated over lanes,
//!   origins moved off by an epsilon over lanes, nothing skipped): see
//!   `flat.rs`. With the own BVH, rays then leave no triangle out.
//! - `--robust-spawn` (with `--simd-surface`): the renderer's spawn
//!   instead of the epsilon, over lanes: the object-space hit point and
//!   its error bound, moved that far and rounded away from the plane, then
//!   mapped to camera space (`flat::Robust`).
//!
//! - `--sobol`: Sobol points in the renderer's way over lanes (see `Rng`).
//!
//! Writes the first round's image to `/tmp/wide-paths.pfm`. Results:
//! docs/BENCHMARKS.md, "Paths in lanes, a prototype". AVX-512 only.

// Lane `k` of several arrays at once.
#![allow(clippy::needless_range_loop)]

use pathstream::render::isa::Avx512;
use pathstream::render::lanes::{Bits, F32s, Real, U32s, Vector, V3};
use pathstream::render::light::points::{toward_point, triangle_point};
use pathstream::render::light::{EmitterShape, LightTri};
use pathstream::render::material::cosine_hemisphere;
use pathstream::render::math::Vec3A;
use pathstream::render::ray::Ray;
use pathstream::render::sampler::sobol::{hash32, lk_hash, superset_sum};
use pathstream::render::world::{Hit, Origin, Surface, World};
use pathstream::render::{Quality, RenderJob};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::time::Instant;

mod flat;
mod tracer;

use flat::{leave_lanes, Flat, Robust, RobustCam};
use tracer::{ffi, Device, EmbreeScene, Tracer};

const L: usize = 16;
const SIZE: u32 = 128;
const MAX_DEPTH: u32 = 6;
const RR_DEPTH: u32 = 5;
type R = F32s<L>;
type U = U32s<L>;
type V = V3<R>;

/// The lanes' random numbers: a hash per lane and dimension, or with
/// `--sobol` the renderer's kind of points (`sampler::sobol`): each
/// pixel's even and odd samples two independently scrambled (0,2)-
/// sequences, a point's index shuffled by a nested uniform scramble and
/// its values Owen-scrambled, the seeds hashed from (pixel, dimension,
/// half). Not the renderer's bits; its work, over lanes.
struct Rng {
    key: U,
    n: u32,
    sobol: Option<(u32, U, U)>,
}

impl Rng {
    /// Samples `s0..s0 + 16` of pixel `pixel`.
    #[inline(always)]
    fn new(pixel: u32, s0: u32, sobol: bool) -> Rng {
        let key = hash32(U32s(std::array::from_fn(|k| pixel * 8192 + s0 + k as u32)));
        let sobol = sobol.then(|| {
            let s = |k: usize| s0 + k as u32;
            (
                pixel,
                U32s(std::array::from_fn(|k| (s(k) >> 1).reverse_bits())),
                U32s(std::array::from_fn(|k| s(k) & 1)),
            )
        });
        Rng { key, n: 0, sobol }
    }

    #[inline(always)]
    fn unit(b: U) -> R {
        F32s(b.0.map(|b| (b >> 8) as f32 * (1.0 / 16_777_216.0)))
    }

    #[inline(always)]
    fn next(&mut self) -> R {
        match self.sobol {
            // A 1-D point: the van der Corput point of the shuffled index,
            // which is the shuffle's hash itself (`sampler::sobol`).
            Some((pixel, rindex, half)) => {
                self.n += 1;
                let (a, b) = (
                    hash32(pixel ^ (self.n << 20)),
                    hash32(pixel ^ (self.n << 20) ^ (1 << 31)),
                );
                let seed = U32s(std::array::from_fn(|k| if half.0[k] != 0 { b } else { a }));
                Self::unit(lk_hash(rindex, seed))
            }
            None => {
                self.n += 1;
                Self::unit(hash32(
                    self.key ^ U::splat(self.n.wrapping_mul(0x9e37_79b9)),
                ))
            }
        }
    }

    #[inline(always)]
    fn next_2d(&mut self) -> (R, R) {
        let Some((pixel, rindex, half)) = self.sobol else {
            return (self.next(), self.next());
        };
        self.n += 1;
        // Three seeds per half, chosen lane by lane.
        let seeds = [0u32, 1].map(|h| {
            let k = hash32(pixel ^ (self.n << 20) ^ (h << 31));
            let x = hash32(k ^ 0x68bc_21eb);
            (k, x, hash32(x ^ 0x2545_f491))
        });
        // Lane by lane, the seed of its half (a select, no call).
        let seed =
            |a: u32, b: u32| U32s(std::array::from_fn(|k| if half.0[k] != 0 { b } else { a }));
        let (s0, s1) = (seeds[0], seeds[1]);
        let shuffled = lk_hash(rindex, seed(s0.0, s1.0)).reverse_bits();
        let x = lk_hash(shuffled, seed(s0.1, s1.1)).reverse_bits();
        let y = lk_hash(superset_sum(shuffled), seed(s0.2, s1.2)).reverse_bits();
        (Self::unit(x), Self::unit(y))
    }
}

/// One of the lamp's triangles, its emission and which triangle of the
/// world it is (object, prim).
struct LampTri {
    tri: LightTri,
    emission: Vec3A,
    id: (u32, u32),
}

/// How rays leave a surface in `--simd-surface` mode.
#[derive(Clone, Copy)]
enum Spawn {
    /// Mitsuba's epsilon.
    Epsilon,
    /// The renderer's: object space, error bound, round trip (`Robust`).
    Object,
    /// The same bound in camera space, on the flat scene's vertices.
    Camera,
}

/// A vertex's spawn data, by [`Spawn`] (on the stack, one a vertex: not
/// boxed, which would allocate at every vertex).
#[allow(clippy::large_enum_variant)]
enum Origins {
    Object(Robust),
    Camera(RobustCam),
}

/// What every pixel reads.
struct Ctx<'a> {
    world: &'a World,
    job: &'a RenderJob,
    lamp: Vec<LampTri>,
    tracer: Tracer<'a>,
    isa: Avx512,
    /// With `--simd-surface`: surfaces over lanes.
    flat: Option<&'a Flat>,
    /// With `--robust-spawn[=camera]` too: the renderer's spawn over lanes.
    robust: Spawn,
    /// The flat scene's camera-space vertices.
    positions: &'a [[f32; 3]],
    /// With `--sobol`: Sobol points, not hashes.
    sobol: bool,
}

fn lane(v: &V, k: usize) -> Vec3A {
    Vec3A::new(v.x.0[k], v.y.0[k], v.z.0[k])
}

fn set(v: &mut V, k: usize, x: Vec3A) {
    v.x.0[k] = x.x;
    v.y.0[k] = x.y;
    v.z.0[k] = x.z;
}

fn zero() -> V {
    V::splat_vec(Vec3A::ZERO)
}

/// The sixteen samples `s0..s0 + 16` of pixel (x, y): their radiance sum.
#[inline(always)]
fn pixel(ctx: &Ctx, x: u32, y: u32, s0: u32) -> Vec3A {
    let (world, job, tracer, isa) = (ctx.world, ctx.job, &ctx.tracer, ctx.isa);
    let c = R::splat;
    let mut rng = Rng::new(y * SIZE + x, s0, ctx.sobol);
    let (u1, u2) = rng.next_2d();
    let (mut o, mut d) = (zero(), zero());
    for k in 0..L {
        let r = job.camera.ray(x as f32 + u1.0[k], y as f32 + u2.0[k]);
        set(&mut o, k, r.origin);
        set(&mut d, k, r.dir);
    }
    let mut alive = [true; L];
    let mut from = [Origin::NONE; L];
    let mut beta = V::splat_vec(Vec3A::ONE);
    let mut l = zero();
    let mut emit = c(1.0);
    let mut surf: [Option<Surface>; L] = [None; L];
    for bounce in 0.. {
        // Rays and surfaces, lane by lane.
        let (mut p, mut ng, mut ns) = (zero(), zero(), zero());
        let (mut albedo, mut emission) = (zero(), zero());
        let mut smooth = [false; L];
        let mut robust = None;
        if let Some(flat) = ctx.flat {
            let os: [Vec3A; L] = std::array::from_fn(|k| lane(&o, k));
            let ds: [Vec3A; L] = std::array::from_fn(|k| lane(&d, k));
            let found = match tracer {
                Tracer::Embree(scene, _) => scene.nearest16(&os, &ds, &alive, false),
                // The own BVH told nothing of the triangle a ray leaves
                // either (the origins are moved off as for Embree); hits
                // as flat triangle numbers.
                Tracer::Own => std::array::from_fn(|k| {
                    let ray = Ray::new(os[k], ds[k]);
                    let h = alive[k]
                        .then(|| world.intersect(isa, &ray, Origin::NONE))
                        .flatten()?;
                    Some(Hit {
                        prim: flat.first[h.object as usize] + h.prim,
                        ..h
                    })
                }),
            };
            let (mut t, mut b) = (c(0.0), [c(1.0 / 3.0); 3]);
            // Lanes without a hit keep a unit normal (no NaN to mask).
            let mut n = [V::splat_vec(Vec3A::Z); 3];
            ng = V::splat_vec(Vec3A::Z);
            for k in 0..L {
                let Some(h) = found[k] else {
                    alive[k] = false;
                    continue;
                };
                let i = h.prim as usize;
                t.0[k] = h.t;
                let g = flat.ng[i];
                set(&mut ng, k, g);
                for j in 0..3 {
                    b[j].0[k] = h.bary[j];
                    let v = if flat.smooth[i] {
                        flat.vn[flat.tris[i][j] as usize]
                    } else {
                        g
                    };
                    set(&mut n[j], k, v);
                }
                set(&mut albedo, k, flat.albedo[i]);
                set(&mut emission, k, flat.emission[i]);
                smooth[k] = flat.smooth[i];
            }
            p = o + d * t;
            ns = (n[0] * b[0] + n[1] * b[1] + n[2] * b[2]).normalize();
            let prims = std::array::from_fn(|k| found[k].map(|h| h.prim));
            match ctx.robust {
                Spawn::Epsilon => {}
                Spawn::Object => {
                    let r = Robust::gather(world, flat, &prims, &b);
                    p = r.point();
                    robust = Some(Origins::Object(r));
                }
                Spawn::Camera => {
                    let r = RobustCam::gather(flat, ctx.positions, &prims, &b);
                    p = r.point();
                    robust = Some(Origins::Camera(r));
                }
            }
        }
        let hits = match ctx.flat {
            Some(_) => [None; L],
            None => tracer.trace(world, isa, &o, &d, &from, &alive),
        };
        for k in 0..L {
            if ctx.flat.is_some() {
                break;
            }
            surf[k] = None;
            if !alive[k] {
                continue;
            }
            let ray = Ray::new(lane(&o, k), lane(&d, k));
            match hits[k] {
                None => alive[k] = false,
                Some(h) => {
                    let s = world.surface(&h, &ray);
                    let m = world.material(s.material);
                    set(&mut p, k, s.p);
                    set(&mut ng, k, s.ng);
                    set(&mut ns, k, s.ns);
                    set(&mut albedo, k, m.albedo);
                    if m.emissive {
                        set(&mut emission, k, m.emission);
                    }
                    smooth[k] = s.smooth;
                    surf[k] = Some(s);
                }
            }
        }
        l = l + V::new(
            beta.x * emission.x,
            beta.y * emission.y,
            beta.z * emission.z,
        ) * emit;
        if bounce >= MAX_DEPTH || !alive.iter().any(|a| *a) {
            break;
        }
        // Normals on the ray's side, over lanes.
        let nl = ng * c(1.0).copysign(-d.dot(ng));
        let ns = ns * c(1.0).copysign(ns.dot(nl));
        // A light sample: a lamp triangle per lane, a point on it.
        let pick = rng.next();
        let (u1, u2) = rng.next_2d();
        let count = ctx.lamp.len();
        let (mut p0, mut e1, mut e2, mut n) = (zero(), zero(), zero(), zero());
        let (mut area, mut le) = (c(0.0), zero());
        let mut target = [(0u32, 0u32); L];
        for k in 0..L {
            let i = ((pick.0[k] * count as f32) as usize).min(count - 1);
            let t = &ctx.lamp[i];
            set(&mut p0, k, t.tri.p0);
            set(&mut e1, k, t.tri.e1);
            set(&mut e2, k, t.tri.e2);
            set(&mut n, k, t.tri.n);
            area.0[k] = t.tri.area;
            set(&mut le, k, t.emission);
            target[k] = t.id;
        }
        let q = triangle_point(p0, e1, e2, u1, u2);
        let (dir, weight, found) = toward_point(p, q, n, area);
        let cos_s = ns.dot(dir);
        let w = cos_s * weight * c(count as f32 * FRAC_1_PI);
        let f = V::new(
            beta.x * albedo.x * le.x,
            beta.y * albedo.y * le.y,
            beta.z * albedo.z * le.z,
        ) * w;
        let toward = nl.dot(dir);
        let mut lit = c(0.0);
        let mut shadow = [false; L];
        let (mut so, mut sfrom) = (zero(), [Origin::NONE; L]);
        if ctx.flat.is_some() {
            so = match &robust {
                Some(Origins::Object(r)) => r.origin(ng, dir),
                Some(Origins::Camera(r)) => r.origin(dir),
                None => leave_lanes(p, ng, dir),
            };
            for k in 0..L {
                shadow[k] = alive[k] && found.0[k] != 0 && cos_s.0[k] > 0.0 && toward.0[k] > 0.0;
            }
        }
        for k in 0..L {
            if ctx.flat.is_some() {
                break;
            }
            let Some(s) = &surf[k] else { continue };
            if found.0[k] == 0 || !(cos_s.0[k] > 0.0 && toward.0[k] > 0.0) {
                continue;
            }
            let dk = lane(&dir, k);
            set(&mut so, k, tracer.leave(world, s, dk));
            sfrom[k] = Origin {
                object: s.object,
                prim: s.prim,
                entering: dk.dot(s.ng) < 0.0,
            };
            shadow[k] = true;
        }
        let reached = tracer.unblocked(world, isa, (&so, &dir, &q), &sfrom, &shadow, &target);
        for k in 0..L {
            if reached[k] {
                lit.0[k] = 1.0;
            }
        }
        l = l + f * lit;
        if bounce + 1 >= MAX_DEPTH {
            break;
        }
        // The bounce, over lanes.
        let (v1, v2) = rng.next_2d();
        let nd = cosine_hemisphere(ns, v1, v2);
        beta = V::new(beta.x * albedo.x, beta.y * albedo.y, beta.z * albedo.z);
        emit = c(0.0);
        let below = nd.dot(nl);
        let survive = rng.next();
        let roulette = bounce + 1 > RR_DEPTH;
        let q = beta.x.max(beta.y).max(beta.z).0.map(|v| v.min(0.99));
        for k in 0..L {
            if !alive[k] {
                continue;
            }
            if smooth[k] && !(below.0[k] > 0.0) {
                alive[k] = false;
                continue;
            }
            if roulette {
                if !(survive.0[k] < q[k]) {
                    alive[k] = false;
                    continue;
                }
                let b = lane(&beta, k) / q[k];
                set(&mut beta, k, b);
            }
        }
        if ctx.flat.is_some() {
            o = match &robust {
                Some(Origins::Object(r)) => r.origin(ng, nd),
                Some(Origins::Camera(r)) => r.origin(nd),
                None => leave_lanes(p, ng, nd),
            };
            d = nd;
            continue;
        }
        for k in 0..L {
            let (true, Some(s)) = (alive[k], &surf[k]) else {
                continue;
            };
            let dk = lane(&nd, k);
            set(&mut o, k, tracer.leave(world, s, dk));
            set(&mut d, k, dk);
            from[k] = Origin {
                object: s.object,
                prim: s.prim,
                entering: dk.dot(s.ng) < 0.0,
            };
        }
    }
    (0..L).map(|k| lane(&l, k)).sum()
}

#[allow(unsafe_code)]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq")]
fn row(ctx: &Ctx, y: u32, spp: u32) -> Vec<Vec3A> {
    (0..SIZE)
        .map(|x| {
            let mut sum = Vec3A::ZERO;
            for s0 in (0..spp).step_by(L) {
                sum += pixel(ctx, x, y, s0);
            }
            sum / spp as f32
        })
        .collect()
}

fn main() {
    let args: Vec<u32> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let spp = args.first().copied().unwrap_or(64).div_ceil(L as u32) * L as u32;
    let rounds = args.get(1).copied().unwrap_or(3);
    let isa = Avx512::detect().expect("this prototype needs AVX-512");
    let mut scene = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    scene.camera.near_clip = 0.0;
    let job = RenderJob::new(&scene, SIZE, SIZE, &Quality::default());
    let world = &job.world;
    let lamp: Vec<LampTri> = world
        .lights
        .emitters
        .iter()
        .filter_map(|e| match &e.shape {
            EmitterShape::Triangle(tri) => Some(LampTri {
                tri: *tri,
                emission: e.emission,
                id: (e.object, e.prim),
            }),
            _ => None,
        })
        .collect();
    assert_eq!(
        lamp.len(),
        world.lights.emitters.len(),
        "triangle emitters only"
    );
    let use_embree = std::env::args().any(|a| a == "--embree");
    let device = Device::new("threads=2");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut map = Vec::new();
    for (i, inst) in world.instances.iter().enumerate() {
        let object = world
            .objects
            .iter()
            .position(|o| matches!(o.geometry, pathstream::render::world::Geometry::Instance(j) if j as usize == i))
            .expect("the instance's object") as u32;
        let base = positions.len() as u32;
        let first = triangles.len() as u32;
        for p in inst.mesh.positions.iter() {
            positions.push(
                inst.cam_from_obj
                    .transform_point3a(Vec3A::from(*p))
                    .to_array(),
            );
        }
        for t in inst.mesh.triangles.iter() {
            triangles.push(t.map(|v| v + base));
            map.push((object, first));
        }
    }
    let scene = EmbreeScene::build(
        &device,
        &positions,
        &triangles,
        ffi::RTC_SCENE_FLAG_NONE,
        ffi::RTC_BUILD_QUALITY_HIGH,
    );
    let tracer = if use_embree {
        Tracer::Embree(&scene, &map)
    } else {
        Tracer::Own
    };
    let simd_surface = std::env::args().any(|a| a == "--simd-surface");
    let flat = simd_surface.then(|| Flat::build(world, &triangles, &map));
    let ctx = Ctx {
        world,
        job: &job,
        lamp,
        tracer,
        isa,
        flat: flat.as_ref(),
        robust: match std::env::args()
            .find(|a| a.starts_with("--robust-spawn"))
            .as_deref()
        {
            None => Spawn::Epsilon,
            Some("--robust-spawn=camera") => Spawn::Camera,
            Some(_) => Spawn::Object,
        },
        positions: &positions,
        sobol: std::env::args().any(|a| a == "--sobol"),
    };
    for round in 0..rounds {
        let start = Instant::now();
        let rows: Vec<Vec<Vec3A>> = (0..SIZE)
            .into_par_iter()
            .map(|y| {
                // SAFETY: `isa` exists only where the CPU has these features.
                #[allow(unsafe_code)]
                unsafe {
                    row(&ctx, y, spp)
                }
            })
            .collect();
        let secs = start.elapsed().as_secs_f64();
        let paths = f64::from(SIZE * SIZE * spp);
        println!(
            "round {round}: {spp} spp in {secs:.2} s, {:.2} M paths/s",
            paths / secs / 1e6
        );
        if round == 0 {
            let mut out = String::from("PF\n128 128\n-1.0\n").into_bytes();
            for r in rows.iter().rev() {
                for v in r {
                    for c in [v.x, v.y, v.z] {
                        out.extend_from_slice(&c.to_le_bytes());
                    }
                }
            }
            std::fs::write("/tmp/wide-paths.pfm", out).expect("written");
        }
    }
}
