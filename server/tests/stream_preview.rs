//! Where one sample of the image is slow (1600x1200 on one render thread,
//! as the server here is told: about 0.8 s on this 2-core machine, and far
//! over a 30 ms pass on any CPU), the first frame after a change is a preview: the view rendered
//! at 1/k of the resolution, each of its pixels covering k x k of the frame,
//! exactly what a render of that smaller image gives. While the first sample
//! is rendered in slices, the frames a watching client gets show the rows
//! done and the preview below them; then whole samples, no preview.

mod http;

use futures_util::SinkExt;
use http::{config, create, next_frame, server, ws_connect_with as connect};
use pathstream::render::backend::CpuBackend;
use pathstream::render::scene::{builtin, CameraEdit};
use pathstream::render::tonemap::Tonemap;
use pathstream::render::{Backend, Film, Quality, RenderJob};
use pathstream::service::ServeConfig;
use serde_json::json;
use tokio_tungstenite::tungstenite::Message;

const W: u32 = 1600;
const H: u32 = 1200;

fn decode(png: &[u8]) -> image::RgbImage {
    image::load_from_memory(png).expect("decodes").to_rgb8()
}

/// The tone-mapped one-sample render of the changed view at `w` x `h`.
fn small_render(w: u32, h: u32) -> Vec<[u8; 3]> {
    let scene = builtin("cornell-glass").expect("scene");
    let edit = CameraEdit {
        vfov_deg: Some(30.0),
        ..CameraEdit::default()
    };
    let scene = scene.edit_camera(&edit).expect("edit");
    let job = RenderJob::new(&scene, w, h, &Quality::default());
    let mut film = Film::new(w, h);
    Backend::Cpu(CpuBackend::default())
        .render(&job, &mut film, 1)
        .expect("render");
    let t = Tonemap::default();
    film.mean().into_iter().map(|p| t.apply(p)).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn after_a_change_a_slow_image_shows_a_preview_then_fills_in() {
    // One render thread: one sample of 1.9 Mpixel takes far longer than a
    // 30 ms pass on any CPU, so previews and slices are certain.
    let (running, base) = server(ServeConfig {
        render_threads: Some(1),
        ..config()
    })
    .await;
    let s = create(
        &base,
        json!({"scene": "cornell-glass", "width": W, "height": H, "backend": "cpu"}),
    )
    .await;
    assert_eq!(s["quality"]["seed"], 0);
    let id = s["id"].as_str().expect("id").to_owned();
    let mut ws = connect(&base, &id, "").await;
    // A frame or two first: the session has measured what a sample costs.
    for _ in 0..2 {
        next_frame(&mut ws).await;
    }
    let change = json!({"camera": {"vfov_deg": 30.0}});
    ws.send(Message::Text(change.to_string().into()))
        .await
        .expect("send");
    let (png, stats) = loop {
        let (png, stats) = next_frame(&mut ws).await;
        if stats["generation"] == 1 {
            break (png, stats);
        }
    };
    // The first frame of the change: a preview, before any sample.
    let k = stats["preview"].as_u64().expect("a preview first") as u32;
    assert!([2, 4, 8, 16].contains(&k), "{stats}");
    assert_eq!(stats["spp"], 0, "{stats}");
    let (pw, ph) = (W.div_ceil(k), H.div_ceil(k));
    let small = small_render(pw, ph);
    let preview = decode(&png);
    assert_eq!(
        preview.dimensions(),
        (W, H),
        "frames keep the session's size"
    );
    for (x, y, p) in preview.enumerate_pixels() {
        let want = small[((y / k) * pw + x / k) as usize];
        assert_eq!(p.0, want, "pixel ({x}, {y}) of a 1/{k} preview");
    }
    // Then frames of the first sample in progress, until a whole sample.
    let mut partial = 0;
    let whole = loop {
        let (png, stats) = next_frame(&mut ws).await;
        assert_eq!(stats["generation"], 1, "{stats}");
        if stats["spp"].as_u64() >= Some(1) {
            break stats;
        }
        assert_eq!(stats["preview"], k, "{stats}");
        let img = decode(&png);
        // The image's last pixels have no sample yet: still the preview's
        // (a slice may end inside the last row, not at its end, else the
        // sample would be whole).
        let last = |x: u32| small[((ph - 1) * pw + x / k) as usize];
        assert_eq!(img.get_pixel(W - 1, H - 1).0, last(W - 1), "the last pixel");
        let rendered = (0..W)
            .rev()
            .find(|&x| img.get_pixel(x, H - 1).0 != last(x))
            .map_or(0, |x| x + 1);
        for x in rendered..W {
            assert_eq!(img.get_pixel(x, H - 1).0, last(x), "last row, x = {x}");
        }
        // The rows above have: not the preview's blocks.
        let differs = img
            .enumerate_pixels()
            .any(|(x, y, p)| p.0 != small[((y / k) * pw + x / k) as usize]);
        assert!(differs, "a partial frame shows rendered rows: {stats}");
        partial += 1;
    };
    assert!(
        partial >= 1,
        "no frame between the preview and the first sample"
    );
    assert_eq!(whole["preview"], json!(null), "{whole}");
    eprintln!("1/{k} preview, then {partial} frames of the first sample in progress");
    running.shutdown().await.expect("shutdown");
}
