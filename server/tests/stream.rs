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

/// Per-channel means of the image's `cols` x `rows` blocks, in 8-bit
/// levels: a frame flipped, shifted or scaled wrongly moves them by far more
/// than a lossy codec's error (the walls are red on the left, blue on the
/// right; the light is at the top).
fn blocks(image: &[u8], cols: u32, rows: u32) -> Vec<[f64; 3]> {
    let img = image::load_from_memory(image).expect("decodes").to_rgb8();
    let (bw, bh) = (img.width() / cols, img.height() / rows);
    assert_eq!((bw * cols, bh * rows), img.dimensions(), "whole blocks");
    let mut out = vec![[0.0; 3]; (cols * rows) as usize];
    for (x, y, p) in img.enumerate_pixels() {
        let b = &mut out[((y / bh) * cols + x / bw) as usize];
        for c in 0..3 {
            b[c] += f64::from(p[c]) / f64::from(bw * bh);
        }
    }
    out
}

/// Asserts that every block of `a` and `b` (a `grid` x `grid` of them) is
/// within `levels` in every channel.
fn assert_blocks_agree(a: &[u8], b: &[u8], grid: u32, levels: f64, what: &str) {
    let (ba, bb) = (blocks(a, grid, grid), blocks(b, grid, grid));
    let worst = (ba.iter().zip(&bb))
        .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
        .fold(0.0, f64::max);
    eprintln!("{what}: blocks differ by at most {worst:.2} levels");
    assert!(
        worst < levels,
        "{what}: a block differs by {worst:.2} levels"
    );
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
    let ((w, h, _), (jw, jh, _)) = (mean(&png), mean(&jpeg));
    assert_eq!((w, h, jw, jh), (128, 96, 128, 96));
    assert_blocks_agree(&png, &jpeg, 8, 6.0, "PNG vs JPEG q80");
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
    let (ww, wh, _) = mean(&webp);
    assert_eq!((ww, wh), (128, 96));
    assert_blocks_agree(&png, &webp, 8, 6.0, "PNG vs WebP q80");
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
    let ((pw, ph, _), (w, h, _)) = (mean(&png), mean(&jpeg));
    assert_eq!((pw, ph, w, h), (64, 48, 64, 48));
    assert_blocks_agree(&png, &jpeg, 4, 6.0, "PNG vs JPEG q90, both 64 wide");
    // The PNG is the film's 2x2 boxes in linear radiance, tone mapped: the
    // film itself, averaged here, says what every pixel must be.
    let film = pfm(&base, id, 16).await;
    let expected: Vec<[f32; 3]> = (0..48 * 64)
        .map(|i| {
            let (x, y) = (2 * (i % 64), 2 * (i / 64));
            let mut sum = [0.0f32; 3];
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = film[(y + dy) * 128 + x + dx];
                for c in 0..3 {
                    sum[c] += p[c] / 4.0;
                }
            }
            sum
        })
        .collect();
    let expected = pathstream::render::tonemap::Tonemap::default().bytes(&expected);
    let got = image::load_from_memory(&png)
        .expect("png")
        .to_rgb8()
        .into_raw();
    let off = (expected.iter().zip(&got))
        .filter(|(e, g)| e.abs_diff(**g) > 1)
        .count();
    assert_eq!(
        off, 0,
        "of the 64x48 PNG's bytes, {off} are not the film's 2x2 means"
    );
    running.shutdown().await.expect("shutdown");
}
