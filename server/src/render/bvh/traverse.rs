//! Nearest-first traversal: a node's four boxes are tested at once, the
//! children hit are pushed farthest first, and a child whose box starts
//! beyond the nearest hit found so far is skipped when it is popped.
//!
//! The box test is conservative (Ize 2013, "Robust BVH Ray Traversal"):
//! the exit distance is enlarged by 1 + 2 gamma(3), which covers the
//! rounding of (bound - origin) * (1 / dir), so a primitive that the exact
//! ray meets is never culled by its box. A direction component of zero has
//! an infinite reciprocal; a ray lying in the plane of a slab then gives
//! 0 * inf = NaN for that plane, and the running max/min drop NaNs, so the
//! slab does not constrain it (it is inside).

use super::{BoxPacket, Bvh, BvhNode, EMPTY};
use crate::render::math::{gamma, Vec3A, Vec4};
use std::mem::MaybeUninit;

/// Exit distances are scaled by this before the overlap test (the OpenCL
/// kernel gets the same bits as `BVH_ROBUST_BITS`).
pub const ROBUST: f32 = 1.0 + 2.0 * gamma(3);

/// Deepest node stack a traversal needs: three more children than it pops
/// at each level, and trees are at most 64 levels deep (see `build`).
pub(crate) const STACK: usize = 3 * 64 + 4;
/// A stack entry holds a child as `child << 3 | count` (leaves hold at most
/// `MAX_LEAF` < 8 primitives) and its entry distance.
pub(super) const COUNT_BITS: u32 = 3;
const _: () = assert!(super::MAX_LEAF < 1 << COUNT_BITS);

/// A ray prepared for box tests: origin and reciprocal direction in every
/// lane, and for each axis which bound (min or max) it meets first.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    pub(super) org: [Vec4; 3],
    pub(super) inv: [Vec4; 3],
    /// Row of `BvhNode::bounds` with the near (entry) plane of each axis.
    pub(super) near: [usize; 3],
    /// Row with the far (exit) plane of each axis.
    pub(super) far: [usize; 3],
}

impl BoxRay {
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        // One vector division: the same bits as three scalar ones.
        let inv = Vec3A::ONE / dir;
        let neg = |d: f32| usize::from(d.is_sign_negative());
        Self {
            org: splat3(origin),
            inv: splat3(inv),
            near: [3 * neg(dir.x), 1 + 3 * neg(dir.y), 2 + 3 * neg(dir.z)],
            far: [3 - 3 * neg(dir.x), 4 - 3 * neg(dir.y), 5 - 3 * neg(dir.z)],
        }
    }

    /// The ray's origin and reciprocal direction.
    #[inline(always)]
    pub fn axes(&self) -> ([f32; 3], [f32; 3]) {
        let x = |v: &[Vec4; 3]| [v[0].x, v[1].x, v[2].x];
        (x(&self.org), x(&self.inv))
    }

    /// The same ray (direction) from `origin`: what a ray becomes in the
    /// space of a mesh placed by a translation alone, without redoing the
    /// divisions. The same bits as `BoxRay::new(origin, dir)`.
    #[inline(always)]
    pub fn from_origin(&self, origin: Vec3A) -> Self {
        Self {
            org: splat3(origin),
            ..*self
        }
    }

    /// Entry distance of each of the node's four boxes, and which of them
    /// the ray meets between 0 and `t_max` (bit i for child i).
    #[inline(always)]
    pub fn test(&self, node: &BvhNode, t_max: f32) -> (Vec4, u32) {
        self.test_rows(&node.bounds, t_max)
    }

    /// [`BoxRay::test`] on four boxes given by their bounds' rows (min x,
    /// min y, min z, max x, max y, max z). No closures here or in the
    /// other hot tests: in the render loop's large function the compiler
    /// may leave one out of line, compiled without the loop's AVX2.
    #[inline(always)]
    pub(super) fn test_rows(&self, b: &[[f32; 4]; 6], t_max: f32) -> (Vec4, u32) {
        let (near, far) = (self.near, self.far);
        let nx = (Vec4::from_array(b[near[0]]) - self.org[0]) * self.inv[0];
        let fx = (Vec4::from_array(b[far[0]]) - self.org[0]) * self.inv[0];
        let ny = (Vec4::from_array(b[near[1]]) - self.org[1]) * self.inv[1];
        let fy = (Vec4::from_array(b[far[1]]) - self.org[1]) * self.inv[1];
        let nz = (Vec4::from_array(b[near[2]]) - self.org[2]) * self.inv[2];
        let fz = (Vec4::from_array(b[far[2]]) - self.org[2]) * self.inv[2];
        let t_near = max_or(nz, max_or(ny, max_or(nx, Vec4::ZERO)));
        let t_far = min_or(fz, min_or(fy, min_or(fx, Vec4::splat(t_max)))) * ROBUST;
        (t_near, t_near.cmple(t_far).bitmask())
    }
}

