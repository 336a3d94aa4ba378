//! The metallic-roughness BSDF's energy by roughness and angle: what a
//! single-scattering GGX lobe keeps of a white furnace (E, the start-up
//! table), against the whole BSDF (multiple-scattering lobes added) for a
//! white metal and for a white base under the dielectric coat, each the
//! mean weight of `N` samples (default 400,000) drawn as the renderer draws
//! them; then the same for rough glass (transmission 1, ior 1.5), light
//! arriving from outside and from inside: E of the single-scattering
//! dielectric (its table), and the whole lobe with the compensation;
//! and rough glass under `KHR_materials_specular` (specular 0, and a
//! tinted half-strength reflection).
//! Everything should read 1 but the single-scattering blocks.
//!
//!   cargo run --release --example ggx_energy [-- N]

use pathstream::render::ggx::{glass, sample, tables, Pbr};
use pathstream::render::math::Vec3A;
use pathstream::render::sampler::Sampler;

const ROUGHNESS: [f32; 6] = [0.05, 0.25, 0.5, 0.75, 0.9, 1.0];
const MU: [f32; 5] = [0.1, 0.3, 0.5, 0.7, 1.0];

fn albedo(p: &Pbr, mu: f32, entering: bool, n: u64) -> f32 {
    let wo = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for i in 0..n {
        let mut s = Sampler::new(1, i, 0);
        let choice = s.next_f32();
        let u = s.next_2d();
        if let Some(s) = sample(tables(), p, Vec3A::ONE, (wo, entering), choice, u) {
            sum += f64::from(s.weight.x);
        }
    }
    (sum / n as f64) as f32
}

fn main() {
    let n: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(400_000);
    let start = std::time::Instant::now();
    glass::table();
    println!(
        "Rough glass table (both parts): {:.2} s\n",
        start.elapsed().as_secs_f64()
    );
    let header = || {
        let cols: Vec<String> = MU.iter().map(|m| format!("cos {m}")).collect();
        println!("| roughness | {} |", cols.join(" | "));
        println!("| ---: |{}", " ---: |".repeat(MU.len()));
    };
    println!("Single-scattering GGX, white (E from the table):\n");
    header();
    for r in ROUGHNESS {
        let row: Vec<String> = MU
            .iter()
            .map(|&m| format!("{:.4}", tables().single_scattering(m, r)))
            .collect();
        println!("| {r} | {} |", row.join(" | "));
    }
    for (what, metallic) in [
        ("White metal", 1.0),
        ("White base under the coat (ior 1.5)", 0.0),
    ] {
        println!("\n{what}, whole BSDF ({n} samples each):\n");
        header();
        for r in ROUGHNESS {
            let p = Pbr::new(metallic, r, 1.5);
            let row: Vec<String> = MU
                .iter()
                .map(|&m| format!("{:.4}", albedo(&p, m, true, n)))
                .collect();
            println!("| {r} | {} |", row.join(" | "));
        }
    }
    for (side, entering) in [("outside", true), ("inside", false)] {
        println!("\nSingle-scattering rough glass (ior 1.5), from {side} (E from the table):\n");
        header();
        for r in ROUGHNESS {
            let row: Vec<String> = MU
                .iter()
                .map(|&m| format!("{:.4}", glass::table().albedo(m, r, 1.5, entering)))
                .collect();
            println!("| {r} | {} |", row.join(" | "));
        }
        println!("\nWhite rough glass (ior 1.5), from {side}, whole lobe ({n} samples each):\n");
        header();
        for r in ROUGHNESS {
            let p = Pbr::new(0.0, r, 1.5).transmitting(1.0);
            let row: Vec<String> = MU
                .iter()
                .map(|&m| format!("{:.4}", albedo(&p, m, entering, n)))
                .collect();
            println!("| {r} | {} |", row.join(" | "));
        }
        // KHR_materials_specular on the glass: the clear glass (specular
        // 0), and a half-strength reflection (its strongest channel, red,
        // which reflects as the untinted glass would at that strength).
        for (what, factor, color) in [
            ("specular 0", 0.0, Vec3A::ONE),
            (
                "specular 0.5, colour (1, 0.5, 0.25)",
                0.5,
                Vec3A::new(1.0, 0.5, 0.25),
            ),
        ] {
            println!("\nRough glass with {what} (ior 1.5), from {side}, whole lobe:\n");
            header();
            for r in ROUGHNESS {
                let p = Pbr::new(0.0, r, 1.5)
                    .transmitting(1.0)
                    .specular(factor, color);
                let row: Vec<String> = MU
                    .iter()
                    .map(|&m| format!("{:.4}", albedo(&p, m, entering, n)))
                    .collect();
                println!("| {r} | {} |", row.join(" | "));
            }
        }
    }
}
