//! Spheres tested against one ray several at once: eight to a batch, stored
//! structure-of-arrays. The portable test here takes four lanes at a time
//! (SSE2 through glam); `sphere_batch_avx2` takes all eight. Both do the same
//! arithmetic as `Sphere::intersect` with `Roots::Any`, lane by lane, in the
//! same order and without fused multiply-adds, so they agree bit for bit: an
//! image does not depend on which one the CPU ran.
//!
//! The nearest hit is found without branches: lane-wise selects keep each
//! lane's nearest distance and object, then the minimum distance wins, and
//! among lanes at exactly that distance the lowest object index.

use crate::render::math::{BVec4A, Vec4};
use crate::render::ray::Ray;
use crate::render::shape::Sphere;

/// Lanes per batch.
pub const LANES: usize = 8;

/// Up to eight spheres; missing lanes never hit.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub struct SphereBatch {
    pub cx: [f32; LANES],
    pub cy: [f32; LANES],
    pub cz: [f32; LANES],
    /// `Sphere::k`; +inf in empty lanes (the discriminant is then negative).
    pub k: [f32; LANES],
    /// Object index of each lane as f32 (exact below 2^24); -1 when empty.
    pub ids: [f32; LANES],
    /// Whether lanes 4..8 hold any sphere (the portable test skips them if not).
    pub upper: bool,
}

/// The ray's start, as the nearest-hit search needs it: the object it
/// leaves (as f32, see `SphereBatch::ids`) and whether it goes into it.
#[derive(Clone, Copy, Debug)]
pub struct Leaving {
    pub id: f32,
    pub entering: bool,
}

impl SphereBatch {
    /// Up to eight spheres with their object indices.
    pub fn new(spheres: &[(u32, Sphere)]) -> Self {
        let get = |f: &dyn Fn(&(u32, Sphere)) -> f32, empty: f32| -> [f32; LANES] {
            std::array::from_fn(|i| spheres.get(i).map_or(empty, f))
        };
        Self {
            cx: get(&|(_, s)| s.center.x, 0.0),
            cy: get(&|(_, s)| s.center.y, 0.0),
            cz: get(&|(_, s)| s.center.z, 0.0),
            k: get(&|(_, s)| s.k, f32::INFINITY),
            ids: get(&|&(id, _)| id as f32, -1.0),
            upper: spheres.len() > 4,
        }
    }

    /// Nearest sphere hit over `batches`, four lanes at a time: (distance,
    /// object index as f32), distance infinity when there is none.
    #[inline(always)]
    pub fn nearest(batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32) {
        let inf = Vec4::splat(f32::INFINITY);
        let from_id = Vec4::splat(from.id);
        let entering = if from.entering {
            BVec4A::TRUE
        } else {
            BVec4A::FALSE
        };
        let (mut best_t, mut best_id) = (inf, Vec4::splat(-1.0));
        let mut visit = |b: &SphereBatch, lo: usize| {
            let lanes = |a: &[f32; LANES]| Vec4::from_slice(&a[lo..lo + 4]);
            let ids = lanes(&b.ids);
            // The sphere the ray starts on: only its far side, and only when
            // the ray goes into it.
            let own = ids.cmpeq(from_id);
            let t = intersect4(
                [lanes(&b.cx), lanes(&b.cy), lanes(&b.cz), lanes(&b.k)],
                ray,
                own,
            );
            let t = Vec4::select(own & !entering, inf, t);
            let closer = t.cmplt(best_t);
            best_t = Vec4::select(closer, t, best_t);
            best_id = Vec4::select(closer, ids, best_id);
        };
        for b in batches {
            visit(b, 0);
            if b.upper {
                visit(b, 4);
            }
        }
        let m = best_t.min_element();
        let id = Vec4::select(best_t.cmpeq(Vec4::splat(m)), best_id, inf).min_element();
        (m, id)
    }
}

