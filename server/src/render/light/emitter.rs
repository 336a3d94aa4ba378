//! The scene's emitters as next-event estimation samples them: emissive
//! spheres, quads and triangles (each triangle of an emissive mesh is an
//! emitter of its own), and the environment.
//!
//! Sampling, per shading point, a direction and 1/pdf of it (solid angle):
//! - spheres seen from outside: uniformly in the cone they subtend (exact
//!   for tiny lights); from inside, or from their own inner surface (the
//!   furnace), uniformly by area, since every point is then visible;
//! - quads and triangles: uniformly by area;
//! - a uniform environment: cosine-weighted about the shading normal;
//! - an environment map: in proportion to its brightness (`envmap`);
//! - a computed sky's sun: uniformly in the cone of its disc.
//!
//! Every emitter is two-sided (emission leaves both sides of a surface).
//!
//! ## Adding an emitter kind ([`EmitterShape`])
//! 1. Here: its `EmitterShape` variant, its `power`, how
//!    `sample_direction` samples it (a chi-square test of the pdf) and
//!    `pdf_direction`, the same density for MIS (`emitter_tests.rs`).
//! 2. `render/world/emitters.rs`: which objects make it; the shadow ray's
//!    visibility test in `render/integrator/nee.rs`.
//! 3. OpenCL: a `LIGHT_` constant and its packing (`kernel_lights` in
//!    `backend/opencl/layout.rs`), its `HAS_` feature (`program.rs`), its
//!    cases in `kernels/lights.h` (`sample_emitter`, `emitter_pdf`), and a
//!    case in the light-sampling parity tests
//!    (`tests/opencl_parity_meshes.rs`).

use super::pick::PickTable;
use super::points::{
    flat_weight, in_cone, quad_point, sphere_weight, toward_point, toward_sphere_point,
    triangle_point,
};
use super::sky::EnvLight;
use crate::render::material::cosine_hemisphere;
use crate::render::math::Vec3A;
use crate::render::shape::{Quad, Sphere};
use std::f32::consts::{PI, TAU};

/// An emissive triangle in camera-relative space.
#[derive(Clone, Copy, Debug)]
pub struct LightTri {
    pub p0: Vec3A,
    pub e1: Vec3A,
    pub e2: Vec3A,
    /// Unit normal.
    pub n: Vec3A,
    pub area: f32,
}

#[derive(Clone, Debug)]
pub enum EmitterShape {
    Sphere(Sphere),
    Quad(Quad),
    Triangle(LightTri),
    /// A uniform environment (its radiance the emitter's `emission`).
    Environment,
    /// An environment map.
    Map(std::sync::Arc<EnvLight>),
    /// A computed sky's sun: a disc infinitely far away.
    Sun(SunLight),
}

/// The sun as an emitter: the directions within its angular radius of
/// `dir`, each with the emitter's `emission`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunLight {
    /// Unit direction towards the disc's centre (world).
    pub dir: Vec3A,
    /// 1 - cos(angular radius), computed without cancellation (a 0.27
    /// degree disc has 1.1e-5).
    pub one_minus_cos: f32,
}

impl SunLight {
    /// The sun of angular radius `radius` (radians) towards unit `dir`.
    pub fn new(dir: Vec3A, radius: f64) -> Self {
        Self {
            dir,
            one_minus_cos: (2.0 * (radius / 2.0).sin().powi(2)) as f32,
        }
    }

    /// Whether unit direction `d` looks into the disc: 1 - cos of its
    /// angle to the centre (|d - dir|^2 / 2, no cancellation) at most the
    /// disc's.
    #[inline(always)]
    pub fn covers(&self, d: Vec3A) -> bool {
        0.5 * (d - self.dir).length_squared() <= self.one_minus_cos
    }

    /// The disc's solid angle.
    #[inline(always)]
    pub fn solid_angle(&self) -> f32 {
        TAU * self.one_minus_cos
    }

    /// A direction uniformly in the disc's cone, and 1/pdf (its solid angle).
    #[inline(always)]
    pub fn sample(&self, u1: f32, u2: f32) -> (Vec3A, f32) {
        (
            in_cone(self.dir, self.one_minus_cos, u1, u2),
            self.solid_angle(),
        )
    }
}

