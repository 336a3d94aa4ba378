//! The client library against a real server: every call, the error paths,
//! and contract drift (the server's JSON and the client's types must have
//! exactly the same fields).

use futures_util::StreamExt;
use pathstream::api::{start, Running};
use pathstream::render::BackendChoice;
use pathstream::service::ServeConfig;
use pathstream_client::{
    CameraPatch, Client, ClientError, CreateSession, LightPatch, QualityPatch, SceneSpec,
    SessionStatus,
};
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::{json, Value};
use std::time::Duration;

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

/// Every key path in `v`, e.g. `camera.position`, `light.index`.
fn key_paths(v: &Value, prefix: &str, out: &mut Vec<String>) {
    if let Value::Object(map) = v {
        for (k, child) in map {
            let path = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            out.push(path.clone());
            key_paths(child, &path, out);
        }
    }
}

/// The server's JSON parses into the client's type, and the type has
/// exactly the server's fields: none unknown to the client, none missing.
fn assert_no_drift<T: DeserializeOwned + Serialize>(what: &str, server: &Value) -> T {
    let typed: T = serde_json::from_value(server.clone())
        .unwrap_or_else(|e| panic!("{what}: the client cannot read it: {e}\n{server}"));
    let back = serde_json::to_value(&typed).expect("serialize");
    let (mut a, mut b) = (Vec::new(), Vec::new());
    key_paths(server, "", &mut a);
    key_paths(&back, "", &mut b);
    a.sort();
    b.sort();
    let unknown: Vec<_> = a.iter().filter(|k| !b.contains(k)).collect();
    let missing: Vec<_> = b.iter().filter(|k| !a.contains(k)).collect();
    assert!(
        unknown.is_empty(),
        "{what}: the server sends fields the client does not know: {unknown:?}"
    );
    assert!(
        missing.is_empty(),
        "{what}: the client expects fields the server lacks: {missing:?}"
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
