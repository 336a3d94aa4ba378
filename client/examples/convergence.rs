//! A convergence sweep through the library: render one scene at several
//! quality settings on a running server and print the error estimate against
//! time for each.
//!
//!     cargo run --release -p pathstream -- serve &          # a server
//!     cargo run --release -p pathstream-client --example convergence -- [URL] [SCENE]

use pathstream_client::{Client, CreateSession, QualityPatch, SceneSpec};
use std::time::{Duration, Instant};

#[tokio::main]
async fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let url = args
        .next()
        .unwrap_or_else(|| "http://127.0.0.1:8080".into());
    let scene = args.next().unwrap_or_else(|| "cornell".into());
    let client = Client::new(&url)?.token(std::env::var("PATHSTREAM_TOKEN").ok());
    let settings: [(&str, QualityPatch); 4] = [
        (
            "depth 6, NEE",
            QualityPatch {
                max_depth: Some(6),
                nee: Some(true),
                ..Default::default()
            },
        ),
        (
            "depth 6, no NEE",
            QualityPatch {
                max_depth: Some(6),
                nee: Some(false),
                ..Default::default()
            },
        ),
        (
            "depth 2, NEE",
            QualityPatch {
                max_depth: Some(2),
                nee: Some(true),
                ..Default::default()
            },
        ),
        (
            "unbounded, NEE",
            QualityPatch {
                max_depth: Some(0),
                nee: Some(true),
                ..Default::default()
            },
        ),
    ];
    println!("{scene} at 128x128: error estimate after each second");
    for (name, mut quality) in settings {
        quality.time_ms = Some(Some(4000));
        let session = client
            .create_session(&CreateSession {
                scene: Some(SceneSpec::Name(scene.clone())),
                width: Some(128),
                height: Some(128),
                quality: Some(quality),
                backend: None,
            })
            .await?;
        let start = Instant::now();
        let mut line = format!("{name:>16}:");
        loop {
            tokio::time::sleep(Duration::from_secs(1)).await;
            let s = client.session(&session.id).await?;
            let err = s
                .error_estimate
                .map_or("  n/a".into(), |e| format!("{:5.2}%", e * 100.0));
            line.push_str(&format!(
                "  {:.0}s {err} ({} spp)",
                start.elapsed().as_secs_f64(),
                s.spp
            ));
            if s.halted() {
                break;
            }
        }
        println!("{line}");
        client.delete_session(&session.id).await?;
    }
    Ok(())
}