/// Each of `v`'s three components in every lane.
#[inline(always)]
fn splat3(v: Vec3A) -> [Vec4; 3] {
    [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)]
}

/// max(x, acc) per lane, or `acc` where x is NaN.
#[inline(always)]
fn max_or(x: Vec4, acc: Vec4) -> Vec4 {
    // SSE's maxps returns its second operand when either is NaN.
    #[cfg(target_arch = "x86_64")]
    return x.max(acc);
    #[cfg(not(target_arch = "x86_64"))]
    return Vec4::select(x.cmpgt(acc), x, acc);
}

/// min(x, acc) per lane, or `acc` where x is NaN.
#[inline(always)]
fn min_or(x: Vec4, acc: Vec4) -> Vec4 {
    #[cfg(target_arch = "x86_64")]
    return x.min(acc);
    #[cfg(not(target_arch = "x86_64"))]
    return Vec4::select(x.cmplt(acc), x, acc);
}

/// A hierarchy's nodes as the traversal sees them: `W` children each.
pub trait Nodes<const W: usize> {
    /// Entry distance of each child of node `index`, and which of them the
    /// ray meets between 0 and `t_max` (bit i for child i).
    fn test(&self, ray: &BoxRay, index: u32, t_max: f32) -> ([f32; W], u32);
    /// Child `i` of node `index` as a stack entry: `child << 3 | count`.
    fn entry(&self, index: u32, i: usize) -> u32;
    /// The boxes of node `index`'s children, as rows (min x, min y, min z,
    /// max x, max y, max z).
    fn bounds(&self, index: u32) -> &[[f32; W]; 6];
}

/// What a walk tests nodes with: one ray ([`BoxRay`], with the node test
/// of `Nodes`), or a packet of rays ([`super::BoxPacket`]).
pub trait Probe<T, const W: usize> {
    /// Entry distance of each child of node `index` and the mask of those
    /// met before `t_max`.
    fn probe(&self, nodes: &T, index: u32, t_max: f32) -> ([f32; W], u32);
}

impl<T: Nodes<W>, const W: usize> Probe<T, W> for BoxRay {
    #[inline(always)]
    fn probe(&self, nodes: &T, index: u32, t_max: f32) -> ([f32; W], u32) {
        nodes.test(self, index, t_max)
    }
}

impl Nodes<4> for &[BvhNode] {
    #[inline(always)]
    fn test(&self, ray: &BoxRay, index: u32, t_max: f32) -> ([f32; 4], u32) {
        let (t, mask) = ray.test(&self[index as usize], t_max);
        (t.to_array(), mask)
    }

    #[inline(always)]
    fn entry(&self, index: u32, i: usize) -> u32 {
        let node = &self[index as usize];
        debug_assert_ne!(node.child[i], EMPTY);
        node.child[i] << COUNT_BITS | node.count[i]
    }

    #[inline(always)]
    fn bounds(&self, index: u32) -> &[[f32; 4]; 6] {
        &self[index as usize].bounds
    }
}

/// A nearest-first traversal in progress: [`Walk::next_leaf`] hands the
/// caller one leaf at a time, so that the caller's leaf test is its own
/// code (inlined with everything around it into the function compiled for
/// the CPU's instruction set, which a callback was not). `N` stack entries
/// are enough for any tree this code builds. `R` tests the nodes: one ray,
/// or a packet (whose walk visits every leaf that any of its rays would).
pub struct Walk<T, const W: usize, const N: usize, R = BoxRay> {
    nodes: T,
    ray: R,
    // Not zeroed: a deep tree's stack is kilobytes, and clearing it for
    // every ray (and again for every instance it enters) cost the mesh
    // scenes a tenth of their time in `memset`.
    stack: [MaybeUninit<(u32, f32)>; N],
    top: usize,
    /// The nearest child hit goes on at once, without the stack.
    next: Option<(u32, f32)>,
}

