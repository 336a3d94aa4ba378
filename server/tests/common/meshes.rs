//! Mesh scenes that intersection tests share.

use super::{mesh_object, scene_json};
use pathstream::model::generate::icosphere;
use pathstream::model::MeshData;
use pathstream::render::isa::Portable;
use pathstream::render::math::{DVec3, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::Sampler;
use pathstream::render::world::{Hit, Origin, Surface, World, NO_PRIM};
use pathstream::render::Scene;
use serde_json::json;

/// A uniformly random unit vector.
pub fn unit(s: &mut Sampler) -> Vec3A {
    let z = 1.0 - 2.0 * s.next_f32();
    let phi = std::f32::consts::TAU * s.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Random triangles (a soup, some sharing vertices) inside a box.
pub fn soup(n: usize, seed: u64) -> MeshData {
    let mut s = Sampler::new(seed, 0, 0);
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for i in 0..n {
        let c = [
            s.next_f32() * 80.0 + 10.0,
            s.next_f32() * 60.0 + 10.0,
            s.next_f32() * 120.0 + 20.0,
        ];
        let base = positions.len() as u32;
        for _ in 0..3 {
            positions.push([
                c[0] + s.next_f32() * 12.0 - 6.0,
                c[1] + s.next_f32() * 12.0 - 6.0,
                c[2] + s.next_f32() * 12.0 - 6.0,
            ]);
        }
        // Every fourth triangle reuses two vertices of the one before.
        if i % 4 == 3 {
            triangles.push([base - 3, base - 2, base]);
        } else {
            triangles.push([base, base + 1, base + 2]);
        }
    }
    MeshData {
        name: "soup".into(),
        positions,
        normals: None,
        triangles,
        materials: vec![0; n],
        ..Default::default()
    }
}

/// cornell-glass with a soup of triangles and an icosphere placed twice
/// (rotated, unevenly scaled): spheres, quads-free walls and meshes together.
pub fn mixed_scene() -> Scene {
    let mut j = scene_json("cornell-glass");
    let objects = j["objects"].as_array_mut().expect("objects");
    objects.push(mesh_object(
        &soup(300, 1),
        "white",
        serde_json::Value::Null,
        false,
    ));
    let ball = icosphere(2);
    objects.push(mesh_object(
        &ball,
        "mirror",
        json!({"translate": [30, 50, 100], "scale": [8, 5, 11],
        "rotate": {"axis": [1, 2, 3], "deg": 40}}),
        true,
    ));
    objects.push(mesh_object(
        &ball,
        "white",
        json!({"translate": [70, 60, 40], "scale": 6}),
        false,
    ));
    Scene::from_json_value(j).expect("valid")
}

/// A ray from a point drawn in the box (lo, hi) of world space, in a
/// random direction.
pub fn ray_in(world: &World, (lo, hi): (DVec3, DVec3), s: &mut Sampler) -> Ray {
    let u = DVec3::new(
        f64::from(s.next_f32()),
        f64::from(s.next_f32()),
        f64::from(s.next_f32()),
    );
    let o = Vec3A::from((lo + (hi - lo) * u - world.origin).as_vec3());
    Ray::new(o, unit(s))
}

/// Where a ray along `dir` leaving `hit` (geometric normal `ng`) starts.
pub fn leaving(hit: &Hit, ng: Vec3A, dir: Vec3A) -> Origin {
    Origin {
        object: hit.object,
        prim: hit.prim,
        entering: dir.dot(ng) < 0.0,
    }
}

/// Points on the triangles of `world` (`mixed_scene`'s: met by `n` random
/// rays from inside its box, those meeting a mesh), each with two unit
/// directions grazing the triangle's plane, one just above and one just
/// below: the directions most likely to meet the triangle again.
pub fn grazing(world: &World, seed: u64, n: u64) -> Vec<(Hit, Surface, [Vec3A; 2])> {
    let mut out = Vec::new();
    for i in 0..n {
        let mut s = Sampler::new(seed, i, 0);
        let o = Vec3A::new(
            1.0 + 98.0 * s.next_f32(),
            81.6 * s.next_f32(),
            170.0 * s.next_f32(),
        ) - Vec3A::from(world.origin.as_vec3());
        let ray = Ray::new(o, unit(&mut s));
        let Some(hit) = world.intersect(Portable, &ray, Origin::NONE) else {
            continue;
        };
        if hit.prim == NO_PRIM {
            continue;
        }
        let surface = world.surface(&hit, &ray);
        let v = unit(&mut s);
        let tangent = (v - surface.ng * v.dot(surface.ng)).normalize();
        let dirs = [1e-3f32, -1e-3].map(|lift| (tangent + surface.ng * lift).normalize());
        out.push((hit, surface, dirs));
    }
    out
}
