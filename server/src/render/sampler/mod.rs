//! Random numbers for paths: every number a path uses is a pure function
//! of (seed, pixel, sample index, dimension), so that any sample of any
//! pixel can be computed alone, in any order, on any thread or device: an
//! image depends only on scene, settings, seed and sample count.
//!
//! Two kinds ([`SamplerKind`], `quality.sampler`):
//! - `sobol` (the default): low-discrepancy points, scrambled Sobol
//!   padded in 2-D and 1-D ([`sobol`]). Each use a path makes of random numbers has
//!   its own dimension, chosen deliberately rather than by the order of
//!   draws: the camera's pixel position (2-D) and lens point (2-D, a
//!   dimension of its own far from the rest); at every vertex v, the light
//!   position (2-D, whose first coordinate also picks the emitter where
//!   there are several: `Sampler::light_pick_2d`), the BSDF's choice of
//!   lobe (1-D) and direction (2-D), and Russian roulette (1-D). A vertex that does
//!   not use one (a mirror draws no direction) leaves it unused, so the
//!   dimensions of the next vertex stay where they are. Sobol points serve
//!   the camera, the first vertex and every vertex's roulette; the light
//!   and BSDF numbers of deeper vertices are independent random numbers
//!   (hashed from the sample and the dimension): stratifying them gained
//!   nothing measurable (random's squared error over this sampler's, 32x32,
//!   8 seeds, 256 spp, unbounded: `cornell` 7.10 with Sobol points at the
//!   first vertex only, 6.97 with them at every vertex; `cornell-mesh`
//!   15.7 and 15.7; the furnace's gain is all in its roulette) and each
//!   2-D Sobol point costs a few times a random number. The film's even
//!   and odd samples are two independently scrambled sequences (sample s
//!   is point s / 2 of half s mod 2): the halves stay independent, as the
//!   error estimate and adaptive sampling assume, and each is a
//!   low-discrepancy set of its own.
//! - `random`: independent numbers, drawn in order: dimension k of a
//!   sample is SplitMix64's finaliser (Steele et al. 2014, passes BigCrush
//!   fed a counter) of a key hashed from (seed, pixel, sample) plus k
//!   times the golden ratio. Images under `random` are the renderer's
//!   before `sobol` existed, bit for bit.
//!
//! Both need only 64-bit multiplies and 32-bit integer operations, which
//! OpenCL C has everywhere: the kernel (`kernels/rng.h`) makes the very
//! same decisions as the CPU.

pub mod sobol;

use serde::{Deserialize, Serialize};
use sobol::Seeds;

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// Which numbers paths draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points: less error per sample.
    #[default]
    Sobol,
    /// Independent random numbers (the renderer's first sampler).
    Random,
}

impl SamplerKind {
    pub const NAMES: [&'static str; 2] = ["sobol", "random"];

    pub fn name(self) -> &'static str {
        match self {
            SamplerKind::Sobol => "sobol",
            SamplerKind::Random => "random",
        }
    }

    pub fn parse(s: &str) -> Option<SamplerKind> {
        match s {
            "sobol" => Some(SamplerKind::Sobol),
            "random" => Some(SamplerKind::Random),
            _ => None,
        }
    }
}

/// SplitMix64's output function: a bijection on u64 with full avalanche.
#[inline(always)]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The 64 hashed bits of Sobol dimension `d` of the sequence `key` names:
/// a 2-D dimension's seeds (`Seeds::from_bits`), whose low 32 bits are a
/// 1-D dimension's.
#[inline(always)]
fn dim_bits(key: u64, d: u64) -> u64 {
    mix64(key.wrapping_add(d.wrapping_mul(GOLDEN)))
}

/// A 2-D point in 32-bit fixed point as f32s in [0, 1).
#[inline(always)]
fn unit_2d((x, y): (u32, u32)) -> (f32, f32) {
    (sobol::unit_f32(x), sobol::unit_f32(y))
}

/// 24 bits as a number in [0, 1): the resolution of an f32 there.
#[inline(always)]
fn unit_24(bits: u64) -> f32 {
    (bits & 0xFF_FFFF) as f32 * (1.0 / 16_777_216.0)
}

