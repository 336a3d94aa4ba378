//! Lane types: the renderer's numerics written once, for one path (`f32`,
//! `u32`) and for several paths at once (`F32s`, `U32s`: arrays whose
//! element-wise operations the compiler turns into SIMD instructions of the
//! instruction set the render loop is compiled for).
//!
//! A function generic over [`Real`] or [`Bits`] does the same IEEE and
//! integer operations in every lane that its `f32`/`u32` instance does on
//! one value, so each lane's result is the scalar result bit for bit (the
//! tests below hold every generic routine to it). Rust never contracts a
//! multiply and an add into a fused one, so nothing differs by width.
//! docs/RENDERER.md ("Wide paths on the CPU") says where this leads.

use glam::Vec3A;
use std::ops::{Add, BitAnd, BitOr, BitXor, Div, Mul, Neg, Not, Shl, Shr, Sub};

/// 32 bits per lane: hashes, masks and the bits of floats.
pub trait Bits:
    Copy
    + BitAnd<Output = Self>
    + BitOr<Output = Self>
    + BitXor<Output = Self>
    + Not<Output = Self>
    + Shl<u32, Output = Self>
    + Shr<u32, Output = Self>
{
    fn splat(x: u32) -> Self;
    fn wrapping_add(self, o: Self) -> Self;
    fn wrapping_sub(self, o: Self) -> Self;
    fn wrapping_mul(self, o: Self) -> Self;
    fn reverse_bits(self) -> Self;
}

/// An f32 per lane.
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    type Bits: Bits;
    fn splat(x: f32) -> Self;
    fn floor(self) -> Self;
    fn sqrt(self) -> Self;
    /// `f32::max` in every lane.
    fn max(self, o: Self) -> Self;
    /// `f32::copysign` in every lane.
    fn copysign(self, sign: Self) -> Self;
    fn to_bits(self) -> Self::Bits;
    fn from_bits(b: Self::Bits) -> Self;
    /// `x as i32 as u32` in every lane (saturating, as Rust converts).
    fn to_int_bits(self) -> Self::Bits;
    fn abs(self) -> Self;
    /// All ones in the lanes where `self > o` (false for NaN), else zero.
    fn gt(self, o: Self) -> Self::Bits;
}

impl Bits for u32 {
    #[inline(always)]
    fn splat(x: u32) -> Self {
        x
    }
    #[inline(always)]
    fn wrapping_add(self, o: Self) -> Self {
        u32::wrapping_add(self, o)
    }
    #[inline(always)]
    fn wrapping_sub(self, o: Self) -> Self {
        u32::wrapping_sub(self, o)
    }
    #[inline(always)]
    fn wrapping_mul(self, o: Self) -> Self {
        u32::wrapping_mul(self, o)
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        u32::reverse_bits(self)
    }
}

impl Real for f32 {
    type Bits = u32;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        x
    }
    #[inline(always)]
    fn floor(self) -> Self {
        f32::floor(self)
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32::max(self, o)
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        f32::copysign(self, sign)
    }
    #[inline(always)]
    fn to_bits(self) -> u32 {
        f32::to_bits(self)
    }
    #[inline(always)]
    fn from_bits(b: u32) -> Self {
        f32::from_bits(b)
    }
    #[inline(always)]
    fn to_int_bits(self) -> u32 {
        self as i32 as u32
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn gt(self, o: Self) -> u32 {
        if self > o {
            u32::MAX
        } else {
            0
        }
    }
}

/// `N` u32 lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct U32s<const N: usize>(pub [u32; N]);

/// `N` f32 lanes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct F32s<const N: usize>(pub [f32; N]);

/// Element-wise binary operators of a lane array type.
macro_rules! lanewise {
    ($t:ident, $($trait:ident $f:ident),*) => {$(
        impl<const N: usize> $trait for $t<N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Self(std::array::from_fn(|k| $trait::$f(self.0[k], o.0[k])))
            }
        }
    )*};
}

lanewise!(U32s, BitAnd bitand, BitOr bitor, BitXor bitxor);
lanewise!(F32s, Add add, Sub sub, Mul mul, Div div);

impl<const N: usize> Not for U32s<N> {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        Self(self.0.map(|x| !x))
    }
}

impl<const N: usize> Shl<u32> for U32s<N> {
    type Output = Self;
    #[inline(always)]
    fn shl(self, s: u32) -> Self {
        Self(self.0.map(|x| x << s))
    }
}

impl<const N: usize> Shr<u32> for U32s<N> {
    type Output = Self;
    #[inline(always)]
    fn shr(self, s: u32) -> Self {
        Self(self.0.map(|x| x >> s))
    }
}

impl<const N: usize> Neg for F32s<N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self(self.0.map(|x| -x))
    }
}

impl<const N: usize> Bits for U32s<N> {
    #[inline(always)]
    fn splat(x: u32) -> Self {
        Self([x; N])
    }
    #[inline(always)]
    fn wrapping_add(self, o: Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k].wrapping_add(o.0[k])))
    }
    #[inline(always)]
    fn wrapping_sub(self, o: Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k].wrapping_sub(o.0[k])))
    }
    #[inline(always)]
    fn wrapping_mul(self, o: Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k].wrapping_mul(o.0[k])))
    }
    #[inline(always)]
    fn reverse_bits(self) -> Self {
        Self(self.0.map(u32::reverse_bits))
    }
}

