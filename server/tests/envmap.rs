//! HDR environment maps, on every backend: a constant map lights a scene
//! as the uniform environment of its value does; a small bright patch
//! lights a plane with the irradiance of the closed form, by MIS, by NEE
//! alone and by BSDF sampling alone, and importance sampling gets there
//! far sooner than cosine sampling; turning a map by 360 degrees changes
//! nothing; the kernel's map routines agree with the CPU's bit for bit;
//! real and broken files are read or refused by name.

mod common;
mod parity;

use common::{assert_agree, assert_clean, assert_mean, backends, pooled, regions, render_on};
use pathstream::render::backend::opencl::{pack, CheckArg};
use pathstream::render::envmap::EnvMap;
use pathstream::render::envmap::{map_direction, map_uv};
use pathstream::render::integrator::Combine;
use pathstream::render::math::Vec3A;
use pathstream::render::sampler::SamplerKind;
use pathstream::render::scene::LoadedModel;
use pathstream::render::scene::{ModelSource, Resolver};
use pathstream::render::{Backend, BackendChoice, Film, Filter, Quality, RenderJob, Scene};
use std::f64::consts::PI;
use std::sync::Arc;

const W: u32 = 32;
const H: u32 = 24;

/// Maps by name, in memory (so that the tests know every texel exactly).
struct Maps(Vec<(&'static str, Arc<EnvMap>)>);

impl Resolver for Maps {
    fn resolve(&self, _: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err("no models here".into())
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        let ModelSource::File(name) = source else {
            return Err("files only".into());
        };
        (self
            .0
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, m)| m.clone()))
        .ok_or_else(|| format!("no map '{name}'"))
    }
}

