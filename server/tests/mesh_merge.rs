//! Small meshes merge into one (`render::world::merge`): the merged
//! world finds the surfaces the unmerged one finds, and every backend
//! renders it as the unmerged world renders.

mod common;

use common::{assert_agree, mesh_backends, mesh_object, scene_json};
use pathstream::model::generate::icosphere;
use pathstream::render::isa::Portable;
use pathstream::render::math::{DVec3, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::Sampler;
use pathstream::render::world::{AccelChoice, Origin, World};
use pathstream::render::{Film, Quality, RenderJob, Scene};
use serde_json::json;

/// cornell-glass with five icospheres: two flat (one of them an emissive
/// lamp), two with shading normals (one turned and unevenly scaled), and
/// one mirrored by its placement (the same mesh as the turned one: that one
/// merges, the mirrored placement keeps its instance).
fn balls() -> Scene {
    let mut j = scene_json("cornell-glass");
    let objects = j["objects"].as_array_mut().expect("objects");
    let turned = json!({"translate": [30, 50, 100], "scale": [8, 5, 11],
        "rotate": {"axis": [1, 2, 3], "deg": 40}});
    objects.push(mesh_object(&icosphere(2), "white", turned, false));
    let lamp = json!({"translate": [50, 40, 90], "scale": 3});
    objects.push(mesh_object(&icosphere(1), "lamp", lamp, false));
    let small = json!({"translate": [70, 60, 40], "scale": [6, 4, 5],
        "rotate": {"axis": [2, 1, 0], "deg": 30}});
    objects.push(mesh_object(&icosphere(1), "mirror", small, true));
    let fine = json!({"translate": [50, 20, 120], "scale": 7});
    objects.push(mesh_object(&icosphere(3), "white", fine, true));
    let mirrored = json!({"translate": [20, 15, 60], "scale": [-5, 5, 5]});
    objects.push(mesh_object(&icosphere(2), "red", mirrored, false));
    Scene::from_json_value(j).expect("valid")
}

fn unit(s: &mut Sampler) -> Vec3A {
    let z = 1.0 - 2.0 * s.next_f32();
    let phi = std::f32::consts::TAU * s.next_f32();
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

#[test]
fn small_meshes_merge_by_kind_and_a_mirrored_one_keeps_its_own() {
    let s = balls();
    let merged = World::new(&s, s.camera.position);
    let unmerged = World::unmerged(&s, s.camera.position, AccelChoice::Auto);
    assert_eq!(unmerged.instances.len(), 5);
    for i in merged.instances.iter().chain(&unmerged.instances) {
        eprintln!(
            "{} tris, normals {}, translation {}",
            i.triangles(),
            i.mesh.normals.is_some(),
            i.translation_only
        );
    }
    // The flat pair, the smooth pair, the mirrored ball.
    assert_eq!(merged.instances.len(), 3);
    let triangles = |w: &World| w.instances.iter().map(|i| i.triangles()).sum::<usize>();
    assert_eq!(triangles(&merged), triangles(&unmerged));
    assert!(merged.instances[..2].iter().all(|i| i.translation_only));
    // The lamp's triangles are emitters in both.
    assert_eq!(merged.lights.emitters.len(), unmerged.lights.emitters.len());
    // The triangle Cornell box: its eleven meshes are two (flat walls and lamp,
    // smooth balls).
    let c = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    assert_eq!(
        World::new(&c, c.camera.position).instances.len(),
        2,
        "walls and balls"
    );
}

/// From random points of the box, and again from the surfaces found: the
/// same surface (distance, material, normal) in both worlds. A ray leaving
/// a surface starts off it by a bound that differs between the worlds (the
/// unmerged instances' bound includes their matrices' rounding), so a
/// second ray that grazes an edge of a faceted ball may meet the facet
/// beside the other world's: the same material a hair away, allowed for
/// one ray in a thousand.
fn assert_same_surfaces(s: &Scene, offset: DVec3, rays: u64) {
    let merged = World::new(s, s.camera.position);
    let unmerged = World::unmerged(s, s.camera.position, AccelChoice::Auto);
    let (lo, hi) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(99.0, 81.6, 170.0));
    let (mut checked, mut beside) = (0, 0);
    let cos = |a: Vec3A, b: Vec3A| a.normalize().dot(b.normalize());
    for i in 0..rays {
        let mut r = Sampler::new(7, i, 0);
        let u = DVec3::new(
            r.next_f32().into(),
            r.next_f32().into(),
            r.next_f32().into(),
        );
        let o = Vec3A::from((lo + (hi - lo) * u + offset - merged.origin).as_vec3());
        let (dir, next) = (unit(&mut r), unit(&mut r));
        let mut rays = [Ray::new(o, dir); 2];
        let mut from = [Origin::NONE; 2];
        for bounce in 0..2 {
            let a = merged.intersect(Portable, &rays[0], from[0]);
            let b = unmerged.intersect(Portable, &rays[1], from[1]);
            let (Some(a), Some(b)) = (a, b) else {
                assert_eq!(
                    a.is_some(),
                    b.is_some(),
                    "ray {i} bounce {bounce}: {a:?} vs {b:?}"
                );
                break;
            };
            let (sa, sb) = (merged.surface(&a, &rays[0]), unmerged.surface(&b, &rays[1]));
            let what = format!("ray {i} bounce {bounce}: {sa:?} vs {sb:?}");
            assert_eq!(sa.material, sb.material, "{what}");
            let same = cos(sa.ng, sb.ng) > 0.9999 && cos(sa.ns, sb.ns) > 0.9999;
            if bounce == 0 {
                // The same ray: the same surface, rounding apart.
                assert!((a.t - b.t).abs() <= 1e-4 * a.t.max(1.0) && same, "{what}");
            } else if same {
                // On the same surface within 1e-5 of the box's size
                // (however far apart along a grazing ray).
                let off = (sa.p - sb.p).dot(sa.ng.normalize()).abs();
                assert!(off <= 2e-3, "{what}: {off} off the surface");
            } else {
                assert!((sa.p - sb.p).length() < 1e-2, "{what}");
                beside += 1;
            }
            checked += 1;
            let leave = [(&merged, sa, a), (&unmerged, sb, b)];
            for (k, (w, surface, hit)) in leave.into_iter().enumerate() {
                rays[k] = w.spawn(&surface, next);
                from[k] = Origin {
                    object: hit.object,
                    prim: hit.prim,
                    entering: next.dot(surface.ng) < 0.0,
                };
            }
        }
    }
    assert!(checked > rays, "{checked} surfaces compared");
    assert!(
        beside <= rays / 1000,
        "{beside} second rays met another facet"
    );
    eprintln!("{checked} surfaces the same, {beside} a facet beside");
}

#[test]
fn the_merged_world_finds_the_surfaces_the_unmerged_one_finds() {
    let s = balls();
    assert_same_surfaces(&s, DVec3::ZERO, 100_000);
    // Far from the origin: the merged mesh keeps its own precision.
    let offset = DVec3::new(1e4, -3e4, 2e4);
    assert_same_surfaces(&s.translated(offset), offset, 30_000);
}

#[test]
fn every_backend_renders_the_merged_world_as_the_unmerged_one() {
    let s = balls();
    let (w, h) = (24, 24);
    let q = |seed: u64| Quality {
        seed,
        ..Quality::default()
    };
    let mut reference = RenderJob::new(&s, w, h, &q(1));
    reference.world = World::unmerged(&s, s.camera.position, AccelChoice::Auto);
    let mut cpu = common::backends().remove(0).1;
    let mut expected = Film::new(w, h);
    cpu.render(&reference, &mut expected, 512).expect("render");
    for (name, mut backend) in mesh_backends() {
        let job = RenderJob::new(&s, w, h, &q(2));
        assert_eq!(job.world.instances.len(), 3);
        let mut film = Film::new(w, h);
        backend.render(&job, &mut film, 512).expect("render");
        assert_agree(
            &expected,
            &film,
            4,
            4.5,
            0.0,
            &format!("{name}: merged vs unmerged"),
        );
    }
}
