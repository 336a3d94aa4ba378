//! The `pathstream-client` command line against a real `pathstream` server
//! process (the workspace builds both binaries into the same folder).

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{assert_fails, client, client_into_closed_pipe, start_server, text};

#[test]
fn render_saves_a_png_and_a_pfm_and_deletes_its_session() {
    let server = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["a.png", "a.pfm"] {
        let out = dir.path().join(name);
        let run = client(
            &server,
            &[
                "render",
                "--scene",
                "cornell",
                "--width",
                "24",
                "--height",
                "16",
                "--spp",
                "16",
                "-o",
                out.to_str().expect("utf-8"),
            ],
        );
        assert!(run.status.success(), "{}", text(&run.stderr));
        assert!(
            text(&run.stdout).contains("16 spp"),
            "{}",
            text(&run.stdout)
        );
        let bytes = std::fs::read(&out).expect("file");
        if name.ends_with("png") {
            let img = image::load_from_memory(&bytes).expect("a PNG");
            assert_eq!((img.width(), img.height()), (24, 16));
        } else {
            assert!(bytes.starts_with(b"PF\n24 16\n-1.0\n"));
            assert_eq!(bytes.len(), 14 + 24 * 16 * 12);
        }
    }
    let sessions = client(&server, &["sessions"]);
    assert!(sessions.status.success());
    assert_eq!(
        text(&sessions.stdout).trim(),
        "",
        "render deleted its sessions"
    );
}

#[test]
fn orbit_renders_n_distinct_frames() {
    let server = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    // An open scene: a red ball and a blue one on a floor, under a lamp.
    let scene = dir.path().join("balls.json");
    std::fs::write(
        &scene,
        r#"{"camera": {"position": [0, 1, 4], "look_at": [0, 0.5, 0], "vfov_deg": 50},
            "materials": {"floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
                          "red": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]},
                          "blue": {"type": "diffuse", "albedo": [0.1, 0.1, 0.8]},
                          "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [10, 10, 10]}},
            "objects": [{"type": "quad", "corner": [-5, 0, -5], "edge_u": [10, 0, 0], "edge_v": [0, 0, 10], "material": "floor"},
                        {"type": "sphere", "center": [0.8, 0.5, 0], "radius": 0.5, "material": "red"},
                        {"type": "sphere", "center": [-0.8, 0.4, 0.3], "radius": 0.4, "material": "blue"},
                        {"type": "sphere", "center": [0, 4, 0], "radius": 0.5, "material": "lamp"}]}"#,
    )
    .expect("scene");
    let out = dir.path().join("frames");
    let run = client(
        &server,
        &[
            "orbit",
            "--scene",
            scene.to_str().expect("utf-8"),
            "--frames",
            "4",
            "--spp",
            "4",
            "--width",
            "24",
            "--height",
            "24",
            "--out-dir",
            out.to_str().expect("utf-8"),
        ],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    let frames: Vec<Vec<u8>> = (0..4)
        .map(|i| {
            let img = image::open(out.join(format!("frame_{i:04}.png"))).expect("a frame");
            img.to_rgb8().into_raw()
        })
        .collect();
    for i in 0..4 {
        for j in i + 1..4 {
            assert_ne!(frames[i], frames[j], "frames {i} and {j} are the same");
        }
    }
}

