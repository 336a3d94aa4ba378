//! Latency from a camera update sent on the WebSocket to the first frame
//! that reflects it (a whole sample, or the server's reduced-resolution
//! preview where one sample of the image is slow), p50 and p95 over 100
//! updates, plus PNG encode time and
//! frames delivered per second. Runs its own server on 127.0.0.1:0, or uses
//! the one at `--url` (a box, or a proxy in front of boxes: deploy/).
//!
//!     cargo run --release --example latency -- [--backend cpu|opencl|auto] [--size 256]
//!         [--height H] [--updates 100] [--url http://HOST:PORT]
//!         [--stream 'format=jpeg&quality=85&progressive=true'] [--ack] [--fov-updates]
//!
//! `--stream` is added to the WebSocket's URL; `--ack` answers every frame
//! with `{"ack": FRAME}` (as the page does), so that one frame is in flight
//! and the stats measure the link (printed at the end).
//! `scripts/netem-bench.sh` runs it across a shaped link.

use futures_util::{SinkExt, StreamExt};
use pathstream::api::start;
use pathstream::render::output::encode_png;
use pathstream::render::tonemap::Tonemap;
use pathstream::render::BackendChoice;
use pathstream::service::ServeConfig;
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

fn arg(name: &str, default: &str) -> String {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| default.to_owned())
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    if std::env::var_os("RUST_LOG").is_some() {
        tracing_subscriber::fmt()
            .with_env_filter(tracing_subscriber::EnvFilter::from_default_env())
            .init();
    }
    let size: u32 = arg("--size", "256").parse()?;
    let height: u32 = arg("--height", &size.to_string()).parse()?;
    let stream_query = arg("--stream", "");
    let ack = std::env::args().any(|a| a == "--ack");
    // Field-of-view updates keep the camera looking into the box (the
    // default moves it, which shows mostly dark walls: small frames).
    let fov_updates = std::env::args().any(|a| a == "--fov-updates");
    let updates: usize = arg("--updates", "100").parse()?;
    let backend_arg = arg("--backend", "cpu");
    let backend = match backend_arg.as_str() {
        "opencl" => BackendChoice::OpenCl { device: None },
        "auto" => BackendChoice::Auto,
        _ => BackendChoice::Cpu,
    };
    let url = arg("--url", "");
    let (running, base) = if url.is_empty() {
        let running = start(ServeConfig {
            addr: "127.0.0.1:0".parse()?,
            backend,
            ..ServeConfig::default()
        })
        .await
        .map_err(anyhow::Error::msg)?;
        let base = format!("http://{}", running.addr);
        (Some(running), base)
    } else {
        (None, url.trim_end_matches('/').to_owned())
    };
    let client = reqwest::Client::new();
    let mut create = json!({"scene": "cornell-glass", "width": size, "height": height});
    if running.is_none() && std::env::args().any(|a| a == "--backend") {
        // Another server renders on its default backend unless asked.
        create["backend"] = json!(backend_arg);
    }
    let created: Value = client
        .post(format!("{base}/api/sessions"))
        .json(&create)
        .send()
        .await?
        .error_for_status()?
        .json()
        .await?;
    let id = created["id"].as_str().unwrap_or_default().to_owned();
    println!(
        "session {id} on {} ({}) at {base}",
        created["backend"], created["device"]
    );
    let query = if stream_query.is_empty() {
        String::new()
    } else {
        format!("?{stream_query}")
    };
    // Without Nagle, as browsers open WebSockets: a small acknowledgement
    // held back until the server's TCP acknowledges the one before it can
    // wait for a delayed ACK (40 ms on Linux).
    let (mut ws, _) = tokio_tungstenite::connect_async_with_config(
        format!(
            "{}/api/sessions/{id}/ws{query}",
            base.replacen("http://", "ws://", 1)
        ),
        None,
        true,
    )
    .await?;

    // Warm up: a few frames.
    let mut seen = 0;
    let mut last_stats = Value::Null;
    while seen < 5 {
        match ws.next().await {
            Some(Ok(Message::Text(t))) => {
                let v: Value = serde_json::from_str(t.as_str())?;
                if ack && v["type"] == "stats" {
                    ws.send(Message::Text(json!({"ack": v["frame"]}).to_string().into()))
                        .await?;
                }
                seen += 1;
            }
            Some(Ok(_)) => {}
            _ => anyhow::bail!("stream ended"),
        }
    }
    let mut latencies = Vec::new();
    let mut previews = 0;
    for i in 0..updates {
        let z = 250.0 + (i % 2) as f64 * 20.0;
        let update = match fov_updates {
            true => json!({"camera": {"vfov_deg": 40.0 + (i % 2) as f64}}),
            false => json!({"camera": {"position": [50, 52, z]}}),
        };
        let sent = Instant::now();
        ws.send(Message::Text(update.to_string().into())).await?;
        let target = i as u64 + 1; // generation after this update
        loop {
            match tokio::time::timeout(Duration::from_secs(30), ws.next()).await {
                Ok(Some(Ok(Message::Text(t)))) => {
                    let v: Value = serde_json::from_str(t.as_str())?;
                    if ack && v["type"] == "stats" {
                        ws.send(Message::Text(json!({"ack": v["frame"]}).to_string().into()))
                            .await?;
                    }
                    // The first image of the new view: a whole sample, or
                    // a reduced-resolution preview of it.
                    let preview = v["preview"].as_u64().is_some();
                    if v["type"] == "stats"
                        && v["generation"].as_u64() >= Some(target)
                        && (v["spp"].as_u64() > Some(0) || preview)
                    {
                        latencies.push(sent.elapsed().as_secs_f64() * 1e3);
                        previews += usize::from(preview);
                        break;
                    }
                }
                Ok(Some(Ok(_))) => {}
                _ => anyhow::bail!("stream ended"),
            }
        }
    }
    latencies.sort_by(f64::total_cmp);
    println!(
        "update -> first frame at {size}x{height}: p50 {:.1} ms, p95 {:.1} ms over {updates} updates ({previews} of them previews)",
        percentile(&latencies, 0.5),
        percentile(&latencies, 0.95)
    );

    // Frames delivered per second to one reading client, steady state.
    let t0 = Instant::now();
    let mut frames = 0;
    let mut bytes = 0usize;
    while t0.elapsed() < Duration::from_secs(3) {
        match tokio::time::timeout(Duration::from_secs(3), ws.next()).await {
            Ok(Some(Ok(Message::Binary(b)))) => {
                frames += 1;
                bytes += b.len();
            }
            Ok(Some(Ok(Message::Text(t)))) => {
                let v: Value = serde_json::from_str(t.as_str())?;
                if v["type"] == "stats" {
                    if ack {
                        ws.send(Message::Text(json!({"ack": v["frame"]}).to_string().into()))
                            .await?;
                    }
                    last_stats = v;
                }
            }
            _ => {}
        }
    }
    if std::env::var_os("LATENCY_STATS").is_some() {
        println!("last stats: {last_stats}");
    }
    println!(
        "frames delivered: {:.1} per second, {:.0} KB per frame; stream stats: format {}, link {} Mbit/s, delivery {} ms",
        frames as f64 / t0.elapsed().as_secs_f64(),
        bytes as f64 / frames.max(1) as f64 / 1e3,
        last_stats["format"],
        last_stats["link_mbps"].as_f64().map_or("-".into(), |m| format!("{m:.1}")),
        last_stats["delivery_ms"].as_f64().map_or("-".into(), |m| format!("{m:.0}")),
    );

    // PNG encode time of one frame of this size (fast compression).
    let pixels: Vec<[f32; 3]> = (0..size * height)
        .map(|i| [(i % 7) as f32 / 7.0, 0.5, 0.25])
        .collect();
    let t = Instant::now();
    let n = 20;
    for _ in 0..n {
        std::hint::black_box(encode_png(size, height, &pixels, &Tonemap::default())?);
    }
    println!(
        "PNG encode at {size}x{height}: {:.2} ms per frame",
        t.elapsed().as_secs_f64() * 1e3 / f64::from(n)
    );
    client
        .delete(format!("{base}/api/sessions/{id}"))
        .send()
        .await?;
    if let Some(running) = running {
        running.shutdown().await?;
    }
    Ok(())
}
