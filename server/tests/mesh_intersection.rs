//! Meshes and the BVH, checked against brute force and for watertightness.

mod common;

use common::meshes::{leaving, mixed_scene, ray_in, unit};
use common::{mesh_object, scene};
use pathstream::model::generate::icosphere;
use pathstream::render::isa::{Isa, Portable};
use pathstream::render::math::{DVec3, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::Sampler;
use pathstream::render::scene::BUILTIN_NAMES;
use pathstream::render::world::{AccelChoice, Origin, World};
use pathstream::render::Scene;
use serde_json::json;

/// Asserts that the BVH (or scan) and brute force agree on `rays`, also for
/// rays that start on the surfaces the first rays hit.
/// Ray origins are drawn in the box (lo, hi) of world space.
fn agree(world: &World, (lo, hi): (DVec3, DVec3), rays: u64, seed: u64, what: &str) {
    let (mut hits, mut on_surface) = (0u64, 0u64);
    for i in 0..rays {
        let mut s = Sampler::new(seed, i, 0);
        let ray = ray_in(world, (lo, hi), &mut s);
        let fast = world.intersect(Portable, &ray, Origin::NONE);
        let slow = world.intersect_brute(&ray, Origin::NONE);
        assert_eq!(fast, slow, "{what}: ray {i}");
        let Some(hit) = fast else { continue };
        hits += 1;
        // A ray leaving that surface, into a random direction.
        let surface = world.surface(&hit, &ray);
        let dir = unit(&mut s);
        let from = leaving(&hit, surface.ng, dir);
        let next = world.spawn(&surface, dir);
        let fast = world.intersect(Portable, &next, from);
        let slow = world.intersect_brute(&next, from);
        assert_eq!(
            fast, slow,
            "{what}: ray {i} leaving object {} prim {}",
            hit.object, hit.prim
        );
        on_surface += u64::from(fast.is_some());
    }
    assert!(
        hits > rays / 4,
        "{what}: only {hits} of {rays} rays hit anything"
    );
    eprintln!("{what}: {hits} hits, {on_surface} secondary hits, all equal to brute force");
}

#[test]
fn bvh_nearest_hit_equals_brute_force_on_random_meshes() {
    let s = mixed_scene();
    let world = World::new(&s, s.camera.position);
    assert!(world.uses_bvh());
    let the_box = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(99.0, 81.6, 170.0));
    agree(&world, the_box, 500_000, 1, "mixed scene");
    // Moved far away: the same in camera-relative coordinates.
    let offset = DVec3::new(1e4, -3e4, 2e4);
    let far = s.translated(offset);
    let world = World::new(&far, far.camera.position);
    agree(
        &world,
        (the_box.0 + offset, the_box.1 + offset),
        100_000,
        2,
        "mixed scene moved 4e4 away",
    );
    // And rays from far outside the box, meeting the walls from behind.
    agree(
        &world,
        (the_box.0, the_box.1),
        100_000,
        4,
        "mixed scene seen from 4e4 away",
    );
}

/// Meshes of one leaf (walls of two triangles, the lamp) are tested
/// without their node: the same hits.
#[test]
fn bvh_nearest_hit_equals_brute_force_in_the_triangle_cornell_box() {
    let s = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    let world = World::new(&s, s.camera.position);
    assert!(world.uses_bvh());
    let the_box = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(99.0, 81.6, 170.0));
    agree(&world, the_box, 3_000, 5, "cornell-mesh");
}

#[test]
fn bvh_nearest_hit_equals_brute_force_on_every_built_in_scene() {
    for name in BUILTIN_NAMES {
        let s = scene(name);
        let bvh = World::with_accel(&s, s.camera.position, AccelChoice::Bvh);
        assert!(bvh.uses_bvh());
        let c = s.camera.position;
        let around = if name == "furnace" { 0.5 } else { 60.0 };
        let region = (
            c - DVec3::splat(around)
                - DVec3::new(0.0, 0.0, if name == "furnace" { 0.0 } else { 150.0 }),
            c + DVec3::splat(around),
        );
        agree(&bvh, region, 100_000, 3, &format!("{name} through the BVH"));
        let scan = World::new(&s, s.camera.position);
        assert!(!scan.uses_bvh(), "{name} is scanned");
    }
}

