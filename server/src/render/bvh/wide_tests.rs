//! Tests of the eight-wide BVH: the same leaves as the four-wide tree in
//! boxes that hold them, fuller nodes, traversals that meet every leaf a
//! ray meets, and the AVX2 node test equal to the portable one bit for bit.

use super::tests::{meets, random_boxes, test_ray};
use super::*;
use crate::render::math::Vec3A;
use crate::render::sampler::Sampler;

/// The portable node test, as `isa::Portable` runs it.
#[derive(Clone, Copy)]
struct Portable;

impl WideTest for Portable {
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        test_portable(ray, node, t_max)
    }
}

/// The AVX2 node test, made only where the CPU has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Avx2(());

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    fn detect() -> Option<Avx2> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Avx2(()))
    }
}

#[cfg(target_arch = "x86_64")]
impl WideTest for Avx2 {
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        // SAFETY: an `Avx2` exists only where `detect` found AVX2 and FMA.
        #[allow(unsafe_code)]
        unsafe {
            test_avx2(ray, node, t_max)
        }
    }
}

/// Every leaf of `bvh` once in `wide`, with the same box; child boxes
/// inside their parent's; the depth as recorded. Returns (leaves, children
/// of inner nodes in all).
fn check_wide(bvh: &Bvh, wide: &WideBvh) -> (usize, usize) {
    let mut want: Vec<(u32, u32, [u32; 6])> = Vec::new();
    let bits = |b: Aabb| [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
    for n in &bvh.nodes {
        for i in 0..4 {
            if n.count[i] > 0 {
                want.push((n.child[i], n.count[i], bits(n.child_bounds(i))));
            }
        }
    }
    let mut got = Vec::new();
    let mut children = 0;
    let mut stack = vec![(0usize, bvh.bounds, 1u32)];
    let mut depth = 0;
    while let Some((index, outer, level)) = stack.pop() {
        depth = depth.max(level);
        let node = &wide.nodes[index];
        for i in 0..WIDTH {
            let b = Aabb::new(
                [node.bounds[0][i], node.bounds[1][i], node.bounds[2][i]].into(),
                [node.bounds[3][i], node.bounds[4][i], node.bounds[5][i]].into(),
            );
            if node.child[i] == EMPTY {
                assert!(b.is_empty() && node.count[i] == 0, "empty slot with a box");
                continue;
            }
            children += 1;
            assert!(
                outer.contains(b.min) && outer.contains(b.max),
                "child box outside its parent's"
            );
            match node.count[i] {
                0 => {
                    assert!(node.child[i] as usize > index, "children after parents");
                    stack.push((node.child[i] as usize, b, level + 1));
                }
                n => got.push((node.child[i], n, bits(b))),
            }
        }
    }
    assert_eq!(depth, wide.depth);
    assert!(wide.depth <= 64);
    want.sort_unstable();
    got.sort_unstable();
    assert_eq!(got, want, "the same leaves with the same boxes");
    (got.len(), children)
}

#[test]
fn the_wide_tree_holds_the_same_leaves_in_fuller_nodes() {
    for n in [2, 3, 4, 5, 17, 1000, 50_000] {
        let boxes = random_boxes(n, n as u64);
        let (bvh, wide) = Bvh::build_pair(&boxes);
        assert_eq!(bvh, Bvh::build(&boxes).aligned_leaves());
        let (leaves, children) = check_wide(&bvh, &wide);
        assert!(leaves >= n.div_ceil(MAX_LEAF));
        if n >= 1000 {
            // Fuller nodes than a four-wide tree can have, and about half
            // as many (nodes above the leaves are nearly full; those just
            // above them hold what their subtree has).
            let fill = children as f64 / wide.nodes.len() as f64;
            assert!(fill > 4.5, "{n} boxes: {fill:.2} children per node");
            assert!(
                wide.nodes.len() * 10 < bvh.nodes.len() * 6,
                "{n} boxes: {} wide nodes, {} four-wide",
                wide.nodes.len(),
                bvh.nodes.len()
            );
        }
    }
    assert_eq!(Bvh::build_pair(&random_boxes(1, 1)).1.nodes.len(), 1);
    assert!(Bvh::build_pair(&[]).1.nodes.is_empty());
}

/// Leaves `wide` visits for a ray, with node test `test`.
fn visited<T: WideTest>(
    bvh: &Bvh,
    wide: &WideBvh,
    test: T,
    o: Vec3A,
    d: Vec3A,
    t_max: f32,
) -> Vec<bool> {
    let mut seen = vec![false; bvh.prims.iter().max().map_or(0, |&p| p as usize + 1)];
    let mut walk = wide.walk(BoxRay::new(o, d), test);
    while let Some((first, count)) = walk.next_leaf(t_max) {
        for slot in first..first + count {
            seen[bvh.prims[slot as usize] as usize] = true;
        }
    }
    seen
}

fn wide_traversal_meets_every_box(test: impl WideTest) {
    let boxes = random_boxes(5_000, 7);
    let (bvh, wide) = Bvh::build_pair(&boxes);
    for i in 0..2_000u64 {
        let (o, d, t_max) = test_ray(98, i);
        let seen = visited(&bvh, &wide, test, o, d, t_max);
        for (p, b) in boxes.iter().enumerate() {
            if meets(b, o, d, f64::from(t_max)) {
                assert!(seen[p], "ray {i}: box {p} met but its leaf was not visited");
            }
        }
    }
}

#[test]
fn wide_traversal_visits_every_leaf_whose_box_the_ray_meets() {
    wide_traversal_meets_every_box(Portable);
    #[cfg(target_arch = "x86_64")]
    if let Some(avx2) = Avx2::detect() {
        wide_traversal_meets_every_box(avx2);
    }
}

#[test]
fn a_ray_in_the_plane_of_a_face_meets_the_wide_box() {
    let boxes = vec![Aabb::new(Vec3A::new(0.0, 0.0, 2.0), Vec3A::new(1.0, 1.0, 2.0)); 30];
    let (bvh, wide) = Bvh::build_pair(&boxes);
    let seen = visited(
        &bvh,
        &wide,
        Portable,
        Vec3A::new(-1.0, 0.5, 2.0),
        Vec3A::X,
        f32::INFINITY,
    );
    assert!(seen.iter().all(|&s| s));
}

#[cfg(target_arch = "x86_64")]
#[test]
fn the_avx2_node_test_gives_the_portable_bits() {
    let Some(avx2) = Avx2::detect() else {
        eprintln!("no AVX2 here: nothing to compare");
        return;
    };
    let boxes = random_boxes(20_000, 3);
    let wide = Bvh::build_pair(&boxes).1;
    let mut met = 0;
    for i in 0..20_000u64 {
        let mut s = Sampler::new(11, i, 0);
        let node = &wide.nodes[(s.next_u64() % wide.nodes.len() as u64) as usize];
        let o = Vec3A::new(s.next_f32(), s.next_f32(), s.next_f32()) * 120.0 - 10.0;
        let mut d =
            Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5).normalize();
        match i % 5 {
            // Axis-parallel (zero components: infinite reciprocals, NaN slabs).
            0 => d = [Vec3A::X, -Vec3A::Y, Vec3A::Z, -Vec3A::Z][(i / 5 % 4) as usize],
            // From a box's corner (a zero numerator).
            1 => {
                let o2 = Vec3A::new(node.bounds[0][0], node.bounds[1][0], node.bounds[2][0]);
                if o2.is_finite() {
                    check_same(avx2, &BoxRay::new(o2, d), node, 50.0, &mut met);
                    continue;
                }
            }
            _ => {}
        }
        let t_max = [f32::INFINITY, 30.0][(i % 2) as usize];
        check_same(avx2, &BoxRay::new(o, d), node, t_max, &mut met);
    }
    assert!(met > 1_000, "only {met} boxes met");
}

#[cfg(target_arch = "x86_64")]
fn check_same(avx2: Avx2, ray: &BoxRay, node: &WideNode, t_max: f32, met: &mut u32) {
    let (t, mask) = avx2.wide_test(ray, node, t_max);
    let (tp, maskp) = Portable.wide_test(ray, node, t_max);
    assert_eq!(mask, maskp, "{ray:?}");
    assert_eq!(t.map(f32::to_bits), tp.map(f32::to_bits), "{ray:?}");
    *met += mask.count_ones();
}
