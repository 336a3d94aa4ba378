//! A BVH leaf's triangles (at most four) in structure-of-arrays form, so
//! that the CPU tests one ray against all of them in one SIMD pass, as
//! Embree's leaves do; incoherent (bounce) rays visit many leaves, where
//! four scalar tests one after another cost the most.
//!
//! Each lane computes exactly what [`TriRay::intersect`] computes for its
//! triangle, in the same order of operations (the shear's dot products sum
//! x, then y, then z, as glam's do; no fused multiply-adds), so the packed
//! test gives the same bits: the same watertightness, the same hits. A lane
//! whose edge function comes out zero goes to the scalar test, which redoes
//! it in f64. The leaf's triangles are then offered in slot order with the
//! scalar loop's rule (a hit counts if it is no farther than the best so
//! far, and [`crate::render::world::Hit`] keeps the lower (object, prim) of
//! two at the same distance), so the nearest hit is the one the scalar loop
//! finds, ties included, whatever order the leaves are visited in.
//!
//! The OpenCL kernel keeps reading the leaf-ordered [`TriVerts`]; packs are
//! the CPU's own copy (160 bytes per leaf), with the triangles' indices, so
//! that a hit is offered without loading its [`TriVerts`] too.

use super::triangle::{TriRay, TriVerts};
use crate::render::bvh::Aabb;
use crate::render::math::{Vec3A, Vec4};

/// Up to four triangles; lanes past the leaf's count repeat its last one
/// (a valid triangle: no spurious zero edge functions) and are ignored.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriPack {
    /// x, y, z of vertex 0, of vertex 1, of vertex 2: one row per
    /// coordinate, one lane per triangle.
    p: [[f32; 4]; 9],
    /// Each lane's triangle index in its mesh; [`NO_LANE`] past the
    /// leaf's count.
    pub index: [u32; 4],
}

/// `TriPack::index` of a lane that holds none of the leaf's triangles (no
/// mesh has that many: it is the world's `NO_PRIM`).
pub const NO_LANE: u32 = u32::MAX;

const _: () = assert!(std::mem::size_of::<TriPack>() == 160);

/// What a packed test found, per lane.
#[derive(Clone, Copy, Debug)]
pub struct PackHits {
    pub t: [f32; 4],
    u: [f32; 4],
    v: [f32; 4],
    w: [f32; 4],
    det: [f32; 4],
    /// Lanes hit after 0 and not beyond `t_max` (bit i: lane i).
    pub hits: u32,
    /// Lanes the scalar test must decide (an edge function was zero).
    pub scalar: u32,
}

impl PackHits {
    /// Barycentric weights of lane `i`'s hit, as the scalar test gives them.
    #[inline(always)]
    pub fn bary(&self, i: usize) -> [f32; 3] {
        let inv = 1.0 / self.det[i];
        [self.u[i] * inv, self.v[i] * inv, self.w[i] * inv]
    }
}

impl TriPack {
    /// The pack of the leaf holding `tris[first .. first + count]`.
    pub fn new(tris: &[TriVerts], first: u32, count: u32) -> Self {
        debug_assert!((1..=4).contains(&count));
        let mut p = [[0.0; 4]; 9];
        let mut index = [NO_LANE; 4];
        for lane in 0..4 {
            let t = &tris[(first + lane.min(count - 1)) as usize];
            if lane < count {
                index[lane as usize] = t.index();
            }
            for (v, vertex) in [&t.v0, &t.v1, &t.v2].into_iter().enumerate() {
                for c in 0..3 {
                    p[3 * v + c][lane as usize] = vertex[c];
                }
            }
        }
        Self { p, index }
    }

    /// The box around the leaf's triangles (the lanes past its count
    /// repeat its last triangle).
    #[inline(always)]
    pub fn bounds(&self) -> Aabb {
        let p = &self.p;
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for c in 0..3 {
            let (a, b, d) = (
                Vec4::from_array(p[c]),
                Vec4::from_array(p[3 + c]),
                Vec4::from_array(p[6 + c]),
            );
            lo[c] = a.min(b).min(d).min_element();
            hi[c] = a.max(b).max(d).max_element();
        }
        Aabb {
            min: Vec3A::from(lo),
            max: Vec3A::from(hi),
        }
    }

    /// Lanes that hold the leaf's triangles.
    #[inline(always)]
    pub fn lanes(&self) -> u32 {
        let mut lanes = 0;
        for (lane, &i) in self.index.iter().enumerate() {
            lanes |= u32::from(i != NO_LANE) << lane;
        }
        lanes
    }
}