impl<const N: usize> Real for F32s<N> {
    type Bits = U32s<N>;
    #[inline(always)]
    fn splat(x: f32) -> Self {
        Self([x; N])
    }
    #[inline(always)]
    fn floor(self) -> Self {
        Self(self.0.map(f32::floor))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Self(self.0.map(f32::sqrt))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k].max(o.0[k])))
    }
    #[inline(always)]
    fn copysign(self, sign: Self) -> Self {
        Self(std::array::from_fn(|k| self.0[k].copysign(sign.0[k])))
    }
    #[inline(always)]
    fn to_bits(self) -> U32s<N> {
        U32s(self.0.map(f32::to_bits))
    }
    #[inline(always)]
    fn from_bits(b: U32s<N>) -> Self {
        Self(b.0.map(f32::from_bits))
    }
    #[inline(always)]
    fn to_int_bits(self) -> U32s<N> {
        U32s(self.0.map(|x| x as i32 as u32))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Self(self.0.map(f32::abs))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> U32s<N> {
        U32s(std::array::from_fn(|k| {
            if self.0[k] > o.0[k] {
                u32::MAX
            } else {
                0
            }
        }))
    }
}

/// A three-component vector: glam's `Vec3A` for one path (the scalar
/// loop's own type, so its code is what it was), [`V3`] of lane arrays for
/// several. Each component's operations are the same IEEE operations.
pub trait Vector:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Neg<Output = Self>
    + Mul<Self::R, Output = Self>
    + Div<Self::R, Output = Self>
{
    type R: Real;
    fn new(x: Self::R, y: Self::R, z: Self::R) -> Self;
    fn x(self) -> Self::R;
    fn y(self) -> Self::R;
    fn z(self) -> Self::R;
    /// `v` in every lane.
    fn splat_vec(v: Vec3A) -> Self;
    /// The dot product, summed x, then y, then z (as glam's).
    fn dot(self, o: Self) -> Self::R;
    #[inline(always)]
    fn length_squared(self) -> Self::R {
        self.dot(self)
    }
    /// Divided by its length (as glam's: each component by the length).
    #[inline(always)]
    fn normalize(self) -> Self {
        self / self.length_squared().sqrt()
    }
}

impl Vector for Vec3A {
    type R = f32;
    #[inline(always)]
    fn new(x: f32, y: f32, z: f32) -> Self {
        Vec3A::new(x, y, z)
    }
    #[inline(always)]
    fn x(self) -> f32 {
        self.x
    }
    #[inline(always)]
    fn y(self) -> f32 {
        self.y
    }
    #[inline(always)]
    fn z(self) -> f32 {
        self.z
    }
    #[inline(always)]
    fn splat_vec(v: Vec3A) -> Self {
        v
    }
    #[inline(always)]
    fn dot(self, o: Self) -> f32 {
        Vec3A::dot(self, o)
    }
    #[inline(always)]
    fn normalize(self) -> Self {
        Vec3A::normalize(self)
    }
}

/// A vector per lane, a component at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct V3<R> {
    pub x: R,
    pub y: R,
    pub z: R,
}

impl<R: Real> Add for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl<R: Real> Sub for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl<R: Real> Neg for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl<R: Real> Mul<R> for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: R) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

impl<R: Real> Div<R> for V3<R> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: R) -> Self {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

impl<R: Real> Vector for V3<R> {
    type R = R;
    #[inline(always)]
    fn new(x: R, y: R, z: R) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    fn x(self) -> R {
        self.x
    }
    #[inline(always)]
    fn y(self) -> R {
        self.y
    }
    #[inline(always)]
    fn z(self) -> R {
        self.z
    }
    #[inline(always)]
    fn splat_vec(v: Vec3A) -> Self {
        V3 {
            x: R::splat(v.x),
            y: R::splat(v.y),
            z: R::splat(v.z),
        }
    }
    #[inline(always)]
    fn dot(self, o: Self) -> R {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
}

/// Bit `k` set where lane `k` of `mask` is true: eight lanes at a time, a
/// multiply gathering the low bit of each of eight bytes into the top
/// byte (a bool is one byte, 0 or 1), not a shift and an or a lane.
#[inline(always)]
pub fn mask_bits<const W: usize>(mask: &[bool; W]) -> u32 {
    const { assert!(W <= 32) };
    let bytes = mask.map(u8::from);
    let mut bits = 0u32;
    let mut k = 0;
    while k + 8 <= W {
        let mut chunk = [0u8; 8];
        chunk.copy_from_slice(&bytes[k..k + 8]);
        let gathered = u64::from_le_bytes(chunk).wrapping_mul(0x0102_0408_1020_4080) >> 56;
        bits |= (gathered as u32) << k;
        k += 8;
    }
    while k < W {
        bits |= u32::from(bytes[k]) << k;
        k += 1;
    }
    bits
}

/// The lanes where `mask` is true, in increasing order. A loop over them
/// branches once a lane taken; a loop that tests every lane branches on
/// each test, and where lanes are paths the outcomes are as good as
/// random: a mispredicted branch each, some fifteen cycles.
#[inline(always)]
pub fn lanes_where<const W: usize>(mask: &[bool; W]) -> impl Iterator<Item = usize> {
    let mut bits = mask_bits(mask);
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let k = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            k
        })
    })
}

#[cfg(test)]
#[path = "lanes_tests.rs"]
mod tests;
