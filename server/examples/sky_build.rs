//! What a computed sky costs before the first sample: its transmittance
//! table, its elevation x azimuth table and the 512 x 256 map filled from
//! it, then the map's sampling tables, for suns at several elevations.
//!
//! ```text
//! cargo run --release --example sky_build -- [--repeat 5]
//! ```
//!
//! Prints the median, min and max of each step per elevation.

use pathstream::render::envmap::sky_model::{sun_direction, Atmosphere, SkyModel};
use pathstream::render::envmap::EnvMap;
use pathstream::render::scene::sky::{SKY_MAP_HEIGHT, SKY_MAP_WIDTH};
use std::time::Instant;

fn stats(mut ms: Vec<f64>) -> String {
    ms.sort_by(f64::total_cmp);
    format!(
        "median {:.0} ms (min {:.0}, max {:.0})",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1]
    )
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repeat: usize = match args.iter().position(|a| a == "--repeat") {
        Some(i) => args
            .get(i + 1)
            .and_then(|n| n.parse().ok())
            .ok_or("--repeat N")?,
        None => 5,
    };
    println!(
        "{} threads, {SKY_MAP_WIDTH}x{SKY_MAP_HEIGHT} sky map, {repeat} runs",
        rayon::current_num_threads()
    );
    for elevation in [2.0f64, 20.0, 60.0] {
        let (mut model_ms, mut image_ms, mut tables_ms) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..repeat {
            let t = Instant::now();
            let sky = SkyModel::new(
                &Atmosphere::default(),
                sun_direction(elevation.to_radians(), 2.0),
            );
            model_ms.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let texels = sky.image(SKY_MAP_WIDTH, SKY_MAP_HEIGHT);
            image_ms.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let map = EnvMap::new("sky", SKY_MAP_WIDTH, SKY_MAP_HEIGHT, texels);
            tables_ms.push(t.elapsed().as_secs_f64() * 1e3);
            std::hint::black_box(map);
        }
        println!(
            "sun at {elevation:>4} degrees: transmittance table {}; sky {}; sampling tables {}",
            stats(model_ms),
            stats(image_ms),
            stats(tables_ms)
        );
    }
    Ok(())
}
