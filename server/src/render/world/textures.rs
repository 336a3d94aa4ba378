//! What texture maps need from the world: the scene's textures gathered
//! once each, every material's maps in the hot path's form, and the
//! texture coordinates and tangent at a hit.
//!
//! Coordinates of the shapes that carry none of their own:
//! - a quad: u along `edge_u` from the corner (0 to 1), v = 1 - (the
//!   fraction along `edge_v`), so that an image lies upright on a quad
//!   whose `edge_v` points up; tangent `edge_u`;
//! - a sphere: latitude-longitude, u = 0.5 + atan2(n.x, n.z) / 2 pi (u = 0.5
//!   facing +z), v = acos(n.y) / pi (0 at the top); tangent towards +u,
//!   around +y.
//!
//! Both sets read the same coordinates there. Meshes interpolate their
//! vertices' sets and tangents (tangents mapped into camera space, the
//! bitangent's sign flipped by a mirroring placement).

use super::{Geometry, Hit, Surface, World};
use crate::render::alpha::{AlphaMode, AlphaTest};
use crate::render::light::Emitter;
use crate::render::maps::{self, Slot, TexCoords, WorldMaps};
use crate::render::material::{SurfaceMaterial, NO_MAPS};
use crate::render::math::Vec3A;
use crate::render::ray::Ray;
use crate::render::scene::{MapSlot, MaterialKind, Scene};
use crate::render::texture::{Map, Texture};
use std::collections::HashMap;
use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::Arc;

/// The scene's textures (each once) and its materials' maps; sets each
/// textured material's `maps` index.
pub(super) fn world_maps(
    scene: &Scene,
    materials: &mut [SurfaceMaterial],
) -> (Vec<Arc<Texture>>, Vec<WorldMaps>) {
    let mut textures: Vec<Arc<Texture>> = Vec::new();
    let mut index_of: HashMap<*const Texture, u32> = HashMap::new();
    let mut maps = Vec::new();
    let mut slot = |s: Option<&MapSlot>| -> Slot {
        let Some(s) = s else {
            return Slot::NONE;
        };
        let index = *index_of.entry(Arc::as_ptr(&s.texture)).or_insert_with(|| {
            textures.push(s.texture.clone());
            (textures.len() - 1) as u32
        });
        Slot {
            texture: index,
            sampling: s.sampling,
        }
    };
    for (m, out) in scene.materials.iter().zip(materials.iter_mut()) {
        if m.maps.is_empty() {
            continue;
        }
        let mut w = WorldMaps::NONE;
        for (map, s) in Map::ALL.into_iter().zip(m.maps.by_slot()) {
            w.slots[map as usize] = slot(s);
        }
        w.normal_scale = m.maps.normal_scale as f32;
        w.clearcoat_normal_scale = m.maps.clearcoat_normal_scale as f32;
        w.shared_mr = w.slot(Map::Metallic) == w.slot(Map::Roughness);
        if let MaterialKind::Pbr {
            metallic,
            roughness,
            transmission,
            clearcoat,
            clearcoat_roughness,
            specular,
            specular_color,
            ..
        } = m.kind
        {
            w.metallic_factor = metallic as f32;
            w.roughness_factor = roughness as f32;
            w.transmission_factor = transmission as f32;
            w.clearcoat_factor = clearcoat as f32;
            w.clearcoat_roughness_factor = clearcoat_roughness as f32;
            w.specular_factor = specular as f32;
            w.specular_color_factor = Vec3A::from(specular_color.map(|c| c as f32));
        } else {
            (w.metallic_factor, w.roughness_factor) = (0.0, 1.0);
        }
        out.maps = maps.len() as u32;
        maps.push(w);
    }
    debug_assert!(materials
        .iter()
        .all(|m| m.maps == NO_MAPS || (m.maps as usize) < maps.len()));
    (textures, maps)
}

/// Each of `materials`' alpha tests (scene material indices, one per
/// mesh slot); None where all are opaque.
pub(super) fn alpha_tests(scene: &Scene, materials: &[u32]) -> Option<Arc<[AlphaTest]>> {
    let tests: Vec<AlphaTest> = (materials.iter())
        .map(|&m| {
            let maps = &scene.materials[m as usize].maps;
            match maps.alpha_mode {
                AlphaMode::Opaque => AlphaTest::OPAQUE,
                mode => AlphaTest {
                    mode,
                    factor: maps.alpha as f32,
                    texture: (maps.base_color.as_ref()).map(|s| (s.texture.clone(), s.sampling)),
                },
            }
        })
        .collect();
    let any = tests.iter().any(|t| t.mode != AlphaMode::Opaque);
    any.then(|| tests.into())
}

impl World {
    /// The radiance emitter `e`, which has an emission map, sends from
    /// `hit`, where `ray` (a shadow ray) met it.
    #[inline(never)]
    pub fn emitted(&self, e: &Emitter, hit: &Hit, ray: &Ray) -> Vec3A {
        let s = self.surface(hit, ray);
        let tc = self.texcoords(hit, &s);
        maps::emission(&self.textures, &self.maps[e.maps as usize], e.emission, &tc)
    }

    /// The texture coordinates and tangent at `hit` on its surface `s`.
    #[inline(always)]
    pub fn texcoords(&self, hit: &Hit, s: &Surface) -> TexCoords {
        match &self.objects[hit.object as usize].geometry {
            Geometry::Quad(q) => {
                let d = s.p - q.corner;
                let a = q.w.dot(d.cross(q.edge_v));
                let b = q.w.dot(q.edge_u.cross(d));
                let uv = [a, 1.0 - b];
                TexCoords {
                    uv: [uv; 2],
                    tangent: q.edge_u,
                    sign: 1.0,
                }
            }
            Geometry::Sphere(_) => {
                let n = s.ng;
                let u = 0.5 + n.x.atan2(n.z) * (0.5 * FRAC_1_PI);
                let v = n.y.clamp(-1.0, 1.0).acos() / PI;
                TexCoords {
                    uv: [[u, v]; 2],
                    tangent: Vec3A::new(n.z, 0.0, -n.x),
                    sign: 1.0,
                }
            }
            Geometry::Instance(i) => {
                let inst = &self.instances[*i as usize];
                let mesh = &*inst.mesh;
                let uv = [0, 1].map(|set| mesh.uv(set, hit.prim, hit.bary));
                let (tangent, sign) = match mesh.tangent(hit.prim, hit.bary) {
                    Some((t, sign)) => {
                        let flip = if inst.mirrored { -1.0 } else { 1.0 };
                        (inst.cam_from_obj.matrix3 * t, sign * flip)
                    }
                    None => (Vec3A::ZERO, 1.0),
                };
                TexCoords { uv, tangent, sign }
            }
        }
    }
}
