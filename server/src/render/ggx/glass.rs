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
//! `KHR_materials_specular` ([`Tint`]): glTF mixes the dielectric's
//! reflection and transmission by F' = specular (F0' + (1 - F0') S) per
//! channel, F0' = min(F0 colour, 1), S Schlick's (1 - cos)^5, and what is
//! transmitted by 1 - max(F'). Here the exact Fresnel curve F takes S's
//! place, rescaled to run from 0 at F0 to 1 at grazing incidence (and
//! total internal reflection): F' = F0s + (F90s - F0s) (F - F0) / (1 -
//! F0), with the material's F0s = min(F0 colour, 1) specular and F90s =
//! specular; without the extension F' is F itself (the exact Fresnel,
//! untouched). Where nothing can cross (total internal reflection)
//! everything is reflected, whatever the tint. Reflection is drawn with probability max(F'), so each
//! channel's weight is F' / max(F') <= 1. The compensation stays the white
//! glass's: the split between reflection and transmission moves only
//! where the two directions lose different shares to masking, and the
//! furnace test bounds that.
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
//! from outside and from inside, integrated once and stored (the
//! renderer reads it on first use). The kernel (`kernels/ggx.h`) gets the
//! same floats and mirrors every routine here.

use super::{distribution, reflect_about, smith_r, visible_normal, TABLE_N};
use crate::render::fresnel;
use crate::render::math::Vec3A;
use std::sync::OnceLock;

/// Points on the table's index axis, x = (ior - 1) / (ior + 1) from 0 to
/// 1 / [`IOR_SCALE`] = 0.8 (ior 1 to 9; larger indices read the last).
pub const IOR_N: usize = 17;
pub const IOR_SCALE: f32 = 1.25;
/// Floats in one part of [`Table::data`]: by side (0: arriving from
/// outside, eta = ior; 1: from inside, eta = 1 / ior), index, roughness,
/// cos(theta_o).
pub const PART_LEN: usize = 2 * IOR_N * TABLE_N * TABLE_N;
/// Floats in [`Table::data`]: the white glass's part, then the clear
/// glass's (one that reflects only where nothing can cross).
pub const TABLE_LEN: usize = 2 * PART_LEN;

/// The white albedo of the single-scattering lobe, and of the lobe of a
/// glass with specular 0 (`KHR_materials_specular`: transmission alone,
/// but for total internal reflection), between which a tinted glass's
/// compensation interpolates.
pub struct Table {
    pub data: Box<[f32]>,
}

/// The table (`tables/glass.f32`, integrated by `integrate.rs`), read
/// once per process on first use.
pub fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    static BYTES: &[u8; TABLE_LEN * 4] = include_bytes!("tables/glass.f32");
    T.get_or_init(|| Table {
        data: super::floats(BYTES),
    })
}

/// The table's index coordinate of `ior`.
#[inline(always)]
fn ior_x(ior: f32) -> f32 {
    (ior - 1.0) / (ior + 1.0)
}

impl Table {
    /// E(mu) at `roughness` and `ior`, for light arriving from outside
    /// (`entering`) or inside: trilinear.
    #[inline(always)]
    pub fn albedo(&self, mu: f32, roughness: f32, ior: f32, entering: bool) -> f32 {
        self.part(0, (mu, roughness, ior), entering)
    }

    /// [`albedo`](Self::albedo) of the clear glass (specular 0).
    #[inline(always)]
    pub fn clear_albedo(&self, mu: f32, roughness: f32, ior: f32, entering: bool) -> f32 {
        self.part(PART_LEN, (mu, roughness, ior), entering)
    }

