//! The glTF 2.0 metallic-roughness BSDF (the specification's appendix B) in
//! the shading frame (z the normal): GGX (Trowbridge-Reitz) microfacets
//! with height-correlated Smith masking-shadowing, sampled by their visible
//! normals (Dupuy and Benyoub 2023, spherical caps); Schlick's Fresnel, the
//! metal tinted by the base colour, the dielectric over a diffuse base.
//!
//! Energy: a single-scattering microfacet lobe loses the light that
//! scatters more than once among the microfacets (a white rough metal goes
//! grey). Each lobe gets it back as Kulla and Conty's (2017) multiple-
//! scattering lobe `(1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg))`, with
//! the Fresnel average's factor; the diffuse base sees only what the
//! specular layer lets through, `(1 - Es(mu_o)) (1 - Es(mu_i)) / (1 -
//! Es_avg)`, so a white base under the coating also keeps every bit of
//! energy. E, and its split into Schlick's F0 and (1 - cos)^5 parts, come
//! from [`Tables`], integrated (not guessed), stored in the binary and read
//! by bilinear lookup; the kernel (`kernels/ggx.h`) gets the same floats and
//! mirrors every routine here operation for operation.
//!
//! Transmission (`KHR_materials_transmission`): the dielectric's diffuse
//! base gives way to a rough dielectric of the same roughness and index
//! ([`glass`]), f = metallic metal + (1 - metallic) ((1 - transmission)
//! coated diffuse + transmission rough glass); what it transmits is tinted
//! by the base colour, what it reflects is not.
//!
//! Sampling: the rough glass with probability (1 - metallic) transmission;
//! else one lobe by the lobes' albedos seen from `wo` (visible normals, or
//! cosine for the multiple-scattering and diffuse lobes); the sample
//! weighted by the mixture's pdf (one-sample MIS, balance heuristic), so
//! every lobe is covered whichever was drawn.

pub mod coat;
pub mod glass;

use crate::render::math::{sincos_turns, Vec3A};
use std::f32::consts::FRAC_1_PI;
use std::sync::OnceLock;

/// Smallest alpha (= roughness^2): a lobe this narrow is a mirror to f32
/// image noise, and its D stays finite.
pub const ALPHA_MIN: f32 = 1e-3;
/// The tables' resolution in cos(theta) and in roughness (both 0..=1).
pub const TABLE_N: usize = 32;
/// Floats in [`Tables::data`]: A and B per (cos, roughness), then their
/// cosine-weighted averages per roughness.
pub const TABLE_LEN: usize = 2 * TABLE_N * TABLE_N + 2 * TABLE_N;

/// The metallic-roughness parameters of one material (its base colour is
/// the material's albedo).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pbr {
    pub metallic: f32,
    /// roughness^2, at least [`ALPHA_MIN`].
    pub alpha: f32,
    /// Perceptual roughness, the tables' coordinate.
    pub roughness: f32,
    /// Normal-incidence reflectance of the dielectric, ((ior-1)/(ior+1))^2.
    pub f0: f32,
    /// The share of the dielectric that is rough glass, not coated diffuse.
    pub transmission: f32,
    /// The index of refraction (what `f0` came from), for the glass.
    pub ior: f32,
    /// The glass is a thin wall (glTF's default without
    /// `KHR_materials_volume`): what it transmits leaves unrefracted.
    pub thin: bool,
    /// The dielectric's Schlick F0 per channel and its F90
    /// (`KHR_materials_specular`: min(f0 specular_color, 1) specular and
    /// specular; f0 and 1 without it).
    pub spec_f0: Vec3A,
    pub spec_f90: f32,
    /// The clear coat's weight (`KHR_materials_clearcoat`; 0: none), its
    /// roughness and alpha ([`coat`]).
    pub coat: f32,
    pub coat_roughness: f32,
    pub coat_alpha: f32,
}

