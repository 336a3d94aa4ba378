//! Every scene validation rule rejects its input with the JSON path of the
//! offending field and a reason.

use pathstream::render::Scene;
use serde_json::{json, Value};

fn valid() -> Value {
    json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "vfov_deg": 40},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [4, 4, 4]},
            "glass": {"type": "glass", "ior": 1.5}
        },
        "objects": [
            {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white"},
            {"type": "quad", "corner": [-1, 2, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "lamp"}
        ]
    })
}

/// Applies `edit` to the valid scene and expects an error at `path`
/// whose reason contains `reason`.
fn rejects(edit: impl FnOnce(&mut Value), path: &str, reason: &str) {
    let mut v = valid();
    edit(&mut v);
    let err = Scene::from_json_str(&v.to_string()).expect_err(path);
    assert_eq!(err.path, path, "{err}");
    assert!(err.reason.contains(reason), "expected '{reason}' in: {err}");
    assert!(err.to_string().starts_with(path), "{err}");
}

#[test]
fn the_valid_scene_is_accepted_and_defaults_apply() {
    let s = Scene::from_json_str(&valid().to_string()).expect("valid");
    assert_eq!(
        s.light,
        Some(1),
        "the first emissive object is the light by default"
    );
    assert_eq!(s.camera.near_clip, 0.0);
}

#[test]
fn malformed_json_and_wrong_types() {
    let err = Scene::from_json_str("{\"camera\": ").expect_err("truncated");
    assert!(err.reason.contains("EOF"), "{err}");
    rejects(
        |v| v["objects"][0]["radius"] = json!("big"),
        "objects[0].radius",
        "invalid type",
    );
    rejects(
        |v| v["camera"]["position"] = json!([1, 2]),
        "camera.position",
        "invalid length",
    );
    let text = valid()
        .to_string()
        .replace("\"radius\":1", "\"radius\":1e400");
    let err = Scene::from_json_str(&text).expect_err("1e400");
    assert_eq!(err.path, "objects[0].radius", "{err}");
    assert!(err.reason.contains("number out of range"), "{err}");
}

#[test]
fn unknown_fields_and_kinds() {
    rejects(
        |v| v["colour"] = json!(1),
        "colour",
        "unknown field `colour`",
    );
    rejects(
        |v| v["camera"]["fov"] = json!(1),
        "camera.fov",
        "unknown field `fov`",
    );
    rejects(
        |v| v["materials"]["white"]["shiny"] = json!(true),
        "materials.white.shiny",
        "unknown field `shiny`",
    );
    rejects(
        |v| v["objects"][1]["radius"] = json!(1),
        "objects[1].radius",
        "unknown field `radius`",
    );
    rejects(
        |v| v["materials"]["white"]["type"] = json!("metal"),
        "materials.white.type",
        "unknown type 'metal' (expected one of: diffuse, mirror, glass, pbr)",
    );
    rejects(
        |v| v["objects"][0]["type"] = json!("cube"),
        "objects[0].type",
        "unknown type 'cube'",
    );
    rejects(
        |v| {
            v["objects"][0].as_object_mut().map(|o| o.remove("type"));
        },
        "objects[0]",
        "missing field `type`",
    );
    rejects(
        |v| v["objects"][0] = json!(3),
        "objects[0]",
        "expected an object",
    );
    rejects(
        |v| v["materials"]["glass"]["fresnel"] = json!("fast"),
        "materials.glass.fresnel",
        "unknown variant `fast`",
    );
}

#[test]
fn missing_fields() {
    rejects(
        |v| {
            v["camera"].as_object_mut().map(|c| c.remove("vfov_deg"));
        },
        "camera",
        "missing field `vfov_deg`",
    );
    rejects(
        |v| {
            v.as_object_mut().map(|c| c.remove("objects"));
        },
        ".",
        "missing field `objects`",
    );
}

