//! The rough dielectric lobe of glTF's transmission
//! (`KHR_materials_transmission` with `KHR_materials_ior`): Walter et al.'s
//! (2007) microfacet BSDF over the same GGX distribution and height-
//! correlated Smith term as the reflection lobes, with the exact
//! (unpolarised) Fresnel equations per microfacet. Sampling draws a visible
//! normal, then reflects with probability F and refracts otherwise, so a
//! sample's weight is G2 / G1(wo) whichever way it went.
//!
//! Directions are in the shading frame with `wo` above (z > 0); `eta` is
//! the index on the far side over the index on `wo`'s side. Radiance that
//! crosses is not scaled by eta^2, as for smooth `glass` (a closed object's
//! entry and exit scalings cancel), so the BTDF obeys f(wo, wi) = eta^2
//! f(wi, wo).
//!
//! A thin wall (glTF's transmission without `KHR_materials_volume`) has
//! air on both sides: what it transmits is its reflection mirrored through
//! the surface (rough but unrefracted), F from the index either way, so its
//! single-scattering albedo is the reflection lobe's white E(mu_o), which
//! the metallic-roughness tables already hold.
//!
//! Energy: single scattering loses the light that bounces among the
//! microfacets (a white rough glass sphere goes grey). The lobe is divided
//! by its white albedo E(mu_o) (Turquin's 2019 scaling), read from
//! [`Table`]: E by cos(theta_o), roughness and index, for light arriving
//! from outside and from inside, integrated on first use (scenes that do
//! not transmit never pay for it). The kernel (`kernels/ggx.h`) gets the
//! same floats and mirrors every routine here.

use super::{distribution, reflect_about, smith_r, visible_normal, ALPHA_MIN, TABLE_N};
use crate::render::fresnel;
use crate::render::math::Vec3A;
use crate::render::sampler::sobol::sobol_2d;
use rayon::prelude::*;
use std::sync::OnceLock;

/// Points on the table's index axis, x = (ior - 1) / (ior + 1) from 0 to
/// 1 / [`IOR_SCALE`] = 0.8 (ior 1 to 9; larger indices read the last).
pub const IOR_N: usize = 17;
pub const IOR_SCALE: f32 = 1.25;
/// Floats in [`Table::data`]: by side (0: arriving from outside, eta =
/// ior; 1: from inside, eta = 1 / ior), index, roughness, cos(theta_o).
pub const TABLE_LEN: usize = 2 * IOR_N * TABLE_N * TABLE_N;
/// Points per table entry (a Sobol (0,2)-sequence).
const TABLE_POINTS: u32 = 512;

/// The white albedo of the single-scattering lobe.
pub struct Table {
    pub data: Box<[f32]>,
}

/// The table, integrated once per process on first use.
pub fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(Table::integrate)
}

/// The table's index coordinate of `ior`.
#[inline(always)]
fn ior_x(ior: f32) -> f32 {
    (ior - 1.0) / (ior + 1.0)
}

impl Table {
    fn integrate() -> Table {
        let n = TABLE_N;
        let points: Vec<(f32, f32)> = (0..TABLE_POINTS)
            .map(|k| {
                let (x, y) = sobol_2d(k);
                let u = |b: u32| ((f64::from(b) + 0.5) / 4_294_967_296.0) as f32;
                (u(x), u(y))
            })
            .collect();
        let mut data = vec![0.0f32; TABLE_LEN];
        data.par_chunks_mut(n).enumerate().for_each(|(row, out)| {
            let j = row % n;
            let k = (row / n) % IOR_N;
            let side = row / (n * IOR_N);
            let x = k as f32 / (IOR_N - 1) as f32 / IOR_SCALE;
            let ior = (1.0 + x) / (1.0 - x);
            let eta = if side == 0 { ior } else { 1.0 / ior };
            let r = j as f32 / (n - 1) as f32;
            let alpha = (r * r).max(ALPHA_MIN);
            for (i, e) in out.iter_mut().enumerate() {
                let mu = (i as f32 / (n - 1) as f32).max(1e-4);
                let wo = Vec3A::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let mut sum = 0.0f64;
                for &(u1, u2) in &points {
                    let h = visible_normal(wo, alpha, u1, u2);
                    let (f, wt) = split(wo, h, eta);
                    let wr = reflect_about(wo, h);
                    if wr.z > 0.0 {
                        sum += f64::from(f * masking_ratio(wo, wr, alpha));
                    }
                    if f < 1.0 && wt.z < 0.0 {
                        sum += f64::from((1.0 - f) * masking_ratio(wo, wt, alpha));
                    }
                }
                *e = (sum / f64::from(TABLE_POINTS)) as f32;
            }
        });
        Table {
            data: data.into_boxed_slice(),
        }
    }

