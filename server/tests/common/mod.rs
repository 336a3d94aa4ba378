//! Shared helpers for the renderer's statistical tests: render on a backend,
//! reduce films to region means with their standard errors, and compare.
#![allow(dead_code)]

pub mod films;
pub mod meshes;

use pathstream::render::scene::{MaterialJson, SurfaceJson};
use pathstream::render::{Backend, BackendChoice, Film, Quality, RenderJob, Scene};

/// Renders `spp` samples per pixel of `scene` on `backend`.
pub fn render_on(
    backend: &mut Backend,
    scene: &Scene,
    w: u32,
    h: u32,
    q: &Quality,
    spp: u64,
) -> Film {
    q.validate().expect("valid quality");
    let job = RenderJob::new(scene, w, h, q);
    let mut film = Film::new(w, h);
    backend.render(&job, &mut film, spp).expect("render");
    film
}

/// OpenCL device 0, if there is one (where `CI` is set, none is a failure,
/// so that a suite cannot pass by skipping).
pub fn opencl_device() -> Option<pathstream::render::backend::opencl::OpenClBackend> {
    match pathstream::render::backend::opencl::OpenClBackend::new(None) {
        Ok(b) => Some(b),
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but there is no OpenCL device: {e}")
        }
        Err(e) => {
            eprintln!("skipping OpenCL: {e}");
            None
        }
    }
}

/// Every backend a check must pass on: rayon, then OpenCL device 0 if
/// there is one (as [`opencl_device`]).
pub fn backends() -> Vec<(&'static str, Backend)> {
    let mut all = vec![("cpu", Backend::choose(BackendChoice::Cpu).expect("cpu"))];
    if let Some(d) = opencl_device() {
        all.push((
            "opencl",
            Backend::OpenCl {
                backend: Box::new(d),
                fallback: false,
            },
        ));
    }
    all
}

/// Whether Embree loads (where `CI` is set, not loading is a failure).
pub fn embree() -> bool {
    match pathstream::render::embree::embree() {
        Ok(_) => true,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but {e} (scripts/test.sh installs it)")
        }
        Err(e) => {
            eprintln!("skipping Embree: {e}");
            false
        }
    }
}

/// What mesh checks must pass on: [`backends`], and the CPU tracing every
/// mesh through Embree where Embree loads (as [`embree`]).
pub fn mesh_backends() -> Vec<(&'static str, Backend)> {
    let mut all = backends();
    if embree() {
        use pathstream::render::backend::{CpuBackend, EmbreeUse};
        let cpu = CpuBackend::default().with_embree(EmbreeUse::AllMeshes);
        all.push(("cpu-embree", Backend::Cpu(cpu)));
    }
    all
}

/// Renders on the CPU backend.
pub fn render(scene: &Scene, w: u32, h: u32, q: &Quality, spp: u64) -> Film {
    let mut backend = Backend::choose(BackendChoice::Cpu).expect("cpu backend");
    render_on(&mut backend, scene, w, h, q, spp)
}

pub fn scene(name: &str) -> Scene {
    pathstream::resolve::load_scene(name).expect("built-in scene")
}

/// The furnace scene with the shell's albedo and emission replaced.
pub fn furnace(albedo: f64, emission: f64) -> Scene {
    let mut json = scene("furnace").to_json();
    json.materials.insert(
        "shell".into(),
        MaterialJson::Diffuse(SurfaceJson {
            albedo: [albedo; 3].into(),
            emission: Some([emission; 3].into()),
            normal: None,
            alpha: None,
        }),
    );
    Scene::from_json(&json).expect("valid furnace")
}

/// Mean of a block of pixels and the variance of that mean, per channel.
#[derive(Clone, Copy, Debug)]
pub struct Region {
    pub mean: [f64; 3],
    pub var: [f64; 3],
}

