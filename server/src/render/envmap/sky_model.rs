//! A clear sky without a map: single scattering in a spherical
//! atmosphere (Nishita et al., "Display of the Earth Taking into Account
//! Atmospheric Scattering", 1993, as Cycles' Nishita sky), wavelength by
//! wavelength, turned into an environment map and a sun disc.
//!
//! - Geometry: the ground a sphere of radius 6360 km, the atmosphere's top
//!   60 km above it; the viewer `altitude_m` above the ground. Rays that
//!   meet the ground end there (the ground sends nothing: below the
//!   horizon the sky is dark).
//! - Air (Rayleigh): scattering 1.24062e-6 / lambda(um)^4 per metre at sea
//!   level, density falling with a scale height of 8 km; phase 3/(16 pi)
//!   (1 + mu^2).
//! - Dust (Mie): extinction 4.44e-6 per metre at sea level (no
//!   wavelength dependence), single-scattering albedo 0.9, scale height
//!   1.2 km; Cornette-Shanks phase with g = 0.8.
//! - Ozone: absorption only, 300 Dobson units in a layer rising linearly
//!   from 10 km to a peak at 25 km and falling to nothing at 40 km; cross
//!   sections from Serdyuchenko et al. (2014) at 233 K, averaged per bin.
//!   (The constants are those of Bruneton's precomputed atmospheric
//!   scattering, 2017.)
//! - The sun: ASTM G-173 outside the atmosphere (`spectrum`), attenuated
//!   along its path to each scattering point (a transmittance table over
//!   altitude and sun angle, built per sky) and to the viewer.
//!
//! `air`, `dust` and `ozone` scale the three densities (1 = the standard
//! atmosphere above; 0 removes it).
//!
//! Units: RGB radiance scaled so that the sun outside the atmosphere gives
//! a surface facing it an illuminance of pi: a white diffuse plane facing
//! the sun above the air reads luminance 1 (times the environment's
//! `intensity`). Under a clear sky at noon such a plane reads ~0.8-0.9.

// Spectra are arrays indexed by wavelength bin, several side by side.
#![allow(clippy::needless_range_loop)]

use super::map_direction;
use super::spectrum::{self, Spectrum, BINS};
use crate::render::math::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

pub const EARTH_RADIUS: f64 = 6_360_000.0;
pub const ATMOSPHERE_TOP: f64 = 6_420_000.0;
const RAYLEIGH_HEIGHT: f64 = 8000.0;
const MIE_HEIGHT: f64 = 1200.0;
const MIE_EXTINCTION: f64 = 5.328e-3 / MIE_HEIGHT;
const MIE_ALBEDO: f64 = 0.9;
const MIE_G: f64 = 0.8;
/// Peak ozone number density (m^-3): 300 DU over the 15 km-thick tent.
const OZONE_PEAK: f64 = 300.0 * 2.687e20 / 15000.0;

/// Ozone absorption cross sections (m^2), bins 380-780 nm.
const OZONE: Spectrum = [
    2.818e-28, 6.636e-28, 1.527e-27, 2.763e-27, 5.52e-27, 8.451e-27, 1.582e-26, 2.316e-26,
    3.669e-26, 4.924e-26, 7.752e-26, 9.016e-26, 1.48e-25, 1.602e-25, 2.139e-25, 2.755e-25,
    3.091e-25, 3.5e-25, 4.266e-25, 4.672e-25, 4.398e-25, 4.701e-25, 5.019e-25, 4.305e-25, 3.74e-25,
    3.215e-25, 2.662e-25, 2.238e-25, 1.852e-25, 1.473e-25, 1.209e-25, 9.423e-26, 7.455e-26,
    6.566e-26, 5.105e-26, 4.15e-26, 4.228e-26, 3.237e-26, 2.451e-26, 2.801e-26, 2.534e-26,
];

