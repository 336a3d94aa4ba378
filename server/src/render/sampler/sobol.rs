//! Scrambled Sobol points by hashing, padded: every 1-D or 2-D sample of
//! a path is its own low-discrepancy sequence, with seeds hashed from (the
//! path's key, the sample's dimension).
//!
//! - **2-D**: Sobol's first two dimensions, a (0,2)-sequence, Owen-scrambled
//!   by hashing (Burley, "Practical Hash-based Owen Scrambling", JCGT
//!   2020): the index order is shuffled by a nested uniform scramble and
//!   the values are Owen-scrambled. The first 2^m indices of any such
//!   sequence form a (0,m,2)-net: every elementary interval of area 2^-m
//!   holds exactly one point, whatever the seeds.
//! - **1-D**: the van der Corput sequence (Sobol's first dimension) with its
//!   index order shuffled by the same nested uniform scramble, and no value
//!   scramble: one hash, no bit reversal, where an Owen-scrambled point
//!   costs two of each. The first 2^m points are a regular grid of step
//!   2^-m, shifted by a random offset and visited in a random nested
//!   order. Every 1-D use (roulette, the light pick and its coin, the
//!   BSDF's lobe) is a step function of its number, where such a grid is as
//!   good as Owen's jittered strata; measured by
//!   `examples/sampler_variance.rs` (docs/RENDERER.md).
//!
//! Neither dimension needs a table: the first is the bit-reversed index
//! (van der Corput); the second is the bit-reversed superset-sum transform
//! of the index (its generator matrix is Pascal's triangle mod 2: by
//! Lucas' theorem, index bit k reaches value bit p exactly when p's bits
//! are a subset of k's), five shift-and-xor steps. All arithmetic is on
//! u32, so the kernel (`kernels/rng.h`) makes the same numbers bit for bit.

use crate::render::lanes::{Bits, U32s};

/// A permutation of u32 in which each output bit depends only on the input
/// bits at or below it (Laine and Karras 2011, with the constants of
/// Vegdahl's 2021 improvement). On bit-reversed values that is a nested
/// uniform (Owen) scramble in base 2.
#[inline(always)]
pub fn lk_hash<B: Bits>(x: B, seed: B) -> B {
    let c = B::splat;
    let mut x = x ^ x.wrapping_mul(c(0x3d20_adea));
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | c(1));
    x = x ^ x.wrapping_mul(c(0x0552_6c56));
    x ^ x.wrapping_mul(c(0x53a2_2864))
}

/// Owen scrambling of a 32-bit fixed-point value in [0, 1).
#[inline(always)]
pub fn owen(v: u32, seed: u32) -> u32 {
    lk_hash(v.reverse_bits(), seed).reverse_bits()
}

/// Bit p of the result is the xor of the bits k of `i` whose set bits
/// include p's: Sobol's second generator matrix applied to `i`, before the
/// bit reversal.
#[inline(always)]
pub fn superset_sum<B: Bits>(mut y: B) -> B {
    let c = B::splat;
    y = y ^ ((y >> 1) & c(0x5555_5555));
    y = y ^ ((y >> 2) & c(0x3333_3333));
    y = y ^ ((y >> 4) & c(0x0F0F_0F0F));
    y = y ^ ((y >> 8) & c(0x00FF_00FF));
    y ^ ((y >> 16) & c(0x0000_FFFF))
}

/// Sobol point `i`, dimensions 0 and 1, unscrambled (32-bit fixed point).
pub fn sobol_2d(i: u32) -> (u32, u32) {
    (i.reverse_bits(), superset_sum(i).reverse_bits())
}

/// Hashed with the x value's seed into the y value's.
const Y_SEED: u32 = 0x2545_F491;

/// The seeds of one sample: the index shuffle's, and each value's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Seeds {
    pub index: u32,
    pub x: u32,
    pub y: u32,
}

impl Seeds {
    /// Three seeds from 64 hashed bits.
    #[inline(always)]
    pub fn from_bits(h: u64) -> Seeds {
        let (index, x) = (h as u32, (h >> 32) as u32);
        Seeds {
            index,
            x,
            y: y_seed(x),
        }
    }
}

/// The y value's seed, from the x value's.
#[inline(always)]
fn y_seed<B: Bits>(x: B) -> B {
    hash32(x ^ B::splat(Y_SEED))
}

