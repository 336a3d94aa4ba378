use super::*;
use crate::render::envmap::EnvMap;
use crate::render::math::{sincos_turns, DVec3};
use std::sync::Arc;

/// A `w` x `h` map whose texel (i, j) is `f(i, j)`.
fn map(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Arc<EnvMap> {
    let texels = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| f(i, j));
    Arc::new(EnvMap::new("test", w, h, texels.collect()))
}

fn light(m: Arc<EnvMap>, rotation_deg: f64) -> EnvLight {
    EnvLight::new(m, 1.0, rotation_deg, true, DVec3::ZERO)
}

/// A small generator of unit directions, uniform on the sphere.
fn directions(n: usize) -> impl Iterator<Item = Vec3A> {
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    (0..n).map(move |_| {
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        let z = 1.0 - 2.0 * next();
        let r = (1.0 - z * z).max(0.0).sqrt();
        let (s, c) = sincos_turns(next());
        Vec3A::new(r * c, r * s, z)
    })
}

#[test]
fn texel_centres_read_their_texels_and_u_wraps() {
    let m = map(8, 4, |i, j| [i as f32, j as f32, 1.0]);
    for j in 0..4 {
        for i in 0..8 {
            let (u, v) = ((i as f32 + 0.5) / 8.0, (j as f32 + 0.5) / 4.0);
            assert_eq!(m.lookup(u, v), Vec3A::new(i as f32, j as f32, 1.0));
        }
    }
    // Across u = 0: halfway between the last column and the first.
    let edge = m.lookup(0.0, 0.5 / 4.0);
    assert!((edge.x - 3.5).abs() < 1e-6, "{edge:?}");
    // Clamped at the poles.
    assert_eq!(m.lookup(0.5 / 8.0, 0.0).y, 0.0);
    assert_eq!(m.lookup(0.5 / 8.0, 0.999).y, 3.0);
}

#[test]
fn directions_and_the_square_correspond() {
    // The orientation the README states: centre column -z, u towards +x,
    // top row +y.
    let (c, _) = map_direction(0.5, 0.5);
    assert!((c - Vec3A::new(0.0, 0.0, -1.0)).length() < 1e-6, "{c:?}");
    let (r, _) = map_direction(0.75, 0.5);
    assert!((r - Vec3A::X).length() < 1e-6, "{r:?}");
    let (up, _) = map_direction(0.3, 0.0);
    assert!((up - Vec3A::Y).length() < 1e-6, "{up:?}");
    for d in directions(10_000) {
        let (u, v) = map_uv(d);
        let (back, sin_t) = map_direction(u, v);
        assert!(
            (back - d).length() < 2e-6,
            "{d:?} -> ({u}, {v}) -> {back:?}"
        );
        assert!((sin_t - (d.x * d.x + d.z * d.z).sqrt()).abs() < 2e-6);
    }
}

#[test]
fn a_full_turn_is_the_identity_and_a_quarter_turn_shifts_the_texels() {
    let (w, h) = (16, 8);
    let f = |i: u32, j: u32| [(i * 7 + j * 3) as f32 % 5.0, j as f32, (i % 3) as f32];
    let m = map(w, h, f);
    let shifted = map(w, h, |i, j| f((i + w / 4) % w, j));
    let (still, full) = (light(m.clone(), 0.0), light(m.clone(), 360.0));
    let (quarter, plain) = (light(m, 90.0), light(shifted, 0.0));
    for d in directions(20_000) {
        assert_eq!(full.radiance(d), still.radiance(d), "{d:?}");
        let (a, b) = (quarter.radiance(d), plain.radiance(d));
        assert!((a - b).abs().max_element() < 1e-4, "{d:?}: {a:?} vs {b:?}");
    }
    // 90 degrees brings the centre column to face -x.
    let (centre, _) = map_direction(0.5, 0.5);
    assert!((quarter.map_to_world(centre) + Vec3A::X).length() < 1e-6);
}

