//! The instruction sets the CPU hot path is compiled for, as zero-sized
//! tokens: the render loop is generic over one and inlined whole into a
//! function compiled for it, so that the token's wide kernels and all the
//! code around them use the same registers and instructions.
//!
//! [`Portable`] runs on every CPU (SSE2 on x86-64). [`Avx2`] can only be
//! made by [`Avx2::detect`], on a CPU that has AVX2 and FMA; holding one is
//! what makes calling its kernels sound.

use crate::render::bvh::{self, BoxRay, WideNode, WideTest, WIDTH};
use crate::render::ray::Ray;
use crate::render::shape::{Leaving, SphereBatch};

/// The wide kernels of one instruction set
/// (and the test of a wide BVH node's eight boxes, [`WideTest`]).
pub trait Isa: Copy + Send + Sync + WideTest {
    /// Nearest sphere hit over `batches`: (distance, object index as f32),
    /// distance infinity when there is none. Same result on every `Isa`.
    fn nearest_sphere(self, batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32);

    /// This token as an [`Avx2`], if it is one (a constant of the type):
    /// what picks the copy of an out-of-line function compiled for it
    /// (`World::intersect`).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx2(self) -> Option<Avx2> {
        None
    }

    /// This token as an [`Avx512`], if it is one (as [`Isa::avx2`]).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx512(self) -> Option<Avx512> {
        None
    }
}

/// Four-lane code that every CPU runs.
#[derive(Clone, Copy, Debug)]
pub struct Portable;

impl WideTest for Portable {
    #[inline(always)]
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        bvh::test_portable(ray, node, t_max)
    }
}

impl Isa for Portable {
    #[inline(always)]
    fn nearest_sphere(self, batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32) {
        SphereBatch::nearest(batches, ray, from)
    }
}

/// Eight-lane AVX2 code; proof that the CPU has AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Avx2(());

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The token, if this CPU has AVX2 and FMA.
    pub fn detect() -> Option<Self> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Self(()))
    }
}

#[cfg(target_arch = "x86_64")]
impl WideTest for Avx2 {
    #[inline(always)]
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        // SAFETY: an `Avx2` exists only where `detect` found AVX2 and FMA.
        #[allow(unsafe_code)]
        unsafe {
            bvh::test_avx2(ray, node, t_max)
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl Isa for Avx2 {
    #[inline(always)]
    fn nearest_sphere(self, batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32) {
        // SAFETY: an `Avx2` exists only where `detect` found AVX2 and FMA.
        #[allow(unsafe_code)]
        unsafe {
            crate::render::shape::nearest_sphere_avx2(batches, ray, from)
        }
    }

    #[inline(always)]
    fn avx2(self) -> Option<Avx2> {
        Some(self)
    }
}

/// The AVX2 kernels in code compiled for AVX-512 (F, VL, BW, DQ): the
/// same arithmetic, with 32 vector registers and mask registers for the
/// compiler. Proof that the CPU has AVX-512 as well as AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub struct Avx512(());

#[cfg(target_arch = "x86_64")]
impl Avx512 {
    /// The token, if this CPU has AVX-512 F, VL, BW and DQ, AVX2 and FMA.
    pub fn detect() -> Option<Self> {
        let avx512 = is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512vl")
            && is_x86_feature_detected!("avx512bw")
            && is_x86_feature_detected!("avx512dq");
        (avx512 && Avx2::detect().is_some()).then_some(Self(()))
    }

    /// The AVX2 token this one implies.
    #[inline(always)]
    pub fn avx2(self) -> Avx2 {
        Avx2(())
    }
}

#[cfg(target_arch = "x86_64")]
impl WideTest for Avx512 {
    #[inline(always)]
    fn wide_test(self, ray: &BoxRay, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        Avx512::avx2(self).wide_test(ray, node, t_max)
    }
}

#[cfg(target_arch = "x86_64")]
impl Isa for Avx512 {
    #[inline(always)]
    fn nearest_sphere(self, batches: &[SphereBatch], ray: &Ray, from: Leaving) -> (f32, f32) {
        Avx512::avx2(self).nearest_sphere(batches, ray, from)
    }

    #[inline(always)]
    fn avx512(self) -> Option<Avx512> {
        Some(self)
    }
}
