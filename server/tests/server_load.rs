//! Scheduling under load, measured on a real server: sessions share the
//! device fairly and a client that never reads slows nobody. One test
//! function runs the scenarios one after the other, alone in this binary,
//! so that no other test's rendering competes for the cores.

mod http;

use http::*;
use serde_json::{json, Value};
use std::time::{Duration, Instant};

async fn eight_sessions_share_the_device_fairly() {
    let (running, base) = server(config()).await;
    let mut ids = Vec::new();
    for i in 0..8 {
        let s = create(&base, json!({"scene": "cornell", "width": 32, "height": 32, "quality": {"seed": i}})).await;
        ids.push(s["id"].as_str().expect("id").to_owned());
    }
    let until = Instant::now() + Duration::from_secs(6);
    let tasks: Vec<_> = ids
        .iter()
        .map(|id| {
            let (base, id) = (base.clone(), id.clone());
            tokio::spawn(async move {
                let mut ws = ws_connect(&base, &id).await;
                read_frames(&mut ws, until).await
            })
        })
        .collect();
    // Sample rates over a window, after the first passes have sized themselves.
    tokio::time::sleep(Duration::from_secs(1)).await;
    let spp = |v: Value| v["spp"].as_u64().expect("spp");
    let mut start = Vec::new();
    for id in &ids {
        start.push(spp(status(&base, id).await));
    }
    let t0 = Instant::now();
    tokio::time::sleep(Duration::from_secs(3)).await;
    let mut rates = Vec::new();
    for (id, s0) in ids.iter().zip(&start) {
        rates.push((spp(status(&base, id).await) - s0) as f64 / t0.elapsed().as_secs_f64());
    }
    for t in tasks {
        let (frames, stats) = t.await.expect("task");
        assert!(frames > 2, "every session streams frames ({frames})");
        assert_eq!(stats["type"], "stats");
    }
    let (lo, hi) = rates.iter().fold((f64::MAX, 0.0f64), |(lo, hi), r| (lo.min(*r), hi.max(*r)));
    eprintln!("eight sessions, spp/s: {rates:.1?}");
    assert!(lo > 0.0 && hi / lo < 2.0, "rates within 2x of each other: {rates:?}");
    running.shutdown().await.expect("shutdown");
}

fn rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| s.lines().find(|l| l.starts_with("VmRSS:")).and_then(|l| l.split_whitespace().nth(1)?.parse().ok()))
        .unwrap_or(0)
}

async fn a_client_that_never_reads_does_not_slow_the_others() {
    let (running, base) = server(config()).await;
    let a = create(&base, json!({"scene": "cornell", "width": 96, "height": 96})).await["id"].as_str().expect("id").to_owned();
    let b = create(&base, json!({"scene": "cornell-glass", "width": 96, "height": 96})).await["id"].as_str().expect("id").to_owned();
    let mut wa = ws_connect(&base, &a).await;
    let mut wb = ws_connect(&base, &b).await;
    let spp = |s: &Value| s["spp"].as_u64().expect("spp");
    // Rate of session b's samples over a window, while both clients read.
    let window = |base: String, b: String| async move {
        let s0 = spp(&status(&base, &b).await);
        let t0 = Instant::now();
        tokio::time::sleep(Duration::from_secs(2)).await;
        (spp(&status(&base, &b).await) - s0) as f64 / t0.elapsed().as_secs_f64()
    };
    let reading = tokio::spawn(async move {
        let until = Instant::now() + Duration::from_secs(5);
        let (fa, fb) = tokio::join!(read_frames(&mut wa, until), read_frames(&mut wb, until));
        (fa.0, fb.0, wa, wb)
    });
    tokio::time::sleep(Duration::from_millis(300)).await;
    let without = window(base.clone(), b.clone()).await;
    let rss_before = rss_kib();
    // A third client on session a that never reads anything.
    let _stalled = ws_connect(&base, &a).await;
    tokio::time::sleep(Duration::from_millis(200)).await;
    let with = window(base.clone(), b.clone()).await;
    let (fa, fb, _wa, _wb) = reading.await.expect("task");
    eprintln!("session b: {without:.1} spp/s without the stalled client, {with:.1} with it; frames {fa} {fb}");
    assert!(fa > 0 && fb > 0);
    assert!((with / without - 1.0).abs() < 0.2, "{with} vs {without} spp/s");
    let grown = rss_kib().saturating_sub(rss_before);
    assert!(grown < 100 * 1024, "memory grew by {grown} KiB");
    running.shutdown().await.expect("shutdown");
}


#[tokio::test(flavor = "multi_thread", worker_threads = 4)]
async fn scheduling_under_load() {
    eight_sessions_share_the_device_fairly().await;
    a_client_that_never_reads_does_not_slow_the_others().await;
}