fn map(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> Arc<EnvMap> {
    let texels = (0..h)
        .flat_map(|j| (0..w).map(move |i| (i, j)))
        .map(|(i, j)| f(i, j));
    Arc::new(EnvMap::new("test", w, h, texels.collect()))
}

fn scene(json: serde_json::Value, maps: &Maps) -> Scene {
    Scene::from_json_str_with(&json.to_string(), maps).expect("valid scene")
}

fn quality(nee: bool, seed: u64) -> Quality {
    Quality {
        filter: Filter::Box,
        sampler: SamplerKind::Random, // independent halves for the error estimate
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

/// A floor, a diffuse ball and a rough metal ball under `environment`.
fn balls(environment: serde_json::Value) -> serde_json::Value {
    serde_json::json!({
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
        "environment": environment
    })
}

#[test]
fn a_constant_map_lights_as_the_uniform_environment_of_its_value() {
    let c = [0.8f32, 0.6, 0.4];
    let maps = Maps(vec![("flat.hdr", map(16, 8, |_, _| c))]);
    let uniform = scene(balls(serde_json::json!(c)), &maps);
    let mapped = scene(balls(serde_json::json!({"map": "flat.hdr"})), &maps);
    let reference = render_on(&mut cpu(), &uniform, W, H, &quality(true, 1), 512);
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &mapped, W, H, &quality(true, 2), 512);
        assert_clean(&film, name);
        assert_agree(
            &reference,
            &film,
            8,
            4.5,
            0.003,
            &format!("{name}: map vs uniform"),
        );
    }
}

/// A map black but for a patch of `L` over columns `cols` and rows `rows`
/// of a 256 x 128 map, above a horizontal diffuse plane of albedo 0.5
/// seen from straight above.
const L: f32 = 400.0;
const ROWS: std::ops::Range<u32> = 32..36;
const COLS: std::ops::Range<u32> = 40..44;

fn patch_scene() -> Scene {
    let patch = map(256, 128, |i, j| {
        if COLS.contains(&i) && ROWS.contains(&j) {
            [L; 3]
        } else {
            [0.0; 3]
        }
    });
    let json = serde_json::json!({
        "camera": {"position": [0, 1, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "vfov_deg": 60},
        "materials": {"grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
        "objects": [
            {"type": "quad", "corner": [-100, 0, -100], "edge_u": [200, 0, 0], "edge_v": [0, 0, 200], "material": "grey"}
        ],
        "environment": {"map": "patch.hdr", "rotation_deg": 73}
    });
    scene(json, &Maps(vec![("patch.hdr", patch)]))
}

/// The plane's radiance: albedo / pi x L x the patch's projected solid
/// angle, (sin^2 theta_end - sin^2 theta_start) / 2 x its width in phi.
fn patch_radiance() -> f64 {
    let theta = |row: u32| PI * f64::from(row) / 128.0;
    let band = (theta(ROWS.end).sin().powi(2) - theta(ROWS.start).sin().powi(2)) / 2.0;
    let phi = 2.0 * PI * f64::from(COLS.len() as u32) / 256.0;
    0.5 / PI * f64::from(L) * band * phi
}

#[test]
fn a_small_patch_lights_a_plane_as_the_closed_form_says() {
    let s = patch_scene();
    let expected = patch_radiance();
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, &s, W, H, &quality(true, 5), 256);
        assert_clean(&film, name);
        assert_mean(&film, 8, expected, 4.5, 0.002, &format!("{name}: MIS"));
    }
    // NEE alone and BSDF sampling alone (CPU).
    let mut job = RenderJob::new(&s, W, H, &quality(true, 6));
    job.settings.combine = Combine::NeeOnly;
    let mut nee_only = Film::new(W, H);
    cpu().render(&job, &mut nee_only, 256).expect("render");
    assert_mean(&nee_only, 8, expected, 4.5, 0.002, "NEE only");
    let bsdf_only = render_on(&mut cpu(), &s, W, H, &quality(false, 7), 8192);
    let whole = pooled(&regions(&bsdf_only, 8));
    let z = (whole.mean[0] - expected).abs() / whole.var[0].sqrt();
    assert!(
        z < 4.5,
        "BSDF only: {} vs {expected} ({z:.1} se)",
        whole.mean[0]
    );
}

#[test]
fn importance_sampling_beats_cosine_sampling_tenfold_on_a_small_patch() {
    let s = patch_scene();
    let spp = 256;
    let variance = |film: &Film| pooled(&regions(film, 8)).var[0];
    let is = variance(&render_on(&mut cpu(), &s, W, H, &quality(true, 8), spp));
    let cosine = variance(&render_on(&mut cpu(), &s, W, H, &quality(false, 9), spp));
    // Time to an error is variance x time per sample; a sample with a
    // shadow ray costs at most about twice one without: ten times sooner
    // needs a variance at least 20 times lower.
    eprintln!("variance at {spp} spp: importance sampling {is:.3e}, cosine {cosine:.3e}");
    assert!(
        cosine > 20.0 * is,
        "importance {is:.3e} vs cosine {cosine:.3e}"
    );
}

#[test]
fn turning_a_map_a_full_turn_changes_no_pixel() {
    let m = map(32, 16, |i, j| {
        [(i % 5) as f32, (j % 3) as f32, 1.0 + (i * j % 7) as f32]
    });
    let maps = Maps(vec![("m.hdr", m)]);
    let still = scene(balls(serde_json::json!({"map": "m.hdr"})), &maps);
    let turned = scene(
        balls(serde_json::json!({"map": "m.hdr", "rotation_deg": 360})),
        &maps,
    );
    let quarter = scene(
        balls(serde_json::json!({"map": "m.hdr", "rotation_deg": 90})),
        &maps,
    );
    for (name, mut backend) in backends() {
        let q = quality(true, 11);
        let a = render_on(&mut backend, &still, 16, 12, &q, 16);
        let b = render_on(&mut backend, &turned, 16, 12, &q, 16);
        let c = render_on(&mut backend, &quarter, 16, 12, &q, 16);
        assert!(
            a.pixels() == b.pixels(),
            "{name}: a full turn changed the image"
        );
        assert!(a.pixels() != c.pixels(), "{name}: a quarter turn did not");
    }
}

#[test]
fn a_hidden_map_lights_the_scene_but_the_camera_sees_the_background() {
    let m = map(16, 8, |_, _| [1.0; 3]);
    let maps = Maps(vec![("m.hdr", m)]);
    let json = |visible: bool| {
        serde_json::json!({
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 30},
            "materials": {"white": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
            "objects": [{"type": "sphere", "center": [0, 0, -100], "radius": 0.5, "material": "white"}],
            "environment": {"map": "m.hdr", "visible": visible, "background": [0.25, 0.5, 0.75]}
        })
    };
    for (name, mut backend) in backends() {
        let q = quality(true, 12);
        let shown = render_on(&mut backend, &scene(json(true), &maps), 8, 8, &q, 4);
        let hidden = render_on(&mut backend, &scene(json(false), &maps), 8, 8, &q, 4);
        let (a, b) = (pooled(&regions(&shown, 8)), pooled(&regions(&hidden, 8)));
        assert!(
            (a.mean[0] - 1.0).abs() < 1e-5,
            "{name}: visible map {:?}",
            a.mean
        );
        for (got, want) in b.mean.iter().zip([0.25, 0.5, 0.75]) {
            assert!((got - want).abs() < 1e-5, "{name}: hidden map {:?}", b.mean);
        }
    }
}

#[test]
fn the_kernel_looks_up_samples_and_weighs_the_map_as_the_cpu_does() {
    let Some(d) = common::opencl_device() else {
        return;
    };
    let real = pathstream::resolve::env_map_file(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/sunset-64.hdr"
    )))
    .expect("reads");
    let maps = Maps(vec![("sunset.hdr", Arc::new(real))]);
    let json =
        balls(serde_json::json!({"map": "sunset.hdr", "rotation_deg": 41, "intensity": 1.5}));
    let s = scene(json, &maps);
    let job = RenderJob::new(&s, 8, 8, &Quality::default());
    let light = job.world.env_map.clone().expect("a map");
    let packed = pack(&job);
    let n = 50_000u64;
    let dirs: Vec<[f32; 4]> = (0..n)
        .map(|i| match i % 50 {
            // The poles, the seam behind the map and the axes.
            0 => [0.0, 1.0, 0.0, 0.0],
            1 => [0.0, -1.0, 0.0, 0.0],
            2 => [0.0, 0.0, 1.0, 0.0],
            3 => [-1.0, 0.0, 0.0, 0.0],
            _ => parity::unit(i, 40).extend(0.0).to_array(),
        })
        .collect();
    let us: Vec<[f32; 2]> = (0..n)
        .map(|i| [parity::uniform(i, 41), parity::uniform(i, 42)])
        .collect();
    let out: Vec<f32> = parity::checks(&d)
        .run(
            "check_env_map",
            n as usize,
            10,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&dirs)),
                CheckArg::Buffer(bytemuck::cast_slice(&us)),
                CheckArg::Buffer(bytemuck::bytes_of(&packed.params)),
                CheckArg::Buffer(bytemuck::cast_slice(packed.env_texels())),
                CheckArg::Buffer(bytemuck::cast_slice(packed.env_dist())),
            ],
        )
        .expect("run");
    let mut sampled = 0;
    for i in 0..n as usize {
        let dv = Vec3A::from_slice(&dirs[i][..3]);
        let r = light.radiance(dv);
        let s = light.sample(us[i][0], us[i][1]);
        let (dir, w) = s.unwrap_or((Vec3A::ZERO, 0.0));
        let want = [
            r.x,
            r.y,
            r.z,
            light.pdf(dv),
            if s.is_some() { 1.0 } else { 0.0 },
            dir.x,
            dir.y,
            dir.z,
            w,
            pathstream::render::math::atan2_turns(dv.y, dv.x),
        ];
        sampled += usize::from(s.is_some());
        let got = &out[10 * i..10 * i + 10];
        for (k, (g, c)) in got.iter().zip(want).enumerate() {
            assert_eq!(
                g.to_bits(),
                c.to_bits(),
                "item {i} ({dv:?}) value {k}: device {g}, CPU {c}"
            );
        }
    }
    assert!(sampled > n as usize * 99 / 100, "samples: {sampled}");
    // The square and the sphere correspond on both sides' terms.
    let (m, _) = map_direction(0.25, 0.5);
    assert!((map_uv(m).0 - 0.25).abs() < 1e-6);
}

