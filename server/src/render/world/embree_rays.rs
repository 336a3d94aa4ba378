//! Nearest hits through Embree (`render::embree`), where the CPU has the
//! library and the world has meshes: the meshes are one Embree scene
//! (`world::embree_scene`), each ray moved into its frame; the few
//! spheres and quads beside them are scanned first, as the scan
//! accelerator scans them, their nearest hit bounding Embree's search.
//!
//! What the world's own search does and Embree is told through a filter:
//! a ray never meets the triangle it leaves, and an alpha-tested texel
//! that does not stop a ray is passed through. Hits are the same surfaces
//! as the world's own BVH finds, up to rounding: Embree's watertight test
//! is not pathstream's, so a ray through a shared edge may name the other
//! triangle, and distances differ in their last bits
//! (`tests/embree.rs` measures both).

use super::build::{scan_cost, SCAN_MAX_COST};
use super::embree_scene::{EmbreeLayout, Frame};
use super::flat::Flat;
use super::{scan, Geometry, Hit, Origin, World, NO_PRIM};
use crate::render::embree::{embree, Answers, HitFilter, Packet, RawHit};
use crate::render::isa::Isa;
use crate::render::lanes::{lanes_where, F32s, V3};
use crate::render::math::Vec3A;
use crate::render::ray::Ray;
use crate::render::shape::{Quad, SphereBatch, SPHERE_BATCH_LANES};
use std::sync::Arc;

/// The world's meshes in Embree, and what is scanned beside them.
pub(super) struct EmbreeRays {
    frame: Arc<Frame>,
    /// What moves a ray's origin into the scene's frame.
    shift: Vec3A,
    sphere_batches: Vec<SphereBatch>,
    quads: Vec<(u32, Quad)>,
    /// Whether some placed mesh has alpha-tested triangles.
    alpha: bool,
    /// The triangles flat for the wide loop, built on first use; None
    /// where it does not serve the world.
    flat: std::sync::OnceLock<Option<Flat>>,
}

impl std::fmt::Debug for EmbreeRays {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EmbreeRays")
            .field("scene", &self.frame.scene)
            .field("spheres", &self.sphere_batches.len())
            .field("quads", &self.quads.len())
            .field("alpha", &self.alpha)
            .finish()
    }
}

/// The rays' filter: the triangle a ray leaves, and alpha tests; for a
/// packet, lane `k`'s ray and origin are `rays[k]` and `from[k]`.
struct Refuse<'a> {
    world: &'a World,
    from: &'a [Origin],
    rays: &'a [Ray],
}

impl HitFilter for Refuse<'_> {
    #[inline(always)]
    fn accepts(&self, lane: u32, id: u32, prim: u32, u: f32, v: f32) -> bool {
        let (Some(from), Some(ray)) = (self.from.get(lane as usize), self.rays.get(lane as usize))
        else {
            return true;
        };
        if id == from.object && prim == from.prim {
            return false;
        }
        let Some(Geometry::Instance(i)) = self.world.objects.get(id as usize).map(|o| o.geometry)
        else {
            return true;
        };
        let instance = &self.world.instances[i as usize];
        match &instance.alpha {
            None => true,
            Some(tests) => {
                let mesh = &*instance.mesh;
                let Some(&slot) = mesh.materials.get(prim as usize) else {
                    return true;
                };
                let bary = [1.0 - u - v, u, v];
                tests[slot as usize].passes(mesh, prim, bary, ray.origin, ray.dir)
            }
        }
    }
}

impl EmbreeRays {
    /// The world's meshes in Embree, or why not: no library, no meshes,
    /// or too many other objects to scan beside them (then the world's own
    /// BVH serves).
    pub(super) fn build(world: &World, min_triangles: usize) -> Result<EmbreeRays, String> {
        let triangles = world.placed_triangles;
        if triangles == 0 || triangles < min_triangles {
            return Err(format!("{triangles} triangles, fewer than {min_triangles}"));
        }
        // What a scan beside Embree would cost, before any mesh is built.
        let count =
            |f: fn(&Geometry) -> bool| world.objects.iter().filter(|o| f(&o.geometry)).count();
        let (n_spheres, n_quads) = (
            count(|g| matches!(g, Geometry::Sphere(_))),
            count(|g| matches!(g, Geometry::Quad(_))),
        );
        if scan_cost(n_spheres, n_quads) > SCAN_MAX_COST {
            return Err(format!(
                "{n_spheres} spheres and {n_quads} quads beside the meshes are more than a scan serves"
            ));
        }
        let mut spheres = Vec::new();
        let mut quads = Vec::new();
        for (id, o) in world.objects.iter().enumerate() {
            match o.geometry {
                Geometry::Sphere(s) => spheres.push((id as u32, s)),
                Geometry::Quad(q) => quads.push((id as u32, q)),
                Geometry::Instance(_) => {}
            }
        }
        let frame = super::embree_scene::frame(world, embree()?)?;
        Ok(EmbreeRays {
            shift: frame.shift(world),
            frame,
            sphere_batches: spheres
                .chunks(SPHERE_BATCH_LANES)
                .map(SphereBatch::new)
                .collect(),
            quads,
            alpha: world.instances.iter().any(|i| i.alpha.is_some()),
            flat: std::sync::OnceLock::new(),
        })
    }

