//! Denoising: the feature buffers on every backend (a wall's albedo is its
//! albedo, normals are unit and face the camera, through a mirror the
//! albedo is the mirrored surface's, both backends agree, a render that is
//! not denoised keeps none), and Open Image Denoise itself: at 4, 16 and
//! 64 spp the denoised image is closer to a long reference than the raw
//! one by 2.1-4.1x (measured, 96x96, as displayed; asserted: 1.6x), on
//! `cornell-glass` and on a mesh scene.

mod common;

use common::{backends, bunny, mesh_object, oidn, render, render_on, scene, scene_json};
use pathstream::render::denoise::{self, FilterQuality};
use pathstream::render::features::Features;
use pathstream::render::quality::Denoise;
use pathstream::render::tonemap::displayed_error;
use pathstream::render::{Film, Quality, Scene};
use serde_json::json;

fn guided() -> Quality {
    Quality {
        denoise: Denoise::Final,
        ..Quality::default()
    }
}

fn features(film: &Film, what: &str) -> Features {
    film.feature_means()
        .unwrap_or_else(|| panic!("{what}: the film keeps no features"))
}

fn near(a: [f32; 3], b: [f32; 3], tol: f32) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
}

/// A camera at the origin looking down -z at `objects`, lit by a white sky.
fn view(objects: serde_json::Value, materials: serde_json::Value) -> Scene {
    let json = json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "up": [0, 1, 0], "vfov_deg": 40},
        "materials": materials,
        "objects": objects,
        "environment": [1, 1, 1]
    });
    Scene::from_json_str(&json.to_string()).expect("valid scene")
}

#[test]
fn a_render_that_is_not_denoised_keeps_no_features() {
    for (name, mut backend) in backends() {
        let film = render_on(
            &mut backend,
            &scene("cornell"),
            16,
            12,
            &Quality::default(),
            2,
        );
        assert!(film.feature_sums().is_empty(), "{name}");
        assert!(film.feature_means().is_none(), "{name}");
    }
}

#[test]
fn a_walls_albedo_is_its_albedo_and_its_normal_faces_the_camera() {
    let wall = view(
        json!([{"type": "quad", "corner": [-50, -50, -3], "edge_u": [100, 0, 0], "edge_v": [0, 100, 0], "material": "wall"}]),
        json!({"wall": {"type": "diffuse", "albedo": [0.3, 0.5, 0.7]}}),
    );
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &wall, 24, 16, &guided(), 5);
        let f = features(&film, name);
        for (i, (a, n)) in f.albedo.iter().zip(&f.normal).enumerate() {
            assert!(
                near(*a, [0.3, 0.5, 0.7], 1e-5),
                "{name}: pixel {i}'s albedo {a:?}"
            );
            // The quad's normal on the camera's side is +z.
            assert!(
                near(*n, [0.0, 0.0, 1.0], 1e-5),
                "{name}: pixel {i}'s normal {n:?}"
            );
        }
    }
}

#[test]
fn normals_are_unit_and_face_the_camera_in_the_cornell_box() {
    let cornell = scene("cornell");
    let eye = cornell.camera.position;
    for (name, mut backend) in backends() {
        let (w, h) = (32, 24);
        let film = render_on(&mut backend, &cornell, w, h, &guided(), 4);
        let f = features(&film, name);
        let job = pathstream::render::RenderJob::new(&cornell, w, h, &guided());
        let mut unit = 0;
        for (i, n) in f.normal.iter().enumerate() {
            let len = n.iter().map(|v| v * v).sum::<f32>().sqrt();
            // A mean of unit vectors: at most 1, exactly 1 where every
            // sample met the same flat wall.
            assert!(
                len <= 1.0 + 1e-5,
                "{name}: pixel {i}'s normal {n:?} is longer than 1"
            );
            unit += usize::from(len > 0.999);
            // Facing the camera: towards the eye from what the pixel shows.
            let (x, y) = ((i % w as usize) as f32 + 0.5, (i / w as usize) as f32 + 0.5);
            let d = job.camera.ray(x, y).dir;
            let facing = -(n[0] * d.x + n[1] * d.y + n[2] * d.z);
            assert!(
                facing >= -1e-4,
                "{name}: pixel {i}'s normal {n:?} faces away ({eye:?})"
            );
        }
        assert!(
            unit > f.normal.len() / 2,
            "{name}: only {unit} unit normals"
        );
    }
}