/// The device keeps a map between jobs: a new job of the same map (a camera
/// move, an edit) uploads its other arrays but not the map, and renders
/// the same samples as before; a job of another map uploads that one.
#[test]
fn a_map_is_uploaded_once_for_the_jobs_that_share_it() {
    let Some(mut d) = common::opencl_device() else {
        return;
    };
    let real = Arc::new(
        pathstream::resolve::env_map_file(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/sunset-64.hdr"
        )))
        .expect("reads"),
    );
    let flat = map(16, 8, |_, _| [0.5, 0.5, 0.5]);
    let bytes = |m: &EnvMap| (m.texels.len() * 12 + m.dist.data.len() * 4) as u64;
    let maps = Maps(vec![
        ("sunset.hdr", real.clone()),
        ("flat.hdr", flat.clone()),
    ]);
    let sunset = scene(balls(serde_json::json!({"map": "sunset.hdr"})), &maps);
    let mut render = |s: &Scene| {
        let before = d.scene_bytes_uploaded;
        let job = RenderJob::new(s, 16, 16, &quality(true, 1));
        let mut film = Film::new(16, 16);
        d.render(&job, &mut film, 4).expect("render");
        (film, d.scene_bytes_uploaded - before)
    };
    let (first, uploaded) = render(&sunset);
    assert!(uploaded >= bytes(&real), "first job: {uploaded} bytes");
    let (again, uploaded) = render(&sunset);
    assert!(
        uploaded < bytes(&real),
        "the same map again: {uploaded} bytes"
    );
    let same = first.mean() == again.mean();
    assert!(same, "the shared map renders the same samples");
    let (_, uploaded) = render(&scene(balls(serde_json::json!({"map": "flat.hdr"})), &maps));
    assert!(uploaded >= bytes(&flat), "another map: {uploaded} bytes");
}
