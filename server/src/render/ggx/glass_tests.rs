//! The rough dielectric lobe against its own definition: energy in a white
//! furnace, the table against a plain quadrature of eval, the pdf's
//! integral over the sphere, sampling against the pdf (chi-square), and
//! the BTDF's generalised reciprocity.

use super::super::tests::{dir, sphere_chi2};
use super::super::ALPHA_MIN;
use super::*;
use crate::render::sampler::Sampler;

fn lobe(roughness: f32, ior: f32, wo: Vec3A, entering: bool) -> Glass {
    let alpha = (roughness * roughness).max(ALPHA_MIN);
    Glass::new(alpha, roughness, ior, wo, entering)
}

/// A thin wall's lobe (its compensation from the reflection tables).
fn thin_lobe(roughness: f32, ior: f32, wo: Vec3A) -> Glass {
    let alpha = (roughness * roughness).max(ALPHA_MIN);
    let e = super::super::tables().single_scattering(wo.z, roughness);
    Glass::thin(alpha, ior, 1.0 / e)
}

/// The mean of sample weights (eval / pdf) from `wo`.
fn albedo(g: &Glass, wo: Vec3A, n: u64) -> f64 {
    let mut sum = 0.0f64;
    for k in 0..n {
        let mut s = Sampler::new(5, k, 0);
        let choice = s.next_f32();
        if let Some(wi) = g.sample(wo, choice, s.next_2d()) {
            let (r, t) = g.eval_cos(wo, wi);
            sum += f64::from((r.x + t) / g.pdf(wo, wi));
        }
    }
    sum / n as f64
}

/// Integral over the sphere of `f`, in cos(theta) by x with cos = +-(1 -
/// x^2) (dense near both poles, where narrow lobes are) and in phi.
fn over_sphere(f: impl Fn(Vec3A) -> f64) -> f64 {
    let (nt, np) = (1500, 600);
    let mut sum = 0.0f64;
    for side in [1.0f32, -1.0] {
        for i in 0..nt {
            let x = (i as f64 + 0.5) / nt as f64;
            let cos = (1.0 - x * x) as f32 * side;
            for j in 0..np {
                let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                sum += f(dir(cos, phi)) * 2.0 * x;
            }
        }
    }
    sum * std::f64::consts::TAU / (nt * np) as f64
}

