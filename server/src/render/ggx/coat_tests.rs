//! The clear coat against its definition: the white furnace under every
//! coat, a dark material never gaining energy from it, the coat lobe's
//! integral against its tabulated albedo, sampling against the pdf.

use super::super::tests::{albedo_from as albedo, assert_samples_follow_the_pdf, dir};
use super::super::{eval_cos, pdf, sample, tables, Lobes, Pbr};
use super::*;
use crate::render::sampler::Sampler;

#[test]
fn a_white_material_under_a_coat_keeps_the_furnace_energy() {
    // Metal, coated diffuse, rough glass (from outside, where the coat is,
    // and from inside, where it is not), at several coat roughnesses.
    for coat_r in [0.03f32, 0.3, 1.0] {
        for (metallic, transmission, r) in [(1.0, 0.0, 0.2), (0.0, 0.0, 0.7), (0.0, 1.0, 0.4)] {
            for weight in [0.5, 1.0] {
                let p = Pbr::new(metallic, r, 1.5)
                    .transmitting(transmission)
                    .coated(weight, coat_r);
                for entering in [true, false] {
                    for mu in [0.1, 0.5, 1.0] {
                        let a = albedo(&p, Vec3A::ONE, (dir(mu, 0.3), entering), 100_000);
                        assert!(
                            (a - Vec3A::ONE).abs().max_element() < 0.01,
                            "coat {weight} at roughness {coat_r} over metallic {metallic} \
                             transmission {transmission} roughness {r}, entering {entering}, \
                             mu {mu}: albedo {a}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn a_dark_material_never_gains_energy_from_its_coat() {
    let base = Vec3A::new(0.9, 0.5, 0.1);
    for coat_r in [0.05f32, 0.5] {
        for metallic in [0.0, 1.0] {
            let p = Pbr::new(metallic, 0.5, 1.5).coated(1.0, coat_r);
            for mu in [0.05, 0.5, 1.0] {
                let a = albedo(&p, base, (dir(mu, 1.0), true), 100_000);
                assert!(
                    a.max_element() < 1.0 && a.min_element() > 0.0,
                    "metallic {metallic} coat roughness {coat_r} mu {mu}: albedo {a}"
                );
            }
        }
        // The coat adds a white reflection: a black diffuse base reflects
        // more under it, and its blue channel more than without.
        let bare = Pbr::new(0.0, 1.0, 1.5);
        let black = Vec3A::ZERO;
        let (without, with) = (
            albedo(&bare, black, (dir(0.3, 0.0), true), 50_000),
            albedo(
                &bare.coated(1.0, coat_r),
                black,
                (dir(0.3, 0.0), true),
                50_000,
            ),
        );
        assert!(with.x > without.x + 0.01, "{without} -> {with}");
    }
}

#[test]
fn the_coat_lobe_integrates_to_its_albedo() {
    // Midpoint quadrature of the coat's eval over the hemisphere against
    // weight (F0 A + B + (1 - E) fms) from the tables: the coat reflects
    // what it takes from the base.
    let t = tables();
    for coat_r in [0.2f32, 0.6, 1.0] {
        for mu in [0.2f32, 0.7, 1.0] {
            let wo = dir(mu, 0.0);
            let alpha = (coat_r * coat_r).max(super::super::ALPHA_MIN);
            let c = Coat::new(t, (0.8, coat_r, alpha), wo, 0.5);
            let (nt, np) = (1000, 400);
            let mut sum = 0.0f64;
            for i in 0..nt {
                let x = (i as f64 + 0.5) / nt as f64;
                let cos = (1.0 - x * x) as f32;
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    sum += f64::from(c.eval_cos(t, wo, dir(cos, phi))) * 2.0 * x;
                }
            }
            let integral = sum * std::f64::consts::TAU / (nt * np) as f64;
            let taken = f64::from(1.0 - c.keep);
            assert!(
                (integral - taken).abs() < 4e-3,
                "coat roughness {coat_r} mu {mu}: integral {integral} vs 1 - keep {taken}"
            );
        }
    }
}

#[test]
fn sampling_under_a_coat_follows_the_pdf_chi_square() {
    let t = tables();
    for (r, metallic, transmission, coat_r, mu) in [
        (0.6f32, 0.0f32, 0.0f32, 0.25f32, 0.6f32),
        (0.2, 1.0, 0.0, 0.5, 0.3),
        (0.4, 0.0, 1.0, 0.2, 0.8),
    ] {
        let p = Pbr::new(metallic, r, 1.5)
            .transmitting(transmission)
            .coated(1.0, coat_r);
        let what = format!(
            "roughness {r} metallic {metallic} transmission {transmission} coat {coat_r} mu {mu}"
        );
        assert_samples_follow_the_pdf(t, &p, dir(mu, 0.2), 17, &what);
    }
}

#[test]
fn weights_under_a_coat_are_eval_over_pdf_and_finite() {
    let t = tables();
    let base = Vec3A::new(0.9, 0.6, 0.3);
    for coat_r in [0.0f32, 0.3, 1.0] {
        for (metallic, transmission, ior) in [
            (0.0, 0.0, 1.5),
            (1.0, 0.0, 1.5),
            (0.0, 1.0, 1.5),
            (0.0, 1.0, 1.0),
        ] {
            let p = Pbr::new(metallic, 0.3, ior)
                .transmitting(transmission)
                .coated(0.7, coat_r);
            for k in 0..20_000u64 {
                let mut s = Sampler::new(19, k, 0);
                let (u1, u2) = s.next_2d();
                let wo = dir(u1.max(1e-6), u2 * std::f32::consts::TAU);
                let entering = k % 2 == 0;
                let choice = s.next_f32();
                let Some(x) = sample(t, &p, base, (wo, entering), choice, s.next_2d()) else {
                    continue;
                };
                assert!(
                    x.weight.is_finite() && x.pdf.is_finite(),
                    "{p:?} wo {wo}: {x:?}"
                );
                if x.pdf > 0.0 {
                    let lobes = Lobes::new(t, &p, base, wo, entering);
                    let w = eval_cos(t, &p, base, &lobes, wo, x.wi) / pdf(&p, &lobes, wo, x.wi);
                    assert!(
                        (w - x.weight).abs().max_element() <= 1e-4 * w.max_element().max(1.0),
                        "{p:?} wo {wo}: {} vs {w}",
                        x.weight
                    );
                }
            }
        }
    }
}

/// The mixture's sample from `wo` with the coat in `frame`.
fn sample_framed(
    p: &Pbr,
    base: Vec3A,
    wo: Vec3A,
    frame: Frame,
    s: &mut Sampler,
) -> Option<super::super::Sample> {
    let t = tables();
    let lobes = Lobes::framed(t, p, base, (wo, true), Some(frame));
    let choice = s.next_f32();
    super::super::sample_from(t, p, base, &lobes, wo, choice, s.next_2d())
}

#[test]
fn a_coat_on_its_own_normal_keeps_the_furnace_energy_and_follows_its_pdf() {
    // The coat's normal tilted 0.35 rad off the base's (as a normal map on
    // the base leaves it): a white material still reflects all it gets,
    // sampling still draws by the mixture's pdf.
    let t = tables();
    let n = Vec3A::new(0.35f32.sin(), 0.0, 0.35f32.cos());
    let frame = Frame::new(n);
    for (metallic, transmission, r, coat_r) in
        [(0.0f32, 0.0f32, 0.7f32, 0.1f32), (1.0, 0.0, 0.3, 0.4)]
    {
        let p = Pbr::new(metallic, r, 1.5)
            .transmitting(transmission)
            .coated(1.0, coat_r);
        for (mu, phi) in [(0.9f32, 0.0f32), (0.5, 3.0), (0.4, 0.0)] {
            let wo = dir(mu, phi);
            let count = 100_000u64;
            let mut sum = Vec3A::ZERO;
            for i in 0..count {
                let mut s = Sampler::new(7, i, 0);
                if let Some(x) = sample_framed(&p, Vec3A::ONE, wo, frame, &mut s) {
                    sum += x.weight;
                }
            }
            let a = sum / count as f32;
            assert!(
                (a - Vec3A::ONE).abs().max_element() < 0.01,
                "metallic {metallic} roughness {r} coat {coat_r}, wo {wo}: albedo {a}"
            );
        }
        let wo = dir(0.6, 0.4);
        let base = Vec3A::new(0.6, 0.5, 0.4);
        let lobes = Lobes::framed(t, &p, base, (wo, true), Some(frame));
        let draw =
            |k: u64| sample_framed(&p, base, wo, frame, &mut Sampler::new(23, k, 0)).map(|x| x.wi);
        let (chi2, dof, tail) =
            super::super::tests::sphere_chi2(400_000, draw, |w| pdf(&p, &lobes, wo, w));
        assert!(
            tail > 1e-4,
            "framed coat: chi2 {chi2:.1} with {dof} bins, p = {tail:.2e}"
        );
    }
}

#[test]
fn a_coat_on_the_base_normal_is_the_unframed_coat() {
    // Frame::new(z) is not the identity (its tangent may turn), but the
    // lobe is isotropic: eval and pdf agree with the unframed coat.
    let t = tables();
    let p = Pbr::new(0.0, 0.5, 1.5).coated(0.8, 0.3);
    let base = Vec3A::new(0.7, 0.5, 0.3);
    let wo = dir(0.7, 1.0);
    let plain = Lobes::new(t, &p, base, wo, true);
    let framed = Lobes::framed(t, &p, base, (wo, true), Some(Frame::new(Vec3A::Z)));
    for k in 0..200u64 {
        let mut s = Sampler::new(3, k, 0);
        let (u1, u2) = s.next_2d();
        let wi = dir(u1 * 2.0 - 1.0, u2 * std::f32::consts::TAU);
        let (a, b) = (
            eval_cos(t, &p, base, &plain, wo, wi),
            eval_cos(t, &p, base, &framed, wo, wi),
        );
        assert!((a - b).abs().max_element() < 1e-5, "{wi}: {a} vs {b}");
        let (a, b) = (pdf(&p, &plain, wo, wi), pdf(&p, &framed, wo, wi));
        assert!((a - b).abs() < 1e-4 * a.max(1.0), "{wi}: {a} vs {b}");
    }
    // Seen from behind its normal the coat is gone: the base is bare.
    let behind = Lobes::framed(t, &p, base, (wo, true), Some(Frame::new(-wo)));
    let bare = Lobes::new(t, &Pbr { coat: 0.0, ..p }, base, wo, true);
    let wi = dir(0.5, 2.0);
    assert_eq!(
        eval_cos(t, &p, base, &behind, wo, wi),
        eval_cos(t, &p, base, &bare, wo, wi)
    );
}