/// Distance to each of four spheres' nearest intersection in front of the
/// ray origin, infinity where there is none; lanes set in `far_only` report
/// only the far intersection (`Roots::FarOnly`). `[cx, cy, cz, k]` as in
/// [`SphereBatch`].
#[inline(always)]
fn intersect4([cx, cy, cz, k]: [Vec4; 4], ray: &Ray, far_only: BVec4A) -> Vec4 {
    let (dx, dy, dz) = (
        Vec4::splat(ray.dir.x),
        Vec4::splat(ray.dir.y),
        Vec4::splat(ray.dir.z),
    );
    let (ox, oy, oz) = (
        Vec4::splat(ray.origin.x),
        Vec4::splat(ray.origin.y),
        Vec4::splat(ray.origin.z),
    );
    let dc = dx * cx + dy * cy + dz * cz;
    let oc = ox * cx + oy * cy + oz * cz;
    let b = Vec4::splat(ray.od) - dc;
    let c = (Vec4::splat(ray.oo) + k) - oc * 2.0;
    let disc = b * b - c;
    let s = disc.max(Vec4::ZERO).sqrt();
    // q = -(b + sign(b) s): the root pair q, c/q without cancellation.
    let q = -(b + s.copysign(b));
    let other = c / q;
    let t0 = q.min(other);
    let t1 = q.max(other);
    let t = Vec4::select(t0.cmpgt(Vec4::ZERO) & !far_only, t0, t1);
    Vec4::select(
        t.cmpgt(Vec4::ZERO) & disc.cmpge(Vec4::ZERO),
        t,
        Vec4::splat(f32::INFINITY),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::render::math::{DVec3, Vec3A};
    use crate::render::sampler::Sampler;
    use crate::render::shape::Roots;

    /// Nine spheres (two batches, the second with one lane) and random rays.
    pub(crate) fn cases() -> (Vec<(u32, Sphere)>, Vec<Ray>) {
        let mut spheres = vec![
            Sphere::new(DVec3::new(0.0, 0.0, -5.0), 1.0),
            Sphere::new(DVec3::new(1e5 + 1.0, 0.0, 0.0), 1e5),
            Sphere::new(DVec3::new(0.5, 0.2, 0.1), 3.0),
        ];
        for i in 0..6 {
            let c = DVec3::new(f64::from(i) - 2.5, (f64::from(i) * 1.7).sin() * 2.0, 1.5);
            spheres.push(Sphere::new(c, 0.4 + 0.1 * f64::from(i)));
        }
        let rays = (0..10_000u64)
            .map(|i| {
                let mut s = Sampler::new(1, i, 0);
                let o =
                    Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 4.0;
                let d = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5)
                    .normalize();
                Ray::new(o, d)
            })
            .collect();
        (
            spheres
                .into_iter()
                .enumerate()
                .map(|(i, s)| (i as u32 * 2 + 1, s))
                .collect(),
            rays,
        )
    }

    pub(crate) fn batches(spheres: &[(u32, Sphere)]) -> Vec<SphereBatch> {
        spheres.chunks(LANES).map(SphereBatch::new).collect()
    }

    /// The nearest hit by the scalar test, ties to the lowest index.
    fn scalar_nearest(spheres: &[(u32, Sphere)], ray: &Ray, from: Leaving) -> (f32, Option<u32>) {
        let mut best = (f32::INFINITY, None);
        for &(id, ref s) in spheres {
            let t = match (id as f32 == from.id, from.entering) {
                (false, _) => s.intersect(ray, Roots::Any),
                (true, true) => s.intersect(ray, Roots::FarOnly),
                (true, false) => f32::INFINITY,
            };
            if t < best.0 {
                best = (t, Some(id));
            }
        }
        best
    }

    #[test]
    fn agrees_with_the_scalar_test() {
        let (spheres, rays) = cases();
        let batches = batches(&spheres);
        let mut hits = 0;
        for (i, ray) in rays.iter().enumerate() {
            let own = spheres[i % spheres.len()].0 as f32;
            for from in [
                Leaving {
                    id: -2.0,
                    entering: false,
                },
                Leaving {
                    id: own,
                    entering: true,
                },
                Leaving {
                    id: own,
                    entering: false,
                },
            ] {
                let (t, id) = SphereBatch::nearest(&batches, ray, from);
                let (scalar, scalar_id) = scalar_nearest(&spheres, ray, from);
                let close = t == scalar || (t - scalar).abs() <= 1e-5 * scalar.abs();
                assert!(close, "ray {i} {from:?}: {t} vs {scalar}");
                if let Some(sid) = scalar_id {
                    assert_eq!(id, sid as f32, "ray {i} {from:?}");
                    hits += 1;
                }
            }
        }
        assert!(hits > 10_000, "too few hits to tell: {hits}");
    }
}
