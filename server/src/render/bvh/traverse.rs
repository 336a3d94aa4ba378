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

use super::{Bvh, BvhNode, EMPTY};
use crate::render::math::{gamma, Vec3A, Vec4};
use std::mem::MaybeUninit;

/// Exit distances are scaled by this before the overlap test (the OpenCL
/// kernel gets the same bits as `BVH_ROBUST_BITS`).
pub const ROBUST: f32 = 1.0 + 2.0 * gamma(3);

/// Deepest node stack a traversal needs: three more children than it pops
/// at each level, and trees are at most 64 levels deep (see `build`).
pub(crate) const STACK: usize = 3 * 64 + 4;
/// The stack of trees at most `SHALLOW_DEPTH` deep (nearly all): small
/// enough that setting it up costs nothing.
const SHALLOW_STACK: usize = 64;
const SHALLOW_DEPTH: u32 = (SHALLOW_STACK as u32 - 1) / 3;
/// A stack entry holds a child as `child << 3 | count` (leaves hold at most
/// `MAX_LEAF` < 8 primitives) and its entry distance.
const COUNT_BITS: u32 = 3;
const _: () = assert!(super::MAX_LEAF < 1 << COUNT_BITS);

/// A ray prepared for box tests: origin and reciprocal direction in every
/// lane, and for each axis which bound (min or max) it meets first.
#[derive(Clone, Copy, Debug)]
pub struct BoxRay {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    /// Row of `BvhNode::bounds` with the near (entry) plane of each axis.
    near: [usize; 3],
    /// Row with the far (exit) plane of each axis.
    far: [usize; 3],
}

impl BoxRay {
    #[inline(always)]
    pub fn new(origin: Vec3A, dir: Vec3A) -> Self {
        let inv = |d: f32| 1.0 / d;
        let neg = |d: f32| usize::from(d.is_sign_negative());
        Self {
            org: [
                Vec4::splat(origin.x),
                Vec4::splat(origin.y),
                Vec4::splat(origin.z),
            ],
            inv: [
                Vec4::splat(inv(dir.x)),
                Vec4::splat(inv(dir.y)),
                Vec4::splat(inv(dir.z)),
            ],
            near: [3 * neg(dir.x), 1 + 3 * neg(dir.y), 2 + 3 * neg(dir.z)],
            far: [3 - 3 * neg(dir.x), 4 - 3 * neg(dir.y), 5 - 3 * neg(dir.z)],
        }
    }

    /// Entry distance of each of the node's four boxes, and which of them
    /// the ray meets between 0 and `t_max` (bit i for child i).
    #[inline(always)]
    pub fn test(&self, node: &BvhNode, t_max: f32) -> (Vec4, u32) {
        let b = &node.bounds;
        let slab = |axis: usize| {
            let near = Vec4::from_array(b[self.near[axis]]);
            let far = Vec4::from_array(b[self.far[axis]]);
            (
                (near - self.org[axis]) * self.inv[axis],
                (far - self.org[axis]) * self.inv[axis],
            )
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let t_near = max_or(nz, max_or(ny, max_or(nx, Vec4::ZERO)));
        let t_far = min_or(fz, min_or(fy, min_or(fx, Vec4::splat(t_max)))) * ROBUST;
        (t_near, t_near.cmple(t_far).bitmask())
    }
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

impl Bvh {
    /// Visits the leaves that `ray` may meet before `t_max`, nearest box
    /// first. `leaf(first_slot, count, t_max)` tests a leaf's primitives
    /// and returns the (possibly nearer) `t_max` to go on with; the last
    /// one is returned.
    #[inline(always)]
    pub fn traverse(
        &self,
        ray: &BoxRay,
        t_max: f32,
        leaf: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        if self.depth <= SHALLOW_DEPTH {
            self.traverse_with::<SHALLOW_STACK>(ray, t_max, leaf)
        } else {
            self.traverse_with::<STACK>(ray, t_max, leaf)
        }
    }

    #[inline(always)]
    fn traverse_with<const N: usize>(
        &self,
        ray: &BoxRay,
        mut t_max: f32,
        mut leaf: impl FnMut(u32, u32, f32) -> f32,
    ) -> f32 {
        if self.nodes.is_empty() {
            return t_max;
        }
        const MASK: u32 = (1 << COUNT_BITS) - 1;
        // Not zeroed: a deep tree's stack is 1.5 KB, and clearing it for
        // every ray (and again for every instance it enters) cost the mesh
        // scenes a tenth of their time in `memset`.
        let mut stack = [MaybeUninit::<(u32, f32)>::uninit(); N];
        let mut top = 0;
        // The nearest child hit goes on at once, without the stack.
        let mut next = Some((0u32, 0.0f32));
        loop {
            let (entry, t_near) = match next.take() {
                Some(e) => e,
                None if top == 0 => break,
                None => {
                    top -= 1;
                    // SAFETY: entries below `top` were all written (pushes
                    // write `stack[top..top + n - 1]` before raising `top`).
                    #[allow(unsafe_code)]
                    unsafe {
                        stack[top].assume_init()
                    }
                }
            };
            if t_near > t_max {
                continue;
            }
            let (child, count) = (entry >> COUNT_BITS, entry & MASK);
            if count > 0 {
                t_max = leaf(child, count, t_max);
                continue;
            }
            let node = &self.nodes[child as usize];
            let (t, mut mask) = ray.test(node, t_max);
            let t = t.to_array();
            // The children hit, sorted by entry distance, nearest last.
            let mut hits = [(0u32, 0.0f32); 4];
            let mut n = 0;
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                debug_assert_ne!(node.child[i], EMPTY);
                let entry = (node.child[i] << COUNT_BITS | node.count[i], t[i]);
                let mut j = n;
                while j > 0 && hits[j - 1].1 < entry.1 {
                    hits[j] = hits[j - 1];
                    j -= 1;
                }
                hits[j] = entry;
                n += 1;
            }
            if n > 0 {
                next = Some(hits[n - 1]);
                for (slot, hit) in stack[top..top + n - 1].iter_mut().zip(&hits[..n - 1]) {
                    *slot = MaybeUninit::new(*hit);
                }
                top += n - 1;
            }
        }
        t_max
    }
}
