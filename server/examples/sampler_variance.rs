//! How much variance each kind of scrambled Sobol point removes from the
//! integrands a path's numbers feed, against independent random numbers:
//! the measurement behind `render/sampler/sobol.rs`'s choices (2-D points
//! Owen-scrambled; 1-D points the shuffled van der Corput sequence without
//! a value scramble).
//!
//! ```sh
//! cargo run --release -p pathstream --example sampler_variance [-- --trials 20000]
//! ```
//!
//! Each estimate averages n points of one pixel's sequence (n = 1 to 256);
//! the variance over `trials` keys (pixels) of random numbers is divided by
//! the variance of each scrambled kind. Above 1: less noise than random.
//! The integrands are those a path meets: steps (Russian roulette, a lobe
//! choice), a chain of roulettes through four dimensions, an emitter pick
//! whose coin is the fraction the pick leaves, a smooth 1-D function, and
//! in 2-D a disk's edge, a smooth function and a lobe through polar
//! coordinates.

use pathstream::render::sampler::mix64;
use pathstream::render::sampler::sobol::{
    lk_hash, owen, sample_1d, sample_2d, sample_2d_x3, unit_f32, Seeds,
};

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;
const COUNTS: [u32; 8] = [1, 2, 3, 4, 8, 16, 64, 256];

fn bits(key: u64, d: u64) -> u64 {
    mix64(key.wrapping_add(d.wrapping_mul(GOLDEN)))
}

fn u(v: u32) -> f64 {
    f64::from(unit_f32(v))
}

/// A 1-D kind: point `rindex` (bit-reversed index) of dimension `d`.
type Kind1 = fn(u64, u32, u64) -> f64;
/// A 2-D kind.
type Kind2 = fn(u64, u32, u64) -> (f64, f64);

fn random_1d(key: u64, rindex: u32, d: u64) -> f64 {
    u((bits(mix64(key ^ u64::from(rindex)), d) >> 32) as u32)
}

/// What the 1-D points were before: the shuffled van der Corput point,
/// Owen-scrambled.
fn owen_1d(key: u64, rindex: u32, d: u64) -> f64 {
    let s = Seeds::from_bits(bits(key, d));
    u(owen(lk_hash(rindex, s.index), s.x))
}

fn shuffled_1d(key: u64, rindex: u32, d: u64) -> f64 {
    u(sample_1d(rindex, bits(key, d) as u32))
}

fn random_2d(key: u64, rindex: u32, d: u64) -> (f64, f64) {
    let b = bits(mix64(key ^ u64::from(rindex)), d);
    (u((b >> 32) as u32), u(b as u32))
}

fn owen_2d(key: u64, rindex: u32, d: u64) -> (f64, f64) {
    let (x, y) = sample_2d(rindex, Seeds::from_bits(bits(key, d)));
    (u(x), u(y))
}

/// The cheap alternative for 2-D, not taken: the shuffled Sobol point with
/// a random digital shift (xor) in place of the Owen scramble.
fn shifted_2d(key: u64, rindex: u32, d: u64) -> (f64, f64) {
    let s = Seeds::from_bits(bits(key, d));
    let x = lk_hash(rindex, s.index);
    // Sobol's second dimension of the same index, in the value domain:
    // the subset-sum transform of the first (the superset-sum, reversed).
    let mut y = x;
    y ^= (y << 1) & 0xAAAA_AAAA;
    y ^= (y << 2) & 0xCCCC_CCCC;
    y ^= (y << 4) & 0xF0F0_F0F0;
    y ^= (y << 8) & 0xFF00_FF00;
    y ^= (y << 16) & 0xFFFF_0000;
    (u(x ^ s.x), u(y ^ s.y))
}

/// Three 2-D Owen points of one index at once (the sampler's camera and
/// first-vertex points), summed.
fn owen_2d_x3(key: u64, rindex: u32) -> f64 {
    let bits = [0, 2, 4].map(|d| bits(key, d));
    let [a, b, c] = sample_2d_x3(rindex, bits);
    [a, b, c].iter().map(|&(x, y)| u(x) + u(y)).sum()
}

