//! Orthographic and panoramic cameras and the f-number, on every backend:
//! an orthographic view sees a square the same size at any distance, with
//! edges exactly where the closed form puts them; a 360-degree panorama
//! seen from the centre of an environment map reproduces the map (each
//! pixel the mean of the bilinear lookup over its texel), turned as the
//! camera turns; the kernel's rays are the CPU's within a few ulps; bad
//! fields are named.

mod common;
mod parity;

use common::{backends, render_on};
use parity::assert_camera_rays_agree;
use pathstream::render::envmap::EnvMap;
use pathstream::render::sampler::{mix64, SamplerKind};
use pathstream::render::scene::{CameraEdit, LoadedModel, ModelSource, Resolver};
use pathstream::render::{Filter, Quality, RenderJob, Scene};
use serde_json::{json, Value};
use std::sync::Arc;

fn quality() -> Quality {
    Quality {
        filter: Filter::Box,
        sampler: SamplerKind::Random,
        max_depth: 1,
        ..Quality::default()
    }
}

/// A 2 x 2 emissive square facing the camera, `depth` in front of it,
/// seen by an orthographic camera 4 units tall.
fn square_at(depth: f64) -> Scene {
    let s = json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40,
                   "projection": "orthographic", "ortho_height": 4},
        "materials": {"glow": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [1, 1, 1]}},
        "objects": [{"type": "quad", "corner": [-1, -1, -depth], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "glow"}]
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}

#[test]
fn an_orthographic_view_sees_a_square_the_same_size_at_any_distance() {
    // 4 units over 32 pixels: the square covers columns and rows 8..24
    // exactly, so with a box filter each pixel is 1 or 0, not a fraction.
    for (name, mut backend) in backends() {
        for depth in [1.0, 50.0] {
            let film = render_on(&mut backend, &square_at(depth), 32, 32, &quality(), 8);
            let mean = film.mean();
            for (i, p) in mean.iter().enumerate() {
                let (x, y) = (i % 32, i / 32);
                let inside = (8..24).contains(&x) && (8..24).contains(&y);
                let want = if inside { 1.0 } else { 0.0 };
                assert!(
                    (p[0] - want).abs() < 1e-6,
                    "{name}: depth {depth}: pixel ({x}, {y}) is {}, want {want}",
                    p[0]
                );
            }
        }
    }
}

/// A map held in memory, so that the test knows every texel.
struct OneMap(Arc<EnvMap>);

impl Resolver for OneMap {
    fn resolve(&self, _: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err("no models here".into())
    }

    fn environment(&self, _: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        Ok(self.0.clone())
    }
}

const MW: u32 = 32;
const MH: u32 = 16;

/// Distinct values per texel and channel, far from constant.
fn texel(i: u32, j: u32) -> [f32; 3] {
    let h = |k: u64| (mix64(k) % 1000) as f32 / 1000.0 + 0.1;
    let k = u64::from(j * MW + i);
    [h(3 * k), h(3 * k + 1), h(3 * k + 2)]
}

fn panorama(look_at: [f64; 3], maps: &OneMap) -> Scene {
    let s = json!({
        "camera": {"position": [0, 0, 0], "look_at": look_at, "vfov_deg": 40, "projection": "panorama"},
        "environment": {"map": "test.hdr"},
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        // A scene needs an object: one too small to see (the pole's row
        // of an equirectangular image spans every longitude, so a ball 1
        // milliradian across straight down would darken it by 0.5%).
        "objects": [{"type": "sphere", "center": [0, -1000, 0], "radius": 1e-6, "material": "m"}]
    });
    Scene::from_json_str_with(&s.to_string(), maps).expect("valid scene")
}

/// The mean of the bilinear lookup over texel (i, j)'s cell: weights 1/8,
/// 3/4, 1/8 along each axis, wrapping across the seam, clamped at the
/// poles (as `EnvMap::lookup` is).
fn cell_mean(i: u32, j: u32) -> [f64; 3] {
    let w = [0.125, 0.75, 0.125];
    let mut out = [0.0; 3];
    for (dj, wj) in w.iter().enumerate() {
        for (di, wi) in w.iter().enumerate() {
            let ii = (i as i32 + di as i32 - 1).rem_euclid(MW as i32) as u32;
            let jj = (j as i32 + dj as i32 - 1).clamp(0, MH as i32 - 1) as u32;
            let t = texel(ii, jj);
            for c in 0..3 {
                out[c] += wi * wj * f64::from(t[c]);
            }
        }
    }
    out
}

