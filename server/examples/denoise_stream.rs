//! What a denoised stream leaves: a 1920x1080 `cornell-glass` session
//! streamed as JPEG (acknowledged, as the page does) for `--seconds`, with
//! `quality.denoise` off and `stream`, at the film's width and at
//! `--width`: frames delivered per second, how many were denoised, and the
//! render rate (camera paths per second) the session kept.
//!
//! ```text
//! PATHSTREAM_OIDN=target/oidn/lib \
//!   cargo run --release --example denoise_stream -- [--seconds 20] [--width 960] [--repeat 3]
//! ```

use futures_util::{SinkExt, StreamExt};
use pathstream::api::start;
use pathstream::render::BackendChoice;
use pathstream::service::ServeConfig;
use serde_json::{json, Value};
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

fn arg(name: &str, default: &str) -> String {
    let args: Vec<String> = std::env::args().collect();
    (args.iter().position(|a| a == name))
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| default.to_owned())
}

/// One run: (frames per second, frames denoised, frames, paths per second).
async fn run(
    base: &str,
    denoise: &str,
    width: Option<u32>,
    seconds: f64,
) -> anyhow::Result<(f64, u64, u64, f64)> {
    let http = reqwest::Client::new();
    let body = json!({"scene": "cornell-glass", "width": 1920, "height": 1080, "quality": {"denoise": denoise}});
    let s: Value = http
        .post(format!("{base}/api/sessions"))
        .json(&body)
        .send()
        .await?
        .json()
        .await?;
    let id = s["id"].as_str().unwrap_or_default().to_owned();
    let query = match width {
        Some(w) => format!("?format=jpeg&width={w}"),
        None => "?format=jpeg".to_owned(),
    };
    let url = format!(
        "{}/api/sessions/{id}/ws{query}",
        base.replace("http://", "ws://")
    );
    let (mut ws, _) = tokio_tungstenite::connect_async(url).await?;
    let (mut frames, mut denoised, mut first) = (0u64, 0u64, None);
    let end = Instant::now() + Duration::from_secs_f64(seconds);
    while let Ok(Some(msg)) = tokio::time::timeout_at(end.into(), ws.next()).await {
        if let Message::Text(t) = msg? {
            let stats: Value = serde_json::from_str(t.as_str())?;
            if stats["type"] != "stats" {
                continue;
            }
            frames += 1;
            denoised += u64::from(stats["denoised"] == true);
            first.get_or_insert_with(Instant::now);
            ws.send(Message::text(json!({"ack": stats["frame"]}).to_string()))
                .await?;
        }
    }
    let status: Value = http
        .get(format!("{base}/api/sessions/{id}"))
        .send()
        .await?
        .json()
        .await?;
    http.delete(format!("{base}/api/sessions/{id}"))
        .send()
        .await?;
    let span = first.map_or(0.0, |t| t.elapsed().as_secs_f64());
    let fps = if span > 0.0 {
        (frames.saturating_sub(1)) as f64 / span
    } else {
        0.0
    };
    Ok((
        fps,
        denoised,
        frames,
        status["samples_per_sec"].as_f64().unwrap_or(0.0),
    ))
}

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    let seconds: f64 = arg("--seconds", "20").parse()?;
    let narrow: u32 = arg("--width", "960").parse()?;
    let repeat: usize = arg("--repeat", "3").parse()?;
    pathstream::render::denoise::available()?;
    let running = start(ServeConfig {
        addr: "127.0.0.1:0".parse()?,
        backend: BackendChoice::Cpu,
        ..ServeConfig::default()
    })
    .await
    .map_err(anyhow::Error::msg)?;
    let base = format!("http://{}", running.addr);
    println!(
        "1920x1080 cornell-glass, JPEG, {seconds} s per run, {repeat} runs, rayon on {} threads",
        rayon::current_num_threads()
    );
    for denoise in ["off", "stream"] {
        for width in [None, Some(narrow)] {
            let mut rows = Vec::new();
            for _ in 0..repeat {
                rows.push(run(&base, denoise, width, seconds).await?);
            }
            rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            let m = rows[rows.len() / 2];
            let paths: Vec<f64> = rows.iter().map(|r| r.3 / 1e6).collect();
            println!(
                "denoise {denoise:<6} width {:>4}: {:.2} frames/s (runs {:.2}-{:.2}), {} of {} denoised; {:.2} M paths/s (runs {:.2}-{:.2})",
                width.map_or("1920".into(), |w| w.to_string()),
                m.0,
                rows[0].0,
                rows[rows.len() - 1].0,
                m.1,
                m.2,
                m.3 / 1e6,
                paths.iter().copied().fold(f64::INFINITY, f64::min),
                paths.iter().copied().fold(0.0, f64::max),
            );
        }
    }
    running.shutdown().await?;
    Ok(())
}
