//! A mesh placed in the world: the map between camera-relative space and
//! the mesh's object space, and what self-intersection needs across it.
//!
//! Rays are mapped into object space (direction not normalised, so that
//! distances along it stay the camera ray's) and meet the mesh's BVH there.
//! A ray leaving a triangle starts from the hit point moved off the plane
//! of the triangle, in object space, by the bound of every rounding between
//! the true intersection and the next ray's origin as the next traversal
//! will see it (pbrt-v4's `OffsetRayOrigin`, after Wächter and Binder 2019):
//! - the hit point from barycentrics, `gamma(7)` of its terms;
//! - the round trip to camera space and back (`cam_from_obj` then
//!   `obj_from_cam`, both f32 matrices that are not exact inverses):
//!   bounded per instance, from the matrices themselves, as
//!   `rt_a * max|p| + rt_b` (see [`round_trip_bound`]).
//!
//! The bound scales with the numbers involved, not with the scene: no
//! epsilon, so meshes stay clean from 1e-3 to 1e3 units and beyond.

use super::{Hit, Surface};
use crate::render::alpha::AlphaTest;
use crate::render::bvh::{BoxRay, MAX_LEAF};
use crate::render::isa::Isa;
use crate::render::math::{gamma, step_toward, Affine3A, DAffine3, DMat3, DVec3, Mat3A, Vec3A};
use crate::render::ray::Ray;
use crate::render::shape::{hit_point, Mesh, TriRay, TriVerts};
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct Instance {
    pub mesh: Arc<Mesh>,
    /// The placement in world space, as the scene gives it (what does not
    /// change with the camera).
    pub world_from_obj: DAffine3,
    pub cam_from_obj: Affine3A,
    pub obj_from_cam: Affine3A,
    /// Maps object-space normals to camera space (inverse transpose).
    pub normal_from_obj: Mat3A,
    /// Round trip bound: |obj_from_cam(cam_from_obj(p)) - p| <= rt_a max|p| + rt_b.
    pub rt_a: f32,
    pub rt_b: f32,
    /// World material of each of the mesh's material slots.
    pub materials: Arc<[u32]>,
    /// `cam_from_obj` is a translation (the mesh's matrix is exactly the
    /// identity): rays keep their direction in object space.
    pub translation_only: bool,
    /// The placement mirrors (its determinant is negative): tangents'
    /// bitangent signs flip with it.
    pub mirrored: bool,
    /// Each slot's alpha test, where some slot's material has one
    /// (`render::alpha`); None: every triangle is opaque.
    pub alpha: Option<Arc<[AlphaTest]>>,
}

/// A camera-space ray prepared once for every mesh placed by a translation
/// alone (a wall, identity matrix): such a mesh keeps the ray's direction,
/// so it reuses the direction's watertight set-up and box reciprocals and
/// only moves the origin.
#[derive(Clone, Copy, Debug)]
pub struct Prepared {
    pub(super) tri: TriRay,
    pub(super) boxes: BoxRay,
}

impl Prepared {
    /// `ray` prepared; `boxes` is `BoxRay::new(ray.origin, ray.dir)`.
    #[inline(always)]
    pub fn new(ray: &Ray, boxes: BoxRay) -> Self {
        Self {
            tri: TriRay::new(ray.origin, ray.dir),
            boxes,
        }
    }
}

/// Where rays leaving a triangle start: in object space, off the plane.
#[derive(Clone, Copy, Debug)]
pub struct Offset {
    pub instance: u32,
    pub p_obj: Vec3A,
    /// Unit geometric normal in object space.
    pub n_obj: Vec3A,
    /// How far along `n_obj` the origin must move.
    pub dist: f32,
}

impl Instance {
    /// `world_from_obj` placed relative to the render origin `origin`.
    pub fn new(
        mesh: Arc<Mesh>,
        world_from_obj: DAffine3,
        origin: DVec3,
        materials: Arc<[u32]>,
    ) -> Self {
        let cam = DAffine3 {
            matrix3: world_from_obj.matrix3,
            translation: world_from_obj.translation - origin,
        };
        let cam_from_obj =
            Affine3A::from_mat3_translation(cam.matrix3.as_mat3(), cam.translation.as_vec3());
        let inv = cam.inverse();
        let obj_from_cam =
            Affine3A::from_mat3_translation(inv.matrix3.as_mat3(), inv.translation.as_vec3());
        let normal_from_obj = Mat3A::from(cam.matrix3.inverse().transpose().as_mat3());
        let (rt_a, rt_b) = round_trip_bound(&cam_from_obj, &obj_from_cam);
        Self {
            mesh,
            world_from_obj,
            cam_from_obj,
            obj_from_cam,
            normal_from_obj,
            rt_a,
            rt_b,
            materials,
            translation_only: cam.matrix3 == DMat3::IDENTITY,
            mirrored: cam.matrix3.determinant() < 0.0,
            alpha: None,
        }
    }

