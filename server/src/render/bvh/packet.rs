//! A packet of rays walked through a BVH as one: each node's boxes are
//! tested once for all of them, against bounds of the packet's origins and
//! reciprocal directions (interval arithmetic), and the walk visits every
//! leaf that any of its rays would visit alone. The caller then tests each
//! ray against the leaf's triangles. Made for a pixel's camera rays, which
//! share a pinhole and nearly a direction: their nodes are the same, so the
//! packet pays for the nodes once (Embree's coherent packets, measured at
//! 2.9-3.2x its single camera rays: docs/BENCHMARKS.md).
//!
//! The bounds are conservative in floating point, not only in exact
//! arithmetic: for a near plane b, each ray's entry distance is the rounded
//! `(b - o) * inv`, and rounding is monotonic, so the packet's smallest
//! candidate, computed from the origin and reciprocal that make it
//! smallest, is no larger than any ray's; likewise the far planes from
//! above, and the packet's `t_max` is its rays' largest. So a node that any
//! ray of the packet meets by [`BoxRay`]'s test, the packet meets too.
//! Rays that share a packet have the same direction sign on each axis (the
//! same near planes) and no zero component (finite reciprocals: no NaN).

use super::traverse::{BoxRay, Nodes, Probe, ROBUST};

/// Most rays a packet holds.
pub const PACKET: usize = 16;

/// Bounds of a packet of rays, prepared for box tests.
#[derive(Clone, Copy, Debug)]
pub struct BoxPacket {
    /// For each axis, the origin coordinate that gives a near plane its
    /// smallest distance (the largest one along a positive direction), and
    /// the one that gives a far plane its largest.
    o_near: [f32; 3],
    o_far: [f32; 3],
    /// For each axis, the smallest and the largest reciprocal direction.
    inv_lo: [f32; 3],
    inv_hi: [f32; 3],
    /// Rows of the node bounds with each axis's near and far planes, as
    /// every ray of the packet has them.
    near: [usize; 3],
    far: [usize; 3],
}

impl BoxPacket {
    /// The packet of `rays`, if they can share one: on each axis every
    /// direction has the same sign, and none is zero. `None` for no rays.
    pub fn of<'a>(rays: impl IntoIterator<Item = &'a BoxRay>) -> Option<Self> {
        let mut rays = rays.into_iter();
        let first = rays.next()?;
        let mut o_lo = [0.0f32; 3];
        let mut inv_lo = [0.0f32; 3];
        for axis in 0..3 {
            o_lo[axis] = first.org[axis].x;
            inv_lo[axis] = first.inv[axis].x;
        }
        let (mut o_hi, mut inv_hi) = (o_lo, inv_lo);
        let usable = |r: &BoxRay| {
            r.near == first.near && r.inv.iter().all(|i| i.x.is_finite() && i.x != 0.0)
        };
        if !usable(first) {
            return None;
        }
        for r in rays {
            if !usable(r) {
                return None;
            }
            for axis in 0..3 {
                let (o, inv) = (r.org[axis].x, r.inv[axis].x);
                o_lo[axis] = o_lo[axis].min(o);
                o_hi[axis] = o_hi[axis].max(o);
                inv_lo[axis] = inv_lo[axis].min(inv);
                inv_hi[axis] = inv_hi[axis].max(inv);
            }
        }
        let mut o_near = [0.0; 3];
        let mut o_far = [0.0; 3];
        for axis in 0..3 {
            // Along a positive direction the near plane is the box's min
            // (row `axis`): the farthest origin is nearest to it.
            let positive = first.near[axis] == axis;
            (o_near[axis], o_far[axis]) = match positive {
                true => (o_hi[axis], o_lo[axis]),
                false => (o_lo[axis], o_hi[axis]),
            };
        }
        Some(Self {
            o_near,
            o_far,
            inv_lo,
            inv_hi,
            near: first.near,
            far: first.far,
        })
    }

    /// For each of `W` boxes given by their bounds' rows, a distance no
    /// larger than any ray's entry distance, and the mask of the boxes
    /// that some ray may meet between 0 and `t_max` (bit i for box i).
    #[inline(always)]
    pub fn test_rows<const W: usize>(&self, b: &[[f32; W]; 6], t_max: f32) -> ([f32; W], u32) {
        let mut t_near = [0.0f32; W];
        let mut t_far = [t_max; W];
        for axis in 0..3 {
            let (near, far) = (&b[self.near[axis]], &b[self.far[axis]]);
            let (lo, hi) = (self.inv_lo[axis], self.inv_hi[axis]);
            for i in 0..W {
                let x = near[i] - self.o_near[axis];
                let y = far[i] - self.o_far[axis];
                t_near[i] = max(t_near[i], min(x * lo, x * hi));
                t_far[i] = min(t_far[i], max(y * lo, y * hi));
            }
        }
        let mut mask = 0;
        for i in 0..W {
            mask |= u32::from(t_near[i] <= t_far[i] * ROBUST) << i;
        }
        (t_near, mask)
    }
}

