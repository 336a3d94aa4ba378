//! The emitter next-event estimation picks, in proportion to its power,
//! from one 32-bit number x: the inverse of the weights' cumulative
//! distribution. Emitter i owns the interval [lower_i, upper_i) of x's top
//! 31 bits, whose length over 2^31 is exactly the probability the
//! estimator divides by (`pmf`). A guide table (Chen and Asau's cutpoint
//! method) starts the search at the emitter under the first x of x's n-th
//! of [0, 1), so a pick takes a step or two on average whatever n is.
//!
//! What x leaves in its emitter's interval, stretched to [0, 1), is uniform
//! again given the pick, and as stratified as x was: it places the point on
//! the emitter ([`PickTable::pick_point`]), so that one 2-D sample both
//! picks and places, as Mitsuba's emitter sampling does. Each emitter owns
//! one interval, so a stratified x stays stratified on each. The alias
//! table this replaces (Walker's method, until 2026-11-30) picked in one
//! step, but an emitter could own a piece of every column: a dominant sky
//! got its points from two stretched halves of x and `sky-window` had 10%
//! more error at 64 spp than with a pick of its own dimension
//! (docs/RENDERER.md, "Sampler").

use crate::render::math::ONE_BELOW;

/// x's top 31 bits are the pick's fixed point: 2^31 fits in u32.
const ONE: u64 = 1 << 31;

#[derive(Clone, Debug, PartialEq)]
pub struct PickTable {
    /// Emitter i owns the 31-bit x in [lower[i], upper[i]) (empty where its
    /// weight is zero; the last one with weight ends at 2^31).
    lower: Vec<u32>,
    upper: Vec<u32>,
    /// guide[g]: the emitter that owns the first x of column g, the x with
    /// x * n / 2^31 in [g, g + 1).
    guide: Vec<u32>,
    /// Each emitter's interval length over 2^31: its pick probability.
    pmf: Vec<f32>,
}