/// The mean of the pixels in columns `xs` and rows `ys`, and the variance of
/// that mean. The variance of each pixel's mean comes from its even/odd
/// halves, (A - B)^2 nA nB / n^2; pixels are independent, so a region's is
/// the sum over n_pixels^2.
pub fn region(film: &Film, xs: std::ops::Range<u32>, ys: std::ops::Range<u32>) -> Region {
    let w = film.width();
    let mut r = Region {
        mean: [0.0; 3],
        var: [0.0; 3],
    };
    let mut count = 0.0;
    for y in ys {
        for x in xs.clone() {
            let i = (y * w + x) as usize;
            // Each pixel's own samples (adaptive films give tiles more).
            let spp = film.pixel_spp(i);
            let (n, na, nb) = (spp as f64, spp.div_ceil(2) as f64, (spp / 2) as f64);
            let p = film.pixels()[i];
            for c in 0..3 {
                r.mean[c] += (p.even[c] + p.odd[c]) / n;
                let d = p.even[c] / na - p.odd[c] / nb;
                r.var[c] += d * d * na * nb / (n * n);
            }
            count += 1.0;
        }
    }
    for c in 0..3 {
        r.mean[c] /= count;
        r.var[c] /= count * count;
    }
    r
}

/// Splits the film into `block` x `block` regions, row by row.
pub fn regions(film: &Film, block: u32) -> Vec<Region> {
    let (w, h) = (film.width(), film.height());
    let mut out = Vec::new();
    for by in (0..h).step_by(block as usize) {
        for bx in (0..w).step_by(block as usize) {
            out.push(region(
                film,
                bx..(bx + block).min(w),
                by..(by + block).min(h),
            ));
        }
    }
    out
}

/// The whole image as one region: the mean of the regions' means and the
/// variance of that mean (regions are independent).
pub fn pooled(regions: &[Region]) -> Region {
    let n = regions.len() as f64;
    let mut all = Region {
        mean: [0.0; 3],
        var: [0.0; 3],
    };
    for r in regions {
        for c in 0..3 {
            all.mean[c] += r.mean[c] / n;
            all.var[c] += r.var[c] / (n * n);
        }
    }
    all
}

/// Chi-square with `k` degrees of freedom exceeded with probability 1e-6
/// (Wilson-Hilferty; within 2% of the exact quantile for k >= 4).
pub fn chi_square_1e6(k: usize) -> f64 {
    let k = k as f64;
    let h = 2.0 / (9.0 * k);
    k * (1.0 - h + 4.753 * h.sqrt()).powi(3)
}

/// How far `x` is from `y` in standard errors `se`, after a `floor`.
fn z_score(x: f64, y: f64, floor: f64, se: f64) -> f64 {
    let diff = (x - y).abs();
    if diff <= floor {
        0.0
    } else {
        (diff - floor) / se
    }
}

/// Asserts that every region of `a` and `b` agrees within `z_max` standard
/// errors (plus a relative floor `rel` for regions with no noise); and, as
/// no region alone has the power to see a small bias spread over the image,
/// that the whole image agrees within `z_max` of its own (much smaller)
/// standard error, and that the regions' squared z-scores, summed per
/// channel, stay below chi-square's 1e-6 quantile.
pub fn assert_agree(a: &Film, b: &Film, block: u32, z_max: f64, rel: f64, what: &str) {
    let (ra, rb) = (regions(a, block), regions(b, block));
    assert_eq!(ra.len(), rb.len());
    let (wa, wb) = (pooled(&ra), pooled(&rb));
    for c in 0..3 {
        let floor = rel * wa.mean[c].abs().max(wb.mean[c].abs());
        let se = (wa.var[c] + wb.var[c]).sqrt();
        let z = z_score(wa.mean[c], wb.mean[c], floor, se);
        assert!(
            z < z_max,
            "{what}: whole image channel {c}: {} vs {} ({z:.1} standard errors apart, se {se:.3e})",
            wa.mean[c],
            wb.mean[c]
        );
    }
    if ra.len() >= 4 {
        let limit = chi_square_1e6(ra.len());
        for c in 0..3 {
            let chi2: f64 = (ra.iter().zip(&rb))
                .map(|(x, y)| {
                    let floor = rel * x.mean[c].abs().max(y.mean[c].abs());
                    let se = (x.var[c] + y.var[c]).sqrt();
                    z_score(x.mean[c], y.mean[c], floor, se).powi(2)
                })
                .sum();
            assert!(
                chi2 < limit,
                "{what}: channel {c}: chi-square {chi2:.1} over {} regions (p = 1e-6 at {limit:.1})",
                ra.len()
            );
        }
    }
    let mut worst = 0.0f64;
    for (i, (x, y)) in ra.iter().zip(&rb).enumerate() {
        for c in 0..3 {
            let diff = (x.mean[c] - y.mean[c]).abs();
            let floor = rel * x.mean[c].abs().max(y.mean[c].abs());
            let se = (x.var[c] + y.var[c]).sqrt();
            let z = if diff <= floor {
                0.0
            } else {
                (diff - floor) / se
            };
            worst = worst.max(z);
            assert!(
                z < z_max,
                "{what}: region {i} channel {c}: {} vs {} ({z:.1} standard errors apart, se {se:.3e})",
                x.mean[c],
                y.mean[c]
            );
        }
    }
    eprintln!("{what}: worst region differs by {worst:.2} standard errors");
}