    /// E(mu) at `roughness` and `ior`, for light arriving from outside
    /// (`entering`) or inside: trilinear.
    #[inline(always)]
    pub fn albedo(&self, mu: f32, roughness: f32, ior: f32, entering: bool) -> f32 {
        let n = TABLE_N;
        let (i, tx) = super::cell(mu);
        let (j, ty) = super::cell(roughness);
        let s = (ior_x(ior) * IOR_SCALE).clamp(0.0, 1.0) * (IOR_N - 1) as f32;
        let k = (s as usize).min(IOR_N - 2);
        let tz = s - k as f32;
        let side = usize::from(!entering);
        let plane = |k: usize| {
            let t = &self.data[(side * IOR_N + k) * n * n..];
            let row0 = t[j * n + i] * (1.0 - tx) + t[j * n + i + 1] * tx;
            let row1 = t[(j + 1) * n + i] * (1.0 - tx) + t[(j + 1) * n + i + 1] * tx;
            row0 * (1.0 - ty) + row1 * ty
        };
        plane(k) * (1.0 - tz) + plane(k + 1) * tz
    }
}

/// G2(wo, wi) / G1(wo), height-correlated, wi on either side.
#[inline(always)]
fn masking_ratio(wo: Vec3A, wi: Vec3A, alpha: f32) -> f32 {
    let (ro, ri) = (smith_r(wo, alpha), smith_r(wi, alpha));
    let ci = wi.z.abs();
    (wo.z + ro) * ci / (ro * ci + ri * wo.z)
}

/// The Fresnel reflectance at microfacet `h` seen from `wo` (wo . h > 0)
/// and the refracted direction (meaningless where the reflectance is 1).
#[inline(always)]
fn split(wo: Vec3A, h: Vec3A, eta: f32) -> (f32, Vec3A) {
    let c = wo.dot(h).max(0.0);
    let s = fresnel::exact(c, 1.0, eta);
    let wt = (h * (c / eta - s.cos_t) - wo / eta).normalize();
    (s.reflectance, wt)
}

/// How near 1 the ratio of indices makes a solid index-matched
/// ([`Glass::matched`]): its Fresnel reflectance is below 3e-7 there.
pub const MATCHED: f32 = 1e-3;

/// The lobe at one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Glass {
    pub alpha: f32,
    /// The far side's index over `wo`'s side's.
    pub eta: f32,
    /// 1 / E(mu_o): the energy compensation.
    pub scale: f32,
    /// A thin wall: transmission is the reflection mirrored.
    pub thin: bool,
}

impl Glass {
    /// The lobe of a surface of index `ior` at `roughness` (alpha its
    /// square, at least [`ALPHA_MIN`]) seen from `wo`, arriving from
    /// outside (`entering`) or inside.
    #[inline(always)]
    pub fn new(alpha: f32, roughness: f32, ior: f32, wo: Vec3A, entering: bool) -> Glass {
        let e = table().albedo(wo.z, roughness, ior, entering);
        Glass {
            alpha,
            eta: if entering { ior } else { 1.0 / ior },
            scale: 1.0 / e.max(0.05),
            thin: false,
        }
    }

    /// A thin wall of index `ior`, `scale` = 1 / the reflection lobe's
    /// white E(mu_o).
    #[inline(always)]
    pub fn thin(alpha: f32, ior: f32, scale: f32) -> Glass {
        Glass {
            alpha,
            eta: ior,
            scale,
            thin: true,
        }
    }

    /// Index-matched (a solid within [`MATCHED`] of its surroundings'
    /// index): light crosses unbent and unreflected, a delta lobe (where
    /// the microfacet BTDF's half vector is undefined).
    #[inline(always)]
    pub fn matched(&self) -> bool {
        !self.thin && (self.eta - 1.0).abs() < MATCHED
    }

    /// [`eval_cos`](Self::eval_cos) of a thin wall.
    #[inline(always)]
    fn thin_eval_cos(&self, wo: Vec3A, wi: Vec3A) -> (f32, f32) {
        let w = Vec3A::new(wi.x, wi.y, wi.z.abs());
        let a = self.alpha;
        let (ro, ri) = (smith_r(wo, a), smith_r(w, a));
        let h = (wo + w).normalize();
        let f = fresnel::exact(wo.dot(h).max(0.0), 1.0, self.eta).reflectance;
        let spec = distribution(h, a) / (2.0 * (ro * w.z + ri * wo.z)) * w.z * self.scale;
        match wi.z > 0.0 {
            true => (f * spec, 0.0),
            false => (0.0, (1.0 - f) * spec),
        }
    }

