//! The glTF metallic-roughness material (`"type": "pbr"`) in whole renders
//! on every backend: a white sphere under a uniform white sky is invisible
//! at every roughness, metal or dielectric (a convex object's every pixel is
//! its directional albedo there); a darker one is darker and never
//! brighter; a sphere grid agrees between the CPU and OpenCL; bad fields
//! are named.

mod common;

use common::{
    assert_backends_agree, assert_clean, assert_mean, assert_nee_on_off_agree, backends,
    box_quality, region, render_on,
};
use pathstream::render::Scene;
use serde_json::json;

fn sky_sphere(base: [f64; 3], metallic: f64, roughness: f64) -> Scene {
    common::sky_sphere(
        json!({"type": "pbr", "base_color": base, "metallic": metallic, "roughness": roughness}),
    )
}

#[test]
fn a_white_sphere_in_a_white_sky_is_invisible_at_every_roughness() {
    for (name, mut backend) in backends() {
        for metallic in [1.0, 0.0] {
            for roughness in [0.05, 0.25, 0.5, 0.75, 1.0] {
                let s = sky_sphere([1.0; 3], metallic, roughness);
                let film = render_on(&mut backend, &s, 24, 24, &box_quality(), 64);
                let what = format!("{name}: metallic {metallic} roughness {roughness}");
                assert_clean(&film, &what);
                // Each 4x4 block within 1% (and its noise), and the whole
                // image within 1% at its own, far smaller, noise.
                assert_mean(&film, 4, 1.0, 4.5, 0.01, &what);
                let all = region(&film, 0..24, 0..24);
                for c in 0..3 {
                    let (m, se) = (all.mean[c], all.var[c].sqrt());
                    assert!(
                        (m - 1.0).abs() < 0.01 + 4.5 * se,
                        "{what}: image mean {m} (se {se:.1e})"
                    );
                }
            }
        }
    }
}

#[test]
fn a_coloured_sphere_reflects_less_than_the_sky_never_more() {
    for (name, mut backend) in backends() {
        for (metallic, roughness) in [(1.0, 0.4), (0.0, 0.4), (0.5, 0.9)] {
            let s = sky_sphere([0.8, 0.4, 0.1], metallic, roughness);
            let film = render_on(&mut backend, &s, 24, 24, &box_quality(), 32);
            let centre = region(&film, 8..16, 8..16);
            let what = format!("{name}: metallic {metallic} roughness {roughness}");
            for c in 0..3 {
                assert!(
                    centre.mean[c] < 0.97 && centre.mean[c] > 0.02,
                    "{what}: channel {c} reads {}",
                    centre.mean[c]
                );
            }
            assert!(
                centre.mean[0] > centre.mean[1] && centre.mean[1] > centre.mean[2],
                "{what}: the base colour's order is kept: {:?}",
                centre.mean
            );
        }
    }
}