/// Nanoseconds per point of each kind, one thread, median of 5 rounds of
/// 10^7 points (each point's key and index differ, as a path's do).
#[inline(always)]
fn per(f: impl Fn(u64, u32) -> f64) -> f64 {
    use std::hint::black_box;
    let n = 10_000_000u64;
    let mut rounds: Vec<f64> = (0..5)
        .map(|_| {
            let t = std::time::Instant::now();
            let mut acc = 0u64;
            for k in 0..n {
                acc ^= f(black_box(k), (k as u32).reverse_bits()).to_bits();
            }
            black_box(acc);
            t.elapsed().as_secs_f64() * 1e9 / n as f64
        })
        .collect();
    rounds.sort_by(f64::total_cmp);
    rounds[2]
}

fn cost() {
    // A path hashes its sample's key once; each random number is one
    // more hash.
    let rows = [
        ("1-D random", per(|k, _| u((bits(k, 3) >> 32) as u32))),
        ("1-D Owen", per(|k, r| owen_1d(k, r, 3))),
        ("1-D shuffled (used)", per(|k, r| shuffled_1d(k, r, 3))),
        (
            "2-D random",
            per(|k, _| {
                let b = bits(k, 3);
                u((b >> 32) as u32) + u(b as u32)
            }),
        ),
        ("2-D Owen (used)", per(|k, r| pair_sum(owen_2d(k, r, 3)))),
        (
            "2-D digital shift",
            per(|k, r| pair_sum(shifted_2d(k, r, 3))),
        ),
    ];
    println!("| point | ns |\n| --- | ---: |");
    for (name, ns) in rows {
        println!("| {name} | {ns:.2} |");
    }
    // The render loop is compiled for AVX2 where the CPU has it, which is
    // where three points at once pay.
    #[cfg(target_arch = "x86_64")]
    if is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        #[allow(unsafe_code)]
        let (one, three) = unsafe {
            (
                per_avx2(|k, r| pair_sum(owen_2d(k, r, 3))),
                per_avx2(owen_2d_x3) / 3.0,
            )
        };
        println!("| 2-D Owen, AVX2 | {one:.2} |");
        println!("| 2-D Owen, three at once, AVX2 (per point) | {three:.2} |");
    }
    let three = per(owen_2d_x3) / 3.0;
    println!("| 2-D Owen, three at once (per point) | {three:.2} |");
}

/// [`per`] compiled for AVX2 and FMA, as the render loop is.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn per_avx2(f: impl Fn(u64, u32) -> f64) -> f64 {
    per(f)
}

fn pair_sum((x, y): (f64, f64)) -> f64 {
    x + y
}

/// Variance of the n-point estimate over `trials` keys.
fn variance(trials: u64, n: u32, f: &dyn Fn(u64, u32) -> f64) -> f64 {
    let est: Vec<f64> = (0..trials)
        .map(|t| {
            let key = mix64(t ^ 0x1234_5678);
            (0..n).map(|j| f(key, j.reverse_bits())).sum::<f64>() / f64::from(n)
        })
        .collect();
    let m = est.iter().sum::<f64>() / est.len() as f64;
    est.iter().map(|e| (e - m).powi(2)).sum::<f64>() / (est.len() as f64 - 1.0)
}

type Integrand1 = fn(&[f64; 4]) -> f64;
type Integrand2 = fn(&[(f64, f64); 2]) -> f64;

const ONE_D: [(&str, Integrand1); 5] = [
    ("step (roulette)", |p| f64::from(u8::from(p[0] < 0.37))),
    ("two steps", |p| {
        f64::from(u8::from(p[0] < 0.6 && p[1] < 0.45))
    }),
    ("roulette chain, 4 dims", |p| {
        let (mut w, mut s) = (1.0, 0.0);
        for &x in p {
            s += w * 0.5;
            if x >= 0.6 {
                break;
            }
            w *= 0.5 / 0.6;
        }
        s
    }),
    ("pick of 3 and its coin", |p| {
        let v = p[0] * 3.0;
        let c = v.floor();
        let keep = [0.2, 0.5, 0.9][c as usize];
        if v - c < keep {
            c + 1.0
        } else {
            0.0
        }
    }),
    ("smooth, sin 3x", |p| (p[0] * 3.0).sin()),
];

