//! Multiple importance sampling at `pbr` vertices: next-event estimation
//! and BSDF sampling each find the light an emitter sends, and each sample
//! is weighted by the power heuristic (Veach 1997, ch. 9) of the two
//! densities, so that a small light on a rough surface comes through the
//! shadow ray and a large one in a sharp highlight through the BSDF's own
//! direction. The weights of the two strategies sum to one for every
//! direction either can give, so the image is unchanged in the mean.
//!
//! The light's density of a direction is the pick's probability
//! (`Lights::pick_pmf`, 1 with `LightSampling::All`) times the emitter's
//! solid-angle density (`Emitter::pdf_direction`). Diffuse surfaces keep
//! next-event estimation alone (their images are the thesis's, bit for
//! bit); mirrors and glass have delta lobes that no light sample meets.

use super::nee::LightSampling;
use crate::render::light::{Lights, Receiver};
use crate::render::math::Vec3A;

/// How a `pbr` vertex combines its two strategies (not a quality setting:
/// `Mis` always, except where tests compare the strategies).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Combine {
    /// Power-heuristic weights.
    #[default]
    Mis,
    /// Next-event estimation alone finds the emitters it can sample; BSDF
    /// samples count only emission it cannot (the limit of the heuristic's
    /// exponent going to infinity).
    NeeOnly,
}

/// The power heuristic (exponent 2) of density `a` against `b`: a^2 /
/// (a^2 + b^2), written so that neither overflow nor a zero makes NaN.
#[inline(always)]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    if !(a > 0.0) {
        return 0.0;
    }
    let r = b / a;
    if r.is_nan() {
        return 0.5; // both infinite
    }
    1.0 / (1.0 + r * r)
}

/// The weight of a light sample of density `light_pdf` whose direction the
/// BSDF draws with density `bsdf_pdf`.
#[inline(always)]
pub fn light_weight(combine: Combine, light_pdf: f32, bsdf_pdf: f32) -> f32 {
    match combine {
        Combine::Mis => power_heuristic(light_pdf, bsdf_pdf),
        Combine::NeeOnly => 1.0,
    }
}

/// Where a path's last BSDF sample left from, for weighing the emission its
/// next hit finds.
#[derive(Clone, Copy, Debug)]
pub struct BsdfVertex {
    pub from: Receiver,
    /// The sample's density; 0 when the next hit counts emission in full.
    pub pdf: f32,
}

impl BsdfVertex {
    pub const NONE: BsdfVertex = BsdfVertex {
        from: Receiver {
            p: Vec3A::ZERO,
            object: u32::MAX,
            prim: u32::MAX,
            nl: Vec3A::ZERO,
            ns: Vec3A::ZERO,
        },
        pdf: 0.0,
    };

    /// The weight of the emission that the sample along `dir` found on
    /// emitter `emitter` (an index into `lights`, None for emission no
    /// light sample aims at) at `q`.
    #[inline(always)]
    pub fn hit_weight(
        &self,
        lights: &Lights,
        (sampling, combine): (LightSampling, Combine),
        emitter: Option<usize>,
        dir: Vec3A,
        q: Vec3A,
    ) -> f32 {
        let Some(i) = emitter else {
            return 1.0;
        };
        let pmf = match sampling {
            LightSampling::Power => lights.pick_pmf(i),
            LightSampling::All => 1.0,
        };
        let light_pdf = pmf * lights.emitters[i].pdf_direction(&self.from, dir, q);
        match combine {
            Combine::Mis => power_heuristic(self.pdf, light_pdf),
            Combine::NeeOnly => {
                if light_pdf > 0.0 {
                    0.0
                } else {
                    1.0
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_weights_sum_to_one_and_never_make_nan() {
        let values = [
            0.0,
            1e-30,
            1e-6,
            0.3,
            1.0,
            7.0,
            1e6,
            1e30,
            f32::MAX,
            f32::INFINITY,
        ];
        for &a in &values {
            for &b in &values {
                let (wa, wb) = (power_heuristic(a, b), power_heuristic(b, a));
                assert!(
                    wa.is_finite() && (0.0..=1.0).contains(&wa),
                    "w({a}, {b}) = {wa}"
                );
                if a > 0.0 || b > 0.0 {
                    assert!(
                        (wa + wb - 1.0).abs() < 1e-6,
                        "w({a}, {b}) + w({b}, {a}) = {}",
                        wa + wb
                    );
                }
            }
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert!((power_heuristic(3.0, 1.0) - 0.9).abs() < 1e-7);
    }
}
