//! A piecewise-constant density over the unit square, sampled by inverting
//! its marginal over rows and then the row's conditional (pbrt's
//! `PiecewiseConstant2D`): how an environment map's texels are chosen in
//! proportion to their brightness.
//!
//! The tables are built in f64 and kept in f32; sampling and the density
//! are a handful of f32 operations in a fixed order, which the kernel's
//! twins (`kernels/envmap.h`) repeat bit for bit: a binary search over a
//! cumulative table, one division to place the point inside its cell.

use crate::render::math::ONE_BELOW;
use rayon::prelude::*;

/// The density of `height` rows of `width` cells each. Its tables are one
/// array, as the kernel reads them (`data`):
/// - the marginal's cumulative masses, `height + 1` entries: 0, the
///   cumulative row masses, 1;
/// - the marginal's densities, per row (mass x height);
/// - per row, the conditional's cumulative masses, `width + 1` entries;
/// - per row, per cell, the conditional's densities (mass x width).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    pub width: u32,
    pub height: u32,
    pub data: Vec<f32>,
}

/// One 1-D table: its cumulative masses (`n + 1`, from 0 to exactly 1) and
/// densities (`n`), from non-negative weights; a row of zeros is uniform.
fn table(weights: &[f64], cdf: &mut Vec<f32>, pdf: &mut Vec<f32>) -> f64 {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    let uniform = !(total > 0.0);
    let w = |i: usize| if uniform { 1.0 } else { weights[i] };
    let total = if uniform { n as f64 } else { total };
    let mut acc = 0.0f64;
    cdf.push(0.0);
    for i in 0..n {
        acc += w(i);
        cdf.push(if i + 1 == n {
            1.0
        } else {
            (acc / total) as f32
        });
        pdf.push((w(i) / total * n as f64) as f32);
    }
    if uniform {
        0.0
    } else {
        total
    }
}