impl Pbr {
    pub fn new(metallic: f32, roughness: f32, ior: f32) -> Pbr {
        let r = (ior - 1.0) / (ior + 1.0);
        Pbr {
            metallic,
            alpha: (roughness * roughness).max(ALPHA_MIN),
            roughness,
            f0: r * r,
            transmission: 0.0,
            ior,
            thin: false,
            spec_f0: Vec3A::splat(r * r),
            spec_f90: 1.0,
            coat: 0.0,
            coat_roughness: 0.0,
            coat_alpha: ALPHA_MIN,
        }
    }

    /// The same material with `KHR_materials_specular`'s `factor` and
    /// `color` (F0 tinted by the colour, at most 1, both scaled by the
    /// factor).
    pub fn specular(self, factor: f32, color: Vec3A) -> Pbr {
        Pbr {
            spec_f0: (color * self.f0).min(Vec3A::ONE) * factor,
            spec_f90: factor,
            ..self
        }
    }

    /// The same material under a clear coat of `weight` and `roughness`.
    pub fn coated(self, weight: f32, roughness: f32) -> Pbr {
        Pbr {
            coat: weight,
            coat_roughness: roughness,
            coat_alpha: (roughness * roughness).max(ALPHA_MIN),
            ..self
        }
    }

    /// The same material, `transmission` of its dielectric rough glass.
    pub fn transmitting(self, transmission: f32) -> Pbr {
        Pbr {
            transmission,
            ..self
        }
    }

    /// The same material with its glass a thin wall (or solid).
    pub fn thin_walled(self, thin: bool) -> Pbr {
        Pbr { thin, ..self }
    }
}

/// Directional albedos of the single-scattering GGX lobe with Schlick's
/// Fresnel, F = F0 + (1 - F0)(1 - cos)^5: its albedo is F0 A + B (white:
/// E = A + B). Rows by roughness, columns by cos(theta_o).
pub struct Tables {
    pub data: Box<[f32]>,
}

/// The tables (`tables/ggx.f32`, integrated by `integrate.rs`), read once
/// per process.
pub fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    static BYTES: &[u8; TABLE_LEN * 4] = include_bytes!("tables/ggx.f32");
    T.get_or_init(|| Tables {
        data: floats(BYTES),
    })
}

