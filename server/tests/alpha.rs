//! Alpha-tested meshes (glTF `alphaMode`), on every backend: a lamp above a
//! floor, a quad between them, and an orthographic camera between the quad
//! and the floor looking down (so that it sees only the floor and the
//! shadow on it).
//!
//! - MASK: a quad whose texture's left half is transparent casts the
//!   shadow of its right half alone (the image of an opaque half quad).
//! - BLEND: a black quad of alpha 0.5 lets half the light through (the
//!   image is the mean of no quad and an opaque one).

mod common;

use common::{assert_agree, mesh_backends, pooled, regions, render_on};
use pathstream::model::write_glb::{glb, GlbMaterial, GlbTexture};
use pathstream::model::{MeshData, Wrap};
use pathstream::render::{Film, Quality, Scene};
use serde_json::{json, Value};

/// A quad in the z = 0 plane facing +z, x from `x0` to 1 and y from -1 to
/// 1, UVs covering the image once (u along +x).
fn quad(x0: f32) -> MeshData {
    let u0 = (x0 + 1.0) / 2.0;
    MeshData {
        name: "quad".into(),
        positions: vec![
            [x0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [x0, 1.0, 0.0],
        ],
        normals: None,
        uvs: [
            Some(vec![[u0, 1.0], [1.0, 1.0], [1.0, 0.0], [u0, 0.0]]),
            None,
        ],
        tangents: None,
        colors: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![0, 0],
    }
}

/// The floor scene with `occluder` (a `.glb`, or none) held flat at y = 1.
fn scene(dir: &tempfile::TempDir, name: &str, occluder: Option<Vec<u8>>) -> Scene {
    let mut objects = Vec::new();
    if let Some(bytes) = occluder {
        std::fs::write(dir.path().join(name), bytes).expect("glb");
        objects.push(json!({"type": "model", "file": name, "transform": {
            "translate": [0, 1, 0], "rotate": {"axis": [1, 0, 0], "deg": -90}, "scale": 0.5}}));
    }
    floor_scene(dir, name, objects, json!({}))
}

/// The floor and the lamp, with `objects` and `materials` added.
fn floor_scene(
    dir: &tempfile::TempDir,
    name: &str,
    objects: Vec<Value>,
    materials: Value,
) -> Scene {
    let mut all = vec![
        json!({"type": "quad", "corner": [-1, 0, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "white"}),
        json!({"type": "quad", "corner": [-0.5, 2, -0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1], "material": "lamp"}),
    ];
    all.extend(objects);
    let mut doc = json!({
        "camera": {"position": [0, 0.5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov_deg": 40,
                   "projection": "orthographic", "ortho_height": 2},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [10, 10, 10]},
        },
        "objects": all,
    });
    if let (Some(m), Some(extra)) = (doc["materials"].as_object_mut(), materials.as_object()) {
        m.extend(extra.clone());
    }
    let file = dir.path().join(format!("{name}.json"));
    std::fs::write(&file, doc.to_string()).expect("scene");
    pathstream::resolve::load_scene(file.to_str().expect("utf-8")).expect("loads")
}

fn black(alpha: f64, mode: &'static str) -> GlbMaterial {
    GlbMaterial {
        base_color: [0.0, 0.0, 0.0, alpha],
        alpha_mode: mode,
        metallic: 0.0,
        ..GlbMaterial::default()
    }
}

fn quality() -> Quality {
    Quality {
        seed: 11,
        ..Quality::default()
    }
}

#[test]
fn a_mask_cutout_shadows_with_its_opaque_part_only() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Left texel transparent, right opaque; clamped, so that the cutoff
    // 0.5 falls exactly on the middle (bilinear between texel centres).
    let mut cut = GlbTexture::new(2, 1, vec![255, 255, 255, 0, 255, 255, 255, 255]);
    cut.wrap = [Wrap::Clamp; 2];
    let masked = GlbMaterial {
        base_color_texture: Some(cut),
        ..black(1.0, "MASK")
    };
    let cutout = scene(&dir, "cutout.glb", Some(glb(&quad(-1.0), &masked)));
    let half = scene(
        &dir,
        "half.glb",
        Some(glb(&quad(0.0), &black(1.0, "OPAQUE"))),
    );
    let whole = scene(
        &dir,
        "whole.glb",
        Some(glb(&quad(-1.0), &black(1.0, "OPAQUE"))),
    );
    for (name, mut backend) in mesh_backends() {
        let what = format!("{name}: cutout");
        assert_cuts_out(&mut backend, [&cutout, &half, &whole], &what);
    }
}