    /// Offers this instance's nearest triangle hit (other than triangle
    /// `skip`) to `best`; `BRUTE` tests every triangle instead of the BVH.
    #[inline(always)]
    pub(super) fn offer<const BRUTE: bool, I: Isa>(
        &self,
        isa: I,
        id: u32,
        (ray, pre): (&Ray, Option<&Prepared>),
        skip: u32,
        best: &mut Hit,
    ) {
        let (tri_ray, box_ray) = self.prepare(ray, pre);
        let mesh = &*self.mesh;
        if BRUTE {
            self.offer_tris(id, (&tri_ray, ray), &mesh.tris, skip, best);
            return;
        }
        let mut walk = mesh.wide.walk(box_ray, isa);
        while let Some((first, _)) = walk.next_leaf(best.t) {
            self.offer_leaf(id, (&tri_ray, ray), first, skip, best);
        }
    }

    /// `ray` in object space, prepared for the triangle and box tests.
    /// `pre` is `ray` prepared in camera space (there whenever some
    /// instance is only translated): a mesh moved but not turned or scaled
    /// (a wall, identity matrix) reuses its direction.
    #[inline(always)]
    pub(super) fn prepare(&self, ray: &Ray, pre: Option<&Prepared>) -> (TriRay, BoxRay) {
        if let (true, Some(pre)) = (self.translation_only, pre) {
            let o = ray.origin + self.obj_from_cam.translation;
            (pre.tri.from_origin(o), pre.boxes.from_origin(o))
        } else {
            let o = self.obj_from_cam.transform_point3a(ray.origin);
            let d = self.obj_from_cam.transform_vector3a(ray.dir);
            (TriRay::new(o, d), BoxRay::new(o, d))
        }
    }

    /// Whether `ray` stops at triangle `index`, met at `bary` (its slot's
    /// alpha test, if it has one).
    #[inline(always)]
    fn stops(&self, ray: &Ray, index: u32, bary: [f32; 3]) -> bool {
        match &self.alpha {
            None => true,
            Some(tests) => tests[self.mesh.materials[index as usize] as usize]
                .passes(&self.mesh, index, bary, ray.origin, ray.dir),
        }
    }

    /// Offers each of `tris` that `tri_ray` (`ray` in object space) meets,
    /// one scalar test each.
    #[inline(always)]
    fn offer_tris(
        &self,
        id: u32,
        (tri_ray, ray): (&TriRay, &Ray),
        tris: &[TriVerts],
        skip: u32,
        best: &mut Hit,
    ) {
        for tri in tris {
            let index = tri.index();
            if index == skip {
                continue;
            }
            if let Some((t, bary)) = tri_ray.intersect(tri.vertices(), best.t) {
                if self.stops(ray, index, bary) {
                    best.offer(t, id, index, bary);
                }
            }
        }
    }

    /// Offers the triangles of the leaf at slot `first` that `tri_ray`
    /// meets: four at a time, in slot order as [`Instance::offer_tris`]
    /// offers them (see `shape::tri_pack`).
    #[inline(always)]
    pub(super) fn offer_leaf(
        &self,
        id: u32,
        (tri_ray, ray): (&TriRay, &Ray),
        first: u32,
        skip: u32,
        best: &mut Hit,
    ) {
        let mesh = &*self.mesh;
        let pack = &mesh.packs[first as usize / MAX_LEAF];
        let found = tri_ray.intersect4(pack, best.t);
        let mut lanes = (found.hits | found.scalar) & pack.lanes();
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let index = pack.index[lane];
            if index == skip {
                continue;
            }
            if found.scalar & (1 << lane) != 0 {
                let tri = std::slice::from_ref(&mesh.tris[first as usize + lane]);
                self.offer_tris(id, (tri_ray, ray), tri, skip, best);
            } else if found.t[lane] <= best.t && self.stops(ray, index, found.bary(lane)) {
                best.offer(found.t[lane], id, index, found.bary(lane));
            }
        }
    }

    /// The surface at `hit` on this instance (number `index`).
    #[inline(always)]
    pub(super) fn surface(&self, hit: &Hit, index: u32) -> Surface {
        let mesh = &*self.mesh;
        let v = mesh.vertices(hit.prim);
        let (p_obj, err) = hit_point(v, hit.bary);
        let n_obj = mesh.face_normal(hit.prim);
        let ng = (self.normal_from_obj * n_obj).normalize_or_zero();
        let (ns, smooth) = match mesh.shading_normal(hit.prim, hit.bary) {
            Some(n) => match (self.normal_from_obj * n).try_normalize() {
                Some(ns) => (ns, true),
                None => (ng, false),
            },
            None => (ng, false),
        };
        let err = err + Vec3A::splat(self.rt_a * p_obj.abs().max_element() + self.rt_b);
        Surface {
            p: self.cam_from_obj.transform_point3a(p_obj),
            ng,
            ns,
            nc: Vec3A::ZERO,
            smooth,
            material: self.materials[mesh.materials[hit.prim as usize] as usize],
            object: hit.object,
            prim: hit.prim,
            offset: Some(Offset {
                instance: index,
                p_obj,
                n_obj,
                dist: n_obj.abs().dot(err),
            }),
        }
    }

    /// The origin (camera space) of a ray leaving `off` along `dir`: the
    /// object-space hit point moved `off.dist` off the plane to the side
    /// `dir` goes, each coordinate rounded away from the plane.
    #[inline(always)]
    pub(super) fn spawn_origin(&self, off: &Offset, ng: Vec3A, dir: Vec3A) -> Vec3A {
        // dist where dir.dot(ng) > 0, else -dist: the sign bit flipped
        // without a branch (which side a ray leaves is as good as random).
        let flip = u32::from(!(dir.dot(ng) > 0.0)) << 31;
        let shift = off.n_obj * f32::from_bits(off.dist.to_bits() ^ flip);
        let p = step_toward(off.p_obj + shift, shift);
        self.cam_from_obj.transform_point3a(p)
    }

    /// Number of triangles (for limits and statistics).
    pub fn triangles(&self) -> usize {
        self.mesh.triangles.len()
    }
}

