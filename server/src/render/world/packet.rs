//! Camera rays in packets: up to [`PACKET`] rays that leave no surface go
//! through the objects' BVH and each mesh's BVH together
//! ([`BoxPacket`]), each ray tested alone at the leaves. Every ray gets
//! the hit that [`World::intersect`] gives it: the packet visits every leaf
//! its rays would visit alone, and [`Hit`]'s tie rule makes the nearest
//! hit independent of the order of the leaves (a packet's walk orders them
//! by the packet's bounds, not by each ray's).

use super::instance::{Instance, Prepared};
use super::{Accel, Geometry, Hit, Origin, World};
use crate::render::bvh::{Aabb, BoxPacket, BoxRay, MAX_LEAF, PACKET, ROBUST};
use crate::render::isa::Isa;
use crate::render::ray::Ray;
use crate::render::world::NO_PRIM;

/// Worlds of this many placed triangles or more trace their camera rays
/// one by one. A packet's walk culls a node only beyond the farthest of
/// its rays' nearest hits so far, so where one of its rays misses (a
/// silhouette) it visits everything in the packet's frustum, behind the
/// surface too. In a mesh of 100,000 triangles that still paid (paths
/// +4-8%); in one of 1M it cost 3x, in one of 4M 6.6x (docs/BENCHMARKS.md,
/// "Issue 32 before and after"). A walk that culls each ray by its own
/// hit at every node mended most of that (1M: 1.65-1.71 M paths/s against
/// 0.70) but still lost to single rays (2.09-2.22) and cost a few percent
/// below the bound: not kept ("Each ray culled by its own hit in a
/// packet's walk"). Where Embree is installed, such worlds go through it
/// anyway (from [`super::EMBREE_MIN_TRIANGLES`], a lower bound since the lane
/// loop: this one is the own walk's alone).
pub const PACKET_MAX_TRIANGLES: usize = 100_000;

impl World {
    /// Whether camera rays gain from going through
    /// [`World::intersect_packet`]: in a world of meshes walked by the own
    /// BVH, of fewer than [`PACKET_MAX_TRIANGLES`] placed triangles.
    /// Spheres and quads alone (a scan, or a BVH of a few objects),
    /// Embree's worlds and larger meshes trace them one by one.
    pub fn packets_pay(&self) -> bool {
        matches!(self.accel, Accel::Bvh { .. })
            && !self.instances.is_empty()
            && !matches!(self.embree.get(), Some(Some(_)))
            && self.placed_triangles < PACKET_MAX_TRIANGLES
    }

    /// The nearest hits of `rays` (at most [`PACKET`], none leaving a
    /// surface) into `hits`, one each: what [`World::intersect`] gives each
    /// ray with [`Origin::NONE`]. Rays that cannot share a packet (both
    /// signs of a direction component, or a zero one), worlds without a
    /// BVH, and Embree's worlds take the rays one by one.
    #[inline(always)]
    pub fn intersect_packet<I: Isa>(&self, isa: I, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert!(rays.len() <= PACKET && hits.len() == rays.len());
        let n = rays.len();
        let embree = matches!(self.embree.get(), Some(Some(_)));
        let packed = match &self.accel {
            Accel::Bvh { bvh, big } if n > 1 && !embree => {
                let boxes: [BoxRay; PACKET] = std::array::from_fn(|k| {
                    let ray = &rays[k.min(n - 1)];
                    BoxRay::new(ray.origin, ray.dir)
                });
                BoxPacket::of(&boxes[..n]).map(|packet| (bvh, big, boxes, packet))
            }
            _ => None,
        };
        let Some((bvh, big, boxes, packet)) = packed else {
            for (hit, ray) in hits.iter_mut().zip(rays) {
                *hit = self.intersect(isa, ray, Origin::NONE);
            }
            return;
        };
        let pre: Option<[Prepared; PACKET]> = self
            .translated_meshes
            .then(|| std::array::from_fn(|k| Prepared::new(&rays[k.min(n - 1)], boxes[k])));
        let pre = pre.as_ref().map(|p| &p[..n]);
        let mut best = [Hit::NONE; PACKET];
        let best = &mut best[..n];
        if !big.is_empty() {
            for (b, ray) in best.iter_mut().zip(rays) {
                *b = super::scan::nearest(isa, big, &[], ray, Origin::NONE);
            }
        }
        let mut walk = bvh.walk_packet(packet);
        while let Some((first, count)) = walk.next_leaf(farthest(best)) {
            for slot in first..first + count {
                let id = bvh.prims[slot as usize];
                if let Geometry::Instance(i) = &self.objects[id as usize].geometry {
                    self.instances[*i as usize].offer_packet(isa, id, (rays, pre), best);
                    continue;
                }
                for (k, (b, ray)) in best.iter_mut().zip(rays).enumerate() {
                    let pre = pre.map(|p| &p[k]);
                    self.offer_object::<false, I>(isa, id, (ray, pre), Origin::NONE, b);
                }
            }
        }
        for (hit, b) in hits.iter_mut().zip(best.iter()) {
            *hit = (b.t < f32::INFINITY).then_some(*b);
        }
    }
}