#[test]
fn ctrl_c_during_render_deletes_the_session() {
    let server = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("never.png");
    let mut render = Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .args([
            "--server",
            &server.url,
            "render",
            "--scene",
            "cornell-glass",
            "--width",
            "64",
            "--height",
            "64",
            "--spp",
            "1000000",
            "-o",
        ])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    // Wait for its session to appear.
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        let list = client(&server, &["sessions"]);
        if !text(&list.stdout).trim().is_empty() {
            break;
        }
        assert!(Instant::now() < deadline, "no session appeared");
        std::thread::sleep(Duration::from_millis(100));
    }
    let kill = Command::new("kill")
        .args(["-INT", &render.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    let status = render.wait().expect("exits");
    assert_eq!(status.code(), Some(130), "interrupted");
    assert!(!out.exists());
    let list = client(&server, &["sessions"]);
    assert_eq!(text(&list.stdout).trim(), "", "the session was deleted");
}

#[test]
fn commands_for_one_session_and_exit_codes() {
    let server = start_server();
    let created = client(
        &server,
        &[
            "create", "--scene", "furnace", "--width", "8", "--height", "8", "--spp", "4",
        ],
    );
    assert!(created.status.success(), "{}", text(&created.stderr));
    let status: serde_json::Value = serde_json::from_slice(&created.stdout).expect("status JSON");
    let id = status["id"].as_str().expect("id").to_owned();
    // A reader that stops early (`| head`) ends the output, not in a panic.
    let unread = client_into_closed_pipe(&server, &["status", &id]);
    assert!(unread.status.success(), "{}", text(&unread.stderr));
    let camera = client(
        &server,
        &["camera", &id, "--vfov-deg", "45", "--position", "0,0.1,0"],
    );
    assert!(camera.status.success(), "{}", text(&camera.stderr));
    let light = client(&server, &["light", &id, "--intensity", "2"]);
    assert!(light.status.success(), "{}", text(&light.stderr));
    let quality = client(
        &server,
        &["quality", &id, "--max-depth", "3", "--nee", "off"],
    );
    let q: serde_json::Value = serde_json::from_slice(&quality.stdout).expect("status JSON");
    assert_eq!(q["quality"]["max_depth"], 3);
    assert_eq!(q["quality"]["nee"], false);
    let preset = client(
        &server,
        &["quality", &id, "--preset", "reference", "--rr-depth", "2"],
    );
    let q: serde_json::Value = serde_json::from_slice(&preset.stdout).expect("status JSON");
    assert_eq!(
        (
            q["quality"]["max_depth"].as_u64(),
            q["quality"]["nee"].as_bool()
        ),
        (Some(0), Some(true))
    );
    assert_eq!(
        q["quality"]["rr_depth"], 2,
        "a setting beside the preset wins"
    );
    let bad = client(&server, &["quality", &id, "--preset", "fast"]);
    assert_fails(&bad, 3, "quality.preset");
    let dir = tempfile::tempdir().expect("tempdir");
    let frame = dir.path().join("f.png");
    let run = client(
        &server,
        &[
            "frame",
            &id,
            "--min-spp",
            "4",
            "-o",
            frame.to_str().expect("utf-8"),
        ],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert!(image::open(&frame).is_ok());
    let stream_dir = dir.path().join("stream");
    let run = client(&server, &["quality", &id, "--spp", "100000"]);
    assert!(run.status.success());
    let run = client(
        &server,
        &[
            "stream",
            &id,
            "--frames",
            "3",
            "--out-dir",
            stream_dir.to_str().expect("utf-8"),
        ],
    );
    assert!(run.status.success(), "{}", text(&run.stderr));
    assert_eq!(std::fs::read_dir(&stream_dir).expect("dir").count(), 3);
    assert!(client(&server, &["status", &id]).status.success());
    assert!(client(&server, &["delete", &id]).status.success());

    // 3: the server said no, and its message is shown.
    let gone = client(&server, &["status", &id]);
    assert_fails(&gone, 3, &format!("no session '{id}'"));
    let bad = client(&server, &["camera", "x", "--position", "1,2"]);
    assert_eq!(bad.status.code(), Some(2), "bad arguments");
    let bad_out = client(&server, &["frame", "x", "-o", "f.jpg"]);
    assert_eq!(bad_out.status.code(), Some(2));
    // 4: nobody there.
    let nobody = Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .args(["--server", "http://127.0.0.1:9", "sessions"])
        .output()
        .expect("runs");
    assert_eq!(nobody.status.code(), Some(4), "{}", text(&nobody.stderr));
}

/// A stand-in server that answers `POST /api/sessions` only when told to,
/// so that a test can press Ctrl-C while the session is being created. It
/// records every request line it gets.
struct HeldServer {
    url: String,
    /// Request lines, as they arrive.
    requests: std::sync::mpsc::Receiver<String>,
    /// Lets the held POST answer.
    release: std::sync::mpsc::Sender<()>,
}

/// Reads one HTTP/1.1 request (head and `content-length` body); its request line.
fn read_request(stream: &mut std::net::TcpStream) -> Option<String> {
    use std::io::Read;
    let mut data = Vec::new();
    let mut buf = [0u8; 4096];
    let head_end = loop {
        if let Some(i) = data.windows(4).position(|w| w == b"\r\n\r\n") {
            break i + 4;
        }
        let n = stream.read(&mut buf).ok().filter(|&n| n > 0)?;
        data.extend_from_slice(&buf[..n]);
    };
    let head = String::from_utf8_lossy(&data[..head_end]).into_owned();
    let length: usize = head
        .lines()
        .find_map(|l| {
            l.to_ascii_lowercase()
                .strip_prefix("content-length:")
                .map(|v| v.trim().parse().unwrap_or(0))
        })
        .unwrap_or(0);
    while data.len() < head_end + length {
        let n = stream.read(&mut buf).ok().filter(|&n| n > 0)?;
        data.extend_from_slice(&buf[..n]);
    }
    head.lines().next().map(str::to_owned)
}

/// Serves `created` (a session status) as the answer to the held POST, and
/// 204 to anything else; one request per connection.
fn held_server(created: String) -> HeldServer {
    use std::io::Write;
    let listener = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    let url = format!("http://{}", listener.local_addr().expect("addr"));
    let (seen, requests) = std::sync::mpsc::channel();
    let (release, released) = std::sync::mpsc::channel::<()>();
    std::thread::spawn(move || {
        for stream in listener.incoming().take(8) {
            let Ok(mut stream) = stream else { continue };
            let Some(line) = read_request(&mut stream) else {
                continue;
            };
            let _ = seen.send(line.clone());
            let response = if line.starts_with("POST /api/sessions ") {
                let _ = released.recv_timeout(Duration::from_secs(30));
                format!("HTTP/1.1 201 Created\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{created}", created.len())
            } else {
                "HTTP/1.1 204 No Content\r\nconnection: close\r\n\r\n".to_owned()
            };
            let _ = stream.write_all(response.as_bytes());
        }
    });
    HeldServer {
        url,
        requests,
        release,
    }
}

#[test]
fn ctrl_c_while_the_session_is_created_still_deletes_it() {
    // A real session status for the stand-in to answer with.
    let real = start_server();
    let created = client(
        &real,
        &[
            "create", "--scene", "furnace", "--width", "8", "--height", "8", "--spp", "1",
        ],
    );
    assert!(created.status.success(), "{}", text(&created.stderr));
    let status: serde_json::Value = serde_json::from_slice(&created.stdout).expect("status JSON");
    let id = status["id"].as_str().expect("id").to_owned();
    let held = held_server(status.to_string());
    let dir = tempfile::tempdir().expect("tempdir");
    let mut render = Command::new(env!("CARGO_BIN_EXE_pathstream-client"))
        .args([
            "--server", &held.url, "render", "--scene", "furnace", "--width", "8", "--height", "8",
            "-o",
        ])
        .arg(dir.path().join("never.png"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    let first = held
        .requests
        .recv_timeout(Duration::from_secs(20))
        .expect("the create request");
    assert!(first.starts_with("POST /api/sessions "), "{first}");
    // Ctrl-C while the server has not answered yet.
    let kill = Command::new("kill")
        .args(["-INT", &render.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    std::thread::sleep(Duration::from_millis(300));
    held.release.send(()).expect("release the answer");
    let status = render.wait().expect("exits");
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut render.stderr.take().expect("stderr"), &mut stderr)
        .expect("stderr");
    assert_eq!(
        status.code(),
        Some(130),
        "interrupted, not killed by the signal: {status:?} {stderr}"
    );
    let rest: Vec<String> = held.requests.try_iter().collect();
    assert_eq!(
        rest,
        [format!("DELETE /api/sessions/{id} HTTP/1.1")],
        "the session made meanwhile was deleted"
    );
}

/// A closed unit tetrahedron as ASCII PLY.
const TETRAHEDRON_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";

#[test]
fn render_uploads_model_files_given_directly_or_named_by_a_scene() {
    let server = start_server();
    let dir = tempfile::tempdir().expect("tempdir");
    let model = dir.path().join("tet.ply");
    std::fs::write(&model, TETRAHEDRON_PLY).expect("model");
    let png = |name: &str| dir.path().join(name).to_str().expect("utf-8").to_owned();
    let render = |scene: &Path, out: &str| {
        let scene = scene.to_str().expect("utf-8");
        let size = ["--width", "24", "--height", "16", "--spp", "8"];
        let args = [&["render", "--scene", scene][..], &size, &["-o", out]].concat();
        client(&server, &args)
    };

    // The file alone: uploaded, framed and lit by the server's defaults.
    let direct = png("direct.png");
    let run = render(&model, &direct);
    assert!(run.status.success(), "{}", text(&run.stderr));
    // No emitter in the file: the server says it lit it by a default sky.
    assert!(
        text(&run.stderr).contains("warning:"),
        "{}",
        text(&run.stderr)
    );
    // Framed: the model covers a good part of the picture, darker than the
    // white sky around it (the default diffuse albedo is 0.8).
    let img = image::open(&direct).expect("a PNG").to_rgb8();
    let sky = img.get_pixel(0, 0).0;
    assert!(
        sky.iter().all(|&c| c > 240),
        "the corner shows the sky: {sky:?}"
    );
    let covered = img.pixels().filter(|p| p.0[1] < 235).count();
    assert!(
        covered * 20 > 24 * 16,
        "the model covers {covered} of {} pixels",
        24 * 16
    );

    // A scene JSON naming the file relative to itself: uploaded once.
    let scene = dir.path().join("scene.json");
    std::fs::write(
        &scene,
        r#"{"materials": {"red": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]}},
            "environment": [1, 1, 1],
            "objects": [{"type": "mesh", "file": "tet.ply", "material": "red"},
                        {"type": "mesh", "file": "tet.ply", "material": "red", "transform": {"translate": [2, 0, 0]}}]}"#,
    )
    .expect("scene");
    let run = render(&scene, &png("scene.png"));
    assert!(run.status.success(), "{}", text(&run.stderr));
    // The same bytes twice, and the file given alone before: one asset.
    let assets = client(&server, &["assets"]);
    assert!(assets.status.success(), "{}", text(&assets.stderr));
    let listed = text(&assets.stdout);
    assert_eq!(listed.lines().count(), 1, "{listed}");
    assert!(listed.contains("4 triangles"), "{listed}");
    let upload = client(&server, &["upload", model.to_str().expect("utf-8")]);
    assert!(upload.status.success(), "{}", text(&upload.stderr));
    let id = text(&upload.stdout).trim().to_owned();
    assert!(listed.starts_with(&id), "{id} not in {listed}");
    assert!(client(&server, &["delete-asset", &id]).status.success());
    assert_eq!(text(&client(&server, &["assets"]).stdout).trim(), "");

    // A file that is not a model: exit 2, the file named.
    let broken = dir.path().join("broken.ply");
    std::fs::write(
        &broken,
        "ply\nformat ascii 1.0\nelement vertex 1\nend_header\n",
    )
    .expect("file");
    let run = render(&broken, &png("x.png"));
    assert_fails(&run, 2, "broken.ply");
    // A scene naming a missing file: exit 2, the JSON path named.
    std::fs::write(
        &scene,
        r#"{"objects": [{"type": "model", "file": "nowhere.obj"}]}"#,
    )
    .expect("scene");
    let run = render(&scene, &png("y.png"));
    assert_fails(&run, 2, "objects[0].file");
}
