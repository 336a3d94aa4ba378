//! Numerical stability at the extremes. Each case states what must hold;
//! every case runs on every backend (rayon, and OpenCL where a device is
//! present; where CI is set a missing OpenCL device fails the suite).
//! Nothing here may put NaN/Inf in the film, panic, or give a wrong answer.
//! Scale, distance and touching surfaces here; grazing rays (`grazing`);
//! the ends of every range (`limits`).

#[path = "../common/mod.rs"]
mod common;
mod grazing;
mod limits;

use common::{
    assert_agree, assert_clean, assert_mean, assert_region, furnace, region, render_on, scene,
};
use pathstream::render::math::DVec3;
use pathstream::render::scene::{GlassJson, MaterialJson, ObjectJson, SphereJson, SurfaceJson};
use pathstream::render::{Backend, BackendChoice, Film, Quality, Scene};

/// Every backend this machine has.
fn backends() -> Vec<Backend> {
    let mut list = vec![Backend::choose(BackendChoice::Cpu).expect("cpu")];
    match Backend::choose(BackendChoice::OpenCl { device: None }) {
        Ok(b) => list.push(b),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => eprintln!("extremes: OpenCL skipped: {e}"),
    }
    list
}

fn q(seed: u64) -> Quality {
    Quality {
        seed,
        ..Quality::default()
    }
}

/// Scene scale: cornell-glass scaled by 1e-4 .. 1e6 renders the same image.
#[test]
fn scene_scale_from_1e_minus_4_to_1e6() {
    let base = scene("cornell-glass");
    for mut b in backends() {
        let reference = render_on(&mut b, &base, 16, 16, &q(1), 256);
        for factor in [1e-4, 1e-2, 1e2, 1e4, 1e6] {
            let film = render_on(&mut b, &base.scaled(factor), 16, 16, &q(2), 256);
            assert_clean(&film, "scaled");
            assert_agree(
                &reference,
                &film,
                8,
                4.5,
                0.0,
                &format!("{} scaled by {factor:e}", b.name()),
            );
        }
    }
}

/// Distance from the origin: the scene moved 1e3, 1e5, 1e6 away renders the same.
#[test]
fn scene_far_from_the_origin() {
    let base = scene("cornell-glass");
    for mut b in backends() {
        let reference = render_on(&mut b, &base, 16, 16, &q(3), 256);
        for d in [1e3, 1e5, 1e6] {
            let film = render_on(
                &mut b,
                &base.translated(DVec3::new(d, -d, d)),
                16,
                16,
                &q(4),
                256,
            );
            assert_clean(&film, "moved");
            assert_agree(
                &reference,
                &film,
                8,
                4.5,
                0.0,
                &format!("{} moved {d:e}", b.name()),
            );
        }
    }
}

fn ball_on_floor(floor: ObjectJson) -> Scene {
    let json = serde_json::json!({
        "camera": {"position": [0, 1.5, 5], "look_at": [0, 0.5, 0], "vfov_deg": 45},
        "materials": {
            "floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "ball": {"type": "diffuse", "albedo": [0.7, 0.2, 0.2]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [30, 30, 30]}
        },
        "objects": [
            serde_json::to_value(floor).expect("floor"),
            {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "ball"},
            {"type": "sphere", "center": [1, 3, 1], "radius": 0.3, "material": "lamp"}
        ]
    });
    Scene::from_json_value(json).expect("valid")
}

/// A sphere of radius 1e7 as a floor renders as the plane it approximates.
#[test]
fn a_radius_1e7_sphere_as_a_floor() {
    let sphere_floor = ball_on_floor(ObjectJson::Sphere(SphereJson {
        center: [0.0, -1e7, 0.0],
        radius: 1e7,
        material: "floor".into(),
    }));
    let quad_floor = ball_on_floor(ObjectJson::Quad(pathstream::render::scene::QuadJson {
        corner: [-1e3, 0.0, -1e3],
        edge_u: [0.0, 0.0, 2e3],
        edge_v: [2e3, 0.0, 0.0],
        material: "floor".into(),
    }));
    for mut b in backends() {
        let a = render_on(&mut b, &sphere_floor, 16, 16, &q(5), 256);
        let c = render_on(&mut b, &quad_floor, 16, 16, &q(6), 256);
        assert_clean(&a, "1e7 floor");
        assert_agree(
            &a,
            &c,
            8,
            4.5,
            0.0,
            &format!("{}: 1e7 sphere floor vs plane", b.name()),
        );
    }
}

