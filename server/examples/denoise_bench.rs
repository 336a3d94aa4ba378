//! What denoising costs and buys: the feature buffers' share of the paths'
//! time on each backend, Open Image Denoise's time per frame at
//! 512x512 and 1920x1080 with the fast filter (streamed frames) and the
//! high-quality one (the last frame), and the error as displayed of the raw
//! and the denoised image against samples per pixel, with the spp at which
//! the raw image reaches what the denoised one shows at 16 spp.
//!
//! ```text
//! PATHSTREAM_OIDN=target/oidn/lib \
//!   cargo run --release --example denoise_bench -- [--repeat 5] [--size 128] \
//!   [--reference-spp 8192] [--plot docs/bench/denoise.png] [--cost-only]
//! ```
//!
//! `scripts/test.sh` puts the library in target/oidn/lib. Renders on the
//! CPU backend; prints medians and the spread of `--repeat` runs.

use pathstream::bench::plot;
use pathstream::render::denoise::{self, FilterQuality};
use pathstream::render::quality::Denoise;
use pathstream::render::tonemap::displayed_error;
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob, Scene};
use std::path::PathBuf;
use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], name: &str, default: T) -> Result<T, String> {
    match args.iter().position(|a| a == name) {
        Some(i) => (args.get(i + 1).and_then(|v| v.parse().ok())).ok_or(format!("{name}: a value")),
        None => Ok(default),
    }
}

fn render(scene: &Scene, (w, h): (u32, u32), spp: u64, seed: u64) -> Result<Film, String> {
    let mut cpu = Backend::choose(BackendChoice::Cpu).map_err(|e| e.to_string())?;
    render_on(&mut cpu, scene, (w, h), spp, (seed, Denoise::Final))
}

fn render_on(
    backend: &mut Backend,
    scene: &Scene,
    (w, h): (u32, u32),
    spp: u64,
    (seed, denoise): (u64, Denoise),
) -> Result<Film, String> {
    let q = Quality {
        denoise,
        seed,
        ..Quality::default()
    };
    let job = RenderJob::new(scene, w, h, &q);
    let mut film = Film::new(w, h);
    backend.prepare(&job).map_err(|e| e.to_string())?;
    backend
        .render(&job, &mut film, spp)
        .map_err(|e| e.to_string())?;
    Ok(film)
}

/// Paths per second with and without the feature buffers, on each backend.
fn feature_cost(scene: &Scene, repeat: usize) -> Result<(), String> {
    let mut backends = vec![(
        "cpu",
        Backend::choose(BackendChoice::Cpu).map_err(|e| e.to_string())?,
    )];
    if let Ok(b) = Backend::choose(BackendChoice::OpenCl { device: None }) {
        backends.push(("opencl", b));
    }
    let (size, spp) = ((256, 256), 16);
    for (name, backend) in &mut backends {
        let mut rates = [Vec::new(), Vec::new()];
        // Warm (programs built, pages touched), then alternate.
        for denoise in [Denoise::Off, Denoise::Final] {
            render_on(backend, scene, size, 1, (0, denoise))?;
        }
        for _ in 0..repeat {
            for (k, denoise) in [Denoise::Off, Denoise::Final].into_iter().enumerate() {
                let t = Instant::now();
                render_on(backend, scene, size, spp, (0, denoise))?;
                rates[k].push(
                    f64::from(size.0 * size.1) * spp as f64 / t.elapsed().as_secs_f64() / 1e6,
                );
            }
        }
        let median = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            (v[v.len() / 2], v[0], v[v.len() - 1])
        };
        let (off, on) = (median(&mut rates[0]), median(&mut rates[1]));
        println!(
            "{name}: {:.2} M paths/s without features ({:.2}-{:.2}), {:.2} with ({:.2}-{:.2}): {:+.1}%",
            off.0, off.1, off.2, on.0, on.1, on.2, 100.0 * (on.0 / off.0 - 1.0)
        );
    }
    Ok(())
}

fn spread(mut ms: Vec<f64>) -> String {
    ms.sort_by(f64::total_cmp);
    format!(
        "median {:.0} ms (min {:.0}, max {:.0})",
        ms[ms.len() / 2],
        ms[0],
        ms[ms.len() - 1]
    )
}