/// Samples `n` directions from `l`; checks each weight against the
/// density and returns the counts per texel.
fn histogram(l: &EnvLight, n: usize) -> Vec<f64> {
    let m = &l.map;
    let mut counts = vec![0.0; (m.width * m.height) as usize];
    let side = (n as f64).sqrt().ceil() as usize;
    for k in 0..n {
        // Stratified over the square, jittered by a hash.
        let h = (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        let jitter = |s: u32| ((h >> s) & 0xffff) as f32 / 65536.0;
        let u1 = ((k % side) as f32 + jitter(0)) / side as f32;
        let u2 = ((k / side) as f32 + jitter(16)) / side as f32;
        let Some((d, weight)) = l.sample(u1.min(0.999_999), u2.min(0.999_999)) else {
            panic!("no sample at ({u1}, {u2})");
        };
        let pdf = l.pdf(d);
        assert!(
            (pdf * weight - 1.0).abs() < 2e-3,
            "pdf {pdf} x weight {weight} at {d:?}"
        );
        let (u, v) = map_uv(l.world_to_map(d));
        let i = ((u * m.width as f32) as u32).min(m.width - 1);
        let j = ((v * m.height as f32) as u32).min(m.height - 1);
        counts[(j * m.width + i) as usize] += 1.0;
    }
    counts
}

/// Pearson's chi-square of `counts` against the distribution's cells,
/// pooled into bins of at least 20 expected samples; (statistic, degrees
/// of freedom).
fn chi_square(m: &EnvMap, counts: &[f64]) -> (f64, usize) {
    let n: f64 = counts.iter().sum();
    let cells = (m.width * m.height) as f64;
    let (mut stat, mut bins, mut exp_acc, mut obs_acc) = (0.0, 0, 0.0, 0.0);
    for (c, &obs) in counts.iter().enumerate() {
        let (i, j) = (c % m.width as usize, c / m.width as usize);
        let expected = n * f64::from(m.dist.cell_pdf(i, j)) / cells;
        if expected == 0.0 {
            assert_eq!(obs, 0.0, "a sample in cell {c}, whose density is 0");
            continue;
        }
        exp_acc += expected;
        obs_acc += obs;
        if exp_acc >= 20.0 {
            stat += (obs_acc - exp_acc) * (obs_acc - exp_acc) / exp_acc;
            bins += 1;
            (exp_acc, obs_acc) = (0.0, 0.0);
        }
    }
    (stat, bins.max(2) - 1)
}

#[test]
fn samples_follow_the_density_on_varied_real_and_one_texel_maps() {
    // Bright spots, a gradient and black regions, on a turned map.
    let varied = map(64, 32, |i, j| {
        let spot = if (i, j) == (40, 10) || (i, j) == (3, 30) {
            500.0
        } else {
            0.0
        };
        let base = if j < 16 { (i as f32 / 64.0) * 2.0 } else { 0.0 };
        [base + spot, base * 0.5 + spot, spot]
    });
    let one = map(
        32,
        16,
        |i, j| if (i, j) == (5, 7) { [9.0; 3] } else { [0.0; 3] },
    );
    // A real map: Poly Haven's "venice sunset" (CC0) at 64 x 32, its sun a
    // few texels.
    let bytes = include_bytes!("../../../tests/data/sunset-64.hdr");
    let img = image::load_from_memory_with_format(bytes, image::ImageFormat::Hdr)
        .expect("reads")
        .into_rgb32f();
    let texels = img.pixels().map(|p| p.0).collect();
    let real = Arc::new(EnvMap::new("sunset", img.width(), img.height(), texels));
    for (name, m, rotation) in [
        ("varied", varied, 37.0),
        ("one texel", one, 0.0),
        ("sunset", real, -120.0),
    ] {
        let l = light(m.clone(), rotation);
        let counts = histogram(&l, 200_000);
        let (stat, dof) = chi_square(&m, &counts);
        // Mean dof, sd sqrt(2 dof): 5 sd is a test that fails on a fault
        // and not by chance.
        let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
        assert!(stat < limit, "{name}: chi-square {stat:.1} over {dof} dof");
    }
}

#[test]
fn the_density_integrates_to_one_over_the_sphere() {
    let m = map(48, 24, |i, j| [(i * j % 7) as f32, 1.0, 0.0]);
    let l = light(m, 12.0);
    let n = 400_000;
    let sum: f64 = directions(n).map(|d| f64::from(l.pdf(d))).sum();
    let integral = sum / n as f64 * 4.0 * std::f64::consts::PI;
    assert!((integral - 1.0).abs() < 0.01, "{integral}");
}

#[test]
fn the_mean_is_the_solid_angle_average() {
    let m = map(
        64,
        32,
        |_, j| if j < 16 { [2.0, 1.0, 0.0] } else { [0.0; 3] },
    );
    // The upper half of the sphere at 2: mean 1 (red), 0.5 (green).
    assert!(
        (m.mean[0] - 1.0).abs() < 1e-3 && (m.mean[1] - 0.5).abs() < 1e-3,
        "{:?}",
        m.mean
    );
}