/// glTF's MetalRoughSpheres in small: metallic by row, roughness by column,
/// on a diffuse floor under a quad light and a dim sky.
fn sphere_grid() -> Scene {
    let mut objects = vec![
        json!({"type": "quad", "corner": [-4, -1, -4], "edge_u": [8, 0, 0], "edge_v": [0, 0, 8], "material": "floor"}),
        json!({"type": "quad", "corner": [-1, 3, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "light"}),
    ];
    let mut materials = serde_json::Map::new();
    materials.insert(
        "floor".into(),
        json!({"type": "diffuse", "albedo": [0.6, 0.6, 0.6]}),
    );
    materials.insert(
        "light".into(),
        json!({"type": "diffuse", "albedo": [0, 0, 0], "emission": [6, 6, 6]}),
    );
    for (row, metallic) in [0.0, 1.0].into_iter().enumerate() {
        for (col, roughness) in [0.1, 0.4, 0.7, 1.0].into_iter().enumerate() {
            let name = format!("m{row}{col}");
            materials.insert(
                name.clone(),
                json!({"type": "pbr", "base_color": [0.9, 0.5, 0.2], "metallic": metallic, "roughness": roughness}),
            );
            objects.push(json!({
                "type": "sphere",
                "center": [-1.5 + col as f64, -0.55 + row as f64 * 1.0, 0],
                "radius": 0.45,
                "material": name
            }));
        }
    }
    let s = json!({
        "camera": {"position": [0, 0.5, 5], "look_at": [0, 0, 0], "vfov_deg": 45},
        "environment": [0.2, 0.25, 0.3],
        "materials": materials,
        "objects": objects
    });
    Scene::from_json_str(&s.to_string()).expect("valid grid")
}

#[test]
fn a_metal_roughness_grid_agrees_on_every_backend() {
    assert_backends_agree(&sphere_grid(), (32, 24), &box_quality(), 128);
}

#[test]
fn nee_on_and_off_agree_on_the_grid() {
    // Next-event estimation gathers the broad lobes' light, the next hit
    // the narrow lobes': together the same image as BSDF sampling alone.
    assert_nee_on_off_agree(&sphere_grid(), (32, 24), &box_quality(), 128);
}

#[test]
fn bad_pbr_fields_are_named() {
    let cases = [
        (
            json!({"type": "pbr", "metallic": 2}),
            "materials.m.metallic",
        ),
        (
            json!({"type": "pbr", "roughness": -0.1}),
            "materials.m.roughness",
        ),
        (json!({"type": "pbr", "ior": 0.5}), "materials.m.ior"),
        (
            json!({"type": "pbr", "base_color": [1.2, 0, 0]}),
            "materials.m.base_color",
        ),
        (json!({"type": "pbr", "shininess": 3}), "shininess"),
        (json!({"type": "pbr", "metallic": "no"}), "materials.m"),
    ];
    for (m, named) in cases {
        common::assert_material_refused(&m, named);
    }
}

#[test]
fn pbr_materials_survive_the_round_trip_through_json() {
    let s = sky_sphere([0.3, 0.6, 0.9], 0.25, 0.5);
    common::assert_round_trip(&s);
}

#[test]
fn specular_weakened_or_tinted_keeps_a_white_sphere_invisible_and_agrees() {
    // KHR_materials_specular: what the dielectric does not reflect the
    // white base does, channel by channel.
    for (specular, color) in [(0.0, [1.0, 1.0, 1.0]), (0.6, [3.0, 1.0, 0.2])] {
        let m = json!({"type": "pbr", "metallic": 0, "roughness": 0.4, "specular": specular,
            "specular_color": color});
        common::assert_invisible(
            &common::sky_sphere(m),
            48,
            0.015,
            &format!("specular {specular} colour {color:?}"),
        );
    }
    let m = json!({"type": "pbr", "base_color": [0.2, 0.3, 0.5], "metallic": 0, "roughness": 0.3,
        "specular": 0.8, "specular_color": [4, 1, 0.2]});
    assert_backends_agree(&common::sky_sphere(m), (24, 24), &box_quality(), 64);
}

#[test]
fn bad_specular_is_named_and_good_survives_the_round_trip() {
    for (field, bad) in [
        ("specular", json!(1.2)),
        ("specular", json!(-0.5)),
        ("specular_color", json!([1, -1, 1])),
        ("specular_color", json!([1, 1, 1000])),
    ] {
        let mut m = json!({"type": "pbr"});
        m[field] = bad;
        common::assert_material_refused(&m, &format!("materials.m.{field}"));
    }
    let s = common::sky_sphere(
        json!({"type": "pbr", "specular": 0.5, "specular_color": [1, 0.5, 0.25]}),
    );
    let text = common::assert_round_trip(&s);
    assert!(
        text.contains("\"specular\":0.5,\"specular_color\":[1.0,0.5,0.25]"),
        "{text}"
    );
    let plain =
        serde_json::to_string(&common::sky_sphere(json!({"type": "pbr"})).to_json()).expect("json");
    assert!(
        !plain.contains("specular"),
        "defaults are not written: {plain}"
    );
}