/// Two numbers from 64 independent bits (a random 2-D sample): the top 24
/// bits and the next 24.
#[inline(always)]
fn pair_24(bits: u64) -> (f32, f32) {
    (unit_24(bits >> 40), unit_24(bits >> 16))
}

/// [`Sampler::light_pick_2d`]'s numbers from 64 independent bits: the top
/// 32 as they are, the low 24 as a number in [0, 1).
#[inline(always)]
fn pick_bits(bits: u64) -> (u32, f32) {
    ((bits >> 32) as u32, unit_24(bits))
}

/// What a path uses a vertex's numbers for: each its own Sobol dimension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u64)]
enum Use {
    // 0 is left unused: it was the light pick's, which now comes from the
    // light position's first coordinate (`Sampler::light_pick_2d`); the
    // other uses keep their dimensions, and so single-emitter images.
    LightPosition = 1,
    BsdfChoice = 2,
    BsdfDirection = 3,
    Roulette = 4,
}

/// Dimensions per vertex (one per [`Use`]).
const USES: u64 = 5;
/// The lens's dimension (a thin-lens camera's point on the aperture) is
/// this shifted left by 32: far from every vertex's, and shared with the
/// kernel as a 32-bit constant.
pub const LENS_DIMENSION_HI: u32 = 1 << 30;
const LENS_DIMENSION: u64 = (LENS_DIMENSION_HI as u64) << 32;
/// Dimensions of the light positions of every emitter but the first
/// (`LightSampling::All`, for tests) start here.
const EXTRA_LIGHTS: u64 = 1 << 63;
/// Vertices whose light and BSDF numbers are Sobol points (deeper ones
/// draw independent numbers; roulette is Sobol at every vertex).
pub const SOBOL_VERTICES: u32 = 1;

/// The random numbers of one camera path.
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    key: u64,
    /// Sobol: the key of this sample's independent numbers (deeper
    /// vertices' light and BSDF draws).
    rkey: u64,
    /// Random: dimensions drawn so far.
    dim: u64,
    /// Sobol: the sample's index in its half's sequence, bit-reversed.
    rindex: u32,
    /// Sobol: the vertex whose numbers are drawn (see [`Sampler::at_vertex`]).
    vertex: u32,
    sobol: bool,
    /// Sobol: the camera's point and the first vertex's light position and
    /// BSDF direction ([`FIRST_DIMENSIONS`]), computed together when the
    /// sampler is made (`sobol::sample_2d_x3`); every path draws the first
    /// and most draw the other two. 32-bit fixed point: the light pick
    /// reads all 32 bits of the light position's first coordinate.
    first: [(u32, u32); 3],
}

/// The 2-D dimensions of [`Sampler::first`]: the camera's (0), and vertex
/// 0's light position and BSDF direction (`Sampler::vertex_dim`).
const FIRST_DIMENSIONS: [u64; 3] = [
    0,
    1 + Use::LightPosition as u64,
    1 + Use::BsdfDirection as u64,
];

impl Sampler {
    /// The `random` numbers of sample `sample` of pixel `pixel` under `seed`.
    #[inline(always)]
    pub fn new(seed: u64, pixel: u64, sample: u64) -> Self {
        let key = mix64(mix64(mix64(seed ^ 0x5851_F42D_4C95_7F2D) ^ pixel) ^ sample);
        Self {
            key,
            rkey: 0,
            dim: 0,
            rindex: 0,
            vertex: 0,
            sobol: false,
            first: [(0, 0); 3],
        }
    }

