//! The ends of every range: lights, glass, resolutions, samples and seeds,
//! quality knobs, and input beyond them.

use super::*;

/// Lights: intensity 1e-6 .. 1e8 scales the image linearly; a light of
/// radius 1e-4; the camera inside a light; a point on a light's surface.
#[test]
fn extreme_lights() {
    let base = scene("cornell");
    let with_light = |scale: f64, radius: f64| {
        let mut s = base.clone();
        let light = s.light.expect("light");
        let m = s.objects[light].material;
        s.materials[m].emission *= scale;
        if let pathstream::render::scene::Shape::Sphere { center, .. } = s.objects[light].shape {
            s.objects[light].shape = pathstream::render::scene::Shape::Sphere { center, radius };
        }
        Scene::from_json(&s.to_json()).expect("valid")
    };
    for mut b in backends() {
        // Same seed: every sample's path is the same, so the image scales
        // exactly (up to f32 rounding).
        let one = render_on(&mut b, &with_light(1.0, 7.0), 8, 8, &q(11), 16).mean();
        for scale in [1e-6, 1e-3, 1e3, 1e8] {
            let film = render_on(&mut b, &with_light(scale, 7.0), 8, 8, &q(11), 16);
            assert_clean(&film, "intensity");
            for (a, s) in one.iter().zip(film.mean()) {
                for c in 0..3 {
                    let expect = f64::from(a[c]) * scale;
                    assert!(
                        (f64::from(s[c]) - expect).abs() <= 1e-4 * expect.abs() + 1e-30,
                        "{}: scale {scale:e}: {} vs {expect}",
                        b.name(),
                        s[c]
                    );
                }
            }
        }
        // A light of radius 1e-4 gives the room the same light as one of
        // radius 0.1 of equal power (radiance x r^2). Both sit in a corner
        // the camera cannot see, so only the light they cast is compared;
        // at 1.0 from the nearest wall the bigger one's size changes that
        // by well under the 2% floor.
        let corner = DVec3::new(2.5, 79.0, 160.0);
        let at = |radius: f64| {
            let mut s = with_light((7.0 / radius).powi(2), radius);
            let light = s.light.expect("light");
            s.objects[light].shape = pathstream::render::scene::Shape::Sphere {
                center: corner,
                radius,
            };
            Scene::from_json(&s.to_json()).expect("valid")
        };
        let tiny = render_on(&mut b, &at(1e-4), 16, 16, &q(12), 256);
        let small = render_on(&mut b, &at(0.1), 16, 16, &q(13), 256);
        assert_clean(&tiny, "tiny light");
        assert!(
            common::regions(&small, 16)[0].mean[1] > 0.01,
            "the corner light lights the room"
        );
        assert_agree(
            &small,
            &tiny,
            8,
            4.5,
            0.02,
            &format!(
                "{}: a radius-1e-4 light vs one of radius 0.1 and equal power",
                b.name()
            ),
        );
    }
    // The camera inside a light: the emissive shell of the furnace seen from
    // inside, and a point on the light's own surface (the shell's inner side)
    // receiving NEE from it: the furnace is exact, checked elsewhere too.
    for mut b in backends() {
        let film = render_on(
            &mut b,
            &furnace(0.5, 0.5),
            8,
            8,
            &Quality {
                max_depth: 3,
                rr_depth: 100,
                ..q(13)
            },
            4,
        );
        for v in film.mean().into_iter().flatten() {
            assert!((f64::from(v) - 0.9375).abs() < 1e-5, "{}: {v}", b.name());
        }
    }
}