/// Rays from inside a closed mesh, aimed exactly at its vertices and at
/// points of its shared edges: none may escape.
#[test]
fn rays_at_shared_edges_and_vertices_never_escape_a_closed_mesh() {
    let ball = icosphere(4);
    let mut j = json!({"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40},
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}, "objects": []});
    j["objects"] = json!([mesh_object(&ball, "m", serde_json::Value::Null, false)]);
    let identity = Scene::from_json_value(j.clone()).expect("valid");
    j["objects"] = json!([mesh_object(
        &ball,
        "m",
        json!({"scale": [3, 0.7, 1.3], "rotate": {"axis": [1, 1, 0], "deg": 33}}),
        false
    )]);
    let transformed = Scene::from_json_value(j).expect("valid");
    let edges: Vec<(u32, u32)> = ball
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .collect();
    for (scene, exact) in [(&identity, true), (&transformed, false)] {
        // The camera, hence the render origin, is the world origin: with the
        // identity placement object space is camera space exactly, so the
        // aims below are exact there.
        let world = World::new(scene, DVec3::ZERO);
        let t = scene.imports[0].instances[0].world_from_object;
        let mut escaped = 0;
        let rays = 1_000_000u64;
        for i in 0..rays {
            let mut s = Sampler::new(11, i, 0);
            let o = unit(&mut s) * (0.3 * s.next_f32());
            let target = if i % 5 == 0 {
                Vec3A::from(ball.positions[(i / 5) as usize % ball.positions.len()])
            } else {
                let (a, b) = edges[(s.next_u64() % edges.len() as u64) as usize];
                let (a, b) = (
                    Vec3A::from(ball.positions[a as usize]),
                    Vec3A::from(ball.positions[b as usize]),
                );
                a + (b - a) * s.next_f32()
            };
            let (o, target) = if exact {
                (o, target)
            } else {
                let map = |p: Vec3A| Vec3A::from(t.transform_point3(p.as_dvec3()).as_vec3());
                (map(o), map(target))
            };
            let ray = Ray::new(o, (target - o).normalize());
            if world.intersect(Portable, &ray, Origin::NONE).is_none() {
                escaped += 1;
            }
        }
        assert_eq!(
            escaped, 0,
            "{escaped} of {rays} rays escaped (exact aims: {exact})"
        );
    }
}

/// A ray leaving a triangle starts strictly on the side it leaves to, as
/// the next traversal sees it (after the round trip camera -> object
/// space), at any scale and distance from the camera: the offset covers
/// every rounding on the way.
#[test]
fn spawned_origins_lie_on_the_side_they_leave_to() {
    let ball = icosphere(3);
    for (scale, at) in [(1e-3, 0.01), (1.0, 5.0), (1e3, 1e4), (3.0, 2e5)] {
        let j = json!({"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40},
            "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
            "objects": [mesh_object(&ball, "m", json!({"translate": [at * 0.6, -at * 0.3, -at],
                "scale": [scale, scale * 0.7, scale * 1.3], "rotate": {"axis": [1, 2, 0.5], "deg": 71}}), false)]});
        let s = Scene::from_json_value(j).expect("valid");
        let world = World::new(&s, s.camera.position);
        let inst = &world.instances[0];
        let (mut wrong_without_offset, mut tried) = (0, 0);
        for i in 0..50_000u64 {
            let mut smp = Sampler::new(21, i, 0);
            // Aim at a random point of the ball from a random direction outside.
            let target = inst.cam_from_obj.transform_point3a(unit(&mut smp) * 0.9);
            let o = target + unit(&mut smp) * (3.0 * scale as f32);
            let ray = Ray::new(o, (target - o).normalize());
            let Some(hit) = world.intersect(Portable, &ray, Origin::NONE) else {
                continue;
            };
            let surface = world.surface(&hit, &ray);
            let dir = unit(&mut smp);
            let next = world.spawn(&surface, dir);
            // The plane of the triangle in object space, exactly.
            let v = inst.mesh.vertices(hit.prim).map(|p| p.as_dvec3());
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            let side = |p: Vec3A| n.dot(inst.obj_from_cam.transform_point3a(p).as_dvec3() - v[0]);
            let leaving_front = inst.obj_from_cam.transform_vector3a(dir).as_dvec3().dot(n) > 0.0;
            let d = side(next.origin);
            assert!(
                d != 0.0 && (d > 0.0) == leaving_front,
                "scale {scale} at {at}: ray {i} starts on the wrong side ({d:e})"
            );
            tried += 1;
            let bare = side(surface.p);
            wrong_without_offset += usize::from(bare == 0.0 || (bare > 0.0) != leaving_front);
        }
        assert!(tried > 40_000, "scale {scale}: only {tried} hits");
        // The offset is needed: the bare hit point is on the wrong side often.
        assert!(wrong_without_offset > tried / 20, "scale {scale} at {at}: bare hit points wrong only {wrong_without_offset} of {tried} times");
    }
}

/// `rays` one by one and as a packet, on `isa`: the same hits, bit for bit.
fn packet_agrees<I: Isa>(isa: I, world: &World, rays: &[Ray], what: &str) {
    let mut packed = vec![None; rays.len()];
    world.intersect_packet(isa, rays, &mut packed);
    for (k, (ray, got)) in rays.iter().zip(&packed).enumerate() {
        let alone = world.intersect(isa, ray, Origin::NONE);
        assert_eq!(*got, alone, "{what}: ray {k} of {}", rays.len());
    }
}