    /// The half vector of a refraction from `wo` to `wi` (wi.z < 0),
    /// facing `wo`'s side; None where no microfacet refracts `wo` to `wi`.
    #[inline(always)]
    fn refraction_half(&self, wo: Vec3A, wi: Vec3A) -> Option<Vec3A> {
        let v = wo + wi * self.eta;
        let len = v.length();
        if !(len > 0.0) {
            return None;
        }
        let h = if v.z < 0.0 { -v / len } else { v / len };
        (wo.dot(h) > 0.0 && wi.dot(h) < 0.0).then_some(h)
    }

    /// BSDF |cos(theta_i)| from `wo` to `wi`: (reflected, transmitted),
    /// white (the caller tints what is transmitted), compensation included.
    #[inline(always)]
    pub fn eval_cos(&self, wo: Vec3A, wi: Vec3A) -> (f32, f32) {
        if self.thin {
            return self.thin_eval_cos(wo, wi);
        }
        let a = self.alpha;
        let (ro, ri) = (smith_r(wo, a), smith_r(wi, a));
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let f = fresnel::exact(wo.dot(h).max(0.0), 1.0, self.eta).reflectance;
            let spec = distribution(h, a) / (2.0 * (ro * wi.z + ri * wo.z));
            return (f * spec * wi.z * self.scale, 0.0);
        }
        let Some(h) = self.refraction_half(wo, wi) else {
            return (0.0, 0.0);
        };
        let (oh, ih) = (wo.dot(h), -wi.dot(h));
        let f = fresnel::exact(oh, 1.0, self.eta).reflectance;
        let ci = -wi.z;
        let denom = oh - self.eta * ih;
        let t = (1.0 - f) * distribution(h, a) * self.eta * self.eta * oh * ih * 2.0 * ci
            / ((ro * ci + ri * wo.z) * (denom * denom));
        (0.0, t * self.scale)
    }

    /// The density of drawing `wi` from `wo` (solid angle).
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let a = self.alpha;
        let ro = smith_r(wo, a);
        if self.thin {
            let w = Vec3A::new(wi.x, wi.y, wi.z.abs());
            let h = (wo + w).normalize();
            let f = fresnel::exact(wo.dot(h).max(0.0), 1.0, self.eta).reflectance;
            let vndf = distribution(h, a) / (2.0 * (wo.z + ro));
            return if wi.z > 0.0 { f } else { 1.0 - f } * vndf;
        }
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let f = fresnel::exact(wo.dot(h).max(0.0), 1.0, self.eta).reflectance;
            return f * distribution(h, a) / (2.0 * (wo.z + ro));
        }
        let Some(h) = self.refraction_half(wo, wi) else {
            return 0.0;
        };
        let (oh, ih) = (wo.dot(h), -wi.dot(h));
        let f = fresnel::exact(oh, 1.0, self.eta).reflectance;
        let denom = oh - self.eta * ih;
        (1.0 - f) * 2.0 * distribution(h, a) * oh * self.eta * self.eta * ih
            / ((wo.z + ro) * (denom * denom))
    }

    /// A direction from `wo`: a visible normal from (u1, u2), reflected if
    /// `choice` < F, else refracted; None where it leaves on the wrong side.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3A, choice: f32, (u1, u2): (f32, f32)) -> Option<Vec3A> {
        let h = visible_normal(wo, self.alpha, u1, u2);
        if self.thin {
            let f = fresnel::exact(wo.dot(h).max(0.0), 1.0, self.eta).reflectance;
            let wr = reflect_about(wo, h);
            return match (wr.z > 0.0, choice < f) {
                (false, _) => None,
                (true, true) => Some(wr),
                (true, false) => Some(Vec3A::new(wr.x, wr.y, -wr.z)),
            };
        }
        let (f, wt) = split(wo, h, self.eta);
        if choice < f {
            let wr = reflect_about(wo, h);
            (wr.z > 0.0).then_some(wr)
        } else {
            (wt.z < 0.0).then_some(wt)
        }
    }
}

#[cfg(test)]
#[path = "glass_tests.rs"]
mod tests;
