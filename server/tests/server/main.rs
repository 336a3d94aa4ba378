//! The render service end to end: a real server on 127.0.0.1:0, real HTTP
//! and WebSocket clients: sessions, updates and light (here); bad input and
//! the token (`guards`); expiry, shutdown and a failed device (`lifetime`);
//! the page's files (`static_files`).

mod guards;
#[path = "../http/mod.rs"]
mod http;
mod lifetime;
mod static_files;

use futures_util::{SinkExt, StreamExt};
use http::*;
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn session_lifecycle() {
    let (running, base) = server(config()).await;
    let health: Value = get_json(format!("{base}/api/health")).await;
    assert_eq!(health["status"], "ok");
    let scenes: Value = get_json(format!("{base}/api/scenes")).await;
    assert!(scenes["scenes"]
        .as_array()
        .expect("list")
        .iter()
        .any(|s| s == "cornell-glass"));

    let s = create(
        &base,
        json!({"scene": "cornell", "width": 24, "height": 16, "quality": {"spp": 32}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    for field in [
        "scene",
        "width",
        "height",
        "camera",
        "light",
        "quality",
        "state",
        "spp",
        "error_estimate",
        "samples_per_sec",
        "elapsed_ms",
        "backend",
        "device",
    ] {
        assert!(s.get(field).is_some(), "status lacks {field}: {s}");
    }
    assert_eq!(s["backend"], "cpu");

    let list: Value = get_json(format!("{base}/api/sessions")).await;
    assert_eq!(list["sessions"][0]["id"], id.as_str());

    // min_spp waits; the halt at 32 spp stops the session.
    let png = get(format!("{base}/api/sessions/{id}/frame.png?min_spp=32")).await;
    assert_eq!(png.headers()["content-type"], "image/png");
    let img = image::load_from_memory(&png.bytes().await.expect("body")).expect("a PNG");
    assert_eq!((img.width(), img.height()), (24, 16));
    let st = status(&base, &id).await;
    assert_eq!(st["spp"], 32);
    assert_eq!(st["state"], "halted");
    let pixels = pfm(&base, &id, 32).await;
    assert_eq!(pixels.len(), 24 * 16);

    let metrics = get(format!("{base}/metrics"))
        .await
        .text()
        .await
        .expect("text");
    assert!(metrics.contains("pathstream_sessions 1"), "{metrics}");
    assert!(
        metrics.contains("pathstream_worker_sessions{worker=\"0\",backend=\"cpu\"} 1"),
        "{metrics}"
    );
    assert!(
        metrics.contains("pathstream_worker_busy_ratio{worker=\"0\",backend=\"cpu\"} "),
        "{metrics}"
    );
    assert!(
        metrics.contains("pathstream_samples_total{backend=\"cpu\"} "),
        "{metrics}"
    );
    let rendered: u64 = metrics
        .lines()
        .find(|l| l.starts_with("pathstream_samples_total{backend=\"cpu\"}"))
        .and_then(|l| l.rsplit(' ').next()?.parse().ok())
        .expect("a count");
    assert!(rendered >= 32 * 24 * 16, "{rendered} camera paths counted");

    let del = delete(format!("{base}/api/sessions/{id}")).await;
    assert_eq!(del.status(), 204);
    let gone = get(format!("{base}/api/sessions/{id}")).await;
    assert_eq!(gone.status(), 404);
    let body: Value = gone.json().await.expect("json error");
    assert!(body["error"].as_str().expect("message").contains(&id));
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn updates_restart_accumulation_and_change_the_image() {
    let (running, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 24, "height": 24, "quality": {"spp": 64}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let before = pfm(&base, &id, 64).await;

    let r = patch(
        &base,
        &id,
        "camera",
        json!({"position": [50, 40, 250], "look_at": [20, 20, 0]}),
    )
    .await;
    assert_eq!(r.status(), 200);
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["generation"], 1);
    assert!(
        st["spp"].as_u64().expect("spp") < 64,
        "accumulation restarted: {st}"
    );
    assert_eq!(st["camera"]["position"], json!([50.0, 40.0, 250.0]));
    let after = pfm(&base, &id, 64).await;
    let diff: f64 = before
        .iter()
        .zip(&after)
        .map(|(a, b)| f64::from((a[0] - b[0]).abs()))
        .sum::<f64>()
        / before.len() as f64;
    assert!(
        diff > 0.05,
        "the camera moved but the image did not change ({diff})"
    );

    // Quality and scene changes restart too.
    let st: Value = patch(&base, &id, "quality", json!({"max_depth": 2}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["generation"], 2);
    assert_eq!(st["quality"]["max_depth"], 2);
    assert_eq!(
        st["quality"]["spp"], 64,
        "fields not named keep their values"
    );
    // A preset sets the path knobs; fields beside it win; seed and halts stay.
    let st: Value = patch(
        &base,
        &id,
        "quality",
        json!({"preset": "reference", "rr_depth": 2}),
    )
    .await
    .json()
    .await
    .expect("json");
    let reference =
        pathstream::render::Preset::Reference.apply(pathstream::render::Quality::default());
    assert_eq!(st["quality"]["max_depth"], reference.max_depth);
    assert_eq!(st["quality"]["nee"], reference.nee);
    assert_eq!(st["quality"]["rr_depth"], 2);
    assert_eq!(st["quality"]["spp"], 64);
    assert_eq!(st["generation"], 3);
    let presets: Value = get_json(format!("{base}/api/presets")).await;
    let names: Vec<&str> = presets["presets"]
        .as_array()
        .expect("list")
        .iter()
        .filter_map(|p| p["name"].as_str())
        .collect();
    assert_eq!(names, ["preview", "interactive", "final", "reference"]);
    assert_eq!(
        presets["presets"][3]["quality"]["max_depth"],
        reference.max_depth
    );
    let r = client()
        .put(format!("{base}/api/sessions/{id}/scene"))
        .json(&json!("cornell-glass"))
        .send()
        .await
        .expect("req");
    let st: Value = r.json().await.expect("json");
    assert_eq!(st["scene"], "cornell-glass");
    assert_eq!(st["generation"], 4);
    running.shutdown().await.expect("shutdown");
}

/// Luminance-weighted mean column of an image `width` pixels wide: where
/// the light falls, left to right.
fn centroid_x(img: &[[f32; 3]], width: usize) -> f64 {
    let (mut sum, mut weighted) = (0.0, 0.0);
    for (i, p) in img.iter().enumerate() {
        let l = f64::from(p[0] + p[1] + p[2]);
        sum += l;
        weighted += l * (i % width) as f64;
    }
    weighted / sum
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn light_changes_the_image_where_expected() {
    let (running, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 16, "height": 16, "quality": {"spp": 256, "seed": 1}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let base_img = pfm(&base, &id, 256).await;

    // Twice the intensity, same seed: every sample's path is the same and
    // its radiance exactly doubles, so every pixel does, to f32 rounding.
    let st: Value = patch(&base, &id, "light", json!({"intensity": 24}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["light"]["intensity"], 24.0);
    let bright = pfm(&base, &id, 256).await;
    for (i, (b, a)) in bright.iter().zip(&base_img).enumerate() {
        for c in 0..3 {
            let (b, a) = (f64::from(b[c]), f64::from(a[c]));
            assert!(
                (b - 2.0 * a).abs() <= 2e-6 * a,
                "pixel {i} channel {c}: {b} vs 2 x {a}"
            );
        }
    }
    assert!(mean(&base_img)[1] > 0.1, "the room is lit");
    // A red light: no green or blue at all.
    let st: Value = patch(&base, &id, "light", json!({"color": [1, 0, 0]}))
        .await
        .json()
        .await
        .expect("json");
    assert_eq!(st["light"]["color"], json!([1.0, 0.0, 0.0]));
    let red = mean(&pfm(&base, &id, 256).await);
    assert!(red[0] > 0.1 && red[1] == 0.0 && red[2] == 0.0, "{red:?}");
    // Moving the light toward a wall moves the light in the image with it.
    let centre = centroid_x(&bright, 16);
    let mut seen = Vec::new();
    for (x, side) in [(15.0, -1.0), (85.0, 1.0)] {
        let r = patch(
            &base,
            &id,
            "light",
            json!({"position": [x, 60, 81.6], "color": [1, 1, 1]}),
        )
        .await;
        assert_eq!(r.status(), 200);
        let st: Value = r.json().await.expect("json");
        assert_eq!(st["light"]["position"], json!([x, 60.0, 81.6]));
        let moved = centroid_x(&pfm(&base, &id, 256).await, 16);
        seen.push(moved);
        assert!(
            (moved - centre) * side > 1.5,
            "light at x = {x}: the image's centroid {moved:.2} vs {centre:.2} in the middle"
        );
    }
    eprintln!(
        "centroid column: light in the middle {centre:.2}, left {:.2}, right {:.2}",
        seen[0], seen[1]
    );
    running.shutdown().await.expect("shutdown");
}
