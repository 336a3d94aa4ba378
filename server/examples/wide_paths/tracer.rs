//! Who traces the lanes' rays.

use super::{lane, Avx512, Hit, Origin, Ray, Surface, Vec3A, World, L, V};

#[path = "../embree_compare/embree.rs"]
#[allow(dead_code, unused_imports)]
mod embree;
pub use embree::{ffi, Device, EmbreeScene};

/// Who traces the lanes' rays: the renderer's BVH one ray at a time, or
/// Embree in packets of sixteen (one flat scene of every placed triangle,
/// `RTC_BUILD_QUALITY_HIGH`, default flags: Mitsuba's set-up).
pub enum Tracer<'a> {
    Own,
    Embree(&'a EmbreeScene, &'a [(u32, u32)]),
}

impl Tracer<'_> {
    /// The nearest hits of the live lanes' rays.
    #[inline(always)]
    pub fn trace(
        &self,
        world: &World,
        isa: Avx512,
        o: &V,
        d: &V,
        from: &[Origin; L],
        live: &[bool; L],
    ) -> [Option<Hit>; L] {
        let mut hits = [None; L];
        match self {
            Tracer::Own => {
                for k in 0..L {
                    if live[k] {
                        let ray = Ray::new(lane(o, k), lane(d, k));
                        hits[k] = world.intersect(isa, &ray, from[k]);
                    }
                }
            }
            Tracer::Embree(scene, map) => {
                let os: [Vec3A; L] = std::array::from_fn(|k| lane(o, k));
                let ds: [Vec3A; L] = std::array::from_fn(|k| lane(d, k));
                let found = scene.nearest16(&os, &ds, live, false);
                for k in 0..L {
                    if let Some(h) = found[k] {
                        let (object, first) = map[h.prim as usize];
                        hits[k] = Some(Hit {
                            object,
                            prim: h.prim - first,
                            ..h
                        });
                    }
                }
            }
        }
        hits
    }

    /// Which live lanes' shadow rays reach their light point `q` on the
    /// lamp triangle `target`: the own BVH's nearest hit is that triangle;
    /// Embree finds nothing before 0.999 of the distance (`rtcOccluded16`,
    /// Mitsuba's shadow test).
    #[inline(always)]
    pub fn unblocked(
        &self,
        world: &World,
        isa: Avx512,
        (o, d, q): (&V, &V, &V),
        from: &[Origin; L],
        live: &[bool; L],
        target: &[(u32, u32); L],
    ) -> [bool; L] {
        match self {
            Tracer::Own => {
                let hits = self.trace(world, isa, o, d, from, live);
                std::array::from_fn(|k| {
                    live[k] && hits[k].is_some_and(|h| (h.object, h.prim) == target[k])
                })
            }
            Tracer::Embree(scene, _) => {
                let os: [Vec3A; L] = std::array::from_fn(|k| lane(o, k));
                let ds: [Vec3A; L] = std::array::from_fn(|k| lane(d, k));
                let tfar: [f32; L] = std::array::from_fn(|k| (lane(q, k) - os[k]).length() * 0.999);
                let blocked = scene.occluded16(&os, &ds, &tfar, live);
                std::array::from_fn(|k| live[k] && !blocked[k])
            }
        }
    }

    /// An origin for a ray leaving `s` along `dir`: the renderer's; for
    /// Embree, which is told nothing of the triangle a ray leaves, moved
    /// off the surface as Mitsuba moves its rays.
    #[inline(always)]
    pub fn leave(&self, world: &World, s: &Surface, dir: Vec3A) -> Vec3A {
        let r = world.spawn(s, dir);
        match self {
            Tracer::Own => r.origin,
            Tracer::Embree(..) => {
                let side = if dir.dot(s.ng) > 0.0 { s.ng } else { -s.ng };
                r.origin + side * (1.0 + s.p.abs().max_element()) * (1500.0 * f32::EPSILON / 2.0)
            }
        }
    }
}