/// Steps along a view ray (spaced quadratically: dense where it starts,
/// where the air is).
pub const VIEW_STEPS: usize = 48;
/// Transmittance table: altitudes (quadratic) by cosines of the sun's angle.
const LUT_HEIGHTS: usize = 64;
const LUT_ANGLES: usize = 256;
/// The table's optical depth where the ground hides the sun.
const HIDDEN_DEPTH: f64 = 1e12;
/// Steps along a path towards the sun.
const SUN_STEPS: usize = 64;

/// What the air holds, and where the viewer is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Atmosphere {
    pub air: f64,
    pub dust: f64,
    pub ozone: f64,
    pub altitude_m: f64,
}

impl Default for Atmosphere {
    fn default() -> Self {
        Self {
            air: 1.0,
            dust: 1.0,
            ozone: 1.0,
            altitude_m: 0.0,
        }
    }
}

/// The sun as the sky model sees it: a disc of uniform radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunDisc {
    /// Unit direction towards its centre, in the map's frame.
    pub dir: DVec3,
    /// Angular radius (radians).
    pub radius: f64,
    /// Linear RGB radiance, in the sky's units.
    pub radiance: [f64; 3],
}

impl SunDisc {
    /// The disc of angular radius `radius` towards unit `dir` that gives
    /// RGB irradiance `irradiance` times `strength`: None where that is black.
    pub fn new(dir: DVec3, irradiance: [f64; 3], radius: f64, strength: f64) -> Option<Self> {
        let solid_angle = 2.0 * PI * (1.0 - radius.cos());
        let radiance = irradiance.map(|c| c * strength / solid_angle);
        (radiance.iter().any(|&c| c > 0.0)).then_some(Self {
            dir,
            radius,
            radiance,
        })
    }
}

/// Distance along unit `d` from `p` inside the sphere of radius `r` to it.
fn exit_distance(p: DVec3, d: DVec3, r: f64) -> f64 {
    let b = p.dot(d);
    let c = p.length_squared() - r * r;
    -b + (b * b - c).max(0.0).sqrt()
}

/// Distance along unit `d` from `p` (above it) to the ground, if it meets it.
fn ground_distance(p: DVec3, d: DVec3) -> Option<f64> {
    let b = p.dot(d);
    let c = p.length_squared() - EARTH_RADIUS * EARTH_RADIUS;
    let disc = b * b - c;
    (b < 0.0 && disc >= 0.0).then(|| (-b - disc.sqrt()).max(0.0))
}

/// Air, dust and ozone densities at height `h` (relative to sea level).
fn densities(h: f64) -> [f64; 3] {
    let ozone = if !(10_000.0..=40_000.0).contains(&h) {
        0.0
    } else if h < 25_000.0 {
        (h - 10_000.0) / 15_000.0
    } else {
        (40_000.0 - h) / 15_000.0
    };
    [(-h / RAYLEIGH_HEIGHT).exp(), (-h / MIE_HEIGHT).exp(), ozone]
}

/// The step boundaries `len (k / n)^2`: the k-th step's start and length.
#[inline]
fn step(len: f64, k: usize, n: usize) -> (f64, f64) {
    let t = |k: usize| len * (k as f64 / n as f64).powi(2);
    (t(k), t(k + 1) - t(k))
}

/// Integrated densities (m) along `len` metres of unit `d` from `p`.
fn optical_depth(p: DVec3, d: DVec3, len: f64, n: usize) -> [f64; 3] {
    let mut depth = [0.0; 3];
    for k in 0..n {
        let (t, dt) = step(len, k, n);
        let rho = densities((p + d * (t + 0.5 * dt)).length() - EARTH_RADIUS);
        for c in 0..3 {
            depth[c] += rho[c] * dt;
        }
    }
    depth
}

/// A clear sky for one sun direction and atmosphere.
pub struct SkyModel {
    sun: DVec3,
    viewer: DVec3,
    rayleigh: Spectrum,
    mie_scattering: f64,
    mie_extinction: f64,
    ozone: Spectrum,
    /// Optical depth to the top towards the sun, by (height, cos angle).
    lut: Vec<[f64; 3]>,
    /// RGB per unit of spectral radiance: the sun's illuminance to pi.
    scale: f64,
}

