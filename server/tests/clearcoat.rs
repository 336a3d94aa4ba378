//! The clear coat (`clearcoat`, KHR_materials_clearcoat) in whole renders
//! on every backend: a white material under a white coat, any roughness,
//! metal, dielectric or rough glass, is invisible under a uniform white sky
//! (the coat reflects what it keeps from the base, no more, no less); a
//! coat shows as a highlight a bare surface lacks; a coated scene agrees
//! between the CPU and OpenCL and with next-event estimation on and off;
//! bad fields are named.

mod common;

use common::{
    assert_backends_agree, assert_clean, assert_invisible, assert_nee_on_off_agree, backends,
    balls_on_a_floor, box_quality, region, render_on, sky_sphere,
};
use pathstream::render::Scene;
use serde_json::json;

#[test]
fn a_white_coated_sphere_in_a_white_sky_is_invisible() {
    for (coat, coat_roughness, base) in [
        (1.0, 0.05, json!({"metallic": 0, "roughness": 0.6})),
        (1.0, 0.4, json!({"metallic": 1, "roughness": 0.2})),
        (
            0.5,
            0.1,
            json!({"metallic": 0, "roughness": 0.3, "transmission": 1}),
        ),
        (
            1.0,
            0.2,
            json!({"metallic": 0, "roughness": 0.2, "transmission": 1, "thin": true}),
        ),
    ] {
        let mut m = base.clone();
        m["type"] = json!("pbr");
        m["clearcoat"] = json!(coat);
        m["clearcoat_roughness"] = json!(coat_roughness);
        let s = sky_sphere(m);
        assert_invisible(
            &s,
            48,
            0.02,
            &format!("coat {coat} at {coat_roughness} over {base}"),
        );
    }
}

/// Spheres of a black base, bare and under a smooth coat, and coated
/// materials over metal and rough glass, on a floor under a quad light.
fn coated_scene() -> Scene {
    balls_on_a_floor([
        (
            "paint",
            json!({"type": "pbr", "base_color": [0.6, 0.05, 0.05], "metallic": 0, "roughness": 0.7,
            "clearcoat": 1, "clearcoat_roughness": 0.05}),
        ),
        (
            "flake",
            json!({"type": "pbr", "base_color": [0.8, 0.7, 0.3], "metallic": 1, "roughness": 0.5,
            "clearcoat": 0.7, "clearcoat_roughness": 0.2}),
        ),
        (
            "lacquer",
            json!({"type": "pbr", "base_color": [0.9, 0.95, 0.9], "metallic": 0, "roughness": 0.3,
            "transmission": 1, "clearcoat": 1, "clearcoat_roughness": 0.1}),
        ),
    ])
}

#[test]
fn a_coated_scene_agrees_on_every_backend() {
    assert_backends_agree(&coated_scene(), (32, 24), &box_quality(), 128);
    // Filling the frame: the coat's share of a dark sphere's image.
    let m = json!({"type": "pbr", "base_color": [0.2, 0.3, 0.5], "metallic": 0, "roughness": 0.8,
        "clearcoat": 1, "clearcoat_roughness": 0.3});
    assert_backends_agree(&sky_sphere(m), (24, 24), &box_quality(), 64);
}

#[test]
fn nee_on_and_off_agree_under_a_coat() {
    assert_nee_on_off_agree(&coated_scene(), (32, 24), &box_quality(), 128);
}

#[test]
fn a_coat_adds_a_white_reflection_to_a_black_base() {
    // A black rough dielectric in a white sky reflects only its own 4%
    // layer (mostly at grazing angles); under a coat twice that or more.
    let bare = json!({"type": "pbr", "base_color": [0, 0, 0], "metallic": 0, "roughness": 1});
    let mut coated = bare.clone();
    coated["clearcoat"] = json!(1);
    for (name, mut backend) in backends() {
        let mean = |m: &serde_json::Value, backend: &mut pathstream::render::Backend| {
            let film = render_on(backend, &sky_sphere(m.clone()), 24, 24, &box_quality(), 32);
            assert_clean(&film, name);
            region(&film, 8..16, 8..16).mean
        };
        let (b, c) = (mean(&bare, &mut backend), mean(&coated, &mut backend));
        assert!(
            c[0] > b[0] + 0.03 && c[2] > b[2] + 0.03,
            "{name}: bare {b:?}, coated {c:?}"
        );
        assert!(c[0] < 0.2, "{name}: coated {c:?}");
    }
}

#[test]
fn bad_clearcoat_is_named_and_good_survives_the_round_trip() {
    for (field, bad) in [
        ("clearcoat", json!(1.5)),
        ("clearcoat", json!(-0.1)),
        ("clearcoat_roughness", json!(2)),
    ] {
        let mut m = json!({"type": "pbr"});
        m[field] = bad;
        common::assert_material_refused(&m, &format!("materials.m.{field}"));
    }
    let s = coated_scene();
    let text = common::assert_round_trip(&s);
    assert!(
        text.contains("\"clearcoat\":0.7,\"clearcoat_roughness\":0.2"),
        "{text}"
    );
}