/// Bounds `a`, `b` with |inv(fwd(p)) - p|_inf <= a |p|_inf + b for every p,
/// where `fwd` and `inv` are evaluated in f32 (three products and three
/// sums per coordinate: gamma(3) each, as pbrt bounds a transform).
///
/// With fwd = [A | t], inv = [B | s]: fl(fwd(p)) = A p + t + e1 with
/// |e1| <= g (|A||p| + |t|); then fl(inv(q)) = B q + s + e2 with
/// |e2| <= g (|B||q| + |s|); and B (A p + t) + s = p + (BA - I) p + (B t + s).
/// So the total is at most
///   (|BA - I| + 2 g |B||A|) |p| + |B t + s| + 2 g |B||t| + g |s|
/// to first order in g; the result is doubled for the second-order terms
/// and the f32 evaluation of `a |p| + b` itself.
fn round_trip_bound(fwd: &Affine3A, inv: &Affine3A) -> (f32, f32) {
    let m = |x: &Affine3A| {
        DMat3::from_cols(
            x.matrix3.x_axis.as_dvec3(),
            x.matrix3.y_axis.as_dvec3(),
            x.matrix3.z_axis.as_dvec3(),
        )
    };
    let (a, b) = (m(fwd), m(inv));
    let (t, s) = (fwd.translation.as_dvec3(), inv.translation.as_dvec3());
    // Infinity norm: the largest row sum of magnitudes.
    let norm = |x: DMat3| {
        let r = x.transpose();
        [r.x_axis, r.y_axis, r.z_axis]
            .iter()
            .map(|row| row.abs().element_sum())
            .fold(0.0, f64::max)
    };
    let g = f64::from(gamma(3));
    let (na, nb) = (norm(a), norm(b));
    let drift = norm(b * a - DMat3::IDENTITY);
    let rt_a = drift + 2.0 * g * nb * na;
    let rt_b = (b * t + s).abs().max_element()
        + 2.0 * g * nb * t.abs().max_element()
        + g * s.abs().max_element();
    ((2.0 * rt_a) as f32, (2.0 * rt_b) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::math::DVec3;
    use crate::render::sampler::Sampler;

    #[test]
    fn round_trip_stays_within_its_bound() {
        // Rotated, unevenly scaled, far from the camera.
        let world = DAffine3::from_scale_rotation_translation(
            DVec3::new(1e-3, 2.5e-3, 7e-4),
            glam::DQuat::from_axis_angle(DVec3::new(0.3, -0.8, 0.5).normalize(), 1.1),
            DVec3::new(1234.5, -77.25, 3e3),
        );
        let cam = DVec3::new(1200.0, -70.0, 2980.0);
        let cam_from = DAffine3 {
            matrix3: world.matrix3,
            translation: world.translation - cam,
        };
        let fwd = Affine3A::from_mat3_translation(
            cam_from.matrix3.as_mat3(),
            cam_from.translation.as_vec3(),
        );
        let inv_d = cam_from.inverse();
        let inv =
            Affine3A::from_mat3_translation(inv_d.matrix3.as_mat3(), inv_d.translation.as_vec3());
        let (a, b) = round_trip_bound(&fwd, &inv);
        let mut worst = 0.0f32;
        for i in 0..100_000u64 {
            let mut s = Sampler::new(1, i, 0);
            let p = Vec3A::new(s.next_f32() - 0.5, s.next_f32() - 0.5, s.next_f32() - 0.5) * 2000.0;
            let back = inv.transform_point3a(fwd.transform_point3a(p));
            let e = (back - p).abs().max_element();
            let bound = a * p.abs().max_element() + b;
            assert!(e <= bound, "round trip {e} beyond bound {bound} at {p:?}");
            worst = worst.max(e / bound);
        }
        // The bound is not absurdly loose either.
        assert!(worst > 1e-3, "worst error / bound {worst}");
    }
}
