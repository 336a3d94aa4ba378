//! Bounding volume hierarchies: one layout for every use (the objects of a
//! scene, the triangles of a mesh) and for both backends.
//!
//! - `build`: a binary tree by the surface area heuristic, binned, with the
//!   large splits binned in parallel and the subtrees built in parallel.
//! - `flatten`: that tree collapsed to four children per node and laid out
//!   depth first in one array of [`BvhNode`]s, the `#[repr(C)]` form that
//!   the CPU traverses and the OpenCL kernel can read unchanged.
//! - `traverse`: nearest-first traversal with a conservative box test.
//! - `wide`: the same hierarchy eight children wide, which the CPU traverses.
//!
//! A BVH does not hold its primitives: a leaf is a range of slots, and
//! `prims[slot]` is the index of the primitive in the caller's list (a mesh
//! stores its triangles in slot order instead, so that a leaf's triangles
//! are read in sequence).

mod aabb;
mod build;
mod flatten;
mod packet;
mod traverse;
mod wide;
#[cfg(target_arch = "x86_64")]
mod wide_avx2;

pub use aabb::Aabb;
pub use build::MAX_LEAF;
pub use packet::{BoxPacket, PACKET};
pub(crate) use traverse::STACK;
pub use traverse::{BoxRay, Nodes, Probe, Walk, Walk4, ROBUST};
pub use wide::{test_portable, Walk8, WideBvh, WideNode, WideNodes, WideTest, WIDTH};
#[cfg(target_arch = "x86_64")]
pub use wide_avx2::test as test_avx2;

use bytemuck::{Pod, Zeroable};

/// A child slot that holds nothing.
pub const EMPTY: u32 = u32::MAX;

/// A node with up to four children, their boxes stored structure of arrays
/// so that one ray is tested against all four at once.
///
/// Child `i` is
/// - an inner node: `count[i] == 0`, `child[i]` its index in the node array;
/// - a leaf: `count[i] > 0` primitives in slots `child[i] .. child[i] + count[i]`;
/// - empty: `count[i] == 0`, `child[i] == EMPTY`, and an inverted box
///   (min +inf, max -inf) that no ray meets.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    /// min x, min y, min z, max x, max y, max z, each for the four children.
    pub bounds: [[f32; 4]; 6],
    pub child: [u32; 4],
    pub count: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 128);

impl BvhNode {
    /// A node whose four slots are empty.
    pub const EMPTY_NODE: BvhNode = BvhNode {
        bounds: [
            [f32::INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::NEG_INFINITY; 4],
            [f32::NEG_INFINITY; 4],
        ],
        child: [EMPTY; 4],
        count: [0; 4],
    };

    /// The box of child `i`.
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let b = &self.bounds;
        Aabb::new(
            [b[0][i], b[1][i], b[2][i]].into(),
            [b[3][i], b[4][i], b[5][i]].into(),
        )
    }

    fn set_child(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        set_slot(&mut self.bounds, i, bounds);
        self.child[i] = child;
        self.count[i] = count;
    }
}

/// Writes `b` into slot `i` of a node's bounds rows (min x, y, z, max x,
/// y, z), for nodes of any width.
fn set_slot<const W: usize>(rows: &mut [[f32; W]; 6], i: usize, b: Aabb) {
    for a in 0..3 {
        rows[a][i] = b.min[a];
        rows[a + 3][i] = b.max[a];
    }
}

/// A hierarchy over `prims.len()` primitives. Node 0 is the root; an empty
/// hierarchy has no nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Primitive index of every leaf slot.
    pub prims: Vec<u32>,
    /// Box of everything.
    pub bounds: Aabb,
    /// Most nodes on a path from the root to a leaf.
    pub depth: u32,
}

impl Bvh {
    /// Most primitives (or nodes) a hierarchy may index: stack entries keep
    /// a slot or node index in 29 bits.
    pub const MAX_PRIMS: usize = 1 << 28;