/// Little-endian f32s.
fn floats(bytes: &[u8]) -> Box<[f32]> {
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Where the averages start in [`Tables::data`] (A's, then B's).
const AVG_A: usize = 2 * TABLE_N * TABLE_N;
#[cfg(test)]
const AVG_B: usize = AVG_A + TABLE_N;

impl Tables {
    /// The single-scattering lobe's white directional albedo E(mu) at
    /// `roughness` (what a microfacet BSDF without the added lobes keeps).
    pub fn single_scattering(&self, mu: f32, roughness: f32) -> f32 {
        self.at(0, mu, roughness) + self.at(1, mu, roughness)
    }

    /// Bilinear lookup of table `part` (0: A, 1: B) at (mu, roughness).
    #[inline(always)]
    fn at(&self, part: usize, mu: f32, roughness: f32) -> f32 {
        let n = TABLE_N;
        let (i, tx) = cell(mu);
        let (j, ty) = cell(roughness);
        let t = &self.data[part * n * n..];
        let row0 = t[j * n + i] * (1.0 - tx) + t[j * n + i + 1] * tx;
        let row1 = t[(j + 1) * n + i] * (1.0 - tx) + t[(j + 1) * n + i + 1] * tx;
        row0 * (1.0 - ty) + row1 * ty
    }

    /// Linear lookup of an average (0: A, 1: B) at `roughness`.
    #[inline(always)]
    fn avg(&self, part: usize, roughness: f32) -> f32 {
        let (j, t) = cell(roughness);
        let a = &self.data[AVG_A + part * TABLE_N..];
        a[j] * (1.0 - t) + a[j + 1] * t
    }
}

/// The cell of coordinate `x` in [0, 1] and the position within it.
#[inline(always)]
fn cell(x: f32) -> (usize, f32) {
    let s = x.clamp(0.0, 1.0) * (TABLE_N - 1) as f32;
    let i = (s as usize).min(TABLE_N - 2);
    (i, s - i as f32)
}

#[inline(always)]
fn pow5(x: f32) -> f32 {
    let x2 = x * x;
    x2 * x2 * x
}

/// sqrt(cos^2 + alpha^2 sin^2) of unit `w`: Smith's Lambda(w) is
/// (R / cos - 1) / 2, so G1 = 2 cos / (cos + R) and the height-correlated
/// G2 = 2 cos_o cos_i / (R_o cos_i + R_i cos_o).
#[inline(always)]
fn smith_r(w: Vec3A, alpha: f32) -> f32 {
    let s2 = w.x * w.x + w.y * w.y;
    (w.z * w.z + alpha * alpha * s2).sqrt()
}

/// GGX's D of unit half vector `h` (sin^2 from x and y, not 1 - cos^2:
/// exact near the peak of a narrow lobe).
#[inline(always)]
fn distribution(h: Vec3A, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let t = h.x * h.x + h.y * h.y + a2 * (h.z * h.z);
    a2 / (std::f32::consts::PI * (t * t))
}

#[inline(always)]
fn reflect_about(wo: Vec3A, h: Vec3A) -> Vec3A {
    h * (2.0 * wo.dot(h)) - wo
}

/// A visible normal of the GGX surface seen from `wo` (wo.z > 0), from
/// (u1, u2) in [0, 1)^2: Dupuy and Benyoub's spherical cap in the
/// stretched (alpha = 1) configuration.
#[inline(always)]
pub fn visible_normal(wo: Vec3A, alpha: f32, u1: f32, u2: f32) -> Vec3A {
    let v = Vec3A::new(wo.x * alpha, wo.y * alpha, wo.z).normalize();
    let (sin_phi, cos_phi) = sincos_turns(u1);
    let z = (1.0 - u2) * (1.0 + v.z) - v.z;
    let sin_t = (1.0 - z * z).max(0.0).sqrt();
    let c = Vec3A::new(sin_t * cos_phi, sin_t * sin_phi, z) + v;
    Vec3A::new(c.x * alpha, c.y * alpha, c.z).normalize()
}

/// What the lobes reflect towards `wo`, read from the tables once per
/// shading point.
#[derive(Clone, Copy, Debug)]
pub struct Lobes {
    /// White single-scattering albedo E(mu_o).
    e_o: f32,
    /// Cosine-weighted averages (E_avg = a_avg + b_avg).
    a_avg: f32,
    b_avg: f32,
    /// Kulla-Conty Fresnel factors of the metal (per channel) and of the
    /// dielectric.
    fms_metal: Vec3A,
    fms_diel: Vec3A,
    /// The dielectric layer's whole albedo at mu_o and its average.
    es_o: Vec3A,
    es_avg: Vec3A,
    /// Probability of drawing the visible-normal lobe (of the lobes other
    /// than the glass).
    p_spec: f32,
    /// Probability of drawing the rough glass, (1 - metallic) transmission,
    /// and the glass itself (meaningless where that is 0).
    p_glass: f32,
    glass: glass::Glass,
    /// The clear coat over it all ([`coat::Coat::NONE`] where there is
    /// none, or on a transmitting solid's inside).
    coat: coat::Coat,
}

#[inline(always)]
fn fresnel_factor(f_avg: f32, e_avg: f32) -> f32 {
    f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))
}

#[inline(always)]
fn mean3(v: Vec3A) -> f32 {
    (v.x + v.y + v.z) * (1.0 / 3.0)
}

impl Lobes {
    /// The lobes seen from `wo`, on a surface the ray reached from outside
    /// (`entering`) or inside (which side the glass's index is on).
    #[inline(always)]
    pub fn new(t: &Tables, p: &Pbr, base: Vec3A, wo: Vec3A, entering: bool) -> Lobes {
        Lobes::framed(t, p, base, (wo, entering), None)
    }