/// Asserts that every region's mean is within `z_max` standard errors of
/// `expected`, and the whole image's within `z_max` of its own standard
/// error (a bias of 1-2% over every pixel hides in a region's noise).
pub fn assert_mean(film: &Film, block: u32, expected: f64, z_max: f64, rel: f64, what: &str) {
    let all = regions(film, block);
    let whole = pooled(&all);
    for c in 0..3 {
        let se = whole.var[c].sqrt();
        let z = z_score(whole.mean[c], expected, rel * expected.abs(), se);
        assert!(
            z < z_max,
            "{what}: whole image channel {c}: {} vs expected {expected} ({z:.1} standard errors, se {se:.2e})",
            whole.mean[c]
        );
    }
    for (i, r) in all.iter().enumerate() {
        for c in 0..3 {
            let diff = (r.mean[c] - expected).abs();
            let floor = rel * expected.abs();
            let se = r.var[c].sqrt();
            assert!(
                diff <= floor || diff - floor < z_max * se,
                "{what}: region {i} channel {c}: {} vs expected {expected} (se {se:.3e})",
                r.mean[c]
            );
        }
    }
}

/// Renders `scene` on every backend (`spp` samples at w x h) and asserts
/// that each image agrees with the first one's (4x4 blocks, 4.5 standard
/// errors, 0.5%); where `CI` is set both backends must have rendered.
pub fn assert_backends_agree(scene: &Scene, (w, h): (u32, u32), q: &Quality, spp: u64) {
    let films: Vec<_> = backends()
        .into_iter()
        .map(|(name, mut b)| {
            let film = render_on(&mut b, scene, w, h, q, spp);
            assert_clean(&film, name);
            (name, film)
        })
        .collect();
    let (first, a) = &films[0];
    for (name, b) in &films[1..] {
        assert_agree(a, b, 4, 4.5, 0.005, &format!("{first} vs {name}"));
    }
    if std::env::var_os("CI").is_some() {
        assert_eq!(films.len(), 2, "CI checks the OpenCL backend too");
    }
}

/// On every backend: `scene` with next-event estimation (`spp` samples)
/// and without it (twice as many) gives the same image (as
/// [`assert_backends_agree`] compares).
pub fn assert_nee_on_off_agree(scene: &Scene, (w, h): (u32, u32), q: &Quality, spp: u64) {
    for (name, mut backend) in backends() {
        let on = render_on(&mut backend, scene, w, h, q, spp);
        let off_q = Quality { nee: false, ..*q };
        let off = render_on(&mut backend, scene, w, h, &off_q, 2 * spp);
        assert_clean(&on, name);
        assert_clean(&off, name);
        assert_agree(&on, &off, 4, 4.5, 0.005, &format!("{name}: NEE on vs off"));
    }
}

/// Every pixel mean is finite and nothing was rejected.
pub fn assert_clean(film: &Film, what: &str) {
    assert_eq!(film.rejected(), 0, "{what}: rejected samples");
    assert!(
        film.mean().iter().flatten().all(|v| v.is_finite()),
        "{what}: non-finite pixel"
    );
}

/// A `mesh` object with inline data (normals kept only if `smooth`).
pub fn mesh_object(
    m: &pathstream::model::MeshData,
    material: &str,
    transform: serde_json::Value,
    smooth: bool,
) -> serde_json::Value {
    let mut data = serde_json::json!({
        "positions": m.positions.iter().map(|p| p.map(f64::from)).collect::<Vec<_>>(),
        "triangles": m.triangles,
    });
    if smooth {
        if let Some(n) = &m.normals {
            data["normals"] =
                serde_json::json!(n.iter().map(|p| p.map(f64::from)).collect::<Vec<_>>());
        }
    }
    let mut o = serde_json::json!({"type": "mesh", "data": data, "material": material});
    if !transform.is_null() {
        o["transform"] = transform;
    }
    o
}

