//! Numerical stability at the extremes. Each case states what must hold;
//! every case runs on every backend (rayon, and OpenCL where a device is
//! present; where CI is set a missing OpenCL device fails the suite).
//! Nothing here may put NaN/Inf in the film, panic, or give a wrong answer.

mod common;

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

/// The direction through raster position (`x`, `y`) of a `w` x `h` image
/// (the pinhole camera of `render::camera`, in f64), not normalised.
fn camera_dir(cam: &pathstream::render::scene::Camera, w: u32, h: u32, x: f64, y: f64) -> DVec3 {
    let forward = (cam.look_at - cam.position).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    let extent = 2.0 * (cam.vfov_deg.to_radians() / 2.0).tan();
    forward
        + right * (extent * f64::from(w) / f64::from(h) * (x / f64::from(w) - 0.5))
        + up * (extent * (0.5 - y / f64::from(h)))
}

/// Grazing rays, part one: a camera 1e-3 above a lit floor, looking along
/// it. With one bounce (emitters seen directly plus direct light), a floor
/// point p under a sphere light of radiance L, radius r and centre c
/// reflects exactly albedo L r^2 cos(theta) / |c - p|^2. The rows below the
/// horizon see points within 0.03 of the camera's foot, where this varies
/// by less than 1%, so each region must match it (pixel centres, 1% floor).
#[test]
fn grazing_rays_along_a_floor() {
    let (albedo, radiance, radius, lamp) = (0.7, 20.0, 1.0, DVec3::new(0.0, 5.0, 0.0));
    let json = serde_json::json!({
        "camera": {"position": [0, 1e-3, 5], "look_at": [0, 1e-3, 0], "vfov_deg": 60},
        "materials": {
            "floor": {"type": "diffuse", "albedo": [albedo, albedo, albedo]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [radiance, radiance, radiance]}
        },
        "objects": [
            {"type": "quad", "corner": [-50, 0, -50], "edge_u": [0, 0, 100], "edge_v": [100, 0, 0], "material": "floor"},
            {"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "floor"},
            {"type": "sphere", "center": lamp.to_array(), "radius": radius, "material": "lamp"}
        ]
    });
    let along = Scene::from_json_value(json).expect("valid");
    let quality = Quality {
        max_depth: 1,
        filter: pathstream::render::Filter::Box,
        ..q(9)
    };
    let expected = |x: u32, y: u32| {
        let d = camera_dir(
            &along.camera,
            32,
            32,
            f64::from(x) + 0.5,
            f64::from(y) + 0.5,
        );
        let p = along.camera.position + d * (along.camera.position.y / -d.y);
        let to_lamp = lamp - p;
        albedo * radiance * radius * radius * (to_lamp.y / to_lamp.length())
            / to_lamp.length_squared()
    };
    for mut b in backends() {
        let film = render_on(&mut b, &along, 32, 32, &quality, 64);
        assert_clean(&film, "camera along a wall");
        // Rows 17.. look at least 2 degrees down (row 16 reaches the horizon).
        for y0 in (17..32).step_by(5) {
            for x0 in (0..32).step_by(8) {
                let (xs, ys) = (x0..x0 + 8, y0..y0 + 5);
                let want = ys
                    .clone()
                    .flat_map(|y| xs.clone().map(move |x| (x, y)))
                    .map(|(x, y)| expected(x, y))
                    .sum::<f64>()
                    / 40.0;
                assert_region(
                    &region(&film, xs, ys),
                    want,
                    4.5,
                    0.01 * want,
                    &format!("{}: floor at columns {x0}.., rows {y0}..", b.name()),
                );
            }
        }
    }
}

/// Grazing rays, part two: rays tangent to a sphere. A diffuse ball (albedo
/// a = 0.5) inside a black shell that emits 1 everywhere: every point of the
/// ball sees only the shell, so it reflects exactly a; the shell is 1. A
/// pixel is then 1 - (1 - a) x (the part of it the ball covers), computed
/// here in f64 on a 64x64 grid per pixel (box filter). A bounce from a
/// grazing hit that wrongly hits the ball again gives a^2 and darkens the
/// silhouette; a missed tangent hit brightens it. NEE off: every sample of a
/// pixel the ball covers wholly or not at all is exact.
#[test]
fn grazing_rays_tangent_to_a_sphere() {
    let (center, radius, a) = (DVec3::new(0.1, -0.05, -0.6), 0.2, 0.5);
    let mut json = furnace(0.0, 1.0).to_json();
    json.materials.insert(
        "ball".into(),
        MaterialJson::Diffuse(SurfaceJson {
            albedo: [a; 3].into(),
            emission: None,
            normal: None,
            alpha: None,
        }),
    );
    json.objects.push(ObjectJson::Sphere(SphereJson {
        center: center.to_array(),
        radius,
        material: "ball".into(),
    }));
    let s = Scene::from_json(&json).expect("valid");
    let n = 24u32;
    const GRID: u32 = 64;
    let coverage: Vec<f64> = (0..n * n)
        .map(|i| {
            let (x, y) = (i % n, i / n);
            let mut hits = 0u32;
            for sy in 0..GRID {
                for sx in 0..GRID {
                    let sub = |k: u32| (f64::from(k) + 0.5) / f64::from(GRID);
                    let d = camera_dir(
                        &s.camera,
                        n,
                        n,
                        f64::from(x) + sub(sx),
                        f64::from(y) + sub(sy),
                    )
                    .normalize();
                    let along = center.dot(d);
                    hits += u32::from(
                        along > 0.0 && center.length_squared() - along * along <= radius * radius,
                    );
                }
            }
            f64::from(hits) / f64::from(GRID * GRID)
        })
        .collect();
    let partial = coverage.iter().filter(|c| **c > 0.0 && **c < 1.0).count();
    assert!(partial > 40, "the silhouette crosses {partial} pixels");
    let expected = |x: u32, y: u32| 1.0 - (1.0 - a) * coverage[(y * n + x) as usize];
    for mut b in backends() {
        for nee in [false, true] {
            let quality = Quality {
                max_depth: 3,
                rr_depth: 100,
                nee,
                filter: pathstream::render::Filter::Box,
                ..q(10)
            };
            let film = render_on(&mut b, &s, n, n, &quality, 256);
            let what = format!("{} nee {nee}", b.name());
            assert_clean(&film, &what);
            let img = film.mean();
            for (i, c) in coverage.iter().enumerate() {
                if !nee && (*c == 0.0 || *c == 1.0) {
                    let v = f64::from(img[i][1]);
                    assert!(
                        (v - (1.0 - (1.0 - a) * c)).abs() < 1e-5,
                        "{what}: pixel {i} (coverage {c}): {v}"
                    );
                }
            }
            for y0 in (0..n).step_by(6) {
                for x0 in (0..n).step_by(6) {
                    let want = (y0..y0 + 6)
                        .flat_map(|y| (x0..x0 + 6).map(move |x| (x, y)))
                        .map(|(x, y)| expected(x, y))
                        .sum::<f64>()
                        / 36.0;
                    let r = region(&film, x0..x0 + 6, y0..y0 + 6);
                    assert_region(
                        &r,
                        want,
                        5.0,
                        2e-3,
                        &format!("{what}: silhouette region at ({x0}, {y0})"),
                    );
                }
            }
        }
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
        // A light of radius 1e-4 gives the room the same light as one of
        // radius 0.1 of equal power (radiance x r^2). Both sit in a corner
        // the camera cannot see, so only the light they cast is compared;
        // at 1.0 from the nearest wall the bigger one's size changes that
        // by well under the 2% floor.
        let corner = DVec3::new(2.5, 79.0, 160.0);
        let at = |radius: f64| {
            let mut s = with_light((7.0 / radius).powi(2), radius);
            let light = s.light.expect("light");
            s.objects[light].shape = pathstream::render::scene::Shape::Sphere {
                center: corner,
                radius,
            };
            Scene::from_json(&s.to_json()).expect("valid")
        };
        let tiny = render_on(&mut b, &at(1e-4), 16, 16, &q(12), 256);
        let small = render_on(&mut b, &at(0.1), 16, 16, &q(13), 256);
        assert_clean(&tiny, "tiny light");
        assert!(
            common::regions(&small, 16)[0].mean[1] > 0.01,
            "the corner light lights the room"
        );
        assert_agree(
            &small,
            &tiny,
            8,
            4.5,
            0.02,
            &format!(
                "{}: a radius-1e-4 light vs one of radius 0.1 and equal power",
                b.name()
            ),
        );
    }
    // The camera inside a light: the emissive shell of the furnace seen from
    // inside, and a point on the light's own surface (the shell's inner side)
    // receiving NEE from it: the furnace is exact, checked elsewhere too.
    for mut b in backends() {
        let film = render_on(
            &mut b,
            &furnace(0.5, 0.5),
            8,
            8,
            &Quality {
                max_depth: 3,
                rr_depth: 100,
                ..q(13)
            },
            4,
        );
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
        json.materials.insert(
            "g".into(),
            MaterialJson::Glass(GlassJson {
                ior,
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
            material: "g".into(),
        }));
        let s = Scene::from_json(&json).expect("valid");
        for mut b in backends() {
            let film = render_on(
                &mut b,
                &s,
                12,
                12,
                &Quality {
                    max_depth: 0,
                    rr_depth: 4,
                    ..q(14)
                },
                256,
            );
            assert_clean(&film, "glass");
            assert_mean(
                &film,
                4,
                1.0,
                4.5,
                0.0,
                &format!("{}: ior {ior} in the furnace", b.name()),
            );
        }
    }
}

/// Resolutions 1x1, 1x4096 and 4096x1: in the depth-capped furnace every
/// pixel is exactly E (1 - a^(D+1)) / (1 - a) (so every pixel is rendered
/// and none twice); and with the box filter the one pixel of a 1x1 image
/// sees the whole frame: its value is the mean of a 16x16 image of it.
#[test]
fn extreme_resolutions() {
    let hot = furnace(0.5, 0.5);
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(15)
    };
    let cornell = scene("cornell");
    let boxed = Quality {
        filter: pathstream::render::Filter::Box,
        ..q(15)
    };
    for mut b in backends() {
        for (w, h) in [(1, 1), (1, 4096), (4096, 1)] {
            let film = render_on(&mut b, &hot, w, h, &capped, 2);
            assert_clean(&film, "resolution");
            assert_eq!(film.mean().len(), (w * h) as usize);
            for (i, v) in film.mean().iter().flatten().enumerate() {
                assert!(
                    (f64::from(*v) - 0.9375).abs() < 1e-5,
                    "{}: {w}x{h}: value {i}: {v}",
                    b.name()
                );
            }
        }
        // Sixteen 1x1 renders with their own seeds: a mean and a standard
        // error with 15 degrees of freedom (one pixel's even/odd halves give 1).
        let ones: Vec<f64> = (0..16u64)
            .map(|k| {
                f64::from(
                    render_on(
                        &mut b,
                        &cornell,
                        1,
                        1,
                        &Quality {
                            seed: 100 + k,
                            ..boxed
                        },
                        64,
                    )
                    .mean()[0][1],
                )
            })
            .collect();
        let one = ones.iter().sum::<f64>() / 16.0;
        let one_var = ones.iter().map(|v| (v - one).powi(2)).sum::<f64>() / 15.0 / 16.0;
        let many = region(
            &render_on(&mut b, &cornell, 16, 16, &boxed, 16),
            0..16,
            0..16,
        );
        let z = (one - many.mean[1]).abs() / (one_var + many.var[1]).sqrt();
        assert!(
            z < 4.5,
            "{}: a 1x1 image {one} vs the mean of a 16x16 one {} ({z:.1} standard errors)",
            b.name(),
            many.mean[1]
        );
    }
}