    /// The numbers of sample `sample` of pixel `pixel` under `seed`.
    #[inline(always)]
    pub fn of_kind(kind: SamplerKind, seed: u64, pixel: u64, sample: u64) -> Self {
        match kind {
            SamplerKind::Random => Self::new(seed, pixel, sample),
            SamplerKind::Sobol => {
                let half = sample & 1;
                let key = mix64(
                    mix64(mix64(seed ^ 0x5851_F42D_4C95_7F2D) ^ pixel)
                        ^ half
                        ^ 0xA076_1D64_78BD_642F,
                );
                let rindex = ((sample >> 1) as u32).reverse_bits();
                let bits = FIRST_DIMENSIONS.map(|d| dim_bits(key, d));
                Self {
                    key,
                    rkey: mix64(key ^ u64::from(rindex)),
                    dim: 0,
                    rindex,
                    vertex: 0,
                    sobol: true,
                    first: sobol::sample_2d_x3(rindex, bits),
                }
            }
        }
    }

    /// The next dimension's number, uniform in [0, 1) with 24 bits (random).
    #[inline(always)]
    pub fn next_f32(&mut self) -> f32 {
        unit_24(self.next_bits() >> 40)
    }

    /// Two numbers from one dimension's 64 bits (a 2-D sample): the top
    /// and the next 24 bits (random).
    #[inline(always)]
    pub fn next_2d(&mut self) -> (f32, f32) {
        pair_24(self.next_bits())
    }

    /// The next dimension's full 64 bits (random).
    #[inline(always)]
    pub fn next_u64(&mut self) -> u64 {
        self.next_bits()
    }

    #[inline(always)]
    fn next_bits(&mut self) -> u64 {
        self.dim += 1;
        dim_bits(self.key, self.dim)
    }

    /// Whether the numbers are Sobol points.
    #[inline(always)]
    pub fn is_sobol(&self) -> bool {
        self.sobol
    }

    /// The seed of 1-D Sobol dimension `d` (the index shuffle's of the
    /// 2-D dimension `d`'s seeds).
    #[inline(always)]
    fn seed_1d(&self, d: u64) -> u32 {
        dim_bits(self.key, d) as u32
    }

    #[inline(always)]
    fn sobol_2d(&self, d: u64) -> (f32, f32) {
        unit_2d(self.sobol_2d_bits(d))
    }

    /// Sobol dimension `d`'s point in 32-bit fixed point.
    #[inline(always)]
    fn sobol_2d_bits(&self, d: u64) -> (u32, u32) {
        sobol::sample_2d(self.rindex, Seeds::from_bits(dim_bits(self.key, d)))
    }

    /// Whether this vertex's light and BSDF numbers are Sobol points.
    #[inline(always)]
    fn stratified(&self) -> bool {
        self.vertex < SOBOL_VERTICES
    }

    /// 64 independent bits for dimension `d` of this sample.
    #[inline(always)]
    fn pad_bits(&self, d: u64) -> u64 {
        dim_bits(self.rkey, d)
    }

    /// Two independent numbers for dimension `d` (as [`Sampler::next_2d`]).
    #[inline(always)]
    fn pad_2d(&self, d: u64) -> (f32, f32) {
        pair_24(self.pad_bits(d))
    }

    /// A number for 1-D dimension `d`: a Sobol point where `stratified`,
    /// else independent.
    #[inline(always)]
    fn number_1d(&self, d: u64, stratified: bool) -> f32 {
        if stratified {
            sobol::unit_f32(sobol::sample_1d(self.rindex, self.seed_1d(d)))
        } else {
            unit_24(self.pad_bits(d) >> 40)
        }
    }

    #[inline(always)]
    fn vertex_dim(&self, u: Use) -> u64 {
        1 + u64::from(self.vertex) * USES + u as u64
    }

    /// The camera sample's position in its pixel.
    #[inline(always)]
    pub fn camera_2d(&mut self) -> (f32, f32) {
        if self.sobol {
            unit_2d(self.first[0])
        } else {
            self.next_2d()
        }
    }

    /// A thin lens's point on its aperture (drawn after [`Sampler::camera_2d`],
    /// only by a camera that has a lens): a Sobol point of its own
    /// dimension, or the next random numbers.
    #[inline(always)]
    pub fn lens_2d(&mut self) -> (f32, f32) {
        if self.sobol {
            self.sobol_2d(LENS_DIMENSION)
        } else {
            self.next_2d()
        }
    }

