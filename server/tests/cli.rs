//! The `pathstream` binary: `render` writes images and one summary line;
//! bad input exits with code 2 and a one-line message naming the problem.

mod common;
mod http;

use std::path::Path;
use std::process::{Command, Output};

fn pathstream(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(args)
        .output()
        .expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn render(dir: &Path, file: &str, extra: &[&str]) -> (Output, std::path::PathBuf) {
    let out = dir.join(file);
    let mut args = vec![
        "render", "--scene", "cornell", "--width", "16", "--height", "12",
    ];
    args.extend_from_slice(extra);
    let out_str = out.to_str().expect("utf-8 path").to_owned();
    args.extend_from_slice(&["--out", &out_str]);
    (pathstream(&args), out)
}

#[test]
fn scenes_lists_every_builtin_and_prints_json() {
    let out = pathstream(&["scenes"]);
    assert!(out.status.success());
    let listing = text(&out.stdout);
    for name in [
        "cornell",
        "cornell-glass",
        "cornell-quads",
        "smallpt",
        "furnace",
    ] {
        assert!(
            listing.lines().any(|l| l.starts_with(name)),
            "{name} missing:\n{listing}"
        );
    }
    let out = pathstream(&["scenes", "--json", "smallpt"]);
    assert!(out.status.success());
    let scene =
        pathstream::render::Scene::from_json_str(&text(&out.stdout)).expect("valid scene JSON");
    assert_eq!(
        scene,
        pathstream::resolve::load_scene("smallpt").expect("smallpt")
    );
    // The bench's scenes too: listed, and printed as the scene they are
    // (what a comparison script gives another renderer).
    for (name, _) in pathstream::bench::scenes::NAMES {
        assert!(
            listing.lines().any(|l| l.starts_with(name)),
            "{name} missing:\n{listing}"
        );
    }
    // A scene made in memory says it has no JSON form.
    let out = pathstream(&["scenes", "--json", "cornell-mesh-textured"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out.stderr).contains("cornell-mesh-textured has no JSON form"));
    let out = pathstream(&["scenes", "--json", "cornell-mesh"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    pathstream::render::Scene::from_json_str(&text(&out.stdout)).expect("valid scene JSON");
    let printed: serde_json::Value = serde_json::from_str(&text(&out.stdout)).expect("JSON");
    let scene = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    let expected = serde_json::to_string(&scene.to_json()).expect("json");
    assert_eq!(
        printed,
        serde_json::from_str::<serde_json::Value>(&expected).expect("json")
    );
}

#[test]
fn output_into_a_closed_pipe_ends_quietly() {
    // `pathstream scenes --json cornell-mesh | head`: the reader has gone
    // before the first write.
    for args in [
        &["scenes", "--json", "cornell-mesh"][..],
        &["scenes"],
        &["devices"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream"))
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("starts");
        drop(child.stdout.take());
        let out = child.wait_with_output().expect("ends");
        assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
        assert!(!text(&out.stderr).contains("panicked"), "{args:?}");
    }
}

#[test]
fn render_writes_a_png_and_prints_one_summary_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (out, path) = render(dir.path(), "a.png", &["--spp", "8"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let img = image::open(&path).expect("a PNG");
    assert_eq!((img.width(), img.height()), (16, 12));
    let summary = text(&out.stdout);
    assert_eq!(summary.lines().count(), 1, "{summary}");
    for part in [
        "cornell 16x12: 8 spp in ",
        " M paths/s, error estimate ",
        "%, backend cpu (rayon, ",
    ] {
        assert!(summary.contains(part), "'{part}' missing from: {summary}");
    }
}

#[test]
fn render_on_every_device_prints_each_devices_share_and_the_one_device_image() {
    let dir = tempfile::tempdir().expect("tempdir");
    let flags = ["--spp", "64", "--seed", "3"];
    let (all, all_path) = render(
        dir.path(),
        "all.pfm",
        &[&flags[..], &["--backend", "all"]].concat(),
    );
    assert!(all.status.success(), "{}", text(&all.stderr));
    let summary = text(&all.stdout);
    assert!(summary.contains("backend all ("), "{summary}");
    let devices: Vec<&str> = summary.lines().skip(1).collect();
    assert!(
        devices
            .iter()
            .any(|l| l.trim_start().starts_with("cpu (rayon")),
        "{summary}"
    );
    assert!(
        devices
            .iter()
            .all(|l| l.contains("M paths/s") && l.contains("% of the samples")),
        "{summary}"
    );
    // Rayon alone (or an OpenCL device fallen back to rayon) would pass the
    // rest: where CI is set, PoCL must have rendered a share itself.
    if std::env::var_os("CI").is_some() {
        assert!(
            devices.iter().any(|l| {
                let l = l.trim_start();
                l.starts_with("opencl (") && !l.contains("dropped out") && !l.contains(" 0.0% of")
            }),
            "CI is set but no OpenCL device rendered a share: {summary}"
        );
    }
    let (one, one_path) = render(
        dir.path(),
        "one.pfm",
        &[&flags[..], &["--backend", "cpu"]].concat(),
    );
    assert!(one.status.success(), "{}", text(&one.stderr));
    let read = |p: &Path| {
        let bytes = std::fs::read(p).expect("pfm");
        pathstream::render::output::decode_pfm(&bytes)
            .expect("decodes")
            .2
    };
    // The same samples: only the devices' rounding differs.
    common::assert_same_samples(
        &read(&all_path),
        &read(&one_path),
        "every device vs rayon alone, same seed",
    );
    let bad = pathstream(&[
        "render",
        "--backend",
        "all",
        "--device",
        "0",
        "--out",
        "x.png",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        text(&bad.stderr).contains("--device"),
        "{}",
        text(&bad.stderr)
    );
}

#[test]
fn render_writes_a_linear_pfm() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (out, path) = render(
        dir.path(),
        "a.pfm",
        &["--spp", "4", "--nee", "off", "--filter", "box"],
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let bytes = std::fs::read(path).expect("file");
    let (w, h, rgb) = pathstream::render::output::decode_pfm(&bytes).expect("PFM");
    assert_eq!((w, h), (16, 12));
    // Linear radiance: the light (emission 12) is not clipped to 1.
    assert!(rgb.iter().flatten().any(|v| *v > 1.0));
}

#[test]
fn time_and_error_halts_end_the_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (out, _) = render(dir.path(), "t.png", &["--time-ms", "300"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let (out, _) = render(dir.path(), "e.png", &["--target-error", "0.5"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let summary = text(&out.stdout);
    let pct: f64 = summary
        .split("error estimate ")
        .nth(1)
        .and_then(|s| s.split('%').next())
        .and_then(|s| s.parse().ok())
        .expect("error estimate in summary");
    assert!(pct <= 50.0, "{summary}");
}

#[test]
fn bad_input_exits_2_with_a_message_naming_the_problem() {
    let dir = tempfile::tempdir().expect("tempdir");
    let bad_scene = dir.path().join("bad.json");
    std::fs::write(
        &bad_scene,
        r#"{"camera": {"position": [0,0,1], "look_at": [0,0,0], "vfov_deg": 40},
        "materials": {"m": {"type": "diffuse", "albedo": [1,1,1]}},
        "objects": [{"type": "sphere", "center": [0,0,0], "radius": -1, "material": "m"}]}"#,
    )
    .expect("write");
    let bad_scene = bad_scene.to_str().expect("utf-8").to_owned();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--width", "0"], "width"),
        (vec!["--height", "100000"], "height"),
        (vec!["--width", "-3"], "--width"),
        (vec!["--clamp", "-1"], "--clamp"),
        (vec!["--spp", "0"], "--spp"),
        (vec!["--target-error", "0"], "--target-error"),
        (vec!["--nee", "maybe"], "--nee"),
        (vec!["--filter", "gauss"], "--filter"),
        (vec!["--max-depth", "100001"], "--max-depth"),
        (vec!["--aperture", "-1"], "camera.aperture"),
        (vec!["--focus-distance", "0"], "camera.focus_distance"),
    ];
    for (extra, needle) in cases {
        let (out, _) = render(dir.path(), "x.png", &extra);
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        let err = text(&out.stderr);
        assert!(err.contains(needle), "{extra:?}: '{needle}' not in: {err}");
    }
    let scene_cases = [
        (
            vec!["render", "--scene", "nope", "--out", "x.png"],
            "'nope' is neither a built-in scene",
        ),
        (
            vec!["render", "--scene", &bad_scene, "--out", "x.png"],
            "objects[0].radius: must be > 0",
        ),
        (
            vec!["render", "--scene", "cornell", "--out", "x.jpg"],
            "--out: unsupported output format",
        ),
        (vec!["render", "--scene", "cornell"], "--out"),
        (vec!["scenes", "--json", "nope"], "unknown scene 'nope'"),
        (
            vec!["serve", "--render-threads", "0"],
            "--render-threads: must be at least 1",
        ),
    ];
    for (args, needle) in scene_cases {
        let out = pathstream(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = text(&out.stderr);
        assert!(err.contains(needle), "{args:?}: '{needle}' not in: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

#[test]
fn help_documents_every_render_flag() {
    let out = pathstream(&["render", "--help"]);
    let help = text(&out.stdout);
    for flag in [
        "--scene",
        "--width",
        "--height",
        "--spp",
        "--time-ms",
        "--target-error",
        "--max-depth",
        "--rr-depth",
        "--nee",
        "--filter",
        "--clamp",
        "--seed",
        "--backend",
        "--exposure",
        "--out",
        "--preset",
        "--embree",
        "--cpu-paths",
    ] {
        assert!(help.contains(flag), "{flag} missing from render --help");
    }
    let out = pathstream(&["bench", "--help"]);
    let help = text(&out.stdout);
    for flag in [
        "--backend",
        "--device",
        "--sections",
        "--scenes",
        "--quick",
        "--out",
        "--cache",
        "--trade-size",
        "--trade-seconds",
        "--throughput-seconds",
        "--reference-error",
        "--reference-seconds",
    ] {
        assert!(help.contains(flag), "{flag} missing from bench --help");
    }
}

#[test]
fn the_cpus_loops_and_tracers_are_chosen_by_flags() {
    let dir = tempfile::tempdir().expect("temp dir");
    let run = |file: &str, flags: &[&str]| {
        let path = dir.path().join(file);
        let mut args = vec!["render", "--scene", "cornell-mesh", "--width", "16"];
        args.extend(["--height", "12", "--spp", "4", "--backend", "cpu"]);
        args.extend(flags);
        args.extend(["--out", path.to_str().expect("utf-8 path")]);
        let out = pathstream(&args);
        assert!(out.status.success(), "{flags:?}: {}", text(&out.stderr));
        std::fs::read(path).expect("image")
    };
    // The own BVH's rays: the lanes' image is the pairs' bit for bit.
    let pairs = run("pairs.pfm", &["--embree", "off", "--cpu-paths", "pairs"]);
    let lanes = run("lanes.pfm", &["--embree", "off", "--cpu-paths", "lanes"]);
    assert!(
        pairs == lanes,
        "--cpu-paths lanes changed the own BVH's image"
    );
    let bad = pathstream(&["render", "--scene", "cornell", "--cpu-paths", "wide"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(text(&bad.stderr).contains("--cpu-paths"));
}

#[test]
fn diff_measures_relative_error_against_a_reference() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (a, pa) = render(dir.path(), "a.pfm", &["--spp", "4"]);
    let (b, pb) = render(dir.path(), "b.pfm", &["--spp", "4", "--seed", "1"]);
    assert!(a.status.success() && b.status.success());
    let (pa, pb) = (pa.to_str().expect("utf-8"), pb.to_str().expect("utf-8"));
    let same = pathstream(&["diff", pa, pa]);
    assert_eq!(text(&same.stdout).trim(), "relative RMS error 0.0000%");
    let other = pathstream(&["diff", pa, pb]);
    assert!(other.status.success());
    assert!(
        !text(&other.stdout).contains(" 0.0000%"),
        "{}",
        text(&other.stdout)
    );
    let missing = pathstream(&["diff", pa, "/nonexistent.pfm"]);
    assert_eq!(missing.status.code(), Some(2));
    assert!(text(&missing.stderr).contains("/nonexistent.pfm"));
}

#[test]
fn serve_prints_its_url_and_survives_a_closed_stdout() {
    use std::io::{Read, Write};
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(["serve", "--addr", "127.0.0.1:0", "--backend", "cpu"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("starts");
    // The reader is gone after this: later writes to stdout fail, and must
    // not kill the server.
    let url = http::served_url(&mut child);
    let addr = url.trim_start_matches("http://").to_owned();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let mut stream = std::net::TcpStream::connect(&addr).expect("still listening");
    stream
        .write_all(
            format!("GET /api/health HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n")
                .as_bytes(),
        )
        .expect("request");
    let mut answer = String::new();
    stream.read_to_string(&mut answer).expect("answer");
    let _ = child.kill();
    let _ = child.wait();
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    assert!(answer.contains("\"status\":\"ok\""), "{answer}");
}

#[test]
fn a_preset_sets_the_path_knobs_and_flags_override_it() {
    use pathstream::render::{Preset, Quality};
    let dir = tempfile::tempdir().expect("tempdir");
    let bytes = |file: &str, extra: &[&str]| {
        let (out, path) = render(dir.path(), file, extra);
        assert!(out.status.success(), "{extra:?}: {}", text(&out.stderr));
        std::fs::read(path).expect("file")
    };
    for preset in Preset::ALL {
        let q = Preset::apply(preset, Quality::default());
        let (depth, rr, clamp) = (
            q.max_depth.to_string(),
            q.rr_depth.to_string(),
            q.clamp.to_string(),
        );
        let explicit = [
            "--spp",
            "3",
            "--max-depth",
            &depth,
            "--rr-depth",
            &rr,
            "--clamp",
            &clamp,
            "--nee",
            "on",
            "--filter",
            "tent2x2",
        ];
        let a = bytes("a.pfm", &["--spp", "3", "--preset", preset.name()]);
        assert_eq!(
            a,
            bytes("b.pfm", &explicit),
            "{} = its settings",
            preset.name()
        );
    }
    // A flag beside the preset wins over it.
    let a = bytes(
        "c.pfm",
        &["--spp", "3", "--preset", "reference", "--max-depth", "1"],
    );
    assert_eq!(
        a,
        bytes(
            "d.pfm",
            &[
                "--spp",
                "3",
                "--max-depth",
                "1",
                "--rr-depth",
                "5",
                "--clamp",
                "0"
            ]
        )
    );
    let out = pathstream(&[
        "render", "--scene", "cornell", "--preset", "fast", "--out", "x.png",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("preview, interactive, final, reference"),
        "{}",
        text(&out.stderr)
    );
}