impl Instance {
    /// [`Instance::offer`] for each of `rays` (`pre`: each prepared in
    /// camera space), their nearest hits so far in `best`, the mesh's BVH
    /// walked once for the packet.
    #[inline(always)]
    fn offer_packet<I: Isa>(
        &self,
        isa: I,
        id: u32,
        (rays, pre): (&[Ray], Option<&[Prepared]>),
        best: &mut [Hit],
    ) {
        let n = rays.len();
        let prepared: [_; PACKET] = std::array::from_fn(|k| {
            let k = k.min(n - 1);
            self.prepare(&rays[k], pre.map(|p| &p[k]))
        });
        let prepared = &prepared[..n];
        let Some(packet) = BoxPacket::of(prepared.iter().map(|p| &p.1)) else {
            for (k, (b, ray)) in best.iter_mut().zip(rays).enumerate() {
                let pre = pre.map(|p| &p[k]);
                self.offer::<false, I>(isa, id, (ray, pre), NO_PRIM, b);
            }
            return;
        };
        let lanes = Lanes::of(prepared.iter().map(|p| &p.1));
        let mut walk = self.mesh.wide.walk_packet(packet, isa);
        while let Some((first, _)) = walk.next_leaf(farthest(best)) {
            // Only the rays that enter the leaf's box before their nearest
            // hit so far test its triangles.
            let pack = &self.mesh.packs[first as usize / MAX_LEAF];
            let mut entering = lanes.entering(pack.bounds(), best);
            while entering != 0 {
                let k = entering.trailing_zeros() as usize;
                entering &= entering - 1;
                self.offer_leaf(id, (&prepared[k].0, &rays[k]), first, NO_PRIM, &mut best[k]);
            }
        }
    }
}

/// A packet's rays for box tests, one lane each (structure of arrays, so
/// that one box is tested against all of them in a few wide operations).
struct Lanes {
    org: [[f32; PACKET]; 3],
    inv: [[f32; PACKET]; 3],
}

impl Lanes {
    /// The rays' origins and reciprocal directions (of a [`BoxPacket`]:
    /// finite, none zero).
    #[inline(always)]
    fn of<'a>(rays: impl Iterator<Item = &'a BoxRay>) -> Self {
        let mut lanes = Lanes {
            org: [[0.0; PACKET]; 3],
            inv: [[1.0; PACKET]; 3],
        };
        for (k, r) in rays.enumerate() {
            let (org, inv) = r.axes();
            for axis in 0..3 {
                lanes.org[axis][k] = org[axis];
                lanes.inv[axis][k] = inv[axis];
            }
        }
        lanes
    }

    /// The rays (bit k for ray k of `best`) that may meet `bounds` no
    /// farther than their hits so far: [`BoxRay`]'s test, its robust
    /// exit distance included, so no ray that meets a triangle in the box
    /// is left out.
    #[inline(always)]
    fn entering(&self, bounds: Aabb, best: &[Hit]) -> u32 {
        let mut t_near = [0.0f32; PACKET];
        let mut t_far = [0.0f32; PACKET];
        for (t, b) in t_far.iter_mut().zip(best) {
            *t = b.t;
        }
        let (lo, hi) = (bounds.min.to_array(), bounds.max.to_array());
        for axis in 0..3 {
            let (org, inv) = (&self.org[axis], &self.inv[axis]);
            for k in 0..PACKET {
                let t0 = (lo[axis] - org[k]) * inv[k];
                let t1 = (hi[axis] - org[k]) * inv[k];
                let (near, far) = if t0 < t1 { (t0, t1) } else { (t1, t0) };
                t_near[k] = if near > t_near[k] { near } else { t_near[k] };
                t_far[k] = if far < t_far[k] { far } else { t_far[k] };
            }
        }
        let mut mask = 0u32;
        for k in 0..PACKET {
            mask |= u32::from(t_near[k] <= t_far[k] * ROBUST) << k;
        }
        mask & ((1u32 << best.len()) - 1)
    }
}

/// The farthest of the hits so far: where the packet's walk may stop.
#[inline(always)]
fn farthest(best: &[Hit]) -> f32 {
    best.iter().fold(0.0, |t, b| t.max(b.t))
}