/// A built-in scene as JSON, to edit.
pub fn scene_json(name: &str) -> serde_json::Value {
    serde_json::to_value(scene(name).to_json()).expect("scene JSON")
}

/// Asserts that the region's mean is within `z_max` standard errors (plus an
/// absolute `floor` for what the expectation's own computation may miss) of
/// `expected`, in every channel.
pub fn assert_region(r: &Region, expected: f64, z_max: f64, floor: f64, what: &str) {
    for c in 0..3 {
        let diff = (r.mean[c] - expected).abs();
        let se = r.var[c].sqrt();
        assert!(
            diff <= floor + z_max * se,
            "{what}: channel {c}: {} vs expected {expected} ({:.1} standard errors, se {se:.2e})",
            r.mean[c],
            (diff - floor).max(0.0) / se
        );
    }
}

/// The Stanford bunny from the npm package `bunny` (installed into
/// tests/models by scripts/test.sh): 1,839 vertices, 3,674 triangles. None
/// when it is not installed, except under CI, where that is a failure.
pub fn bunny() -> Option<pathstream::model::MeshData> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/models/node_modules/bunny/index.js");
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("{}: {e} (scripts/test.sh installs it)", path.display())
        }
        Err(e) => {
            eprintln!(
                "skipping: no bunny at {} ({e}); scripts/test.sh installs it",
                path.display()
            );
            return None;
        }
    };
    // Two lines: `exports.positions=[[x,y,z],...]` and `exports.cells=[[a,b,c],...]`.
    let value = |key: &str| -> serde_json::Value {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("exports.{key}=")))
            .expect("bunny line");
        serde_json::from_str(&line[line.find('=').expect("=") + 1..]).expect("bunny JSON")
    };
    let positions: Vec<[f32; 3]> = serde_json::from_value(value("positions")).expect("positions");
    let triangles: Vec<[u32; 3]> = serde_json::from_value(value("cells")).expect("cells");
    Some(pathstream::model::MeshData {
        name: "bunny".into(),
        materials: vec![0; triangles.len()],
        positions,
        normals: None,
        triangles,
        ..Default::default()
    })
}

/// Largest relative RMS difference between two devices' renders of the
/// same samples: their rounding turns a few paths another way, which moved
/// cornell-glass at 32x32 by up to 2.7e-4 relative RMS (PoCL and rayon, 64
/// to 1024 spp, 4 seeds each), where another seed or a block lost or
/// doubled moves it by about the noise, 1e-2 to 1e-1.
pub const ROUNDING_RMS: f64 = 1e-3;

/// Most pixels (a share) of which a channel may differ by more than 1e-4
/// relative between two devices' renders of the same samples: those where
/// rounding turned a path: up to 3% measured (as above), 6% at 1024 spp
/// through the service (all_devices.rs). A block lost, doubled or scaled
/// by 0.3% moves nearly every pixel by more.
pub const ROUNDING_PIXELS: f64 = 0.2;

/// Asserts that `a` and `b` are one image made of the same samples by
/// different devices: within [`ROUNDING_RMS`] relative RMS, and all but
/// [`ROUNDING_PIXELS`] of the pixels equal to 1e-4 (f32 sums of the same
/// samples in another order agree to ~1e-6).
pub fn assert_same_samples(a: &[[f32; 3]], b: &[[f32; 3]], what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: sizes");
    let rms = pathstream::render::film::relative_rms_error(a, b);
    let differing = a
        .iter()
        .zip(b)
        .filter(|(x, y)| {
            (0..3).any(|c| {
                let scale = x[c].abs().max(y[c].abs()).max(1e-3);
                (x[c] - y[c]).abs() / scale > 1e-4
            })
        })
        .count();
    let share = differing as f64 / a.len() as f64;
    eprintln!(
        "{what}: {rms:.2e} relative RMS, {differing} of {} pixels differ",
        a.len()
    );
    assert!(
        rms < ROUNDING_RMS && share <= ROUNDING_PIXELS,
        "{what}: {rms:e} relative RMS (rounding: < {ROUNDING_RMS:e}), {differing} of {} pixels differ",
        a.len()
    );
}