    #[inline(always)]
    fn part(&self, at: usize, (mu, roughness, ior): (f32, f32, f32), entering: bool) -> f32 {
        let n = TABLE_N;
        let (i, tx) = super::cell(mu);
        let (j, ty) = super::cell(roughness);
        let s = (ior_x(ior) * IOR_SCALE).clamp(0.0, 1.0) * (IOR_N - 1) as f32;
        let k = (s as usize).min(IOR_N - 2);
        let tz = s - k as f32;
        let side = usize::from(!entering);
        let plane = |k: usize| {
            let t = &self.data[at + (side * IOR_N + k) * n * n..];
            let row0 = t[j * n + i] * (1.0 - tx) + t[j * n + i + 1] * tx;
            let row1 = t[(j + 1) * n + i] * (1.0 - tx) + t[(j + 1) * n + i + 1] * tx;
            row0 * (1.0 - ty) + row1 * ty
        };
        plane(k) * (1.0 - tz) + plane(k + 1) * tz
    }
}

/// The Fresnel reflectance at microfacet `h` seen from `wo` (wo . h > 0)
/// and the refracted direction (meaningless where the reflectance is 1).
#[inline(always)]
pub(super) fn split(wo: Vec3A, h: Vec3A, eta: f32) -> (f32, Vec3A) {
    let c = wo.dot(h).max(0.0);
    let s = fresnel::exact(c, 1.0, eta);
    let wt = (h * (c / eta - s.cos_t) - wo / eta).normalize();
    (s.reflectance, wt)
}

/// How near 1 the ratio of indices makes a solid index-matched
/// ([`Glass::matched`]): its Fresnel reflectance is below 3e-7 there.
pub const MATCHED: f32 = 1e-3;

/// `KHR_materials_specular` on the glass: the untinted F0 of its index and
/// the material's tinted, scaled F0s and F90s ([`super::Pbr`]'s
/// `spec_f0`, `spec_f90`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tint {
    pub f0: f32,
    pub spec_f0: Vec3A,
    pub spec_f90: f32,
}

impl Tint {
    /// The tint of `KHR_materials_specular`'s F0s, F90s over a dielectric of
    /// reflectance `f0`; None where they are the index's own (no tint).
    #[inline(always)]
    pub fn new(f0: f32, spec_f0: Vec3A, spec_f90: f32) -> Option<Tint> {
        (spec_f90 != 1.0 || spec_f0 != Vec3A::splat(f0)).then_some(Tint {
            f0,
            spec_f0,
            spec_f90,
        })
    }
}

/// The reflectance per channel of exact Fresnel reflectance `f` under
/// `tint`, and the probability of reflecting (its largest channel).
#[inline(always)]
fn tinted(tint: &Option<Tint>, f: f32) -> (Vec3A, f32) {
    match tint {
        None => (Vec3A::splat(f), f),
        // Total internal reflection: nothing can cross, all is reflected.
        Some(_) if f >= 1.0 => (Vec3A::ONE, 1.0),
        Some(t) => {
            let s = ((f - t.f0) / (1.0 - t.f0)).clamp(0.0, 1.0);
            let r = t.spec_f0 + (Vec3A::splat(t.spec_f90) - t.spec_f0) * s;
            (r, r.max_element())
        }
    }
}

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
    /// `KHR_materials_specular`'s change to the Fresnel mix (None: exact).
    pub tint: Option<Tint>,
}

impl Glass {
    /// The lobe of a surface of index `ior` at `roughness` (alpha its
    /// square, at least [`ALPHA_MIN`]) seen from `wo`, arriving from
    /// outside (`entering`) or inside.
    #[inline(always)]
    pub fn new(alpha: f32, roughness: f32, ior: f32, wo: Vec3A, entering: bool) -> Glass {
        Glass::with_tint(alpha, roughness, ior, (wo, entering), None)
    }

    /// [`Glass::new`] under `KHR_materials_specular`'s `tint`: its
    /// compensation interpolates between the white glass's albedo and the
    /// clear glass's by the specular factor (F90s).
    #[inline(always)]
    pub fn with_tint(
        alpha: f32,
        roughness: f32,
        ior: f32,
        (wo, entering): (Vec3A, bool),
        tint: Option<Tint>,
    ) -> Glass {
        let t = table();
        let mut e = t.albedo(wo.z, roughness, ior, entering);
        if let Some(tint) = &tint {
            let e0 = t.clear_albedo(wo.z, roughness, ior, entering);
            e = e0 + (e - e0) * tint.spec_f90;
        }
        Glass {
            alpha,
            eta: if entering { ior } else { 1.0 / ior },
            scale: 1.0 / e.max(0.05),
            thin: false,
            tint,
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
            tint: None,
        }
    }