/// `cutout` renders as `half` (the opaque part alone) does, not as
/// `whole`; the whole quad's image.
fn assert_cuts_out(
    backend: &mut pathstream::render::Backend,
    [cutout, half, whole]: [&Scene; 3],
    what: &str,
) -> Film {
    let a = render_on(backend, cutout, 24, 24, &quality(), 64);
    let b = render_on(backend, half, 24, 24, &quality(), 64);
    assert_agree(&a, &b, 6, 4.5, 1e-4, &format!("{what} vs half quad"));
    // And it is not the whole quad's shadow.
    let c = render_on(backend, whole, 24, 24, &quality(), 64);
    let (ma, mc) = (mean(&a), mean(&c));
    assert!(ma > 1.2 * mc, "{what} {ma} vs whole quad {mc}");
    c
}

fn mean(f: &Film) -> f64 {
    pooled(&regions(f, 6)).mean[0]
}

#[test]
fn a_blended_quad_lets_through_its_share_of_light() {
    let dir = tempfile::tempdir().expect("tempdir");
    let half = scene(
        &dir,
        "blend.glb",
        Some(glb(&quad(-1.0), &black(0.5, "BLEND"))),
    );
    let open = scene(&dir, "none", None);
    let shut = scene(
        &dir,
        "shut.glb",
        Some(glb(&quad(-1.0), &black(1.0, "OPAQUE"))),
    );
    for (name, mut backend) in mesh_backends() {
        let stats = |s: &Scene, backend: &mut pathstream::render::Backend| {
            let r = pooled(&regions(&render_on(backend, s, 24, 24, &quality(), 128), 6));
            (r.mean[0], r.var[0])
        };
        let (h, vh) = stats(&half, &mut backend);
        let (o, vo) = stats(&open, &mut backend);
        let (s, vs) = stats(&shut, &mut backend);
        let want = 0.5 * (o + s);
        let z = (h - want).abs() / (vh + 0.25 * (vo + vs)).sqrt();
        eprintln!("{name}: blend {h}, open {o}, shut {s}: z {z:.2}");
        assert!(
            z < 4.5,
            "{name}: blend {h} vs mean of open and shut {want} (z {z:.1})"
        );
        assert!(o > 1.5 * s, "{name}: the quad shades the floor: {o} vs {s}");
    }
}

/// The occluder's place as a scene JSON quad: x from -0.5 to 0.5 (u along
/// +x), z from -0.5 to 0.5, at y = 1, as the `.glb` quad is placed.
fn json_quad(material: &str) -> Value {
    json!({"type": "quad", "corner": [-0.5, 1, 0.5], "edge_u": [1, 0, 0], "edge_v": [0, 0, -1], "material": material})
}