/// The point a shadow ray leaves from, as light sampling sees it.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub p: Vec3A,
    /// The object and primitive the point is on (an emitter does not
    /// sample itself, except a sphere seen from inside).
    pub object: u32,
    pub prim: u32,
    /// Geometric and shading normals, on the side the path arrived from.
    pub nl: Vec3A,
    pub ns: Vec3A,
}

/// One thing next-event estimation can aim at.
#[derive(Clone, Debug)]
pub struct Emitter {
    /// The object a shadow ray must hit to see it (unused for the environment).
    pub object: u32,
    /// The triangle of that object, or the world's `NO_PRIM`.
    pub prim: u32,
    /// Its material's emission (before its emission map, if any).
    pub emission: Vec3A,
    pub shape: EmitterShape,
    /// The material's maps (`World::maps`) where it has an emission map,
    /// else `NO_MAPS`: a shadow ray that reaches it reads the map there.
    pub maps: u32,
    /// The emission map's mean colour (1 without one): the pick weighs by it.
    pub mean: Vec3A,
}

/// Every emitter, and a table that picks one in proportion to its power.
#[derive(Clone, Debug, Default)]
pub struct Lights {
    pub emitters: Vec<Emitter>,
    pub table: Option<PickTable>,
    /// Each emitter's weight in the table (its power, up to a factor).
    power: Vec<f64>,
}

/// Radiance's brightness for the power estimate.
fn brightness(e: Vec3A) -> f64 {
    f64::from(e.x + e.y + e.z) / 3.0
}

impl Lights {
    /// These emitters, with a table that picks one in proportion to its
    /// power; an environment among them counts as seen from everywhere
    /// within `radius` of the origin.
    pub fn new(emitters: Vec<Emitter>, radius: f64) -> Self {
        debug_assert!(
            emitters
                .windows(2)
                .all(|w| (w[0].object, w[0].prim) < (w[1].object, w[1].prim)),
            "emitters in (object, prim) order, for index_of"
        );
        let power: Vec<f64> = emitters.iter().map(|e| e.power(radius)).collect();
        Self {
            table: PickTable::new(&power),
            emitters,
            power,
        }
    }

    /// Scales emitter `i`'s weight in the table by `factor` (> 0): it is
    /// then picked less often, and every estimate divides by its new
    /// probability, so images stay unbiased.
    pub fn scale_power(&mut self, i: usize, factor: f64) {
        self.power[i] *= factor;
        self.table = PickTable::new(&self.power);
    }

    /// Gives emitter `i` the weight that makes its pick probability
    /// `share` (in (0, 1)) of all (the others keep their proportions).
    pub fn set_share(&mut self, i: usize, share: f64) {
        let others: f64 = (self.power.iter().enumerate())
            .filter(|&(k, _)| k != i)
            .map(|(_, p)| p)
            .sum();
        self.power[i] = others * share / (1.0 - share);
        self.table = PickTable::new(&self.power);
    }

    pub fn is_empty(&self) -> bool {
        self.emitters.is_empty()
    }

    /// The emitter that is triangle `prim` of `object` (or the whole
    /// object, `prim` the world's `NO_PRIM`). The list is in object order
    /// and a mesh's triangles in triangle order (`world/emitters.rs`), so
    /// this is a binary search; the kernel's `light_index` does the same.
    #[inline(always)]
    pub fn index_of(&self, object: u32, prim: u32) -> Option<usize> {
        self.emitters
            .binary_search_by(|e| (e.object, e.prim).cmp(&(object, prim)))
            .ok()
    }

    /// The environment's emitter (always the last).
    #[inline(always)]
    pub fn environment(&self) -> Option<usize> {
        let last = self.emitters.len().checked_sub(1)?;
        self.emitters[last].shape.is_environment().then_some(last)
    }

    /// The sun's emitter (just before the environment's, or the last).
    #[inline(always)]
    pub fn sun(&self) -> Option<usize> {
        let n = self.emitters.len();
        (n.saturating_sub(2)..n).find(|&i| matches!(self.emitters[i].shape, EmitterShape::Sun(_)))
    }

