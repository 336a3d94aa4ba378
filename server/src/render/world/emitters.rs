//! The world's emitters, listed for next-event estimation: emissive
//! spheres and quads, each emissive triangle of a mesh instance, and the
//! environment when it is not black.
//!
//! The list is in (object, triangle) order, a computed sky's sun (object
//! `NO_OBJECT`, prim [`SUN_PRIM`]) and the environment last:
//! `Lights::index_of` (and the kernel's `light_index`) find the emitter a
//! BSDF sample hit by binary search on it.

use super::{Geometry, Instance, WorldObject, NO_OBJECT, NO_PRIM};
use crate::render::light::{Emitter, EmitterShape, EnvLight, LightTri, Lights, SunLight};
use crate::render::maps::{WorldMaps, NO_TEXTURE};
use crate::render::material::{SurfaceMaterial, NO_MAPS};
use crate::render::math::Vec3A;
use crate::render::texture::{Map, Texture};
use std::sync::Arc;

/// The scene's materials with their maps and textures.
pub(super) struct Materials<'a> {
    pub list: &'a [SurfaceMaterial],
    pub maps: &'a [WorldMaps],
    pub textures: &'a [Arc<Texture>],
}

impl Materials<'_> {
    /// An emitter of material `m`: its maps where it has an emission map,
    /// and that map's mean colour.
    fn emission_map(&self, m: &SurfaceMaterial) -> (u32, Vec3A) {
        let Some(maps) = self.maps.get(m.maps as usize) else {
            return (NO_MAPS, Vec3A::ONE);
        };
        match maps.slot(Map::Emission).texture {
            NO_TEXTURE => (NO_MAPS, Vec3A::ONE),
            t => (m.maps, Vec3A::from(self.textures[t as usize].mean_srgb)),
        }
    }
}

/// The sun's place in the emitter list: after every object's, before
/// the environment's (`NO_OBJECT`, `NO_PRIM`).
pub const SUN_PRIM: u32 = NO_PRIM - 1;

/// What lights the scene from outside.
pub(super) enum Sky {
    Uniform(Vec3A),
    Map(Arc<EnvLight>),
}

/// The emitters of these objects; the sun (radiance and disc) and the
/// sky (if not black) as seen from everywhere within `radius` of the origin.
pub(super) fn lights(
    objects: &[WorldObject],
    instances: &[Instance],
    materials: &Materials<'_>,
    (sun, sky): (Option<(SunLight, Vec3A)>, Sky),
    radius: f64,
) -> Lights {
    let mut emitters = Vec::new();
    for (id, o) in objects.iter().enumerate() {
        let id = id as u32;
        let flat = |shape: EmitterShape| {
            let m = &materials.list[o.material as usize];
            let (maps, mean) = materials.emission_map(m);
            m.emissive.then_some(Emitter {
                object: id,
                prim: NO_PRIM,
                emission: m.emission,
                shape,
                maps,
                mean,
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
    let sky = match sky {
        Sky::Uniform(e) if e.max_element() > 0.0 => Some((e, EmitterShape::Environment)),
        Sky::Uniform(_) => None,
        Sky::Map(m) => (m.mean_brightness() > 0.0).then_some((Vec3A::ZERO, EmitterShape::Map(m))),
    };
    if let Some((sun, emission)) = sun.filter(|(_, e)| e.max_element() > 0.0) {
        emitters.push(Emitter {
            object: NO_OBJECT,
            prim: SUN_PRIM,
            emission,
            shape: EmitterShape::Sun(sun),
            maps: NO_MAPS,
            mean: Vec3A::ONE,
        });
    }
    if let Some((emission, shape)) = sky {
        emitters.push(Emitter {
            object: NO_OBJECT,
            prim: NO_PRIM,
            emission,
            shape,
            maps: NO_MAPS,
            mean: Vec3A::ONE,
        });
    }
    Lights::new(emitters, radius)
}

/// Every emissive triangle of object `id`, instance `inst`, of non-zero
/// area, in camera-relative space.
fn triangles(id: u32, inst: &Instance, materials: &Materials<'_>, out: &mut Vec<Emitter>) {
    let mesh = &*inst.mesh;
    for (t, &slot) in mesh.materials.iter().enumerate() {
        let m = &materials.list[inst.materials[slot as usize] as usize];
        if !m.emissive {
            continue;
        }
        let (maps, mean) = materials.emission_map(m);
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
            maps,
            mean,
        });
    }
}
