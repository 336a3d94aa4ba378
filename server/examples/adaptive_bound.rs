//! What an allocation of samples can gain over uniform sampling, measured
//! without timing noise (docs/RENDERER.md, "What an allocation can gain").
//! `cargo run --release --example adaptive_bound -- [scene] [width] [height] [runs] [spp per run] [pilot spp] [seeds]`
//!
//! The truth: `runs` independent uniform renders of `spp` samples (the
//! bench's unbiased setting); a pixel's variance per sample, v_p, from the
//! spread of their means. Samples in proportion to a_p give the image the
//! error sum v_p / n_p; for the same total, uniform's error over the
//! allocation's is gain(a) = sum(v) P / (sum(v / a) sum(a)).
//!
//! Printed per tile size: the oracle (a = sqrt of the tile's true mean
//! variance, the best any allocation by tiles can do; "halves" takes the
//! rates from half of the runs and judges them on the other half, so that
//! the runs' own noise cannot flatter it), then allocations steered by a
//! pilot render's own error estimate (one more render of `pilot spp`,
//! another seed, its even/odd halves as the film uses them), from the tile
//! alone or the tile grown by 1 or 2 pixels. Last, the renderer's adaptive
//! sampling against uniform at `pilot spp` on average (`seeds` seeds, 4
//! unless given; squared errors against the runs' mean, its own error taken
//! out).
use pathstream::bench::settings;
use pathstream::render::film::relative_rms_error;
use pathstream::render::progressive::{self, halted, Progress};
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob};
use std::time::Duration;

/// Per-pixel variance of one sample, summed over channels, from `films`
/// (independent renders of `spp` samples each).
fn true_variance(films: &[Vec<[f32; 3]>], spp: u64) -> Vec<f64> {
    let k = films.len() as f64;
    (0..films[0].len())
        .map(|p| {
            (0..3)
                .map(|c| {
                    let m = films.iter().map(|f| f64::from(f[p][c])).sum::<f64>() / k;
                    let s = films
                        .iter()
                        .map(|f| (f64::from(f[p][c]) - m).powi(2))
                        .sum::<f64>();
                    s / (k - 1.0) * spp as f64
                })
                .sum()
        })
        .collect()
}

/// Per-pixel variance of one sample as a film of `n` uniform samples
/// estimates it from its halves: (A - B)^2 n_a n_b / n.
fn estimated_variance(film: &Film) -> Vec<f64> {
    let n = film.spp();
    let (na, nb) = (n.div_ceil(2) as f64, (n / 2) as f64);
    film.pixels()
        .iter()
        .map(|p| {
            (0..3)
                .map(|c| (p.even[c] / na - p.odd[c] / nb).powi(2) * na * nb / n as f64)
                .sum()
        })
        .collect()
}

/// The rate of each `s`x`s` tile from the mean of `v` over the tile grown
/// by `m` pixels on every side (cut at the image's edges), floored at 5%.
fn rates(v: &[f64], (w, h): (usize, usize), s: usize, m: usize) -> Vec<f64> {
    let (cols, rows) = (w.div_ceil(s), h.div_ceil(s));
    let mut rate = vec![0.0f64; cols * rows];
    for ty in 0..rows {
        for tx in 0..cols {
            let (x0, y0) = ((tx * s).saturating_sub(m), (ty * s).saturating_sub(m));
            let (x1, y1) = ((tx * s + s + m).min(w), (ty * s + s + m).min(h));
            let (mut sum, mut n) = (0.0, 0.0);
            for y in y0..y1 {
                for x in x0..x1 {
                    sum += v[y * w + x];
                    n += 1.0;
                }
            }
            rate[ty * cols + tx] = (sum / n).max(0.0).sqrt();
        }
    }
    let mut a: Vec<f64> = (0..w * h)
        .map(|p| rate[(p / w / s) * cols + (p % w) / s])
        .collect();
    let mean = a.iter().sum::<f64>() / a.len() as f64;
    for r in &mut a {
        *r = r.max(0.05 * mean);
    }
    a
}

