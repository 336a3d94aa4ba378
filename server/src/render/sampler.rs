//! Counter-based random numbers: every number a path uses is a pure function
//! of (seed, pixel, sample index, dimension).
//!
//! Why not the thesis's Xorshift: a stateful generator needs a per-pixel seed
//! buffer that the host refreshes every pass, and its output depends on how
//! samples were split into passes and threads. A counter-based generator has
//! no state to carry, so any sample of any pixel can be computed alone, in any
//! order, on any thread or device: an image depends only on scene, settings,
//! seed and sample count. The mixer is SplitMix64's finaliser (Steele et al.
//! 2014), which passes BigCrush when fed a counter; it needs only 64-bit
//! multiplies, which OpenCL C has everywhere, so the kernel makes the very same
//! decisions as the CPU.

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function: a bijection on u64 with full avalanche.
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The random stream of one camera path.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    dim: u64,
}

impl Sampler {
    /// The stream of sample `sample` of pixel `pixel` under `seed`.
    #[inline(always)]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let key = mix64(mix64(mix64(seed ^ 0x5851_F42D_4C95_7F2D) ^ pixel) ^ sample);
        Self { key, dim: 0 }
    }

    /// The next dimension's number, uniform in [0, 1) with 24 bits.
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_bits() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two numbers from one dimension's 64 bits (a 2-D sample): the top
    /// and the next 24 bits.
    #[inline(always)]
    pub fn next_2d(&mut self) -> (f32, f32) {
        let bits = self.next_bits();
        const SCALE: f32 = 1.0 / 16_777_216.0;
        (
            (bits >> 40) as f32 * SCALE,
            ((bits >> 16) & 0xFF_FFFF) as f32 * SCALE,
        )
    }

    /// The next dimension's full 64 bits (for choices among many, where
    /// 24 bits would not resolve every option).
    #[inline(always)]
    pub fn next_u64(&mut self) -> u64 {
        self.next_bits()
    }

    #[inline(always)]
    fn next_bits(&mut self) -> u64 {
        self.dim += 1;
        mix64(self.key.wrapping_add(self.dim.wrapping_mul(GOLDEN)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_stream_and_different_keys_differ() {
        let mut a = Sampler::new(7, 123, 9);
        let mut b = Sampler::new(7, 123, 9);
        let mut c = Sampler::new(7, 124, 9);
        let mut d = Sampler::new(8, 123, 9);
        let (va, vb, vc, vd): (Vec<f32>, Vec<f32>, Vec<f32>, Vec<f32>) = (
            (0..16).map(|_| a.next_f32()).collect(),
            (0..16).map(|_| b.next_f32()).collect(),
            (0..16).map(|_| c.next_f32()).collect(),
            (0..16).map(|_| d.next_f32()).collect(),
        );
        assert_eq!(va, vb);
        assert_ne!(va, vc);
        assert_ne!(va, vd);
    }

    #[test]
    fn uniform_moments_and_range_over_many_keys() {
        // Mean 1/2 and variance 1/12 over dimensions and neighbouring pixels,
        // the case where a weak hash would show correlation first.
        let (mut sum, mut sum2, mut n) = (0.0f64, 0.0f64, 0u32);
        for pixel in 0..4096u64 {
            let mut s = Sampler::new(0, pixel, 0);
            for _ in 0..8 {
                let u = s.next_f32();
                assert!((0.0..1.0).contains(&u));
                sum += f64::from(u);
                sum2 += f64::from(u) * f64::from(u);
                n += 1;
            }
        }
        let n = f64::from(n);
        let mean = sum / n;
        let var = sum2 / n - mean * mean;
        // Standard error of the mean is sqrt(1/12/n) ~ 1.1e-3.
        assert!((mean - 0.5).abs() < 5e-3, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 3e-3, "variance {var}");
    }

    #[test]
    fn neighbouring_pixels_are_uncorrelated() {
        let n = 20_000u64;
        let (mut sxy, mut sx, mut sy) = (0.0f64, 0.0f64, 0.0f64);
        for p in 0..n {
            let x = f64::from(Sampler::new(1, p, 3).next_f32());
            let y = f64::from(Sampler::new(1, p + 1, 3).next_f32());
            sxy += x * y;
            sx += x;
            sy += y;
        }
        let nf = n as f64;
        let cov = sxy / nf - (sx / nf) * (sy / nf);
        // Standard error of the covariance is about 1/12/sqrt(n) ~ 6e-4.
        assert!(cov.abs() < 4e-3, "covariance {cov}");
    }
}
