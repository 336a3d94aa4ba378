//! Adaptive sampling through the service: the quality field, the spread of
//! samples in status and WebSocket stats, the samples map, and a session
//! that halts when every tile reaches its share of the target error.

mod http;

use http::{config, create, get, halted, patch, read_frames, server, ws_connect};
use pathstream::render::adaptive::TILE_SIZE;
use serde_json::{json, Value};
use std::time::{Duration, Instant};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_adaptive_session_spreads_its_samples_and_says_where() {
    let (_server, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": 44, "height": 28,
               "quality": {"adaptive": true, "spp": 64, "seed": 3}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    let done = halted(&base, &id, None).await;
    assert_eq!(done["state"], "halted", "{done}");
    assert_eq!(done["quality"]["adaptive"], true);
    assert_eq!(done["spp"], 64, "the mean: a uniform render's budget");
    let spread = &done["spp_spread"];
    let (min, median, max) = (
        spread["min"].as_u64().expect("min"),
        spread["median"].as_u64().expect("median"),
        spread["max"].as_u64().expect("max"),
    );
    assert!(
        min >= 16 && min <= median && median <= max && max > 2 * min,
        "{spread}"
    );
    let tile = done["tile_size"].as_u64().expect("tile_size") as u32;
    assert_eq!(tile, TILE_SIZE);
    let (cols, rows) = (44u32.div_ceil(tile), 28u32.div_ceil(tile));
    assert_eq!(done["tiles"], cols * rows, "44x28 in {tile}x{tile} tiles");

    // The map: one pixel per tile, more than one colour.
    let r = get(format!("{base}/api/sessions/{id}/samples.png")).await;
    assert_eq!(r.status(), 200);
    assert_eq!(r.headers()["content-type"], "image/png");
    let map = image::load_from_memory(&r.bytes().await.expect("body")).expect("png");
    assert_eq!((map.width(), map.height()), (cols, rows));
    let map = map.to_rgba8();
    assert!(map.pixels().any(|p| p != map.get_pixel(0, 0)), "one colour");

    // Off again: the film restarts uniform, the spread collapses.
    let r = patch(&base, &id, "quality", json!({"adaptive": false})).await;
    assert_eq!(r.status(), 200);
    let uniform = halted(&base, &id, None).await;
    assert_eq!(uniform["quality"]["adaptive"], false);
    assert_eq!(
        uniform["spp_spread"],
        json!({"min": 64, "median": 64, "max": 64})
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_target_error_halts_when_the_tiles_are_done_and_the_stream_says_so() {
    let (_server, base) = server(config()).await;
    let s = create(
        &base,
        json!({"scene": "cornell", "width": 32, "height": 32,
               "quality": {"preset": "final", "target_error": 0.05, "clamp": 4}}),
    )
    .await;
    let id = s["id"].as_str().expect("id").to_owned();
    assert_eq!(
        s["quality"]["adaptive"], true,
        "the final preset samples adaptively"
    );
    let mut ws = ws_connect(&base, &id).await;
    let done = halted(&base, &id, None).await;
    assert_eq!(done["state"], "halted", "{done}");
    let estimate = done["error_estimate"].as_f64().expect("estimate");
    assert!(estimate <= 0.05, "{done}");
    // The target is its only halt (so the target halted it), and done
    // tiles stopped taking samples while others went on.
    assert_eq!(
        (&done["quality"]["spp"], &done["quality"]["time_ms"]),
        (&Value::Null, &Value::Null),
        "{done}"
    );
    let (min, max) = (
        done["spp_spread"]["min"].as_u64().expect("min"),
        done["spp_spread"]["max"].as_u64().expect("max"),
    );
    let (tiles_done, tiles) = (
        done["tiles_done"].as_u64().expect("tiles_done"),
        done["tiles"].as_u64().expect("tiles"),
    );
    assert!(
        min < max && tiles_done > 0 && tiles_done <= tiles,
        "done tiles froze while others went on: {done}"
    );
    let (frames, stats) = read_frames(&mut ws, Instant::now() + Duration::from_secs(2)).await;
    assert!(frames >= 1);
    assert_eq!(stats["type"], "stats", "{stats}");
    assert_eq!(stats["spp_spread"], done["spp_spread"]);
    assert_eq!(stats["tiles_done"], done["tiles_done"]);
    assert_eq!(stats["state"], "halted", "the stream says so: {stats}");
    // A preset without adaptive sampling turns it off.
    let r = patch(&base, &id, "quality", json!({"preset": "interactive"})).await;
    let v: Value = r.json().await.expect("json");
    assert_eq!(v["quality"]["adaptive"], false, "{v}");
}
