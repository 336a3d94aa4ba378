//! Meshes rendered, against closed forms and the analytic shapes they
//! approximate; many-light sampling; the environment; the camera's near clip.
//! Every check runs on every backend: rayon, and OpenCL where there is a
//! device (PoCL in CI, where finding none is a failure).

mod common;

use common::{
    assert_agree, assert_clean, assert_mean, mesh_backends, mesh_object, regions, render,
    render_on, scene, scene_json,
};
use pathstream::model::generate::icosphere;
use pathstream::model::MeshData;
use pathstream::render::integrator::LightSampling;
use pathstream::render::{Backend, BackendChoice, Film, Filter, Quality, RenderJob, Scene};
use serde_json::{json, Value};

fn q(seed: u64) -> Quality {
    Quality {
        seed,
        ..Quality::default()
    }
}

/// The camera at the centre of a closed icosphere of radius `scale`.
fn triangle_furnace(levels: u32, scale: f64, smooth: bool) -> Scene {
    let ball = icosphere(levels);
    Scene::from_json_value(json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -scale], "vfov_deg": 100},
        "materials": {"shell": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [0.5, 0.5, 0.5]}},
        "objects": [mesh_object(&ball, "shell", json!({"scale": scale}), smooth)]
    }))
    .expect("valid furnace")
}

