//! The world's placed triangles laid out flat for the wide loop
//! (`backend::cpu::wide_loop`), which computes sixteen surfaces at
//! once: each triangle's vertices as the Embree scene holds them (in its
//! frame, the same floats Embree tests), its geometric and shading
//! normals and its material, one record a triangle, so that a lane's
//! surface is a gather from one place rather than a walk through object,
//! instance, mesh and index buffers.
//!
//! Only for the worlds that loop serves ([`Flat::build`] says why not
//! otherwise): every mesh one of the Embree scene's own (no instance of a
//! mesh scene), nothing scanned beside them, materials without maps,
//! triangle emitters, no environment map or sun.

use super::embree_scene::{frame_point, placed_in, Frame};
use super::{Geometry, World};
use crate::render::light::EmitterShape;
use crate::render::material::{Bsdf, NO_MAPS};
use crate::render::math::Vec3A;

/// One placed triangle as the wide loop reads it.
#[derive(Clone, Copy, Debug)]
pub struct FlatTri {
    /// Its vertices in the Embree scene's frame.
    pub v: [[f32; 3]; 3],
    /// The unit geometric normal (world orientation): the scalar surface's
    /// own (`Instance::surface`), bit for bit.
    pub ng: [f32; 3],
    /// Its material (a `World::material` index) and whether that is plain
    /// diffuse (shaded over lanes; any other is shaded a lane at a time),
    /// its albedo, and its emission (zero where it emits none).
    pub material: u32,
    pub plain: bool,
    pub albedo: [f32; 3],
    pub emission: [f32; 3],
    /// Its vertices' shading normals (world orientation, not normalised),
    /// where its mesh has normals; else zero.
    pub normals: [[f32; 3]; 3],
    /// Whether its mesh has shading normals.
    pub smooth: bool,
}

/// An emissive triangle as the wide loop samples it: in the frame, on the
/// very triangle the scene holds.
#[derive(Clone, Copy, Debug)]
pub struct FlatEmitter {
    pub p0: [f32; 3],
    pub e1: [f32; 3],
    pub e2: [f32; 3],
    /// Unit normal and area (the emitter's own).
    pub n: [f32; 3],
    pub area: f32,
    pub emission: [f32; 3],
    /// The triangle's object and number, which a point on it must not
    /// sample.
    pub object: u32,
    pub prim: u32,
}

/// The world's triangles flat ([`FlatTri`]), and its emitters.
#[derive(Debug)]
pub struct Flat {
    /// Each object's first flat triangle (`u32::MAX`: not a mesh).
    pub first: Vec<u32>,
    pub tris: Vec<FlatTri>,
    /// `world.lights.emitters`, in the same order.
    pub emitters: Vec<FlatEmitter>,
    /// What moves a camera-space point into the frame.
    pub shift: Vec3A,
    /// Whether every triangle's material is plain diffuse.
    pub plain: bool,
}

/// How `world` fails the wide loop's conditions on its materials and
/// lights, if it does.
fn unserved(world: &World) -> Option<&'static str> {
    if world.vertex_colors {
        return Some("vertex colours");
    }
    if world.env_map.is_some() || world.sun.is_some() {
        return Some("an environment map or sun");
    }
    let lights = &world.lights;
    if lights.emitters.is_empty() || (lights.emitters.len() > 1 && lights.table.is_none()) {
        return Some("no emitter to sample");
    }
    let flat_emitters = (lights.emitters.iter())
        .all(|e| matches!(e.shape, EmitterShape::Triangle(_)) && e.maps == NO_MAPS);
    if !flat_emitters {
        return Some("emitters other than plain triangles");
    }
    let unmapped = (world.instances.iter()).all(|inst| {
        (inst.mesh.materials.iter())
            .all(|&slot| world.material(inst.materials[slot as usize]).maps == NO_MAPS)
    });
    (!unmapped).then_some("texture maps")
}

impl Flat {
    /// The flat triangles of `world`, whose meshes are all the scene's
    /// own triangles in `frame` (the caller knows); or why the wide loop
    /// does not serve it.
    pub(super) fn build(world: &World, frame: &Frame) -> Result<Flat, &'static str> {
        if frame.layout.instances > 0 {
            return Err("meshes placed as Embree instances");
        }
        if let Some(why) = unserved(world) {
            return Err(why);
        }
        let mut first = vec![u32::MAX; world.objects.len()];
        let mut tris = Vec::with_capacity(world.placed_triangles);
        for (id, o) in world.objects.iter().enumerate() {
            let Geometry::Instance(i) = o.geometry else {
                return Err("objects other than meshes");
            };
            let inst = &world.instances[i as usize];
            let (mesh, here) = (&*inst.mesh, placed_in(&inst.world_from_obj, frame.centre));
            first[id] = tris.len() as u32;
            let placed: Vec<[f32; 3]> = (mesh.positions.iter())
                .map(|&p| frame_point(&here, p))
                .collect();
            if placed.iter().flatten().any(|c| !c.is_finite()) {
                return Err("vertices beyond f32's range");
            }
            let n = inst.normal_from_obj;
            for (prim, t) in mesh.triangles.iter().enumerate() {
                let ng = (n * mesh.face_normal(prim as u32)).normalize_or_zero();
                let normals = match &mesh.normals {
                    Some(vn) => t.map(|v| (n * Vec3A::from(vn[v as usize])).to_array()),
                    None => [[0.0; 3]; 3],
                };
                let material = inst.materials[mesh.materials[prim] as usize];
                let m = world.material(material);
                tris.push(FlatTri {
                    material,
                    plain: matches!(m.bsdf, Bsdf::Diffuse) && m.absorb == Vec3A::ZERO,
                    v: t.map(|v| placed[v as usize]),
                    ng: ng.to_array(),
                    albedo: m.albedo.to_array(),
                    emission: match m.emissive {
                        true => m.emission.to_array(),
                        false => [0.0; 3],
                    },
                    normals,
                    smooth: mesh.normals.is_some(),
                });
            }
        }
        let mut emitters = Vec::with_capacity(world.lights.emitters.len());
        for e in &world.lights.emitters {
            let EmitterShape::Triangle(lt) = &e.shape else {
                return Err("emitters other than plain triangles");
            };
            let at = (first.get(e.object as usize).copied())
                .filter(|&f| f != u32::MAX)
                .and_then(|f| tris.get((f + e.prim) as usize))
                .ok_or("an emitter that is no placed triangle")?;
            let [a, b, c] = at.v.map(Vec3A::from);
            emitters.push(FlatEmitter {
                p0: a.to_array(),
                e1: (b - a).to_array(),
                e2: (c - a).to_array(),
                n: lt.n.to_array(),
                area: lt.area,
                emission: e.emission.to_array(),
                object: e.object,
                prim: e.prim,
            });
        }
        Ok(Flat {
            first,
            plain: tris.iter().all(|t| t.plain),
            tris,
            emitters,
            shift: frame.shift(world),
        })
    }
}
