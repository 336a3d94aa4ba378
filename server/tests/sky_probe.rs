//! A sky that walls hide (`render::sky_probe`): in a closed room lit by a
//! lamp, under a bright sky, light selection no longer spends its shadow
//! rays on the sky: the image is the one without a sky, as unbiased and
//! nearly as quiet, on every backend; a room with a window keeps the sky
//! in proportion to what the window lets through; an open scene's table
//! is power-proportional as before.

mod common;

use common::{assert_agree, backends, render_on};
use pathstream::render::sampler::SamplerKind;
use pathstream::render::sky_probe::{sky_visibility, HIDDEN_SKY_SHARE};
use pathstream::render::world::World;
use pathstream::render::{Film, Filter, Quality, RenderJob, Scene};
use serde_json::{json, Value};

const W: u32 = 32;
const H: u32 = 32;

/// `bench::scenes::sky_room`: a closed 2 x 2 x 2 room lit by a small
/// lamp, or one with a window of side `window`, under `sky`.
fn room(window: Option<f64>, sky: Value) -> Scene {
    pathstream::bench::scenes::sky_room(window, sky).expect("valid scene")
}

fn quality(seed: u64) -> Quality {
    Quality {
        filter: Filter::Box,
        sampler: SamplerKind::Random,
        max_depth: 3,
        rr_depth: 8,
        seed,
        ..Quality::default()
    }
}

/// The sky's chance of being picked for a shadow ray in `scene`'s job.
fn sky_pmf(scene: &Scene) -> f32 {
    let job = RenderJob::new(scene, W, H, &quality(1));
    let lights = &job.world.lights;
    lights.pick_pmf(lights.environment().expect("a sky"))
}

/// Summed variance of the pixel means (from each pixel's even/odd halves).
fn noise(film: &Film) -> f64 {
    common::regions(film, 4)
        .iter()
        .map(|r| r.var.iter().sum::<f64>())
        .sum()
}

#[test]
fn a_hidden_sky_gets_almost_no_shadow_rays_and_changes_nothing_but_the_noise() {
    let closed = room(None, json!([50, 50, 50]));
    let dark = room(None, json!([0, 0, 0]));
    let job = RenderJob::new(&closed, W, H, &quality(1));
    assert_eq!(
        sky_visibility(&job.world, &job.camera),
        Some(0.0),
        "no probe ray sees the sky"
    );
    let pmf = f64::from(sky_pmf(&closed));
    assert!(
        (pmf - HIDDEN_SKY_SHARE).abs() < 1e-6,
        "the hidden sky is picked with probability {pmf}"
    );
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &closed, W, H, &quality(1), 256);
        let b = render_on(&mut backend, &dark, W, H, &quality(2), 256);
        assert_agree(
            &a,
            &b,
            4,
            4.5,
            1e-4,
            &format!("{name}: closed room with and without a sky"),
        );
        // The same samples without the sky, and picking it by power alone
        // (what selection did before the probe: the lamp then gets 0.3%
        // of the shadow rays).
        let dark = render_on(&mut backend, &dark, W, H, &quality(1), 256);
        let mut power = RenderJob::new(&closed, W, H, &quality(1));
        power.world = World::new(&closed, closed.camera.position);
        let mut by_power = Film::new(W, H);
        backend.render(&power, &mut by_power, 256).expect("render");
        let (vs_dark, vs_power) = (noise(&a) / noise(&dark), noise(&a) / noise(&by_power));
        eprintln!("{name}: noise with a hidden sky over without one {vs_dark:.3}, over power-proportional picks {vs_power:.4}");
        assert!(
            vs_dark < 1.5,
            "{name}: a hidden sky made the image {vs_dark:.2}x as noisy"
        );
        assert!(
            vs_power < 0.1,
            "{name}: only {:.1}x less noise than picking by power",
            1.0 / vs_power
        );
    }
}

#[test]
fn a_window_keeps_the_sky_in_proportion_and_an_open_scene_is_unchanged() {
    // Through a 1 x 1 window in a 2 x 2 wall: some of the room sees some
    // sky, so the sky keeps a share between the floor and its full one.
    let sky = json!([50, 50, 50]);
    let windowed = room(Some(1.0), sky.clone());
    let job = RenderJob::new(&windowed, W, H, &quality(1));
    let power_only = World::new(&windowed, windowed.camera.position);
    let i = power_only.lights.environment().expect("sky");
    let (full, weighed) = (power_only.lights.pick_pmf(i), job.world.lights.pick_pmf(i));
    // The odds of a sky pick scale by the fraction of probe rays that saw
    // it: here a few per cent (the window is a sixteenth of the walls).
    let odds = |p: f32| f64::from(p) / (1.0 - f64::from(p));
    let v = sky_visibility(&power_only, &job.camera).expect("probed");
    eprintln!(
        "windowed room: sky pmf {weighed:.4} (power-proportional {full:.4}), visibility {v:.4}"
    );
    assert!((0.01..0.2).contains(&v), "visibility {v}");
    assert!((odds(weighed) / odds(full) / v - 1.0).abs() < 1e-4);
    // Unbiased: the image agrees with one made without light selection at
    // all (BSDF sampling only).
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &windowed, W, H, &quality(3), 1024);
        let no_nee = Quality {
            nee: false,
            ..quality(4)
        };
        let b = render_on(&mut backend, &windowed, W, H, &no_nee, 4096);
        // 8 x 8 regions: BSDF sampling meets the lamp rarely, and its
        // noise is far from normal in smaller ones.
        assert_agree(
            &a,
            &b,
            8,
            4.5,
            1e-4,
            &format!("{name}: window, weighed sky vs BSDF sampling alone"),
        );
    }
    // Nothing hides the sky from a floor under it (its lamp is below it,
    // facing down): the table is as before.
    let open = Scene::from_json_str(
        &json!({
            "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "vfov_deg": 50},
            "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
                          "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [20, 20, 20]}},
            "objects": [
                {"type": "quad", "corner": [-5, 0, 5], "edge_u": [10, 0, 0], "edge_v": [0, 0, -10], "material": "grey"},
                {"type": "quad", "corner": [-1, -1, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "lamp"}
            ],
            "environment": [1, 1, 1]
        })
        .to_string(),
    )
    .expect("valid");
    let job = RenderJob::new(&open, W, H, &quality(1));
    let plain = World::new(&open, open.camera.position);
    let i = plain.lights.environment().expect("sky");
    assert_eq!(job.world.lights.pick_pmf(i), plain.lights.pick_pmf(i));
}

#[test]
fn a_sun_behind_walls_gets_almost_no_shadow_rays_either() {
    // A computed sky's sun carries far more power than its sky: without
    // the probe it would take most shadow rays in the closed room.
    let closed = room(None, json!({"sky": {"sun_elevation_deg": 50}}));
    let job = RenderJob::new(&closed, W, H, &quality(1));
    let lights = &job.world.lights;
    let (sun, sky) = (
        lights.sun().expect("a sun"),
        lights.environment().expect("a sky"),
    );
    for (what, i) in [("sun", sun), ("sky", sky)] {
        let pmf = lights.pick_pmf(i);
        assert!(f64::from(pmf) <= 2.0 * HIDDEN_SKY_SHARE, "{what}: {pmf}");
    }
    // Power alone (no probe) gives the sun most picks.
    let open = World::new(&closed, closed.camera.position);
    let pmf = open.lights.pick_pmf(open.lights.sun().expect("a sun"));
    assert!(pmf > 0.5, "without the probe: {pmf}");
}