    /// The same lobe with `KHR_materials_specular`'s [`Tint`] (a thin
    /// wall's compensation holds for any: its reflection and transmission
    /// are mirror images, masked alike).
    #[inline(always)]
    pub fn tinted(self, tint: Option<Tint>) -> Glass {
        Glass { tint, ..self }
    }

    /// Reflectance per channel and probability of reflecting at a
    /// microfacet seen at cosine `c`.
    #[inline(always)]
    fn split_at(&self, c: f32) -> (Vec3A, f32) {
        tinted(&self.tint, fresnel::exact(c, 1.0, self.eta).reflectance)
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
    fn thin_eval_cos(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        let w = Vec3A::new(wi.x, wi.y, wi.z.abs());
        let a = self.alpha;
        let (ro, ri) = (smith_r(wo, a), smith_r(w, a));
        let h = (wo + w).normalize();
        let (f, m) = self.split_at(wo.dot(h).max(0.0));
        let spec = distribution(h, a) / (2.0 * (ro * w.z + ri * wo.z)) * w.z * self.scale;
        match wi.z > 0.0 {
            true => (f * spec, 0.0),
            false => (Vec3A::ZERO, (1.0 - m) * spec),
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

    /// BSDF |cos(theta_i)| from `wo` to `wi`: (reflected per channel,
    /// transmitted; the caller tints what is transmitted), compensation
    /// included.
    #[inline(always)]
    pub fn eval_cos(&self, wo: Vec3A, wi: Vec3A) -> (Vec3A, f32) {
        if self.thin {
            return self.thin_eval_cos(wo, wi);
        }
        let a = self.alpha;
        let (ro, ri) = (smith_r(wo, a), smith_r(wi, a));
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let (f, _) = self.split_at(wo.dot(h).max(0.0));
            let spec = distribution(h, a) / (2.0 * (ro * wi.z + ri * wo.z));
            return (f * (spec * wi.z * self.scale), 0.0);
        }
        let Some(h) = self.refraction_half(wo, wi) else {
            return (Vec3A::ZERO, 0.0);
        };
        let (oh, ih) = (wo.dot(h), -wi.dot(h));
        let (_, f) = self.split_at(oh);
        let ci = -wi.z;
        let denom = oh - self.eta * ih;
        let t = (1.0 - f) * distribution(h, a) * self.eta * self.eta * oh * ih * 2.0 * ci
            / ((ro * ci + ri * wo.z) * (denom * denom));
        (Vec3A::ZERO, t * self.scale)
    }

    /// The density of drawing `wi` from `wo` (solid angle).
    #[inline(always)]
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        let a = self.alpha;
        let ro = smith_r(wo, a);
        if self.thin {
            let w = Vec3A::new(wi.x, wi.y, wi.z.abs());
            let h = (wo + w).normalize();
            let (_, f) = self.split_at(wo.dot(h).max(0.0));
            let vndf = distribution(h, a) / (2.0 * (wo.z + ro));
            return if wi.z > 0.0 { f } else { 1.0 - f } * vndf;
        }
        if wi.z > 0.0 {
            let h = (wo + wi).normalize();
            let (_, f) = self.split_at(wo.dot(h).max(0.0));
            return f * distribution(h, a) / (2.0 * (wo.z + ro));
        }
        let Some(h) = self.refraction_half(wo, wi) else {
            return 0.0;
        };
        let (oh, ih) = (wo.dot(h), -wi.dot(h));
        let (_, f) = self.split_at(oh);
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
            let (_, f) = self.split_at(wo.dot(h).max(0.0));
            let wr = reflect_about(wo, h);
            return match (wr.z > 0.0, choice < f) {
                (false, _) => None,
                (true, true) => Some(wr),
                (true, false) => Some(Vec3A::new(wr.x, wr.y, -wr.z)),
            };
        }
        let (f, wt) = split(wo, h, self.eta);
        let (_, f) = tinted(&self.tint, f);
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