    /// The nearest hit along `ray` in `world`, never the surface the ray
    /// starts on (t infinite: none).
    #[inline(always)]
    pub(super) fn nearest<I: Isa>(&self, world: &World, isa: I, ray: &Ray, from: Origin) -> Hit {
        let mut best = match self.sphere_batches.is_empty() && self.quads.is_empty() {
            true => Hit::NONE,
            false => scan::nearest(isa, &self.sphere_batches, &self.quads, ray, from),
        };
        let (o, d) = ((ray.origin + self.shift).to_array(), ray.dir.to_array());
        let (from, ray) = ([from], [*ray]);
        let refuse = Refuse {
            world,
            from: &from,
            rays: &ray,
        };
        let hit = match from[0].prim != NO_PRIM || self.alpha {
            true => self.frame.scene.intersect(o, d, best.t, Some(&refuse)),
            false => self.frame.scene.intersect::<Refuse<'_>>(o, d, best.t, None),
        };
        if let Some(h) = hit.filter(|h| h.t < best.t) {
            best = as_hit(h);
        }
        best
    }

    /// [`EmbreeRays::nearest`] for the live lanes of a packet of `W` rays
    /// (4, 8 or 16), Embree's packet query serving them all at once.
    #[inline(always)]
    fn nearest_lanes<I: Isa, const W: usize>(
        &self,
        world: &World,
        isa: I,
        (rays, from): (&[Ray; W], &[Origin; W]),
        live: &[bool; W],
    ) -> [Hit; W] {
        let mut best = [Hit::NONE; W];
        self.scan_lanes(isa, rays, from, live, &mut best);
        let mut packet = Packet::<W>::new();
        for k in lanes_where(live) {
            let (o, d) = (
                (rays[k].origin + self.shift).to_array(),
                rays[k].dir.to_array(),
            );
            packet.set(k, o, d, best[k].t);
        }
        // No filter but for alpha tests: the spawn's offset keeps nearly
        // every ray off the triangle it leaves, and the few lanes that
        // meet it again are asked once more, alone, with the filter.
        let filter = self.alpha.then_some(Refuse { world, from, rays });
        let camera = (from.iter().zip(live)).all(|(f, &l)| !l || *f == Origin::NONE);
        (self.frame.scene).intersect_lanes(&mut packet, (filter.as_ref(), camera));
        for k in lanes_where(live) {
            let (found, h) = packet.answer(k);
            // A lane that met the triangle it leaves (rare): asked again.
            // One comparison of the bits, not three: LLVM splits `a & b`
            // of comparisons back into branches, the first on `found`.
            let other = (h.id ^ from[k].object) | (h.prim ^ from[k].prim) | u32::from(!found);
            if other == 0 {
                let again = self.nearest(world, isa, &rays[k], from[k]);
                if again.t < best[k].t {
                    best[k] = again;
                }
                continue;
            }
            // Whether a path's ray hit is as good as random: a select.
            best[k] = Hit::select(found & (h.t < best[k].t), as_hit(h), best[k]);
        }
        best
    }

