//! The metallic-roughness BSDF against its own definition: energy in a
//! white furnace, sampling against the pdf (chi-square), the pdf's
//! integral, reciprocity.

use super::*;
use crate::render::sampler::Sampler;

const ROUGHNESS: [f32; 5] = [0.05, 0.25, 0.5, 0.75, 1.0];

pub(super) fn dir(cos: f32, phi: f32) -> Vec3A {
    let s = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3A::new(s * phi.cos(), s * phi.sin(), cos)
}

/// The directional albedo seen from `wo` from outside: the mean of sample
/// weights.
fn albedo(p: &Pbr, base: Vec3A, wo: Vec3A, n: u64) -> Vec3A {
    albedo_from(p, base, (wo, true), n)
}

/// The directional albedo seen from `wo` on the side `entering` says.
pub(super) fn albedo_from(p: &Pbr, base: Vec3A, (wo, entering): (Vec3A, bool), n: u64) -> Vec3A {
    let t = tables();
    let mut sum = Vec3A::ZERO;
    for i in 0..n {
        let mut s = Sampler::new(7, i, 0);
        let choice = s.next_f32();
        let u = s.next_2d();
        if let Some(s) = sample(t, p, base, (wo, entering), choice, u) {
            sum += s.weight;
        }
    }
    sum / n as f32
}

#[test]
fn white_lobes_keep_the_furnace_energy_at_every_roughness() {
    // A white metal and a white base under the dielectric coating reflect
    // everything, at every roughness and angle (within 1%: the tables'
    // quadrature and interpolation, and 1/sqrt(n) noise).
    for r in ROUGHNESS {
        for metallic in [1.0, 0.0] {
            let p = Pbr::new(metallic, r, 1.5);
            for mu in [0.05, 0.2, 0.5, 0.8, 1.0] {
                let a = albedo(&p, Vec3A::ONE, dir(mu, 0.3), 200_000);
                for c in a.to_array() {
                    assert!(
                        (c - 1.0).abs() < 0.01,
                        "metallic {metallic} roughness {r} mu {mu}: albedo {a}"
                    );
                }
            }
        }
    }
}

#[test]
fn transmitting_materials_keep_the_furnace_energy() {
    // Rough glass alone, and mixed with the coated diffuse and the metal,
    // from outside and from inside: reflected plus transmitted is 1.
    let t = tables();
    for r in [0.05f32, 0.3, 0.7] {
        for (metallic, transmission) in [(0.0, 1.0), (0.0, 0.5), (0.5, 0.7)] {
            let p = Pbr::new(metallic, r, 1.5).transmitting(transmission);
            for entering in [true, false] {
                for mu in [0.1, 0.5, 1.0] {
                    let wo = dir(mu, 0.3);
                    let mut sum = Vec3A::ZERO;
                    let n = 100_000u64;
                    for i in 0..n {
                        let mut s = Sampler::new(9, i, 0);
                        let choice = s.next_f32();
                        let u = s.next_2d();
                        if let Some(s) = sample(t, &p, Vec3A::ONE, (wo, entering), choice, u) {
                            sum += s.weight;
                        }
                    }
                    let a = sum / n as f32;
                    assert!(
                        (a - Vec3A::ONE).abs().max_element() < 0.01,
                        "metallic {metallic} transmission {transmission} roughness {r} \
                         entering {entering} mu {mu}: albedo {a}"
                    );
                }
            }
        }
    }
}

#[test]
fn darker_materials_never_gain_energy() {
    for r in ROUGHNESS {
        for metallic in [1.0, 0.5, 0.0] {
            let p = Pbr::new(metallic, r, 1.5);
            let base = Vec3A::new(0.9, 0.5, 0.1);
            for mu in [0.05, 0.5, 1.0] {
                let a = albedo(&p, base, dir(mu, 1.0), 100_000);
                assert!(
                    a.max_element() < 1.0 && a.min_element() > 0.0,
                    "metallic {metallic} roughness {r} mu {mu}: albedo {a}"
                );
            }
        }
    }
}

