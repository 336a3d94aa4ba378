//! A binary hierarchy by the binned surface area heuristic (Wald 2007).
//!
//! Each node bins its primitives' centroids into 16 slabs along each axis,
//! keeping per bin the box of the primitives and of their centroids, and
//! splits where the heuristic cost A_left N_left + A_right N_right is least;
//! the bins also give both children their boxes, so no primitive is visited
//! twice per level. Large nodes bin in parallel; subtrees build in parallel.
//!
//! The depth is bounded: below `SAH_DEPTH` levels a node splits at the
//! median of its centroids, so no tree is deeper than SAH_DEPTH + log2(n)
//! and a fixed traversal stack always suffices.

use super::Aabb;
use crate::render::math::Vec3A;
use rayon::prelude::*;

/// Most primitives in a leaf, except where the heuristic cannot tell them
/// apart (identical centroids at the depth limit's median split never
/// leave more than this either: the median always halves).
pub const MAX_LEAF: usize = 4;
const BINS: usize = 16;
/// Nodes with more primitives than this bin in parallel.
const PARALLEL_BINNING: usize = 32 * 1024;
/// Nodes with more primitives than this build their subtrees in parallel.
const PARALLEL_SUBTREE: usize = 2 * 1024;
/// Levels split by the heuristic before median splits take over.
const SAH_DEPTH: u32 = 40;
/// Cost of visiting a node, relative to testing one primitive (0.5, 1, 2
/// and 4 measured with the embree_compare example: 2 and 4 trace 6% more
/// bounce rays per second than 1 and build 20% faster; docs/BENCHMARKS.md).
const TRAVERSAL_COST: f32 = 2.0;

/// A node of the binary tree; leaves are ranges of the primitive order.
pub(super) enum Node2 {
    Leaf {
        bounds: Aabb,
        start: u32,
        count: u32,
    },
    Inner {
        bounds: Aabb,
        children: Box<[Node2; 2]>,
    },
}

impl Node2 {
    pub(super) fn bounds(&self) -> Aabb {
        match self {
            Node2::Leaf { bounds, .. } | Node2::Inner { bounds, .. } => *bounds,
        }
    }
}

/// The tree over `boxes` and the primitive order its leaves index.
pub(super) fn build(boxes: &[Aabb]) -> (Option<Node2>, Vec<u32>) {
    if boxes.is_empty() {
        return (None, Vec::new());
    }
    let centroids: Vec<Vec3A> = boxes.par_iter().map(Aabb::centroid).collect();
    let mut refs: Vec<u32> = (0..boxes.len() as u32).collect();
    let ctx = Ctx {
        boxes,
        centroids: &centroids,
    };
    let (bounds, cbounds) = ctx.bounds_of(&refs);
    let tree = ctx.node(&mut refs, 0, 0, bounds, cbounds);
    (Some(tree), refs)
}

struct Ctx<'a> {
    boxes: &'a [Aabb],
    centroids: &'a [Vec3A],
}

/// The primitives of one bin: their boxes' union, their centroids' box, and how many.
#[derive(Clone, Copy, Default)]
struct Bin {
    bounds: Aabb,
    cbounds: Aabb,
    count: u32,
}

impl Bin {
    fn merge(self, o: Bin) -> Bin {
        Bin {
            bounds: self.bounds.union(o.bounds),
            cbounds: self.cbounds.union(o.cbounds),
            count: self.count + o.count,
        }
    }
}

type Bins = [[Bin; BINS]; 3];

struct Split {
    axis: usize,
    /// Bins below this go left.
    bin: usize,
    cost: f32,
    left: Bin,
    right: Bin,
}