    /// Numbers drawn from now on are vertex `v`'s (the path's (v+1)-th
    /// surface hit; Sobol only: random numbers go on in order).
    #[inline(always)]
    pub fn at_vertex(&mut self, v: u32) {
        self.vertex = v;
    }

    /// One of several emitters picked and a point on it, from one 2-D
    /// sample (the light position's): all 32 bits of its first coordinate,
    /// for `PickTable::pick_point`, which picks with them and hands back
    /// what they leave as the point's first coordinate, and the second
    /// coordinate as a number in [0, 1). One sample places the point on
    /// whichever emitter it picks, so a stratified sample stays stratified
    /// on each (a separate pick, independent of the position, left each
    /// emitter a random subset of the points: 1.3-1.6x the squared error
    /// on `glossy-plane`, 1.03-1.05x on `cornell-mesh`; docs/RENDERER.md).
    #[inline(always)]
    pub fn light_pick_2d(&mut self) -> (u32, f32) {
        if !self.sobol {
            return pick_bits(self.next_bits());
        }
        let d = self.vertex_dim(Use::LightPosition);
        match self.stratified() {
            true => {
                let (x, y) = match self.vertex {
                    0 => self.first[1],
                    _ => self.sobol_2d_bits(d),
                };
                (x, sobol::unit_f32(y))
            }
            false => pick_bits(self.pad_bits(d)),
        }
    }

    /// A point on emitter `k` of those sampled at this vertex (0 unless
    /// every emitter is sampled).
    #[inline(always)]
    pub fn light_2d(&mut self, k: u32) -> (f32, f32) {
        if !self.sobol {
            return self.next_2d();
        }
        let d = match k {
            0 => self.vertex_dim(Use::LightPosition),
            _ => EXTRA_LIGHTS | (u64::from(self.vertex) << 32) | u64::from(k),
        };
        match self.stratified() {
            true if self.vertex == 0 && k == 0 => unit_2d(self.first[1]),
            true => self.sobol_2d(d),
            false => self.pad_2d(d),
        }
    }

    /// The BSDF's choice among its lobes (reflect or refract).
    #[inline(always)]
    pub fn bsdf_choice(&mut self) -> f32 {
        if !self.sobol {
            return self.next_f32();
        }
        self.number_1d(self.vertex_dim(Use::BsdfChoice), self.stratified())
    }

    /// The BSDF's sampled direction.
    #[inline(always)]
    pub fn bsdf_2d(&mut self) -> (f32, f32) {
        if !self.sobol {
            return self.next_2d();
        }
        let d = self.vertex_dim(Use::BsdfDirection);
        match self.stratified() {
            true if self.vertex == 0 => unit_2d(self.first[2]),
            true => self.sobol_2d(d),
            false => self.pad_2d(d),
        }
    }

    /// Russian roulette's number.
    #[inline(always)]
    pub fn roulette(&mut self) -> f32 {
        if !self.sobol {
            return self.next_f32();
        }
        self.number_1d(self.vertex_dim(Use::Roulette), true)
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

    #[test]
    fn points_made_ahead_are_those_of_their_dimensions() {
        for (seed, pixel, sample) in [(0, 0, 0), (3, 17, 5), (9, 4095, 1000), (1, 2, 65_537)] {
            let mut s = Sampler::of_kind(SamplerKind::Sobol, seed, pixel, sample);
            let alone = |s: &Sampler, u| s.sobol_2d(s.vertex_dim(u));
            assert_eq!(s.camera_2d(), s.sobol_2d(0));
            s.at_vertex(0);
            assert_eq!(s.light_2d(0), alone(&s, Use::LightPosition));
            assert_eq!(s.bsdf_2d(), alone(&s, Use::BsdfDirection));
            assert_ne!(s.light_2d(1), s.light_2d(0), "other emitters' dimensions");
            let (x, y) = s.sobol_2d_bits(s.vertex_dim(Use::LightPosition));
            assert_eq!(s.light_pick_2d(), (x, sobol::unit_f32(y)));
            assert_eq!(sobol::unit_f32(x), s.light_2d(0).0);
        }
    }
}
