//! Vertex colours (PLY's red/green/blue, glTF's COLOR_0) multiply the base
//! colour, on every backend:
//!
//! - a white diffuse quad of two triangles under a uniform white sky,
//!   alone: every path sees the sky after one bounce, so each pixel shows
//!   its albedo (in expectation), the vertex colours interpolated across
//!   the quad, which vary linearly here; each column's mean is that closed
//!   form within its standard error;
//! - a quad of one colour everywhere renders as a `diffuse` quad of that
//!   albedo (its twin), lit by a lamp.

mod common;

use common::{assert_agree, backends, region, render_on};
use pathstream::render::texture::srgb_table;
use pathstream::render::{Quality, Scene};
use serde_json::{json, Value};

fn quality() -> Quality {
    Quality {
        seed: 5,
        ..Quality::default()
    }
}

/// An ASCII PLY quad over [-1, 1]^2 at z = 0 facing +z, two triangles,
/// with sRGB byte colours at its corners (-x-y, +x-y, +x+y, -x+y).
fn quad_ply(colors: [[u8; 3]; 4]) -> String {
    let corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]];
    let mut s = "ply\nformat ascii 1.0\nelement vertex 4\n\
        property float x\nproperty float y\nproperty float z\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        .to_owned();
    for ([x, y], [r, g, b]) in corners.iter().zip(colors) {
        s.push_str(&format!("{x} {y} 0 {r} {g} {b}\n"));
    }
    s.push_str("3 0 1 2\n3 0 2 3\n");
    s
}

/// A scene of `objects` (the PLY placed as a model), `environment`
/// radiance and `materials`, seen orthographically face on.
fn scene(dir: &tempfile::TempDir, ply: &str, environment: f64, extra: Value) -> Scene {
    std::fs::write(dir.path().join("quad.ply"), ply).expect("ply");
    let mut objects = vec![json!({"type": "model", "file": "quad.ply"})];
    objects.extend(extra["objects"].as_array().cloned().unwrap_or_default());
    let environment = [environment; 3];
    let doc = json!({
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40,
            "projection": "orthographic", "ortho_height": 2},
        "environment": environment,
        "materials": extra.get("materials").cloned().unwrap_or(json!({})),
        "objects": objects,
    });
    let file = dir.path().join("scene.json");
    std::fs::write(&file, doc.to_string()).expect("scene");
    pathstream::resolve::load_scene(file.to_str().expect("utf-8")).expect("loads")
}

fn linear(c: [u8; 3]) -> [f64; 3] {
    c.map(|b| f64::from(srgb_table()[b as usize]))
}

#[test]
fn colours_interpolate_across_the_quad_as_the_closed_form_says() {
    let dir = tempfile::tempdir().expect("tempdir");
    // Left edge one colour, right edge another: linear in x on both
    // triangles.
    let (left, right) = ([230, 40, 120], [20, 200, 90]);
    let s = scene(&dir, &quad_ply([left, right, right, left]), 1.0, json!({}));
    let (a, b) = (linear(left), linear(right));
    let n = 16;
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &s, n, n, &quality(), 256);
        // Columns of pixels clear of the edges (the pixel filter's reach,
        // where the sky shows).
        for x in 2..n - 2 {
            let r = region(&film, x..x + 1, 2..n - 2);
            let t = (f64::from(x) + 0.5) / f64::from(n);
            for k in 0..3 {
                let want = a[k] + (b[k] - a[k]) * t;
                let se = r.var[k].sqrt();
                assert!(
                    (r.mean[k] - want).abs() <= 1e-4 + 4.5 * se,
                    "{name}: column {x} channel {k}: {} vs {want} (se {se:.1e})",
                    r.mean[k]
                );
            }
        }
    }
}

#[test]
fn a_uniform_colour_renders_as_its_diffuse_twin() {
    let dir = tempfile::tempdir().expect("tempdir");
    let c = [200, 120, 60];
    let lamp = json!({"materials": {"lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [8, 8, 8]}},
        "objects": [{"type": "quad", "corner": [3, -1, 1], "edge_u": [0, 2, 0], "edge_v": [-1, 0, 1], "material": "lamp"}]});
    let coloured = scene(&dir, &quad_ply([c; 4]), 0.0, lamp.clone());
    let mut twin_extra = lamp.clone();
    twin_extra["materials"]["paint"] = json!({"type": "diffuse", "albedo": linear(c)});
    twin_extra["objects"]
        .as_array_mut()
        .expect("objects")
        .push(json!({"type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0], "edge_v": [0, 2, 0], "material": "paint"}));
    // The twin's scene still holds the PLY, moved far out of sight.
    let far = quad_ply([c; 4]).replace(" 0 200", " -100 200");
    let twin = scene(&dir, &far, 0.0, twin_extra);
    for (name, mut backend) in backends() {
        let a = render_on(&mut backend, &coloured, 24, 24, &quality(), 64);
        let b = render_on(&mut backend, &twin, 24, 24, &quality(), 64);
        let what = format!("{name}: uniform vertex colour vs diffuse albedo");
        assert_agree(&a, &b, 6, 4.5, 1e-4, &what);
    }
}