    /// A hierarchy over primitives with these boxes (finite, or the
    /// primitive can never be hit: such boxes are placed but never split on).
    /// At most [`Bvh::MAX_PRIMS`] of them.
    pub fn build(boxes: &[Aabb]) -> Bvh {
        Self::build_with_tree(boxes).0
    }

    /// [`Bvh::build`], and the binary tree it was collapsed from.
    fn build_with_tree(boxes: &[Aabb]) -> (Bvh, Option<build::Node2>) {
        assert!(
            boxes.len() <= Self::MAX_PRIMS,
            "too many primitives for one BVH"
        );
        let (tree, prims) = build::build(boxes);
        let mut bvh = flatten::flatten(tree.as_ref());
        bvh.prims = prims;
        (bvh, tree)
    }

    /// A mesh's two hierarchies over the same leaves: the four-wide one with
    /// aligned leaves ([`Bvh::aligned_leaves`]), which the OpenCL kernel
    /// reads, and its eight-wide twin ([`WideBvh`]), which the CPU
    /// traverses. At most [`Bvh::MAX_PRIMS`] / [`MAX_LEAF`] primitives.
    pub fn build_pair(boxes: &[Aabb]) -> (Bvh, WideBvh) {
        let (bvh, tree) = Self::build_with_tree(boxes);
        let mut wide = WideBvh::from_tree(tree.as_ref());
        let (bvh, firsts) = bvh.align();
        wide.move_leaves(|first| {
            let k = firsts.binary_search(&first).expect("a leaf of both trees");
            (k * MAX_LEAF) as u32
        });
        (bvh, wide)
    }

    /// Moves every leaf to slots `4k .. 4k + count` for its number k in
    /// slot order, the slots past its count holding its last primitive
    /// again (traversals read `count` slots: they never see them). A
    /// mesh's leaves are then numbered by `first / 4` (its SIMD packs).
    /// For at most [`Bvh::MAX_PRIMS`] / [`MAX_LEAF`] primitives (the padded
    /// slots stay within [`Bvh::MAX_PRIMS`]).
    pub fn aligned_leaves(self) -> Bvh {
        self.align().0
    }

    /// [`Bvh::aligned_leaves`], and the leaves' first slots before, in
    /// slot order (leaf k's).
    fn align(mut self) -> (Bvh, Vec<u32>) {
        let mut leaves: Vec<(u32, usize, usize)> = Vec::new(); // (first, node, child)
        for (n, node) in self.nodes.iter().enumerate() {
            for i in 0..4 {
                if node.count[i] > 0 {
                    leaves.push((node.child[i], n, i));
                }
            }
        }
        assert!(
            leaves.len() * MAX_LEAF <= Self::MAX_PRIMS,
            "too many primitives to align"
        );
        leaves.sort_unstable();
        let mut prims = Vec::with_capacity(leaves.len() * MAX_LEAF);
        for (k, &(first, n, i)) in leaves.iter().enumerate() {
            let count = self.nodes[n].count[i];
            for lane in 0..MAX_LEAF as u32 {
                prims.push(self.prims[(first + lane.min(count - 1)) as usize]);
            }
            self.nodes[n].child[i] = (k * MAX_LEAF) as u32;
        }
        self.prims = prims;
        (self, leaves.into_iter().map(|l| l.0).collect())
    }

    /// The one leaf of a hierarchy that is nothing else (a mesh of at most
    /// [`MAX_LEAF`] primitives): its first slot and count. A ray that
    /// reached the hierarchy's box may test it at once, without a node.
    #[inline(always)]
    pub fn single_leaf(&self) -> Option<(u32, u32)> {
        match self.nodes.as_slice() {
            [root] if root.count[0] > 0 && root.child[1..] == [EMPTY; 3] => {
                Some((root.child[0], root.count[0]))
            }
            _ => None,
        }
    }

    /// Bytes held by the nodes and the slot list.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<BvhNode>() + self.prims.len() * 4
    }
}

#[cfg(test)]
mod tests;
#[cfg(test)]
mod wide_tests;
