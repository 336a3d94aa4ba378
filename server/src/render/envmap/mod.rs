//! Environment maps: an equirectangular (latitude-longitude) HDR image of
//! the radiance arriving from every direction, looked up bilinearly and
//! sampled by next-event estimation in proportion to its brightness.
//!
//! Orientation: the map's top row is straight up (+y), its bottom row
//! straight down; its centre column faces -z, and u grows towards +x (a
//! viewer at the centre looking down -z sees the map's middle, right of
//! centre to the right). `rotation_deg` turns the map about +y, right-handed:
//! 90 degrees brings the centre column to face -x.
//!
//! Sampling: a piecewise-constant density over the texels
//! ([`Distribution2D`]) proportional to each texel's brightness as the
//! bilinear lookup spreads it (the mean of the lookup over the texel's
//! cell: weights 1/8, 3/4, 1/8 along each axis, so that every direction the
//! lookup lights has a positive density) times the row's mean sin(theta)
//! (the cell's solid angle). The density in solid angle is the square's density divided by
//! 2 pi^2 sin(theta).
//!
//! This module holds the image and its tables (what a scene keeps, built
//! once per file); `light::sky` turns, scales and samples it as an emitter.
//! The kernel's twins are in `kernels/envmap.h`: the same arithmetic in
//! the same order, so that lookups, samples and densities agree bit for bit
//! (`tests/envmap.rs`).

pub mod distribution;
pub mod sky_model;
pub mod spectrum;
pub mod sun_position;

pub use distribution::Distribution2D;

use crate::render::math::{atan2_turns, sincos_turns, Vec3A};
use rayon::prelude::*;
use std::f64::consts::PI;

/// 2 pi^2: the Jacobian from the unit square to the sphere, over sin(theta).
pub(crate) const TWO_PI2: f32 = (2.0 * PI * PI) as f32;

/// An environment image and its sampling tables, built once per image.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    /// The file's (or the upload's) name.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row by row from the top.
    pub texels: Vec<[f32; 3]>,
    pub dist: Distribution2D,
    /// The radiance averaged over the sphere (solid angle), per channel.
    pub mean: [f64; 3],
    /// What reading the image changed, for the scene's warnings.
    pub warning: Option<String>,
}

impl EnvMap {
    /// The map of these texels (`width * height`, finite, non-negative).
    pub fn new(name: &str, width: u32, height: u32, texels: Vec<[f32; 3]>) -> Self {
        let (w, h) = (width as usize, height as usize);
        assert_eq!(texels.len(), w * h, "one texel per cell");
        let brightness: Vec<f64> = texels
            .iter()
            .map(|t| (f64::from(t[0]) + f64::from(t[1]) + f64::from(t[2])) / 3.0)
            .collect();
        let at = |i: isize, j: isize| {
            let i = i.rem_euclid(w as isize) as usize;
            let j = j.clamp(0, h as isize - 1) as usize;
            brightness[j * w + i]
        };
        const TAP: [(isize, f64); 3] = [(-1, 0.125), (0, 0.75), (1, 0.125)];
        let mut weights = vec![0.0f64; w * h];
        // Row by row in parallel (a 4k map has 8M texels): each row's
        // weights and its share of the mean, summed in row order after.
        let rows: Vec<[f64; 3]> = weights
            .par_chunks_mut(w)
            .enumerate()
            .map(|(j, row)| {
                // The row's mean sin(theta), whose sum is its solid angle.
                let theta = |j: usize| PI * j as f64 / h as f64;
                let sin = (theta(j).cos() - theta(j + 1).cos()) * h as f64 / PI;
                let mut mean = [0.0f64; 3];
                for (i, out) in row.iter_mut().enumerate() {
                    let (ii, jj) = (i as isize, j as isize);
                    let spread: f64 = TAP
                        .iter()
                        .flat_map(|&(dj, wj)| TAP.iter().map(move |&(di, wi)| (di, dj, wi * wj)))
                        .map(|(di, dj, k)| k * at(ii + di, jj + dj))
                        .sum();
                    *out = spread * sin;
                    for (c, m) in mean.iter_mut().enumerate() {
                        *m += f64::from(texels[j * w + i][c]) * sin;
                    }
                }
                mean
            })
            .collect();
        let mean = rows
            .iter()
            .fold([0.0f64; 3], |a, r| [a[0] + r[0], a[1] + r[1], a[2] + r[2]]);
        // Each texel's solid angle is sin(theta) (2 pi / w) (pi / h).
        let scale = 2.0 * PI * PI / (w * h) as f64 / (4.0 * PI);
        Self {
            name: name.to_owned(),
            width,
            height,
            dist: Distribution2D::new(width, height, &weights),
            mean: mean.map(|m| m * scale),
            texels,
            warning: None,
        }
    }

    #[inline(always)]
    fn texel(&self, i: u32, j: u32) -> Vec3A {
        Vec3A::from_array(self.texels[(j * self.width + i) as usize])
    }

    /// The bilinear lookup at (u, v) of the unit square: texel centres at
    /// half-integers, wrapping across u = 0 and 1, clamped at the poles.
    #[inline(always)]
    pub fn lookup(&self, u: f32, v: f32) -> Vec3A {
        let (w, h) = (self.width, self.height);
        let x = u * w as f32 - 0.5;
        let y = v * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let i0 = (x0 as i32).rem_euclid(w as i32) as u32;
        let i1 = if i0 + 1 == w { 0 } else { i0 + 1 };
        let j0 = (y0 as i32).clamp(0, h as i32 - 1) as u32;
        let j1 = (y0 as i32 + 1).clamp(0, h as i32 - 1) as u32;
        let top = self.texel(i0, j0) * (1.0 - fx) + self.texel(i1, j0) * fx;
        let bottom = self.texel(i0, j1) * (1.0 - fx) + self.texel(i1, j1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Bytes the image and its tables hold.
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * 12 + self.dist.memory_bytes()
    }
}

/// The point (u, v) of the map's square that unit direction `m` (in the
/// map's frame) looks at.
#[inline(always)]
pub fn map_uv(m: Vec3A) -> (f32, f32) {
    let u = 0.5 + atan2_turns(m.x, -m.z);
    let s = (m.x * m.x + m.z * m.z).sqrt();
    let v = 2.0 * atan2_turns(s, m.y);
    (u, v)
}

/// The direction (in the map's frame) of point (u, v) of the square, and
/// sin(theta) there.
#[inline(always)]
pub fn map_direction(u: f32, v: f32) -> (Vec3A, f32) {
    let (sin_t, cos_t) = sincos_turns(v * 0.5);
    let (sin_p, cos_p) = sincos_turns(u);
    (Vec3A::new(-(sin_t * sin_p), cos_t, sin_t * cos_p), sin_t)
}