/// Samples and seeds: one sample is already exact where the answer is
/// (the furnace), 1 then 3 samples are the same film as 4 at once, and
/// there is no error estimate before the second; seeds 0 and u64::MAX
/// are valid, differ, and converge to the same image.
#[test]
fn one_sample_and_extreme_seeds() {
    let s = scene("cornell");
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(0)
    };
    for mut b in backends() {
        let film = render_on(&mut b, &furnace(0.5, 0.5), 8, 8, &capped, 1);
        assert_eq!(film.error_estimate(), None);
        for v in film.mean().iter().flatten() {
            assert!(
                (f64::from(*v) - 0.9375).abs() < 1e-5,
                "{}: 1 spp in the furnace: {v}",
                b.name()
            );
        }
        let job = pathstream::render::RenderJob::new(&s, 8, 8, &q(0));
        let mut stepwise = Film::new(8, 8);
        b.render(&job, &mut stepwise, 1).expect("render");
        assert_clean(&stepwise, "1 spp");
        assert_eq!(stepwise.error_estimate(), None);
        b.render(&job, &mut stepwise, 3).expect("render");
        assert!(stepwise.error_estimate().is_some());
        let at_once = render_on(&mut b, &s, 8, 8, &q(0), 4);
        assert_eq!(
            stepwise.pixels(),
            at_once.pixels(),
            "{}: 1 + 3 samples vs 4",
            b.name()
        );

        let max = render_on(&mut b, &s, 16, 16, &q(u64::MAX), 32);
        let zero = render_on(&mut b, &s, 16, 16, &q(0), 32);
        assert_clean(&max, "seed max");
        assert_ne!(max.pixels(), zero.pixels(), "{}", b.name());
        assert_agree(
            &zero,
            &max,
            8,
            4.5,
            0.0,
            &format!("{}: seed 0 vs seed u64::MAX", b.name()),
        );
    }
}

