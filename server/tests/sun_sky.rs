//! A clear sky and sun without a map (`environment.sky`), on every
//! backend: outside the air the sun lights a plane with exactly the
//! closed form's irradiance (the sky's unit: luminance 1 on a white plane
//! facing it), by MIS, by NEE alone and by BSDF samples alone; seen
//! directly it is a disc of its angular size and radiance; a full sky
//! renders alike on the CPU and in the kernel, whose sun routines agree
//! with the CPU's bit for bit; bad settings are refused by name.

mod common;
mod parity;

use common::{assert_agree, assert_clean, backends, pooled, regions, render_on};
use pathstream::render::backend::opencl::{pack, CheckArg};
use pathstream::render::envmap::spectrum::luminance;
use pathstream::render::integrator::Combine;
use pathstream::render::math::Vec3A;
use pathstream::render::sampler::SamplerKind;
use pathstream::render::{Backend, BackendChoice, Film, Filter, Quality, RenderJob, Scene};
use serde_json::{json, Value};

fn quality(nee: bool, seed: u64) -> Quality {
    Quality {
        filter: Filter::Box,
        sampler: SamplerKind::Random,
        nee,
        seed,
        max_depth: 0,
        rr_depth: 3,
        ..Quality::default()
    }
}

fn cpu() -> Backend {
    Backend::choose(BackendChoice::Cpu).expect("cpu")
}

fn scene(json: Value) -> Scene {
    Scene::from_json_str(&json.to_string()).expect("valid scene")
}

/// No air, dust or ozone: a black sky and the sun as it is in space.
fn space(sun_size_deg: f64, elevation: f64) -> Value {
    json!({"sky": {"air": 0, "dust": 0, "ozone": 0, "sun_elevation_deg": elevation,
                   "sun_azimuth_deg": 135, "sun_size_deg": sun_size_deg}, "intensity": 2})
}

/// A grey plane seen from straight above.
fn plane(environment: Value) -> Scene {
    scene(json!({
        "camera": {"position": [0, 1, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov_deg": 60},
        "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [{"type": "quad", "corner": [-100, 0, -100], "edge_u": [200, 0, 0],
                     "edge_v": [0, 0, 200], "material": "grey"}],
        "environment": environment
    }))
}

/// Asserts the whole image's mean per channel within `z` standard errors
/// (after a relative floor `rel`) of `want`.
fn assert_rgb(film: &Film, want: [f64; 3], z: f64, rel: f64, what: &str) {
    let whole = pooled(&regions(film, 8));
    for (c, want) in want.iter().enumerate() {
        let diff = (whole.mean[c] - want).abs() - rel * want;
        let se = whole.var[c].sqrt();
        assert!(
            diff < z * se.max(1e-12),
            "{what}: channel {c}: {} vs {} (se {se:.2e})",
            whole.mean[c],
            want
        );
    }
}

#[test]
fn the_sun_in_space_lights_a_plane_as_the_closed_form_says() {
    let (albedo, intensity, elevation) = (0.5f64, 2.0f64, 60f64);
    let cos_zenith = elevation.to_radians().sin();
    for size in [0.545f64, 20.0] {
        let s = plane(space(size, elevation));
        let job = RenderJob::new(&s, 32, 24, &quality(true, 1));
        let (_, radiance) = job.world.sun.expect("a sun");
        let r = (size / 2.0).to_radians();
        // A disc above the horizon: projected solid angle pi sin^2 r cos.
        let want = [radiance.x, radiance.y, radiance.z]
            .map(|l| albedo * f64::from(l) * r.sin().powi(2) * cos_zenith);
        // The sky's unit: E / pi has luminance `intensity` facing a point
        // sun; a disc's is (1 + cos r) / 2 of that (its edge is lower).
        let unit = albedo * intensity * cos_zenith * (1.0 + r.cos()) / 2.0;
        assert!(
            (luminance(want) / unit - 1.0).abs() < 1e-3,
            "{want:?} vs {unit}"
        );
        for (name, mut backend) in backends() {
            let film = render_on(&mut backend, &s, 32, 24, &quality(true, 2), 64);
            assert_clean(&film, name);
            assert_rgb(
                &film,
                want,
                4.5,
                1e-4,
                &format!("{name}: {size} degree sun, MIS"),
            );
        }
        if size > 1.0 {
            // NEE alone and BSDF samples alone (a 20-degree sun is found
            // by cosine samples 3% of the time).
            let mut job = RenderJob::new(&s, 32, 24, &quality(true, 3));
            job.settings.combine = Combine::NeeOnly;
            let mut nee_only = Film::new(32, 24);
            cpu().render(&job, &mut nee_only, 64).expect("render");
            assert_rgb(&nee_only, want, 4.5, 1e-4, "NEE only");
            let bsdf_only = render_on(&mut cpu(), &s, 32, 24, &quality(false, 4), 1024);
            assert_rgb(&bsdf_only, want, 4.5, 0.0, "BSDF only");
        }
    }
}