#[test]
fn a_closed_triangle_furnace_is_exact_at_every_depth_without_nee() {
    // No path may leak out: every bounce meets the shell, so each sample is
    // E (1 - a^(D+1)) / (1 - a) exactly, at every scale.
    for (backend, mut b) in mesh_backends() {
        for scale in [1e-3, 1.0, 1e3] {
            let s = triangle_furnace(3, scale, false);
            for depth in [1u32, 4, 9] {
                let expected = 0.5 * (1.0 - 0.5f64.powi(depth as i32 + 1)) / 0.5;
                let qq = Quality {
                    max_depth: depth,
                    rr_depth: 1000,
                    nee: false,
                    ..q(1)
                };
                let film = render_on(&mut b, &s, 12, 12, &qq, 16);
                assert_clean(&film, "triangle furnace");
                for v in film.mean().into_iter().flatten() {
                    assert!(
                        (f64::from(v) - expected).abs() < 1e-5,
                        "{backend}: scale {scale} depth {depth}: {v} vs {expected}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_closed_triangle_furnace_has_radiance_one_with_and_without_shading_normals() {
    for (backend, mut b) in mesh_backends() {
        for scale in [1e-3, 1e3] {
            for smooth in [false, true] {
                let s = triangle_furnace(4, scale, smooth);
                for nee in [true, false] {
                    let qq = Quality {
                        max_depth: 0,
                        rr_depth: 2,
                        nee,
                        filter: Filter::Box,
                        ..q(2)
                    };
                    let film = render_on(&mut b, &s, 16, 16, &qq, 256);
                    assert_clean(&film, "triangle furnace");
                    let what = format!("{backend}: scale {scale}, normals {smooth}, nee {nee}");
                    let all: Vec<f64> = film.mean().into_iter().flatten().map(f64::from).collect();
                    let mean = all.iter().sum::<f64>() / all.len() as f64;
                    assert!((mean - 1.0).abs() < 0.01, "{what}: mean radiance {mean}");
                    assert_mean(&film, 4, 1.0, 4.5, 0.01, &what);
                }
            }
        }
    }
}

/// `cornell` with its right ball replaced by an icosphere of 81,920
/// triangles (with shading normals) in the same place.
fn tessellated_cornell() -> Scene {
    let mut j = scene_json("cornell");
    let ball = icosphere(6);
    assert!(ball.triangles.len() >= 80_000);
    let objects = j["objects"].as_array_mut().expect("objects");
    let right = objects
        .iter()
        .position(|o| o["center"] == json!([73.0, 16.5, 78.0]))
        .expect("right ball");
    objects[right] = mesh_object(
        &ball,
        "white",
        json!({"translate": [73, 16.5, 78], "scale": 16.5}),
        true,
    );
    Scene::from_json_value(j).expect("valid")
}

#[test]
fn a_finely_tessellated_sphere_renders_as_the_analytic_sphere() {
    // Icosphere level 6 deviates from the sphere by at most r (1 - cos(0.6
    // deg)) ~ 1e-3 units: far below a pixel here (~0.6 units), so the two
    // images agree within noise.
    let qq = Quality {
        max_depth: 4,
        ..q(3)
    };
    let analytic = render(&scene("cornell"), 32, 32, &qq, 512);
    let tessellated = tessellated_cornell();
    for (backend, mut b) in mesh_backends() {
        let mesh = render_on(
            &mut b,
            &tessellated,
            32,
            32,
            &Quality { seed: 13, ..qq },
            512,
        );
        assert_clean(&mesh, "tessellated");
        assert_agree(
            &analytic,
            &mesh,
            4,
            4.5,
            0.005,
            &format!("{backend}: tessellated vs analytic sphere"),
        );
    }
}

#[test]
fn a_quad_as_two_triangles_renders_as_the_quad() {
    // cornell-quads' floor as a two-triangle mesh.
    let mut j = scene_json("cornell-quads");
    let objects = j["objects"].as_array_mut().expect("objects");
    let floor = objects.iter().position(|o| {
        o["corner"] == json!([1.0, 0.0, 0.0]) && o["edge_v"] == json!([0.0, 0.0, 170.0])
    });
    let floor = floor.expect("the floor quad");
    let o = objects[floor].clone();
    let (c, u, v) = (&o["corner"], &o["edge_u"], &o["edge_v"]);
    let p = |a: f64, b: f64| {
        (0..3)
            .map(|k| {
                c[k].as_f64().unwrap_or(0.0)
                    + a * u[k].as_f64().unwrap_or(0.0)
                    + b * v[k].as_f64().unwrap_or(0.0)
            })
            .collect::<Vec<_>>()
    };
    objects[floor] = json!({"type": "mesh", "material": o["material"],
        "data": {"positions": [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)], "triangles": [[0, 1, 2], [0, 2, 3]]}});
    let two = Scene::from_json_value(j).expect("valid");
    let qq = Quality {
        max_depth: 4,
        ..q(4)
    };
    let a = render(&scene("cornell-quads"), 32, 32, &qq, 256);
    for (backend, mut b) in mesh_backends() {
        let mesh = render_on(&mut b, &two, 32, 32, &Quality { seed: 14, ..qq }, 256);
        assert_agree(
            &a,
            &mesh,
            4,
            4.5,
            0.002,
            &format!("{backend}: two triangles vs the quad"),
        );
    }
}

/// `cornell` lit by an emissive icosphere (320 triangles) instead of its
/// small spherical lamp.
fn mesh_lit_cornell() -> Scene {
    let mut j = scene_json("cornell");
    let objects = j["objects"].as_array_mut().expect("objects");
    let lamp = objects
        .iter()
        .position(|o| o["material"] == "lamp")
        .expect("lamp");
    objects[lamp] = mesh_object(
        &icosphere(2),
        "lamp",
        json!({"translate": [50, 66.6, 81.6], "scale": 7}),
        false,
    );
    Scene::from_json_value(j).expect("valid")
}

fn render_sampling(s: &Scene, qq: &Quality, sampling: LightSampling, spp: u64) -> Film {
    let mut job = RenderJob::new(s, 24, 24, qq);
    job.settings.light_sampling = sampling;
    let mut film = Film::new(24, 24);
    let mut b = Backend::choose(BackendChoice::Cpu).expect("cpu");
    b.render(&job, &mut film, spp).expect("render");
    film
}

#[test]
fn an_emissive_mesh_converges_to_the_same_image_with_and_without_nee() {
    let s = mesh_lit_cornell();
    assert_eq!(s.light, Some(8), "the emissive mesh is the scene's light");
    let off = render(
        &s,
        24,
        24,
        &Quality {
            max_depth: 3,
            nee: false,
            ..q(6)
        },
        4096,
    );
    for (backend, mut b) in mesh_backends() {
        let with_nee = Quality {
            max_depth: 3,
            nee: true,
            ..q(5)
        };
        let on = render_on(&mut b, &s, 24, 24, &with_nee, 1024);
        assert_agree(
            &on,
            &off,
            6,
            4.5,
            0.0,
            &format!("{backend}: emissive mesh, NEE on vs off"),
        );
    }
}

#[test]
fn power_proportional_light_picking_agrees_with_a_ray_to_every_emitter() {
    // 320 emissive triangles plus a second, spherical light.
    let mut j = serde_json::to_value(mesh_lit_cornell().to_json()).expect("json");
    j["objects"]
        .as_array_mut()
        .expect("objects")
        .push(json!({"type": "sphere", "center": [20, 40, 60], "radius": 2, "material": "lamp"}));
    let s = Scene::from_json_value(j).expect("valid");
    let qq = Quality {
        max_depth: 3,
        ..q(7)
    };
    let power = render_sampling(&s, &qq, LightSampling::Power, 1024);
    let all = render_sampling(&s, &qq, LightSampling::All, 64);
    assert_agree(
        &power,
        &all,
        6,
        4.5,
        0.0,
        "one emitter by power vs every emitter",
    );
}

/// A diffuse ball (albedo 0.5) under a uniform environment of radiance 1:
/// every point of a convex body sees the sky over its whole hemisphere, so
/// it reflects exactly 0.5; the background is exactly 1.
fn ball_under_the_sky(mesh: Option<&MeshData>) -> Scene {
    let ball: Value = match mesh {
        Some(m) => mesh_object(m, "grey", Value::Null, false),
        None => json!({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "grey"}),
    };
    Scene::from_json_value(json!({
        "camera": {"position": [0, 0, 6], "look_at": [0, 0, 0], "vfov_deg": 30},
        "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [ball],
        "environment": [1, 1, 1]
    }))
    .expect("valid")
}

#[test]
fn a_convex_ball_under_a_uniform_sky_reflects_albedo_times_sky() {
    for (backend, mut b) in mesh_backends() {
        for (what, s) in [
            ("sphere", ball_under_the_sky(None)),
            ("icosphere", ball_under_the_sky(Some(&icosphere(3)))),
        ] {
            let what = format!("{backend}, {what}");
            let what = what.as_str();
            for nee in [true, false] {
                let qq = Quality {
                    max_depth: 0,
                    nee,
                    filter: Filter::Box,
                    ..q(8)
                };
                let film = render_on(&mut b, &s, 32, 32, &qq, 256);
                assert_clean(&film, what);
                let r = regions(&film, 4);
                // The 8x8 blocks: the centre four lie on the ball, the corners on the sky.
                for &i in &[27usize, 28, 35, 36] {
                    for c in 0..3 {
                        let z = (r[i].mean[c] - 0.5).abs() / r[i].var[c].sqrt().max(1e-9);
                        assert!(
                            z < 4.5,
                            "{what}, nee {nee}: ball block {i}: {} vs 0.5",
                            r[i].mean[c]
                        );
                    }
                }
                for &i in &[0usize, 7, 56, 63] {
                    assert!(
                        (r[i].mean[0] - 1.0).abs() < 1e-6,
                        "{what}: sky block {i}: {}",
                        r[i].mean[0]
                    );
                }
            }
        }
    }
}

#[test]
fn a_mesh_without_emitters_or_camera_is_framed_and_lit_by_default() {
    let s = Scene::from_json_value(json!({
        "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [mesh_object(&icosphere(1), "grey", json!({"translate": [10, 20, 30], "scale": 4}), false)]
    }))
    .expect("valid");
    assert_eq!(s.environment.to_array(), [1.0, 1.0, 1.0]);
    assert!(
        s.warnings.iter().any(|w| w.contains("no emitters")),
        "{:?}",
        s.warnings
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("framed")),
        "{:?}",
        s.warnings
    );
    // Framed: looking at the mesh's centre, which is then in the middle of
    // the image and lit: the centre block is the ball (0.5), not the sky (1).
    let d = s.camera.look_at - glam::DVec3::new(10.0, 20.0, 30.0);
    assert!(d.length() < 0.5, "look_at {:?}", s.camera.look_at);
    for (backend, mut b) in mesh_backends() {
        let qq = Quality {
            max_depth: 0,
            ..q(9)
        };
        let film = render_on(&mut b, &s, 16, 16, &qq, 128);
        let centre = regions(&film, 8)[0].mean[0].min(regions(&film, 8)[3].mean[0]);
        assert!(centre < 0.9, "{backend}: the mesh does not show: {centre}");
    }
    // Round trip: the default environment is now explicit, no new warning.
    let again = s.revalidate(&s.to_json()).expect("revalidate");
    assert_eq!(again.environment, s.environment);
    assert!(!again.warnings.iter().any(|w| w.contains("no emitters")));
}

#[test]
fn smallpt_top_row_is_no_brighter_than_the_row_below() {
    // near_clip along each ray (a sphere), as smallpt: on a plane, the top
    // row's rays would start above the ceiling and see the light.
    let film = render(
        &scene("smallpt"),
        64,
        48,
        &Quality {
            max_depth: 0,
            nee: false,
            ..q(10)
        },
        64,
    );
    let m = film.mean();
    let row = |y: usize| {
        (0..64)
            .map(|x| m[y * 64 + x].iter().map(|v| f64::from(*v)).sum::<f64>())
            .sum::<f64>()
            / 64.0
    };
    assert!(
        row(0) <= row(1) * 1.15,
        "top row {} vs next {}",
        row(0),
        row(1)
    );
}

#[test]
fn mesh_scenes_render_on_the_cpu_when_opencl_is_asked_for_automatically() {
    // `auto` may pick an OpenCL device; a mesh scene must still render (on
    // rayon) rather than fail.
    // Auto always has rayon to fall back on: failing to choose is a fault.
    let mut b = Backend::choose(BackendChoice::Auto).expect("auto chooses a backend");
    let s = mesh_lit_cornell();
    let film = render_on(&mut b, &s, 8, 8, &q(11), 4);
    assert_eq!(film.spp(), 4);
    assert_clean(&film, "auto backend, mesh scene");
}
