//! Denoising through the server: a session that denoises streams denoised
//! frames (the stats say so) unless the stream asks for the raw image, its
//! halted frame is denoised under `final` and raw under `stream`, the frame
//! routes take `?denoise=1|0`; and a server without Open Image Denoise (no
//! library, or a broken file) starts, renders, says why in
//! `/api/devices`, and refuses a denoise request with a 400 naming the
//! library, as `pathstream render --denoise` exits 2.

mod common;
mod http;

use common::oidn;
use http::{create, get, get_json, halted, next_frame, patch, server, ws_connect_with, ws_send};
use serde_json::{json, Value};
use std::process::{Command, Stdio};

/// Sum of absolute differences of horizontally adjacent values as
/// displayed (a PFM frame's pixel noise, the light's edges clipped).
fn roughness(pfm: &[u8]) -> f64 {
    use pathstream::render::tonemap::srgb;
    let (w, _, px) = pathstream_wire::pfm::decode(pfm).expect("a PFM");
    let (w, px) = (w as usize, &px);
    let mut sum = 0.0;
    for (i, p) in px.iter().enumerate().filter(|(i, _)| i % w != 0) {
        let d = |c: usize| f64::from((srgb(p[c]) - srgb(px[i - 1][c])).abs());
        sum += d(0) + d(1) + d(2);
    }
    sum
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_denoising_session_streams_denoised_frames_unless_asked_for_raw() {
    if !oidn() {
        return;
    }
    let (running, base) = server(http::config()).await;
    let body = json!({"scene": "cornell", "width": 64, "height": 48, "quality": {"denoise": "stream", "spp": 8}});
    let s = create(&base, body).await;
    let id = s["id"].as_str().expect("id").to_owned();
    assert_eq!(s["quality"]["denoise"], "stream");
    let mut ws = ws_connect_with(&base, &id, "").await;
    let mut raw = ws_connect_with(&base, &id, "?raw=true").await;
    let (_, stats) = next_frame(&mut ws).await;
    let (_, raw_stats) = next_frame(&mut raw).await;
    let running_frame = |s: &Value| s["state"] == "rendering" || s["spp"].as_u64() < Some(8);
    if running_frame(&stats) {
        assert_eq!(stats["denoised"], true, "{stats}");
    }
    assert_eq!(raw_stats["denoised"], false, "{raw_stats}");
    // Asked by message too: from the next frames on (one may be on its
    // way already; the newest is sent again as asked, halted or not).
    ws_send(&mut ws, json!({"stream": {"raw": true}})).await;
    let mut seen = Vec::new();
    while seen.len() < 4 {
        let (_, s) = next_frame(&mut ws).await;
        seen.push(s["denoised"].clone());
        if s["denoised"] == false {
            break;
        }
    }
    assert_eq!(seen.last(), Some(&json!(false)), "{seen:?}");

    // `stream`: the halted frame goes out raw; `?denoise=1` denoises it.
    halted(&base, &id, None).await;
    let frame = |q: &str| get(format!("{base}/api/sessions/{id}/frame.pfm?min_spp=8{q}"));
    let plain = frame("").await;
    assert_eq!(plain.headers()["x-pathstream-denoised"], "false");
    let plain = plain.bytes().await.expect("body");
    let asked = frame("&denoise=1").await;
    assert_eq!(asked.headers()["x-pathstream-denoised"], "true");
    let asked = asked.bytes().await.expect("body");
    eprintln!(
        "roughness: denoised {}, raw {}",
        roughness(&asked),
        roughness(&plain)
    );
    assert!(
        roughness(&asked) * 2.0 < roughness(&plain),
        "denoised {} vs raw {}",
        roughness(&asked),
        roughness(&plain)
    );

    // `final`: the halted frame is denoised; `?denoise=0` is the raw one.
    let r = patch(&base, &id, "quality", json!({"denoise": "final"})).await;
    assert_eq!(r.status(), 200);
    let g = r.json::<Value>().await.expect("json")["generation"].as_u64();
    halted(&base, &id, g).await;
    let png = get(&format!("{base}/api/sessions/{id}/frame.png?min_spp=8")).await;
    assert_eq!(png.headers()["x-pathstream-denoised"], "true");
    let png = get(&format!(
        "{base}/api/sessions/{id}/frame.png?min_spp=8&denoise=0"
    ))
    .await;
    assert_eq!(png.headers()["x-pathstream-denoised"], "false");
    let bad = get(&format!("{base}/api/sessions/{id}/frame.png?denoise=yes")).await;
    assert_eq!(bad.status(), 400);
    assert!(bad.text().await.expect("body").contains("denoise"));
    running.shutdown().await.expect("shutdown");
}

/// `pathstream serve` with PATHSTREAM_OIDN set to `oidn`; its URL.
fn serve_with(oidn: &str) -> (std::process::Child, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(["serve", "--addr", "127.0.0.1:0", "--backend", "cpu"])
        .env("PATHSTREAM_OIDN", oidn)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("starts");
    let url = http::served_url(&mut child);
    (child, url)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_the_library_the_server_renders_and_refuses_to_denoise_by_name() {
    let dir = tempfile::tempdir().expect("tempdir");
    let broken = dir.path().join("libOpenImageDenoise.so.2");
    std::fs::write(&broken, b"not a shared library").expect("write");
    let broken = broken.to_str().expect("utf-8").to_owned();
    for oidn in ["/nonexistent/oidn", broken.as_str()] {
        let (mut child, base) = serve_with(oidn);
        let devices: Value = get_json(&format!("{base}/api/devices")).await;
        let d = &devices["denoiser"];
        assert_eq!(d["available"], false, "{oidn}: {d}");
        let why = d["reason"].as_str().unwrap_or_default();
        assert!(
            why.contains(oidn) && why.contains("libOpenImageDenoise.so.2"),
            "{oidn}: {why}"
        );

        // Refused by name, with a 400, wherever it is asked for.
        let refused = |what: &str, r: &Value| {
            let text = r["error"].as_str().unwrap_or_default();
            assert!(
                text.contains("denoise") && text.contains("Open Image Denoise"),
                "{oidn} {what}: {r}"
            );
        };
        let r = http::client()
            .post(format!("{base}/api/sessions"))
            .json(&json!({"scene": "cornell", "width": 16, "height": 12, "quality": {"denoise": "stream"}}))
            .send()
            .await
            .expect("request");
        assert_eq!(r.status(), 400);
        refused("create", &r.json().await.expect("json"));
        let s = create(
            &base,
            json!({"scene": "cornell", "width": 16, "height": 12, "quality": {"spp": 2}}),
        )
        .await;
        let id = s["id"].as_str().expect("id");
        let r = patch(&base, id, "quality", json!({"denoise": "final"})).await;
        assert_eq!(r.status(), 400);
        refused("quality", &r.json().await.expect("json"));
        let r = get(&format!(
            "{base}/api/sessions/{id}/frame.png?min_spp=2&denoise=1"
        ))
        .await;
        assert_eq!(r.status(), 400);
        refused("frame.png", &r.json().await.expect("json"));
        // It renders as before.
        let r = get(&format!("{base}/api/sessions/{id}/frame.png?min_spp=2")).await;
        assert_eq!(r.status(), 200);
        assert_eq!(r.headers()["x-pathstream-denoised"], "false");
        let _ = child.kill();
        let _ = child.wait();

        let out = Command::new(env!("CARGO_BIN_EXE_pathstream"))
            .args([
                "render",
                "--scene",
                "cornell",
                "--width",
                "8",
                "--height",
                "8",
                "--denoise",
            ])
            .args(["--out", dir.path().join("x.png").to_str().expect("utf-8")])
            .env("PATHSTREAM_OIDN", oidn)
            .output()
            .expect("runs");
        assert_eq!(out.status.code(), Some(2), "{oidn}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("--denoise") && err.contains(oidn), "{err}");
    }
}
