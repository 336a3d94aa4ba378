//! Walker's alias method (Vose's construction): picks index i with
//! probability w_i / sum(w) in constant time, from one 64-bit random number.
//!
//! The top 32 bits choose a column (Lemire's multiply-shift, so every
//! column has probability within 2^-32 of 1/n), the low 32 bits choose
//! between the column's own index and its alias against a 32-bit
//! threshold. The probabilities the estimator divides by (`pmf`) are the
//! exact normalised weights; the picking probabilities differ from them by
//! at most n 2^-32 relatively, far below any image's noise.

#[derive(Clone, Debug, PartialEq)]
pub struct AliasTable {
    /// Per column: keep the column's index when the low bits are below this.
    threshold: Vec<u32>,
    alias: Vec<u32>,
    pmf: Vec<f32>,
}

impl AliasTable {
    /// A table for `weights` (finite, >= 0); None if none is positive.
    pub fn new(weights: &[f64]) -> Option<Self> {
        let total: f64 = weights.iter().filter(|w| w.is_finite() && **w > 0.0).sum();
        if !(total > 0.0) || weights.len() > u32::MAX as usize {
            return None;
        }
        let n = weights.len();
        let clean = |w: f64| if w.is_finite() && w > 0.0 { w } else { 0.0 };
        let pmf: Vec<f64> = weights.iter().map(|&w| clean(w) / total).collect();
        let mut scaled: Vec<f64> = pmf.iter().map(|p| p * n as f64).collect();
        let (mut small, mut large): (Vec<u32>, Vec<u32>) =
            (0..n as u32).partition(|&i| scaled[i as usize] < 1.0);
        let mut prob = vec![1.0f64; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            prob[s as usize] = scaled[s as usize];
            alias[s as usize] = l;
            scaled[l as usize] -= 1.0 - scaled[s as usize];
            if scaled[l as usize] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // What is left (rounding) keeps its own column always.
        let threshold = prob
            .iter()
            .map(|&p| {
                if p >= 1.0 {
                    u32::MAX
                } else {
                    (p * 4_294_967_296.0) as u32
                }
            })
            .collect();
        Some(Self {
            threshold,
            alias,
            pmf: pmf.iter().map(|&p| p as f32).collect(),
        })
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// The index picked by `bits` and its probability.
    #[inline(always)]
    pub fn pick(&self, bits: u64) -> (usize, f32) {
        let column = (((bits >> 32) * self.pmf.len() as u64) >> 32) as usize;
        let low = bits as u32;
        // u32::MAX as a threshold means "always keep" (even for low = MAX).
        let keep = low < self.threshold[column] || self.threshold[column] == u32::MAX;
        let i = if keep {
            column
        } else {
            self.alias[column] as usize
        };
        (i, self.pmf[i])
    }

    /// The probability of index `i`.
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Column `i` as [`AliasTable::pick`] reads it: (threshold, alias,
    /// pmf of index i); for a device to pick the same index from the same bits.
    pub fn column(&self, i: usize) -> (u32, u32, f32) {
        (self.threshold[i], self.alias[i], self.pmf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::mix64;

    #[test]
    fn picks_in_proportion_to_the_weights() {
        let weights = [1.0, 0.0, 3.0, 0.5, 10.0, 0.25, 2.0];
        let table = AliasTable::new(&weights).expect("positive weights");
        let total: f64 = weights.iter().sum();
        let n = 2_000_000u64;
        let mut counts = [0u64; 7];
        for i in 0..n {
            let (k, p) = table.pick(mix64(i));
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
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[f64::NAN, -1.0]).is_none());
        let one = AliasTable::new(&[0.0, 2.0]).expect("one positive");
        for bits in [0, u64::MAX, 1 << 63, 12345] {
            assert_eq!(one.pick(bits).0, 1);
        }
    }
}
