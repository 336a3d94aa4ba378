//! Model files end to end: the Stanford bunny and generated files through
//! `pathstream render` and `resolve::load_scene`; malformed files exit 2 naming the
//! problem.

mod common;

use common::bunny;
use pathstream::model::write::write_ply_binary;
use pathstream::render::output::decode_pfm;

use std::path::Path;
use std::process::{Command, Output};
use std::sync::Arc;

fn pathstream(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(args)
        .output()
        .expect("runs")
}

fn path_str(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn the_stanford_bunny_loads_and_renders_framed_under_the_default_sky() {
    let Some(mesh) = bunny() else { return };
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), (1839, 3674));
    let dir = tempfile::tempdir().expect("tempdir");
    let ply = dir.path().join("bunny.ply");
    let mut f = std::fs::File::create(&ply).expect("create");
    write_ply_binary(&mesh, &mut f).expect("write");
    drop(f);

    let scene = pathstream::resolve::load_scene(path_str(&ply)).expect("loads");
    assert_eq!(scene.unique_triangles(), 3674);

    let out_file = dir.path().join("bunny.pfm");
    let out = pathstream(&[
        "render",
        "--scene",
        path_str(&ply),
        "--width",
        "48",
        "--height",
        "48",
        "--spp",
        "32",
        "--backend",
        "cpu",
        "--out",
        path_str(&out_file),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "render failed: {stderr}");
    assert!(
        stderr.contains("warning: ") && stderr.contains("no emitters") && stderr.contains("framed"),
        "{stderr}"
    );
    let (w, h, img) = decode_pfm(&std::fs::read(&out_file).expect("pfm")).expect("decode");
    assert_eq!((w, h), (48, 48));
    // The corners see the sky (radiance exactly 1); the middle sees the
    // bunny, diffuse 0.8 under that sky: darker than the sky, not black.
    for (x, y) in [(0, 0), (47, 0), (0, 47), (47, 47)] {
        assert_eq!(img[y * 48 + x], [1.0, 1.0, 1.0], "corner ({x}, {y})");
    }
    let centre: f64 = (20..28)
        .flat_map(|y| (20..28).map(move |x| (x, y)))
        .map(|(x, y)| f64::from(img[y * 48 + x][1]))
        .sum::<f64>()
        / 64.0;
    assert!(centre > 0.1 && centre < 0.85, "centre radiance {centre}");
}

const CUBE_OBJ: &str = "mtllib cube.mtl
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
usemtl clay
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 4 7 3
f 4 8 7
f 1 5 8
usemtl glow
f 1 8 4
f 2 3 7
f 2 7 6
";

const CUBE_MTL: &str = "newmtl clay
Kd 0.6 0.5 0.4
newmtl glow
Kd 0 0 0
Ke 5 5 5
";