    /// The emitters infinitely far away (the sun, the environment), which
    /// a shadow ray sees by leaving the scene.
    pub fn distant(&self) -> impl Iterator<Item = usize> + '_ {
        (self.emitters.iter().enumerate())
            .filter(|(_, e)| e.shape.is_distant())
            .map(|(i, _)| i)
    }

    /// The probability that one power-proportional pick chooses emitter
    /// `i`: 1 for the only one, 0 where nothing is picked (no table).
    #[inline(always)]
    pub fn pick_pmf(&self, i: usize) -> f32 {
        match (self.emitters.len(), &self.table) {
            (1, _) => 1.0,
            (_, Some(t)) => t.pmf(i),
            (_, None) => 0.0,
        }
    }
}

impl EmitterShape {
    /// Whether this is the environment (uniform or a map): what rays that
    /// leave the scene meet.
    #[inline(always)]
    pub fn is_environment(&self) -> bool {
        matches!(self, EmitterShape::Environment | EmitterShape::Map(_))
    }

    /// Whether a shadow ray sees this emitter by leaving the scene.
    #[inline(always)]
    pub fn is_distant(&self) -> bool {
        matches!(
            self,
            EmitterShape::Environment | EmitterShape::Map(_) | EmitterShape::Sun(_)
        )
    }
}

impl Emitter {
    /// The radiance this emitter sends along `-dir` (towards a receiver
    /// looking along unit `dir`).
    #[inline(always)]
    pub fn radiance(&self, dir: Vec3A) -> Vec3A {
        match &self.shape {
            EmitterShape::Map(m) => m.radiance(dir),
            _ => self.emission,
        }
    }

    /// Power up to a common factor (brightness x area, the solid-angle
    /// factor folded into the constants; only ratios matter): an
    /// environment as bright as a sphere of `radius` lit from everywhere.
    fn power(&self, radius: f64) -> f64 {
        let b = brightness(self.emission * self.mean);
        match &self.shape {
            EmitterShape::Sphere(s) => {
                let r = f64::from(s.radius);
                b * 4.0 * std::f64::consts::PI * r * r
            }
            EmitterShape::Quad(q) => b * 2.0 * f64::from(q.area),
            EmitterShape::Triangle(t) => b * 2.0 * f64::from(t.area),
            EmitterShape::Environment => b * 4.0 * std::f64::consts::PI * radius * radius,
            EmitterShape::Map(m) => {
                m.mean_brightness() * 4.0 * std::f64::consts::PI * radius * radius
            }
            EmitterShape::Sun(sun) => b * f64::from(sun.solid_angle()) * radius * radius,
        }
    }

    /// Whether `r` lies on this emitter's own surface (its object and,
    /// for a triangle, its triangle): sampling and its density both ask.
    /// One comparison of the bits: `a == b && c == d` would branch on the
    /// object first, which goes either way where the receiver is on the
    /// emitter's mesh.
    #[inline(always)]
    fn under(&self, r: &Receiver) -> bool {
        ((self.object ^ r.object) | (self.prim ^ r.prim)) == 0
    }

    /// A direction from `r` towards this emitter and 1/pdf (solid angle)
    /// of choosing it.
    #[inline(always)]
    pub fn sample_direction(&self, r: &Receiver, u1: f32, u2: f32) -> Option<(Vec3A, f32)> {
        let (s, nl, ns) = (r, r.nl, r.ns);
        let on_self = self.under(r);
        match &self.shape {
            EmitterShape::Sphere(sphere) => sample_sphere(sphere, s.p, nl, on_self, u1, u2),
            EmitterShape::Quad(q) => {
                if on_self {
                    return None;
                }
                let at = quad_point(q.corner, q.edge_u, q.edge_v, u1, u2);
                toward(s.p, at, q.normal, q.area)
            }
            EmitterShape::Triangle(t) => {
                if on_self {
                    return None;
                }
                toward(s.p, triangle_point(t.p0, t.e1, t.e2, u1, u2), t.n, t.area)
            }
            EmitterShape::Environment => {
                let dir = cosine_hemisphere(ns, u1, u2);
                let cos = ns.dot(dir);
                (cos > 0.0).then(|| (dir, PI / cos))
            }
            EmitterShape::Map(m) => m.sample(u1, u2),
            EmitterShape::Sun(sun) => Some(sun.sample(u1, u2)),
        }
    }
}

