//! The binary tree collapsed to `W` children per node (four for
//! [`BvhNode`], eight for `WideNode`): each node takes its two children,
//! then repeatedly opens the inner child with the largest surface (the one
//! most rays would have to enter) until it holds `W`. Nodes are laid out
//! depth first, parents before children.

use super::build::Node2;
use super::{Aabb, Bvh, BvhNode};

/// A node of child slots, as collapsing fills it.
pub(super) trait Slots: Sized {
    const WIDTH: usize;
    /// A node whose slots are all empty.
    const EMPTY: Self;
    fn set(&mut self, i: usize, bounds: Aabb, child: u32, count: u32);
}

impl Slots for BvhNode {
    const WIDTH: usize = 4;
    const EMPTY: Self = BvhNode::EMPTY_NODE;
    fn set(&mut self, i: usize, bounds: Aabb, child: u32, count: u32) {
        self.set_child(i, bounds, child, count);
    }
}

pub(super) fn flatten(root: Option<&Node2>) -> Bvh {
    let (nodes, depth) = collapse::<BvhNode>(root);
    Bvh {
        nodes,
        prims: Vec::new(),
        bounds: root.map_or_else(Aabb::default, Node2::bounds),
        depth,
    }
}

/// The tree under `root` as nodes of `N::WIDTH` children, and its depth
/// (none and 0 for no tree; a lone leaf gets a node of its own).
pub(super) fn collapse<N: Slots>(root: Option<&Node2>) -> (Vec<N>, u32) {
    let mut nodes = Vec::new();
    let depth = match root {
        None => 0,
        Some(Node2::Leaf {
            bounds,
            start,
            count,
        }) => {
            let mut node = N::EMPTY;
            node.set(0, *bounds, *start, *count);
            nodes.push(node);
            1
        }
        Some(inner) => emit(inner, &mut nodes),
    };
    (nodes, depth)
}

/// Appends the node for inner node `node` and its subtree; its depth.
fn emit<N: Slots>(node: &Node2, out: &mut Vec<N>) -> u32 {
    let Node2::Inner { children, .. } = node else {
        unreachable!("emit is only called on inner nodes");
    };
    let mut kids: Vec<&Node2> = vec![&children[0], &children[1]];
    while kids.len() < N::WIDTH {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, Node2::Inner { .. }))
            .max_by(|(_, a), (_, b)| a.bounds().half_area().total_cmp(&b.bounds().half_area()))
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let Node2::Inner { children, .. } = kids[i] else {
            break;
        };
        kids[i] = &children[0];
        kids.push(&children[1]);
    }
    let index = out.len();
    out.push(N::EMPTY);
    let mut depth = 0;
    for (slot, kid) in kids.into_iter().enumerate() {
        match kid {
            Node2::Leaf {
                bounds,
                start,
                count,
            } => out[index].set(slot, *bounds, *start, *count),
            Node2::Inner { bounds, .. } => {
                let child = out.len() as u32;
                depth = depth.max(emit(kid, out));
                out[index].set(slot, *bounds, child, 0);
            }
        }
    }
    depth + 1
}