impl SkyModel {
    /// The sky with the sun towards unit `sun` (map frame: +y up).
    pub fn new(atmosphere: &Atmosphere, sun: DVec3) -> Self {
        let mut rayleigh = [0.0; BINS];
        let mut ozone = [0.0; BINS];
        for i in 0..BINS {
            let um = spectrum::lambda(i) * 1e-3;
            rayleigh[i] = atmosphere.air * 1.24062e-6 / um.powi(4);
            ozone[i] = atmosphere.ozone * OZONE_PEAK * OZONE[i];
        }
        let lut = (0..LUT_HEIGHTS * LUT_ANGLES)
            .into_par_iter()
            .map(|k| {
                let (h, mu) = lut_point(k / LUT_ANGLES, k % LUT_ANGLES);
                let p = DVec3::new(0.0, EARTH_RADIUS + h, 0.0);
                let d = DVec3::new((1.0 - mu * mu).max(0.0).sqrt(), mu, 0.0);
                match ground_distance(p, d) {
                    // Through the ground: dark (finite, so that the table
                    // interpolates to the earth's shadow without NaN).
                    Some(_) => [HIDDEN_DEPTH; 3],
                    None => optical_depth(p, d, exit_distance(p, d, ATMOSPHERE_TOP), SUN_STEPS),
                }
            })
            .collect();
        let solar_y = spectrum::to_xyz(&spectrum::solar_irradiance())[1];
        Self {
            sun: sun.normalize(),
            viewer: DVec3::new(0.0, EARTH_RADIUS + atmosphere.altitude_m.max(0.01), 0.0),
            rayleigh,
            mie_scattering: atmosphere.dust * MIE_EXTINCTION * MIE_ALBEDO,
            mie_extinction: atmosphere.dust * MIE_EXTINCTION,
            ozone,
            lut,
            scale: PI / solar_y,
        }
    }

    /// Optical depth from point `p` to the top towards the sun (the
    /// table, bilinearly), or None where the ground hides the sun.
    fn sun_depth(&self, p: DVec3) -> Option<[f64; 3]> {
        if ground_distance(p, self.sun).is_some() {
            return None;
        }
        let r = p.length();
        let h = (r - EARTH_RADIUS).clamp(0.0, ATMOSPHERE_TOP - EARTH_RADIUS);
        let mu = (p.dot(self.sun) / r).clamp(-1.0, 1.0);
        let x = (h / (ATMOSPHERE_TOP - EARTH_RADIUS)).sqrt() * (LUT_HEIGHTS - 1) as f64;
        let y = (mu + 1.0) * 0.5 * (LUT_ANGLES - 1) as f64;
        let (i, j) = (x.floor() as usize, y.floor() as usize);
        let (i1, j1) = ((i + 1).min(LUT_HEIGHTS - 1), (j + 1).min(LUT_ANGLES - 1));
        let (fx, fy) = (x - i as f64, y - j as f64);
        let at = |i: usize, j: usize| self.lut[i * LUT_ANGLES + j];
        let mut out = [0.0; 3];
        for c in 0..3 {
            let top = at(i, j)[c] * (1.0 - fy) + at(i, j1)[c] * fy;
            let bottom = at(i1, j)[c] * (1.0 - fy) + at(i1, j1)[c] * fy;
            out[c] = top * (1.0 - fx) + bottom * fx;
        }
        Some(out)
    }

    /// exp(-extinction) of optical depth `depth`, per bin.
    fn transmittance(&self, depth: [f64; 3]) -> Spectrum {
        std::array::from_fn(|i| {
            (-(self.rayleigh[i] * depth[0]
                + self.mie_extinction * depth[1]
                + self.ozone[i] * depth[2]))
                .exp()
        })
    }

