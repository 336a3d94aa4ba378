//! The client library against a real server: every call, the error paths,
//! and contract drift (what the server sends must read into the shared wire
//! types and back unchanged: the same fields, the same values).

use futures_util::{SinkExt, StreamExt};
use pathstream::api::{start, Running};
use pathstream::render::BackendChoice;
use pathstream::service::ServeConfig;
use pathstream_client::wire::{ErrorBody, StreamMessage};
use pathstream_client::{
    CameraPatch, Client, ClientError, CreateSession, LightPatch, QualityPatch, SceneSpec,
    SessionStatus,
};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::{json, Value};
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message as WsMessage;

async fn server(token: Option<&str>) -> Running {
    start(ServeConfig {
        addr: "127.0.0.1:0".parse().expect("addr"),
        backend: BackendChoice::Cpu,
        token: token.map(str::to_owned),
        ..ServeConfig::default()
    })
    .await
    .expect("server starts")
}

fn small(scene: &str) -> CreateSession {
    CreateSession {
        scene: Some(SceneSpec::Name(scene.into())),
        width: Some(16),
        height: Some(12),
        quality: Some(QualityPatch {
            spp: Some(Some(16)),
            ..QualityPatch::default()
        }),
        backend: Some("cpu".into()),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_library_call_works_against_a_real_server() {
    let running = server(None).await;
    let client = Client::new(&format!("http://{}", running.addr)).expect("client");
    assert_eq!(client.health().await.expect("health").status, "ok");
    assert!(client
        .devices()
        .await
        .expect("devices")
        .backends
        .iter()
        .any(|b| b.backend == "cpu"));
    assert!(client
        .scenes()
        .await
        .expect("scenes")
        .contains(&"smallpt".to_owned()));

    let s = client
        .create_session(&small("cornell"))
        .await
        .expect("create");
    assert_eq!((s.width, s.height, s.scene.as_str()), (16, 12, "cornell"));
    assert_eq!(client.sessions().await.expect("list")[0].id, s.id);
    let png = client.frame_png(&s.id, Some(16), None).await.expect("png");
    assert_eq!(image::load_from_memory(&png).expect("a PNG").width(), 16);
    let pfm = client.frame_pfm(&s.id, Some(16), None).await.expect("pfm");
    assert!(pfm.starts_with(b"PF\n16 12\n-1.0\n"));
    assert!(client.session(&s.id).await.expect("status").halted());

    let c = client
        .set_camera(
            &s.id,
            &CameraPatch {
                vfov_deg: Some(35.0),
                ..CameraPatch::default()
            },
        )
        .await
        .expect("camera");
    assert_eq!(c.camera.vfov_deg, 35.0);
    assert_eq!(c.generation, 1);
    let l = client
        .set_light(
            &s.id,
            &LightPatch {
                intensity: Some(6.0),
                ..LightPatch::default()
            },
        )
        .await
        .expect("light");
    assert_eq!(l.light.expect("light").intensity, 6.0);
    let q = client
        .set_quality(
            &s.id,
            &QualityPatch {
                max_depth: Some(3),
                spp: Some(None),
                ..QualityPatch::default()
            },
        )
        .await
        .expect("quality");
    assert_eq!((q.quality.max_depth, q.quality.spp), (3, None));
    let sc = client
        .set_scene(&s.id, &SceneSpec::Name("furnace".into()))
        .await
        .expect("scene");
    assert_eq!(sc.scene, "furnace");

    // The stream: frames with stats, and changes sent on the same socket.
    let mut stream = client.stream(&s.id).await.expect("stream");
    let first = stream.next().await.expect("a frame").expect("ok");
    assert!(image::load_from_memory(&first.png).is_ok());
    assert_eq!(first.status.id, s.id);
    stream
        .send(&json!({"camera": {"vfov_deg": 50}}))
        .await
        .expect("send");
    stream.send(&json!({"nonsense": 1})).await.expect("send");
    let mut saw_error = false;
    let mut saw_change = false;
    for _ in 0..50 {
        match tokio::time::timeout(Duration::from_secs(10), stream.next())
            .await
            .expect("in time")
        {
            Some(Ok(f)) if f.status.camera.vfov_deg == 50.0 => saw_change = true,
            Some(Ok(_)) => {}
            Some(Err(ClientError::Server { message, .. })) => {
                assert!(message.contains("unknown key 'nonsense'"), "{message}");
                saw_error = true;
            }
            other => panic!("unexpected {other:?}"),
        }
        if saw_error && saw_change {
            break;
        }
    }
    assert!(saw_error && saw_change);
    stream.close().await.expect("close");

    client.delete_session(&s.id).await.expect("delete");
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn errors_carry_the_servers_message_and_status() {
    let running = server(Some("t0ken")).await;
    let base = format!("http://{}", running.addr);
    let anonymous = Client::new(&base).expect("client");
    match anonymous.sessions().await {
        Err(ClientError::Server {
            status: 401,
            message,
        }) => assert!(message.contains("token"), "{message}"),
        other => panic!("expected 401, got {other:?}"),
    }
    let wrong = Client::new(&base)
        .expect("client")
        .token(Some("nope".into()));
    assert!(matches!(
        wrong.health().await,
        Err(ClientError::Server { status: 401, .. })
    ));
    assert!(matches!(
        wrong.stream("x").await,
        Err(ClientError::Server { status: 401, .. })
    ));

    let client = Client::new(&base)
        .expect("client")
        .token(Some("t0ken".into()));
    match client.session("missing").await {
        Err(ClientError::Server {
            status: 404,
            message,
        }) => assert_eq!(message, "no session 'missing'"),
        other => panic!("expected 404, got {other:?}"),
    }
    let bad = CreateSession {
        scene: Some(SceneSpec::Json(json!({"camera": {}}))),
        ..small("x")
    };
    match client.create_session(&bad).await {
        Err(ClientError::Server {
            status: 400,
            message,
        }) => assert!(message.starts_with("scene: camera"), "{message}"),
        other => panic!("expected 400, got {other:?}"),
    }
    let s = client
        .create_session(&small("cornell"))
        .await
        .expect("create");
    match client
        .set_camera(
            &s.id,
            &CameraPatch {
                up: Some([0.0, 0.0, 0.0]),
                ..CameraPatch::default()
            },
        )
        .await
    {
        Err(ClientError::Server {
            status: 400,
            message,
        }) => assert!(message.contains("camera.up"), "{message}"),
        other => panic!("expected 400, got {other:?}"),
    }
    running.shutdown().await.expect("shutdown");
    // Nothing listens there any more.
    assert!(matches!(
        client.health().await,
        Err(ClientError::Unreachable(_))
    ));
    assert!(matches!(Client::new("ftp://x"), Err(ClientError::Input(_))));
}

/// The fields that are f32 on both sides (written as f64 in some bodies,
/// so compared at f32 precision); every other number must read back as it
/// was sent.
const F32_FIELDS: [&str; 1] = ["quality.clamp"];

/// Where `back` (the server's JSON read into the wire type and written
/// again) differs from `sent`, path by path, arrays' items included: keys
/// the type does not know, keys it adds, values it changes (an integer
/// read back as a float too).
fn differences(sent: &Value, back: &Value, path: &str, out: &mut Vec<String>) {
    let at = |key: &str| {
        if path.is_empty() {
            key.to_owned()
        } else {
            format!("{path}.{key}")
        }
    };
    match (sent, back) {
        (Value::Object(a), Value::Object(b)) => {
            for (key, v) in a {
                match b.get(key) {
                    Some(w) => differences(v, w, &at(key), out),
                    None => out.push(format!("{}: unknown to the wire types", at(key))),
                }
            }
            for key in b.keys().filter(|k| !a.contains_key(*k)) {
                out.push(format!("{}: expected, but the server lacks it", at(key)));
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (v, w)) in a.iter().zip(b).enumerate() {
                differences(v, w, &format!("{path}[{i}]"), out);
            }
        }
        (Value::Number(a), Value::Number(b))
            if a.is_f64() && b.is_f64() && F32_FIELDS.iter().any(|f| path.ends_with(f)) =>
        {
            let (x, y) = (a.as_f64().unwrap_or(0.0), b.as_f64().unwrap_or(0.0));
            if x as f32 != y as f32 {
                out.push(format!("{path}: sent {x}, read back as {y}"));
            }
        }
        (a, b) if a == b => {}
        (a, b) => out.push(format!("{path}: sent {a}, read back as {b}")),
    }
}

/// The server's JSON parses into the wire type, and reads back the same:
/// no field unknown to the type, none that the server leaves out, no value
/// changed (in nested objects and arrays too). Where the server serializes
/// the wire type itself this holds by construction; it is checked on what
/// the server actually sends, so that a body assembled around the types (a
/// list, the stream's stats, an error) or a value converted into them on
/// the way out cannot drift either.
fn assert_no_drift<T: DeserializeOwned + Serialize>(what: &str, server: &Value) -> T {
    let typed: T = serde_json::from_value(server.clone())
        .unwrap_or_else(|e| panic!("{what}: the client cannot read it: {e}\n{server}"));
    let back = serde_json::to_value(&typed).expect("serialize");
    let mut out = Vec::new();
    differences(server, &back, "", &mut out);
    assert!(
        out.is_empty(),
        "{what}: drift from the wire types: {out:?}\n{server}"
    );
    typed
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_client_types_match_every_route_of_the_server() {
    let running = server(None).await;
    let client = Client::new(&format!("http://{}", running.addr)).expect("client");
    assert_no_drift::<pathstream_client::Health>(
        "GET /api/health",
        &client.get_json("/api/health").await.expect("json"),
    );
    assert_no_drift::<pathstream_client::Devices>(
        "GET /api/devices",
        &client.get_json("/api/devices").await.expect("json"),
    );
    assert_no_drift::<pathstream_client::Scenes>(
        "GET /api/scenes",
        &client.get_json("/api/scenes").await.expect("json"),
    );
    // Sessions in every state the status can take: a light and none, halted
    // and rendering.
    let a = client
        .create_session(&small("cornell"))
        .await
        .expect("create");
    let mut no_light = small("furnace");
    no_light.scene = Some(SceneSpec::Json(json!({
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "vfov_deg": 40},
        "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]
    })));
    let b = client.create_session(&no_light).await.expect("create");
    client
        .frame_png(&a.id, Some(16), None)
        .await
        .expect("frame");
    for id in [&a.id, &b.id] {
        let s: SessionStatus = assert_no_drift(
            "GET /api/sessions/{id}",
            &client
                .get_json(&format!("/api/sessions/{id}"))
                .await
                .expect("json"),
        );
        assert_eq!(&s.id, id);
    }
    assert_no_drift::<pathstream_client::SessionList>(
        "GET /api/sessions",
        &client.get_json("/api/sessions").await.expect("json"),
    );
    running.shutdown().await.expect("shutdown");
}

/// The next text message on `socket` (frames in between are skipped).
async fn next_text(socket: &mut Socket) -> Value {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(30), socket.next())
            .await
            .expect("a message in time")
            .expect("the socket stays open")
            .expect("a message");
        if let WsMessage::Text(text) = message {
            return serde_json::from_str(text.as_str()).expect("JSON text");
        }
    }
}

type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_streams_messages_and_the_error_bodies_match_the_wire_types() {
    let running = server(None).await;
    let base = format!("http://{}", running.addr);
    let client = Client::new(&base).expect("client");
    let response = reqwest::get(format!("{base}/api/sessions/missing"))
        .await
        .expect("an answer");
    assert_eq!(response.status().as_u16(), 404);
    let body: ErrorBody = assert_no_drift("a 404's body", &response.json().await.expect("JSON"));
    assert_eq!(body.error, "no session 'missing'");

    // A quality whose clamp is not exact in binary: the stats write the
    // f32 widened, the status does not; both read back.
    let mut req = small("cornell");
    req.quality = Some(QualityPatch {
        clamp: Some(0.1),
        ..req.quality.unwrap_or_default()
    });
    let s = client.create_session(&req).await.expect("create");
    let ws = base.replacen("http", "ws", 1);
    let refused =
        tokio_tungstenite::connect_async(format!("{ws}/api/sessions/{}/ws?format=gif", s.id));
    match refused.await {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => {
            assert_eq!(r.status().as_u16(), 400);
            let body = serde_json::from_slice(r.body().as_deref().unwrap_or_default());
            let body: ErrorBody = assert_no_drift("a refused upgrade's body", &body.expect("JSON"));
            assert_eq!(
                body.error,
                "stream.format: must be png, jpeg or webp (got 'gif')"
            );
        }
        other => panic!("expected a 400, got {other:?}"),
    }

    let url = format!("{ws}/api/sessions/{}/ws?format=jpeg&quality=50", s.id);
    let (mut socket, _) = tokio_tungstenite::connect_async(url)
        .await
        .expect("connects");
    match assert_no_drift("the stream's stats", &next_text(&mut socket).await) {
        StreamMessage::Stats(stats) => {
            assert_eq!(
                (stats.status.id, stats.format.as_str()),
                (s.id.clone(), "jpeg")
            );
            assert!(stats.frame >= 1 && stats.frame_bytes > 0);
        }
        other => panic!("expected stats, got {other:?}"),
    }
    for (sent, said) in [
        (
            r#"{"nonsense": 1}"#,
            "message: unknown key 'nonsense' (expected camera, environment, light, quality or scene)",
        ),
        (
            r#"{"stream": {"format": "gif"}}"#,
            "stream.format: must be png, jpeg or webp (got 'gif')",
        ),
    ] {
        socket.send(WsMessage::text(sent)).await.expect("sends");
        let error = loop {
            let text = next_text(&mut socket).await;
            if text["type"] == "error" {
                break text;
            }
        };
        let error: StreamMessage = assert_no_drift("the stream's error", &error);
        assert_eq!(error, StreamMessage::Error(ErrorBody::new(said)));
    }
    let status = client.get_json(&format!("/api/sessions/{}", s.id)).await;
    let status: SessionStatus = assert_no_drift("a clamped status", &status.expect("json"));
    assert_eq!(status.quality.clamp, 0.1);
    running.shutdown().await.expect("shutdown");
}

#[test]
fn the_blocking_client_works_without_a_runtime_of_its_own() {
    // The server runs on its own runtime thread; the test thread has none.
    let (tx, rx) = std::sync::mpsc::channel();
    let (stop_tx, stop_rx) = tokio::sync::oneshot::channel::<()>();
    let server = std::thread::spawn(move || {
        let rt = tokio::runtime::Runtime::new().expect("runtime");
        rt.block_on(async move {
            let running = server(None).await;
            tx.send(running.addr).expect("send");
            let _ = stop_rx.await;
            running.shutdown().await.expect("shutdown");
        });
    });
    let addr = rx.recv().expect("address");
    let client =
        pathstream_client::blocking::Client::new(&format!("http://{addr}")).expect("client");
    assert_eq!(client.health().expect("health").status, "ok");
    assert!(!client.devices().expect("devices").backends.is_empty());
    assert!(client.scenes().expect("scenes").len() >= 5);
    let s = client.create_session(&small("cornell")).expect("create");
    assert_eq!(client.sessions().expect("list").len(), 1);
    assert!(client
        .frame_png(&s.id, Some(16), None)
        .expect("png")
        .starts_with(b"\x89PNG"));
    assert!(client
        .frame_pfm(&s.id, None, None)
        .expect("pfm")
        .starts_with(b"PF"));
    client
        .set_camera(
            &s.id,
            &CameraPatch {
                vfov_deg: Some(30.0),
                ..CameraPatch::default()
            },
        )
        .expect("camera");
    client
        .set_light(
            &s.id,
            &LightPatch {
                color: Some([1.0, 0.5, 0.5]),
                ..LightPatch::default()
            },
        )
        .expect("light");
    client
        .set_quality(
            &s.id,
            &QualityPatch {
                nee: Some(false),
                ..QualityPatch::default()
            },
        )
        .expect("quality");
    let st = client
        .set_scene(&s.id, &SceneSpec::Name("smallpt".into()))
        .expect("scene");
    assert_eq!((st.scene.as_str(), st.generation), ("smallpt", 4));
    assert!(!client.session(&s.id).expect("status").quality.nee);
    client.delete_session(&s.id).expect("delete");
    assert!(matches!(
        client.session(&s.id),
        Err(ClientError::Server { status: 404, .. })
    ));
    stop_tx.send(()).expect("stop");
    server.join().expect("server thread");
}

/// A closed unit tetrahedron as OBJ text.
const TETRAHEDRON_OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn assets_upload_list_render_and_delete_through_the_client() {
    let running = server(None).await;
    let client = Client::new(&format!("http://{}", running.addr)).expect("client");
    let first = client
        .upload_asset("tet.obj", TETRAHEDRON_OBJ.into())
        .await
        .expect("upload");
    assert!(!first.deduplicated);
    assert_eq!(
        (first.asset.format.as_str(), first.asset.triangles),
        ("obj", 4)
    );
    let again = client
        .upload_asset("other-name.obj", TETRAHEDRON_OBJ.into())
        .await
        .expect("upload");
    assert!(again.deduplicated);
    assert_eq!(again.asset.id, first.asset.id);

    let id = first.asset.id.clone();
    let one: pathstream_client::Asset = assert_no_drift(
        "GET /api/assets/{id}",
        &client
            .get_json(&format!("/api/assets/{id}"))
            .await
            .expect("json"),
    );
    assert_eq!(one, client.asset(&id).await.expect("asset"));
    let list: pathstream_client::AssetList = assert_no_drift(
        "GET /api/assets",
        &client.get_json("/api/assets").await.expect("json"),
    );
    assert_eq!(list.assets.len(), 1);
    assert!(list.memory_bytes > 0 && list.memory_bytes <= list.memory_limit_bytes);

    // A session on the asset: framed and lit by the defaults, it renders.
    let mut req = small("x");
    req.scene = Some(SceneSpec::Json(
        json!({"objects": [{"type": "model", "asset": id}]}),
    ));
    let s = client
        .create_session(&req)
        .await
        .expect("a session on the asset");
    let st: SessionStatus = assert_no_drift(
        "GET /api/sessions/{id} (warnings)",
        &client
            .get_json(&format!("/api/sessions/{}", s.id))
            .await
            .expect("json"),
    );
    assert!(
        st.warnings.iter().any(|w| w.contains("environment")),
        "{:?}",
        st.warnings
    );
    let png = client.frame_png(&s.id, Some(4), None).await.expect("png");
    assert_eq!(image::load_from_memory(&png).expect("a PNG").width(), 16);

    match client
        .upload_asset("broken.obj", b"v 0 0 0\nf 1 2 3\n".to_vec())
        .await
    {
        Err(ClientError::Server {
            status: 400,
            message,
        }) => assert!(message.contains("broken.obj"), "{message}"),
        other => panic!("expected 400, got {other:?}"),
    }
    client.delete_asset(&id).await.expect("delete");
    assert!(matches!(
        client.asset(&id).await,
        Err(ClientError::Server { status: 404, .. })
    ));
    running.shutdown().await.expect("shutdown");
}
