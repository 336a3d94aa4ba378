//! The binary tree collapsed to four children per node: each node takes
//! its two children, then repeatedly opens the inner child with the largest
//! surface (the one most rays would have to enter) until it holds four.
//! Nodes are laid out depth first, parents before children.

use super::build::Node2;
use super::{Bvh, BvhNode};

pub(super) fn flatten(root: Option<&Node2>) -> Bvh {
    let Some(root) = root else {
        return Bvh::default();
    };
    let mut nodes = Vec::new();
    let depth = match root {
        Node2::Leaf {
            bounds,
            start,
            count,
        } => {
            let mut node = BvhNode::EMPTY_NODE;
            node.set_child(0, *bounds, *start, *count);
            nodes.push(node);
            1
        }
        Node2::Inner { .. } => emit(root, &mut nodes),
    };
    Bvh {
        nodes,
        prims: Vec::new(),
        bounds: root.bounds(),
        depth,
    }
}

/// Appends the node for inner node `node` and its subtree; its depth.
fn emit(node: &Node2, out: &mut Vec<BvhNode>) -> u32 {
    let Node2::Inner { children, .. } = node else {
        unreachable!("emit is only called on inner nodes");
    };
    let mut kids: Vec<&Node2> = vec![&children[0], &children[1]];
    while kids.len() < 4 {
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
    out.push(BvhNode::EMPTY_NODE);
    let mut depth = 0;
    for (slot, kid) in kids.into_iter().enumerate() {
        match kid {
            Node2::Leaf {
                bounds,
                start,
                count,
            } => out[index].set_child(slot, *bounds, *start, *count),
            Node2::Inner { bounds, .. } => {
                let child = out.len() as u32;
                depth = depth.max(emit(kid, out));
                out[index].set_child(slot, *bounds, child, 0);
            }
        }
    }
    depth + 1
}
