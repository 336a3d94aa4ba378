//! `/api/assets` end to end: upload, dedupe, sessions rendering uploaded
//! meshes and models, deletion, limits, and a 4xx for every bad upload.

mod http;

use http::*;
use pathstream::model::generate::icosphere;
use pathstream::model::write::write_ply_binary;
use pathstream::service::assets::asset_id;
use serde_json::{json, Value};
use std::io::{Read, Write};
use std::time::Duration;

fn ball_ply() -> Vec<u8> {
    let mut out = Vec::new();
    write_ply_binary(&icosphere(2), &mut out).expect("write");
    out
}

/// A binary glTF with one triangle and a camera 3 units along +z.
fn glb_with_camera() -> Vec<u8> {
    let mut bin = Vec::new();
    for x in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.01}}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.3, 0.3, 3]}],
        "scenes": [{"nodes": [0, 1]}], "scene": 0
    });
    let mut json_chunk = doc.to_string().into_bytes();
    while !json_chunk.len().is_multiple_of(4) {
        json_chunk.push(b' ');
    }
    let total = 12 + 8 + json_chunk.len() + 8 + bin.len();
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&(total as u32).to_le_bytes());
    glb.extend_from_slice(&(json_chunk.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json_chunk);
    glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&bin);
    glb
}

/// Asserts that a session of `scene` is refused (400) with an error that
/// says `words`.
async fn assert_refused(base: &str, scene: Value, words: &str) {
    let r = client()
        .post(format!("{base}/api/sessions"))
        .json(&json!({"scene": scene}))
        .send()
        .await
        .expect("req");
    assert_eq!(r.status(), 400);
    let e: Value = r.json().await.expect("json");
    assert!(
        e["error"].as_str().is_some_and(|e| e.contains(words)),
        "{words}: {e}"
    );
}

