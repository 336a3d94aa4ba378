//! Absorption inside transmitting solids (`attenuation`,
//! KHR_materials_volume's Beer-Lambert law) in whole renders on every
//! backend. Closed form: a ball of index 1 (light crosses it unbent and
//! unreflected) seen by an orthographic camera against a white sky keeps
//! exp(-sigma * chord) of the sky along each ray, the chord 2 sqrt(1 - b^2)
//! at distance b from the axis; smooth `glass` and rough `pbr` glass alike.
//! A scene of absorbing glass agrees between the CPU and OpenCL and with
//! next-event estimation on and off; bad fields are named.

mod common;

use common::{
    assert_backends_agree, assert_clean, assert_nee_on_off_agree, backends, balls_on_a_floor,
    box_quality, region, render_on,
};
use pathstream::render::{Filter, Quality, Scene};
use serde_json::{json, Value};

/// Pixels across the image, and the image's height in scene units.
const SIZE: u32 = 24;
const VIEW: f64 = 2.4;
/// What the ball keeps of the light along its diameter (2 units), per
/// channel: the attenuation colour at distance 2.
const KEPT: [f64; 3] = [0.8, 0.5, 0.2];

/// A unit ball of `material` at the origin under a white sky, seen along
/// -z by an orthographic camera `VIEW` units tall.
fn ball(material: Value) -> Scene {
    let s = json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 30,
            "projection": "orthographic", "ortho_height": VIEW},
        "environment": [1, 1, 1],
        "materials": {"m": material},
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}

fn attenuation() -> Value {
    json!({"color": KEPT, "distance": 2})
}

/// The mean over pixels `xs` x `ys` of what the ball keeps: per pixel the
/// average, over its square (box filter), of KEPT^sqrt(1 - b^2) inside the
/// disc and 1 outside (a 32 x 32 midpoint grid per pixel).
fn expected(xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> [f64; 3] {
    const N: u32 = 32;
    let pixel = VIEW / f64::from(SIZE);
    let mut sum = [0.0; 3];
    let mut count = 0.0;
    for y in ys {
        for x in xs.clone() {
            for j in 0..N {
                for i in 0..N {
                    let px =
                        (f64::from(x) + (f64::from(i) + 0.5) / f64::from(N)) * pixel - VIEW / 2.0;
                    let py =
                        (f64::from(y) + (f64::from(j) + 0.5) / f64::from(N)) * pixel - VIEW / 2.0;
                    let b2 = px * px + py * py;
                    for c in 0..3 {
                        sum[c] += if b2 < 1.0 {
                            KEPT[c].powf((1.0 - b2).sqrt())
                        } else {
                            1.0
                        };
                    }
                    count += 1.0;
                }
            }
        }
    }
    sum.map(|s| s / count)
}

/// On every backend the ball's image matches [`expected`] in every channel,
/// over the whole image and over its centre, within `rel` (and 4.5
/// standard errors).
fn assert_beer_lambert(scene: &Scene, spp: u64, rel: f64, what: &str) {
    let q = Quality {
        filter: Filter::Box,
        max_depth: 0,
        ..Quality::default()
    };
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, scene, SIZE, SIZE, &q, spp);
        let what = format!("{name}: {what}");
        assert_clean(&film, &what);
        for (xs, ys, part) in [
            (0..SIZE, 0..SIZE, "image"),
            (8..16, 8..16, "centre"),
            (2..6, 10..14, "rim"),
        ] {
            let want = expected(xs.clone(), ys.clone());
            let got = region(&film, xs, ys);
            for (c, want) in want.iter().enumerate() {
                let (m, se) = (got.mean[c], got.var[c].sqrt());
                assert!(
                    (m - want).abs() < rel * want + 4.5 * se,
                    "{what}: {part} channel {c}: {m} (se {se:.1e}), Beer-Lambert gives {want}"
                );
            }
        }
    }
}

#[test]
fn a_smooth_index_1_ball_keeps_exp_of_minus_sigma_times_the_chord() {
    let m = json!({"type": "glass", "ior": 1.0, "attenuation": attenuation()});
    assert_beer_lambert(&ball(m), 16, 0.003, "smooth glass, ior 1");
}

#[test]
fn a_rough_index_1_ball_keeps_the_same() {
    // Rough glass of index 1 refracts through any microfacet unbent; the
    // energy compensation keeps its throughput at 1 on average.
    let m = json!({"type": "pbr", "metallic": 0, "roughness": 0.3, "transmission": 1, "ior": 1.0,
        "attenuation": attenuation()});
    assert_beer_lambert(&ball(m), 64, 0.01, "rough glass, ior 1");
}