const TWO_D: [(&str, Integrand2); 4] = [
    ("disk edge", |p| {
        f64::from(u8::from(
            (p[0].0 - 0.3).powi(2) + (p[0].1 - 0.4).powi(2) < 0.2,
        ))
    }),
    ("smooth", |p| {
        (-(p[0].0 * p[0].0 + 2.0 * p[0].1 * p[0].1)).exp() * (1.0 + p[0].0)
    }),
    ("lobe in polar coordinates", |p| {
        let x = p[0].0.sqrt() * (std::f64::consts::TAU * p[0].1).cos();
        if x > 0.2 {
            1.0
        } else {
            0.3
        }
    }),
    ("edge across two padded pairs", |p| {
        match p[0].0 + p[1].1 < 0.9 {
            true => p[0].1 + p[1].0,
            false => 0.2,
        }
    }),
];

/// The rows of one integrand: random's variance over each kind's at every
/// count; `estimate(kind, key, rindex)` is one sample of the integrand.
fn compare<K: Copy>(
    trials: u64,
    name: &str,
    random: K,
    kinds: &[(&str, K)],
    estimate: impl Fn(K, u64, u32) -> f64,
) {
    let ratios: Vec<Vec<f64>> = COUNTS
        .iter()
        .map(|&n| {
            let of = |kind: K| variance(trials, n, &|key, r| estimate(kind, key, r));
            let random = of(random);
            kinds.iter().map(|(_, k)| random / of(*k)).collect()
        })
        .collect();
    let names: Vec<&str> = kinds.iter().map(|k| k.0).collect();
    row(name, &names, &ratios);
}

/// One line per kind; `ratios[count][kind]`.
fn row(name: &str, kinds: &[&str], ratios: &[Vec<f64>]) {
    for (k, kind) in kinds.iter().enumerate() {
        let cells: Vec<String> = ratios.iter().map(|r| format!("{:.2}", r[k])).collect();
        println!("| {name} | {kind} | {} |", cells.join(" | "));
    }
}

fn header(what: &str) {
    let counts: Vec<String> = COUNTS.iter().map(|n| format!("n = {n}")).collect();
    println!("\n| {what} | points | {} |", counts.join(" | "));
    println!("| --- | --- |{}", " ---: |".repeat(COUNTS.len()));
}

fn main() {
    let mut args = std::env::args().skip(1);
    let mut trials = 20_000u64;
    while let Some(a) = args.next() {
        match (a.as_str(), args.next().and_then(|v| v.parse().ok())) {
            ("--trials", Some(t)) if t > 1 => trials = t,
            _ => {
                eprintln!("usage: sampler_variance [--trials N (at least 2)]");
                std::process::exit(2);
            }
        }
    }
    cost();
    println!("\nRandom's variance over each kind's ({trials} keys per cell)");
    header("1-D integrand");
    let kinds1: [(&str, Kind1); 2] = [("Owen", owen_1d), ("shuffled (used)", shuffled_1d)];
    for (name, f) in ONE_D {
        compare(trials, name, random_1d as Kind1, &kinds1, |kind, key, r| {
            f(&[1, 2, 3, 4].map(|d| kind(key, r, d)))
        });
    }
    header("2-D integrand");
    let kinds2: [(&str, Kind2); 2] = [("Owen (used)", owen_2d), ("digital shift", shifted_2d)];
    for (name, f) in TWO_D {
        compare(trials, name, random_2d as Kind2, &kinds2, |kind, key, r| {
            f(&[1, 2].map(|d| kind(key, r, d)))
        });
    }
}