    /// [`Lobes::new`] with the coat's own frame (None: the base's).
    #[inline(always)]
    pub fn framed(
        t: &Tables,
        p: &Pbr,
        base: Vec3A,
        (wo, entering): (Vec3A, bool),
        coat_frame: Option<coat::Frame>,
    ) -> Lobes {
        let a_o = t.at(0, wo.z, p.roughness);
        let b_o = t.at(1, wo.z, p.roughness);
        let a_avg = t.avg(0, p.roughness);
        let b_avg = t.avg(1, p.roughness);
        let e_o = a_o + b_o;
        let e_avg = a_avg + b_avg;
        let f_avg_metal = base + (Vec3A::ONE - base) * (1.0 / 21.0);
        let fms_metal = Vec3A::new(
            fresnel_factor(f_avg_metal.x, e_avg),
            fresnel_factor(f_avg_metal.y, e_avg),
            fresnel_factor(f_avg_metal.z, e_avg),
        );
        let (f0, f90) = (p.spec_f0, p.spec_f90);
        let f_avg_diel = f0 + (Vec3A::splat(f90) - f0) * (1.0 / 21.0);
        let fms_diel = Vec3A::new(
            fresnel_factor(f_avg_diel.x, e_avg),
            fresnel_factor(f_avg_diel.y, e_avg),
            fresnel_factor(f_avg_diel.z, e_avg),
        );
        let es_o = f0 * a_o + Vec3A::splat(f90 * b_o) + fms_diel * (1.0 - e_o);
        let es_avg = f0 * a_avg + Vec3A::splat(f90 * b_avg) + fms_diel * (1.0 - e_avg);
        // The visible-normal lobe's share of what wo sees: the single-
        // scattering albedos against the cosine-shaped lobes'.
        let spec = p.metallic * mean3(base * a_o + Vec3A::splat(b_o))
            + (1.0 - p.metallic) * mean3(f0 * a_o + Vec3A::splat(f90 * b_o));
        let rest = p.metallic * (1.0 - e_o) * mean3(fms_metal)
            + (1.0 - p.metallic) * mean3(fms_diel * (1.0 - e_o) + (Vec3A::ONE - es_o) * base);
        let p_spec = (spec / (spec + rest)).clamp(0.05, 0.95);
        let p_glass = (1.0 - p.metallic) * p.transmission;
        let glass = if p_glass > 0.0 {
            let tint = glass::Tint::new(p.f0, p.spec_f0, p.spec_f90);
            match p.thin {
                true => {
                    glass::Glass::thin(p.alpha, p.ior, 1.0 / (a_o + b_o).max(0.05)).tinted(tint)
                }
                false => glass::Glass::with_tint(p.alpha, p.roughness, p.ior, (wo, entering), tint),
            }
        } else {
            glass::Glass {
                alpha: p.alpha,
                eta: 1.0,
                scale: 0.0,
                thin: false,
                tint: None,
            }
        };
        // The coat faces outwards: on both sides of an opaque surface or a
        // thin wall, on the outside of a transmitting solid.
        let coat = if p.coat > 0.0 && (entering || p_glass == 0.0 || p.thin) {
            let below = (spec + rest) * (1.0 - p_glass) + p_glass;
            let c = (p.coat, p.coat_roughness, p.coat_alpha);
            coat::Coat::framed(t, c, wo, below, coat_frame)
        } else {
            coat::Coat::NONE
        };
        Lobes {
            e_o,
            a_avg,
            b_avg,
            fms_metal,
            fms_diel,
            es_o,
            es_avg,
            p_spec,
            p_glass,
            glass,
            coat,
        }
    }
}