#[test]
fn the_sun_seen_directly_is_a_disc_of_its_size_and_radiance() {
    let (elevation, azimuth) = (30f64.to_radians(), 135f64.to_radians());
    let to_sun = [
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
        -elevation.cos() * azimuth.cos(),
    ];
    let (size, fov, n) = (0.545f64, 2.0f64, 64u32);
    let view = |visible: bool| {
        scene(json!({
            "camera": {"position": [0, 0, 0], "look_at": to_sun, "vfov_deg": fov},
            "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
            "objects": [{"type": "sphere", "center": [0, -50, 0], "radius": 1, "material": "grey"}],
            "environment": {"sky": {"air": 0, "dust": 0, "ozone": 0, "sun_elevation_deg": 30,
                                    "sun_azimuth_deg": 135, "sun_size_deg": size},
                            "visible": visible, "background": [0.25, 0.5, 0.75]}
        }))
    };
    let s = view(true);
    let job = RenderJob::new(&s, n, n, &quality(true, 1));
    let (sun, radiance) = job.world.sun.expect("a sun");
    // Radiance: the sun's irradiance (luminance pi) over its solid angle.
    let l = [radiance.x, radiance.y, radiance.z].map(f64::from);
    let omega = f64::from(sun.solid_angle());
    assert!((luminance(l) * omega / std::f64::consts::PI - 1.0).abs() < 2e-3);
    let r = (size / 2.0).to_radians();
    let pixel = 2.0 * (fov / 2.0).to_radians().tan() / f64::from(n);
    let area = std::f64::consts::PI * (r.tan() / pixel).powi(2);
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &s, n, n, &quality(true, 2), 256);
        assert_clean(&film, name);
        let mean = film.mean();
        let centre = mean[(n / 2 * n + n / 2) as usize];
        for c in 0..3 {
            assert!(
                (f64::from(centre[c]) / l[c] - 1.0).abs() < 1e-4,
                "{name}: centre {centre:?} vs {l:?}"
            );
        }
        let covered: f64 = mean.iter().map(|p| f64::from(p[1]) / l[1]).sum();
        assert!(
            (covered / area - 1.0).abs() < 0.01,
            "{name}: {covered} pixels vs {area}"
        );
        // Hidden: the background everywhere, the sun too.
        let hidden = render_on(&mut backend, &view(false), n, n, &quality(true, 3), 4);
        assert!(
            hidden.mean().iter().all(|p| *p == [0.25, 0.5, 0.75]),
            "{name}: hidden sun"
        );
    }
}

/// A floor, a diffuse ball and a rough metal ball under a sky.
fn balls(sky: Value) -> Scene {
    scene(json!({
        "camera": {"position": [0, 1.2, 4], "look_at": [0, 0.5, 0], "vfov_deg": 40},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "metal": {"type": "pbr", "base_color": [0.9, 0.8, 0.6], "metallic": 1, "roughness": 0.3}
        },
        "objects": [
            {"type": "quad", "corner": [-3, 0, -3], "edge_u": [6, 0, 0], "edge_v": [0, 0, 6], "material": "white"},
            {"type": "sphere", "center": [-0.7, 0.6, 0], "radius": 0.6, "material": "metal"},
            {"type": "sphere", "center": [0.7, 0.6, 0], "radius": 0.6, "material": "white"}
        ],
        "environment": {"sky": sky, "rotation_deg": 30}
    }))
}

#[test]
fn a_clear_sky_renders_alike_on_every_backend() {
    // Late afternoon in Lisbon in June, a little hazy.
    let s = balls(
        json!({"time": "2026-06-21T18:30:00+01:00", "latitude_deg": 38.72,
                         "longitude_deg": -9.14, "dust": 2}),
    );
    let reference = render_on(&mut cpu(), &s, 32, 24, &quality(true, 1), 256);
    assert_clean(&reference, "cpu");
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &s, 32, 24, &quality(true, 2), 256);
        assert_clean(&film, name);
        assert_agree(
            &reference,
            &film,
            8,
            4.5,
            0.003,
            &format!("{name}: clear sky"),
        );
    }
}