    /// Whether anything but the surface each live lane's ray leaves
    /// blocks it before `tmax[k]`.
    #[inline(always)]
    fn occluded_lanes<I: Isa, const W: usize>(
        &self,
        world: &World,
        isa: I,
        (rays, from, tmax): (&[Ray; W], &[Origin; W], &[f32; W]),
        live: &[bool; W],
    ) -> [bool; W] {
        let mut best = [Hit::NONE; W];
        self.scan_lanes(isa, rays, from, live, &mut best);
        let scanned: [bool; W] = std::array::from_fn(|k| live[k] & (best[k].t < tmax[k]));
        let mut packet = Packet::<W>::new();
        for k in lanes_where::<W>(&std::array::from_fn(|k| live[k] & !scanned[k])) {
            let (o, d) = (
                (rays[k].origin + self.shift).to_array(),
                rays[k].dir.to_array(),
            );
            packet.set(k, o, d, tmax[k]);
        }
        if !(0..W).any(|k| packet.live(k)) {
            return scanned;
        }
        // Without the filter but for alpha tests, as in `nearest_lanes`:
        // a ray spawned off a triangle does not meet it again
        // (`tests/lane_loop.rs` counts the answers against the filtered
        // query's).
        let filter = self.alpha.then_some(Refuse { world, from, rays });
        (self.frame.scene).occluded_lanes(&mut packet, filter.as_ref());
        std::array::from_fn(|k| scanned[k] | packet.blocked(k))
    }

    /// The spheres' and quads' nearest hits of the live lanes, into `best`.
    #[inline(always)]
    fn scan_lanes<I: Isa, const W: usize>(
        &self,
        isa: I,
        rays: &[Ray; W],
        from: &[Origin; W],
        live: &[bool; W],
        best: &mut [Hit; W],
    ) {
        if self.sphere_batches.is_empty() && self.quads.is_empty() {
            return;
        }
        for k in (0..W).filter(|&k| live[k]) {
            best[k] = scan::nearest(isa, &self.sphere_batches, &self.quads, &rays[k], from[k]);
        }
    }
}

/// Embree's hit as the world's search reports it.
#[inline(always)]
fn as_hit(h: RawHit) -> Hit {
    Hit {
        t: h.t,
        object: h.id,
        prim: h.prim,
        bary: [1.0 - h.u - h.v, h.u, h.v],
    }
}

/// Placed triangles from which the CPU backend traces through Embree
/// where it can. One ray at a time, Embree paid from 100,000 (its own BVH
/// was as fast below: docs/BENCHMARKS.md, "Embree as the CPU's tracer");
/// with the lane loop's packets, from 10,000 at least (1.17x at 9,800,
/// 1.12x on `cornell-mesh`: "The lane loop"). Smaller worlds, not
/// measured, keep the own BVH.
pub const EMBREE_MIN_TRIANGLES: usize = 10_000;

impl World {
    /// Whether this world's rays go through Embree on the CPU: on the
    /// first call, where the library loads and the world places at least
    /// `min_triangles` triangles, builds the Embree scenes (else says why
    /// not, once, in the log); from then on [`World::intersect`] uses them.
    /// Later calls return the first one's answer.
    pub fn use_embree(&self, min_triangles: usize) -> bool {
        let built = self
            .embree
            .get_or_init(|| match EmbreeRays::build(self, min_triangles) {
                Ok(rays) => Some(Arc::new(rays)),
                Err(why) => {
                    tracing::debug!("meshes traced by the CPU's own BVH: {why}");
                    None
                }
            });
        built.is_some()
    }

    /// How Embree holds this world's meshes, where it traces them.
    pub fn embree_layout(&self) -> Option<EmbreeLayout> {
        match self.embree.get() {
            Some(Some(e)) => Some(e.frame.layout),
            _ => None,
        }
    }

    /// Whether [`World::use_embree`] has made rays go through Embree.
    pub fn traced_by_embree(&self) -> bool {
        matches!(self.embree.get(), Some(Some(_)))
    }

    /// [`World::intersect`] for the live lanes of `W` rays (4, 8 or 16):
    /// through Embree's packets where it traces this world, else one ray
    /// at a time. A lane without a hit (or not live) answers an infinite
    /// distance ([`Hit::found`], [`Hit::some`]): no `Option` a lane, whose
    /// test would be one more branch as good as random.
    #[inline(always)]
    pub fn intersect_lanes<I: Isa, const W: usize>(
        &self,
        isa: I,
        rays: &[Ray; W],
        from: &[Origin; W],
        live: &[bool; W],
    ) -> [Hit; W] {
        match self.embree.get() {
            Some(Some(e)) => e.nearest_lanes(self, isa, (rays, from), live),
            _ => std::array::from_fn(|k| match live[k] {
                true => self.intersect(isa, &rays[k], from[k]).unwrap_or(Hit::NONE),
                false => Hit::NONE,
            }),
        }
    }

