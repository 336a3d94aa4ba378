//! The thin-lens camera (`camera.aperture`, `camera.focus_distance`):
//! aperture 0 is the pinhole, image for image; a point light on the plane
//! in focus stays a point and one off it spreads over the thin lens's
//! circle of confusion, on every backend; the kernel's camera rays are the
//! CPU's within a few ulps (its numbers bit for bit: `opencl_parity.rs`);
//! bad fields are named, in scenes and in camera edits.

mod common;
mod parity;

use common::{assert_clean, backends, render_on};
use parity::assert_camera_rays_agree;
use pathstream::render::scene::CameraEdit;
use pathstream::render::{Film, Filter, Quality, RenderJob, Scene};
use serde_json::{json, Value};

const SIZE: u32 = 64;

/// The sphere's radius in pixels as the camera sees it at any depth.
const SPHERE_PX: f64 = 2.0;

/// 2.4 degrees of view over `SIZE` pixels: a pixel's width at distance 1.
fn pixel() -> f64 {
    2.0 * (1.2f64).to_radians().tan() / f64::from(SIZE)
}

/// A small bright sphere `depth` in front of the camera, on its axis,
/// `SPHERE_PX` pixels in radius at any depth, seen through `lens` (the
/// camera JSON's extra fields).
fn point_light(depth: f64, lens: Value) -> Scene {
    let mut camera = json!({"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 2.4});
    if let (Some(c), Some(l)) = (camera.as_object_mut(), lens.as_object()) {
        c.extend(l.clone());
    }
    let s = json!({
        "camera": camera,
        "materials": {"glow": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [1000, 1000, 1000]}},
        "objects": [{"type": "sphere", "center": [0, 0, -depth], "radius": SPHERE_PX * pixel() * depth, "material": "glow"}]
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}

fn quality() -> Quality {
    Quality {
        filter: Filter::Box,
        max_depth: 1,
        ..Quality::default()
    }
}

/// The blur's radius in pixels: the image's second moment about the
/// centre, E[rho^2], is R^2 / 2 for a uniform disc of radius R, plus the
/// sphere's own disc's (SPHERE_PX^2 / 2) and a box filter's pixel (1/6),
/// as variances of independent offsets add.
fn blur_radius(film: &Film) -> f64 {
    let mean = film.mean();
    let c = f64::from(SIZE) / 2.0;
    let (mut sum, mut moment) = (0.0, 0.0);
    for (i, p) in mean.iter().enumerate() {
        let (x, y) = (
            (i as u32 % SIZE) as f64 + 0.5 - c,
            (i as u32 / SIZE) as f64 + 0.5 - c,
        );
        sum += f64::from(p[0]);
        moment += f64::from(p[0]) * (x * x + y * y);
    }
    let m2 = moment / sum;
    (2.0 * (m2 - 1.0 / 6.0) - SPHERE_PX * SPHERE_PX)
        .max(0.0)
        .sqrt()
}

#[test]
fn aperture_zero_is_the_pinhole_image_for_image() {
    let pinhole = point_light(5.0, json!({}));
    let zero = point_light(5.0, json!({"aperture": 0, "focus_distance": 2}));
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &pinhole, 16, 16, &quality(), 16);
        let b = render_on(&mut backend, &zero, 16, 16, &quality(), 16);
        assert_eq!(a.pixels(), b.pixels(), "{name}: aperture 0 vs no lens");
    }
}

#[test]
fn the_plane_in_focus_is_sharp_and_the_rest_blurs_by_the_circle_of_confusion() {
    // A point at depth z seen through a lens of radius A focused at f
    // spreads over a disc of radius A |z - f| / z on the plane in focus,
    // A |z - f| / (z f) at distance 1.
    let (aperture, focus) = (0.026, 2.5);
    for (name, mut backend) in backends() {
        let sharp = point_light(
            focus,
            json!({"aperture": aperture, "focus_distance": focus}),
        );
        let film = render_on(&mut backend, &sharp, SIZE, SIZE, &quality(), 64);
        assert_clean(&film, name);
        let r = blur_radius(&film);
        assert!(r < 0.5, "{name}: in focus the point blurs by {r:.2} pixels");
        for depth in [5.0, 1.5] {
            let s = point_light(
                depth,
                json!({"aperture": aperture, "focus_distance": focus}),
            );
            let film = render_on(&mut backend, &s, SIZE, SIZE, &quality(), 256);
            assert_clean(&film, name);
            let expected = aperture * (depth - focus).abs() / (depth * focus) / pixel();
            let r = blur_radius(&film);
            eprintln!("{name}: depth {depth}: blur radius {r:.2} px, thin lens {expected:.2} px");
            assert!(
                (r - expected).abs() < 0.05 * expected + 0.3,
                "{name}: depth {depth}: blur radius {r:.2} px, thin lens says {expected:.2}"
            );
        }
    }
}

#[test]
fn camera_rays_through_the_lens_agree_within_a_few_ulps() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    let scene = point_light(
        4.0,
        json!({"aperture": 0.01, "focus_distance": 3.0, "near_clip": 0.5}),
    );
    let job = RenderJob::new(&scene, 64, 48, &Quality::default());
    assert!(job.camera.has_lens());
    assert_camera_rays_agree(&d, &job, "thin lens");
}

#[test]
fn bad_lens_fields_are_named() {
    for (lens, named) in [
        (json!({"aperture": -1}), "camera.aperture"),
        (json!({"aperture": "wide"}), "camera"),
        (json!({"focus_distance": 0}), "camera.focus_distance"),
        (json!({"focus_distance": -2}), "camera.focus_distance"),
        (json!({"f_stop": 2}), "f_stop"),
    ] {
        let mut camera = json!({"position": [0, 0, 0], "look_at": [0, 0, -1], "vfov_deg": 40});
        if let (Some(c), Some(l)) = (camera.as_object_mut(), lens.as_object()) {
            c.extend(l.clone());
        }
        let s = json!({"camera": camera, "objects": [{"type": "sphere", "center": [0, 0, -3], "radius": 1, "material": "m"}], "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}});
        let e = Scene::from_json_str(&s.to_string()).expect_err("invalid");
        assert!(e.to_string().contains(named), "{lens}: {e}");
    }
    let s = point_light(5.0, json!({}));
    let bad = CameraEdit {
        aperture: Some(f64::NAN),
        ..CameraEdit::default()
    };
    let e = s.edit_camera(&bad).expect_err("NaN aperture");
    assert!(e.to_string().contains("camera.aperture"), "{e}");
    let good = CameraEdit {
        aperture: Some(0.05),
        focus_distance: Some(4.0),
        ..CameraEdit::default()
    };
    let edited = s.edit_camera(&good).expect("a lens");
    assert_eq!(
        (edited.camera.aperture, edited.camera.focus_distance),
        (0.05, Some(4.0))
    );
    let back = Scene::from_json(&edited.to_json()).expect("round trip");
    assert_eq!(back.camera, edited.camera);
}
