//! Grazing rays: along a floor, and tangent to a sphere.

use super::*;

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
