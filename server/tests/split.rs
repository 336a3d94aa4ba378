//! One render on several devices (`--backend all`, `render::split`): the
//! merged film holds samples 0..spp exactly as one device's would, whoever
//! rendered which block; a device that fails mid-render loses nothing.
//! Runs on PoCL and rayon as the two devices (PoCL is required where CI is set).

mod common;

use common::{assert_agree, assert_same_samples, opencl_device, render, scene};
use pathstream::render::backend::CpuBackend;
use pathstream::render::split::{render_split, render_split_taking_turns};
use pathstream::render::{Backend, Film, Quality, RenderJob};

const SIDE: u32 = 32;

fn quality(spp: u64, seed: u64) -> Quality {
    Quality {
        spp: Some(spp),
        seed,
        ..Quality::default()
    }
}

fn split(
    backends: &mut [Backend],
    name: &str,
    q: &Quality,
) -> (Film, Vec<pathstream::render::split::DeviceShare>) {
    let job = RenderJob::new(&scene(name), SIDE, SIDE, q);
    // As `pathstream render` does: programs built before the clock starts.
    for b in backends.iter_mut() {
        b.prepare(&job).expect("prepare");
    }
    let mut film = Film::new(SIDE, SIDE);
    // The lanes take turns, so that each render here merges blocks of every
    // device, interleaved (left to the race, one lane can take a render this
    // small whole, and the test would compare a one-device render with
    // itself).
    let (progress, shares) =
        render_split_taking_turns(&job, backends, &mut film, q, |_| {}).expect("render");
    assert_eq!(progress.spp, q.spp.expect("spp"));
    (film, shares)
}

fn cpu() -> Backend {
    Backend::Cpu(CpuBackend::default())
}

fn pocl() -> Option<Backend> {
    opencl_device().map(|d| Backend::OpenCl {
        backend: Box::new(d),
        fallback: false,
    })
}

/// Largest relative difference of any pixel channel (above a floor).
fn worst_relative(a: &Film, b: &Film) -> f64 {
    let (ma, mb) = (a.mean(), b.mean());
    ma.iter()
        .zip(&mb)
        .flat_map(|(x, y)| {
            (0..3).map(move |c| (x[c] - y[c]).abs() / x[c].abs().max(y[c].abs()).max(1e-3))
        })
        .fold(0.0, f32::max) as f64
}

#[test]
fn blocks_on_two_rayon_devices_merge_into_the_one_device_image() {
    // Same device kind twice: every sample is the same bits, so the merged
    // film differs from one device's only by the order of f64 additions.
    for name in ["cornell", "cornell-glass"] {
        let q = quality(48, 5);
        let (merged, shares) = split(&mut [cpu(), cpu()], name, &q);
        assert!(
            shares.iter().all(|s| s.samples > 0),
            "{name}: every lane took blocks: {shares:?}"
        );
        let single = render(&scene(name), SIDE, SIDE, &q, 48);
        assert_eq!(merged.spp(), 48);
        assert_eq!(merged.total_samples(), single.total_samples());
        let worst = worst_relative(&merged, &single);
        assert!(worst < 1e-6, "{name}: a pixel differs by {worst:e}");
        assert_eq!(
            merged.error_estimate().map(|e| (e * 1e6).round()),
            single.error_estimate().map(|e| (e * 1e6).round())
        );
        let total: u64 = shares.iter().map(|s| s.samples).sum();
        assert_eq!(
            total,
            merged.total_samples(),
            "{name}: every path counted once"
        );
    }
}

#[test]
fn pocl_and_rayon_together_render_the_one_device_image() {
    let Some(device) = pocl() else { return };
    let q = quality(256, 9);
    let (merged, shares) = split(&mut [device, cpu()], "cornell-glass", &q);
    assert!(
        shares
            .iter()
            .all(|s| s.samples > 0 && s.samples_per_sec > 0.0),
        "{shares:?}"
    );
    let single = render(&scene("cornell-glass"), SIDE, SIDE, &q, 256);
    // The same sample indices with the same random numbers: only the
    // devices' rounding differs.
    assert_same_samples(
        &merged.mean(),
        &single.mean(),
        "PoCL + rayon vs rayon, same seed",
    );
    // And statistically the image of another seed.
    let other = render(&scene("cornell-glass"), SIDE, SIDE, &quality(256, 10), 256);
    assert_agree(
        &merged,
        &other,
        8,
        4.5,
        0.0,
        "PoCL + rayon vs rayon, other seed",
    );
}

#[test]
fn a_device_that_fails_mid_render_loses_no_samples() {
    let Some(Backend::OpenCl { mut backend, .. }) = pocl() else {
        return;
    };
    // A few launches succeed (blocks merged), then every launch fails.
    backend.fail_after_launches = Some(2);
    let failing = Backend::OpenCl {
        backend,
        fallback: false,
    };
    let q = quality(400, 3);
    let (merged, shares) = split(&mut [failing, cpu()], "cornell", &q);
    assert!(
        shares[0]
            .failure
            .as_deref()
            .is_some_and(|f| f.contains("injected")),
        "{shares:?}"
    );
    assert!(
        shares[0].samples > 0,
        "the device rendered some blocks before failing: {shares:?}"
    );
    assert!(shares[1].failure.is_none());
    assert_eq!(merged.spp(), 400);
    let single = render(&scene("cornell"), SIDE, SIDE, &q, 400);
    // Samples 0..400, each exactly once: a lost or doubled block would move
    // every pixel by about the noise.
    assert_same_samples(&merged.mean(), &single.mean(), "a device failed mid-render");
}

#[test]
fn every_device_failing_is_an_error() {
    let Some(Backend::OpenCl { mut backend, .. }) = pocl() else {
        return;
    };
    backend.fail_launches = true;
    let mut one = [Backend::OpenCl {
        backend,
        fallback: false,
    }];
    let q = quality(8, 1);
    let job = RenderJob::new(&scene("cornell"), 8, 8, &q);
    let mut film = Film::new(8, 8);
    let err = render_split(&job, &mut one, &mut film, &q, |_| {}).expect_err("fails");
    assert!(err.to_string().contains("injected"), "{err}");
    assert_eq!(film.spp(), 0);
}

#[test]
fn an_adaptive_render_splits_its_warm_up_then_goes_on_on_one_device() {
    let q = Quality {
        adaptive: true,
        ..quality(48, 2)
    };
    let (merged, shares) = split(&mut [cpu(), cpu()], "cornell-glass", &q);
    assert!(merged.adaptive_started(), "rounds ran");
    assert!(merged.rounds() > 0);
    let spread = merged.spp_spread();
    assert!(spread.max > spread.min, "{spread:?}");
    assert_eq!(
        shares.iter().map(|s| s.samples).sum::<u64>(),
        merged.total_samples()
    );
}