/// Whether Open Image Denoise is installed (where `CI` is set, its absence
/// fails the test: scripts/test.sh installs it).
pub fn oidn() -> bool {
    match pathstream::render::denoise::available() {
        Ok(()) => true,
        Err(e) if std::env::var_os("CI").is_some() => {
            panic!("CI is set but {e} (scripts/test.sh installs it)")
        }
        Err(e) => {
            eprintln!("skipping: {e}");
            false
        }
    }
}

/// A unit ball of `material` at the origin under a uniform white sky,
/// filling most of a square view.
pub fn sky_sphere(material: serde_json::Value) -> Scene {
    let s = serde_json::json!({
        "camera": {"position": [0, 0, 3.2], "look_at": [0, 0, 0], "vfov_deg": 36},
        "environment": [1, 1, 1],
        "materials": {"m": material},
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}

/// A scene of one sphere of `material` (named `m`) is refused, and the
/// message names `named` (a field's path, e.g. `materials.m.ior`).
pub fn assert_material_refused(material: &serde_json::Value, named: &str) {
    let s = serde_json::json!({
        "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "vfov_deg": 40},
        "materials": {"m": material},
        "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}]
    });
    let e = Scene::from_json_str(&s.to_string()).expect_err("invalid");
    assert!(e.to_string().contains(named), "{material}: {e}");
}

/// `scene` written as JSON and read back has the same materials; the JSON
/// text, for what a test expects it to say.
pub fn assert_round_trip(scene: &Scene) -> String {
    let back = Scene::from_json(&scene.to_json()).expect("round trip");
    assert_eq!(scene.materials, back.materials);
    serde_json::to_string(&scene.to_json()).expect("serialises")
}

/// The whole image's mean, and its centre's, is 1 within `rel` (and 4.5 of
/// its standard errors), in every channel. Paths are unbounded (Russian
/// roulette ends them): light may bounce inside many times.
pub fn assert_invisible(scene: &Scene, spp: u64, rel: f64, what: &str) {
    let q = Quality {
        max_depth: 0,
        filter: pathstream::render::Filter::Box,
        ..Quality::default()
    };
    for (name, mut backend) in backends() {
        let film = render_on(&mut backend, scene, 24, 24, &q, spp);
        let what = format!("{name}: {what}");
        assert_clean(&film, &what);
        let all = region(&film, 0..24, 0..24);
        let centre = region(&film, 6..18, 6..18);
        for c in 0..3 {
            for (r, part) in [(&all, "image"), (&centre, "centre")] {
                let (m, se) = (r.mean[c], r.var[c].sqrt());
                assert!(
                    (m - 1.0).abs() < rel + 4.5 * se,
                    "{what}: {part} mean {m} (se {se:.1e})"
                );
            }
        }
    }
}

/// The box filter, everything else default: what the material tests use.
pub fn box_quality() -> Quality {
    Quality {
        filter: pathstream::render::Filter::Box,
        ..Quality::default()
    }
}

/// Three balls of radius 0.5 (materials named as `balls` gives them, left
/// to right, the middle one nearer) on a diffuse floor under a quad light
/// and a dim sky.
pub fn balls_on_a_floor(balls: [(&str, serde_json::Value); 3]) -> Scene {
    let mut materials = serde_json::json!({
        "floor": {"type": "diffuse", "albedo": [0.6, 0.6, 0.6]},
        "light": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [6, 6, 6]}
    });
    let mut objects = vec![
        serde_json::json!({"type": "quad", "corner": [-4, -1, -4], "edge_u": [8, 0, 0], "edge_v": [0, 0, 8], "material": "floor"}),
        serde_json::json!({"type": "quad", "corner": [-1, 3, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "light"}),
    ];
    for ((name, m), center) in
        balls
            .into_iter()
            .zip([[-1.1, -0.5, 0.0], [0.0, -0.5, 0.3], [1.1, -0.5, 0.0]])
    {
        materials[name] = m;
        objects.push(serde_json::json!({"type": "sphere", "center": center, "radius": 0.5, "material": name}));
    }
    let s = serde_json::json!({
        "camera": {"position": [0, 0.6, 4], "look_at": [0, -0.2, 0], "vfov_deg": 45},
        "environment": [0.2, 0.25, 0.3],
        "materials": materials,
        "objects": objects
    });
    Scene::from_json_str(&s.to_string()).expect("valid scene")
}