    /// The spectral radiance (W m^-2 sr^-1 nm^-1) arriving at the viewer
    /// from unit direction `d`, single scattering in `steps` steps.
    pub fn spectral_radiance(&self, d: DVec3, steps: usize) -> Spectrum {
        let p0 = self.viewer;
        let top = exit_distance(p0, d, ATMOSPHERE_TOP);
        let len = ground_distance(p0, d).map_or(top, |g| g.min(top));
        let mu = d.dot(self.sun);
        let phase_r = 3.0 / (16.0 * PI) * (1.0 + mu * mu);
        let g2 = MIE_G * MIE_G;
        let phase_m = 3.0 / (8.0 * PI) * (1.0 - g2) * (1.0 + mu * mu)
            / ((2.0 + g2) * (1.0 + g2 - 2.0 * MIE_G * mu).powf(1.5));
        let mut sum = [0.0; BINS];
        let mut view = [0.0; 3];
        for k in 0..steps {
            let (t, dt) = step(len, k, steps);
            let p = p0 + d * (t + 0.5 * dt);
            let rho = densities(p.length() - EARTH_RADIUS);
            let to_mid: [f64; 3] = std::array::from_fn(|c| view[c] + 0.5 * rho[c] * dt);
            for c in 0..3 {
                view[c] += rho[c] * dt;
            }
            let Some(sun) = self.sun_depth(p) else {
                continue;
            };
            let t = self.transmittance(std::array::from_fn(|c| to_mid[c] + sun[c]));
            let mie = self.mie_scattering * rho[1] * phase_m;
            for i in 0..BINS {
                sum[i] += t[i] * (self.rayleigh[i] * rho[0] * phase_r + mie) * dt;
            }
        }
        let solar = spectrum::solar_irradiance();
        std::array::from_fn(|i| sum[i] * solar[i])
    }

    /// Linear RGB (the sky's units) of spectral radiance `s`.
    pub fn rgb(&self, s: &Spectrum) -> [f64; 3] {
        spectrum::xyz_to_rgb(spectrum::to_xyz(s)).map(|c| c * self.scale)
    }

    /// The sun's transmittance from the top of the air to the viewer, or
    /// None below the horizon.
    pub fn sun_transmittance(&self) -> Option<Spectrum> {
        let p = self.viewer;
        if ground_distance(p, self.sun).is_some() {
            return None;
        }
        let len = exit_distance(p, self.sun, ATMOSPHERE_TOP);
        Some(self.transmittance(optical_depth(p, self.sun, len, 4 * SUN_STEPS)))
    }

    /// The sun as a disc of angular radius `radius`, its radiance scaled by
    /// `strength`: None below the horizon or with no strength.
    pub fn sun_disc(&self, radius: f64, strength: f64) -> Option<SunDisc> {
        SunDisc::new(self.sun, self.sun_irradiance()?, radius, strength)
    }

    /// The sunlight reaching the viewer, as RGB irradiance on a surface
    /// facing the sun (the sky's units), or None below the horizon.
    pub fn sun_irradiance(&self) -> Option<[f64; 3]> {
        let t = self.sun_transmittance()?;
        let solar = spectrum::solar_irradiance();
        let s: Spectrum = std::array::from_fn(|i| solar[i] * t[i]);
        Some(self.rgb(&s).map(|c| c.max(0.0)))
    }

