//! Transmission, clear coat and specular textures (glTF's
//! `KHR_materials_transmission`, `_clearcoat` and `_specular` textures; a
//! scene names PNG files in the same `pbr` fields), on every backend:
//!
//! - each renders as its constant twin, the material with the texel's
//!   value as its factor: transmission and clear coat from red, the coat's
//!   roughness from green, specular from alpha, the specular colour from
//!   sRGB RGB. The texel's channels differ, so a slot that reads the wrong
//!   channel (or none) renders another image;
//! - the kernel's `shade_maps` gives the CPU's floats bit for bit with
//!   every slot textured at once;
//! - bad texture fields are named; a scene writes the names back and
//!   validates again to itself.

mod common;
mod parity;

use common::{assert_agree, backends, render_on};
use pathstream::render::texture::srgb_table;
use pathstream::render::{Quality, Scene};
use serde_json::{json, Value};

/// The one texel of `layers.png`: red, green, blue, alpha.
const TEXEL: [u8; 4] = [204, 51, 153, 102];

fn unorm(b: u8) -> f64 {
    f64::from(b) / 255.0
}

fn quality() -> Quality {
    Quality {
        seed: 11,
        ..Quality::default()
    }
}

/// A directory with `layers.png` (1 x 1, [`TEXEL`]).
fn textures() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("layers.png");
    image::save_buffer(&path, &TEXEL, 1, 1, image::ExtendedColorType::Rgba8).expect("png");
    dir
}

/// `pbr` material fields (on a base colour `base`) on a quad facing the
/// camera, lit by a lamp to its side, before a blue sky that shows through
/// what it transmits; the scene file in `dir`.
fn lit(dir: &tempfile::TempDir, base: [f64; 3], fields: Value) -> Result<Scene, String> {
    let mut m = json!({"type": "pbr", "base_color": base, "metallic": 0, "roughness": 0.4});
    for (k, v) in fields.as_object().expect("fields") {
        m[k] = v.clone();
    }
    let doc = json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40,
            "projection": "orthographic", "ortho_height": 2},
        "environment": [0.1, 0.2, 0.5],
        "materials": {"m": m,
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [8, 8, 8]}},
        "objects": [
            {"type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "m"},
            {"type": "quad", "corner": [3, -1, 1], "edge_u": [0, 2, 0], "edge_v": [-1, 0, 1], "material": "lamp"}],
    });
    let file = dir.path().join("scene.json");
    std::fs::write(&file, doc.to_string()).expect("scene");
    pathstream::resolve::load_scene(file.to_str().expect("utf-8")).map_err(|e| e.to_string())
}

fn assert_twins(dir: &tempfile::TempDir, base: [f64; 3], textured: Value, twin: Value, what: &str) {
    let a = lit(dir, base, textured).expect("textured loads");
    let b = lit(dir, base, twin).expect("twin loads");
    for (name, mut backend) in backends() {
        let fa = render_on(&mut backend, &a, 24, 24, &quality(), 64);
        let fb = render_on(&mut backend, &b, 24, 24, &quality(), 64);
        assert_agree(&fa, &fb, 6, 4.5, 1e-4, &format!("{name}: {what}"));
    }
}

#[test]
fn transmission_reads_red() {
    let dir = textures();
    let tex = json!({"texture": "layers.png"});
    assert_twins(
        &dir,
        [0.9, 0.7, 0.5],
        json!({"transmission": tex, "thin": true}),
        json!({"transmission": unorm(TEXEL[0]), "thin": true}),
        "transmission texture vs factor",
    );
}

#[test]
fn the_clear_coat_reads_red_and_its_roughness_green() {
    let dir = textures();
    // Over a black base only the coat reflects the lamp.
    assert_twins(
        &dir,
        [0.0; 3],
        json!({"clearcoat": {"texture": "layers.png", "factor": 0.75},
            "clearcoat_roughness": {"texture": "layers.png"}}),
        json!({"clearcoat": 0.75 * unorm(TEXEL[0]), "clearcoat_roughness": unorm(TEXEL[1])}),
        "clear coat textures vs factors",
    );
}

