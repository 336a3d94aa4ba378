//! The WebSocket stream's frames: PNG at the film's size by default, JPEG
//! or WebP and a smaller width when a socket asks (on its URL or by message), each
//! frame's stats naming the format, its bytes and size; bad settings are
//! refused by name.

mod http;

use futures_util::SinkExt;
use http::{client, config, create, next_frame, pfm, server, ws_connect_with as connect};
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

const JPEG: [u8; 3] = [0xFF, 0xD8, 0xFF];
const PNG: [u8; 4] = [0x89, b'P', b'N', b'G'];

fn mean(image: &[u8]) -> (u32, u32, f64) {
    let img = image::load_from_memory(image).expect("decodes").to_rgb8();
    let sum: f64 = img.pixels().flat_map(|p| p.0).map(f64::from).sum();
    (
        img.width(),
        img.height(),
        sum / f64::from(img.width() * img.height() * 3),
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_socket_chooses_jpeg_or_png_and_stats_say_which_and_how_big() {
    let (running, base) = server(config()).await;
    // Halted at 4 spp: noisy, and every frame the same image.
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 128, "height": 96, "quality": {"spp": 4}}),
    )
    .await;
    let id = s["id"].as_str().expect("id");
    // Both sockets must see the halted frame, not one of the frames before.
    pfm(&base, id, 4).await;
    let mut png_ws = connect(&base, id, "").await;
    let (png, png_stats) = next_frame(&mut png_ws).await;
    assert_eq!(png[..4], PNG);
    assert_eq!(png_stats["format"], "png");
    assert_eq!(png_stats["frame_bytes"], png.len());
    let mut ws = connect(&base, id, "?format=jpeg&quality=80").await;
    let (jpeg, stats) = next_frame(&mut ws).await;
    assert_eq!(jpeg[..3], JPEG);
    assert_eq!(
        (stats["format"].clone(), stats["frame_bytes"].clone()),
        (json!("jpeg"), json!(jpeg.len()))
    );
    // The same image, smaller: a noisy frame defeats PNG's compression.
    let ((w, h, a), (_, _, b)) = (mean(&png), mean(&jpeg));
    assert_eq!((w, h), (128, 96));
    assert!(
        (a - b).abs() < 0.02 * a.max(1.0),
        "mean {a} (PNG) vs {b} (JPEG)"
    );
    assert!(
        jpeg.len() * 2 < png.len(),
        "JPEG {} bytes, PNG {}",
        jpeg.len(),
        png.len()
    );
    // Lossy WebP: a RIFF/WEBP file of the same image, smaller than the PNG.
    let mut webp_ws = connect(&base, id, "?format=webp&quality=80").await;
    let (webp, webp_stats) = next_frame(&mut webp_ws).await;
    assert_eq!((&webp[..4], &webp[8..12]), (&b"RIFF"[..], &b"WEBP"[..]));
    assert_eq!(
        (
            webp_stats["format"].clone(),
            webp_stats["frame_bytes"].clone()
        ),
        (json!("webp"), json!(webp.len()))
    );
    let (ww, wh, c) = mean(&webp);
    assert_eq!((ww, wh), (128, 96));
    assert!(
        (a - c).abs() < 0.02 * a.max(1.0),
        "mean {a} (PNG) vs {c} (WebP)"
    );
    assert!(
        webp.len() * 2 < png.len(),
        "WebP {} bytes, PNG {}",
        webp.len(),
        png.len()
    );
    eprintln!(
        "cornell-glass 128x96 at 4 spp: PNG {} bytes, JPEG q80 {} bytes, WebP q80 {} bytes",
        png.len(),
        jpeg.len(),
        webp.len()
    );
    // By message: back to PNG, together with a change.
    ws.send(Message::Text(
        json!({"stream": {"format": "png"}, "quality": {"spp": 2}})
            .to_string()
            .into(),
    ))
    .await
    .expect("send");
    let until = Instant::now() + Duration::from_secs(60);
    loop {
        let (image, stats) = next_frame(&mut ws).await;
        if stats["quality"]["spp"] == 2 && stats["spp"] == 2 {
            assert_eq!(image[..4], PNG, "{stats}");
            break;
        }
        assert!(Instant::now() < until, "the change shows");
    }
    // A bad setting by message: an error naming it, and the socket stays.
    ws.send(Message::Text(
        json!({"stream": {"format": "jpeg", "quality": 101}})
            .to_string()
            .into(),
    ))
    .await
    .expect("send");
    let e = http::next_error(&mut ws).await;
    assert!(e.contains("stream.quality"), "{e}");
    ws.send(Message::Text(
        json!({"stream": {"format": "jpeg"}}).to_string().into(),
    ))
    .await
    .expect("the socket is still open");
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_stream_settings_on_the_url_are_refused_by_name() {
    let (running, base) = server(config()).await;
    let s = create(&base, json!({"scene": "cornell", "width": 8, "height": 8})).await;
    let id = s["id"].as_str().expect("id");
    for (query, needle) in [
        ("?format=gif", "format: must be png, jpeg or webp"),
        (
            "?format=jpeg&quality=0",
            "stream.quality: must be between 1 and 100",
        ),
        (
            "?quality=50",
            "stream.quality: only for format jpeg or webp",
        ),
        ("?fromat=jpeg", "fromat"),
    ] {
        let r = client()
            .get(format!("{base}/api/sessions/{id}/ws{query}"))
            .header("connection", "upgrade")
            .header("upgrade", "websocket")
            .header("sec-websocket-version", "13")
            .header("sec-websocket-key", "dGhlIHNhbXBsZSBub25jZQ==")
            .send()
            .await
            .expect("answer");
        assert_eq!(r.status(), 400, "{query}");
        let body: Value = r.json().await.expect("a JSON error");
        let e = body["error"].as_str().unwrap_or("");
        assert!(e.contains(needle), "{query}: {e}");
    }
    running.shutdown().await.expect("shutdown");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_scale_to_the_width_a_socket_asks_for_and_keep_the_image() {
    let (running, base) = server(config()).await;
    // A furnace capped at one bounce without NEE or roulette: every sample
    // of every pixel exactly 0.5 + 0.5 x 0.5, at any size.
    let furnace = create(
        &base,
        json!({"scene": "furnace", "width": 96, "height": 64,
               "quality": {"spp": 2, "max_depth": 1, "nee": false, "rr_depth": 100}}),
    )
    .await;
    let id = furnace["id"].as_str().expect("id");
    let mut full = connect(&base, id, "").await;
    let (png, _) = next_frame(&mut full).await;
    let mut small = connect(&base, id, "?width=30").await;
    let (scaled, stats) = next_frame(&mut small).await;
    assert_eq!(scaled[..4], PNG);
    assert_eq!(
        (stats["frame_width"].clone(), stats["frame_height"].clone()),
        (json!(30), json!(20))
    );
    assert_eq!(
        (stats["width"].clone(), stats["height"].clone()),
        (json!(96), json!(64)),
        "the film is unchanged"
    );
    let (a, b) = (
        image::load_from_memory(&png).expect("png").to_rgb8(),
        image::load_from_memory(&scaled).expect("png").to_rgb8(),
    );
    assert_eq!((b.width(), b.height()), (30, 20));
    assert!(
        b.pixels().all(|p| *p == *a.get_pixel(0, 0)),
        "a constant image stays that constant"
    );
    // A noisy one, asked by message, as JPEG: the same image as the PNG
    // of that width (means within JPEG's loss).
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 128, "height": 96, "quality": {"spp": 16}}),
    )
    .await;
    let id = s["id"].as_str().expect("id");
    let mut ws = connect(&base, id, "").await;
    let _ = next_frame(&mut ws).await;
    ws.send(Message::Text(
        json!({"stream": {"format": "jpeg", "quality": 90, "width": 64}})
            .to_string()
            .into(),
    ))
    .await
    .expect("send");
    ws.send(Message::Text(
        json!({"quality": {"spp": 16, "seed": 1}})
            .to_string()
            .into(),
    ))
    .await
    .expect("send");
    let until = Instant::now() + Duration::from_secs(60);
    let (jpeg, stats) = loop {
        let (image, stats) = next_frame(&mut ws).await;
        if stats["format"] == "jpeg" && stats["spp"] == 16 && stats["quality"]["seed"] == 1 {
            break (image, stats);
        }
        assert!(Instant::now() < until, "the JPEG frames come");
    };
    assert_eq!(jpeg[..3], JPEG);
    assert_eq!(
        (stats["frame_width"].clone(), stats["frame_height"].clone()),
        (json!(64), json!(48))
    );
    let mut png_ws = connect(&base, id, "?width=64").await;
    let (png, png_stats) = next_frame(&mut png_ws).await;
    assert_eq!(
        png_stats["generation"], stats["generation"],
        "the same frame"
    );
    let ((pw, ph, m_png), (w, h, m_jpeg)) = (mean(&png), mean(&jpeg));
    assert_eq!((pw, ph, w, h), (64, 48, 64, 48));
    assert!(
        (m_png - m_jpeg).abs() < 0.02 * m_png,
        "mean {m_png} (PNG) vs {m_jpeg} (JPEG 90)"
    );
    running.shutdown().await.expect("shutdown");
}
