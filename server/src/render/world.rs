//! The scene as the hot path sees it: f32, relative to a render origin (the
//! camera position), with materials flattened and emitters listed.
//!
//! Working camera-relative is what makes the image independent of where the
//! scene sits in the world: a scene moved 1e6 units from the origin has the
//! same f32 coordinates here as one at the origin (the subtraction is done in
//! f64), so f32 only ever holds numbers of the scene's own size.

use crate::render::isa::Isa;
use crate::render::material::SurfaceMaterial;
use crate::render::math::{DVec3, Vec3A};
use crate::render::ray::Ray;
use crate::render::scene::{Scene, Shape, MAX_OBJECTS};
use crate::render::shape::{Leaving, Quad, Sphere, SphereBatch, SPHERE_BATCH_LANES};

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
    /// The spheres again, several to a batch with their object indices, so
    /// that the nearest hit is found with lane-wise selects, not branches.
    sphere_batches: Vec<SphereBatch>,
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
        let mut quads = Vec::new();
        for (i, o) in objects.iter().enumerate() {
            match o.geometry {
                Geometry::Sphere(s) => spheres.push((i as u32, s)),
                Geometry::Quad(q) => quads.push((i as u32, q)),
            }
        }
        let sphere_batches = spheres.chunks(SPHERE_BATCH_LANES).map(SphereBatch::new).collect();
        Self {
            origin,
            objects,
            sphere_batches,
            quads,
            materials: scene.materials.iter().map(SurfaceMaterial::new).collect(),
            lights: scene.emitters().map(|i| i as u32).collect(),
        }
    }

    /// Nearest hit along `ray`, never the surface the ray starts on; the
    /// spheres are tested with `isa`'s kernel.
    #[inline(always)]
    pub fn intersect<I: Isa>(&self, isa: I, ray: &Ray, from: Origin) -> Option<Hit> {
        let leaving = Leaving {
            id: from.object as f32,
            entering: from.entering,
        };
        let (t, id) = isa.nearest_sphere(&self.sphere_batches, ray, leaving);
        // id + 2^23 has the integer id in its low mantissa bits: no
        // saturating float-to-int conversion on the way to the material.
        const _: () = assert!(MAX_OBJECTS < 1 << 23);
        let object = (id + 8_388_608.0).to_bits() & 0x7F_FFFF;
        let mut best = Hit { t, object };
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
    #[inline(always)]
    pub fn normal(&self, object: u32, p: Vec3A) -> Vec3A {
        match &self.objects[object as usize].geometry {
            Geometry::Sphere(s) => s.normal(p),
            Geometry::Quad(q) => q.normal,
        }
    }

    #[inline(always)]
    pub fn material_of(&self, object: u32) -> &SurfaceMaterial {
        &self.materials[self.objects[object as usize].material as usize]
    }
}