#[test]
fn specular_reads_alpha_and_its_colour_srgb() {
    let dir = textures();
    let srgb = |b: u8| f64::from(srgb_table()[b as usize]);
    assert_twins(
        &dir,
        [0.0; 3],
        json!({"specular": {"texture": "layers.png"},
            "specular_color": {"texture": "layers.png", "factor": [1, 2, 4]}}),
        json!({"specular": unorm(TEXEL[3]),
            "specular_color": [srgb(TEXEL[0]), 2.0 * srgb(TEXEL[1]), 4.0 * srgb(TEXEL[2])]}),
        "specular textures vs factors",
    );
}

#[test]
fn the_kernels_layer_maps_agree_with_the_cpus_bit_for_bit() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    // 3 x 2 texels of hashed bytes: bilinear weights at every lookup.
    let rgba: Vec<u8> = (0..24u64)
        .map(|i| (parity::uniform(i, 5) * 256.0) as u8)
        .collect();
    let path = dir.path().join("layers.png");
    image::save_buffer(&path, &rgba, 3, 2, image::ExtendedColorType::Rgba8).expect("png");
    let t = |extra: Value| {
        let mut v = json!({"texture": "layers.png", "wrap": ["mirror", "clamp"]});
        for (k, x) in extra.as_object().expect("object") {
            v[k] = x.clone();
        }
        v
    };
    let scene = lit(
        &dir,
        [0.9, 0.8, 0.7],
        json!({"metallic": t(json!({"factor": 0.6})), "roughness": t(json!({})),
            "transmission": t(json!({"factor": 0.9, "transform": {"rotation_deg": 30}})),
            "clearcoat": t(json!({"factor": 0.7})), "clearcoat_roughness": t(json!({"uv": 1})),
            "specular": t(json!({"factor": 0.8})), "specular_color": t(json!({"factor": [2, 1, 0.5]})),
            "normal": t(json!({"scale": 0.8})), "clearcoat_normal": t(json!({"scale": 1.3, "uv": 1})),
            "ior": 1.7}),
    )
    .expect("loads");
    let job = pathstream::render::RenderJob::new(&scene, 8, 8, &quality());
    parity::assert_maps_agree(&d, &job, 20_000);
}

#[test]
fn bad_layer_textures_are_named_and_good_ones_written_back() {
    let dir = textures();
    let base = [0.5; 3];
    for (fields, path, says) in [
        (
            json!({"clearcoat": {"texture": "nope.png"}}),
            "materials.m.clearcoat.texture",
            "nope.png",
        ),
        (
            json!({"specular": {"texture": "layers.png", "factor": 1.5}}),
            "materials.m.specular.factor",
            "between 0 and 1",
        ),
        (
            json!({"specular_color": {"texture": "layers.png", "factor": [1, -1, 1]}}),
            "materials.m.specular_color.factor",
            "between 0 and 100",
        ),
        (
            json!({"transmission": {"texture": "layers.png", "uv": 2}}),
            "materials.m.transmission.uv",
            "must be 0 or 1",
        ),
        (
            json!({"clearcoat_roughness": {"texture": "layers.png", "wrap": "wavy"}}),
            "materials.m.clearcoat_roughness",
            "wrap: expected",
        ),
    ] {
        let e = lit(&dir, base, fields.clone()).expect_err("refused");
        assert!(e.contains(path) && e.contains(says), "{fields}: {e}");
    }
    let scene = lit(
        &dir,
        base,
        json!({"clearcoat": {"texture": "layers.png", "factor": 0.75},
            "specular_color": {"texture": "layers.png"}}),
    )
    .expect("loads");
    let json = serde_json::to_value(scene.to_json()).expect("json");
    let m = &json["materials"]["m"];
    assert_eq!(
        m["clearcoat"],
        json!({"texture": "layers.png", "factor": 0.75}),
        "{m}"
    );
    assert_eq!(m["specular_color"], json!({"texture": "layers.png"}), "{m}");
    let again = scene.revalidate(&scene.to_json()).expect("valid again");
    assert_eq!(again, scene);
}