impl Emitter {
    /// The density (solid angle) with which [`Emitter::sample_direction`]
    /// from `r` gives the unit direction `dir` that meets this emitter at
    /// `q` (ignored for the environment): what multiple importance
    /// sampling weighs a BSDF sample that found the emitter against. The
    /// same branches and formulas as sampling, so that 1/pdf is the weight
    /// sampling would have returned for that direction; 0 where sampling
    /// cannot give it.
    #[inline(always)]
    pub fn pdf_direction(&self, r: &Receiver, dir: Vec3A, q: Vec3A) -> f32 {
        let on_self = self.under(r);
        let weight = match &self.shape {
            EmitterShape::Sphere(s) => {
                let Some(v) = SphereView::new(s, r.p, r.nl, on_self) else {
                    return 0.0;
                };
                if v.inside {
                    let m = (q - s.center) * (1.0 / s.radius);
                    sphere_weight(m, dir, v.r2, (q - r.p).length_squared())
                } else {
                    TAU * v.one_minus_cos_max()
                }
            }
            EmitterShape::Quad(quad) if !on_self => {
                flat_weight(quad.normal, dir, quad.area, (q - r.p).length_squared())
            }
            EmitterShape::Triangle(t) if !on_self => {
                flat_weight(t.n, dir, t.area, (q - r.p).length_squared())
            }
            EmitterShape::Quad(_) | EmitterShape::Triangle(_) => return 0.0,
            EmitterShape::Environment => {
                let cos = r.ns.dot(dir);
                if !(cos > 0.0) {
                    return 0.0;
                }
                PI / cos
            }
            EmitterShape::Map(m) => return m.pdf(dir),
            EmitterShape::Sun(sun) => match sun.covers(dir) {
                true => sun.solid_angle(),
                false => 0.0,
            },
        };
        if weight > 0.0 {
            1.0 / weight
        } else {
            0.0
        }
    }
}

/// The direction from `p` towards `q`, a point drawn uniformly on a surface
/// of unit normal `n` and area `area`, and 1/pdf of it (solid angle).
#[inline(always)]
fn toward(p: Vec3A, q: Vec3A, n: Vec3A, area: f32) -> Option<(Vec3A, f32)> {
    found(toward_point(p, q, n, area))
}

/// A direction and its weight where the mask says there is one.
#[inline(always)]
fn found((dir, weight, mask): (Vec3A, f32, u32)) -> Option<(Vec3A, f32)> {
    (mask != 0).then_some((dir, weight))
}

/// A sphere as seen from a point: which way its centre lies, and whether
/// the point is inside it (from its own surface: facing its interior),
/// which decides between area and cone sampling. None where the point is on
/// the sphere's outside, which sees none of it.
struct SphereView {
    to_center: Vec3A,
    d2: f32,
    r2: f32,
    inside: bool,
}

impl SphereView {
    #[inline(always)]
    fn new(s: &Sphere, p: Vec3A, nl: Vec3A, on_self: bool) -> Option<Self> {
        let to_center = s.center - p;
        let d2 = to_center.length_squared();
        let r2 = s.radius * s.radius;
        let inside = if on_self {
            // On the light itself: inside when facing its interior.
            nl.dot(to_center) > 0.0
        } else {
            d2 < r2
        };
        (inside || !on_self).then_some(Self {
            to_center,
            d2,
            r2,
            inside,
        })
    }

    /// 1 - cos(theta_max) of the cone it fills, without cancellation for
    /// small lights.
    #[inline(always)]
    fn one_minus_cos_max(&self) -> f32 {
        let sin2 = self.r2 / self.d2;
        let cos_max = (1.0 - sin2).max(0.0).sqrt();
        sin2 / (1.0 + cos_max)
    }
}

#[inline(always)]
fn sample_sphere(
    s: &Sphere,
    p: Vec3A,
    nl: Vec3A,
    on_self: bool,
    u1: f32,
    u2: f32,
) -> Option<(Vec3A, f32)> {
    let v = SphereView::new(s, p, nl, on_self)?;
    if v.inside {
        found(toward_sphere_point((s.center, s.radius, v.r2), p, u1, u2))
    } else {
        let one_minus_cos_max = v.one_minus_cos_max();
        let axis = v.to_center / v.d2.sqrt();
        let dir = in_cone(axis, one_minus_cos_max, u1, u2);
        Some((dir, TAU * one_minus_cos_max))
    }
}

#[cfg(test)]
#[path = "emitter_tests.rs"]
mod tests;