/// Glass: ior 1.0 is invisible, 1.0001 nearly so; ior 4.0 and total internal
/// reflection stay finite and energy-conserving in the furnace.
#[test]
fn extreme_glass() {
    for ior in [1.0, 1.0001, 4.0] {
        let mut json = furnace(0.5, 0.5).to_json();
        json.materials.insert(
            "g".into(),
            MaterialJson::Glass(GlassJson {
                ior,
                albedo: None,
                fresnel: Default::default(),
                attenuation: None,
                emission: None,
                normal: None,
            }),
        );
        json.objects.push(ObjectJson::Sphere(SphereJson {
            center: [0.0, 0.0, -0.5],
            radius: 0.3,
            material: "g".into(),
        }));
        let s = Scene::from_json(&json).expect("valid");
        for mut b in backends() {
            let film = render_on(
                &mut b,
                &s,
                12,
                12,
                &Quality {
                    max_depth: 0,
                    rr_depth: 4,
                    ..q(14)
                },
                256,
            );
            assert_clean(&film, "glass");
            assert_mean(
                &film,
                4,
                1.0,
                4.5,
                0.0,
                &format!("{}: ior {ior} in the furnace", b.name()),
            );
        }
    }
}

/// Resolutions 1x1, 1x4096 and 4096x1: in the depth-capped furnace every
/// pixel is exactly E (1 - a^(D+1)) / (1 - a) (so every pixel is rendered
/// and none twice); and with the box filter the one pixel of a 1x1 image
/// sees the whole frame: its value is the mean of a 16x16 image of it.
#[test]
fn extreme_resolutions() {
    let hot = furnace(0.5, 0.5);
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(15)
    };
    let cornell = scene("cornell");
    let boxed = Quality {
        filter: pathstream::render::Filter::Box,
        ..q(15)
    };
    for mut b in backends() {
        for (w, h) in [(1, 1), (1, 4096), (4096, 1)] {
            let film = render_on(&mut b, &hot, w, h, &capped, 2);
            assert_clean(&film, "resolution");
            assert_eq!(film.mean().len(), (w * h) as usize);
            for (i, v) in film.mean().iter().flatten().enumerate() {
                assert!(
                    (f64::from(*v) - 0.9375).abs() < 1e-5,
                    "{}: {w}x{h}: value {i}: {v}",
                    b.name()
                );
            }
        }
        // Sixteen 1x1 renders with their own seeds: a mean and a standard
        // error with 15 degrees of freedom (one pixel's even/odd halves give 1).
        let ones: Vec<f64> = (0..16u64)
            .map(|k| {
                f64::from(
                    render_on(
                        &mut b,
                        &cornell,
                        1,
                        1,
                        &Quality {
                            seed: 100 + k,
                            ..boxed
                        },
                        64,
                    )
                    .mean()[0][1],
                )
            })
            .collect();
        let one = ones.iter().sum::<f64>() / 16.0;
        let one_var = ones.iter().map(|v| (v - one).powi(2)).sum::<f64>() / 15.0 / 16.0;
        let many = region(
            &render_on(&mut b, &cornell, 16, 16, &boxed, 16),
            0..16,
            0..16,
        );
        let z = (one - many.mean[1]).abs() / (one_var + many.var[1]).sqrt();
        assert!(
            z < 4.5,
            "{}: a 1x1 image {one} vs the mean of a 16x16 one {} ({z:.1} standard errors)",
            b.name(),
            many.mean[1]
        );
    }
}