/// Absorbing smooth and rough glass of several indices on a diffuse floor
/// under a quad light and a dim sky.
fn absorbing_scene() -> Scene {
    balls_on_a_floor([
        (
            "amber",
            json!({"type": "glass", "ior": 1.5, "attenuation": {"color": [0.9, 0.6, 0.2], "distance": 0.5}}),
        ),
        (
            "jade",
            json!({"type": "pbr", "base_color": [0.9, 1, 0.9], "metallic": 0, "roughness": 0.4, "transmission": 1,
            "ior": 1.6, "attenuation": {"color": [0.3, 0.8, 0.5], "distance": 0.3}}),
        ),
        (
            "tea",
            json!({"type": "pbr", "metallic": 0, "roughness": 0.1, "transmission": 0.8, "ior": 1.33,
            "attenuation": {"color": [0.7, 0.4, 0.1], "distance": 1}}),
        ),
    ])
}

#[test]
fn absorbing_glass_agrees_on_every_backend() {
    assert_backends_agree(&absorbing_scene(), (32, 24), &box_quality(), 128);
    // Filling the frame, where what crosses the solid is most of the image
    // (refracted and reflected inside many times).
    for m in [
        json!({"type": "glass", "ior": 1.5, "attenuation": {"color": [0.9, 0.6, 0.2], "distance": 1}}),
        json!({"type": "pbr", "metallic": 0, "roughness": 0.3, "transmission": 1, "ior": 1.5,
            "attenuation": {"color": [0.9, 0.6, 0.2], "distance": 1}}),
    ] {
        assert_backends_agree(&ball(m), (SIZE, SIZE), &box_quality(), 64);
    }
}

#[test]
fn nee_on_and_off_agree_through_absorbing_glass() {
    assert_nee_on_off_agree(&absorbing_scene(), (32, 24), &box_quality(), 128);
}

#[test]
fn bad_attenuation_is_named_and_good_survives_the_round_trip() {
    let pbr = |attenuation: Value| json!({"type": "pbr", "transmission": 1, "metallic": 0, "attenuation": attenuation});
    for (material, field) in [
        (
            pbr(json!({"color": [1.2, 0.5, 0.5], "distance": 1})),
            "materials.m.attenuation.color",
        ),
        (
            pbr(json!({"color": [0.5, -0.1, 0.5], "distance": 1})),
            "materials.m.attenuation.color",
        ),
        (
            pbr(json!({"color": [0.5, 0.5, 0.5], "distance": 0})),
            "materials.m.attenuation.distance",
        ),
        (
            pbr(json!({"color": [0.5, 0.5, 0.5], "distance": -2})),
            "materials.m.attenuation.distance",
        ),
        (pbr(json!({"color": [0.5, 0.5, 0.5]})), "materials.m"),
        (
            pbr(json!({"color": [0.5, 0.5, 0.5], "distance": 1, "density": 2})),
            "materials.m",
        ),
        (
            json!({"type": "pbr", "transmission": 1, "thin": true,
                "attenuation": {"color": [0.5, 0.5, 0.5], "distance": 1}}),
            "materials.m.attenuation",
        ),
        (
            json!({"type": "glass", "ior": 1.5, "attenuation": {"color": [0.5, 0.5, 0.5], "distance": "far"}}),
            "materials.m",
        ),
    ] {
        common::assert_material_refused(&material, field);
    }
    let s = absorbing_scene();
    let text = common::assert_round_trip(&s);
    assert!(
        text.contains("\"attenuation\":{\"color\":[0.3,0.8,0.5],\"distance\":0.3}"),
        "{text}"
    );
}

#[test]
fn a_colour_component_of_zero_absorbs_that_channel_and_stays_finite() {
    let m =
        json!({"type": "glass", "ior": 1.0, "attenuation": {"color": [1, 0, 0.5], "distance": 1}});
    let q = Quality {
        filter: Filter::Box,
        ..Quality::default()
    };
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &ball(m.clone()), SIZE, SIZE, &q, 8);
        assert_clean(&film, name);
        let centre = region(&film, 10..14, 10..14).mean;
        assert!(
            (centre[0] - 1.0).abs() < 1e-3,
            "{name}: red passes whole: {centre:?}"
        );
        assert!(centre[1] < 1e-6, "{name}: green is gone: {centre:?}");
        assert!(
            centre[2] > 0.2 && centre[2] < 0.3,
            "{name}: blue keeps 0.5^~2: {centre:?}"
        );
    }
}
