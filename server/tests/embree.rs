//! The CPU's rays through Embree (`render::embree`, `world::embree_rays`),
//! checked against the world's own brute-force search: the same surfaces
//! for rays from anywhere and for rays leaving the surfaces they hit,
//! never the triangle a ray leaves, in a world of meshes (placed rotated,
//! scaled, merged) beside spheres, near the origin and 4e4 away. Renders
//! through Embree pass every mesh check (`mesh_render.rs`, `alpha.rs`,
//! `mesh_merge.rs` run on `common::mesh_backends`).
//!
//! Embree's watertight test is not the CPU's own, so hits may differ by
//! rounding: distances in their last bits, and a ray through a shared edge
//! may name the other triangle (counted, and bounded here).

mod common;

use common::meshes::{grazing, leaving, mixed_scene, ray_in, soup, unit};
use pathstream::render::isa::Portable;
use pathstream::render::math::DVec3;
use pathstream::render::ray::Ray;
use pathstream::render::sampler::Sampler;
use pathstream::render::world::{Hit, Origin, World, NO_PRIM};
use pathstream::render::Scene;
use serde_json::json;

/// `scene`'s world with its meshes in Embree (None: Embree is not
/// installed, outside CI).
fn embree_world(scene: &Scene) -> Option<World> {
    if !common::embree() {
        return None;
    }
    let world = World::new(scene, scene.camera.position);
    assert!(world.use_embree(0), "Embree takes the world's meshes");
    assert!(world.traced_by_embree());
    Some(world)
}

#[derive(Default, Debug)]
struct Tally {
    rays: u64,
    hits: u64,
    /// Hit by one search and missed by the other.
    missed: u64,
    /// The same distance, another triangle (a shared edge).
    other_triangle: u64,
    /// The largest distance across the surface between the two hits,
    /// relative to the coordinates' size.
    worst_apart: f32,
}

impl Tally {
    /// Compares Embree's hit with the brute-force one, which `ray` meets
    /// at `cos` (the cosine of its angle to the surface's normal).
    fn add(
        &mut self,
        embree: Option<Hit>,
        brute: Option<Hit>,
        (ray, cos): (&Ray, f32),
        what: &str,
    ) {
        self.rays += 1;
        match (embree, brute) {
            (Some(a), Some(b)) => {
                self.hits += 1;
                // How far apart the two points are across the surface, for
                // the size of the numbers involved (a grazing ray's
                // distance itself is ill-conditioned).
                let scale = ray.origin.abs().max_element() + b.t + 1.0;
                let apart = (a.t - b.t).abs() * cos / scale;
                self.worst_apart = self.worst_apart.max(apart);
                assert!(
                    apart < 1e-5,
                    "{what}: Embree's hit at {a:?}, brute force's at {b:?}, cosine {cos}"
                );
                if (a.object, a.prim) != (b.object, b.prim) {
                    self.other_triangle += 1;
                } else if a.prim != NO_PRIM {
                    // The same point of the triangle, which shading reads
                    // (normals, texture coordinates) through these weights.
                    let off = (0..3)
                        .map(|k| (a.bary[k] - b.bary[k]).abs())
                        .fold(0.0, f32::max);
                    assert!(
                        off < 1e-3,
                        "{what}: barycentrics {:?} vs {:?}",
                        a.bary,
                        b.bary
                    );
                }
                let sum: f32 = a.bary.iter().sum();
                let on_triangle = a.prim == NO_PRIM || (sum - 1.0).abs() < 1e-4;
                assert!(on_triangle, "{what}: {a:?} vs {b:?}");
            }
            (None, None) => {}
            _ => self.missed += 1,
        }
    }
}

/// Asserts that a ray leaving triangle `left` did not meet it again.
fn not_again(next: Option<Hit>, left: &Hit, what: &str) {
    if let Some(h) = next {
        assert!(
            (h.object, h.prim) != (left.object, left.prim),
            "{what}: met triangle {} of object {} again at t = {}",
            left.prim,
            left.object,
            h.t
        );
    }
}