/// Uniform's error over the error of samples in proportion to `a`.
fn gain(v: &[f64], a: &[f64]) -> f64 {
    let p = v.len() as f64;
    let sv: f64 = v.iter().sum();
    let sva: f64 = v.iter().zip(a).map(|(v, a)| v / a).sum();
    sv * p / (sva * a.iter().sum::<f64>())
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_owned());
    let name = arg(1, "cornell-glass");
    let scene = pathstream::resolve::load_scene(&name).expect("scene");
    let num = |i: usize, d: &str| -> u64 { arg(i, d).parse().expect("a number") };
    let (w, h) = (num(2, "64") as u32, num(3, "64") as u32);
    let (runs, spp, pilot_spp) = (num(4, "64"), num(5, "64"), num(6, "64"));
    let seeds = num(7, "4");
    let mut backend = Backend::choose(BackendChoice::Cpu).expect("cpu");
    let mut render = |seed: u64, spp: u64| {
        let q = Quality {
            seed,
            ..settings::unbiased()
        };
        let job = RenderJob::new(&scene, w, h, &q);
        let mut film = Film::new(w, h);
        backend.render(&job, &mut film, spp).expect("render");
        film
    };
    let films: Vec<Vec<[f32; 3]>> = (0..runs).map(|k| render(1000 + k, spp).mean()).collect();
    let v = true_variance(&films, spp);
    let size = (w as usize, h as usize);
    println!("{name} {w}x{h}: {runs} runs of {spp} spp; pilot {pilot_spp} spp");
    // The oracle's rates from one half of the runs, judged on the other
    // half's variances: free of the runs' own noise flattering it.
    let half = films.len() / 2;
    let (va, vb) = (
        true_variance(&films[..half], spp),
        true_variance(&films[half..], spp),
    );
    println!("uniform's error over the allocation's, for the same samples:");
    println!("tile | oracle | oracle (halves) | pilot | pilot, tile grown by 1 pixel | by 2");
    let pilot = estimated_variance(&render(7, pilot_spp));
    for s in [16, 8, 4, 2, 1] {
        let cells: Vec<String> = (0..3)
            .map(|m| format!("{:.3}", gain(&v, &rates(&pilot, size, s, m))))
            .collect();
        println!(
            "{s:>4} | {:.3} | {:.3} | {}",
            gain(&v, &rates(&v, size, s, 0)),
            gain(&vb, &rates(&va, size, s, 0)),
            cells.join(" | ")
        );
    }
    // The renderer's own adaptive sampling against uniform at the same
    // mean spp, `seeds` seeds; the truth is the mean of the runs.
    let truth: Vec<[f32; 3]> = (0..films[0].len())
        .map(|p| std::array::from_fn(|c| films.iter().map(|f| f[p][c]).sum::<f32>() / runs as f32))
        .collect();
    let truth_err2 = v.iter().sum::<f64>()
        / (runs * spp) as f64
        / truth
            .iter()
            .flatten()
            .map(|&x| f64::from(x).powi(2))
            .sum::<f64>();
    let (mut eu, mut ea) = (0.0, 0.0);
    for seed in 1..=seeds {
        let q = Quality {
            seed,
            spp: Some(pilot_spp),
            ..settings::unbiased()
        };
        let job = RenderJob::new(&scene, w, h, &q);
        let mut film = Film::new(w, h);
        backend.render(&job, &mut film, pilot_spp).expect("render");
        eu += relative_rms_error(&film.mean(), &truth).powi(2) - truth_err2;
        let q = Quality {
            adaptive: true,
            ..q
        };
        let mut film = Film::new(w, h);
        loop {
            let traced = progressive::step(&job, &mut backend, &mut film, &q, u64::from(w * h) * 8)
                .expect("step");
            if traced == 0 || halted(&q, &Progress::of(&film, Duration::ZERO)) {
                break;
            }
        }
        ea += relative_rms_error(&film.mean(), &truth).powi(2) - truth_err2;
    }
    println!(
        "the renderer's adaptive sampling at {pilot_spp} mean spp ({seeds} seeds): uniform's error^2 / adaptive's = {:.3}",
        eu / ea
    );
}
