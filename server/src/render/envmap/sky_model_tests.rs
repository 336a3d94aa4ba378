//! The sky model against closed forms: in an optically thin atmosphere,
//! single scattering seen straight up is the sun's irradiance times the
//! scattering coefficient's column times the phase function; the sun's
//! transmittance is exp(-column) per wavelength.

#![allow(clippy::needless_range_loop)]

use super::*;
use crate::render::envmap::spectrum::{lambda, luminance, solar_irradiance};

const UP: DVec3 = DVec3::Y;

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a / b - 1.0).abs() < rel
}

/// The column of an exponential layer of scale height `h` up to the top.
fn column(h: f64) -> f64 {
    h * (1.0 - (-(ATMOSPHERE_TOP - EARTH_RADIUS) / h).exp())
}

#[test]
fn thin_air_straight_up_is_rayleigh_column_times_phase() {
    let atm = Atmosphere {
        air: 1e-3,
        dust: 0.0,
        ozone: 0.0,
        altitude_m: 0.0,
    };
    let sky = SkyModel::new(&atm, UP);
    let l = sky.spectral_radiance(UP, VIEW_STEPS);
    let solar = solar_irradiance();
    for i in 0..BINS {
        let beta = 1e-3 * 1.24062e-6 / (lambda(i) * 1e-3).powi(4);
        // Forward scattering (mu = 1): 3/(16 pi) * 2.
        let want = solar[i] * beta * column(8000.0) * 3.0 / (8.0 * PI);
        assert!(close(l[i], want, 5e-3), "bin {i}: {} vs {want}", l[i]);
    }
}

#[test]
fn thin_dust_is_mie_column_times_the_cornette_shanks_phase() {
    let atm = Atmosphere {
        air: 0.0,
        dust: 1e-3,
        ozone: 0.0,
        altitude_m: 0.0,
    };
    // The sun 30 degrees up, the view straight up: mu = cos 60 = 0.5.
    let sky = SkyModel::new(&atm, sun_direction(30f64.to_radians(), 0.0));
    let l = sky.spectral_radiance(UP, VIEW_STEPS);
    let (g, mu) = (0.8f64, 0.5f64);
    let phase = 3.0 / (8.0 * PI) * (1.0 - g * g) * (1.0 + mu * mu)
        / ((2.0 + g * g) * (1.0 + g * g - 2.0 * g * mu).powf(1.5));
    let solar = solar_irradiance();
    for i in 0..BINS {
        let want = solar[i] * 1e-3 * 5.328e-3 / 1200.0 * 0.9 * column(1200.0) * phase;
        assert!(close(l[i], want, 5e-3), "bin {i}: {} vs {want}", l[i]);
    }
}

#[test]
fn the_sun_straight_up_is_dimmed_by_exp_of_each_column() {
    let air = Atmosphere {
        air: 1.0,
        dust: 0.0,
        ozone: 0.0,
        altitude_m: 0.0,
    };
    let t = SkyModel::new(&air, UP)
        .sun_transmittance()
        .expect("above the horizon");
    for i in 0..BINS {
        let tau = 1.24062e-6 / (lambda(i) * 1e-3).powi(4) * column(8000.0);
        assert!(
            close(t[i].ln(), -tau, 2e-3),
            "bin {i}: {} vs {}",
            -t[i].ln(),
            tau
        );
    }
    // Ozone: 300 Dobson units times the cross section.
    let ozone = Atmosphere {
        air: 0.0,
        dust: 0.0,
        ozone: 1.0,
        altitude_m: 0.0,
    };
    let t = SkyModel::new(&ozone, UP)
        .sun_transmittance()
        .expect("above the horizon");
    let i = 22; // 600 nm, the Chappuis band's peak
    let tau = 300.0 * 2.687e20 * 5.019e-25;
    assert!(close(-t[i].ln(), tau, 1e-2), "{} vs {tau}", -t[i].ln());
}

#[test]
fn a_noon_sky_is_blue_a_low_sun_is_red_and_a_set_sun_is_gone() {
    let atm = Atmosphere::default();
    let noon = SkyModel::new(&atm, sun_direction(70f64.to_radians(), 0.0));
    let zenith = noon.rgb(&noon.spectral_radiance(UP, VIEW_STEPS));
    assert!(zenith[2] > 1.5 * zenith[0], "zenith {zenith:?}");
    let sun = noon.sun_disc(0.00465, 1.0).expect("a noon sun");
    let [r, g, b] = sun.radiance;
    assert!(
        r > g && g > b && b > 0.65 * r,
        "noon sun {:?}",
        sun.radiance
    );
    let low = SkyModel::new(&atm, sun_direction(2f64.to_radians(), 0.0));
    let [r, g, b] = low.sun_disc(0.00465, 1.0).expect("a low sun").radiance;
    assert!(r > 2.0 * g && g > 2.0 * b, "low sun {:?}", [r, g, b]);
    let set = SkyModel::new(&atm, sun_direction(-2f64.to_radians(), 0.0));
    assert!(set.sun_disc(0.00465, 1.0).is_none());
    // The sky stays lit a little after sunset (the upper air still sees the sun).
    let dusk = set.rgb(&set.spectral_radiance(UP, VIEW_STEPS));
    assert!(luminance(dusk) > 0.0 && luminance(dusk) < 0.1 * luminance(zenith));
}