impl<T: Nodes<W>, const W: usize> Probe<T, W> for BoxPacket {
    #[inline(always)]
    fn probe(&self, nodes: &T, index: u32, t_max: f32) -> ([f32; W], u32) {
        self.test_rows(nodes.bounds(index), t_max)
    }
}

/// The smaller of two numbers that are not NaN (a select the compiler
/// turns into `minps`).
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::bvh::{test_portable, WideNode, WIDTH};
    use crate::render::math::Vec3A;
    use crate::render::sampler::Sampler;

    /// Random boxes against random packets (origins spread over a small
    /// box, directions in a cone): every box that a ray of the packet meets
    /// alone, the packet meets, from no farther.
    #[test]
    fn a_packet_meets_every_box_its_rays_meet() {
        let mut rng = Sampler::new(17, 0, 0);
        let mut f = || rng.next_f32() * 2.0 - 1.0;
        let (mut met, mut packets) = (0u64, 0u64);
        for case in 0..4_000u32 {
            let mut node = WideNode::EMPTY_NODE;
            for i in 0..WIDTH - (case % 3) as usize {
                let c = Vec3A::new(f(), f(), f()) * 4.0;
                let h = Vec3A::new(f().abs(), f().abs(), f().abs()) * [0.01, 0.5, 2.0][i % 3];
                let b = super::super::Aabb {
                    min: c - h,
                    max: c + h,
                };
                node.set_child(i, b, i as u32, 1);
            }
            let o = Vec3A::new(f(), f(), f()) * 6.0;
            let axis = Vec3A::new(f(), f(), f()).normalize_or_zero();
            let spread = [0.0, 1e-3, 0.05, 0.3][(case % 4) as usize];
            let size = [0.0, 1e-2, 0.5][(case % 3) as usize];
            let rays: Vec<BoxRay> = (0..PACKET)
                .map(|_| {
                    let d = (axis + Vec3A::new(f(), f(), f()) * spread).normalize_or_zero();
                    BoxRay::new(o + Vec3A::new(f(), f(), f()) * size, d)
                })
                .collect();
            let Some(packet) = BoxPacket::of(&rays) else {
                continue;
            };
            packets += 1;
            let t_max = [f32::INFINITY, 5.0, 0.5][(case % 3) as usize];
            let (t_packet, mask) = packet.test_rows(&node.bounds, t_max);
            for ray in &rays {
                let (t, alone) = test_portable(ray, &node, t_max);
                for i in 0..WIDTH {
                    if alone & (1 << i) != 0 {
                        met += 1;
                        assert!(mask & (1 << i) != 0, "case {case}: box {i} missed");
                        assert!(t_packet[i] <= t[i], "case {case}: box {i} entered late");
                    }
                }
            }
        }
        assert!(
            packets > 2_000 && met > 1_000,
            "{packets} packets, {met} boxes met"
        );
    }

    /// Rays whose directions differ in sign on an axis, or lie in a slab's
    /// plane, do not share a packet.
    #[test]
    fn rays_of_both_signs_or_a_zero_component_make_no_packet() {
        let o = Vec3A::ZERO;
        let a = BoxRay::new(o, Vec3A::new(0.6, 0.8, 0.1));
        let b = BoxRay::new(o, Vec3A::new(0.6, 0.8, -0.1));
        let flat = BoxRay::new(o, Vec3A::new(0.6, 0.8, 0.0));
        assert!(BoxPacket::of([&a, &a]).is_some());
        assert!(BoxPacket::of([&a, &b]).is_none());
        assert!(BoxPacket::of([&flat]).is_none());
        assert!(BoxPacket::of(std::iter::empty()).is_none());
    }
}
