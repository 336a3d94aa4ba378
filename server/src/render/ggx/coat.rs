//! The clear coat (`KHR_materials_clearcoat`): a dielectric layer of index
//! 1.5 (F0 = 0.04) with its own GGX roughness over the whole material, on
//! the side the geometric normal faces. As glTF defines it,
//! f = coat f_coat + (1 - coat F_coat) f_base; here the base is scaled by
//! what the coat lets through towards `wo`, 1 - coat Es(mu_o), with Es
//! the coat lobe's whole directional albedo (single scattering with
//! Schlick's Fresnel plus Kulla and Conty's multiple-scattering lobe, from
//! the GGX [`Tables`]): a white material under a white coat keeps every bit
//! of a white furnace's energy (coat Es + (1 - coat Es) 1), and a darker
//! one never gains any. Not reciprocal (the base's scale depends on
//! `wo` alone), which a camera-path tracer does not need.
//!
//! Sampling: the coat's visible normals with probability `p`, its albedo's
//! share of what the coated material reflects towards `wo`.

use super::{distribution, fresnel_factor, pow5, reflect_about, smith_r, visible_normal, Tables};
use crate::render::math::Vec3A;
use std::f32::consts::FRAC_1_PI;

/// The coat's normal-incidence reflectance (index 1.5, as glTF fixes it).
pub const F0: f32 = 0.04;

/// The coat at one shading point (`weight` 0: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coat {
    /// glTF's `clearcoatFactor`, in [0, 1].
    pub weight: f32,
    pub alpha: f32,
    pub roughness: f32,
    /// The white single-scattering albedo at mu_o and its average.
    e_o: f32,
    e_avg: f32,
    /// The Fresnel factor of the multiple-scattering lobe.
    fms: f32,
    /// What the base keeps: 1 - weight Es(mu_o).
    pub keep: f32,
    /// Probability of sampling the coat.
    pub p: f32,
}

impl Coat {
    pub const NONE: Coat = Coat {
        weight: 0.0,
        alpha: 1.0,
        roughness: 1.0,
        e_o: 0.0,
        e_avg: 0.0,
        fms: 0.0,
        keep: 1.0,
        p: 0.0,
    };

    /// The coat of `weight` and `roughness` (alpha its square, at least
    /// `ALPHA_MIN`) seen from `wo`, over a base that reflects `base_albedo`
    /// towards `wo` (for the sampling probability only).
    #[inline(always)]
    pub fn new(
        t: &Tables,
        (weight, roughness, alpha): (f32, f32, f32),
        wo: Vec3A,
        base_albedo: f32,
    ) -> Coat {
        let (a_o, b_o) = (t.at(0, wo.z, roughness), t.at(1, wo.z, roughness));
        let e_o = a_o + b_o;
        let e_avg = t.avg(0, roughness) + t.avg(1, roughness);
        let fms = fresnel_factor(F0 + (1.0 - F0) * (1.0 / 21.0), e_avg);
        let es_o = F0 * a_o + b_o + (1.0 - e_o) * fms;
        let reflected = weight * es_o;
        let keep = 1.0 - reflected;
        let p = (reflected / (reflected + keep * base_albedo).max(1e-6)).clamp(0.05, 0.95);
        Coat {
            weight,
            alpha,
            roughness,
            e_o,
            e_avg,
            fms,
            keep,
            p,
        }
    }

    /// Whether there is a coat to evaluate and sample.
    #[inline(always)]
    pub fn on(&self) -> bool {
        self.weight > 0.0
    }

    /// The coat's BSDF |cos(theta_i)| (weight included; white).
    #[inline(always)]
    pub fn eval_cos(&self, t: &Tables, wo: Vec3A, wi: Vec3A) -> f32 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let a = self.alpha;
        let h = (wo + wi).normalize();
        let (ro, ri) = (smith_r(wo, a), smith_r(wi, a));
        let spec = distribution(h, a) / (2.0 * (ro * wi.z + ri * wo.z));
        let c5 = pow5(1.0 - wo.dot(h).clamp(0.0, 1.0));
        let e_i = t.at(0, wi.z, self.roughness) + t.at(1, wi.z, self.roughness);
        let ms = (1.0 - self.e_o) * (1.0 - e_i) * FRAC_1_PI / (1.0 - self.e_avg).max(1e-6);
        self.weight * ((F0 + (1.0 - F0) * c5) * spec + self.fms * ms) * wi.z
    }

    /// The density of drawing `wi` by the coat's visible normals.
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        distribution(h, self.alpha) / (2.0 * (wo.z + smith_r(wo, self.alpha)))
    }

    /// A direction reflected about one of the coat's visible normals.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3A, (u1, u2): (f32, f32)) -> Option<Vec3A> {
        let wi = reflect_about(wo, visible_normal(wo, self.alpha, u1, u2));
        (wi.z > 0.0).then_some(wi)
    }
}

#[cfg(test)]
#[path = "coat_tests.rs"]
mod tests;
