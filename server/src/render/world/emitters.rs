//! The world's emitters, listed for next-event estimation: emissive
//! spheres and quads, each emissive triangle of a mesh instance, and the
//! environment when it is not black.
//!
//! The list is in (object, triangle) order, the environment last:
//! `Lights::index_of` (and the kernel's `light_index`) find the emitter a
//! BSDF sample hit by binary search on it.

use super::{Geometry, Instance, WorldObject, NO_PRIM};
use crate::render::light::{Emitter, EmitterShape, LightTri, Lights};
use crate::render::material::SurfaceMaterial;
use crate::render::math::Vec3A;

/// The emitters of these objects; `environment` (if not black) as seen
/// from everywhere within `radius` of the origin.
pub(super) fn lights(
    objects: &[WorldObject],
    instances: &[Instance],
    materials: &[SurfaceMaterial],
    environment: Vec3A,
    radius: f64,
) -> Lights {
    let mut emitters = Vec::new();
    for (id, o) in objects.iter().enumerate() {
        let id = id as u32;
        let flat = |shape: EmitterShape| {
            let m = &materials[o.material as usize];
            m.emissive.then_some(Emitter {
                object: id,
                prim: NO_PRIM,
                emission: m.emission,
                shape,
            })
        };
        match o.geometry {
            Geometry::Sphere(s) => emitters.extend(flat(EmitterShape::Sphere(s))),
            Geometry::Quad(q) => emitters.extend(flat(EmitterShape::Quad(q))),
            Geometry::Instance(i) => {
                triangles(id, &instances[i as usize], materials, &mut emitters)
            }
        }
    }
    if environment.max_element() > 0.0 {
        emitters.push(Emitter {
            object: u32::MAX,
            prim: NO_PRIM,
            emission: environment,
            shape: EmitterShape::Environment,
        });
    }
    Lights::new(emitters, radius)
}

/// Every emissive triangle of object `id`, instance `inst`, of non-zero
/// area, in camera-relative space.
fn triangles(id: u32, inst: &Instance, materials: &[SurfaceMaterial], out: &mut Vec<Emitter>) {
    let mesh = &*inst.mesh;
    for (t, &slot) in mesh.materials.iter().enumerate() {
        let m = &materials[inst.materials[slot as usize] as usize];
        if !m.emissive {
            continue;
        }
        let [a, b, c] = mesh
            .vertices(t as u32)
            .map(|v| inst.cam_from_obj.transform_point3a(v));
        let cross = (b - a).cross(c - a);
        let area = 0.5 * cross.length();
        if !(area > 0.0) {
            continue;
        }
        out.push(Emitter {
            object: id,
            prim: t as u32,
            emission: m.emission,
            shape: EmitterShape::Triangle(LightTri {
                p0: a,
                e1: b - a,
                e2: c - a,
                n: cross.normalize(),
                area,
            }),
        });
    }
}
