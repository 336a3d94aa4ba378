//! Rough glass (`"type": "pbr"` with `transmission`,
//! KHR_materials_transmission) in whole renders on every backend: a white
//! rough glass sphere under a uniform white sky is invisible (it keeps
//! every bit of energy, in and out through any number of internal
//! bounces), and so is a thin-walled one; a tinted one passes its colour and never more than the sky; a
//! scene of rough glass agrees between the CPU and OpenCL, and with next-
//! event estimation on and off; bad fields are named.

mod common;

use common::{
    assert_backends_agree, assert_clean, assert_invisible, assert_nee_on_off_agree, backends,
    balls_on_a_floor, box_quality, region, render_on, sky_sphere,
};
use pathstream::render::Scene;
use serde_json::json;

#[test]
fn a_white_rough_glass_sphere_in_a_white_sky_is_invisible() {
    // The bar is 2% up to roughness 0.3; the compensation keeps
    // the rougher spheres there too.
    for roughness in [0.05, 0.15, 0.3, 0.6, 1.0] {
        let m = json!({"type": "pbr", "metallic": 0, "roughness": roughness, "transmission": 1, "ior": 1.5});
        assert_invisible(
            &sky_sphere(m),
            64,
            0.02,
            &format!("rough glass, roughness {roughness}"),
        );
    }
}

#[test]
fn a_white_thin_walled_sphere_in_a_white_sky_is_invisible() {
    // A bubble: both walls thin (glTF's transmission without a volume).
    for roughness in [0.0, 0.3, 1.0] {
        let m = json!({"type": "pbr", "metallic": 0, "roughness": roughness, "transmission": 1,
            "thin": true});
        assert_invisible(
            &sky_sphere(m),
            64,
            0.02,
            &format!("thin wall, roughness {roughness}"),
        );
    }
}

#[test]
fn glass_mixed_with_the_coated_base_keeps_the_energy_too() {
    for (transmission, metallic, ior) in [(0.5, 0.0, 1.5), (0.7, 0.3, 2.0)] {
        let m = json!({"type": "pbr", "metallic": metallic, "roughness": 0.4,
            "transmission": transmission, "ior": ior});
        assert_invisible(
            &sky_sphere(m),
            64,
            0.02,
            &format!("transmission {transmission}, metallic {metallic}, ior {ior}"),
        );
    }
}

#[test]
fn tinted_rough_glass_passes_its_colour_and_no_more() {
    let m = json!({"type": "pbr", "base_color": [0.9, 0.5, 0.2], "metallic": 0,
        "roughness": 0.3, "transmission": 1});
    let s = sky_sphere(m);
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &s, 24, 24, &box_quality(), 32);
        assert_clean(&film, name);
        let centre = region(&film, 8..16, 8..16);
        let c = centre.mean;
        assert!(
            c[0] < 1.0 && c[0] > c[1] && c[1] > c[2] && c[2] > 0.02,
            "{name}: the tint's order, under the sky: {c:?}"
        );
    }
}

/// Rough glass of two roughnesses, whole and half transmissive (that one
/// a thin wall), on a diffuse floor under a quad light and a dim sky.
fn glass_scene() -> Scene {
    balls_on_a_floor([
        (
            "frosted",
            json!({"type": "pbr", "base_color": [0.9, 0.8, 0.6], "metallic": 0, "roughness": 0.5, "transmission": 1}),
        ),
        (
            "clear",
            json!({"type": "pbr", "metallic": 0, "roughness": 0.15, "transmission": 1, "ior": 1.33}),
        ),
        (
            "half",
            json!({"type": "pbr", "base_color": [0.3, 0.5, 0.9], "metallic": 0, "roughness": 0.3, "transmission": 0.5,
            "thin": true}),
        ),
    ])
}

#[test]
fn rough_glass_agrees_on_every_backend() {
    assert_backends_agree(&glass_scene(), (32, 24), &box_quality(), 128);
}

#[test]
fn nee_on_and_off_agree_through_rough_glass() {
    // Next-event estimation gathers what the glass reflects; what it
    // transmits is BSDF sampling's alone, counted whole: the same image.
    assert_nee_on_off_agree(&glass_scene(), (32, 24), &box_quality(), 128);
}

#[test]
fn bad_transmission_is_named_and_good_survives_the_round_trip() {
    for bad in [json!(1.5), json!(-0.1), json!("all")] {
        let s = json!({
            "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "vfov_deg": 40},
            "materials": {"m": {"type": "pbr", "transmission": bad}},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]
        });
        let e = Scene::from_json_str(&s.to_string()).expect_err("invalid");
        assert!(e.to_string().contains("materials.m"), "{bad}: {e}");
        if bad.is_number() {
            assert!(
                e.to_string().contains("materials.m.transmission"),
                "{bad}: {e}"
            );
        }
    }
    let s = glass_scene();
    let text = common::assert_round_trip(&s);
    assert!(text.contains("\"transmission\":0.5"), "{text}");
    assert!(text.contains("\"thin\":true"), "{text}");
}
