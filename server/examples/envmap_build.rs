//! What an environment map costs before the first sample: reading the file
//! and building its sampling tables, for a 4096 x 2048 map.
//!
//! ```text
//! cargo run --release --example envmap_build -- MAP.hdr|MAP.exr [--repeat 5]
//! ```
//!
//! The map is scaled up (nearest texel) to 4096 x 2048 and written as
//! Radiance `.hdr` and as OpenEXR (float, as the `image` crate writes it)
//! into a temporary folder; each is then read and its tables built
//! `--repeat` times. Prints the median, min and max of each step.

use image::{ImageEncoder, Rgb32FImage};
use pathstream::render::envmap::EnvMap;
use std::time::Instant;

const W: u32 = 4096;
const H: u32 = 2048;

fn stats(mut ms: Vec<f64>) -> String {
    ms.sort_by(f64::total_cmp);
    format!(
        "median {:.0} ms (min {:.0}, max {:.0}, {} runs)",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1],
        ms.len()
    )
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let source = args
        .first()
        .ok_or("usage: envmap_build MAP.hdr|MAP.exr [--repeat N]")?;
    let repeat: usize = match args.iter().position(|a| a == "--repeat") {
        Some(i) => args
            .get(i + 1)
            .and_then(|n| n.parse().ok())
            .ok_or("--repeat N")?,
        None => 5,
    };
    let bytes = std::fs::read(source).map_err(|e| format!("{source}: {e}"))?;
    let small = pathstream::model::hdr::read_hdr(&bytes, source)?;
    let big = Rgb32FImage::from_fn(W, H, |x, y| {
        let (sx, sy) = (x * small.width / W, y * small.height / H);
        image::Rgb(small.texels[(sy * small.width + sx) as usize])
    });
    let dir = std::env::temp_dir().join(format!("envmap-build-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let hdr = dir.join("map.hdr");
    let exr = dir.join("map.exr");
    {
        let f = std::fs::File::create(&hdr).map_err(|e| e.to_string())?;
        let pixels: Vec<image::Rgb<f32>> = big.pixels().copied().collect();
        image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(f))
            .encode(&pixels, W as usize, H as usize)
            .map_err(|e| e.to_string())?;
        let f = std::fs::File::create(&exr).map_err(|e| e.to_string())?;
        image::codecs::openexr::OpenExrEncoder::new(std::io::BufWriter::new(f))
            .write_image(
                bytemuck::cast_slice(big.as_raw()),
                W,
                H,
                image::ExtendedColorType::Rgb32F,
            )
            .map_err(|e| e.to_string())?;
    }
    println!(
        "{W}x{H} map from {source}; {} threads available",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    for path in [&hdr, &exr] {
        let file = std::fs::read(path).map_err(|e| e.to_string())?;
        let (mut read, mut build) = (Vec::new(), Vec::new());
        for _ in 0..repeat {
            let t = Instant::now();
            let img = pathstream::model::hdr::read_hdr(&file, "map")?;
            read.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let map = EnvMap::new("map", img.width, img.height, img.texels);
            build.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(map);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy())
            .unwrap_or_default();
        println!(
            "{name} ({:.1} MB): read {}; tables {}",
            file.len() as f64 / 1e6,
            stats(read),
            stats(build)
        );
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(())
}