#[test]
fn the_tables_are_what_a_plain_integration_gives() {
    // E(mu) by midpoint quadrature over the hemisphere of the single-
    // scattering lobe (no importance sampling), against the table.
    let t = tables();
    for r in [0.3f32, 0.7, 1.0] {
        let alpha = (r * r).max(ALPHA_MIN);
        for mu in [0.2f32, 0.6, 0.95] {
            let wo = dir(mu, 0.0);
            let (nt, np) = (800, 400);
            let mut sum = 0.0f64;
            for i in 0..nt {
                let cos = (i as f32 + 0.5) / nt as f32;
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    let wi = dir(cos, phi);
                    let h = (wo + wi).normalize();
                    let f = distribution(h, alpha)
                        / (2.0 * (smith_r(wo, alpha) * wi.z + smith_r(wi, alpha) * wo.z));
                    sum += f64::from(f * wi.z);
                }
            }
            let e = sum * std::f64::consts::TAU / (nt * np) as f64;
            let table = f64::from(t.at(0, mu, r) + t.at(1, mu, r));
            assert!(
                (e - table).abs() < 4e-3,
                "roughness {r} mu {mu}: {e} vs table {table}"
            );
        }
    }
}

#[test]
fn the_pdf_integrates_to_one() {
    let t = tables();
    for r in [0.3f32, 0.6, 1.0] {
        for metallic in [0.0, 1.0] {
            let p = Pbr::new(metallic, r, 1.5);
            let wo = dir(0.7, 0.4);
            let lobes = Lobes::new(t, &p, Vec3A::new(0.8, 0.6, 0.4), wo, true);
            let (nt, np) = (2000, 1000);
            let mut sum = 0.0f64;
            for i in 0..nt {
                // Denser near the normal, where narrow lobes are: cos = 1 - x^2.
                let x = (i as f64 + 0.5) / nt as f64;
                let cos = (1.0 - x * x) as f32;
                let jac = 2.0 * x; // d cos / d x
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    sum += f64::from(pdf(&p, &lobes, wo, dir(cos, phi))) * jac;
                }
            }
            let total = sum * std::f64::consts::TAU / (nt * np) as f64;
            // Reflections of visible normals that point below the surface
            // are samples the pdf does not count (they end the path).
            let n = 200_000u64;
            let below = (0..n)
                .filter(|&k| {
                    let mut s = Sampler::new(3, k, 0);
                    let (u1, u2) = s.next_2d();
                    reflect_about(wo, visible_normal(wo, p.alpha, u1, u2)).z <= 0.0
                })
                .count() as f64
                / n as f64;
            let expected = 1.0 - f64::from(lobes.p_spec) * below;
            assert!(
                (total - expected).abs() < 3e-3,
                "roughness {r} metallic {metallic}: {total} vs {expected} ({below} below)"
            );
        }
    }
}

#[test]
fn eval_is_reciprocal() {
    let t = tables();
    let base = Vec3A::new(0.7, 0.3, 0.9);
    for r in ROUGHNESS {
        for metallic in [0.0, 0.4, 1.0] {
            let p = Pbr::new(metallic, r, 1.45);
            for (a, b) in [((0.3, 0.1), (0.8, 2.0)), ((0.9, 1.0), (0.15, 4.0))] {
                let (wo, wi) = (dir(a.0, a.1), dir(b.0, b.1));
                let fo = eval_cos(t, &p, base, &Lobes::new(t, &p, base, wo, true), wo, wi) / wi.z;
                let fi = eval_cos(t, &p, base, &Lobes::new(t, &p, base, wi, true), wi, wo) / wo.z;
                assert!(
                    (fo - fi).abs().max_element() <= 1e-4 * fo.max_element().max(1e-3),
                    "roughness {r} metallic {metallic}: {fo} vs {fi}"
                );
            }
        }
    }
}

/// Upper tail of chi-square with `dof` degrees of freedom at `x`
/// (Wilson-Hilferty normal approximation).
fn chi2_tail(x: f64, dof: f64) -> f64 {
    let z = ((x / dof).powf(1.0 / 3.0) - (1.0 - 2.0 / (9.0 * dof))) / (2.0 / (9.0 * dof)).sqrt();
    0.5 * erfc(z / std::f64::consts::SQRT_2)
}