/// Denoise time per frame at each size and filter.
fn timings(scene: &Scene, repeat: usize) -> Result<(), String> {
    for (w, h) in [(512u32, 512u32), (1920, 1080)] {
        let film = render(scene, (w, h), 1, 0)?;
        let (raw, features) = (film.mean(), film.feature_means());
        for quality in [FilterQuality::Fast, FilterQuality::High] {
            let mut ms = Vec::new();
            let mut first = 0.0;
            for k in 0..=repeat {
                let t = Instant::now();
                denoise::denoise(w, h, &raw, features.as_ref(), quality)
                    .map_err(|e| e.to_string())?;
                let took = t.elapsed().as_secs_f64() * 1e3;
                match k {
                    0 => first = took,
                    _ => ms.push(took),
                }
            }
            let fps = 1e3 / ms[ms.len() / 2];
            println!(
                "{w}x{h} {quality:?}: {} (first call, with the filter's set-up: {first:.0} ms); \
                 at most {fps:.1} denoised frames/s",
                spread(ms)
            );
        }
    }
    Ok(())
}

/// A plotted line: its label and (spp, error) points.
type Line = (String, Vec<(f64, f64)>);

/// Error as displayed, raw and denoised, against spp.
fn errors(name: &str, scene: &Scene, size: u32, reference_spp: u64) -> Result<Vec<Line>, String> {
    let t = Instant::now();
    let truth = render(scene, (size, size), reference_spp, 99)?.mean();
    println!(
        "{name} {size}x{size}: reference of {reference_spp} spp in {:.0} s",
        t.elapsed().as_secs_f64()
    );
    let (mut raw_line, mut clean_line) = (Vec::new(), Vec::new());
    for spp in [1u64, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024] {
        let film = render(scene, (size, size), spp, spp)?;
        let raw = film.mean();
        let clean = denoise::denoise(
            size,
            size,
            &raw,
            film.feature_means().as_ref(),
            FilterQuality::High,
        )
        .map_err(|e| e.to_string())?;
        let (e_raw, e_clean) = (
            displayed_error(&raw, &truth),
            displayed_error(&clean, &truth),
        );
        println!(
            "  {spp:>5} spp: raw {:.2}%, denoised {:.2}% ({:.1}x)",
            100.0 * e_raw,
            100.0 * e_clean,
            e_raw / e_clean
        );
        raw_line.push((spp as f64, e_raw));
        clean_line.push((spp as f64, e_clean));
    }
    if let Some(&(_, at16)) = clean_line.iter().find(|(s, _)| *s == 16.0) {
        // Where the raw line (log-log, piecewise linear) crosses it.
        let crossing = raw_line.windows(2).find_map(|p| {
            let ((s0, e0), (s1, e1)) = (p[0], p[1]);
            (e0 >= at16 && e1 <= at16).then(|| {
                let f = (e0.ln() - at16.ln()) / (e0.ln() - e1.ln()).max(1e-12);
                (s0.ln() + f * (s1.ln() - s0.ln())).exp()
            })
        });
        match crossing {
            Some(s) => println!(
                "  the raw image reaches the denoised 16-spp error ({:.2}%) at about {s:.0} spp",
                100.0 * at16
            ),
            None => println!(
                "  the raw image does not reach the denoised 16-spp error ({:.2}%) by 1024 spp",
                100.0 * at16
            ),
        }
    }
    Ok(vec![
        (format!("{name} raw"), raw_line),
        (format!("{name} denoised"), clean_line),
    ])
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repeat: usize = arg(&args, "--repeat", 5)?;
    let size: u32 = arg(&args, "--size", 128)?;
    let reference_spp: u64 = arg(&args, "--reference-spp", 8192)?;
    let plot_path: PathBuf = arg(&args, "--plot", PathBuf::from("target/denoise.png"))?;
    denoise::available().map_err(|e| e.to_string())?;
    let info = denoise::status();
    let device = info
        .device
        .and_then(|i| info.devices.get(i))
        .map_or("?".into(), |d| format!("{} ({})", d.name, d.kind));
    println!(
        "Open Image Denoise {} on {device}; renders on {} rayon threads; {repeat} runs each",
        info.version.unwrap_or_default(),
        rayon::current_num_threads()
    );
    let load = |name: &str| pathstream::resolve::load_scene(name).map_err(|e| e.to_string());
    feature_cost(&load("cornell-glass")?, repeat)?;
    if args.iter().any(|a| a == "--cost-only") {
        return Ok(());
    }
    timings(&load("cornell-glass")?, repeat)?;
    let mut lines = errors(
        "cornell-glass",
        &load("cornell-glass")?,
        size,
        reference_spp,
    )?;
    lines.extend(errors("cornell", &load("cornell")?, size, reference_spp)?);
    let title =
        format!("Error as displayed against samples per pixel, {size}x{size}, raw and denoised");
    plot::error_vs_spp(
        &plot_path,
        &title,
        "relative RMS error (sRGB) vs reference",
        &lines,
    )
    .map_err(|e| e.to_string())?;
    println!("plot: {}", plot_path.display());
    Ok(())
}
