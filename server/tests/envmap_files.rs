//! Environment map files: a real map (a 64 x 32 reduction of Poly Haven's
//! CC0 "venice sunset", `tests/data/sunset-64.hdr`) and generated OpenEXR
//! files read through a scene file, kept by edits without being read
//! again; broken files and bad settings refused with the JSON path and the
//! problem named, on the command line too (exit code 2).

use pathstream::render::scene::{EnvironmentJson, Scene};
use pathstream::resolve::load_scene;
use std::path::Path;
use std::sync::Arc;

const SUNSET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/sunset-64.hdr");

/// A scene file in `dir` lit by `environment`.
fn scene_file(dir: &Path, environment: serde_json::Value) -> String {
    let json = serde_json::json!({
        "camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "vfov_deg": 40},
        "materials": {"white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]}},
        "objects": [{"type": "sphere", "center": [0, 0.5, 0], "radius": 0.5, "material": "white"}],
        "environment": environment
    });
    let path = dir.join("scene.json");
    std::fs::write(&path, json.to_string()).expect("write scene");
    path.to_string_lossy().into_owned()
}

/// An OpenEXR file of `w` x `h` float RGB texels, all `rgb`.
fn exr(w: u32, h: u32, rgb: [f32; 3]) -> Vec<u8> {
    use image::ImageEncoder;
    let texels: Vec<f32> = (0..w * h).flat_map(|_| rgb).collect();
    let mut bytes = std::io::Cursor::new(Vec::new());
    image::codecs::openexr::OpenExrEncoder::new(&mut bytes)
        .write_image(
            bytemuck::cast_slice(&texels),
            w,
            h,
            image::ExtendedColorType::Rgb32F,
        )
        .expect("encode");
    bytes.into_inner()
}

#[test]
fn a_real_map_is_read_through_its_scene_and_kept_by_edits() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::copy(SUNSET, dir.path().join("sunset.hdr")).expect("copy");
    let path = scene_file(
        dir.path(),
        serde_json::json!({"map": "sunset.hdr", "intensity": 2, "rotation_deg": 30, "visible": false}),
    );
    let scene = load_scene(&path).expect("loads");
    let m = scene.environment_map.as_ref().expect("a map");
    assert_eq!((m.map.width, m.map.height), (64, 32));
    // The sun: the brightest texel is far above the mean.
    let peak = m.map.texels.iter().map(|t| t[0]).fold(0.0, f32::max);
    assert!(
        f64::from(peak) > 20.0 * m.map.mean[0],
        "peak {peak}, mean {:?}",
        m.map.mean
    );
    // Back to JSON and through an edit: the same settings, the same image,
    // not read again.
    let json = scene.to_json();
    let Some(EnvironmentJson::Map(j)) = &json.environment else {
        panic!("{:?}", json.environment)
    };
    assert_eq!((j.intensity, j.rotation_deg, j.visible), (2.0, 30.0, false));
    let again = scene.revalidate(&json).expect("revalidates");
    let kept = again.environment_map.as_ref().expect("a map");
    assert!(
        Arc::ptr_eq(&kept.map, &m.map),
        "the edit read the map again"
    );
    assert_eq!(again, scene);
}

#[test]
fn generated_exr_files_read_to_their_values() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("flat.exr"), exr(8, 4, [0.5, 1.5, 2.5])).expect("write");
    let path = scene_file(dir.path(), serde_json::json!({"map": "flat.exr"}));
    let scene = load_scene(&path).expect("loads");
    let m = &scene.environment_map.as_ref().expect("a map").map;
    assert_eq!((m.width, m.height), (8, 4));
    assert!(m.texels.iter().all(|t| *t == [0.5, 1.5, 2.5]));
    assert!((m.mean[2] - 2.5).abs() < 1e-9, "{:?}", m.mean);
}

/// The scene error for a map file of `bytes` named `name`, or for settings
/// `environment` (the file then being the real map).
fn refusal(name: &str, bytes: &[u8], environment: Option<serde_json::Value>) -> String {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join(name), bytes).expect("write");
    let env = environment.unwrap_or_else(|| serde_json::json!({"map": name}));
    let path = scene_file(dir.path(), env);
    load_scene(&path).expect_err("refused").to_string()
}