/// Packets of up to sixteen rays (as the render loop makes of a pixel's
/// camera rays, or of a run of pixels'): each ray gets the hit it gets
/// alone. Origins from one point (a pinhole) to a spread of 20 units (a
/// lens), directions from nearly one to any (rays whose directions differ
/// in sign cannot share a packet and go one by one); on the triangle
/// Cornell box and on meshes that are rotated, scaled and moved.
#[test]
fn packets_of_rays_get_the_hits_their_rays_get_alone() {
    let cornell = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    let mixed = mixed_scene();
    for (name, s) in [("cornell-mesh", &cornell), ("mixed scene", &mixed)] {
        let world = World::new(s, s.camera.position);
        assert!(world.uses_bvh());
        let (mut shared, mut hits, mut all) = (0, 0, 0);
        for i in 0..4_000u64 {
            let mut smp = Sampler::new(31, i, 0);
            let spread = [0.0, 0.01, 1.0, 20.0][(i % 4) as usize];
            let cone = [1e-3, 0.02, 0.3, 3.0][(i / 4 % 4) as usize];
            let axis = (unit(&mut smp) * 0.15 + Vec3A::NEG_Z).normalize();
            let centre = unit(&mut smp) * spread;
            let rays: Vec<Ray> = (0..1 + i % 16)
                .map(|_| {
                    let o = centre + unit(&mut smp) * (spread * 0.5);
                    Ray::new(o, (axis + unit(&mut smp) * cone).normalize())
                })
                .collect();
            let signs = |r: &Ray| r.dir.to_array().map(|c| c.is_sign_negative());
            shared += usize::from(rays.iter().all(|r| signs(r) == signs(&rays[0])));
            packet_agrees(Portable, &world, &rays, name);
            #[cfg(target_arch = "x86_64")]
            if let Some(avx2) = pathstream::render::isa::Avx2::detect() {
                packet_agrees(avx2, &world, &rays, name);
            }
            all += rays.len();
            hits += rays
                .iter()
                .filter(|r| world.intersect(Portable, r, Origin::NONE).is_some())
                .count();
        }
        assert!(
            shared > 1_000 && hits > all / 3,
            "{name}: {shared} packets shared, {hits} hits of {all} rays"
        );
    }
}

/// A ball placed twice at the same place: every ray meets two triangles
/// at the same distance, and the hit is the lower (object, triangle) of
/// the two, whichever the traversal met first, for single rays and
/// packets alike (as the OpenCL kernel decides it).
#[test]
fn a_tie_goes_to_the_lower_object_and_triangle() {
    let ball = icosphere(5);
    let objects: Vec<_> = (0..2)
        .map(|_| {
            mesh_object(
                &ball,
                "m",
                json!({"translate": [0, 0, -4], "scale": 1.5}),
                true,
            )
        })
        .collect();
    let j = json!({"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40},
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}, "objects": objects});
    let s = Scene::from_json_value(j).expect("valid");
    let world = World::new(&s, s.camera.position);
    let n = ball.triangles.len() as u32;
    let mut hits = 0;
    for i in 0..2_000u64 {
        let mut smp = Sampler::new(41, i, 0);
        let axis = (unit(&mut smp) * 0.3 + Vec3A::NEG_Z).normalize();
        let rays: Vec<Ray> = (0..16)
            .map(|_| Ray::new(Vec3A::ZERO, (axis + unit(&mut smp) * 0.01).normalize()))
            .collect();
        packet_agrees(Portable, &world, &rays, "the ball placed twice");
        for ray in &rays {
            let Some(hit) = world.intersect(Portable, ray, Origin::NONE) else {
                continue;
            };
            hits += 1;
            assert!(
                hit.object == 0 && hit.prim < n,
                "ray {i}: object {} triangle {} of {n}",
                hit.object,
                hit.prim
            );
            assert_eq!(Some(hit), world.intersect_brute(ray, Origin::NONE));
        }
    }
    assert!(hits > 10_000, "only {hits} hits");
}

/// Camera rays go as packets only in worlds of fewer than
/// `PACKET_MAX_TRIANGLES` placed triangles: in larger meshes a packet
/// with a ray that misses walks everything in its frustum (a 1M-triangle
/// mesh rendered 3x slower, docs/BENCHMARKS.md).
#[test]
fn large_worlds_trace_their_camera_rays_one_by_one() {
    use pathstream::render::world::PACKET_MAX_TRIANGLES;
    let ball = icosphere(5);
    let per_ball = ball.triangles.len();
    let world_of = |balls: usize| {
        let objects: Vec<_> = (0..balls)
            .map(|k| mesh_object(&ball, "m", json!({"translate": [3 * k, 0, -4]}), true))
            .collect();
        let j = json!({"camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40},
            "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}, "objects": objects});
        let s = Scene::from_json_value(j).expect("valid");
        World::new(&s, s.camera.position)
    };
    let below = (PACKET_MAX_TRIANGLES - 1) / per_ball;
    assert!(
        world_of(below).packets_pay(),
        "{} triangles",
        below * per_ball
    );
    assert!(
        !world_of(below + 1).packets_pay(),
        "{} triangles",
        (below + 1) * per_ball
    );
}