#[test]
fn unknown_material_names() {
    rejects(
        |v| v["objects"][0]["material"] = json!("whyte"),
        "objects[0].material",
        "unknown material 'whyte' (known: glass, lamp, white)",
    );
}

#[test]
fn shapes() {
    rejects(
        |v| v["objects"][0]["radius"] = json!(0),
        "objects[0].radius",
        "must be > 0",
    );
    rejects(
        |v| v["objects"][0]["radius"] = json!(-2),
        "objects[0].radius",
        "must be > 0",
    );
    rejects(
        |v| v["objects"][0]["radius"] = json!(1e300),
        "objects[0].radius",
        "must be at most",
    );
    rejects(
        |v| v["objects"][0]["center"] = json!([1e16, 0, 0]),
        "objects[0].center",
        "coordinates must be within",
    );
    rejects(
        |v| v["objects"][1]["edge_v"] = json!([4, 0, 0]),
        "objects[1].edge_v",
        "degenerate",
    );
    rejects(
        |v| v["objects"][1]["edge_u"] = json!([0, 0, 0]),
        "objects[1].edge_v",
        "degenerate",
    );
    rejects(
        |v| v["objects"] = json!([]),
        "objects",
        "at least one object",
    );
    rejects(|v| v["light"] = json!(2), "light", "out of range");
}

#[test]
fn materials() {
    rejects(
        |v| v["materials"]["white"]["albedo"] = json!([0.5, 1.5, 0.5]),
        "materials.white.albedo",
        "between 0 and 1",
    );
    rejects(
        |v| v["materials"]["white"]["albedo"] = json!([0.5, -0.1, 0.5]),
        "materials.white.albedo",
        "between 0 and 1",
    );
    rejects(
        |v| v["materials"]["lamp"]["emission"] = json!([1, -1, 1]),
        "materials.lamp.emission",
        "between 0 and",
    );
    rejects(
        |v| v["materials"]["glass"]["ior"] = json!(0.5),
        "materials.glass.ior",
        "between 1 and 10",
    );
    rejects(
        |v| v["materials"]["glass"]["ior"] = json!(11),
        "materials.glass.ior",
        "between 1 and 10",
    );
}

#[test]
fn camera() {
    rejects(
        |v| v["camera"]["up"] = json!([0, 0, 3]),
        "camera.up",
        "parallel to the view direction",
    );
    rejects(
        |v| v["camera"]["up"] = json!([0, 0, 0]),
        "camera.up",
        "zero vector",
    );
    rejects(
        |v| v["camera"]["look_at"] = json!([0, 0, 5]),
        "camera.look_at",
        "must differ from camera.position",
    );
    rejects(
        |v| v["camera"]["vfov_deg"] = json!(0),
        "camera.vfov_deg",
        "between 0 and 180",
    );
    rejects(
        |v| v["camera"]["vfov_deg"] = json!(180),
        "camera.vfov_deg",
        "between 0 and 180",
    );
    rejects(
        |v| v["camera"]["near_clip"] = json!(-1),
        "camera.near_clip",
        "must be >= 0",
    );
}

#[test]
fn non_finite_numbers_built_in_code_are_rejected() {
    // JSON text cannot spell NaN; scenes built in code can.
    let mut raw = Scene::from_json_str(&valid().to_string())
        .expect("valid")
        .to_json();
    raw.camera.as_mut().expect("camera").vfov_deg = f64::NAN;
    let err = Scene::from_json(&raw).expect_err("nan");
    assert_eq!(err.path, "camera.vfov_deg");
    assert!(err.reason.contains("finite"), "{err}");
    let mut raw = Scene::from_json_str(&valid().to_string())
        .expect("valid")
        .to_json();
    if let pathstream::render::scene::ObjectJson::Sphere(sphere) = &mut raw.objects[0] {
        sphere.center[2] = f64::INFINITY;
    }
    let err = Scene::from_json(&raw).expect_err("inf");
    assert_eq!(err.path, "objects[0].center[2]");
}