fn erfc(x: f64) -> f64 {
    // Numerical Recipes' erfc (fractional error below 1.2e-7).
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// A chi-square goodness-of-fit test of directions over the sphere: `n`
/// samples (`draw(k)`, None for one that gives no direction) binned in
/// (cos theta, phi), 32 x 16, against the counts `pdf` integrated over each
/// bin predicts; bins expecting fewer than 5 pooled. The statistic, its
/// degrees of freedom and its upper-tail probability.
pub(super) fn sphere_chi2(
    n: u64,
    draw: impl Fn(u64) -> Option<Vec3A>,
    pdf: impl Fn(Vec3A) -> f32,
) -> (f64, f64, f64) {
    let (bt, bp) = (32usize, 16usize);
    let bin = |w: Vec3A| {
        let i = (((w.z + 1.0) * 0.5 * bt as f32) as usize).min(bt - 1);
        let phi = w.y.atan2(w.x).rem_euclid(std::f32::consts::TAU);
        let j = ((phi / std::f32::consts::TAU * bp as f32) as usize).min(bp - 1);
        i * bp + j
    };
    let mut observed = vec![0f64; bt * bp];
    for wi in (0..n).filter_map(draw) {
        observed[bin(wi)] += 1.0;
    }
    let sub = 24;
    let mut expected = vec![0f64; bt * bp];
    let area = 2.0 * std::f64::consts::TAU / ((bt * sub) * (bp * sub)) as f64;
    for i in 0..bt * sub {
        let cos = (i as f32 + 0.5) / (bt * sub) as f32 * 2.0 - 1.0;
        for j in 0..bp * sub {
            let phi = (j as f32 + 0.5) / (bp * sub) as f32 * std::f32::consts::TAU;
            let w = dir(cos, phi);
            expected[bin(w)] += f64::from(pdf(w)) * area * n as f64;
        }
    }
    let (mut chi2, mut dof, mut pool_o, mut pool_e) = (0.0, 0.0, 0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        if *e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof += 1.0;
        }
    }
    if pool_e >= 5.0 {
        chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        dof += 1.0;
    }
    (chi2, dof, chi2_tail(chi2, dof - 1.0))
}

#[test]
fn sampling_follows_the_pdf_chi_square() {
    // Over the sphere, not the hemisphere: transmitting materials sample
    // both. Directions on the wrong side count too (where samples land,
    // weights aside).
    let t = tables();
    for (r, metallic, mu, transmission) in [
        (0.2f32, 1.0f32, 0.6f32, 0.0f32),
        (0.6, 0.0, 0.3, 0.0),
        (1.0, 0.5, 0.9, 0.0),
        (0.35, 0.0, 0.8, 0.0),
        (0.3, 0.0, 0.7, 0.6),
        (0.5, 0.3, 0.4, 1.0),
    ] {
        let p = Pbr::new(metallic, r, 1.5).transmitting(transmission);
        let what = format!("roughness {r} metallic {metallic} transmission {transmission} mu {mu}");
        assert_samples_follow_the_pdf(t, &p, dir(mu, 0.2), 11, &what);
    }
}

/// Directions [`sample`]d from `wo` (outside, a fixed base colour, seed
/// `seed`) pass the chi-square test against [`pdf`] at p > 1e-4.
pub(super) fn assert_samples_follow_the_pdf(t: &Tables, p: &Pbr, wo: Vec3A, seed: u64, what: &str) {
    let base = Vec3A::new(0.6, 0.5, 0.4);
    let lobes = Lobes::new(t, p, base, wo, true);
    let draw = |k: u64| {
        let mut s = Sampler::new(seed, k, 0);
        let choice = s.next_f32();
        let u = s.next_2d();
        sample(t, p, base, (wo, true), choice, u).map(|s| s.wi)
    };
    let (chi2, dof, tail) = sphere_chi2(400_000, draw, |w| pdf(p, &lobes, wo, w));
    assert!(
        tail > 1e-4,
        "{what}: chi2 {chi2:.1} with {dof} bins, p = {tail:.2e}"
    );
}

