//! Bytes and encode time (tone mapping included; the best of three, one
//! thread) of one stream frame as PNG, JPEG and WebP:
//! `cargo run --release --example encode_cost -- [scene] [width] [height] [spp]`.
use pathstream::render::output::{encode_jpeg, encode_png, encode_webp};
use pathstream::render::tonemap::Tonemap;
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob};
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_owned());
    let scene = pathstream::resolve::load_scene(&arg(1, "cornell-glass")).expect("scene");
    let (w, h): (u32, u32) = (
        arg(2, "1920").parse().expect("width"),
        arg(3, "1080").parse().expect("height"),
    );
    let spp: u64 = arg(4, "4").parse().expect("spp");
    let job = RenderJob::new(&scene, w, h, &Quality::default());
    let mut film = Film::new(w, h);
    Backend::choose(BackendChoice::Cpu)
        .expect("cpu")
        .render(&job, &mut film, spp)
        .expect("render");
    let pixels = film.mean();
    let time = |f: &dyn Fn() -> Vec<u8>| {
        let mut best = f64::INFINITY;
        let mut len = 0;
        for _ in 0..3 {
            let t = Instant::now();
            len = f().len();
            best = best.min(t.elapsed().as_secs_f64());
        }
        (len, best)
    };
    let t = Tonemap::default();
    let (png, png_s) = time(&|| encode_png(w, h, &pixels, &t).expect("png"));
    println!(
        "{w}x{h} at {spp} spp: PNG {:.2} MB in {:.0} ms",
        png as f64 / 1e6,
        png_s * 1e3
    );
    for q in [95u8, 85, 70] {
        let (jpeg, s) = time(&|| encode_jpeg(w, h, &pixels, &t, q).expect("jpeg"));
        println!(
            "JPEG q{q}: {:.2} MB in {:.0} ms ({:.1}x smaller)",
            jpeg as f64 / 1e6,
            s * 1e3,
            png as f64 / jpeg as f64
        );
        let (webp, s) = time(&|| encode_webp(w, h, &pixels, &t, q).expect("webp"));
        println!(
            "WebP q{q}: {:.2} MB in {:.0} ms ({:.1}x smaller)",
            webp as f64 / 1e6,
            s * 1e3,
            png as f64 / webp as f64
        );
    }
}
