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
//!
//! The coat has its own normal ([`Frame`]) where it differs from the
//! base's: glTF's coat follows the surface's unmapped normal, or its own
//! `clearcoatNormalTexture`, not the base's normal map. Its lobe is then
//! evaluated, and sampled, in that frame, and the base keeps what the coat
//! lets through towards `wo` as seen from the coat's normal.

use super::{distribution, fresnel_factor, pow5, reflect_about, smith_r, visible_normal, Tables};
use crate::render::math::{basis, Vec3A};
use std::f32::consts::FRAC_1_PI;

/// The coat's normal-incidence reflectance (index 1.5, as glTF fixes it).
pub const F0: f32 = 0.04;

/// The coat's shading frame in the base's (whose normal is z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    t: Vec3A,
    b: Vec3A,
    n: Vec3A,
}

impl Frame {
    /// The frame of unit normal `n` (in the base's frame).
    #[inline(always)]
    pub fn new(n: Vec3A) -> Frame {
        let (t, b) = basis(n);
        Frame { t, b, n }
    }

    /// `v` (base frame) in the coat's frame.
    #[inline(always)]
    fn local(&self, v: Vec3A) -> Vec3A {
        Vec3A::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }

    /// `v` (coat frame) in the base's frame.
    #[inline(always)]
    fn base(&self, v: Vec3A) -> Vec3A {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

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
    /// Its own frame (None: the base's).
    frame: Option<Frame>,
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
        frame: None,
    };

    /// The coat of `weight` and `roughness` (alpha its square, at least
    /// `ALPHA_MIN`) seen from `wo`, over a base that reflects `base_albedo`
    /// towards `wo` (for the sampling probability only).
    #[inline(always)]
    pub fn new(t: &Tables, k: (f32, f32, f32), wo: Vec3A, base_albedo: f32) -> Coat {
        Coat::framed(t, k, wo, base_albedo, None)
    }

    /// [`Coat::new`] with the coat's own `frame` (None: the base's); `wo`
    /// in the base's frame.
    #[inline(always)]
    pub fn framed(
        t: &Tables,
        (weight, roughness, alpha): (f32, f32, f32),
        wo: Vec3A,
        base_albedo: f32,
        frame: Option<Frame>,
    ) -> Coat {
        let wo = match &frame {
            Some(f) => f.local(wo),
            None => wo,
        };
        // Seen edge-on or from behind its own normal, the coat reflects
        // nothing and lets everything through.
        if !(wo.z > 0.0) {
            return Coat::NONE;
        }
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
            frame,
        }
    }

    /// `wo` and `wi` (base frame) in the coat's frame.
    #[inline(always)]
    fn local(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, Vec3A) {
        match &self.frame {
            Some(f) => (f.local(wo), f.local(wi)),
            None => (wo, wi),
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
        let (wo, wi) = self.local(wo, wi);
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
        let (wo, wi) = self.local(wo, wi);
        if !(wi.z > 0.0 && wo.z > 0.0) {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        distribution(h, self.alpha) / (2.0 * (wo.z + smith_r(wo, self.alpha)))
    }

    /// A direction reflected about one of the coat's visible normals.
    #[inline(always)]
    pub fn sample(&self, wo: Vec3A, (u1, u2): (f32, f32)) -> Option<Vec3A> {
        let Some(f) = &self.frame else {
            let wi = reflect_about(wo, visible_normal(wo, self.alpha, u1, u2));
            return (wi.z > 0.0).then_some(wi);
        };
        let wo = f.local(wo);
        if !(wo.z > 0.0) {
            return None;
        }
        let wi = reflect_about(wo, visible_normal(wo, self.alpha, u1, u2));
        (wi.z > 0.0).then(|| f.base(wi))
    }
}

#[cfg(test)]
#[path = "coat_tests.rs"]
mod tests;
