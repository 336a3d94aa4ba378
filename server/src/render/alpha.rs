//! Alpha-tested surfaces (glTF's `alphaMode`): a mesh triangle whose
//! material is `MASK` or `BLEND` is only hit where its alpha (the base
//! colour's alpha factor times its texture's alpha channel) lets the ray
//! stop; elsewhere every ray (camera, bounce, shadow) passes through it.
//!
//! - `MASK`: the surface is there where alpha >= cutoff.
//! - `BLEND`: there with probability alpha (stochastic transparency), the
//!   random number a hash of the ray and the triangle ([`blend_u`]), so
//!   that a ray meets the same surfaces on every backend and any thread
//!   count.
//!
//! The test runs inside the intersection search, only for instances that
//! have such a material (`Instance::alpha`); other meshes pay nothing.
//! `kernels/triangles.h` (`alpha_passes`) mirrors it.

use crate::render::math::Vec3A;
use crate::render::sampler::sobol::hash32;
use crate::render::shape::Mesh;
use crate::render::texture::{self, Sampling, Texture};
use std::sync::Arc;

pub use crate::material_maps::AlphaMode;

/// One material slot's test.
#[derive(Clone, Debug)]
pub struct AlphaTest {
    pub mode: AlphaMode,
    /// The base colour factor's alpha.
    pub factor: f32,
    /// The base colour texture, whose alpha channel multiplies `factor`.
    pub texture: Option<(Arc<Texture>, Sampling)>,
}

impl AlphaTest {
    pub const OPAQUE: AlphaTest = AlphaTest {
        mode: AlphaMode::Opaque,
        factor: 1.0,
        texture: None,
    };

    /// The alpha of triangle `prim` of `mesh` at barycentrics `bary`.
    #[inline(always)]
    pub fn alpha(&self, mesh: &Mesh, prim: u32, bary: [f32; 3]) -> f32 {
        match &self.texture {
            None => self.factor,
            Some((t, s)) => {
                let uv = mesh.uv(s.uv as usize & 1, prim, bary);
                self.factor * texture::lookup(t, s, uv, false)[3]
            }
        }
    }

    /// Whether a ray from `o` along `d` stops at triangle `prim` of `mesh`
    /// at barycentrics `bary`. Out of line: inlined into the traversal, the
    /// part of `blend_u`'s hash that does not depend on the triangle was
    /// hoisted to the start of every ray's search and computed for every
    /// ray of every scene (75 instructions, 4% of a `cornell-mesh` sample's).
    #[inline(never)]
    pub fn passes(&self, mesh: &Mesh, prim: u32, bary: [f32; 3], o: Vec3A, d: Vec3A) -> bool {
        match self.mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask(cutoff) => self.alpha(mesh, prim, bary) >= cutoff,
            AlphaMode::Blend => blend_u(o, d, prim) < self.alpha(mesh, prim, bary),
        }
    }
}

/// A number in [0, 1) from a ray (origin `o`, direction `d`, camera
/// space) and a triangle: the bits of all seven mixed (a 32-bit
/// multiply-xorshift hash, which the kernel computes identically).
#[inline(always)]
pub fn blend_u(o: Vec3A, d: Vec3A, prim: u32) -> f32 {
    let words = [
        o.x.to_bits(),
        o.y.to_bits(),
        o.z.to_bits(),
        d.x.to_bits(),
        d.y.to_bits(),
        d.z.to_bits(),
        prim,
    ];
    let mut h: u32 = 0x9E37_79B9;
    for w in words {
        h = hash32(h ^ w);
    }
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_numbers_are_uniform_and_depend_on_every_input() {
        // 20 bins of 100,000 rays: chi-square against uniform.
        let n = 100_000u32;
        let mut bins = [0u32; 20];
        for i in 0..n {
            let f = i as f32;
            let u = blend_u(
                Vec3A::new(f * 0.001, 1.0, -f),
                Vec3A::new(0.0, 0.6, 0.8),
                i % 7,
            );
            assert!((0.0..1.0).contains(&u));
            bins[(u * 20.0) as usize] += 1;
        }
        let e = f64::from(n) / 20.0;
        let chi2: f64 = bins.iter().map(|&b| (f64::from(b) - e).powi(2) / e).sum();
        // 19 degrees of freedom: p = 1e-4 at 48.
        assert!(chi2 < 48.0, "chi2 {chi2}: {bins:?}");
        let base = blend_u(Vec3A::ONE, Vec3A::Z, 3);
        assert_ne!(base, blend_u(Vec3A::ONE, Vec3A::Z, 4));
        assert_ne!(base, blend_u(Vec3A::new(1.0, 1.0, 1.5), Vec3A::Z, 3));
        assert_ne!(base, blend_u(Vec3A::ONE, Vec3A::Y, 3));
    }
}