#[test]
fn broken_files_and_bad_settings_are_refused_by_name() {
    let real = std::fs::read(SUNSET).expect("read");
    let mut unknown = exr(4, 2, [1.0; 3]);
    // The header's compression attribute: its name, its type, its size (1)
    // and the value, which no OpenEXR version defines.
    let key = b"compression\0compression\0\x01\0\0\0";
    let at = unknown
        .windows(key.len())
        .position(|w| w == key)
        .expect("attribute")
        + key.len();
    unknown[at] = 42;
    let huge = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 50000 +X 100000\n".to_vec();
    type Case = (
        &'static str,
        Vec<u8>,
        Option<serde_json::Value>,
        &'static [&'static str],
    );
    let cases: Vec<Case> = vec![
        (
            "cut.hdr",
            real[..real.len() / 2].to_vec(),
            None,
            &["environment.map", "cut.hdr"],
        ),
        (
            "odd.exr",
            unknown,
            None,
            &["environment.map", "odd.exr", "compression"],
        ),
        ("huge.hdr", huge, None, &["huge.hdr", "100000x50000"]),
        (
            "nan.exr",
            exr(4, 2, [1.0, f32::NAN, 1.0]),
            None,
            &["nan.exr", "NaN", "finite"],
        ),
        (
            "neg.exr",
            exr(4, 2, [1.0, -3.0, 1.0]),
            None,
            &["neg.exr", "-3", "non-negative"],
        ),
        (
            "map.png",
            b"\x89PNG".to_vec(),
            None,
            &["map.png", ".hdr or .exr"],
        ),
        (
            "a.hdr",
            real.clone(),
            Some(serde_json::json!({"map": "missing.hdr"})),
            &["environment.map", "missing.hdr"],
        ),
        (
            "a.hdr",
            real.clone(),
            Some(serde_json::json!({"map": "a.hdr", "intensity": -1})),
            &["environment.intensity"],
        ),
        (
            "a.hdr",
            real.clone(),
            Some(serde_json::json!({"map": "a.hdr", "rotation_deg": 1e300})),
            &["environment.rotation_deg"],
        ),
        (
            "a.hdr",
            real.clone(),
            Some(serde_json::json!({"map": "a.hdr", "background": [0, -1, 0]})),
            &["environment.background"],
        ),
        (
            "a.hdr",
            real.clone(),
            Some(serde_json::json!({"map": "a.hdr", "exposure": 2})),
            &["environment", "exposure"],
        ),
        (
            "a.hdr",
            real,
            Some(serde_json::json!(3)),
            &["environment", "[r, g, b]"],
        ),
    ];
    for (name, bytes, env, words) in cases {
        let e = refusal(name, &bytes, env);
        for w in words {
            assert!(e.contains(w), "{name}: '{e}' does not say '{w}'");
        }
    }
    // Over the API there are no files: a map file is refused by name.
    let json = serde_json::json!({
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "environment": {"map": "studio.hdr"}
    });
    let e = Scene::from_json_str(&json.to_string()).expect_err("no files");
    assert!(e.to_string().contains("environment.map"), "{e}");
}

#[test]
fn the_command_line_exits_2_naming_a_broken_map() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("cut.hdr"), b"#?RADIANCE\n").expect("write");
    let path = scene_file(dir.path(), serde_json::json!({"map": "cut.hdr"}));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(["render", "--scene", &path, "--width", "8", "--height", "8"])
        .args(["--spp", "1", "--out"])
        .arg(dir.path().join("x.png"))
        .output()
        .expect("runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("environment.map") && stderr.contains("cut.hdr"),
        "{stderr}"
    );
}

#[test]
fn the_command_line_lights_any_scene_with_a_map_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.pfm");
    let run = |map: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
            .args([
                "render", "--scene", "cornell", "--width", "8", "--height", "8",
            ])
            .args(["--spp", "2", "--environment", map, "--env-rotation", "45"])
            .arg("--out")
            .arg(&out)
            .output()
            .expect("runs")
    };
    let ok = run(SUNSET);
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    assert!(out.is_file());
    let missing = run("/no/such/map.exr");
    let stderr = String::from_utf8_lossy(&missing.stderr);
    assert_eq!(missing.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--environment") && stderr.contains("map.exr"),
        "{stderr}"
    );
}