#[test]
fn a_white_plane_under_a_clear_noon_sky_reads_most_of_the_suns_unit() {
    // Sun and sky at 90 degrees elevation, integrated over the upper
    // hemisphere as a white diffuse plane sees them: E / pi.
    let atm = Atmosphere::default();
    let sky = SkyModel::new(&atm, UP);
    let radius = 0.545f64.to_radians() / 2.0;
    let sun = sky.sun_disc(radius, 1.0).expect("noon");
    let omega = 2.0 * PI * (1.0 - radius.cos());
    let direct = luminance(sun.radiance) * omega / PI;
    let (w, h) = (128u32, 64u32);
    let img = sky.image(w, h);
    let mut diffuse = 0.0;
    for j in 0..h / 2 {
        let (t0, t1) = (PI * j as f64 / h as f64, PI * (j + 1) as f64 / h as f64);
        // Solid angle times cos over the row: (sin^2 t1 - sin^2 t0) / 2 * dphi.
        let weight = (t1.sin().powi(2) - t0.sin().powi(2)) / 2.0 * (2.0 * PI / w as f64);
        for i in 0..w {
            let t = img[(j * w + i) as usize].map(f64::from);
            diffuse += luminance(t) * weight / PI;
        }
    }
    eprintln!("noon: sun {direct:.3} + sky {diffuse:.3}");
    assert!((0.75..0.9).contains(&direct), "direct {direct}");
    // Single scattering only: clear skies measure ~10% diffuse at noon.
    assert!((0.03..0.2).contains(&diffuse), "sky {diffuse}");
    let t = std::time::Instant::now();
    let _ = sky.image(512, 256);
    eprintln!("512x256 sky in {:?}", t.elapsed());
}

#[test]
fn more_steps_change_the_horizon_little_and_the_sky_is_mirror_symmetric_about_the_sun() {
    let atm = Atmosphere::default();
    let sky = SkyModel::new(&atm, sun_direction(20f64.to_radians(), 0.0));
    for elevation in [1.0f64, 5.0, 30.0] {
        let d = sun_direction(elevation.to_radians(), 1.0);
        let coarse = luminance(sky.rgb(&sky.spectral_radiance(d, VIEW_STEPS)));
        let fine = luminance(sky.rgb(&sky.spectral_radiance(d, 8 * VIEW_STEPS)));
        assert!(close(coarse, fine, 0.02), "{elevation}: {coarse} vs {fine}");
        let mirrored = sun_direction(elevation.to_radians(), -1.0);
        let m = luminance(sky.rgb(&sky.spectral_radiance(mirrored, VIEW_STEPS)));
        assert!(close(coarse, m, 1e-9), "{coarse} vs {m}");
    }
}

#[test]
fn sun_directions_follow_the_compass() {
    let near = |a: DVec3, b: DVec3| (a - b).length() < 1e-12;
    assert!(near(sun_direction(PI / 2.0, 1.0), UP));
    assert!(near(sun_direction(0.0, 0.0), -DVec3::Z), "north is -z");
    assert!(near(sun_direction(0.0, PI / 2.0), DVec3::X), "east is +x");
}

#[test]
fn the_maps_table_matches_the_sky_computed_per_texel() {
    let atm = Atmosphere::default();
    let sky = SkyModel::new(&atm, sun_direction(25f64.to_radians(), 0.7));
    let (w, h) = (64u32, 32u32);
    let img = sky.image(w, h);
    let mut worst = 0.0f64;
    for j in 0..h / 2 - 1 {
        for i in 0..w {
            let (m, _) = map_direction((i as f32 + 0.5) / w as f32, (j as f32 + 0.5) / h as f32);
            let d = DVec3::new(m.x.into(), m.y.into(), m.z.into()).normalize();
            let want = luminance(sky.rgb(&sky.spectral_radiance(d, VIEW_STEPS)));
            let got = luminance(img[(j * w + i) as usize].map(f64::from));
            worst = worst.max((got / want - 1.0).abs());
        }
    }
    assert!(worst < 0.02, "worst texel {worst}");
}