/// Quality knobs at their ends, in the furnace (radiance 1 per bounce
/// series, so each has a closed form): max depth 1 gives E (1 + a) = 0.75,
/// max depth 10000 without roulette 1 - 0.5^10001 = 1; a clamp of 1e-6
/// makes every sample 1e-6, one of 1e30 changes nothing. On cornell-glass
/// they stay finite, and the clamp of 1e30 gives the very film of no clamp.
#[test]
fn quality_knobs_at_their_ends() {
    let hot = furnace(0.5, 0.5);
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(16)
    };
    let cases = [
        (
            Quality {
                max_depth: 1,
                ..q(16)
            },
            0.75,
        ),
        (
            Quality {
                max_depth: 10_000,
                rr_depth: 10_000,
                ..q(16)
            },
            1.0,
        ),
        (
            Quality {
                clamp: 1e-6,
                ..capped
            },
            1e-6,
        ),
        (
            Quality {
                clamp: 1e30,
                ..capped
            },
            0.9375,
        ),
    ];
    let glass = scene("cornell-glass");
    for mut b in backends() {
        for (quality, expected) in cases {
            let film = render_on(&mut b, &hot, 8, 8, &quality, 4);
            assert_clean(&film, "knobs");
            for v in film.mean().iter().flatten() {
                assert!(
                    (f64::from(*v) - expected).abs() <= 1e-5 * expected,
                    "{}: {quality:?}: {v} vs {expected}",
                    b.name()
                );
            }
            let film = render_on(&mut b, &glass, 8, 8, &quality, 8);
            assert_clean(&film, "knobs on cornell-glass");
        }
        let huge = render_on(
            &mut b,
            &glass,
            8,
            8,
            &Quality {
                clamp: 1e30,
                ..q(17)
            },
            8,
        );
        let off = render_on(&mut b, &glass, 8, 8, &q(17), 8);
        assert_eq!(
            huge.pixels(),
            off.pixels(),
            "{}: a clamp no sample reaches",
            b.name()
        );
    }
}

/// Out-of-range input is refused with a message, never rendered wrongly.
#[test]
fn out_of_range_is_refused() {
    assert!(Quality {
        max_depth: 100_001,
        ..Quality::default()
    }
    .validate()
    .is_err());
    assert!(pathstream::render::job::check_size(0, 1).is_err());
    assert!(pathstream::render::job::check_size(4097, 4097).is_err());
    let mut json = scene("cornell").to_json();
    json.materials.insert(
        "hot".into(),
        MaterialJson::Diffuse(SurfaceJson {
            albedo: [0.5; 3].into(),
            emission: Some([1e21; 3].into()),
            normal: None,
            alpha: None,
        }),
    );
    assert!(Scene::from_json(&json).is_err());
}
