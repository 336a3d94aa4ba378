//! The scene as the hot path sees it: f32, relative to a render origin (the
//! camera position), with materials flattened and emitters listed.
//!
//! Working camera-relative is what makes the image independent of where the
//! scene sits in the world: a scene moved 1e6 units from the origin has the
//! same f32 coordinates here as one at the origin (the subtraction is done in
//! f64), so f32 only ever holds numbers of the scene's own size.

use crate::render::material::SurfaceMaterial;
use crate::render::math::{BVec4A, DVec3, Vec3A, Vec4};
use crate::render::ray::Ray;
use crate::render::scene::{Scene, Shape};
use crate::render::shape::{Quad, Sphere, SphereBatch};

/// An object's geometry; a closed set matched in one place (here).
#[derive(Clone, Copy, Debug)]
pub enum Geometry {
    Sphere(Sphere),
    Quad(Quad),
}

#[derive(Clone, Copy, Debug)]
pub struct WorldObject {
    pub geometry: Geometry,
    pub material: u32,
}

/// The object a ray starts on, so that it cannot hit itself again: a ray
/// leaving a quad or leaving a sphere outwards never meets that surface
/// again; a ray going into a sphere meets only its far side. No epsilon.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Origin {
    pub object: u32,
    pub entering: bool,
}

impl Origin {
    /// A ray that starts on no surface (camera rays).
    pub const NONE: Origin = Origin {
        object: u32::MAX,
        entering: false,
    };
}

/// The nearest intersection.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    pub object: u32,
}

#[derive(Clone, Debug)]
pub struct World {
    /// World-space position that is (0, 0, 0) here.
    pub origin: DVec3,
    pub objects: Vec<WorldObject>,
    pub materials: Vec<SurfaceMaterial>,
    /// Indices of emissive objects, in scene order.
    pub lights: Vec<u32>,
    /// The spheres again, four to a batch, and the object index of each
    /// lane as f32 (exact below 2^24; -1 for empty lanes), so that the
    /// nearest hit is found with lane-wise selects instead of branches.
    sphere_batches: Vec<SphereBatch>,
    sphere_ids: Vec<Vec4>,
    /// The quads again with their object indices.
    quads: Vec<(u32, Quad)>,
}

impl World {
    /// The scene relative to `origin` (normally the camera position).
    pub fn new(scene: &Scene, origin: DVec3) -> Self {
        let objects = scene
            .objects
            .iter()
            .map(|o| WorldObject {
                geometry: match o.shape {
                    Shape::Sphere { center, radius } => {
                        Geometry::Sphere(Sphere::new(center - origin, radius))
                    }
                    Shape::Quad {
                        corner,
                        edge_u,
                        edge_v,
                    } => Geometry::Quad(Quad::new(corner - origin, edge_u, edge_v)),
                },
                material: o.material as u32,
            })
            .collect::<Vec<_>>();
        let mut spheres = Vec::new();
        let mut sphere_ids = Vec::new();
        let mut quads = Vec::new();
        for (i, o) in objects.iter().enumerate() {
            match o.geometry {
                Geometry::Sphere(s) => {
                    spheres.push(s);
                    sphere_ids.push(i as u32);
                }
                Geometry::Quad(q) => quads.push((i as u32, q)),
            }
        }
        let sphere_batches = spheres.chunks(4).map(SphereBatch::new).collect();
        let sphere_ids = sphere_ids
            .chunks(4)
            .map(|ids| Vec4::from_array(std::array::from_fn(|i| ids.get(i).map_or(-1.0, |&id| id as f32))))
            .collect();
        Self {
            origin,
            objects,
            sphere_batches,
            sphere_ids,
            quads,
            materials: scene.materials.iter().map(SurfaceMaterial::new).collect(),
            lights: scene.emitters().map(|i| i as u32).collect(),
        }
    }

    /// Nearest hit along `ray`, never the surface the ray starts on.
    #[inline]
    pub fn intersect(&self, ray: &Ray, from: Origin) -> Option<Hit> {
        let inf = Vec4::splat(f32::INFINITY);
        let from_id = Vec4::splat(from.object as f32);
        let (mut best_t, mut best_id) = (inf, Vec4::splat(-1.0));
        let entering = if from.entering { BVec4A::TRUE } else { BVec4A::FALSE };
        for (batch, &ids) in self.sphere_batches.iter().zip(&self.sphere_ids) {
            // The sphere the ray starts on: only its far side, and only when
            // the ray goes into it.
            let own = ids.cmpeq(from_id);
            let t = batch.intersect(ray, own);
            let t = Vec4::select(own & !entering, inf, t);
            let closer = t.cmplt(best_t);
            best_t = Vec4::select(closer, t, best_t);
            best_id = Vec4::select(closer, ids, best_id);
        }
        // Nearest lane without branches: the minimum, then its first lane.
        let m = best_t.min_element();
        let lane = best_t.cmpeq(Vec4::splat(m)).bitmask().trailing_zeros() as usize & 3;
        let mut best = Hit {
            t: m,
            object: best_id.to_array()[lane] as u32,
        };
        for &(id, ref quad) in &self.quads {
            if id == from.object {
                continue;
            }
            let t = quad.intersect(ray);
            if t < best.t {
                best = Hit { t, object: id };
            }
        }
        (best.t < f32::INFINITY).then_some(best)
    }

    /// Outward (spheres) or plane (quads) unit normal at `p` on `object`.
    #[inline]
    pub fn normal(&self, object: u32, p: Vec3A) -> Vec3A {
        match &self.objects[object as usize].geometry {
            Geometry::Sphere(s) => s.normal(p),
            Geometry::Quad(q) => q.normal,
        }
    }

    #[inline]
    pub fn material_of(&self, object: u32) -> &SurfaceMaterial {
        &self.materials[self.objects[object as usize].material as usize]
    }
}