#[test]
fn a_scene_file_places_a_model_file_twice_and_stores_it_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("cube.obj"), CUBE_OBJ).expect("obj");
    std::fs::write(dir.path().join("cube.mtl"), CUBE_MTL).expect("mtl");
    let scene_file = dir.path().join("two.json");
    std::fs::write(
        &scene_file,
        serde_json::json!({
            "camera": {"position": [0, 2, 12], "look_at": [0, 0, 0], "vfov_deg": 45},
            "objects": [
                {"type": "mesh", "file": "cube.obj", "transform": {"translate": [-2, 0, 0]}},
                {"type": "mesh", "file": "cube.obj", "transform": {"translate": [2, 0, 0], "rotate": {"axis": [0, 1, 0], "deg": 45}}}
            ]
        })
        .to_string(),
    )
    .expect("scene");
    let scene = pathstream::resolve::load_scene(path_str(&scene_file)).expect("loads");
    assert_eq!(scene.imports.len(), 2);
    let (a, b) = (
        &scene.imports[0].instances[0].mesh,
        &scene.imports[1].instances[0].mesh,
    );
    assert!(Arc::ptr_eq(a, b), "one mesh, two placements");
    assert_eq!(scene.unique_triangles(), 12);
    let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["cube.obj/clay", "cube.obj/glow"]);
    // The glowing faces make both cubes emitters: no default sky.
    assert_eq!(scene.emitters().count(), 2);
    assert_eq!(scene.environment.to_array(), [0.0; 3]);
    // Written back, the files' materials stay out of the JSON.
    let json = serde_json::to_value(scene.to_json()).expect("json");
    assert!(
        json["materials"].as_object().is_some_and(|m| m.is_empty()),
        "{json}"
    );

    let out_file = dir.path().join("two.png");
    let out = pathstream(&[
        "render",
        "--scene",
        path_str(&scene_file),
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "4",
        "--out",
        path_str(&out_file),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A glTF file with a triangle and a camera node 3 units along +z.
fn gltf_with_camera() -> String {
    let mut bin = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            bin.extend_from_slice(&x.to_le_bytes());
        }
    }
    const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for chunk in bin.chunks(3) {
        let n = chunk
            .iter()
            .enumerate()
            .fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for i in 0..4 {
            b64.push(if i <= chunk.len() {
                char::from(B64[(n >> (18 - 6 * i) & 63) as usize])
            } else {
                '='
            });
        }
    }
    serde_json::json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{b64}")}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.25, 0.25, 3]}],
        "scenes": [{"nodes": [0, 1]}],
        "scene": 0
    })
    .to_string()
}

#[test]
fn a_gltf_model_brings_its_camera() {
    let dir = tempfile::tempdir().expect("tempdir");
    let file = dir.path().join("tri.gltf");
    std::fs::write(&file, gltf_with_camera()).expect("gltf");
    let scene = pathstream::resolve::load_scene(path_str(&file)).expect("loads");
    let c = scene.camera;
    assert!(
        (c.position - glam::DVec3::new(0.25, 0.25, 3.0)).length() < 1e-9,
        "{c:?}"
    );
    let forward = (c.look_at - c.position).normalize();
    assert!(
        (forward - glam::DVec3::new(0.0, 0.0, -1.0)).length() < 1e-9,
        "{c:?}"
    );
    assert!((c.vfov_deg - 0.8f64.to_degrees()).abs() < 1e-9);
    assert!(
        !scene.warnings.iter().any(|w| w.contains("framed")),
        "{:?}",
        scene.warnings
    );
}

#[test]
fn malformed_model_files_exit_2_naming_the_problem() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.png");
    let mut cases: Vec<(String, Vec<u8>, &str)> = vec![
        ("nan.obj".into(), b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n".to_vec(), "line 3"),
        ("range.obj".into(), b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n".to_vec(), "line 4"),
        ("empty.obj".into(), b"v 0 0 0\n".to_vec(), "no triangles"),
        ("absurd.ply".into(), b"ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec(), "4000000000"),
    ];
    if let Some(mesh) = bunny() {
        let mut ply = Vec::new();
        write_ply_binary(&mesh, &mut ply).expect("write");
        ply.truncate(ply.len() / 2);
        cases.push(("cut.ply".into(), ply, "truncated"));
    }
    for (name, bytes, expect) in &cases {
        let file = dir.path().join(name);
        std::fs::write(&file, bytes).expect("write");
        let r = pathstream(&[
            "render",
            "--scene",
            path_str(&file),
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            path_str(&out),
        ]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{name}: {stderr}");
        assert!(
            stderr.contains(name.as_str()) && stderr.contains(expect),
            "{name}: expected '{expect}' in: {stderr}"
        );
    }
    // A scene file naming a file that is not there.
    let scene_file = dir.path().join("missing.json");
    std::fs::write(
        &scene_file,
        r#"{"objects": [{"type": "model", "file": "nowhere.glb"}]}"#,
    )
    .expect("write");
    let r = pathstream(&[
        "render",
        "--scene",
        path_str(&scene_file),
        "--out",
        path_str(&out),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("objects[0].file") && stderr.contains("nowhere.glb"),
        "{stderr}"
    );
}