/// A 32-bit integer hash (Wellons' lowbias32).
#[inline(always)]
pub fn hash32<B: Bits>(mut x: B) -> B {
    let c = B::splat;
    x = x ^ (x >> 16);
    x = x.wrapping_mul(c(0x7feb_352d));
    x = x ^ (x >> 15);
    x = x.wrapping_mul(c(0x846c_a68b));
    x ^ (x >> 16)
}

/// The shuffled index of point `index` (given bit-reversed): a nested
/// uniform scramble of the index, so that the first 2^m points are a
/// scrambled aligned block of the sequence.
#[inline(always)]
fn shuffled<B: Bits>(rindex: B, seed: B) -> B {
    lk_hash(rindex, seed).reverse_bits()
}

/// Point `index` (given bit-reversed) of the 1-D sequence `seed` names,
/// 32-bit fixed point: the van der Corput point of the shuffled index,
/// which is the shuffle's hash itself (`reverse(shuffled(..))`).
#[inline(always)]
pub fn sample_1d(rindex: u32, seed: u32) -> u32 {
    lk_hash(rindex, seed)
}

/// Point `index` (given bit-reversed) of the 2-D sequence `seeds` name,
/// 32-bit fixed point.
#[inline(always)]
pub fn sample_2d(rindex: u32, seeds: Seeds) -> (u32, u32) {
    sample_2d_lanes(rindex, [seeds.index, seeds.x, seeds.y])
}

/// [`sample_2d`] in every lane: the index and the seeds (index's, x's,
/// y's) per lane.
#[inline(always)]
pub fn sample_2d_lanes<B: Bits>(rindex: B, [index, x, y]: [B; 3]) -> (B, B) {
    let i = shuffled(rindex, index);
    (
        lk_hash(i, x).reverse_bits(),
        lk_hash(superset_sum(i), y).reverse_bits(),
    )
}

/// [`sample_2d`] of three sequences at the same index, each named by the
/// 64 bits [`Seeds::from_bits`] takes: the same numbers, computed lane for
/// lane over arrays, so that the compiler evaluates the three points'
/// hashes and bit reversals in SIMD registers (about a quarter less time
/// per point than three calls, `examples/sampler_variance.rs`;
/// docs/RENDERER.md).
#[inline(always)]
pub fn sample_2d_x3(rindex: u32, bits: [u64; 3]) -> [(u32, u32); 3] {
    // Four lanes (the last repeats the third) and eight: register widths.
    let bits = [bits[0], bits[1], bits[2], bits[2]];
    let x = U32s(bits.map(|b| (b >> 32) as u32));
    let y = y_seed(x);
    let i = shuffled(U32s::splat(rindex), U32s(bits.map(|b| b as u32)));
    let j = superset_sum(i);
    // The x values' hashes in lanes 0-3, the y values' in 4-7.
    let v = U32s::<8>(std::array::from_fn(
        |k| if k < 4 { i.0[k] } else { j.0[k - 4] },
    ));
    let seed = U32s::<8>(std::array::from_fn(
        |k| if k < 4 { x.0[k] } else { y.0[k - 4] },
    ));
    let v = lk_hash(v, seed).reverse_bits();
    [(v.0[0], v.0[4]), (v.0[1], v.0[5]), (v.0[2], v.0[6])]
}