/// Rays from points drawn in (lo, hi) of world space in random directions,
/// and from each surface they hit onwards (spawned as the integrator
/// spawns them): Embree agrees with brute force, and never names the
/// triangle a ray leaves.
fn agree(world: &World, (lo, hi): (DVec3, DVec3), rays: u64, seed: u64, what: &str) -> Tally {
    let mut tally = Tally::default();
    for i in 0..rays {
        let mut s = Sampler::new(seed, i, 0);
        let ray = ray_in(world, (lo, hi), &mut s);
        let cos = |hit: Option<Hit>, ray: &Ray| {
            hit.map_or(1.0, |h| world.surface(&h, ray).ng.dot(ray.dir).abs())
        };
        let hit = world.intersect(Portable, &ray, Origin::NONE);
        let brute = world.intersect_brute(&ray, Origin::NONE);
        tally.add(hit, brute, (&ray, cos(brute, &ray)), what);
        let Some(hit) = hit else { continue };
        let surface = world.surface(&hit, &ray);
        let dir = unit(&mut s);
        let from = leaving(&hit, surface.ng, dir);
        let next = world.spawn(&surface, dir);
        let onward = world.intersect(Portable, &next, from);
        if hit.prim != NO_PRIM {
            not_again(onward, &hit, &format!("{what}: ray {i}"));
        }
        let brute = world.intersect_brute(&next, from);
        tally.add(onward, brute, (&next, cos(brute, &next)), what);
    }
    eprintln!("{what}: {tally:?}");
    assert!(tally.hits > rays / 4, "{what}: few hits: {tally:?}");
    // Measured: none of either kind in 2 x 600,000 rays.
    assert!(tally.missed * 20_000 <= tally.rays, "{what}: {tally:?}");
    assert!(
        tally.other_triangle * 5_000 <= tally.rays,
        "{what}: {tally:?}"
    );
    tally
}

#[test]
fn embree_finds_the_surfaces_brute_force_finds() {
    let s = mixed_scene();
    let Some(world) = embree_world(&s) else {
        return;
    };
    let the_box = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(99.0, 81.6, 170.0));
    agree(&world, the_box, 100_000, 1, "mixed scene");
    let offset = DVec3::new(1e4, -3e4, 2e4);
    let far = s.translated(offset);
    let world = embree_world(&far).expect("Embree loaded a moment ago");
    agree(
        &world,
        (the_box.0 + offset, the_box.1 + offset),
        50_000,
        2,
        "mixed scene moved 4e4 away",
    );
}

/// A ray that starts exactly on a triangle (not moved off it) and leaves it
/// meets other surfaces, never that triangle: the filter refuses it.
#[test]
fn a_ray_from_a_triangle_never_meets_that_triangle() {
    let s = mixed_scene();
    let Some(world) = embree_world(&s) else {
        return;
    };
    let (mut tried, mut onward) = (0u64, 0u64);
    // Grazing the plane both ways: the directions most likely to meet the
    // triangle again at t = 0.
    for (i, (hit, surface, dirs)) in grazing(&world, 9, 200_000).into_iter().enumerate() {
        for dir in dirs {
            let from = leaving(&hit, surface.ng, dir);
            tried += 1;
            let next = world.intersect(Portable, &Ray::new(surface.p, dir), from);
            onward += u64::from(next.is_some());
            not_again(next, &hit, &format!("ray {i}"));
        }
    }
    eprintln!("{tried} rays from triangles, {onward} met something else");
    assert!(
        tried > 50_000 && onward > tried / 4,
        "{tried} tried, {onward} hit"
    );
}