/// BSDF times |cos(theta_i)| for `wo` and `wi` in the shading frame: the
/// single-scattering microfacet lobes, the multiple-scattering lobes and
/// the diffuse base, and the rough glass where the material transmits.
#[inline(always)]
pub fn eval_cos(t: &Tables, p: &Pbr, base: Vec3A, lobes: &Lobes, wo: Vec3A, wi: Vec3A) -> Vec3A {
    let mut out = Vec3A::ZERO;
    if lobes.p_glass > 0.0 && wo.z > 0.0 {
        let (r, tr) = lobes.glass.eval_cos(wo, wi);
        out = (r + base * tr) * lobes.p_glass;
    }
    out += eval_reflection(t, p, base, lobes, wo, wi);
    match lobes.coat.on() {
        true => out * lobes.coat.keep + Vec3A::splat(lobes.coat.eval_cos(t, wo, wi)),
        false => out,
    }
}

/// [`eval_cos`] of the lobes other than the glass.
#[inline(always)]
fn eval_reflection(t: &Tables, p: &Pbr, base: Vec3A, lobes: &Lobes, wo: Vec3A, wi: Vec3A) -> Vec3A {
    if !(wi.z > 0.0 && wo.z > 0.0) {
        return Vec3A::ZERO;
    }
    let h = (wo + wi).normalize();
    let (ro, ri) = (smith_r(wo, p.alpha), smith_r(wi, p.alpha));
    // D G2 / (4 cos_o cos_i), with G2 = 2 cos_o cos_i / (R_o cos_i + R_i cos_o).
    let spec = distribution(h, p.alpha) / (2.0 * (ro * wi.z + ri * wo.z));
    let c5 = pow5(1.0 - wo.dot(h).clamp(0.0, 1.0));
    let a_i = t.at(0, wi.z, p.roughness);
    let b_i = t.at(1, wi.z, p.roughness);
    let e_i = a_i + b_i;
    let e_avg = lobes.a_avg + lobes.b_avg;
    let ms = (1.0 - lobes.e_o) * (1.0 - e_i) * FRAC_1_PI / (1.0 - e_avg).max(1e-6);
    let (f0, f90) = (p.spec_f0, p.spec_f90);
    let es_i = f0 * a_i + Vec3A::splat(f90 * b_i) + lobes.fms_diel * (1.0 - e_i);
    let diffuse = (Vec3A::ONE - lobes.es_o) * (Vec3A::ONE - es_i) * FRAC_1_PI
        / (Vec3A::ONE - lobes.es_avg).max(Vec3A::splat(1e-6));
    // The coated diffuse's share.
    let layer = (1.0 - p.metallic) * (1.0 - p.transmission);
    let single = (base + (Vec3A::ONE - base) * c5) * (spec * p.metallic)
        + (f0 + (Vec3A::splat(f90) - f0) * c5) * (spec * layer);
    let multiple =
        lobes.fms_metal * (ms * p.metallic) + (base * diffuse + lobes.fms_diel * ms) * layer;
    (single + multiple) * wi.z
}

/// The sampling density of direction `wi` (solid angle) from `wo`.
#[inline(always)]
pub fn pdf(p: &Pbr, lobes: &Lobes, wo: Vec3A, wi: Vec3A) -> f32 {
    let under = pdf_under_coat(p, lobes, wo, wi);
    match lobes.coat.on() {
        true => lobes.coat.p * lobes.coat.pdf(wo, wi) + (1.0 - lobes.coat.p) * under,
        false => under,
    }
}

/// [`pdf`] of the lobes under the coat.
#[inline(always)]
fn pdf_under_coat(p: &Pbr, lobes: &Lobes, wo: Vec3A, wi: Vec3A) -> f32 {
    if !(wo.z > 0.0) {
        return 0.0;
    }
    let glass = if lobes.p_glass > 0.0 {
        lobes.p_glass * lobes.glass.pdf(wo, wi)
    } else {
        0.0
    };
    if !(wi.z > 0.0) {
        return glass;
    }
    let h = (wo + wi).normalize();
    // G1(wo) D(h) / (4 cos_o) = D / (2 (cos_o + R_o)).
    let vndf = distribution(h, p.alpha) / (2.0 * (wo.z + smith_r(wo, p.alpha)));
    (lobes.p_spec * vndf + (1.0 - lobes.p_spec) * wi.z * FRAC_1_PI) * (1.0 - lobes.p_glass) + glass
}

