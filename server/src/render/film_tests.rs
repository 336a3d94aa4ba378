//! Tests of `film.rs`: sums, rejected samples, the error estimate.

use super::*;

#[test]
fn non_finite_samples_are_rejected_and_counted() {
    let mut film = Film::new(2, 1);
    let bad = [
        Vec3A::new(f32::NAN, 1.0, 1.0),
        Vec3A::new(1.0, f32::INFINITY, 1.0),
        Vec3A::new(1.0, 1.0, f32::NEG_INFINITY),
    ];
    let mut rejected = 0;
    for s in 0..8u64 {
        let row = film.pixels_mut();
        for (i, px) in row.iter_mut().enumerate() {
            let l = if i == 1 && s < 3 {
                bad[s as usize]
            } else {
                Vec3A::splat(2.0)
            };
            if !px.add(s, l) {
                rejected += 1;
            }
        }
    }
    film.commit(8, rejected);
    assert_eq!(film.rejected(), 3);
    let mean = film.mean();
    assert_eq!(mean[0], [2.0; 3]);
    // The rejected samples count as black: 5 of 8 samples were 2.
    assert!(mean[1].iter().all(|v| (v - 2.0 * 5.0 / 8.0).abs() < 1e-6));
    assert!(mean.iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn a_constant_pixel_keeps_its_value_over_1e8_samples() {
    let mut film = Film::new(1, 1);
    let value = Vec3A::new(0.1, 1.0 / 3.0, 7.77);
    let count = 100_000_000u64;
    let px = &mut film.pixels_mut()[0];
    for s in 0..count {
        px.add(s, value);
    }
    film.commit(count, 0);
    let mean = film.mean()[0];
    for (m, v) in mean.iter().zip(value.to_array()) {
        assert!(((m - v) / v).abs() < 1e-6, "{m} vs {v}");
    }
    assert_eq!(film.error_estimate(), Some(0.0));
}

#[test]
fn error_estimate_matches_the_known_variance_of_a_noise_film() {
    // Samples uniform in [0, 2): mean 1, variance 1/3. After n samples
    // the relative RMS error of the mean is sqrt(1/3/n).
    let (w, h, n) = (64u32, 64u32, 64u64);
    let mut film = Film::new(w, h);
    for (i, px) in film.pixels_mut().iter_mut().enumerate() {
        for s in 0..n {
            let mut rng = crate::render::sampler::Sampler::new(9, i as u64, s);
            px.add(
                s,
                Vec3A::new(
                    2.0 * rng.next_f32(),
                    2.0 * rng.next_f32(),
                    2.0 * rng.next_f32(),
                ),
            );
        }
    }
    film.commit(n, 0);
    let expected = (1.0 / 3.0 / n as f64).sqrt();
    let estimate = film.error_estimate().expect("estimate");
    assert!(
        (estimate / expected - 1.0).abs() < 0.05,
        "{estimate} vs {expected}"
    );
    let truth = relative_rms_error(&film.mean(), &vec![[1.0; 3]; (w * h) as usize]);
    assert!(
        (truth / expected - 1.0).abs() < 0.05,
        "{truth} vs {expected}"
    );
}