/// A walk of a four-wide [`Bvh`].
pub type Walk4<'a> = Walk<&'a [BvhNode], 4, STACK>;

impl<T: Nodes<W>, const W: usize, const N: usize, R: Probe<T, W>> Walk<T, W, N, R> {
    /// A walk from stack entry `start` (node 0: `Some(0)`; nothing to
    /// visit: `None`).
    #[inline(always)]
    pub(super) fn new(nodes: T, ray: R, start: Option<u32>) -> Self {
        Self {
            nodes,
            ray,
            stack: [MaybeUninit::uninit(); N],
            top: 0,
            next: start.map(|e| (e, 0.0)),
        }
    }

    /// The next leaf the ray may meet before `t_max` (the caller's nearest
    /// hit so far), as (first slot, count); `None` when there is none.
    #[inline(always)]
    pub fn next_leaf(&mut self, t_max: f32) -> Option<(u32, u32)> {
        const MASK: u32 = (1 << COUNT_BITS) - 1;
        loop {
            let (entry, t_near) = match self.next.take() {
                Some(e) => e,
                None if self.top == 0 => return None,
                None => {
                    self.top -= 1;
                    // SAFETY: entries below `top` were all written (pushes
                    // write `stack[top..top + n - 1]` before raising `top`).
                    #[allow(unsafe_code)]
                    unsafe {
                        self.stack[self.top].assume_init()
                    }
                }
            };
            if t_near > t_max {
                continue;
            }
            let (child, count) = (entry >> COUNT_BITS, entry & MASK);
            if count > 0 {
                return Some((child, count));
            }
            let (t, mut mask) = self.ray.probe(&self.nodes, child, t_max);
            // One or two children hit (most nodes): no sort loop, and the
            // order the loop below would give (on a tie, the later child
            // first).
            if mask == 0 {
                continue;
            }
            let i0 = mask.trailing_zeros() as usize;
            let rest = mask & (mask - 1);
            let a = (self.nodes.entry(child, i0), t[i0]);
            if rest == 0 {
                self.next = Some(a);
                continue;
            }
            if rest & (rest - 1) == 0 {
                let i1 = rest.trailing_zeros() as usize;
                let b = (self.nodes.entry(child, i1), t[i1]);
                let (near, far) = if b.1 <= a.1 { (b, a) } else { (a, b) };
                self.stack[self.top] = MaybeUninit::new(far);
                self.top += 1;
                self.next = Some(near);
                continue;
            }
            // The children hit, sorted by entry distance, nearest last.
            let mut hits = [(0u32, 0.0f32); W];
            let mut n = 0;
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let entry = (self.nodes.entry(child, i), t[i]);
                let mut j = n;
                while j > 0 && hits[j - 1].1 < entry.1 {
                    hits[j] = hits[j - 1];
                    j -= 1;
                }
                hits[j] = entry;
                n += 1;
            }
            if n > 0 {
                self.next = Some(hits[n - 1]);
                let top = self.top;
                for (slot, hit) in self.stack[top..top + n - 1].iter_mut().zip(&hits[..n - 1]) {
                    *slot = MaybeUninit::new(*hit);
                }
                self.top += n - 1;
            }
        }
    }
}

impl Bvh {
    /// A nearest-first walk of the leaves `ray` may meet.
    #[inline(always)]
    pub fn walk(&self, ray: BoxRay) -> Walk4<'_> {
        let start = (!self.nodes.is_empty()).then_some(0);
        Walk::new(self.nodes.as_slice(), ray, start)
    }

    /// A walk of the leaves that any ray of `packet` may meet, nearest
    /// (for the packet's bounds) first.
    #[inline(always)]
    pub fn walk_packet(&self, packet: BoxPacket) -> Walk<&[BvhNode], 4, STACK, BoxPacket> {
        let start = (!self.nodes.is_empty()).then_some(0);
        Walk::new(self.nodes.as_slice(), packet, start)
    }

    /// Visits the leaves that `ray` may meet before `t_max`, nearest box
    /// first. `leaf(first_slot, count, t_max)` tests a leaf's primitives
    /// and returns the (possibly nearer) `t_max` to go on with; the last
    /// one is returned.
    #[inline(always)]
    pub fn traverse(
        &self,
        ray: &BoxRay,
        mut t_max: f32,
        mut leaf: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        let mut walk = self.walk(*ray);
        while let Some((first, count)) = walk.next_leaf(t_max) {
            t_max = leaf(first, count, t_max);
        }
        t_max
    }
}
