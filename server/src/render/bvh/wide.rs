//! An eight-wide copy of a mesh's BVH for the CPU: each node's eight boxes
//! are tested against one ray at once (one AVX register per slab plane
//! where the CPU has AVX2, two SSE registers elsewhere), which halves the
//! levels a ray descends and the nodes it loads. Embree's BVH8 is why its
//! single rays outran the four-wide traversal.
//!
//! Made from the same binary tree as the four-wide [`super::Bvh`]
//! ([`super::Bvh::build_pair`]), over the same leaves at the same (aligned)
//! slots, so a leaf's triangles and packs are where the four-wide tree has
//! them; the OpenCL kernel keeps reading the four-wide nodes.

use super::build::Node2;
use super::flatten::{collapse, Slots};
use super::traverse::{BoxRay, Nodes, Walk, COUNT_BITS};
use super::{Aabb, BoxPacket, EMPTY};

/// Children per node.
pub const WIDTH: usize = 8;

/// Deepest stack: seven more children than it pops at each level (the tree
/// is no deeper than the four-wide one, at most 64 levels).
const STACK: usize = (WIDTH - 1) * 64 + WIDTH;

/// A walk of a [`WideBvh`] with node test `T`.
pub type Walk8<'a, T> = Walk<WideNodes<'a, T>, WIDTH, STACK>;

/// A node of up to eight children, boxes structure of arrays; child `i`
/// as in [`BvhNode`] (inner: count 0 and its node index; leaf: count > 0
/// and its first slot; empty: [`EMPTY`] with an inverted box).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideNode {
    /// min x, min y, min z, max x, max y, max z, each for the eight children.
    pub bounds: [[f32; WIDTH]; 6],
    pub child: [u32; WIDTH],
    pub count: [u32; WIDTH],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 256);
const _: () = assert!(super::MAX_LEAF < 1 << COUNT_BITS);

impl WideNode {
    pub(super) const EMPTY_NODE: WideNode = WideNode {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        child: [EMPTY; WIDTH],
        count: [0; WIDTH],
    };

    pub(super) fn set_child(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        super::set_slot(&mut self.bounds, i, bounds);
        self.child[i] = child;
        self.count[i] = count;
    }
}

impl Slots for WideNode {
    const WIDTH: usize = WIDTH;
    const EMPTY: Self = WideNode::EMPTY_NODE;
    fn set(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        self.set_child(i, bounds, child, count);
    }
}

/// The eight-wide hierarchy of a [`Bvh`]; node 0 is the root.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    /// Most nodes on a path from the root to a leaf.
    pub depth: u32,
    /// Where a walk starts: the root node, the one leaf of a tree that is
    /// nothing else (a wall's two triangles: the box that led here is the
    /// same), or nothing.
    start: Option<u32>,
}

impl WideBvh {
    /// The binary tree collapsed to eight children a node (as `flatten`
    /// collapses it to four); leaves keep the tree's slots.
    pub(super) fn from_tree(root: Option<&Node2>) -> WideBvh {
        let (nodes, depth) = collapse::<WideNode>(root);
        let start = start_of(&nodes);
        WideBvh {
            nodes,
            depth,
            start,
        }
    }

    /// Moves every leaf from slot `first` to slot `to(first)`.
    pub(super) fn move_leaves(&mut self, to: impl Fn(u32) -> u32) {
        for node in &mut self.nodes {
            for i in 0..WIDTH {
                if node.count[i] > 0 {
                    node.child[i] = to(node.child[i]);
                }
            }
        }
        self.start = start_of(&self.nodes);
    }

    /// A nearest-first walk of the leaves `ray` may meet (as [`Bvh::walk`]),
    /// testing nodes with `test`.
    #[inline(always)]
    pub fn walk<T: WideTest>(&self, ray: BoxRay, test: T) -> Walk8<'_, T> {
        let nodes = WideNodes {
            nodes: &self.nodes,
            test,
        };
        Walk::new(nodes, ray, self.start)
    }

    /// A walk of the leaves that any ray of `packet` may meet (`test`
    /// only gives the walk its type: a packet tests nodes itself).
    #[inline(always)]
    pub fn walk_packet<T: WideTest>(
        &self,
        packet: BoxPacket,
        test: T,
    ) -> Walk<WideNodes<'_, T>, WIDTH, STACK, BoxPacket> {
        let nodes = WideNodes {
            nodes: &self.nodes,
            test,
        };
        Walk::new(nodes, packet, self.start)
    }

    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
    }
}

/// Where a walk of `nodes` starts: the root, the one leaf of a tree that is
/// nothing else, or nothing.
fn start_of(nodes: &[WideNode]) -> Option<u32> {
    match nodes {
        [] => None,
        [root] if root.count[0] > 0 && root.child[1..] == [EMPTY; WIDTH - 1] => {
            Some(root.child[0] << COUNT_BITS | root.count[0])
        }
        _ => Some(0),
    }
}

/// How this CPU tests a wide node's eight boxes against one ray: entry
/// distances and the mask of those met before `t_max` (`render::isa`
/// implements it for each instruction set, with [`test_portable`] or
/// `wide_avx2::test`: the same bits).
pub trait WideTest: Copy {
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32);
}

/// The four-wide test ([`BoxRay::test`]) on each half of the node, with
/// SSE (or the portable fallback of [`Vec4`]).
#[inline(always)]
pub fn test_portable(ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
    let b = &node.bounds;
    let mut lo = [[0.0; 4]; 6];
    let mut hi = [[0.0; 4]; 6];
    for r in 0..6 {
        lo[r].copy_from_slice(&b[r][..4]);
        hi[r].copy_from_slice(&b[r][4..]);
    }
    let ((lo, lo_mask), (hi, hi_mask)) = (ray.test_rows(&lo, t_max), ray.test_rows(&hi, t_max));
    let mut t = [0.0; WIDTH];
    t[..4].copy_from_slice(&lo.to_array());
    t[4..].copy_from_slice(&hi.to_array());
    (t, lo_mask | hi_mask << 4)
}

/// A wide tree's nodes with the test that this CPU runs.
#[derive(Clone, Copy)]
pub struct WideNodes<'a, T> {
    nodes: &'a [WideNode],
    test: T,
}

impl<T: WideTest> Nodes<WIDTH> for WideNodes<'_, T> {
    #[inline(always)]
    fn test(&self, ray: &BoxRay, index: u32, t_max: f32) -> ([f32; WIDTH], u32) {
        self.test.wide_test(ray, &self.nodes[index as usize], t_max)
    }

    #[inline(always)]
    fn entry(&self, index: u32, i: usize) -> u32 {
        let node = &self.nodes[index as usize];
        debug_assert_ne!(node.child[i], EMPTY);
        node.child[i] << COUNT_BITS | node.count[i]
    }

    #[inline(always)]
    fn bounds(&self, index: u32) -> &[[f32; WIDTH]; 6] {
        &self.nodes[index as usize].bounds
    }
}
