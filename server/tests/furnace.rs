//! White furnace checks: inside a closed diffuse sphere with albedo a and
//! emission E the radiance is E (1 - a^(D+1)) / (1 - a) with depth cap D,
//! and E / (1 - a) unbounded, with NEE on or off.

mod common;

use common::{assert_clean, assert_mean, furnace, render};
use pathstream::render::scene::{GlassJson, MaterialJson, ObjectJson, SphereJson};
use pathstream::render::{Filter, Quality, Scene};

#[test]
fn depth_capped_furnace_is_exact_with_and_without_nee() {
    // Every path meets the shell at every bounce, so with Russian roulette
    // out of reach each sample is the closed form itself, up to rounding:
    // a shadow ray to a point of the shell close to where it leaves has
    // cosines and a distance that cancel with f32 error ~1e-7 R / d
    // (measured worst pixel over 20 seeds at depth 8: 9.5e-6 with random
    // numbers, 1.4e-5 with Sobol points; every other depth 2e-7).
    for (a, e) in [(0.5, 0.5), (0.8, 0.25), (0.3, 2.0)] {
        let s = furnace(a, e);
        for depth in [1u32, 2, 3, 5, 8] {
            let expected = e * (1.0 - a.powi(depth as i32 + 1)) / (1.0 - a);
            for nee in [true, false] {
                let q = Quality {
                    max_depth: depth,
                    rr_depth: 1000,
                    nee,
                    ..Quality::default()
                };
                let film = render(&s, 8, 8, &q, 8);
                assert_clean(&film, "furnace");
                for px in film.mean() {
                    for v in px {
                        let rel = (f64::from(v) - expected).abs() / expected;
                        assert!(
                            rel < 5e-5,
                            "a {a} E {e} depth {depth} nee {nee}: {v} vs {expected}"
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn unbounded_furnace_converges_to_e_over_one_minus_a() {
    for nee in [true, false] {
        let s = furnace(0.5, 0.5);
        let q = Quality {
            max_depth: 0,
            rr_depth: 2,
            nee,
            filter: Filter::Box,
            ..Quality::default()
        };
        let film = render(&s, 16, 16, &q, 256);
        assert_clean(&film, "furnace");
        assert_mean(
            &film,
            4,
            1.0,
            4.5,
            0.0,
            &format!("unbounded furnace, nee {nee}"),
        );
        // The estimate must also be noisy only as much as RR makes it.
        let e = film.error_estimate().expect("estimate");
        assert!(e < 0.05, "error estimate {e}");
    }
}

#[test]
fn an_albedo_one_glass_sphere_in_the_furnace_is_invisible() {
    use pathstream::render::scene::FresnelJson;
    for fresnel in [FresnelJson::Exact, FresnelJson::Schlick] {
        let mut json = furnace(0.5, 0.5).to_json();
        json.materials.insert(
            "clear".into(),
            MaterialJson::Glass(GlassJson {
                ior: 1.5,
                albedo: None,
                fresnel,
                attenuation: None,
                emission: None,
                normal: None,
            }),
        );
        json.objects.push(ObjectJson::Sphere(SphereJson {
            center: [0.1, -0.05, -0.5],
            radius: 0.3,
            material: "clear".into(),
        }));
        let s = Scene::from_json(&json).expect("valid");
        for nee in [true, false] {
            let q = Quality {
                max_depth: 0,
                rr_depth: 4,
                nee,
                ..Quality::default()
            };
            let film = render(&s, 16, 16, &q, 256);
            assert_clean(&film, "glass furnace");
            assert_mean(
                &film,
                4,
                1.0,
                4.5,
                0.0,
                &format!("glass ({fresnel:?}) in furnace, nee {nee}"),
            );
        }
    }
}
