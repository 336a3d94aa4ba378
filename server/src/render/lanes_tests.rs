//! Every lane of a generic routine against its scalar instance, bit for bit.

use super::*;
use crate::render::math::sincos_turns;
use crate::render::sampler::sobol::{hash32, lk_hash, sample_2d_lanes};
use crate::render::sampler::{mix64, Sampler};

/// `N` values from key `k`: hashed bits, made floats by `f`.
fn lanes<const N: usize, T>(k: u64, f: impl Fn(u64) -> T) -> [T; N] {
    std::array::from_fn(|i| f(mix64(k ^ (i as u64) << 40)))
}

/// Floats that corner the routines: 0, quarter turns and their
/// neighbours, the largest below 1, negatives, huge values and NaN.
const CORNERS: [f32; 16] = [
    0.0,
    0.25,
    0.5,
    0.75,
    0.249_999_99,
    0.250_000_03,
    0.999_999_94,
    1e-30,
    -0.0,
    -0.3,
    -2.5,
    3.5e9,
    -3.5e9,
    f32::INFINITY,
    f32::NAN,
    7.0,
];

/// An operation's name, its lanes' results, and the scalar operation.
type Op = (&'static str, F32s<16>, fn(f32, f32) -> f32);

/// The same bits, any NaN matching any NaN: Rust leaves the sign and
/// payload of a NaN that arithmetic makes unspecified, and they differ
/// between one the compiler folds from constants and one the processor
/// makes (sincos_turns of an infinity: sin 0xffc00000 folded, 0x7fc00000
/// computed), so whether the test's scalar call was folded decided it.
/// A NaN against a number still fails.
fn same_bits(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

#[test]
fn every_lane_of_sincos_turns_is_the_scalar_one() {
    fn check<const N: usize>(u: [f32; N]) {
        let (s, c) = sincos_turns(F32s(u));
        for (k, &uk) in u.iter().enumerate() {
            let (s1, c1) = sincos_turns(uk);
            assert!(
                same_bits(s.0[k], s1) && same_bits(c.0[k], c1),
                "u {uk} lane {k} of {N}"
            );
        }
    }
    check(CORNERS);
    for key in 0..20_000u64 {
        let mut s = Sampler::new(3, key, 0);
        check::<8>(std::array::from_fn(|_| s.next_f32()));
        check::<16>(std::array::from_fn(|_| s.next_f32()));
    }
}

#[test]
fn every_lane_of_the_float_operations_is_the_scalar_one() {
    let a = F32s(CORNERS);
    let mut b = CORNERS;
    b.rotate_left(5);
    let b = F32s(b);
    let ops: [Op; 9] = [
        ("add", a + b, |x, y| x + y),
        ("sub", a - b, |x, y| x - y),
        ("mul", a * b, |x, y| x * y),
        ("div", a / b, |x, y| x / y),
        ("max", a.max(b), f32::max),
        ("copysign", a.copysign(b), f32::copysign),
        ("neg", -a, |x, _| -x),
        ("floor", a.floor(), |x, _| x.floor()),
        ("sqrt", a.sqrt(), |x, _| x.sqrt()),
    ];
    for (name, wide, one) in ops {
        for k in 0..16 {
            let want = one(a.0[k], b.0[k]);
            assert!(
                same_bits(wide.0[k], want),
                "{name} lane {k}: {} for {want}",
                wide.0[k]
            );
        }
    }
    let ints = a.to_int_bits();
    let bits = a.to_bits();
    for k in 0..16 {
        assert_eq!(ints.0[k], a.0[k] as i32 as u32, "to_int_bits lane {k}");
        assert_eq!(F32s::from_bits(bits).0[k].to_bits(), a.0[k].to_bits());
    }
}

#[test]
fn every_lane_of_the_hashes_and_sobol_points_is_the_scalar_one() {
    for key in 0..20_000u64 {
        let x: [u32; 8] = lanes(key, |h| h as u32);
        let seed: [u32; 8] = lanes(key + (1 << 20), |h| (h >> 32) as u32);
        let (wx, ws) = (U32s(x), U32s(seed));
        let (h, l) = (hash32(wx), lk_hash(wx, ws));
        let index: [u32; 8] = lanes(key + (2 << 20), |h| h as u32);
        let (px, py) = sample_2d_lanes(ws, [U32s(index), wx, h]);
        for k in 0..8 {
            assert_eq!(h.0[k], hash32(x[k]), "hash32, key {key} lane {k}");
            assert_eq!(
                l.0[k],
                lk_hash(x[k], seed[k]),
                "lk_hash, key {key} lane {k}"
            );
            let one = sample_2d_lanes(seed[k], [index[k], x[k], hash32(x[k])]);
            assert_eq!((px.0[k], py.0[k]), one, "sample_2d, key {key} lane {k}");
        }
    }
    // Shifts, rotations of bits, wrapping arithmetic at the edges.
    let a = U32s([0, 1, 2, u32::MAX, 1 << 31, 0x8000_0001, 12345, 0xdead_beef]);
    let b = U32s([u32::MAX, 3, 0, 2, 1 << 31, 7, 0xffff, 1]);
    for k in 0..8 {
        let (x, y) = (a.0[k], b.0[k]);
        assert_eq!(a.wrapping_add(b).0[k], x.wrapping_add(y));
        assert_eq!(a.wrapping_sub(b).0[k], x.wrapping_sub(y));
        assert_eq!(a.wrapping_mul(b).0[k], x.wrapping_mul(y));
        assert_eq!(a.reverse_bits().0[k], x.reverse_bits());
        assert_eq!((!a).0[k], !x);
        assert_eq!((a << 7).0[k], x << 7);
        assert_eq!((a >> 9).0[k], x >> 9);
        assert_eq!((a & b).0[k], x & y);
        assert_eq!((a | b).0[k], x | y);
        assert_eq!((a ^ b).0[k], x ^ y);
    }
}

#[test]
fn every_lane_of_the_basis_and_cosine_sampling_is_the_scalar_one() {
    use crate::render::material::cosine_hemisphere;
    use crate::render::math::{basis, Vec3A};
    type L = F32s<8>;
    let same = |w: V3<L>, k: usize, v: Vec3A| {
        same_bits(w.x.0[k], v.x) && same_bits(w.y.0[k], v.y) && same_bits(w.z.0[k], v.z)
    };
    // Normals all round, the poles and the equator (n.z = +-0) included.
    let corners = [
        Vec3A::Z,
        -Vec3A::Z,
        Vec3A::X,
        Vec3A::new(0.0, -1.0, -0.0),
        Vec3A::new(0.6, 0.0, 0.8),
        Vec3A::new(0.0, 0.6, -0.8),
    ];
    for key in 0..20_000u64 {
        let mut s = Sampler::new(5, key, 0);
        let n: [Vec3A; 8] = std::array::from_fn(|k| match corners.get(k) {
            Some(&c) if key == 0 => c,
            _ => {
                let z = 1.0 - 2.0 * s.next_f32();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (sin, cos) = sincos_turns(s.next_f32());
                Vec3A::new(r * cos, r * sin, z)
            }
        });
        let (u1, u2): ([f32; 8], [f32; 8]) = (
            std::array::from_fn(|_| s.next_f32()),
            std::array::from_fn(|_| s.next_f32()),
        );
        let wide = V3 {
            x: F32s(n.map(|v| v.x)),
            y: F32s(n.map(|v| v.y)),
            z: F32s(n.map(|v| v.z)),
        };
        let (t, b) = basis(wide);
        let d = cosine_hemisphere(wide, F32s(u1), F32s(u2));
        for k in 0..8 {
            let (t1, b1) = basis(n[k]);
            assert!(same(t, k, t1) && same(b, k, b1), "basis of {:?}", n[k]);
            let d1 = cosine_hemisphere(n[k], u1[k], u2[k]);
            assert!(
                same(d, k, d1),
                "direction about {:?}, u {} {}",
                n[k],
                u1[k],
                u2[k]
            );
        }
    }
}

#[test]
fn lanes_where_names_the_true_lanes_in_order() {
    fn check<const W: usize>(key: u64) {
        let mask: [bool; W] = lanes(key, |b| b & 1 == 1);
        let got: Vec<usize> = lanes_where(&mask).collect();
        let want: Vec<usize> = (0..W).filter(|&k| mask[k]).collect();
        assert_eq!(got, want, "{mask:?}");
    }
    for key in 0..200 {
        check::<4>(key);
        check::<8>(key);
        check::<16>(key);
    }
    assert_eq!(lanes_where(&[true; 16]).count(), 16);
    assert_eq!(lanes_where(&[false; 16]).count(), 0);
}