/// A 32-bit fixed-point value as f32 in [0, 1) (its top 24 bits).
#[inline(always)]
pub fn unit_f32(v: u32) -> f32 {
    (v >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether `points` (2^m of them) form a (0,m,2)-net: for every split
    /// of m into x bits and y bits, each cell holds exactly one point.
    fn is_net(points: &[(u32, u32)], m: u32) -> bool {
        (0..=m).all(|bx| {
            let by = m - bx;
            let mut seen = vec![false; 1 << m];
            points.iter().all(|&(x, y)| {
                let cx = if bx == 0 { 0 } else { x >> (32 - bx) };
                let cy = if by == 0 { 0 } else { y >> (32 - by) };
                let cell = ((cx << by) | cy) as usize;
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn the_second_dimension_is_sobols() {
        // Direction numbers of dimension 1 (Joe and Kuo: s = 1, m = 1):
        // v_1 = 1 << 31, v_{j+1} = v_j ^ (v_j >> 1).
        let mut v = 1u32 << 31;
        for k in 0..32 {
            assert_eq!(sobol_2d(1 << k).1, v, "bit {k}");
            v ^= v >> 1;
        }
        // Linear over GF(2): a point is the xor of its bits' points.
        for i in [3u32, 5, 6, 0xDEAD_BEEF, u32::MAX] {
            let xor = (0..32)
                .filter(|k| i >> k & 1 == 1)
                .fold(0, |a, k| a ^ sobol_2d(1 << k).1);
            assert_eq!(sobol_2d(i).1, xor, "{i:#x}");
        }
    }

    #[test]
    fn scrambled_prefixes_are_nets_for_any_seeds() {
        let mut h = 0x1234_5678_9ABC_DEF0u64;
        for _ in 0..20 {
            h = crate::render::sampler::mix64(h);
            let seeds = Seeds::from_bits(h);
            for m in 0..=10u32 {
                let points: Vec<(u32, u32)> = (0..1u32 << m)
                    .map(|i| sample_2d(i.reverse_bits(), seeds))
                    .collect();
                assert!(is_net(&points, m), "seeds {seeds:?}, 2^{m} points");
                // Each coordinate alone is stratified too.
                let mut xs: Vec<u32> = points.iter().map(|p| p.0 >> (32 - m.max(1))).collect();
                xs.sort_unstable();
                if m > 0 {
                    assert_eq!(xs, (0..1u32 << m).collect::<Vec<_>>());
                }
            }
        }
        // Unscrambled too (the test must be able to fail: see below).
        let plain: Vec<(u32, u32)> = (0..256u32).map(sobol_2d).collect();
        assert!(is_net(&plain, 8));
        let random: Vec<(u32, u32)> = (0..256u64)
            .map(|i| {
                let b = crate::render::sampler::mix64(i);
                (b as u32, (b >> 32) as u32)
            })
            .collect();
        assert!(!is_net(&random, 8), "random points are no net");
    }

    #[test]
    fn one_dimension_is_stratified_and_values_are_in_range() {
        for seed in [0, 1, 0xFEED_FACE, u32::MAX] {
            for m in 0..=10u32 {
                let mut cells: Vec<u32> = (0..1u32 << m)
                    .map(|i| {
                        sample_1d(i.reverse_bits(), seed)
                            .checked_shr(32 - m)
                            .unwrap_or(0)
                    })
                    .collect();
                cells.sort_unstable();
                assert_eq!(
                    cells,
                    (0..1u32 << m).collect::<Vec<_>>(),
                    "seed {seed}, 2^{m}"
                );
            }
        }
        // Each prefix is also a prefix of the same order: point 1 lies in
        // the other half from point 0, points 2 and 3 in the other quarters.
        let p: Vec<u32> = (0..4u32)
            .map(|i| sample_1d(i.reverse_bits(), 7) >> 30)
            .collect();
        assert_eq!(p[0] >> 1 ^ p[1] >> 1, 1, "{p:?}");
        for v in [0, 1, 255, 256, u32::MAX] {
            let u = unit_f32(v);
            assert!((0.0..1.0).contains(&u), "{v}: {u}");
        }
    }

    #[test]
    fn seeds_change_the_points() {
        let a = Seeds::from_bits(1);
        let b = Seeds::from_bits(2);
        let pa: Vec<_> = (0..16u32).map(|i| sample_2d(i.reverse_bits(), a)).collect();
        let pb: Vec<_> = (0..16u32).map(|i| sample_2d(i.reverse_bits(), b)).collect();
        assert_ne!(pa, pb);
        assert_ne!(a.x, a.y, "the two coordinates scramble apart");
        let qa: Vec<_> = (0..16u32)
            .map(|i| sample_1d(i.reverse_bits(), a.index))
            .collect();
        let qb: Vec<_> = (0..16u32)
            .map(|i| sample_1d(i.reverse_bits(), b.index))
            .collect();
        assert_ne!(qa, qb);
    }

    #[test]
    fn three_at_once_are_the_three_points() {
        use crate::render::sampler::mix64;
        for k in 0..20_000u64 {
            let bits = [mix64(3 * k), mix64(3 * k + 1), mix64(3 * k + 2)];
            let rindex = mix64(!k) as u32;
            let one_by_one = bits.map(|b| sample_2d(rindex, Seeds::from_bits(b)));
            assert_eq!(sample_2d_x3(rindex, bits), one_by_one, "key {k}");
        }
    }
}