#[test]
fn a_panorama_from_the_centre_reproduces_the_map_and_turns_with_the_camera() {
    let texels = (0..MH)
        .flat_map(|j| (0..MW).map(move |i| texel(i, j)))
        .collect();
    let map = Arc::new(EnvMap::new("test", MW, MH, texels));
    let maps = OneMap(map.clone());
    // One sample's variance in each pixel (a uniform point of its cell),
    // from a 32 x 32 grid of lookups: the noise the mean is judged by.
    let spp = 1024;
    let sample_var = |i: u32, j: u32| -> [f64; 3] {
        let (mut s1, mut s2) = ([0.0; 3], [0.0; 3]);
        for g in 0..32 * 32 {
            let u = (f64::from(i) + (f64::from(g % 32) + 0.5) / 32.0) / f64::from(MW);
            let v = (f64::from(j) + (f64::from(g / 32) + 0.5) / 32.0) / f64::from(MH);
            let l = map.lookup(u as f32, v as f32);
            for (c, x) in [l.x, l.y, l.z].into_iter().enumerate() {
                s1[c] += f64::from(x) / 1024.0;
                s2[c] += f64::from(x) * f64::from(x) / 1024.0;
            }
        }
        [0, 1, 2].map(|c| (s2[c] - s1[c] * s1[c]).max(1e-12))
    };
    // Facing -z the image's centre column is the map's; facing +x it is
    // the column a quarter turn towards +x (u = 0.75), so image column i
    // shows map column i + MW/4.
    let views = [([0.0, 0.0, -1.0], 0), ([1.0, 0.0, 0.0], MW / 4)];
    for (name, mut backend) in backends() {
        for (look_at, shift) in views {
            let film = render_on(
                &mut backend,
                &panorama(look_at, &maps),
                MW,
                MH,
                &quality(),
                spp,
            );
            let mean = film.mean();
            // Per channel: a pixel's three channels share its sample
            // positions, so their z-scores are not independent.
            let (mut chi2, mut worst) = ([0.0; 3], 0.0f64);
            for y in 0..MH {
                for x in 0..MW {
                    let got = mean[(y * MW + x) as usize];
                    let (i, j) = ((x + shift) % MW, y);
                    let (want, var) = (cell_mean(i, j), sample_var(i, j));
                    for c in 0..3 {
                        let z = (f64::from(got[c]) - want[c]) / (var[c] / spp as f64).sqrt();
                        chi2[c] += z * z;
                        worst = worst.max(z.abs());
                    }
                }
            }
            let k = (MW * MH) as usize;
            eprintln!(
                "{name}: facing {look_at:?}: chi2 {chi2:.0?} over {k} pixels, worst z {worst:.2}"
            );
            assert!(
                worst < 5.5,
                "{name}: facing {look_at:?}: a pixel {worst:.1} sigma off the map"
            );
            assert!(
                chi2.iter().all(|&c| c < common::chi_square_1e6(k)),
                "{name}: facing {look_at:?}: chi-square {chi2:.0?} over {k} pixels"
            );
        }
    }
}

#[test]
fn the_f_number_sets_the_aperture_from_a_full_frame_focal_length() {
    // vfov 2 atan(12 / 50): a 50 mm lens on a 24 mm tall sensor; at f/2
    // the lens's radius is 12.5 mm, in metres as scene units.
    let vfov = 2.0 * (12.0f64 / 50.0).atan().to_degrees();
    let s = json!({
        "camera": {"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": vfov, "f_number": 2.0, "focus_distance": 3},
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [{"type": "sphere", "center": [0, 0, -3], "radius": 1, "material": "m"}]
    });
    let scene = Scene::from_json_str(&s.to_string()).expect("valid");
    assert!(
        (scene.camera.aperture - 0.0125).abs() < 1e-12,
        "{}",
        scene.camera.aperture
    );
    // It round-trips as the f-number, and an edit of the aperture replaces it.
    let back = scene.camera.to_json();
    assert_eq!((back.f_number, back.aperture), (Some(2.0), 0.0));
    let edited = scene
        .edit_camera(&CameraEdit {
            aperture: Some(0.03),
            ..CameraEdit::default()
        })
        .expect("edit");
    assert_eq!(
        (edited.camera.f_number, edited.camera.aperture),
        (None, 0.03)
    );
    let edited = edited
        .edit_camera(&CameraEdit {
            f_number: Some(4.0),
            ..CameraEdit::default()
        })
        .expect("edit");
    assert!((edited.camera.aperture - 0.00625).abs() < 1e-12);
}

#[test]
fn bad_projection_fields_are_named() {
    for (extra, named) in [
        (json!({"projection": "fisheye"}), "camera.projection"),
        (
            json!({"projection": "orthographic", "ortho_height": 0}),
            "camera.ortho_height",
        ),
        (
            json!({"projection": "orthographic", "ortho_height": -1}),
            "camera.ortho_height",
        ),
        (json!({"ortho_height": 2}), "camera.ortho_height"),
        (
            json!({"projection": "panorama", "aperture": 0.1}),
            "camera.aperture",
        ),
        (
            json!({"projection": "orthographic", "f_number": 2}),
            "camera.f_number",
        ),
        (json!({"f_number": 0}), "camera.f_number"),
        (json!({"f_number": 2, "aperture": 0.1}), "camera.f_number"),
    ] {
        let mut camera = json!({"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40});
        if let (Some(c), Some(l)) = (camera.as_object_mut(), extra.as_object()) {
            c.extend(l.clone());
        }
        let s = json!({"camera": camera, "objects": [{"type": "sphere", "center": [0, 0, -3], "radius": 1, "material": "m"}], "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}});
        let e = Scene::from_json_str(&s.to_string()).expect_err("invalid");
        assert!(e.to_string().contains(named), "{extra}: {e}");
    }
}

fn projected(extra: Value) -> Scene {
    let mut camera =
        json!({"position": [1, 2, 3], "look_at": [2, 2, 1], "vfov_deg": 50, "near_clip": 0.25});
    if let (Some(c), Some(l)) = (camera.as_object_mut(), extra.as_object()) {
        c.extend(l.clone());
    }
    let s = json!({
        "camera": camera,
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [{"type": "sphere", "center": [0, 0, -3], "radius": 1, "material": "m"}]
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}

#[test]
fn the_kernels_orthographic_and_panoramic_rays_agree_within_a_few_ulps() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    for extra in [
        json!({"projection": "orthographic", "ortho_height": 3.5}),
        json!({"projection": "panorama"}),
    ] {
        let job = RenderJob::new(&projected(extra.clone()), 64, 48, &Quality::default());
        assert_camera_rays_agree(&d, &job, &extra.to_string());
    }
}
