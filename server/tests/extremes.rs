//! Numerical stability at the extremes. Each case states what must hold;
//! every case runs on every backend (rayon, and OpenCL where a device is
//! present; where CI is set a missing OpenCL device fails the suite).
//! Nothing here may put NaN/Inf in the film, panic, or give a wrong answer.

mod common;

use common::{assert_agree, assert_clean, assert_mean, furnace, render_on, scene};
use pathstream::render::math::DVec3;
use pathstream::render::scene::{GlassJson, MaterialJson, ObjectJson, SphereJson, SurfaceJson};
use pathstream::render::{Backend, BackendChoice, Film, Quality, Scene};

/// Every backend this machine has.
fn backends() -> Vec<Backend> {
    let mut list = vec![Backend::choose(BackendChoice::Cpu).expect("cpu")];
    match Backend::choose(BackendChoice::OpenCl { device: None }) {
        Ok(b) => list.push(b),
        Err(e) if std::env::var_os("CI").is_some() => panic!("CI is set but there is no OpenCL device: {e}"),
        Err(e) => eprintln!("extremes: OpenCL skipped: {e}"),
    }
    list
}

fn q(seed: u64) -> Quality {
    Quality { seed, ..Quality::default() }
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
            assert_agree(&reference, &film, 8, 4.5, 0.0, &format!("{} scaled by {factor:e}", b.name()));
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
            let film = render_on(&mut b, &base.translated(DVec3::new(d, -d, d)), 16, 16, &q(4), 256);
            assert_clean(&film, "moved");
            assert_agree(&reference, &film, 8, 4.5, 0.0, &format!("{} moved {d:e}", b.name()));
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
        assert_agree(&a, &c, 8, 4.5, 0.0, &format!("{}: 1e7 sphere floor vs plane", b.name()));
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
            for (dx, dy) in [(-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1)] {
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
    json.objects.push(ObjectJson::Sphere(SphereJson { center: [0.0, 0.0, 0.0], radius: 1.0 - 4e-5, material: "shell".into() }));
    let nested = Scene::from_json(&json).expect("valid");
    // Glass inside glass inside the furnace: invisible too.
    let mut json = furnace(0.5, 0.5).to_json();
    json.materials.insert("clear".into(), MaterialJson::Glass(GlassJson { ior: 1.5, albedo: None, fresnel: Default::default(), emission: None }));
    json.materials.insert("denser".into(), MaterialJson::Glass(GlassJson { ior: 2.0, albedo: None, fresnel: Default::default(), emission: None }));
    json.objects.push(ObjectJson::Sphere(SphereJson { center: [0.0, 0.0, -0.5], radius: 0.3, material: "clear".into() }));
    json.objects.push(ObjectJson::Sphere(SphereJson { center: [0.0, 0.0, -0.5], radius: 0.15, material: "denser".into() }));
    let glass = Scene::from_json(&json).expect("valid");
    for mut b in backends() {
        for depth in [2u32, 5] {
            let expected = 0.5 * (1.0 - 0.5f64.powi(depth as i32 + 1)) / 0.5;
            // Next-event estimation picks one of the two shells per
            // shading point (by power), so a sample is no longer the closed
            // form itself; its mean is.
            let film = render_on(&mut b, &nested, 12, 12, &Quality { max_depth: depth, rr_depth: 1000, ..q(7) }, 128);
            assert_clean(&film, "nested");
            assert_mean(&film, 4, expected, 4.5, 1e-6, &format!("{}: nested shells depth {depth}", b.name()));
            assert_eq!(acne_pixels(&film), 0, "{}: nested shells: acne", b.name());
        }
        let film = render_on(&mut b, &glass, 16, 16, &Quality { max_depth: 0, rr_depth: 4, ..q(8) }, 256);
        assert_clean(&film, "glass in glass");
        assert_mean(&film, 4, 1.0, 4.5, 0.0, &format!("{}: glass in glass in the furnace", b.name()));
        assert_eq!(acne_pixels(&film), 0, "{}: acne", b.name());
    }
}

/// Grazing rays: a camera looking along a wall, and rays tangent to spheres.
#[test]
fn grazing_rays() {
    // The camera sits 1e-3 above a lit floor, looking along it.
    let json = serde_json::json!({
        "camera": {"position": [0, 1e-3, 5], "look_at": [0, 1e-3, 0], "vfov_deg": 60},
        "materials": {
            "floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [20, 20, 20]}
        },
        "objects": [
            {"type": "quad", "corner": [-50, 0, -50], "edge_u": [0, 0, 100], "edge_v": [100, 0, 0], "material": "floor"},
            {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "floor"},
            {"type": "sphere", "center": [0, 5, 0], "radius": 1, "material": "lamp"}
        ]
    });
    let along = Scene::from_json_value(json).expect("valid");
    for mut b in backends() {
        let film = render_on(&mut b, &along, 32, 32, &q(9), 64);
        assert_clean(&film, "camera along a wall");
        // The floor below the horizon is lit: the bottom rows are not black.
        let img = film.mean();
        let bottom: f64 = img[img.len() - 32..].iter().map(|p| f64::from(p[0])).sum();
        assert!(bottom > 0.0, "{}: floor along the camera unlit", b.name());
    }
    // Tangent rays: the ball's silhouette in smallpt is clean on every backend.
    for mut b in backends() {
        let film = render_on(&mut b, &scene("cornell"), 32, 32, &q(10), 64);
        assert_clean(&film, "tangent rays");
    }
}

/// Lights: intensity 1e-6 .. 1e8 scales the image linearly; a light of
/// radius 1e-4; the camera inside a light; a point on a light's surface.
#[test]
fn extreme_lights() {
    let base = scene("cornell");
    let with_light = |scale: f64, radius: f64| {
        let mut s = base.clone();
        let light = s.light.expect("light");
        let m = s.objects[light].material;
        s.materials[m].emission *= scale;
        if let pathstream::render::scene::Shape::Sphere { center, .. } = s.objects[light].shape {
            s.objects[light].shape = pathstream::render::scene::Shape::Sphere { center, radius };
        }
        Scene::from_json(&s.to_json()).expect("valid")
    };
    for mut b in backends() {
        // Same seed: every sample's path is the same, so the image scales
        // exactly (up to f32 rounding).
        let one = render_on(&mut b, &with_light(1.0, 7.0), 8, 8, &q(11), 16).mean();
        for scale in [1e-6, 1e-3, 1e3, 1e8] {
            let film = render_on(&mut b, &with_light(scale, 7.0), 8, 8, &q(11), 16);
            assert_clean(&film, "intensity");
            for (a, s) in one.iter().zip(film.mean()) {
                for c in 0..3 {
                    let expect = f64::from(a[c]) * scale;
                    assert!(
                        (f64::from(s[c]) - expect).abs() <= 1e-4 * expect.abs() + 1e-30,
                        "{}: scale {scale:e}: {} vs {expect}",
                        b.name(),
                        s[c]
                    );
                }
            }
        }
        // A light of radius 1e-4 as bright in total: power ~ E r^2, so scale E.
        let tiny = with_light((7.0f64 / 1e-4).powi(2), 1e-4);
        let film = render_on(&mut b, &tiny, 16, 16, &q(12), 64);
        assert_clean(&film, "tiny light");
        let mean: f64 = film.mean().iter().map(|p| f64::from(p[1])).sum::<f64>() / 256.0;
        assert!(mean > 0.01, "{}: a radius-1e-4 light lights the room ({mean})", b.name());
    }
    // The camera inside a light: the emissive shell of the furnace seen from
    // inside, and a point on the light's own surface (the shell's inner side)
    // receiving NEE from it: the furnace is exact, checked elsewhere too.
    for mut b in backends() {
        let film = render_on(&mut b, &furnace(0.5, 0.5), 8, 8, &Quality { max_depth: 3, rr_depth: 100, ..q(13) }, 4);
        for v in film.mean().into_iter().flatten() {
            assert!((f64::from(v) - 0.9375).abs() < 1e-5, "{}: {v}", b.name());
        }
    }
}

/// Glass: ior 1.0 is invisible, 1.0001 nearly so; ior 4.0 and total internal
/// reflection stay finite and energy-conserving in the furnace.
#[test]
fn extreme_glass() {
    for ior in [1.0, 1.0001, 4.0] {
        let mut json = furnace(0.5, 0.5).to_json();
        json.materials.insert("g".into(), MaterialJson::Glass(GlassJson { ior, albedo: None, fresnel: Default::default(), emission: None }));
        json.objects.push(ObjectJson::Sphere(SphereJson { center: [0.0, 0.0, -0.5], radius: 0.3, material: "g".into() }));
        let s = Scene::from_json(&json).expect("valid");
        for mut b in backends() {
            let film = render_on(&mut b, &s, 12, 12, &Quality { max_depth: 0, rr_depth: 4, ..q(14) }, 256);
            assert_clean(&film, "glass");
            assert_mean(&film, 4, 1.0, 4.5, 0.0, &format!("{}: ior {ior} in the furnace", b.name()));
        }
    }
}

/// Resolutions 1x1, 1x4096 and 4096x1.
#[test]
fn extreme_resolutions() {
    let s = scene("cornell");
    for mut b in backends() {
        for (w, h) in [(1, 1), (1, 4096), (4096, 1)] {
            let film = render_on(&mut b, &s, w, h, &q(15), 2);
            assert_clean(&film, "resolution");
            assert_eq!(film.mean().len(), (w * h) as usize);
            assert!(film.mean().iter().any(|p| p[0] > 0.0), "{}: {w}x{h} is black", b.name());
        }
    }
}

/// Samples and seeds: 1 spp works (no error estimate yet); seeds 0 and
/// u64::MAX are valid and differ.
#[test]
fn one_sample_and_extreme_seeds() {
    let s = scene("cornell");
    for mut b in backends() {
        let film = render_on(&mut b, &s, 8, 8, &q(0), 1);
        assert_clean(&film, "1 spp");
        assert_eq!(film.error_estimate(), None);
        let max = render_on(&mut b, &s, 8, 8, &q(u64::MAX), 4);
        let zero = render_on(&mut b, &s, 8, 8, &q(0), 4);
        assert_clean(&max, "seed max");
        assert_ne!(max.pixels(), zero.pixels(), "{}", b.name());
    }
}

/// Quality knobs at their ends: max depth 1 and 10000, clamp tiny and huge.
#[test]
fn quality_knobs_at_their_ends() {
    let s = scene("cornell-glass");
    for mut b in backends() {
        for quality in [
            Quality { max_depth: 1, ..q(16) },
            Quality { max_depth: 10_000, rr_depth: 10_000, ..q(16) },
            Quality { clamp: 1e-6, ..q(16) },
            Quality { clamp: 1e30, ..q(16) },
        ] {
            let film = render_on(&mut b, &s, 8, 8, &quality, 8);
            assert_clean(&film, "knobs");
            if quality.clamp > 0.0 && quality.clamp < 1.0 {
                assert!(film.mean().iter().flatten().all(|v| *v <= 1e-6 * 1.0001), "{}: clamp", b.name());
            }
        }
    }
}

/// Out-of-range input is refused with a message, never rendered wrongly.
#[test]
fn out_of_range_is_refused() {
    assert!(Quality { max_depth: 100_001, ..Quality::default() }.validate().is_err());
    assert!(pathstream::render::job::check_size(0, 1).is_err());
    assert!(pathstream::render::job::check_size(4097, 4097).is_err());
    let mut json = scene("cornell").to_json();
    json.materials.insert("hot".into(), MaterialJson::Diffuse(SurfaceJson { albedo: [0.5; 3], emission: Some([1e21; 3]) }));
    assert!(Scene::from_json(&json).is_err());
}