impl TriRay {
    /// [`TriRay::intersect`] for the pack's four triangles at once.
    #[inline(always)]
    pub fn intersect4(&self, pack: &TriPack, t_max: f32) -> PackHits {
        // Plain functions, no closures: in the render loop's large function
        // the compiler may leave a closure out of line, without its AVX2.
        let o = self.origin;
        let (a, b, c) = (rel(pack, 0, o), rel(pack, 1, o), rel(pack, 2, o));
        let (ax, ay) = (dot(self.row_x, a), dot(self.row_y, a));
        let (bx, by) = (dot(self.row_x, b), dot(self.row_y, b));
        let (cx, cy) = (dot(self.row_x, c), dot(self.row_y, c));
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let scalar = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).bitmask();
        let negative = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let positive = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        let det = u + v + w;
        let t_scaled = u * dot(self.row_z, a) + v * dot(self.row_z, b) + w * dot(self.row_z, c);
        let t = t_scaled / det;
        let inside = !(negative & positive).bitmask() & 0xf;
        let hits = inside
            & det.cmpne(zero).bitmask()
            & t.cmpgt(zero).bitmask()
            & t.cmple(Vec4::splat(t_max)).bitmask()
            & !scalar;
        PackHits {
            t: t.to_array(),
            u: u.to_array(),
            v: v.to_array(),
            w: w.to_array(),
            det: det.to_array(),
            hits,
            scalar,
        }
    }
}

/// Vertex `v` of the pack's four triangles, relative to `o`.
#[inline(always)]
fn rel(pack: &TriPack, v: usize, o: Vec3A) -> (Vec4, Vec4, Vec4) {
    let p = &pack.p;
    (
        Vec4::from_array(p[3 * v]) - Vec4::splat(o.x),
        Vec4::from_array(p[3 * v + 1]) - Vec4::splat(o.y),
        Vec4::from_array(p[3 * v + 2]) - Vec4::splat(o.z),
    )
}

/// `r` dotted with each lane's (x, y, z).
#[inline(always)]
fn dot(r: Vec3A, (x, y, z): (Vec4, Vec4, Vec4)) -> Vec4 {
    Vec4::splat(r.x) * x + Vec4::splat(r.y) * y + Vec4::splat(r.z) * z
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Sampler;

    /// Random triangles (some tiny, some sharing edges) and rays: every
    /// lane's answer is the scalar test's, bit for bit.
    #[test]
    fn a_pack_answers_as_four_scalar_tests() {
        let mut rng = Sampler::new(5, 0, 0);
        let mut f = || rng.next_f32() * 2.0 - 1.0;
        let (mut hit, mut missed) = (0, 0);
        for case in 0..20_000u32 {
            let scale = [1e-3f32, 1.0, 1e3][(case % 3) as usize];
            let mut v = || Vec3A::new(f(), f(), f()) * scale;
            let (a, b, c, d) = (v(), v(), v(), v());
            // Lanes 0 and 1 share the edge b-c.
            let tris = [
                TriVerts::new(0, [a, b, c].map(Into::into)),
                TriVerts::new(1, [c, b, d].map(Into::into)),
                TriVerts::new(2, [a, d, b].map(Into::into)),
                TriVerts::new(3, [a * 1e-4, b * 1e-4, c * 1e-4].map(Into::into)),
            ];
            let count = 1 + case % 4;
            let pack = TriPack::new(&tris, 0, count);
            assert_eq!(pack.lanes(), (1 << count) - 1, "case {case}");
            for (lane, tri) in tris.iter().enumerate().take(count as usize) {
                assert_eq!(pack.index[lane], tri.index(), "case {case}, lane {lane}");
            }
            let origin = Vec3A::new(f(), f(), f()) * scale * 3.0;
            // Aim at a point of triangle 0's edge b-c every other time.
            let dir = match case % 2 {
                0 => (b + (c - b) * 0.5 * (1.0 + f()) - origin).normalize_or_zero(),
                _ => Vec3A::new(f(), f(), f()).normalize_or_zero(),
            };
            if dir == Vec3A::ZERO {
                continue;
            }
            let ray = TriRay::new(origin, dir);
            let t_max = [f32::INFINITY, scale * 2.0][(case % 5 == 0) as usize];
            let hits = ray.intersect4(&pack, t_max);
            for (lane, tri) in tris.iter().enumerate().take(count as usize) {
                let want = ray.intersect(tri.vertices(), t_max);
                if hits.scalar & (1 << lane) != 0 {
                    continue; // the scalar test decides this lane
                }
                let got = (hits.hits & (1 << lane) != 0).then(|| (hits.t[lane], hits.bary(lane)));
                assert_eq!(got, want, "case {case}, lane {lane}");
                if got.is_some() {
                    hit += 1;
                } else {
                    missed += 1;
                }
            }
        }
        // Both answers are well represented (half the rays aim at an edge).
        assert!(hit > 5_000 && missed > 5_000, "{hit} hits, {missed} misses");
    }
}