/// Pixels much darker than the mean of their 8 neighbours: acne on a flat,
/// smoothly lit surface.
fn acne_pixels(film: &Film) -> usize {
    let (w, h) = (film.width() as i64, film.height() as i64);
    let img = film.mean();
    let lum = |x: i64, y: i64| {
        let p = img[(y * w + x) as usize];
        f64::from(p[0] + p[1] + p[2])
    };
    let mut count = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let mut sum = 0.0;
            for (dx, dy) in [
                (-1, -1),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                sum += lum(x + dx, y + dy);
            }
            if lum(x, y) < 0.3 * sum / 8.0 {
                count += 1;
            }
        }
    }
    count
}

/// A furnace shell with another diffuse sphere 4e-5 inside it (touching
/// almost everywhere the camera looks) and a glass sphere inside a glass
/// sphere: every hit found, no acne, radiance exact where known.
#[test]
fn nested_and_touching_spheres() {
    let mut json = furnace(0.5, 0.5).to_json();
    // A second shell 4e-5 inside the first, same material: the image must
    // still be exactly 1 everywhere (it is the same furnace, one layer in).
    json.objects.push(ObjectJson::Sphere(SphereJson {
        center: [0.0, 0.0, 0.0],
        radius: 1.0 - 4e-5,
        material: "shell".into(),
    }));
    let nested = Scene::from_json(&json).expect("valid");
    // Glass inside glass inside the furnace: invisible too.
    let mut json = furnace(0.5, 0.5).to_json();
    json.materials.insert(
        "clear".into(),
        MaterialJson::Glass(GlassJson {
            ior: 1.5,
            albedo: None,
            fresnel: Default::default(),
            attenuation: None,
            emission: None,
            normal: None,
        }),
    );
    json.materials.insert(
        "denser".into(),
        MaterialJson::Glass(GlassJson {
            ior: 2.0,
            albedo: None,
            fresnel: Default::default(),
            attenuation: None,
            emission: None,
            normal: None,
        }),
    );
    json.objects.push(ObjectJson::Sphere(SphereJson {
        center: [0.0, 0.0, -0.5],
        radius: 0.3,
        material: "clear".into(),
    }));
    json.objects.push(ObjectJson::Sphere(SphereJson {
        center: [0.0, 0.0, -0.5],
        radius: 0.15,
        material: "denser".into(),
    }));
    let glass = Scene::from_json(&json).expect("valid");
    for mut b in backends() {
        for depth in [2u32, 5] {
            let expected = 0.5 * (1.0 - 0.5f64.powi(depth as i32 + 1)) / 0.5;
            // Next-event estimation picks one of the two shells per
            // shading point (by power), so a sample is no longer the closed
            // form itself; its mean is. The shells' powers differ by 4e-5:
            // with Sobol points each half of a pixel's samples picks them
            // in exactly equal numbers, except on rare draws, so the two
            // halves agree (a standard error of 1e-9) while the mean is
            // off by ~2e-5 until the rare draws come (measured: 2e-4 at 16
            // spp, 4e-5 at 128, 5e-6 at 1024, always converging): hence a
            // floor of 1e-4.
            let film = render_on(
                &mut b,
                &nested,
                12,
                12,
                &Quality {
                    max_depth: depth,
                    rr_depth: 1000,
                    ..q(7)
                },
                128,
            );
            assert_clean(&film, "nested");
            assert_mean(
                &film,
                4,
                expected,
                4.5,
                1e-4,
                &format!("{}: nested shells depth {depth}", b.name()),
            );
            assert_eq!(acne_pixels(&film), 0, "{}: nested shells: acne", b.name());
        }
        let film = render_on(
            &mut b,
            &glass,
            16,
            16,
            &Quality {
                max_depth: 0,
                rr_depth: 4,
                ..q(8)
            },
            256,
        );
        assert_clean(&film, "glass in glass");
        assert_mean(
            &film,
            4,
            1.0,
            4.5,
            0.0,
            &format!("{}: glass in glass in the furnace", b.name()),
        );
        assert_eq!(acne_pixels(&film), 0, "{}: acne", b.name());
    }
}