#[test]
fn weights_and_densities_are_finite_from_every_angle() {
    // Grazing, normal and everything between, both sides, every mix, and
    // indices at and near 1 (where refraction's half vector is undefined:
    // index-matched glass is a delta straight through): a sample is either
    // no contribution or a finite weight and density.
    let t = tables();
    let base = Vec3A::new(0.9, 0.6, 0.3);
    for (ior, n) in [
        (1.5, 200_000u64),
        (1.0, 40_000),
        (1.0005, 40_000),
        (1.0011, 40_000),
        (1.01, 40_000),
    ] {
        for r in [0.0f32, 0.02, 0.3, 1.0] {
            for (metallic, transmission) in [(0.0, 1.0), (0.0, 0.5), (0.4, 0.6), (0.0, 0.0)] {
                let p = Pbr::new(metallic, r, ior).transmitting(transmission);
                for k in 0..n {
                    let mut s = Sampler::new(21, k, 0);
                    let (u1, u2) = s.next_2d();
                    let wo = dir(u1.max(1e-7), u2 * std::f32::consts::TAU);
                    let entering = k % 2 == 0;
                    let choice = s.next_f32();
                    let (v1, v2) = s.next_2d();
                    let wi = dir(v1 * 2.0 - 1.0, v2 * std::f32::consts::TAU);
                    let lobes = Lobes::new(t, &p, base, wo, entering);
                    let (f, d) = (
                        eval_cos(t, &p, base, &lobes, wo, wi),
                        pdf(&p, &lobes, wo, wi),
                    );
                    assert!(
                        f.is_finite() && d.is_finite(),
                        "roughness {r} metallic {metallic} transmission {transmission} \
                     wo {wo} wi {wi} entering {entering}: eval {f} pdf {d}"
                    );
                    if let Some(x) = sample(t, &p, base, (wo, entering), choice, s.next_2d()) {
                        let matched =
                            ior < 1.001 && x.wi == -wo && x.weight == base && x.pdf == 0.0;
                        assert!(
                        x.weight.is_finite() && x.pdf.is_finite() && (x.pdf > 0.0 || matched),
                        "ior {ior} roughness {r} metallic {metallic} transmission {transmission} \
                         wo {wo} entering {entering}: {x:?}"
                    );
                    }
                }
            }
        }
    }
}

#[test]
fn white_lobes_keep_the_furnace_energy_under_any_specular() {
    // KHR_materials_specular weakens or tints the dielectric's reflection;
    // a white base takes whatever it leaves, per channel: still 1.
    for r in [0.1f32, 0.5, 1.0] {
        for (factor, color) in [
            (0.0, Vec3A::ONE),
            (0.5, Vec3A::ONE),
            (1.0, Vec3A::new(1.0, 0.4, 0.1)),
            (0.7, Vec3A::new(20.0, 5.0, 1.0)),
        ] {
            let p = Pbr::new(0.0, r, 1.5).specular(factor, color);
            for mu in [0.1, 0.5, 1.0] {
                let a = albedo(&p, Vec3A::ONE, dir(mu, 0.3), 100_000);
                assert!(
                    (a - Vec3A::ONE).abs().max_element() < 0.01,
                    "specular {factor} colour {color} roughness {r} mu {mu}: albedo {a}"
                );
            }
        }
    }
}

#[test]
fn a_tinted_specular_reflects_its_colour_off_a_black_base() {
    // Over a black base only the dielectric reflects: at normal incidence
    // a smooth one reflects about F0 = min(0.04 colour, 1) factor per
    // channel, in the colour's order.
    let p = Pbr::new(0.0, 0.05, 1.5).specular(0.8, Vec3A::new(10.0, 5.0, 1.0));
    let a = albedo(&p, Vec3A::ZERO, dir(0.999, 0.0), 100_000);
    let f0 = (Vec3A::new(10.0, 5.0, 1.0) * 0.04).min(Vec3A::ONE) * 0.8;
    assert!((a - f0).abs().max_element() < 0.02, "albedo {a}, F0 {f0}");
    assert!(a.x > a.y && a.y > a.z, "{a}");
}

#[test]
fn sampling_under_a_tinted_specular_follows_the_pdf_chi_square() {
    let p = Pbr::new(0.2, 0.4, 1.5).specular(0.6, Vec3A::new(2.0, 1.0, 0.3));
    assert_samples_follow_the_pdf(tables(), &p, dir(0.5, 0.2), 23, "tinted specular");
}
