//! The OpenCL backend passes the same checks as the CPU one, agrees with it,
//! and fails cleanly. These tests run on any OpenCL device (PoCL in CI);
//! where `CI` is set, finding no device is a failure, so the suite can never
//! pass by skipping.

mod common;

use common::{
    assert_agree, assert_clean, assert_mean, furnace, opencl_device as device, render, render_on,
    scene,
};
use pathstream::render::backend::opencl::{OpenClBackend, OpenClError, SOURCES};
use pathstream::render::math::DVec3;
use pathstream::render::scene::{FresnelJson, GlassJson, MaterialJson, ObjectJson, SphereJson};
use pathstream::render::{Backend, BackendChoice, Film, Filter, Quality, RenderJob, Scene};

fn opencl() -> Option<Backend> {
    device().map(|d| Backend::OpenCl {
        backend: Box::new(d),
        fallback: false,
    })
}

#[test]
fn shared_structs_have_the_same_size_on_the_device() {
    let Some(d) = device() else { return };
    let sizes = d.device_layout_sizes().expect("layout kernel");
    assert_eq!(
        sizes,
        [96, 128, 208, 128, 112, 224, 48],
        "Object, Material, Params, BvhNode, Light, Instance, TriVerts as the device compiler sees them"
    );
}

#[test]
fn a_broken_kernel_fails_with_its_build_log() {
    let Some(d) = device() else { return };
    let mut sources = SOURCES.to_vec();
    sources.push("__kernel void broken(__global float *x) { x[0] = undefined_name; }\n");
    let err = d
        .build_sources(&sources, "-cl-std=CL1.2")
        .expect_err("must not build");
    let OpenClError::Build { log, .. } = &err else {
        panic!("not a build error: {err}")
    };
    assert!(
        log.contains("undefined_name"),
        "the log names the error: {log}"
    );
    assert!(err.to_string().contains("failed to build"), "{err}");
}

#[test]
fn depth_capped_furnace_is_exact() {
    let Some(mut cl) = opencl() else { return };
    for (a, e) in [(0.5, 0.5), (0.8, 0.25)] {
        let s = furnace(a, e);
        for depth in [1u32, 2, 5] {
            let expected = e * (1.0 - a.powi(depth as i32 + 1)) / (1.0 - a);
            for nee in [true, false] {
                let q = Quality {
                    max_depth: depth,
                    rr_depth: 1000,
                    nee,
                    ..Quality::default()
                };
                let film = render_on(&mut cl, &s, 8, 8, &q, 8);
                assert_clean(&film, "furnace");
                for v in film.mean().into_iter().flatten() {
                    let rel = (f64::from(v) - expected).abs() / expected;
                    assert!(
                        rel < 1e-5,
                        "a {a} E {e} depth {depth} nee {nee}: {v} vs {expected}"
                    );
                }
            }
        }
    }
}

