//! Tests of the BVH: its structure for random and degenerate boxes, and
//! traversals that meet every leaf a ray meets.

use super::*;
use crate::render::math::Vec3A;
use crate::render::sampler::Sampler;

pub(super) fn random_boxes(n: usize, seed: u64) -> Vec<Aabb> {
    (0..n as u64)
        .map(|i| {
            let mut s = Sampler::new(seed, i, 0);
            let c = Vec3A::new(s.next_f32(), s.next_f32(), s.next_f32()) * 100.0;
            let e = Vec3A::new(s.next_f32(), s.next_f32(), s.next_f32()) * 3.0;
            Aabb::new(c - e, c + e)
        })
        .collect()
}

/// Every primitive sits in exactly one leaf whose box holds it, every
/// child box holds its subtree, leaves are small and the tree shallow.
fn check_structure(bvh: &Bvh, boxes: &[Aabb]) {
    let mut seen = vec![0u32; boxes.len()];
    let mut sorted = bvh.prims.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..boxes.len() as u32).collect::<Vec<_>>(),
        "prims is a permutation"
    );
    fn walk(
        bvh: &Bvh,
        boxes: &[Aabb],
        node: usize,
        outer: Aabb,
        seen: &mut [u32],
        depth: u32,
    ) -> u32 {
        let n = &bvh.nodes[node];
        let mut deepest = depth;
        for i in 0..4 {
            let b = n.child_bounds(i);
            if n.count[i] == 0 && n.child[i] == EMPTY {
                assert!(b.is_empty(), "empty slot with a box");
                continue;
            }
            assert!(
                outer.contains(b.min) && outer.contains(b.max),
                "child box outside its parent's"
            );
            if n.count[i] > 0 {
                assert!(n.count[i] as usize <= MAX_LEAF, "leaf of {}", n.count[i]);
                for slot in n.child[i]..n.child[i] + n.count[i] {
                    let p = bvh.prims[slot as usize] as usize;
                    seen[p] += 1;
                    assert!(
                        b.contains(boxes[p].min) && b.contains(boxes[p].max),
                        "leaf box does not hold prim {p}"
                    );
                }
            } else {
                assert!(
                    n.child[i] as usize > node,
                    "children come after their parent"
                );
                deepest = deepest.max(walk(bvh, boxes, n.child[i] as usize, b, seen, depth + 1));
            }
        }
        deepest
    }
    let depth = walk(bvh, boxes, 0, bvh.bounds, &mut seen, 1);
    assert_eq!(depth, bvh.depth);
    assert!(
        seen.iter().all(|&c| c == 1),
        "every prim in exactly one leaf"
    );
}

#[test]
fn structure_holds_for_random_boxes_of_every_size() {
    for n in [1, 2, 3, 4, 5, 17, 1000, 50_000] {
        let boxes = random_boxes(n, n as u64);
        let bvh = Bvh::build(&boxes);
        check_structure(&bvh, &boxes);
        assert!(bvh.depth <= 64, "{n} boxes: depth {}", bvh.depth);
    }
}

#[test]
fn identical_boxes_still_give_small_leaves_and_a_bounded_depth() {
    let boxes = vec![Aabb::new(Vec3A::ZERO, Vec3A::ONE); 10_000];
    let bvh = Bvh::build(&boxes);
    check_structure(&bvh, &boxes);
    assert!(bvh.depth <= 20, "depth {}", bvh.depth);
}

#[test]
fn empty_input_gives_an_empty_hierarchy_that_nothing_meets() {
    let bvh = Bvh::build(&[]);
    assert!(bvh.nodes.is_empty());
    let ray = BoxRay::new(Vec3A::ZERO, Vec3A::X);
    assert_eq!(bvh.traverse(&ray, 5.0, |_, _, _| panic!("no leaves")), 5.0);
}

/// Exact slab test in f64 for comparison: does the segment [0, t_max] of
/// the ray meet the box?
pub(super) fn meets(b: &Aabb, o: Vec3A, d: Vec3A, t_max: f64) -> bool {
    let (mut t0, mut t1) = (0.0f64, t_max);
    for a in 0..3 {
        let (o, d) = (f64::from(o[a]), f64::from(d[a]));
        let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
        if d == 0.0 {
            if o < lo || o > hi {
                return false;
            }
            continue;
        }
        let (mut a0, mut a1) = ((lo - o) / d, (hi - o) / d);
        if a0 > a1 {
            std::mem::swap(&mut a0, &mut a1);
        }
        t0 = t0.max(a0);
        t1 = t1.min(a1);
    }
    t0 <= t1
}

/// Ray `i` of a set through `random_boxes`' space: origin, direction
/// (every fourth axis-parallel: zero components) and segment length.
pub(super) fn test_ray(seed: u64, i: u64) -> (Vec3A, Vec3A, f32) {
    let mut s = Sampler::new(seed, i, 0);
    let o = Vec3A::new(s.next_f32(), s.next_f32(), s.next_f32()) * 120.0 - 10.0;
    let mut d = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5).normalize();
    if i.is_multiple_of(4) {
        d = [Vec3A::X, -Vec3A::Y, Vec3A::Z, -Vec3A::X][(i / 4 % 4) as usize];
    }
    let t_max = if i.is_multiple_of(3) {
        40.0
    } else {
        f32::INFINITY
    };
    (o, d, t_max)
}

#[test]
fn traversal_visits_every_leaf_whose_primitive_the_ray_meets() {
    let boxes = random_boxes(5_000, 7);
    let bvh = Bvh::build(&boxes);
    for i in 0..2_000u64 {
        let (o, d, t_max) = test_ray(99, i);
        let mut visited = vec![false; boxes.len()];
        bvh.traverse(&BoxRay::new(o, d), t_max, |first, count, t| {
            for slot in first..first + count {
                visited[bvh.prims[slot as usize] as usize] = true;
            }
            t
        });
        for (p, b) in boxes.iter().enumerate() {
            if meets(b, o, d, f64::from(t_max)) {
                assert!(
                    visited[p],
                    "ray {i}: box {p} met but its leaf was not visited"
                );
            }
        }
    }
}

#[test]
fn a_ray_in_the_plane_of_a_box_face_still_meets_the_box() {
    // Flat boxes (a triangle in the plane z = 2) and rays lying in that plane.
    let boxes = vec![Aabb::new(Vec3A::new(0.0, 0.0, 2.0), Vec3A::new(1.0, 1.0, 2.0)); 3];
    let bvh = Bvh::build(&boxes);
    let ray = BoxRay::new(Vec3A::new(-1.0, 0.5, 2.0), Vec3A::X);
    let mut visited = 0;
    bvh.traverse(&ray, f32::INFINITY, |_, count, t| {
        visited += count;
        t
    });
    assert_eq!(visited, 3);
}