#[test]
fn a_scene_json_quad_cuts_out_and_blends_as_a_model_file_does() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Left texel transparent, right opaque (as the .glb test's texture).
    image::RgbaImage::from_raw(2, 1, vec![255, 255, 255, 0, 255, 255, 255, 255])
        .expect("2x1")
        .save(dir.path().join("cut.png"))
        .expect("png");
    let cutout = floor_scene(
        &dir,
        "json-cutout",
        vec![json_quad("leaf")],
        json!({"leaf": {"type": "diffuse", "alpha": {"mode": "mask"},
                        "albedo": {"texture": "cut.png", "factor": [0, 0, 0], "wrap": "clamp"}}}),
    );
    let world = pathstream::render::world::World::new(&cutout, cutout.camera.position);
    assert_eq!(
        world.instances.len(),
        1,
        "the cut-out quad is a mesh instance"
    );
    assert!(world.instances[0].alpha.is_some(), "with its alpha test");
    let half = scene(
        &dir,
        "half.glb",
        Some(glb(&quad(0.0), &black(1.0, "OPAQUE"))),
    );
    let blend = floor_scene(
        &dir,
        "json-blend",
        vec![json_quad("smoke")],
        json!({"smoke": {"type": "pbr", "base_color": [0, 0, 0], "metallic": 0,
                         "alpha": {"mode": "blend", "factor": 0.5}}}),
    );
    let blend_glb = scene(
        &dir,
        "blend.glb",
        Some(glb(&quad(-1.0), &black(0.5, "BLEND"))),
    );
    let whole = floor_scene(
        &dir,
        "json-whole",
        vec![json_quad("black")],
        json!({"black": {"type": "diffuse", "albedo": [0, 0, 0]}}),
    );
    for (name, mut backend) in mesh_backends() {
        let what = format!("{name}: JSON cutout");
        let c = assert_cuts_out(&mut backend, [&cutout, &half, &whole], &what);
        let mc = mean(&c);
        let d = render_on(&mut backend, &blend, 24, 24, &quality(), 64);
        let e = render_on(&mut backend, &blend_glb, 24, 24, &quality(), 64);
        assert_agree(
            &d,
            &e,
            6,
            4.5,
            1e-4,
            &format!("{name}: JSON blend vs .glb blend"),
        );
        let md = mean(&d);
        assert!(
            md > 1.2 * mc,
            "{name}: blend {md} lets more through than shut {mc}"
        );
    }
}

/// The error of a scene with `material` on `object`'s shape.
fn error_of(material: Value, object: Value) -> String {
    let doc = json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40},
        "materials": {"m": material},
        "objects": [object],
    });
    match Scene::from_json_str(&doc.to_string()) {
        Ok(_) => "accepted".into(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn alpha_fields_are_checked_by_name_and_written_back() {
    let quad = json!({"type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "m"});
    let sphere = json!({"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"});
    let diffuse =
        |alpha: Value| json!({"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "alpha": alpha});
    let cases = [
        (
            diffuse(json!({"mode": "mask", "cutoff": 1.5})),
            quad.clone(),
            "materials.m.alpha.cutoff: must be between 0 and 1",
        ),
        (
            diffuse(json!({"mode": "blend", "factor": -0.1})),
            quad.clone(),
            "materials.m.alpha.factor: must be between 0 and 1",
        ),
        (
            diffuse(json!({"mode": "blend", "cutoff": 0.5})),
            quad.clone(),
            "materials.m.alpha.cutoff: only `mask` has a cutoff",
        ),
        (
            diffuse(json!({"mode": "dither"})),
            quad.clone(),
            "materials.m",
        ),
        (
            diffuse(json!({"mode": "mask"})),
            sphere,
            "objects[0].material: an alpha-tested material",
        ),
        (
            json!({"type": "glass", "ior": 1.5, "alpha": {"mode": "mask"}}),
            quad.clone(),
            "alpha",
        ),
    ];
    for (material, object, want) in cases {
        let got = error_of(material.clone(), object);
        assert!(
            got.contains(want),
            "{material}: {got:?} should name {want:?}"
        );
    }
    // Accepted ones write themselves back as given.
    for alpha in [
        json!({"mode": "mask", "cutoff": 0.3}),
        json!({"mode": "blend", "factor": 0.25}),
    ] {
        let doc = json!({
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40},
            "materials": {"m": diffuse(alpha.clone())},
            "objects": [quad.clone()],
        });
        let s = Scene::from_json_str(&doc.to_string()).expect("valid");
        let back = serde_json::to_value(s.to_json()).expect("json");
        assert_eq!(back["materials"]["m"]["alpha"], alpha);
        let again = Scene::from_json_value(back).expect("reloads");
        assert_eq!(again.materials, s.materials);
    }
}