/// A sampled direction and its weights.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Below the surface (z < 0) where it went through.
    pub wi: Vec3A,
    /// BSDF cos / pdf.
    pub weight: Vec3A,
    /// The density it was drawn with ([`pdf`]), for multiple importance
    /// sampling (0 for index-matched glass's delta).
    pub pdf: f32,
}

/// A direction from `wo` (shading frame) on a surface reached from
/// outside (`entering`) or inside, drawn with `choice` and (u1, u2) in
/// [0, 1), and its weights; None where it leaves on the wrong side (no
/// contribution).
#[inline(always)]
pub fn sample(
    t: &Tables,
    p: &Pbr,
    base: Vec3A,
    (wo, entering): (Vec3A, bool),
    choice: f32,
    (u1, u2): (f32, f32),
) -> Option<Sample> {
    if !(wo.z > 0.0) {
        return None;
    }
    let lobes = Lobes::new(t, p, base, wo, entering);
    sample_from(t, p, base, &lobes, wo, choice, (u1, u2))
}

/// [`sample`] with the lobes `wo` sees already built (by next-event
/// estimation at the same vertex, from the same `wo` and side).
#[inline(always)]
pub fn sample_from(
    t: &Tables,
    p: &Pbr,
    base: Vec3A,
    lobes: &Lobes,
    wo: Vec3A,
    choice: f32,
    (u1, u2): (f32, f32),
) -> Option<Sample> {
    if !(wo.z > 0.0) {
        return None;
    }
    let mut choice = choice;
    let mut under = 1.0;
    if lobes.coat.on() {
        if choice < lobes.coat.p {
            let wi = lobes.coat.sample(wo, (u1, u2))?;
            return weighed(t, p, base, lobes, wo, wi);
        }
        choice = (choice - lobes.coat.p) / (1.0 - lobes.coat.p);
        under = lobes.coat.keep / (1.0 - lobes.coat.p);
    }
    let wi = if choice < lobes.p_glass {
        if lobes.glass.matched() {
            // Straight through, tinted: the glass's share of eval over the
            // probability of picking it (and what the coat lets through). A
            // delta: no density to weigh.
            return Some(Sample {
                wi: -wo,
                weight: base * under,
                pdf: 0.0,
            });
        }
        lobes.glass.sample(wo, choice / lobes.p_glass, (u1, u2))?
    } else {
        let choice = (choice - lobes.p_glass) / (1.0 - lobes.p_glass);
        let wi = if choice < lobes.p_spec {
            reflect_about(wo, visible_normal(wo, p.alpha, u1, u2))
        } else {
            let (sin, cos) = sincos_turns(u1);
            let r = u2.sqrt();
            Vec3A::new(r * cos, r * sin, (1.0 - u2).max(0.0).sqrt())
        };
        if !(wi.z > 0.0) {
            return None;
        }
        wi
    };
    weighed(t, p, base, lobes, wo, wi)
}

/// `wi` drawn from `wo`, weighed by the whole mixture's density.
#[inline(always)]
fn weighed(
    t: &Tables,
    p: &Pbr,
    base: Vec3A,
    lobes: &Lobes,
    wo: Vec3A,
    wi: Vec3A,
) -> Option<Sample> {
    let pdf = pdf(p, lobes, wo, wi);
    if !(pdf > 0.0) {
        return None;
    }
    Some(Sample {
        wi,
        weight: eval_cos(t, p, base, lobes, wo, wi) / pdf,
        pdf,
    })
}

#[cfg(test)]
mod integrate;
#[cfg(test)]
mod tests;