async fn upload(base: &str, name: &str, bytes: Vec<u8>) -> (u16, Value) {
    let r = client()
        .post(format!("{base}/api/assets?name={name}"))
        .header("content-type", "application/octet-stream")
        .body(bytes)
        .send()
        .await
        .expect("request");
    let status = r.status().as_u16();
    (status, r.json().await.expect("json body"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uploaded_meshes_and_models_render_in_sessions() {
    let (running, base) = server(config()).await;
    let ply = ball_ply();
    let (status, a) = upload(&base, "ball.ply", ply.clone()).await;
    assert_eq!(status, 201, "{a}");
    let id = a["id"].as_str().expect("id").to_owned();
    assert_eq!(id, asset_id(&ply), "content-addressed");
    assert_eq!(
        (
            a["format"].as_str(),
            a["triangles"].as_u64(),
            a["deduplicated"].as_bool()
        ),
        (Some("ply"), Some(320), Some(false))
    );
    assert!(
        a["warnings"]
            .as_array()
            .expect("warnings")
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains("no materials"))),
        "{a}"
    );
    // The same bytes again: the same asset.
    let (status, again) = upload(&base, "other-name.ply", ply).await;
    assert_eq!(
        (
            status,
            again["id"].as_str(),
            again["deduplicated"].as_bool()
        ),
        (200, Some(id.as_str()), Some(true))
    );
    let list: Value = get_json(format!("{base}/api/assets")).await;
    assert_eq!(list["assets"].as_array().map(Vec::len), Some(1));
    assert!(list["memory_bytes"].as_u64().is_some_and(|m| m > 0));

    // A session renders it: the sky (exactly 1) around a grey ball.
    let s = create(&base, json!({"width": 24, "height": 24, "quality": {"spp": 16, "max_depth": 0},
        "scene": {"materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                  "objects": [{"type": "mesh", "asset": id, "material": "grey"}], "environment": [1, 1, 1]}})).await;
    let sid = s["id"].as_str().expect("id").to_owned();
    let img = pfm(&base, &sid, 16).await;
    assert_eq!(img[0], [1.0, 1.0, 1.0], "the sky");
    let centre = img[12 * 24 + 12][0];
    assert!(centre > 0.2 && centre < 0.8, "the ball: {centre}");

    // A model brings its camera.
    let (status, m) = upload(&base, "tri.glb", glb_with_camera()).await;
    assert_eq!(status, 201, "{m}");
    assert_eq!(m["has_camera"], true);
    let s2 = create(&base, json!({"width": 8, "height": 8, "scene": {"objects": [{"type": "model", "asset": m["id"]}]}})).await;
    assert_eq!(s2["camera"]["position"], json!([0.3, 0.3, 3.0]), "{s2}");

    // Deleted: gone for new scenes, still rendered by the sessions using it.
    let r = delete(format!("{base}/api/assets/{id}")).await;
    assert_eq!(r.status(), 204);
    let r = get(format!("{base}/api/assets/{id}")).await;
    assert_eq!(r.status(), 404);
    let r = patch(&base, &sid, "camera", json!({"vfov_deg": 50})).await;
    assert_eq!(r.status(), 200, "{:?}", r.text().await);
    let r = client()
        .post(format!("{base}/api/sessions"))
        .json(&json!({"scene": {"objects": [{"type": "mesh", "asset": id, "material": "x"}]}}))
        .send()
        .await
        .expect("req");
    assert_eq!(r.status(), 400);
    let e: Value = r.json().await.expect("json");
    assert!(
        e["error"]
            .as_str()
            .is_some_and(|e| e.contains("objects[0].asset") && e.contains("no asset")),
        "{e}"
    );
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_bad_upload_or_reference_is_a_4xx_naming_the_problem() {
    let mut cfg = config();
    cfg.assets.max_asset_bytes = 64 * 1024;
    cfg.max_triangles = 100;
    let (running, base) = server(cfg).await;
    let nan_obj = b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec();
    let mut cut = ball_ply();
    cut.truncate(cut.len() - 100);
    let cases: Vec<(&str, Vec<u8>, u16, &str)> = vec![
        ("big.ply", vec![b'x'; 70 * 1024], 413, "limit"),
        ("empty.ply", Vec::new(), 400, "empty"),
        (
            "notes.txt",
            b"hello, world".to_vec(),
            400,
            "not a model file",
        ),
        ("cut.ply", cut, 400, "truncated"),
        ("nan.obj", nan_obj, 400, "line 2"),
        (
            "garbage.glb",
            b"glTF\x02\0\0\0\xff\xff\xff\x7f".to_vec(),
            400,
            "garbage.glb",
        ),
    ];
    for (name, bytes, code, expect) in cases {
        let (status, body) = upload(&base, name, bytes).await;
        let e = body["error"].as_str().unwrap_or_default();
        assert_eq!(status, code, "{name}: {body}");
        assert!(e.contains(expect), "{name}: expected '{expect}' in {e:?}");
    }
    // Refused from Content-Length alone, before any of the body is sent.
    let addr = base.trim_start_matches("http://");
    let mut tcp = std::net::TcpStream::connect(addr).expect("connect");
    tcp.set_read_timeout(Some(Duration::from_secs(10)))
        .expect("timeout");
    write!(tcp, "POST /api/assets?name=x.ply HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\nContent-Length: 1000000000\r\n\r\n").expect("write");
    let mut head = [0u8; 64];
    let n = tcp.read(&mut head).expect("an answer without the body");
    assert!(
        String::from_utf8_lossy(&head[..n]).starts_with("HTTP/1.1 413"),
        "{}",
        String::from_utf8_lossy(&head[..n])
    );

    // Scenes: files are never read, unknown assets and too many triangles refused.
    let (_, ball) = upload(&base, "ball.ply", ball_ply()).await;
    let scenes = [
        (
            json!({"objects": [{"type": "mesh", "file": "/etc/passwd", "material": "m"}], "materials": {"m": {"type": "diffuse", "albedo": [1, 1, 1]}}}),
            "objects[0].file",
        ),
        (
            json!({"objects": [{"type": "mesh", "asset": "0123", "material": "m"}], "materials": {"m": {"type": "diffuse", "albedo": [1, 1, 1]}}}),
            "objects[0].asset",
        ),
        (
            json!({"objects": [{"type": "mesh", "data": {"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 2]]}}]}),
            "objects[0].material",
        ),
        (
            json!({"objects": [{"type": "mesh", "data": {"positions": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "triangles": [[0, 1, 7]]}, "material": "m"}],
            "materials": {"m": {"type": "diffuse", "albedo": [1, 1, 1]}}}),
            "objects[0].data: triangle 0: vertex index 7",
        ),
        (
            json!({"objects": [{"type": "mesh", "asset": ball["id"], "material": "m"}], "materials": {"m": {"type": "diffuse", "albedo": [1, 1, 1]}}}),
            "320 triangles",
        ),
        (
            json!({"objects": [{"type": "model", "asset": ball["id"], "transform": {"scale": 0}}]}),
            "objects[0].transform.scale",
        ),
    ];
    for (scene, expect) in scenes {
        assert_refused(&base, scene, expect).await;
    }
    let r = delete(format!("{base}/api/assets/nothing")).await;
    assert_eq!(r.status(), 404);
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_asset_store_answers_507() {
    let mut cfg = config();
    cfg.assets.max_total_bytes = 1000;
    let (running, base) = server(cfg).await;
    let (status, body) = upload(&base, "ball.ply", ball_ply()).await;
    assert_eq!(status, 507, "{body}");
    assert!(
        body["error"]
            .as_str()
            .is_some_and(|e| e.contains("DELETE /api/assets")),
        "{body}"
    );
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uploaded_environment_maps_light_sessions() {
    let (running, base) = server(config()).await;
    let hdr = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sunset-64.hdr"
    ))
    .expect("read");
    let (status, a) = upload(&base, "sunset.hdr", hdr.clone()).await;
    assert_eq!(status, 201, "{a}");
    assert_eq!(
        (a["format"].as_str(), &a["map_size"]),
        (Some("hdr"), &json!([64, 32])),
        "{a}"
    );
    let id = a["id"].as_str().expect("id").to_owned();
    // A ball under the map: camera rays that miss it see the map.
    let scene = |env: Value| {
        json!({"width": 16, "height": 16, "quality": {"spp": 4},
            "scene": {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "vfov_deg": 60},
                "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "grey"}],
                "environment": env}})
    };
    let s = create(&base, scene(json!({"map": id}))).await;
    let sid = s["id"].as_str().expect("id").to_owned();
    let img = pfm(&base, &sid, 4).await;
    assert!(
        img[0].iter().all(|c| *c > 0.0),
        "the map behind: {:?}",
        img[0]
    );
    let hidden = create(&base, scene(json!({"map": id, "visible": false}))).await;
    let img = pfm(&base, hidden["id"].as_str().expect("id"), 4).await;
    assert_eq!(img[0], [0.0, 0.0, 0.0], "a hidden map shows black");
    assert!(img[8 * 16 + 8][0] > 0.0, "but lights the ball");

    // A map is no mesh, a mesh no map, a broken map no asset.
    let (_, ply) = upload(&base, "ball.ply", ball_ply()).await;
    let refusals = [
        (
            json!({"objects": [{"type": "mesh", "asset": id, "material": "x"}]}),
            "environment map",
        ),
        (
            json!({"objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
                   "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                   "environment": {"map": ply["id"]}}),
            "is a model",
        ),
    ];
    for (scene, words) in refusals {
        assert_refused(&base, scene, words).await;
    }
    let (status, e) = upload(&base, "cut.hdr", hdr[..hdr.len() / 3].to_vec()).await;
    assert_eq!(status, 400, "{e}");
    assert!(
        e["error"].as_str().is_some_and(|e| e.contains("cut.hdr")),
        "{e}"
    );
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_environment_alone_changes_by_its_own_verb() {
    let (running, base) = server(config()).await;
    let hdr = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sunset-64.hdr"
    ))
    .expect("read");
    let (_, a) = upload(&base, "sunset.hdr", hdr).await;
    let map = a["id"].as_str().expect("id").to_owned();
    // A ball in a black world: every pixel that misses it is black.
    let s = create(
        &base,
        json!({"width": 16, "height": 16, "quality": {"spp": 4},
            "scene": {"camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "vfov_deg": 60},
                "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 0.5, "material": "grey"}],
                "environment": [0, 0, 0]}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    assert_eq!(s["environment"], json!([0.0, 0.0, 0.0]), "{s}");
    assert_eq!(pfm(&base, &id, 4).await[0], [0.0, 0.0, 0.0]);
    let put = |body: Value| {
        let (base, id) = (base.clone(), id.clone());
        async move {
            let r = client()
                .put(format!("{base}/api/sessions/{id}/environment"))
                .json(&body)
                .send()
                .await
                .expect("req");
            (r.status().as_u16(), r.json::<Value>().await.expect("json"))
        }
    };
    let (code, st) = put(json!({"map": map, "intensity": 2, "rotation_deg": 90})).await;
    assert_eq!(code, 200, "{st}");
    assert_eq!(
        st["environment"],
        json!({"map": map, "intensity": 2.0, "rotation_deg": 90.0}),
        "{st}"
    );
    assert_eq!(st["environment_name"], json!("sunset.hdr"));
    // The camera is the scene's still; the corner now shows the map.
    assert_eq!(st["camera"], s["camera"]);
    let lit = pfm(&base, &id, 4).await;
    assert!(lit[0].iter().all(|c| *c > 0.0), "{:?}", lit[0]);
    // Twice as bright as at intensity 1, the same samples otherwise.
    let (_, st1) = put(json!({"map": map, "rotation_deg": 90})).await;
    assert_eq!(st1["environment"]["intensity"], json!(1.0));
    let half = pfm(&base, &id, 4).await;
    for c in 0..3 {
        let ratio = lit[0][c] / half[0][c];
        assert!(
            (ratio - 2.0).abs() < 1e-5,
            "corner: intensity 2 over 1 is {ratio}"
        );
    }
    // Over the WebSocket as well, beside a camera change.
    let mut ws = ws_connect(&base, &id).await;
    ws_send(
        &mut ws,
        json!({"environment": [0.25, 0.5, 1.0], "camera": {"vfov_deg": 50}}),
    )
    .await;
    let st = wait_status(&base, &id, |st| st["camera"]["vfov_deg"] == json!(50.0)).await;
    assert_eq!(st["environment"], json!([0.25, 0.5, 1.0]));
    assert!(st.get("environment_name").is_none(), "{st}");
    // Refusals name the field and change nothing.
    for (body, words) in [
        (
            json!({"map": map, "intensity": -1}),
            "environment.intensity",
        ),
        (json!({"map": "a".repeat(64)}), "environment.map"),
        (json!({"map": "/etc/passwd"}), "environment.map"),
        (json!({"map": map, "size": 3}), "environment"),
        (json!([1, 2]), "environment"),
        (json!([-1, 0, 0]), "environment"),
    ] {
        let (code, e) = put(body.clone()).await;
        assert_eq!(code, 400, "{body}: {e}");
        assert!(
            e["error"].as_str().is_some_and(|e| e.contains(words)),
            "{body}: {e}"
        );
    }
    assert_eq!(
        status(&base, &id).await["environment"],
        json!([0.25, 0.5, 1.0])
    );
    running.shutdown().await.expect("shutdown");
}

/// `rgba` (`w` x `h`) as PNG bytes.
fn png(w: u32, h: u32, rgba: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut out),
        rgba,
        w,
        h,
        image::ExtendedColorType::Rgba8,
    )
    .expect("png");
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn uploaded_images_texture_scene_materials() {
    let (running, base) = server(config()).await;
    // Red on the left, blue on the right.
    let (status, a) = upload(
        &base,
        "rb.png",
        png(2, 1, &[255, 0, 0, 255, 0, 0, 255, 255]),
    )
    .await;
    assert_eq!(status, 201, "{a}");
    assert_eq!(
        (a["format"].as_str(), &a["image_size"]),
        (Some("png"), &json!([2, 1])),
        "{a}"
    );
    assert_eq!(a["memory_bytes"], json!(8));
    let image = a["id"].as_str().expect("id").to_owned();
    // A mirror tinted by it fills the view, in a white sky: noise-free.
    let scene = |albedo: Value| {
        json!({"camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40,
                          "projection": "orthographic", "ortho_height": 2},
               "environment": [1, 1, 1],
               "materials": {"m": {"type": "mirror", "albedo": albedo}},
               "objects": [{"type": "quad", "corner": [-1, -1, 0], "edge_u": [2, 0, 0],
                            "edge_v": [0, 2, 0], "material": "m"}]})
    };
    let textured = scene(json!({"texture": image, "wrap": "clamp"}));
    let s = create(
        &base,
        json!({"width": 16, "height": 16, "quality": {"spp": 2}, "scene": textured}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let halves = |img: &[[f32; 3]]| (img[8 * 16 + 3], img[8 * 16 + 12]);
    assert_eq!(
        halves(&pfm(&base, &id, 2).await),
        ([1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    );
    // Another environment keeps the texture (the scene's own image, not read again).
    let r = client()
        .put(format!("{base}/api/sessions/{id}/environment"))
        .json(&json!([0.5, 0.5, 0.5]))
        .send()
        .await
        .expect("req");
    assert_eq!(r.status(), 200);
    let st = wait_status(&base, &id, |st| st["environment"] == json!([0.5, 0.5, 0.5])).await;
    assert_eq!(st["environment"], json!([0.5, 0.5, 0.5]));
    assert_eq!(
        halves(&pfm(&base, &id, 2).await),
        ([0.5, 0.0, 0.0], [0.0, 0.0, 0.5])
    );

    // An image is no model, a model no image, a file no asset; a broken
    // image is no upload.
    let (_, ply) = upload(&base, "ball.ply", ball_ply()).await;
    for (scene, words) in [
        (
            json!({"objects": [{"type": "mesh", "asset": image, "material": "x"}]}),
            "texture image",
        ),
        (
            scene(json!({"texture": ply["id"]})),
            "materials.m.albedo.texture: asset",
        ),
        (scene(json!({"texture": "rb.png"})), "POST /api/assets"),
        (
            scene(json!({"texture": image, "uv": 3})),
            "materials.m.albedo.uv",
        ),
    ] {
        assert_refused(&base, scene, words).await;
    }
    let bytes = png(2, 1, &[255, 0, 0, 255, 0, 0, 255, 255]);
    let (status, e) = upload(&base, "cut.png", bytes[..bytes.len() - 20].to_vec()).await;
    assert_eq!(status, 400, "{e}");
    assert!(
        e["error"].as_str().is_some_and(|e| e.contains("cut.png")),
        "{e}"
    );
    running.shutdown().await.expect("shutdown");
}