/// Worlds the CPU leaves to its own BVH: no meshes, or too few triangles
/// for the backend's default.
#[test]
fn embree_takes_only_worlds_with_enough_triangles() {
    let s = common::scene("cornell");
    let world = World::new(&s, s.camera.position);
    assert!(!world.use_embree(0), "no meshes");
    assert!(!world.traced_by_embree());
    let s = mixed_scene();
    let world = World::new(&s, s.camera.position);
    let min = pathstream::render::world::EMBREE_MIN_TRIANGLES;
    assert!(!world.use_embree(min), "a few thousand triangles");
    assert!(!world.traced_by_embree());
    // A mesh beside more spheres than a scan beside Embree serves.
    let mut j = common::scene_json("cornell-glass");
    let objects = j["objects"].as_array_mut().expect("objects");
    for k in 0..300 {
        objects.push(
            serde_json::json!({"type": "sphere", "center": [k as f64 * 0.3, 40, 80],
            "radius": 0.1, "material": "white"}),
        );
    }
    objects.push(common::mesh_object(
        &common::meshes::soup(50, 2),
        "white",
        serde_json::Value::Null,
        false,
    ));
    let s = Scene::from_json_value(j).expect("valid");
    let world = World::new(&s, s.camera.position);
    assert!(!world.use_embree(0), "300 spheres to scan beside the mesh");
    assert!(!world.traced_by_embree());
}

/// Meshes placed once are triangles of Embree's scene itself, a large
/// mesh placed twice an instance of its own scene, and rays through both
/// agree with brute force. The scene depends on the placements only: a
/// camera move reuses it, a moved mesh builds it again.
#[test]
fn embrees_scene_holds_what_is_placed_once_and_outlives_a_camera_move() {
    let s = mixed_scene();
    let Some(world) = embree_world(&s) else {
        return;
    };
    let layout = world.embree_layout().expect("Embree traces the world");
    assert_eq!(layout.instances, 0, "{layout:?}");
    assert!(layout.own_triangles >= 300 + 2 * 320, "{layout:?}");
    let elsewhere = World::new(&s, s.camera.position + DVec3::new(3.0, -20.0, 70.0));
    assert!(elsewhere.use_embree(0));
    assert_eq!(elsewhere.embree_layout(), Some(layout), "a camera move");
    let moved = s.translated(DVec3::new(0.0, 1.0, 0.0));
    let moved = World::new(&moved, moved.camera.position);
    assert!(moved.use_embree(0));
    let build = moved.embree_layout().expect("Embree").build;
    assert!(build > layout.build, "a moved scene, build {build}");

    // Beyond merging (`MERGE_MESH_MAX`), placed twice: instances.
    let mut j = common::scene_json("cornell-glass");
    let objects = j["objects"].as_array_mut().expect("objects");
    let big = soup(70_000, 4);
    for t in [
        json!({"scale": 0.5}),
        json!({"translate": [40, 30, 70], "scale": [0.4, 0.5, 0.3],
            "rotate": {"axis": [1, 2, 3], "deg": 40}}),
    ] {
        objects.push(common::mesh_object(&big, "white", t, false));
    }
    let s = Scene::from_json_value(j).expect("valid");
    let world = embree_world(&s).expect("Embree loaded a moment ago");
    let layout = world.embree_layout().expect("Embree");
    assert_eq!(layout.instances, 2, "{layout:?}");
    let the_box = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(99.0, 81.6, 170.0));
    agree(&world, the_box, 1_500, 3, "a mesh placed twice");
}

/// A triangle naming a vertex the mesh does not have is refused before
/// Embree reads it.
#[test]
fn embree_refuses_a_vertex_index_beyond_the_vertices() {
    if !common::embree() {
        return;
    }
    let embree = pathstream::render::embree::embree().expect("Embree loads");
    let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    assert!(embree.mesh(&positions, &[[0, 1, 2]]).is_ok());
    let refused = embree.mesh(&positions, &[[0, 1, 2], [0, 1, 3]]);
    assert_eq!(refused.err().as_deref(), Some("vertex index 3 of 3"));
}