    /// Where Embree traces this world: whether anything but the surface
    /// each live lane's ray leaves blocks it before `tmax[k]` (Embree's
    /// occlusion query, which stops at the first blocker). None elsewhere
    /// (the own BVH answers a nearest-hit query as fast).
    #[inline(always)]
    pub fn occluded_lanes<I: Isa, const W: usize>(
        &self,
        isa: I,
        (rays, from, tmax): (&[Ray; W], &[Origin; W], &[f32; W]),
        live: &[bool; W],
    ) -> Option<[bool; W]> {
        match self.embree.get() {
            Some(Some(e)) => Some(e.occluded_lanes(self, isa, (rays, from, tmax), live)),
            _ => None,
        }
    }

    /// The world's triangles flat for the wide loop, where it serves this
    /// world (Embree traces it, every mesh is the scene's own, nothing
    /// else beside them; `Flat::build` for the rest): built on the first
    /// call, which logs why not where it does not serve.
    pub fn flat(&self) -> Option<&Flat> {
        let Some(Some(e)) = self.embree.get() else {
            return None;
        };
        let flat = e.flat.get_or_init(|| {
            let built = match e.sphere_batches.is_empty() && e.quads.is_empty() && !e.alpha {
                true => Flat::build(self, &e.frame),
                false => Err("spheres, quads or alpha tests beside the meshes"),
            };
            built
                .map_err(|why| tracing::debug!("paths in lanes, shaded one by one: {why}"))
                .ok()
        });
        flat.as_ref()
    }

    /// The nearest hits of `W` rays given in the Embree scene's frame
    /// (`org`, `dir`), each never the triangle it leaves, for the live
    /// lanes of a world [`World::flat`] serves (else none): a lane's
    /// distance is infinite where it hit nothing. `coherent`: camera rays.
    #[inline(always)]
    pub fn framed_nearest<const W: usize>(
        &self,
        (org, dir): (&V3<F32s<W>>, &V3<F32s<W>>),
        from: &[Origin; W],
        live: &[bool; W],
        coherent: bool,
    ) -> Answers<W> {
        let mut packet = Packet::<W>::new();
        let Some(Some(e)) = self.embree.get() else {
            return packet.answers();
        };
        let lanes = ([org.x.0, org.y.0, org.z.0], [dir.x.0, dir.y.0, dir.z.0]);
        packet.set_lanes(lanes, [f32::INFINITY; W], live);
        (e.frame.scene).intersect_lanes::<Refuse<'_>, W>(&mut packet, (None, coherent));
        let mut found = packet.answers();
        // A lane that met the triangle it leaves (rare) is asked again,
        // alone, with the filter that refuses it.
        let again: [bool; W] = std::array::from_fn(|k| {
            let other = (found.id[k] ^ from[k].object) | (found.prim[k] ^ from[k].prim);
            (found.t[k] < f32::INFINITY) & (other == 0)
        });
        for k in lanes_where(&again) {
            let o = [org.x.0[k], org.y.0[k], org.z.0[k]];
            let d = [dir.x.0[k], dir.y.0[k], dir.z.0[k]];
            let (from, ray) = ([from[k]], [Ray::new(o.into(), d.into())]);
            let refuse = Refuse {
                world: self,
                from: &from,
                rays: &ray,
            };
            let h = e.frame.scene.intersect(o, d, f32::INFINITY, Some(&refuse));
            found.t[k] = h.map_or(f32::INFINITY, |h| h.t);
            if let Some(h) = h {
                (found.id[k], found.prim[k], found.u[k], found.v[k]) = (h.id, h.prim, h.u, h.v);
            }
        }
        found
    }

    /// Whether anything blocks each live lane's ray (in the frame, as for
    /// [`World::framed_nearest`]) before `tmax[k]`.
    #[inline(always)]
    pub fn framed_occluded<const W: usize>(
        &self,
        (org, dir, tmax): (&V3<F32s<W>>, &V3<F32s<W>>, &[f32; W]),
        live: &[bool; W],
    ) -> [bool; W] {
        let Some(Some(e)) = self.embree.get() else {
            return [false; W];
        };
        let mut packet = Packet::<W>::new();
        let lanes = ([org.x.0, org.y.0, org.z.0], [dir.x.0, dir.y.0, dir.z.0]);
        packet.set_lanes(lanes, *tmax, live);
        (e.frame.scene).occluded_lanes::<Refuse<'_>, W>(&mut packet, None);
        std::array::from_fn(|k| packet.blocked(k))
    }
}