#[test]
fn unbounded_furnace_and_invisible_glass() {
    let Some(mut cl) = opencl() else { return };
    let s = furnace(0.5, 0.5);
    for nee in [true, false] {
        let q = Quality {
            max_depth: 0,
            rr_depth: 2,
            nee,
            filter: Filter::Box,
            ..Quality::default()
        };
        let film = render_on(&mut cl, &s, 16, 16, &q, 256);
        assert_clean(&film, "furnace");
        assert_mean(
            &film,
            4,
            1.0,
            4.5,
            0.0,
            &format!("opencl unbounded furnace, nee {nee}"),
        );
    }
    let mut json = s.to_json();
    json.materials.insert(
        "clear".into(),
        MaterialJson::Glass(GlassJson {
            ior: 1.5,
            albedo: None,
            fresnel: FresnelJson::Schlick,
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
    let glass = Scene::from_json(&json).expect("valid");
    let q = Quality {
        max_depth: 0,
        rr_depth: 4,
        ..Quality::default()
    };
    let film = render_on(&mut cl, &glass, 16, 16, &q, 256);
    assert_clean(&film, "glass furnace");
    assert_mean(&film, 4, 1.0, 4.5, 0.0, "opencl glass in furnace");
}

#[test]
fn nee_on_and_off_agree() {
    let Some(mut cl) = opencl() else { return };
    let s = scene("cornell");
    let a = render_on(
        &mut cl,
        &s,
        24,
        24,
        &Quality {
            nee: true,
            seed: 1,
            ..Quality::default()
        },
        256,
    );
    let b = render_on(
        &mut cl,
        &s,
        24,
        24,
        &Quality {
            nee: false,
            seed: 2,
            ..Quality::default()
        },
        2048,
    );
    assert_agree(&a, &b, 8, 4.5, 0.0, "opencl cornell: NEE on vs off");
}

#[test]
fn cpu_and_opencl_agree_on_a_scene_searched_through_the_bvh() {
    let Some(mut cl) = opencl() else { return };
    // cornell and 300 small spheres, a third of them mirrors: the six
    // walls are tested first, the rest through the BVH, on both backends.
    let mut j = serde_json::to_value(scene("cornell").to_json()).expect("json");
    j["materials"]["chrome"] = serde_json::json!({"type": "mirror", "albedo": [0.9, 0.9, 0.9]});
    let objects = j["objects"].as_array_mut().expect("objects");
    for i in 0..300u64 {
        let mut s = pathstream::render::sampler::Sampler::new(7, i, 0);
        let c = [
            10.0 + 80.0 * s.next_f32(),
            5.0 + 60.0 * s.next_f32(),
            20.0 + 120.0 * s.next_f32(),
        ];
        let material = if i % 3 == 0 { "chrome" } else { "white" };
        objects.push(serde_json::json!({"type": "sphere", "center": c, "radius": 1.0 + 3.0 * s.next_f32(), "material": material}));
    }
    let s = Scene::from_json_value(j).expect("valid");
    let q = Quality::default();
    let cpu = render(&s, 16, 16, &Quality { seed: 10, ..q }, 256);
    let gpu = render_on(&mut cl, &s, 16, 16, &Quality { seed: 11, ..q }, 256);
    assert_clean(&gpu, "crowded cornell");
    assert_agree(&cpu, &gpu, 8, 4.5, 1e-4, "crowded cornell: CPU vs OpenCL");
}

#[test]
fn cpu_and_opencl_agree_on_every_scene_and_setting() {
    let Some(mut cl) = opencl() else { return };
    let grid = [
        Quality::default(),
        Quality {
            max_depth: 1,
            ..Quality::default()
        },
        Quality {
            max_depth: 0,
            nee: false,
            ..Quality::default()
        },
        Quality {
            filter: Filter::Box,
            clamp: 2.0,
            rr_depth: 1,
            ..Quality::default()
        },
    ];
    for name in pathstream::render::scene::BUILTIN_NAMES {
        let s = scene(name);
        for (i, q) in grid.iter().enumerate() {
            let spp = if q.nee { 128 } else { 512 };
            let cpu = render(&s, 16, 16, &Quality { seed: 10, ..*q }, spp);
            let gpu = render_on(&mut cl, &s, 16, 16, &Quality { seed: 11, ..*q }, spp);
            assert_clean(&gpu, name);
            assert_agree(
                &cpu,
                &gpu,
                8,
                4.5,
                1e-4,
                &format!("{name}, setting {i}: CPU vs OpenCL"),
            );
        }
    }
}

#[test]
fn same_seed_same_image_however_samples_are_split() {
    let Some(mut cl) = opencl() else { return };
    let s = scene("cornell-glass");
    let q = Quality {
        seed: 5,
        ..Quality::default()
    };
    let job = RenderJob::new(&s, 20, 12, &q);
    let mut once = Film::new(20, 12);
    cl.render(&job, &mut once, 12).expect("render");
    let mut split = Film::new(20, 12);
    for n in [1, 4, 7] {
        cl.render(&job, &mut split, n).expect("render");
    }
    assert_eq!(once.pixels(), split.pixels(), "split into passes");
    let mut again = Film::new(20, 12);
    cl.render(&RenderJob::new(&s, 20, 12, &q), &mut again, 12)
        .expect("render");
    assert_eq!(once.pixels(), again.pixels(), "run to run");
}

#[test]
fn invariant_under_scale_and_translation_including_smallpt_walls() {
    let Some(mut cl) = opencl() else { return };
    for name in ["cornell-glass", "smallpt"] {
        let base = scene(name);
        let reference = render(
            &base,
            24,
            24,
            &Quality {
                seed: 20,
                ..Quality::default()
            },
            256,
        );
        for (what, s) in [
            ("scaled 1e-3", base.scaled(1e-3)),
            ("scaled 1e3", base.scaled(1e3)),
            ("moved 1e4", base.translated(DVec3::new(1e4, -1e4, 1e4))),
        ] {
            let film = render_on(
                &mut cl,
                &s,
                24,
                24,
                &Quality {
                    seed: 21,
                    ..Quality::default()
                },
                256,
            );
            assert_clean(&film, what);
            assert_agree(
                &reference,
                &film,
                8,
                4.5,
                0.0,
                &format!("{name} {what}: CPU vs OpenCL"),
            );
        }
    }
}

#[test]
fn nan_samples_are_rejected_and_counted_on_the_device() {
    let Some(mut d) = device() else { return };
    d.inject_nan_every = Some(4);
    let s = scene("cornell");
    let job = RenderJob::new(&s, 8, 8, &Quality::default());
    let mut film = Film::new(8, 8);
    d.render(&job, &mut film, 10).expect("render");
    d.render(&job, &mut film, 6).expect("render");
    // Samples 0, 4, 8 and 12 of every pixel are NaN.
    assert_eq!(film.rejected(), 4 * 64);
    assert!(film.mean().iter().flatten().all(|v| v.is_finite()));
}

#[test]
fn the_device_film_keeps_a_constant_to_1e6_over_1e8_samples() {
    let Some(d) = device() else { return };
    for value in [0.1f32, 1.0 / 3.0, 7.77] {
        let sum = d.accumulate_constant(value, 100_000_000).expect("kernel");
        let mean = sum / 1e8;
        let rel = (mean - f64::from(value)).abs() / f64::from(value);
        assert!(rel < 1e-6, "{value}: mean {mean}, relative error {rel}");
    }
}

#[test]
fn every_feature_combination_builds() {
    let Some(_) = device() else { return };
    use pathstream::render::backend::opencl::{Features, ProgramKey};
    let mut keys = Vec::new();
    // (spheres, quads, meshes); with meshes, diffuse alone or every material.
    for shapes in [
        (true, false, false),
        (false, true, false),
        (true, true, false),
        (false, false, true),
        (true, true, true),
    ] {
        for materials in 1u8..8 {
            if shapes.2 && materials != 1 && materials != 7 {
                continue;
            }
            let (diffuse, mirror, glass) =
                (materials & 1 != 0, materials & 2 != 0, materials & 4 != 0);
            let fresnels: &[(bool, bool)] = if glass {
                &[(true, false), (false, true), (true, true)]
            } else {
                &[(false, false)]
            };
            for &(schlick, exact) in fresnels {
                for lights in 0u8..4 {
                    keys.push(ProgramKey::Specialised(Features {
                        spheres: shapes.0,
                        quads: shapes.1,
                        diffuse,
                        mirror,
                        glass,
                        // Half the combinations with the metallic-roughness code.
                        ggx: lights % 2 == 1,
                        // Rough glass with half of those.
                        transmission: lights == 3,
                        // Absorption inside with glass or rough glass.
                        volume: (glass && lights == 0) || lights == 3,
                        // A clear coat with the metallic-roughness code,
                        // with and without rough glass.
                        coat: lights % 2 == 1 && materials % 2 == 1,
                        // Its own normal where textures are in too.
                        coat_normal: lights == 1 && materials % 2 == 1,
                        // Vertex colours with meshes, half the time.
                        vertex_colors: shapes.2 && lights % 2 == 0,
                        schlick,
                        exact,
                        sphere_lights: lights & 1 != 0,
                        quad_lights: lights & 2 != 0,
                        nee: lights != 0,
                        box_filter: lights == 3,
                        sobol: lights != 1,
                        num_objects: 3,
                        num_lights: u32::from(lights != 0),
                        max_depth: u32::from(materials),
                        // With and without the BVH code (always with meshes).
                        bvh_stack: if lights % 2 == 0 || shapes.2 {
                            3 * u32::from(materials) + 4
                        } else {
                            0
                        },
                        mesh_stack: if shapes.2 { 40 } else { 0 },
                        tri_lights: shapes.2 && lights & 1 != 0,
                        environment: shapes.2 && lights & 2 != 0,
                        // An environment map where there are no meshes and
                        // there is a light (with and without MAT_PBR).
                        env_map: !shapes.2 && lights & 2 != 0,
                        // A sky's sun with half the maps.
                        sun: !shapes.2 && lights & 2 != 0 && materials % 2 == 1,
                        // A thin lens in half the combinations.
                        lens: materials % 2 == 0,
                        // Each projection (perspective most often).
                        projection: u32::from(materials % 3 == 1) * (1 + u32::from(lights) % 2),
                        // The denoiser's features with a third.
                        features: materials % 3 == 2,
                        // Texture maps with a quarter (every material kind).
                        textures: lights == 1 || (lights == 2 && materials == 3),
                        // Alpha tests with meshes, with and without textures.
                        alpha: shapes.2 && lights <= 1,
                        inject_nan_every: None,
                    }));
                }
            }
        }
    }
    keys.push(ProgramKey::Generic {
        inject_nan_every: None,
        features: true,
    });
    assert_eq!(keys.len(), 3 * 15 * 4 + 2 * 4 * 4 + 1);
    // Two threads, each with its own context: the compiler is the slow part.
    let failures: Vec<String> = std::thread::scope(|scope| {
        let halves: Vec<_> = keys
            .chunks(keys.len().div_ceil(2))
            .map(|chunk| {
                scope.spawn(move || {
                    let d = OpenClBackend::new(None).expect("device");
                    chunk
                        .iter()
                        .filter_map(|k| {
                            d.build_sources(&SOURCES, &k.build_options())
                                .err()
                                .map(|e| format!("{k:?}: {e}"))
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        halves
            .into_iter()
            .flat_map(|h| h.join().expect("thread"))
            .collect()
    });
    assert!(
        failures.is_empty(),
        "{} programs failed to build:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn auto_falls_back_to_rayon_and_says_so_when_there_is_no_platform() {
    let empty = tempfile::tempdir().expect("tempdir");
    let out = empty.path().join("x.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args([
            "render",
            "--scene",
            "furnace",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "--backend",
            "auto",
            "--out",
        ])
        .arg(&out)
        .env("OCL_ICD_VENDORS", empty.path())
        .output()
        .expect("runs");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains("backend cpu (rayon"), "{summary}");
    assert!(
        summary.contains("no OpenCL platform found"),
        "says why: {summary}"
    );
    let devices = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .arg("devices")
        .env("OCL_ICD_VENDORS", empty.path())
        .output()
        .expect("runs");
    let text = String::from_utf8_lossy(&devices.stdout);
    assert!(text.contains("auto picks: rayon on the CPU"), "{text}");
}

#[test]
fn explicit_opencl_with_a_bad_device_number_is_a_clear_error() {
    let Some(_) = device() else { return };
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args([
            "render",
            "--scene",
            "furnace",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "2",
            "--device",
            "99",
            "--out",
            "/tmp/x.png",
        ])
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("--device 99"), "{err}");
}

#[test]
fn a_device_that_fails_mid_render_loses_no_samples() {
    let Some(first) = device() else { return };
    let s = scene("cornell");
    let job = RenderJob::new(&s, 8, 8, &Quality::default());
    // Asked for by name: the error comes back and the film is untouched.
    let mut named = Backend::OpenCl {
        backend: Box::new(first),
        fallback: false,
    };
    let mut film = Film::new(8, 8);
    named.render(&job, &mut film, 4).expect("render");
    let before = film.pixels().to_vec();
    if let Backend::OpenCl { backend, .. } = &mut named {
        backend.fail_launches = true;
    }
    let err = named
        .render(&job, &mut film, 4)
        .expect_err("injected failure");
    assert!(err.to_string().contains("kernel launch failed"), "{err}");
    assert_eq!(film.spp(), 4);
    assert_eq!(film.pixels(), &before[..]);
    // Chosen by auto: a logged fall back to rayon that carries on from sample 4.
    let mut failing = OpenClBackend::new(None).expect("device");
    failing.fail_launches = true;
    let mut auto = Backend::OpenCl {
        backend: Box::new(failing),
        fallback: true,
    };
    auto.render(&job, &mut film, 4).expect("falls back");
    assert_eq!(auto.name(), "cpu");
    assert!(auto.device().contains("OpenCL failed"), "{}", auto.device());
    assert_eq!(film.spp(), 8);
    // Samples 4..8 are the CPU's own: what the fallback added to each pixel
    // is exactly what a CPU render adds after its own first four samples.
    let mut cpu = Backend::choose(BackendChoice::Cpu).expect("cpu");
    let (mut first4, mut all8) = (Film::new(8, 8), Film::new(8, 8));
    cpu.render(&job, &mut first4, 4).expect("render");
    cpu.render(&job, &mut all8, 8).expect("render");
    for (i, ((after, opencl), (c8, c4))) in film
        .pixels()
        .iter()
        .zip(&before)
        .zip(all8.pixels().iter().zip(first4.pixels()))
        .enumerate()
    {
        for c in 0..3 {
            for (added, cpu_added, scale) in [
                (
                    after.even[c] - opencl.even[c],
                    c8.even[c] - c4.even[c],
                    after.even[c].abs() + c8.even[c].abs(),
                ),
                (
                    after.odd[c] - opencl.odd[c],
                    c8.odd[c] - c4.odd[c],
                    after.odd[c].abs() + c8.odd[c].abs(),
                ),
            ] {
                assert!(
                    (added - cpu_added).abs() <= 1e-12 * scale,
                    "pixel {i} channel {c}: fallback added {added}, the CPU adds {cpu_added}"
                );
            }
        }
    }
}

#[test]
fn the_generic_program_renders_what_the_specialised_one_does() {
    let Some(mut specialised) = device() else {
        return;
    };
    let mut generic = OpenClBackend::new(None).expect("device");
    generic.generic = true;
    for name in ["cornell", "cornell-glass", "cornell-quads"] {
        let job = RenderJob::new(
            &scene(name),
            16,
            16,
            &Quality {
                seed: 5,
                ..Quality::default()
            },
        );
        let (mut a, mut b) = (Film::new(16, 16), Film::new(16, 16));
        specialised.render(&job, &mut a, 16).expect("render");
        generic.render(&job, &mut b, 16).expect("render");
        // The same samples along the same paths: pixel for pixel equal, to
        // the rounding that compiling two programs may differ in.
        let (ma, mb) = (a.mean(), b.mean());
        let close = ma
            .iter()
            .zip(&mb)
            .filter(|(x, y)| {
                (0..3).all(|c| (x[c] - y[c]).abs() <= 1e-4 * x[c].abs().max(y[c].abs()).max(1e-3))
            })
            .count();
        eprintln!("{name}: {close} of 256 pixels equal to 1e-4");
        assert!(close >= 240, "{name}: only {close} of 256 pixels agree between the specialised and the generic program");
        assert_agree(
            &a,
            &b,
            8,
            4.5,
            1e-4,
            &format!("{name}: specialised vs generic program"),
        );
    }
}

#[test]
fn launches_split_into_pixel_ranges_give_the_same_image() {
    let Some(mut whole) = device() else { return };
    let mut tiled = OpenClBackend::new(None).expect("device");
    // A target no launch can meet: one sample per launch.
    tiled.launch_target = std::time::Duration::from_nanos(1);
    // Taller than one launch's worth of pixels: several launches per sample.
    tiled.launch_pixels = 4096;
    let (w, h) = (64, (tiled.launch_pixels / 64 + 3) as u32);
    let s = scene("cornell-glass");
    let job = RenderJob::new(
        &s,
        w,
        h,
        &Quality {
            seed: 3,
            max_depth: 2,
            ..Quality::default()
        },
    );
    let (mut a, mut b) = (Film::new(w, h), Film::new(w, h));
    whole.render(&job, &mut a, 3).expect("render");
    for n in [1, 2] {
        tiled.render(&job, &mut b, n).expect("render");
    }
    assert_eq!(b.spp(), 3);
    assert_eq!(a.pixels(), b.pixels());
}

#[test]
fn sessions_taking_turns_on_one_device_keep_their_films() {
    let Some(mut shared) = device() else { return };
    let (a, b) = (scene("cornell"), scene("cornell-glass"));
    let (ja, jb) = (
        RenderJob::new(&a, 16, 12, &Quality::default()),
        RenderJob::new(&b, 16, 12, &Quality::default()),
    );
    let (mut fa, mut fb) = (Film::new(16, 12), Film::new(16, 12));
    for n in [3, 5] {
        shared.render(&ja, &mut fa, n).expect("render");
        shared.render(&jb, &mut fb, n).expect("render");
    }
    for (job, film) in [(&ja, &fa), (&jb, &fb)] {
        let mut alone = OpenClBackend::new(None).expect("device");
        let mut f = Film::new(16, 12);
        alone.render(job, &mut f, 8).expect("render");
        assert_eq!(f.pixels(), film.pixels(), "taking turns changed the image");
    }
}