impl Ctx<'_> {
    fn node(
        &self,
        refs: &mut [u32],
        offset: usize,
        depth: u32,
        bounds: Aabb,
        cbounds: Aabb,
    ) -> Node2 {
        let n = refs.len();
        let leaf = || Node2::Leaf {
            bounds,
            start: offset as u32,
            count: n as u32,
        };
        if n == 1 {
            return leaf();
        }
        let (mid, left, right) = if depth >= SAH_DEPTH {
            if n <= MAX_LEAF {
                return leaf();
            }
            self.median_split(refs, &cbounds)
        } else {
            match self.best_split(refs, &cbounds) {
                Some(s) if n > MAX_LEAF || s.cost < n as f32 * bounds.half_area() => {
                    let mid = partition(refs, |&r| self.bin_of(r, s.axis, &cbounds) < s.bin);
                    if mid == 0 || mid == n {
                        self.median_split(refs, &cbounds)
                    } else {
                        (mid, s.left, s.right)
                    }
                }
                None if n > MAX_LEAF => self.median_split(refs, &cbounds),
                _ => return leaf(),
            }
        };
        let (l, r) = refs.split_at_mut(mid);
        let (a, b) = if n > PARALLEL_SUBTREE {
            rayon::join(
                || self.node(l, offset, depth + 1, left.bounds, left.cbounds),
                || self.node(r, offset + mid, depth + 1, right.bounds, right.cbounds),
            )
        } else {
            (
                self.node(l, offset, depth + 1, left.bounds, left.cbounds),
                self.node(r, offset + mid, depth + 1, right.bounds, right.cbounds),
            )
        };
        Node2::Inner {
            bounds,
            children: Box::new([a, b]),
        }
    }

    /// Boxes of the primitives and of their centroids.
    fn bounds_of(&self, refs: &[u32]) -> (Aabb, Aabb) {
        let fold = |refs: &[u32]| {
            refs.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), &r| {
                (
                    b.union(self.boxes[r as usize]),
                    c.with_point(self.centroids[r as usize]),
                )
            })
        };
        if refs.len() > PARALLEL_BINNING {
            refs.par_chunks(PARALLEL_BINNING / 4).map(fold).reduce(
                || (Aabb::EMPTY, Aabb::EMPTY),
                |(a, b), (c, d)| (a.union(c), b.union(d)),
            )
        } else {
            fold(refs)
        }
    }

    #[inline]
    fn bin_of(&self, r: u32, axis: usize, cbounds: &Aabb) -> usize {
        let extent = cbounds.max[axis] - cbounds.min[axis];
        let scale = BINS as f32 * (1.0 - 1e-6) / extent;
        let k = ((self.centroids[r as usize][axis] - cbounds.min[axis]) * scale) as usize;
        k.min(BINS - 1)
    }

    fn bin(&self, refs: &[u32], cbounds: &Aabb) -> Bins {
        let fold = |refs: &[u32]| {
            let mut bins: Bins = [[Bin::default(); BINS]; 3];
            for &r in refs {
                let (b, c) = (self.boxes[r as usize], self.centroids[r as usize]);
                for (axis, axis_bins) in bins.iter_mut().enumerate() {
                    if cbounds.max[axis] > cbounds.min[axis] {
                        let bin = &mut axis_bins[self.bin_of(r, axis, cbounds)];
                        bin.bounds = bin.bounds.union(b);
                        bin.cbounds = bin.cbounds.with_point(c);
                        bin.count += 1;
                    }
                }
            }
            bins
        };
        if refs.len() > PARALLEL_BINNING {
            refs.par_chunks(PARALLEL_BINNING / 4).map(fold).reduce(
                || [[Bin::default(); BINS]; 3],
                |mut a, b| {
                    for (x, y) in a.iter_mut().flatten().zip(b.iter().flatten()) {
                        *x = x.merge(*y);
                    }
                    a
                },
            )
        } else {
            fold(refs)
        }
    }

    /// The cheapest split between bins, or None when every centroid is the same point.
    fn best_split(&self, refs: &[u32], cbounds: &Aabb) -> Option<Split> {
        let bins = self.bin(refs, cbounds);
        let mut best: Option<Split> = None;
        for (axis, bins) in bins.iter().enumerate() {
            if !(cbounds.max[axis] > cbounds.min[axis]) {
                continue;
            }
            // right[i]: bins i.. merged.
            let mut right = [Bin::default(); BINS];
            let mut acc = Bin::default();
            for i in (1..BINS).rev() {
                acc = acc.merge(bins[i]);
                right[i] = acc;
            }
            let mut left = Bin::default();
            for i in 1..BINS {
                left = left.merge(bins[i - 1]);
                let r = right[i];
                if left.count == 0 || r.count == 0 {
                    continue;
                }
                let cost = left.bounds.half_area() * left.count as f32
                    + r.bounds.half_area() * r.count as f32;
                if best.as_ref().is_none_or(|b| cost < b.cost) {
                    best = Some(Split {
                        axis,
                        bin: i,
                        cost,
                        left,
                        right: r,
                    });
                }
            }
        }
        // The parent's own visit, in the same units.
        let parent = cbounds_parent_area(&best);
        best.map(|mut s| {
            s.cost += TRAVERSAL_COST * parent;
            s
        })
    }

    /// Splits at the median centroid along the widest axis of the centroids.
    fn median_split(&self, refs: &mut [u32], cbounds: &Aabb) -> (usize, Bin, Bin) {
        let e = cbounds.extent();
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let mid = refs.len() / 2;
        let c = self.centroids;
        refs.select_nth_unstable_by(mid, |&a, &b| {
            c[a as usize][axis].total_cmp(&c[b as usize][axis])
        });
        let side = |refs: &[u32]| {
            let (bounds, cbounds) = self.bounds_of(refs);
            Bin {
                bounds,
                cbounds,
                count: refs.len() as u32,
            }
        };
        (mid, side(&refs[..mid]), side(&refs[mid..]))
    }
}

/// The area of the union of a split's two sides (the parent's box).
fn cbounds_parent_area(split: &Option<Split>) -> f32 {
    split
        .as_ref()
        .map_or(0.0, |s| s.left.bounds.union(s.right.bounds).half_area())
}

/// Moves the elements for which `left` holds to the front; how many there are.
fn partition(refs: &mut [u32], left: impl Fn(&u32) -> bool) -> usize {
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if left(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
        }
    }
    i
}
