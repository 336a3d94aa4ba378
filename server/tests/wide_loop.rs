//! The CPU's wide loop (`backend/cpu/wide_loop.rs`: paths whose state is
//! in lanes, diffuse surfaces shaded over them and every other material a
//! lane at a time, for worlds of meshes without maps lit by emissive
//! triangles that Embree traces) against the lane loop, which shades the
//! same paths one at a time: the same random numbers in the
//! same order, the surfaces computed in Embree's frame instead of object
//! space, so the image is the lane loop's up to rounding; bit for bit the
//! same at every width, however its lanes are refilled; a closed form
//! where one holds; and every world or setting it does not serve left to
//! the lane loop.

mod common;

use common::films::apart;
use common::{assert_clean, assert_mean, mesh_object};
use pathstream::bench::scenes::load;
use pathstream::model::generate::icosphere;
use pathstream::render::backend::{CpuBackend, EmbreeUse, IsaCap, PathLoop};
use pathstream::render::quality::Denoise;
use pathstream::render::{Film, Filter, Quality, RenderJob, Scene};
use serde_json::json;

fn render(backend: CpuBackend, scene: &Scene, (w, h): (u32, u32), q: &Quality, spp: u64) -> Film {
    let job = RenderJob::new(scene, w, h, q);
    let mut film = Film::new(w, h);
    let mut backend = backend;
    backend.render(&job, &mut film, spp);
    film
}

fn embree(paths: PathLoop) -> CpuBackend {
    CpuBackend::default()
        .with_embree(EmbreeUse::AllMeshes)
        .with_paths(paths)
}

/// A closed icosphere of radius `scale` around the camera, albedo and
/// emission 0.5: radiance 1 everywhere.
fn furnace(scale: f64, smooth: bool) -> Scene {
    Scene::from_json_value(json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -scale], "vfov_deg": 100},
        "materials": {"shell": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [0.5, 0.5, 0.5]}},
        "objects": [mesh_object(&icosphere(4), "shell", json!({"scale": scale}), smooth)]
    }))
    .expect("valid furnace")
}

/// Whether the wide loop serves `scene`'s world.
fn served(scene: &Scene) -> bool {
    let job = RenderJob::new(scene, 8, 8, &Quality::default());
    job.world.use_embree(0) && job.world.flat().is_some()
}

#[test]
fn the_wide_loop_serves_meshes_without_maps_lit_by_triangles_only() {
    if !common::embree() {
        return;
    }
    for (name, scene, serves) in [
        ("cornell-mesh", load("cornell-mesh").expect("scene"), true),
        ("furnace", furnace(1.0, true), true),
        (
            "cornell-mesh-pbr",
            load("cornell-mesh-pbr").expect("scene"),
            true,
        ),
        (
            "cornell-mesh-coated",
            load("cornell-mesh-coated").expect("scene"),
            true,
        ),
        (
            "cornell-mesh-specular",
            load("cornell-mesh-specular").expect("scene"),
            true,
        ),
        (
            "cornell-mesh-textured",
            load("cornell-mesh-textured").expect("scene"),
            false,
        ),
        (
            "cornell-glass-mesh",
            load("cornell-glass-mesh").expect("scene"),
            false,
        ),
        ("sunset-balls", load("sunset-balls").expect("scene"), false),
    ] {
        assert_eq!(served(&scene), serves, "{name}");
    }
}

#[test]
fn the_wide_loop_gives_the_lane_loops_image_up_to_rounding() {
    if !common::embree() {
        return;
    }
    let q = Quality::default();
    // Roulette from the first bounce: paths of every length, whose lanes
    // are refilled as they end.
    let early = Quality {
        max_depth: 16,
        rr_depth: 1,
        ..Quality::default()
    };
    let cornell = load("cornell-mesh").expect("scene");
    for (name, scene, q) in [
        ("cornell-mesh", cornell.clone(), q),
        ("cornell-mesh, early roulette", cornell, early),
        // Metal and coated plastic (`pbr`, MIS); a clear coat over paint and
        // an absorbing rough glass; a mirror and a smooth glass.
        (
            "cornell-mesh-pbr",
            load("cornell-mesh-pbr").expect("scene"),
            q,
        ),
        (
            "cornell-mesh-coated",
            load("cornell-mesh-coated").expect("scene"),
            early,
        ),
        (
            "cornell-mesh-specular",
            load("cornell-mesh-specular").expect("scene"),
            q,
        ),
        ("furnace 1e3, shading normals", furnace(1e3, true), q),
        ("furnace 1e-3", furnace(1e-3, false), q),
    ] {
        assert!(served(&scene), "{name}: the wide loop serves it");
        let size = (48, 36);
        let pixels = (size.0 * size.1) as usize;
        let lanes = render(embree(PathLoop::Lanes), &scene, size, &q, 16);
        let wide = render(embree(PathLoop::Auto), &scene, size, &q, 16);
        assert_clean(&wide, name);
        let (differ, rel) = apart(&wide, &lanes);
        eprintln!("{name}: {differ} of {pixels} pixels differ, sums {rel:.2e} apart");
        assert!(
            wide.pixels() != lanes.pixels(),
            "{name}: the wide loop did not run (its surfaces round differently)"
        );
        assert!(
            differ * 50 < pixels && rel < 1e-3,
            "{name}: {differ} of {pixels} pixels differ, sums {rel:.2e} apart"
        );
        // Sixteen lanes (AVX-512 here), eight (AVX2) and four (every CPU).
        for cap in [IsaCap::Avx2, IsaCap::Portable] {
            let narrow = render(embree(PathLoop::Auto).isa_cap(cap), &scene, size, &q, 16);
            assert!(
                narrow.pixels() == wide.pixels(),
                "{name}: the wide loop at {cap:?} differs from sixteen lanes"
            );
        }
    }
}

#[test]
fn the_wide_loop_keeps_the_furnace_at_radiance_one() {
    if !common::embree() {
        return;
    }
    for scale in [1e-3, 1e3] {
        for smooth in [false, true] {
            let scene = furnace(scale, smooth);
            assert!(served(&scene));
            let q = Quality {
                max_depth: 0,
                rr_depth: 2,
                filter: Filter::Box,
                seed: 5,
                ..Quality::default()
            };
            let film = render(embree(PathLoop::Auto), &scene, (16, 16), &q, 256);
            let what = format!("wide loop furnace, scale {scale}, normals {smooth}");
            assert_clean(&film, &what);
            assert_mean(&film, 4, 1.0, 4.5, 0.01, &what);
        }
    }
}

#[test]
fn settings_the_wide_loop_does_not_serve_go_to_the_lane_loop() {
    if !common::embree() {
        return;
    }
    let scene = load("cornell-mesh").expect("scene");
    for (what, q) in [
        (
            "NEE off",
            Quality {
                nee: false,
                ..Quality::default()
            },
        ),
        (
            "denoiser features",
            Quality {
                denoise: Denoise::Final,
                ..Quality::default()
            },
        ),
    ] {
        let lanes = render(embree(PathLoop::Lanes), &scene, (24, 16), &q, 8);
        let auto = render(embree(PathLoop::Auto), &scene, (24, 16), &q, 8);
        assert!(
            auto.pixels() == lanes.pixels(),
            "{what}: not the lane loop's image"
        );
    }
}