#[test]
fn white_rough_glass_keeps_the_furnace_energy() {
    // Reflected plus transmitted, compensated, is 1 from every angle, both
    // sides, at every roughness and index (within 1%: the table's
    // quadrature and interpolation, and noise).
    for r in [0.05f32, 0.3, 0.6, 1.0] {
        for ior in [1.33f32, 1.5, 2.4] {
            for entering in [true, false] {
                for mu in [0.1f32, 0.5, 0.95] {
                    let wo = dir(mu, 0.7);
                    let a = albedo(&lobe(r, ior, wo, entering), wo, 100_000);
                    assert!(
                        (a - 1.0).abs() < 0.01,
                        "roughness {r} ior {ior} entering {entering} mu {mu}: albedo {a}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_white_thin_wall_keeps_the_furnace_energy() {
    for r in [0.05f32, 0.3, 0.6, 1.0] {
        for mu in [0.1f32, 0.5, 0.95] {
            let wo = dir(mu, 0.7);
            let a = albedo(&thin_lobe(r, 1.5, wo), wo, 100_000);
            assert!((a - 1.0).abs() < 0.01, "roughness {r} mu {mu}: albedo {a}");
        }
    }
}

#[test]
fn a_thin_wall_passes_light_unrefracted() {
    // At roughness near 0 a ray through a thin wall keeps its direction
    // (a solid's would bend towards the normal).
    // (GGX's tails: a few samples stray further even at alpha 1e-3.)
    let wo = dir(0.6, 0.0);
    let g = thin_lobe(0.0, 1.5, wo);
    let (mut through, mut near) = (0, 0);
    for k in 0..1000u64 {
        let mut s = Sampler::new(8, k, 0);
        let choice = s.next_f32();
        if let Some(wi) = g.sample(wo, choice, s.next_2d()) {
            let straight = if wi.z < 0.0 {
                -wo
            } else {
                dir(0.6, std::f32::consts::PI)
            };
            through += usize::from(wi.z < 0.0);
            near += usize::from((wi - straight).length() < 0.01);
        }
    }
    assert!(
        near >= 970,
        "{near} of 1000 within 0.01 of the straight line"
    );
    assert!(through > 900, "{through} of 1000 through (F ~ 4%)");
}

#[test]
fn the_table_is_what_a_plain_quadrature_of_eval_gives() {
    // E(mu) = integral of the uncompensated BSDF cos over the sphere (no
    // sampling), against the table.
    for (r, ior, entering, mu) in [
        (0.3f32, 1.5f32, true, 0.6f32),
        (0.6, 1.5, false, 0.9),
        (1.0, 2.0, true, 0.3),
        (0.5, 1.33, false, 0.5),
    ] {
        let wo = dir(mu, 0.0);
        let mut g = lobe(r, ior, wo, entering);
        g.scale = 1.0;
        let e = over_sphere(|wi| {
            let (a, b) = g.eval_cos(wo, wi);
            f64::from(a.x + b)
        });
        let table = f64::from(table().albedo(mu, r, ior, entering));
        assert!(
            (e - table).abs() < 5e-3,
            "roughness {r} ior {ior} entering {entering} mu {mu}: {e} vs table {table}"
        );
    }
}

#[test]
fn the_pdf_integrates_to_what_lands_on_the_right_side() {
    for (r, ior, entering, mu, thin) in [
        (0.3f32, 1.5f32, true, 0.7f32, false),
        (0.7, 1.5, false, 0.4, false),
        (0.4, 1.5, true, 0.5, true),
    ] {
        let wo = dir(mu, 0.4);
        let g = match thin {
            true => thin_lobe(r, ior, wo),
            false => lobe(r, ior, wo, entering),
        };
        let total = over_sphere(|wi| f64::from(g.pdf(wo, wi)));
        // Samples that leave on the wrong side are not counted by the pdf.
        let n = 200_000u64;
        let lost = (0..n)
            .filter(|&k| {
                let mut s = Sampler::new(3, k, 0);
                let choice = s.next_f32();
                g.sample(wo, choice, s.next_2d()).is_none()
            })
            .count() as f64
            / n as f64;
        assert!(
            (total - (1.0 - lost)).abs() < 4e-3,
            "roughness {r} entering {entering}: {total} vs {} ({lost} lost)",
            1.0 - lost
        );
    }
}

#[test]
fn the_btdf_is_reciprocal_up_to_eta_squared() {
    // Seen from the far side (mirrored so that it is above), the same pair
    // with eta inverted: f(wo, wi) = eta^2 f(wi, wo).
    let flip = |v: Vec3A| Vec3A::new(v.x, v.y, -v.z);
    for r in [0.4f32, 0.7, 1.0] {
        for (a, b) in [((0.3, 0.1), (-0.8, 3.0)), ((0.9, 1.0), (-0.95, 4.5))] {
            let (wo, wi) = (dir(a.0, a.1), dir(b.0, b.1));
            let alpha = r * r;
            let g = Glass {
                alpha,
                eta: 1.5,
                scale: 1.0,
                thin: false,
                tint: None,
            };
            let back = Glass {
                eta: 1.0 / 1.5,
                ..g
            };
            let fo = g.eval_cos(wo, wi).1 / wi.z.abs();
            let fi = back.eval_cos(flip(wi), flip(wo)).1 / wo.z;
            assert!(fo > 0.0, "roughness {r}: the pair refracts");
            assert!(
                (fo - 1.5 * 1.5 * fi).abs() <= 1e-4 * fo,
                "roughness {r}: {fo} vs eta^2 {fi}"
            );
        }
    }
}

#[test]
fn sampling_follows_the_pdf_chi_square() {
    for (r, ior, entering, mu, thin) in [
        (0.2f32, 1.5f32, true, 0.6f32, false),
        (0.5, 1.5, false, 0.8, false),
        (0.35, 1.33, false, 0.3, false),
        (0.8, 2.0, true, 0.2, false),
        (0.4, 1.5, true, 0.6, true),
    ] {
        let wo = dir(mu, 0.2);
        let g = match thin {
            true => thin_lobe(r, ior, wo),
            false => lobe(r, ior, wo, entering),
        };
        let draw = |k: u64| {
            let mut s = Sampler::new(11, k, 0);
            let choice = s.next_f32();
            g.sample(wo, choice, s.next_2d())
        };
        let (chi2, dof, tail) = sphere_chi2(400_000, draw, |w| g.pdf(wo, w));
        assert!(
            tail > 1e-4,
            "roughness {r} ior {ior} entering {entering} thin {thin} mu {mu}: \
             chi2 {chi2:.1} with {dof} bins, p = {tail:.2e}"
        );
    }
}

/// `KHR_materials_specular` on rough glass: a material transmitting all
/// its dielectric, with specular `factor` and `color`.
fn specular_glass(roughness: f32, factor: f32, color: Vec3A, thin: bool) -> super::super::Pbr {
    super::super::Pbr::new(0.0, roughness, 1.5)
        .transmitting(1.0)
        .thin_walled(thin)
        .specular(factor, color)
}

#[test]
fn specular_tints_and_scales_the_glass_reflection_and_keeps_energy() {
    use super::super::tests::albedo_from;
    // Untinted, the glass keeps its exact Fresnel: no tint at all.
    let plain = specular_glass(0.3, 1.0, Vec3A::ONE, false);
    assert_eq!(Tint::new(plain.f0, plain.spec_f0, plain.spec_f90), None);
    let color = Vec3A::new(1.0, 0.5, 0.25);
    for r in [0.05f32, 0.3] {
        for thin in [false, true] {
            for entering in [true, false] {
                for mu in [0.2f32, 0.7, 1.0] {
                    let wo = dir(mu, 0.3);
                    // The strongest channel reflects as much as untinted
                    // glass and transmits the rest: the furnace's value; the
                    // others reflect less and never gain.
                    let p = specular_glass(r, 1.0, color, thin);
                    let a = albedo_from(&p, Vec3A::ONE, (wo, entering), 100_000);
                    let what = format!("roughness {r} thin {thin} entering {entering} mu {mu}");
                    assert!((a.x - 1.0).abs() < 0.02, "{what}: tinted albedo {a}");
                    assert!(
                        a.max_element() < 1.02 && a.y <= a.x + 1e-3 && a.z <= a.y + 1e-3,
                        "{what}: {a}"
                    );
                    // Specular 0: nothing reflected from outside, everything
                    // through (inside, total internal reflection stays).
                    let p = specular_glass(r, 0.0, Vec3A::ONE, thin);
                    let t = super::super::tables();
                    let lobes = super::super::Lobes::new(t, &p, Vec3A::ONE, wo, entering);
                    let up = super::super::eval_cos(t, &p, Vec3A::ONE, &lobes, wo, dir(mu, 3.4));
                    if entering {
                        assert_eq!(up, Vec3A::ZERO, "{what}: specular 0 reflects {up}");
                    }
                    let a = albedo_from(&p, Vec3A::ONE, (wo, entering), 100_000);
                    assert!(
                        (a - Vec3A::ONE).abs().max_element() < 0.03,
                        "{what}: specular 0 albedo {a}"
                    );
                }
            }
        }
    }
}

#[test]
fn tinted_glass_samples_follow_the_pdf_chi_square() {
    let t = super::super::tables();
    for (r, thin, mu) in [(0.3f32, false, 0.6f32), (0.5, true, 0.4)] {
        let p = specular_glass(r, 0.6, Vec3A::new(0.3, 1.0, 0.6), thin);
        let what = format!("tinted glass roughness {r} thin {thin} mu {mu}");
        super::super::tests::assert_samples_follow_the_pdf(t, &p, dir(mu, 0.7), 29, &what);
    }
}