/// The cell of a 1-D table that `u` in [0, 1) falls in, and where inside
/// it, in [0, 1): the last cell whose cumulative mass is at most `u` (so
/// never one of zero mass).
#[inline(always)]
pub fn invert(cdf: &[f32], u: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let (mut lo, mut hi) = (0usize, n);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if cdf[mid] <= u {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let width = cdf[lo + 1] - cdf[lo];
    let du = if width > 0.0 {
        (u - cdf[lo]) / width
    } else {
        0.0
    };
    (lo, du.clamp(0.0, ONE_BELOW))
}

impl Distribution2D {
    /// The density proportional to `weights` (row by row, finite and
    /// non-negative); uniform where all are zero.
    pub fn new(width: u32, height: u32, weights: &[f64]) -> Self {
        let (w, h) = (width as usize, height as usize);
        assert_eq!(weights.len(), w * h, "one weight per cell");
        // Each row's table in parallel, then joined in row order.
        let per_row: Vec<(Vec<f32>, Vec<f32>, f64)> = weights
            .par_chunks_exact(w)
            .map(|row| {
                let (mut cdf, mut pdf) = (Vec::with_capacity(w + 1), Vec::with_capacity(w));
                let total = table(row, &mut cdf, &mut pdf);
                (cdf, pdf, total)
            })
            .collect();
        let rows: Vec<f64> = per_row.iter().map(|r| r.2).collect();
        let (mut data, mut marginal_pdf) = (Vec::new(), Vec::new());
        table(&rows, &mut data, &mut marginal_pdf);
        data.reserve(h + h * (2 * w + 1));
        data.extend(marginal_pdf);
        data.extend(per_row.iter().flat_map(|r| r.0.iter().copied()));
        data.extend(per_row.iter().flat_map(|r| r.1.iter().copied()));
        Self {
            width,
            height,
            data,
        }
    }

    /// The marginal's cumulative masses (`height + 1`).
    #[inline(always)]
    pub fn marginal_cdf(&self) -> &[f32] {
        &self.data[..self.height as usize + 1]
    }

    /// The marginal's densities (`height`).
    #[inline(always)]
    pub fn marginal_pdf(&self) -> &[f32] {
        let h = self.height as usize;
        &self.data[h + 1..2 * h + 1]
    }

    /// Row `row`'s cumulative masses (`width + 1`).
    #[inline(always)]
    fn conditional_cdf(&self, row: usize) -> &[f32] {
        let (w, h) = (self.width as usize, self.height as usize);
        let start = 2 * h + 1 + row * (w + 1);
        &self.data[start..start + w + 1]
    }

    /// A point of the unit square drawn with this density from `(u1, u2)`
    /// in [0, 1)^2, and its density.
    #[inline(always)]
    pub fn sample(&self, u1: f32, u2: f32) -> (f32, f32, f32) {
        let (w, h) = (self.width, self.height);
        let (row, dv) = invert(self.marginal_cdf(), u2);
        let (col, du) = invert(self.conditional_cdf(row), u1);
        // (Below 1: the last cell's top rounds up to 1 in a wide table.)
        let x = ((col as f32 + du) / w as f32).min(ONE_BELOW);
        let y = ((row as f32 + dv) / h as f32).min(ONE_BELOW);
        (x, y, self.cell_pdf(col, row))
    }

    /// The density of cell (col, row).
    #[inline(always)]
    pub fn cell_pdf(&self, col: usize, row: usize) -> f32 {
        let (w, h) = (self.width as usize, self.height as usize);
        let conditional = 2 * h + 1 + h * (w + 1);
        self.data[h + 1 + row] * self.data[conditional + row * w + col]
    }

    /// The density at (x, y) of the unit square.
    #[inline(always)]
    pub fn pdf(&self, x: f32, y: f32) -> f32 {
        let col = ((x * self.width as f32) as usize).min(self.width as usize - 1);
        let row = ((y * self.height as f32) as usize).min(self.height as usize - 1);
        self.cell_pdf(col, row)
    }

    /// Bytes the tables hold.
    pub fn memory_bytes(&self) -> usize {
        4 * self.data.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_density_integrates_to_one_and_follows_the_weights() {
        let weights = [0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 2.0, 2.0];
        let d = Distribution2D::new(4, 2, &weights);
        let total: f64 = (0..2)
            .flat_map(|r| (0..4).map(move |c| (c, r)))
            .map(|(c, r)| f64::from(d.cell_pdf(c, r)) / 8.0)
            .sum();
        assert!((total - 1.0).abs() < 1e-6, "{total}");
        // Cell (2, 0) holds 3/8 of the mass: density 3/8 * 8 = 3.
        assert!((d.cell_pdf(2, 0) - 3.0).abs() < 1e-6);
        assert_eq!(d.cell_pdf(0, 0), 0.0);
        assert_eq!(d.marginal_cdf(), &[0.0, 0.5, 1.0]);
    }

    #[test]
    fn sampling_never_lands_in_a_cell_of_zero_mass() {
        let weights = [0.0, 0.0, 5.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0];
        let d = Distribution2D::new(3, 3, &weights);
        for i in 0..=1000 {
            for u in [0.0, i as f32 / 1000.0, ONE_BELOW] {
                let (x, y, pdf) = d.sample(u, 1.0 - u.max(1e-7));
                assert!(pdf > 0.0 && d.pdf(x, y) == pdf, "({x}, {y}) {pdf}");
                assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
            }
        }
    }

    #[test]
    fn a_row_of_zeros_is_never_chosen_and_an_all_zero_map_is_uniform() {
        let d = Distribution2D::new(2, 2, &[0.0, 0.0, 1.0, 1.0]);
        assert_eq!(d.marginal_pdf(), &[0.0, 2.0]);
        let z = Distribution2D::new(2, 2, &[0.0; 4]);
        assert_eq!(z.cell_pdf(1, 1), 1.0);
    }
}