    /// The sky (without the sun's disc) as a `width` x `height`
    /// equirectangular map in the environment maps' layout; negative RGB
    /// (colours outside sRGB's gamut) clipped to 0. The sky depends only
    /// on a direction's elevation and its azimuth from the sun's (it is
    /// mirror-symmetric about the sun's vertical plane), so it is computed
    /// on a table over those two, [`SKY_ROWS`] elevations (denser near the
    /// horizon) by [`SKY_COLUMNS`] azimuths from 0 to 180 degrees, and the
    /// map's texels interpolate it bilinearly.
    pub fn image(&self, width: u32, height: u32) -> Vec<[f32; 3]> {
        let sun_azimuth = self.sun.x.atan2(-self.sun.z);
        let table: Vec<[f64; 3]> = (0..SKY_ROWS * SKY_COLUMNS)
            .into_par_iter()
            .map(|k| {
                let (e, a) = sky_table_point(k / SKY_COLUMNS, k % SKY_COLUMNS);
                let d = sun_direction(e, sun_azimuth + a);
                self.rgb(&self.spectral_radiance(d, VIEW_STEPS))
                    .map(|c| c.max(0.0))
            })
            .collect();
        (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % width, k / width);
                let u = (i as f32 + 0.5) / width as f32;
                let v = (j as f32 + 0.5) / height as f32;
                let (m, _) = map_direction(u, v);
                let m = DVec3::new(m.x.into(), m.y.into(), m.z.into()).normalize();
                let elevation = m.y.clamp(-1.0, 1.0).asin();
                let azimuth = m.x.atan2(-m.z) - sun_azimuth;
                // |azimuth from the sun's| in [0, pi].
                let a = (azimuth + PI).rem_euclid(2.0 * PI) - PI;
                let x = elevation.abs() / (PI / 2.0);
                let half = (SKY_ROWS - 1) / 2;
                let row = half as f64 + elevation.signum() * x.sqrt() * half as f64;
                let col = a.abs() / PI * (SKY_COLUMNS - 1) as f64;
                let (r0, c0) = (row.floor() as usize, col.floor() as usize);
                let (r1, c1) = ((r0 + 1).min(SKY_ROWS - 1), (c0 + 1).min(SKY_COLUMNS - 1));
                let (fr, fc) = (row - r0 as f64, col - c0 as f64);
                let at = |r: usize, c: usize| table[r * SKY_COLUMNS + c];
                std::array::from_fn(|ch| {
                    let top = at(r0, c0)[ch] * (1.0 - fc) + at(r0, c1)[ch] * fc;
                    let bottom = at(r1, c0)[ch] * (1.0 - fc) + at(r1, c1)[ch] * fc;
                    (top * (1.0 - fr) + bottom * fr) as f32
                })
            })
            .collect()
    }
}

/// Elevations in the sky's table: from -90 to 90 degrees, spaced as the
/// square of the distance from the horizon (dense where the sky changes).
pub const SKY_ROWS: usize = 2 * 96 + 1;
/// Azimuths from the sun's in the sky's table: 0 to 180 degrees.
pub const SKY_COLUMNS: usize = 129;

/// The elevation and azimuth (from the sun's) of sky table entry (row, col).
fn sky_table_point(row: usize, col: usize) -> (f64, f64) {
    let half = (SKY_ROWS - 1) / 2;
    let x = (row as f64 - half as f64) / half as f64;
    let elevation = x.signum() * x * x * (PI / 2.0);
    (elevation, col as f64 / (SKY_COLUMNS - 1) as f64 * PI)
}

/// The height and cosine of table entry (i, j).
fn lut_point(i: usize, j: usize) -> (f64, f64) {
    let x = i as f64 / (LUT_HEIGHTS - 1) as f64;
    let mu = j as f64 / (LUT_ANGLES - 1) as f64 * 2.0 - 1.0;
    (x * x * (ATMOSPHERE_TOP - EARTH_RADIUS), mu)
}

/// The unit direction towards a sun at `elevation` above the horizon and
/// `azimuth` clockwise from -z (north) seen from above (90 degrees: +x,
/// east), both in radians.
pub fn sun_direction(elevation: f64, azimuth: f64) -> DVec3 {
    let (se, ce) = elevation.sin_cos();
    let (sa, ca) = azimuth.sin_cos();
    DVec3::new(ce * sa, se, -ce * ca)
}

#[cfg(test)]
#[path = "sky_model_tests.rs"]
mod tests;