impl PickTable {
    /// A table for `weights` (finite, >= 0); None if none is positive or
    /// there are more than 2^30. Every positive weight gets an interval
    /// (at least one 2^-31), so every emitter with power is picked
    /// sometimes: at a diffuse surface next-event estimation is the only
    /// way light reaches it.
    pub fn new(weights: &[f64]) -> Option<Self> {
        let clean = |w: f64| if w.is_finite() && w > 0.0 { w } else { 0.0 };
        let total: f64 = weights.iter().map(|&w| clean(w)).sum();
        let n = weights.len();
        if !(total > 0.0) || n > 1 << 30 {
            return None;
        }
        let mut width: Vec<u64> = (weights.iter())
            .map(|&w| match clean(w) {
                0.0 => 0,
                w => ((w / total * ONE as f64).round() as u64).max(1),
            })
            .collect();
        settle(&mut width);
        let mut lower = Vec::with_capacity(n);
        let mut upper = Vec::with_capacity(n);
        let mut end = 0u64;
        for &w in &width {
            lower.push(end as u32);
            end += w;
            upper.push(end as u32);
        }
        debug_assert_eq!(end, ONE);
        let mut guide = Vec::with_capacity(n);
        let mut j = 0;
        for g in 0..n as u64 {
            let first = (g * ONE).div_ceil(n as u64);
            while first >= u64::from(upper[j]) {
                j += 1;
            }
            guide.push(j as u32);
        }
        let pmf = width
            .iter()
            .map(|&w| (w as f64 / ONE as f64) as f32)
            .collect();
        Some(Self {
            lower,
            upper,
            guide,
            pmf,
        })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// The index picked by `x`, its probability, and what `x` leaves: a
    /// number in [0, 1), uniform given the pick when `x` is uniform and
    /// stratified where `x` is (the offset in the interval over its length,
    /// an f32 division that the kernel does correctly rounded too).
    /// Out of line: inlined into the render loop, it cost `cornell-mesh`
    /// 5% of its paths/s (the loop's code around it, not its own steps).
    #[inline(never)]
    pub fn pick_point(&self, x: u32) -> (usize, f32, f32) {
        let x = x >> 1;
        let column = (u64::from(x) * self.pmf.len() as u64) >> 31;
        let mut i = self.guide[column as usize] as usize;
        // Ends: the last emitter with weight reaches 2^31 > x.
        while x >= self.upper[i] {
            i += 1;
        }
        let (lower, upper) = (self.lower[i], self.upper[i]);
        let u = ((x - lower) as f32 / (upper - lower) as f32).min(ONE_BELOW);
        (i, self.pmf[i], u)
    }

    /// The probability of index `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Emitter `i` as [`PickTable::pick_point`] reads it: (lower, upper,
    /// guide entry i, pmf of index i); for a device to pick the same index
    /// from the same bits.
    pub fn column(&self, i: usize) -> (u32, u32, u32, f32) {
        (self.lower[i], self.upper[i], self.guide[i], self.pmf[i])
    }
}

/// Makes the widths add up to 2^31: what rounding left over goes to the
/// widest; what it took too much comes off the widest ones, none below 1.
fn settle(width: &mut [u64]) {
    let sum: u64 = width.iter().sum();
    if sum <= ONE {
        if let Some(w) = width.iter_mut().max() {
            *w += ONE - sum;
        }
        return;
    }
    let mut excess = sum - ONE;
    let mut order: Vec<usize> = (0..width.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(width[i]));
    for i in order {
        let take = excess.min(width[i].saturating_sub(1));
        width[i] -= take;
        excess -= take;
        if excess == 0 {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::mix64;

    #[test]
    fn picks_in_proportion_to_the_weights() {
        let weights = [1.0, 0.0, 3.0, 0.5, 10.0, 0.25, 2.0];
        let table = PickTable::new(&weights).expect("positive weights");
        let total: f64 = weights.iter().sum();
        let n = 2_000_000u64;
        let mut counts = [0u64; 7];
        for i in 0..n {
            let (k, p, _) = table.pick_point((mix64(i) >> 32) as u32);
            assert!((f64::from(p) - weights[k] / total).abs() < 1e-7);
            counts[k] += 1;
        }
        assert_eq!(counts[1], 0, "a zero weight is never picked");
        for (k, &w) in weights.iter().enumerate() {
            let expected = w / total;
            let got = counts[k] as f64 / n as f64;
            let se = (expected * (1.0 - expected) / n as f64).sqrt();
            assert!(
                (got - expected).abs() <= 5.0 * se + 1e-9,
                "index {k}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn no_positive_weight_gives_no_table() {
        assert!(PickTable::new(&[]).is_none());
        assert!(PickTable::new(&[0.0, 0.0]).is_none());
        assert!(PickTable::new(&[f64::NAN, -1.0]).is_none());
        let one = PickTable::new(&[0.0, 2.0, 0.0]).expect("one positive");
        for x in [0, u32::MAX, 1 << 31, 12345] {
            assert_eq!(one.pick_point(x).0, 1);
        }
        assert_eq!(one.pmf(1), 1.0);
    }

    /// A weight far below 2^-31 of the total keeps an interval (and the pmf
    /// the estimator divides by is that interval's), and the ends of x pick
    /// the first and last emitters with weight, past empty ones.
    #[test]
    fn tiny_weights_and_the_ends_of_x() {
        let weights = [0.0, 1e-12, 1.0, 0.0, 1e-15, 0.0];
        let table = PickTable::new(&weights).expect("positive weights");
        assert_eq!(table.pick_point(0).0, 1);
        assert_eq!(table.pick_point(2).0, 2);
        assert_eq!(table.pick_point(u32::MAX).0, 4);
        assert_eq!(table.pmf(1), 1.0 / ONE as f32);
        assert_eq!(table.pmf(3), 0.0);
        let sum: f64 = (0..6).map(|i| f64::from(table.pmf(i))).sum();
        assert!((sum - 1.0).abs() < 1e-6, "{sum}");
    }

    /// x on a regular grid: each index's leftover numbers must be spread
    /// over [0, 1) as evenly as a regular grid is, the Kolmogorov-Smirnov
    /// distance of their empirical distribution within 2 / count (one
    /// interval of x, stretched: a grid at an offset); independent numbers
    /// would be ~1/sqrt(count) off (here 15-90 times the bound), and a leftover
    /// not stretched to [0, 1), or not uniform, further still. The alias
    /// table's leftovers (up to n + 1 intervals each) were up to 4.5 / count.
    #[test]
    fn what_the_pick_leaves_is_uniform_and_stratified_on_each_index() {
        let weights = [1.0, 0.0, 3.0, 0.5, 10.0, 0.25, 2.0, 2.0];
        let table = PickTable::new(&weights).expect("positive weights");
        let n = 1u64 << 16;
        let mut left: Vec<Vec<f32>> = vec![Vec::new(); weights.len()];
        for k in 0..n {
            let x = ((k << 32) / n + (1 << 15)) as u32;
            let (i, _, u) = table.pick_point(x);
            assert!((0.0..1.0).contains(&u), "x {x}: {u}");
            left[i].push(u);
        }
        for (i, us) in left.iter_mut().enumerate() {
            if us.is_empty() {
                assert_eq!(weights[i], 0.0, "index {i} never picked");
                continue;
            }
            us.sort_by(f32::total_cmp);
            let c = us.len() as f64;
            let ks = us
                .iter()
                .enumerate()
                .map(|(j, &u)| {
                    let u = f64::from(u);
                    (u - j as f64 / c).abs().max(((j + 1) as f64 / c - u).abs())
                })
                .fold(0.0, f64::max);
            assert!(
                ks * c <= 2.0,
                "index {i}: KS distance {ks} over {c} numbers"
            );
        }
    }
}