/// `dir` with `tilted.png`: one texel of a tangent-space normal tilted 30
/// degrees towards +u (+x on the quad), which turns the reflection of the
/// camera's direction onto the lamp.
fn tilted(dir: &tempfile::TempDir) {
    let n = [0.5f64, 0.0, 0.75f64.sqrt()];
    let texel = n.map(|c| ((c + 1.0) * 0.5 * 255.0).round() as u8);
    let path = dir.path().join("tilted.png");
    let rgba = [texel[0], texel[1], texel[2], 255];
    image::save_buffer(&path, &rgba, 1, 1, image::ExtendedColorType::Rgba8).expect("png");
}

/// A black base that reflects nothing itself (specular 0) under a smooth
/// coat: what the image shows is the coat's alone.
fn coat_only(extra: Value) -> Value {
    let mut m = json!({"specular": 0, "clearcoat": 1, "clearcoat_roughness": 0.1});
    for (k, v) in extra.as_object().expect("object") {
        m[k] = v.clone();
    }
    m
}

#[test]
fn a_coat_lies_on_the_unmapped_normal_not_on_the_bases_map() {
    // glTF: without its own normal map the coat follows the surface, so
    // the base's tilted map changes nothing where only the coat reflects.
    let dir = textures();
    tilted(&dir);
    assert_twins(
        &dir,
        [0.0; 3],
        coat_only(json!({"normal": {"texture": "tilted.png"}})),
        coat_only(json!({})),
        "a base normal map under a coat",
    );
}

#[test]
fn the_coats_own_normal_map_turns_its_highlight_on_every_backend() {
    let dir = textures();
    tilted(&dir);
    let scene = |extra: Value| lit(&dir, [0.0; 3], coat_only(extra)).expect("loads");
    let turned = scene(json!({"clearcoat_normal": {"texture": "tilted.png"}}));
    let flat = scene(json!({"clearcoat_normal": {"texture": "tilted.png", "scale": 0}}));
    for (name, mut backend) in backends() {
        let mean = |s: &Scene, b: &mut pathstream::render::Backend| {
            let film = render_on(b, s, 24, 24, &quality(), 32);
            common::region(&film, 4..20, 4..20).mean
        };
        let (t, f) = (mean(&turned, &mut backend), mean(&flat, &mut backend));
        // Turned, the coat mirrors the lamp (radiance 8, a 4% coat: ~0.3);
        // flat, it mirrors the dim sky above the camera (~0.02).
        assert!(
            t[0] > 5.0 * f[0] && t[0] > 0.1,
            "{name}: turned {t:?}, flat {f:?}"
        );
    }
    // A base map and the coat's own, different: the same image on every
    // backend, and with NEE on and off.
    let both = scene(json!({"normal": {"texture": "layers.png", "scale": 0.7},
        "clearcoat_normal": {"texture": "tilted.png"}, "base_color": [0.5, 0.4, 0.3], "specular": 1}));
    common::assert_backends_agree(&both, (24, 24), &quality(), 96);
    common::assert_nee_on_off_agree(&both, (24, 24), &quality(), 96);
}

#[test]
fn a_clear_coat_normal_map_is_validated_and_written_back() {
    let dir = textures();
    tilted(&dir);
    let e = lit(
        &dir,
        [0.5; 3],
        coat_only(json!({"clearcoat_normal": {"texture": "none.png"}})),
    )
    .expect_err("refused");
    assert!(
        e.contains("materials.m.clearcoat_normal") && e.contains("none.png"),
        "{e}"
    );
    let e = lit(
        &dir,
        [0.5; 3],
        coat_only(json!({"clearcoat_normal": {"texture": "tilted.png", "scale": "x"}})),
    )
    .expect_err("refused");
    assert!(e.contains("clearcoat_normal"), "{e}");
    let field = json!({"texture": "tilted.png", "scale": 0.5, "uv": 1});
    let scene = lit(
        &dir,
        [0.5; 3],
        coat_only(json!({"clearcoat_normal": field})),
    )
    .expect("loads");
    let json = serde_json::to_value(scene.to_json()).expect("json");
    assert_eq!(json["materials"]["m"]["clearcoat_normal"], field);
    assert_eq!(
        scene.revalidate(&scene.to_json()).expect("valid again"),
        scene
    );
}