/// Samples and seeds: one sample is already exact where the answer is
/// (the furnace), 1 then 3 samples are the same film as 4 at once, and
/// there is no error estimate before the second; seeds 0 and u64::MAX
/// are valid, differ, and converge to the same image.
#[test]
fn one_sample_and_extreme_seeds() {
    let s = scene("cornell");
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(0)
    };
    for mut b in backends() {
        let film = render_on(&mut b, &furnace(0.5, 0.5), 8, 8, &capped, 1);
        assert_eq!(film.error_estimate(), None);
        for v in film.mean().iter().flatten() {
            assert!(
                (f64::from(*v) - 0.9375).abs() < 1e-5,
                "{}: 1 spp in the furnace: {v}",
                b.name()
            );
        }
        let job = pathstream::render::RenderJob::new(&s, 8, 8, &q(0));
        let mut stepwise = Film::new(8, 8);
        b.render(&job, &mut stepwise, 1).expect("render");
        assert_clean(&stepwise, "1 spp");
        assert_eq!(stepwise.error_estimate(), None);
        b.render(&job, &mut stepwise, 3).expect("render");
        assert!(stepwise.error_estimate().is_some());
        let at_once = render_on(&mut b, &s, 8, 8, &q(0), 4);
        assert_eq!(
            stepwise.pixels(),
            at_once.pixels(),
            "{}: 1 + 3 samples vs 4",
            b.name()
        );

        let max = render_on(&mut b, &s, 16, 16, &q(u64::MAX), 32);
        let zero = render_on(&mut b, &s, 16, 16, &q(0), 32);
        assert_clean(&max, "seed max");
        assert_ne!(max.pixels(), zero.pixels(), "{}", b.name());
        assert_agree(
            &zero,
            &max,
            8,
            4.5,
            0.0,
            &format!("{}: seed 0 vs seed u64::MAX", b.name()),
        );
    }
}

/// Quality knobs at their ends, in the furnace (radiance 1 per bounce
/// series, so each has a closed form): max depth 1 gives E (1 + a) = 0.75,
/// max depth 10000 without roulette 1 - 0.5^10001 = 1; a clamp of 1e-6
/// makes every sample 1e-6, one of 1e30 changes nothing. On cornell-glass
/// they stay finite, and the clamp of 1e30 gives the very film of no clamp.
#[test]
fn quality_knobs_at_their_ends() {
    let hot = furnace(0.5, 0.5);
    let capped = Quality {
        max_depth: 3,
        rr_depth: 100,
        ..q(16)
    };
    let cases = [
        (
            Quality {
                max_depth: 1,
                ..q(16)
            },
            0.75,
        ),
        (
            Quality {
                max_depth: 10_000,
                rr_depth: 10_000,
                ..q(16)
            },
            1.0,
        ),
        (
            Quality {
                clamp: 1e-6,
                ..capped
            },
            1e-6,
        ),
        (
            Quality {
                clamp: 1e30,
                ..capped
            },
            0.9375,
        ),
    ];
    let glass = scene("cornell-glass");
    for mut b in backends() {
        for (quality, expected) in cases {
            let film = render_on(&mut b, &hot, 8, 8, &quality, 4);
            assert_clean(&film, "knobs");
            for v in film.mean().iter().flatten() {
                assert!(
                    (f64::from(*v) - expected).abs() <= 1e-5 * expected,
                    "{}: {quality:?}: {v} vs {expected}",
                    b.name()
                );
            }
            let film = render_on(&mut b, &glass, 8, 8, &quality, 8);
            assert_clean(&film, "knobs on cornell-glass");
        }
        let huge = render_on(
            &mut b,
            &glass,
            8,
            8,
            &Quality {
                clamp: 1e30,
                ..q(17)
            },
            8,
        );
        let off = render_on(&mut b, &glass, 8, 8, &q(17), 8);
        assert_eq!(
            huge.pixels(),
            off.pixels(),
            "{}: a clamp no sample reaches",
            b.name()
        );
    }
}

/// Out-of-range input is refused with a message, never rendered wrongly.
#[test]
fn out_of_range_is_refused() {
    assert!(Quality {
        max_depth: 100_001,
        ..Quality::default()
    }
    .validate()
    .is_err());
    assert!(pathstream::render::job::check_size(0, 1).is_err());
    assert!(pathstream::render::job::check_size(4097, 4097).is_err());
    let mut json = scene("cornell").to_json();
    json.materials.insert(
        "hot".into(),
        MaterialJson::Diffuse(SurfaceJson {
            albedo: [0.5; 3].into(),
            emission: Some([1e21; 3].into()),
            normal: None,
            alpha: None,
        }),
    );
    assert!(Scene::from_json(&json).is_err());
}