#[test]
fn the_kernels_sun_routines_agree_with_the_cpus_bit_for_bit() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    let s = balls(json!({"sun_elevation_deg": 41, "sun_azimuth_deg": 200, "sun_size_deg": 3}));
    let job = RenderJob::new(&s, 8, 8, &Quality::default());
    let (sun, _) = job.world.sun.expect("a sun");
    let lights = &job.world.lights;
    let which = lights.sun().expect("its emitter");
    let e = &lights.emitters[which];
    let packed = pack(&job);
    let n = 50_000u64;
    let us: Vec<[f32; 2]> = (0..n)
        .map(|i| [parity::uniform(i, 51), parity::uniform(i, 52)])
        .collect();
    // Half the directions near the disc's edge, half anywhere.
    let dirs: Vec<[f32; 4]> = (0..n)
        .map(|i| {
            let d = match i % 2 {
                0 => {
                    sun.sample(parity::uniform(i, 53) * 1.2, parity::uniform(i, 54))
                        .0
                }
                _ => parity::unit(i, 55),
            };
            d.normalize().extend(0.0).to_array()
        })
        .collect();
    let out: Vec<f32> = parity::checks(&d)
        .run(
            "check_sun",
            n as usize,
            6,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&us)),
                CheckArg::Buffer(bytemuck::cast_slice(&dirs)),
                CheckArg::Buffer(bytemuck::bytes_of(&packed.params)),
                CheckArg::Buffer(bytemuck::cast_slice(&packed.lights)),
                CheckArg::U32(which as u32),
            ],
        )
        .expect("run");
    let mut inside = 0;
    for i in 0..n as usize {
        let (dir, w) = sun.sample(us[i][0], us[i][1]);
        let dv = Vec3A::from_slice(&dirs[i][..3]);
        let at = pathstream::render::light::Receiver {
            p: Vec3A::ZERO,
            object: u32::MAX,
            prim: u32::MAX,
            nl: dv,
            ns: dv,
        };
        let covers = sun.covers(dv);
        inside += usize::from(covers);
        let want = [
            dir.x,
            dir.y,
            dir.z,
            w,
            f32::from(u8::from(covers)),
            e.pdf_direction(&at, dv, dv),
        ];
        for (k, (g, c)) in out[6 * i..6 * i + 6].iter().zip(want).enumerate() {
            assert_eq!(
                g.to_bits(),
                c.to_bits(),
                "item {i} value {k}: device {g}, CPU {c}"
            );
        }
    }
    assert!(inside > n as usize / 5, "directions in the disc: {inside}");
}

#[test]
fn bad_sky_settings_are_refused_by_name() {
    let cases = [
        (
            json!({"sky": {"sun_elevation_deg": 95}}),
            "environment.sky.sun_elevation_deg",
        ),
        (
            json!({"sky": {"sun_direction": [0, 0, 0]}}),
            "environment.sky.sun_direction",
        ),
        (
            json!({"sky": {"time": "yesterday", "latitude_deg": 0, "longitude_deg": 0}}),
            "environment.sky.time",
        ),
        (
            json!({"sky": {"time": "2026-06-21T12:00:00Z"}}),
            "environment.sky",
        ),
        (
            json!({"sky": {"time": "2026-06-21T12:00:00Z", "latitude_deg": 91, "longitude_deg": 0}}),
            "environment.sky.latitude_deg",
        ),
        (
            json!({"sky": {"sun_elevation_deg": 10, "sun_direction": [0, 1, 0]}}),
            "environment.sky",
        ),
        (json!({"sky": {"air": -1}}), "environment.sky.air"),
        (json!({"sky": {"dust": "thick"}}), "environment.sky.dust"),
        (
            json!({"sky": {"sun_size_deg": 0}}),
            "environment.sky.sun_size_deg",
        ),
        (
            json!({"sky": {"sun_intensity": -2}}),
            "environment.sky.sun_intensity",
        ),
        (
            json!({"sky": {"altitude_m": 1e9}}),
            "environment.sky.altitude_m",
        ),
        (json!({"sky": {"bogus": 1}}), "environment.sky.bogus"),
        (json!({"sky": {}, "map": "studio.hdr"}), "environment"),
    ];
    for (environment, field) in cases {
        let j = json!({
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40},
            "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "grey"}],
            "environment": environment
        });
        let err = Scene::from_json_str(&j.to_string()).expect_err(&environment.to_string());
        assert_eq!(err.path, field, "{environment}: {err}");
    }
}