#[test]
fn through_a_mirror_the_albedo_is_the_mirrored_surfaces() {
    // A mirror filling the view; behind the camera, a wall it shows.
    let mirrored = view(
        json!([
            {"type": "quad", "corner": [-50, -50, -2], "edge_u": [100, 0, 0], "edge_v": [0, 100, 0], "material": "mirror"},
            {"type": "quad", "corner": [-500, -500, 6], "edge_u": [1000, 0, 0], "edge_v": [0, 1000, 0], "material": "wall"}
        ]),
        json!({
            "mirror": {"type": "mirror", "albedo": [0.9, 0.8, 0.5]},
            "wall": {"type": "diffuse", "albedo": [0.2, 0.6, 0.4]}
        }),
    );
    let expected = [0.9 * 0.2, 0.8 * 0.6, 0.5 * 0.4];
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &mirrored, 16, 12, &guided(), 3);
        let f = features(&film, name);
        for (i, (a, n)) in f.albedo.iter().zip(&f.normal).enumerate() {
            assert!(
                near(*a, expected, 1e-5),
                "{name}: pixel {i}'s albedo {a:?}, not {expected:?}"
            );
            // The wall seen from the mirror's side: its normal is -z.
            assert!(
                near(*n, [0.0, 0.0, -1.0], 1e-5),
                "{name}: pixel {i}'s normal {n:?}"
            );
        }
    }
}

#[test]
fn both_backends_find_the_same_features() {
    let cornell_glass = scene("cornell-glass");
    let films: Vec<(&str, Features)> = backends()
        .into_iter()
        .map(|(name, mut b)| {
            let film = render_on(&mut b, &cornell_glass, 48, 36, &guided(), 8);
            (name, features(&film, name))
        })
        .collect();
    let Some(((_, cpu), (_, cl))) = films.first().zip(films.get(1)) else {
        return; // no OpenCL device here (under CI, `backends` fails instead)
    };
    // The same samples on both: only rounding may send a path elsewhere.
    let differ = (cpu.albedo.iter().zip(&cl.albedo))
        .chain(cpu.normal.iter().zip(&cl.normal))
        .filter(|(a, b)| !near(**a, **b, 1e-3))
        .count();
    let all = cpu.albedo.len() * 2;
    assert!(
        differ * 100 <= all,
        "{differ} of {all} feature pixels differ by more than 1e-3"
    );
}

/// The relative RMS error, as displayed (`tonemap::displayed_error`), of
/// the raw and the denoised image of `scene` at each of `spps`, against a
/// reference of `ref_spp`.
fn errors(scene: &Scene, (w, h): (u32, u32), spps: &[u64], ref_spp: u64) -> Vec<(u64, f64, f64)> {
    let reference = render(scene, w, h, &Quality::default(), ref_spp);
    let truth = reference.mean();
    spps.iter()
        .map(|&spp| {
            let q = Quality {
                seed: 7 + spp,
                ..guided()
            };
            let film = render(scene, w, h, &q, spp);
            let raw = film.mean();
            let f = film.feature_means();
            let clean =
                denoise::denoise(w, h, &raw, f.as_ref(), FilterQuality::High).expect("denoised");
            let e_raw = displayed_error(&raw, &truth);
            let e_clean = displayed_error(&clean, &truth);
            eprintln!(
                "{spp} spp: raw {e_raw:.4}, denoised {e_clean:.4}, ratio {:.2}",
                e_raw / e_clean
            );
            (spp, e_raw, e_clean)
        })
        .collect()
}

/// Asserts each denoised error is at most the raw one over `factor`.
fn assert_cut(what: &str, rows: &[(u64, f64, f64)], factor: f64) {
    for &(spp, raw, clean) in rows {
        assert!(
            clean * factor <= raw,
            "{what} at {spp} spp: denoised error {clean:.4} is not {factor}x below the raw {raw:.4}"
        );
    }
}

#[test]
fn denoising_cuts_the_error_of_cornell_glass() {
    if !oidn() {
        return;
    }
    let rows = errors(&scene("cornell-glass"), (96, 96), &[4, 16, 64], 2048);
    assert_cut("cornell-glass", &rows, 1.6);
}

#[test]
fn denoising_cuts_the_error_of_a_mesh_scene() {
    if !oidn() {
        return;
    }
    let Some(bunny) = bunny() else {
        return;
    };
    let mut json = scene_json("cornell");
    json["materials"]["clay"] = json!({"type": "diffuse", "albedo": [0.7, 0.6, 0.5]});
    let transform = json!({"translate": [55, 0, 85], "scale": 3});
    json["objects"]
        .as_array_mut()
        .expect("objects")
        .push(mesh_object(&bunny, "clay", transform, true));
    let scene = Scene::from_json_str(&json.to_string()).expect("cornell with a bunny");
    let rows = errors(&scene, (96, 96), &[4, 16, 64], 2048);
    assert_cut("a bunny in the cornell box", &rows, 1.6);
}
