//! The kernel's routines against their Rust twins, routine by routine, on
//! the same inputs (check kernels in `kernels/checks.cl`): the sampler bit
//! for bit; sincos, the tent filter, sphere and quad intersection, the
//! nearest hit and scattering off every material within a few ulps. Runs on
//! any OpenCL device (PoCL in CI, where a missing device is a failure).

mod common;
mod parity;

use common::opencl_device as device;
use parity::{checks, ray_input, rays_around, ulps, uniform, unit};
use pathstream::render::backend::nearest_hits;
use pathstream::render::backend::opencl::{
    device_uses_bvh, pack, CheckArg, Checks, KernelParams, OpenClBackend, Packed,
};
use pathstream::render::material::{scatter, Bsdf};
use pathstream::render::math::{sincos_turns, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::{mix64, Sampler, SamplerKind};
use pathstream::render::shape::Roots;
use pathstream::render::world::{Geometry, Origin};
use pathstream::render::{Filter, Quality, RenderJob, Scene};

fn job(scene: &str) -> RenderJob {
    RenderJob::new(
        &pathstream::resolve::load_scene(scene).expect("built-in"),
        16,
        16,
        &Quality::default(),
    )
}

#[test]
fn the_sampler_is_bit_exact() {
    let Some(d) = device() else { return };
    let n = 4096u64;
    let input: Vec<u64> = (0..n)
        .flat_map(|i| [mix64(i), mix64(i + n) % 1_000_000, i * 7])
        .collect();
    let out: Vec<u64> = checks(&d)
        .run(
            "check_rng",
            n as usize,
            8,
            &[CheckArg::Buffer(bytemuck::cast_slice(&input))],
        )
        .expect("run");
    for i in 0..n as usize {
        let mut s = Sampler::new(input[3 * i], input[3 * i + 1], input[3 * i + 2]);
        let cpu: Vec<u64> = (0..8).map(|_| s.next_u64()).collect();
        assert_eq!(&out[8 * i..8 * i + 8], &cpu[..], "item {i}");
    }
}

/// Both ways the kernel may make a Sobol path's first points: lazily, where
/// each is used (GPUs), and ahead, with the sampler (CPU devices).
#[test]
fn every_use_of_either_sampler_gives_the_same_bits() {
    let Some(d) = device() else { return };
    for ahead in ["-D SAMPLER_AHEAD=0", "-D SAMPLER_AHEAD=1"] {
        let c = d.checks(ahead).expect("the check program builds");
        sampler_uses_agree(&c, ahead);
    }
}

fn sampler_uses_agree(c: &Checks<'_>, options: &str) {
    let n = 1u64 << 12;
    let input: Vec<u64> = (0..n)
        .flat_map(|i| {
            [
                i % 2,
                mix64(i) % 5,
                mix64(i + n) % 1_000_000,
                (i / 2) * 5 + mix64(i) % 3,
            ]
        })
        .collect();
    let out: Vec<u32> = c
        .run(
            "check_sampler_uses",
            n as usize,
            28,
            &[CheckArg::Buffer(bytemuck::cast_slice(&input))],
        )
        .expect("run");
    for i in 0..n as usize {
        let kind = [SamplerKind::Random, SamplerKind::Sobol][input[4 * i] as usize];
        let mut s = Sampler::of_kind(kind, input[4 * i + 1], input[4 * i + 2], input[4 * i + 3]);
        let mut cpu = Vec::new();
        for k in 0..2 {
            s.at_vertex(3 * k);
            let c = s.camera_2d();
            let lens = s.lens_2d();
            let pick = s.light_pick_2d();
            let (l0, l2) = (s.light_2d(0), s.light_2d(2));
            let b = s.bsdf_choice();
            let d = s.bsdf_2d();
            let r = s.roulette();
            cpu.extend([
                c.0.to_bits(),
                c.1.to_bits(),
                lens.0.to_bits(),
                lens.1.to_bits(),
                pick.0,
                pick.1.to_bits(),
            ]);
            cpu.extend([l0.0, l0.1, l2.0, l2.1, b, d.0, d.1, r].map(f32::to_bits));
        }
        assert_eq!(
            &out[28 * i..28 * i + 28],
            &cpu[..],
            "item {i} ({kind:?}, {options})"
        );
    }
}

#[test]
fn sincos_and_the_pixel_filters_agree_to_an_ulp() {
    let Some(d) = device() else { return };
    let c = checks(&d);
    let n = 1 << 16;
    let u: Vec<f32> = (0..n)
        .map(|i| {
            if i % 2 == 0 {
                i as f32 / n as f32
            } else {
                uniform(i, 1)
            }
        })
        .collect();
    let out: Vec<f32> = c
        .run(
            "check_sincos",
            n as usize,
            2,
            &[CheckArg::Buffer(bytemuck::cast_slice(&u))],
        )
        .expect("run");
    let worst = (0..n as usize)
        .map(|i| {
            let (s, cs) = sincos_turns(u[i]);
            ulps(out[2 * i], s).max(ulps(out[2 * i + 1], cs))
        })
        .max()
        .unwrap_or(0);
    assert!(worst <= 1, "sincos differs by {worst} ulps");

    for (filter, stratified) in [
        (Filter::Tent2x2, false),
        (Filter::Box, false),
        (Filter::Tent2x2, true),
        (Filter::Box, true),
    ] {
        let mut params = pack(&job("cornell")).params;
        params.filter = u32::from(filter == Filter::Box);
        params.sampler = u32::from(stratified);
        let items = 1 << 14;
        let out: Vec<f32> = c
            .run(
                "check_pixel_offset",
                items,
                2,
                &[
                    CheckArg::Buffer(bytemuck::cast_slice(&u[..2 * items])),
                    CheckArg::Buffer(bytemuck::bytes_of(&params)),
                ],
            )
            .expect("run");
        for i in 0..items {
            let (x, y) = if stratified {
                filter.pixel_offset_stratified(u[2 * i], u[2 * i + 1])
            } else {
                filter.pixel_offset(i as u64, u[2 * i], u[2 * i + 1])
            };
            assert!(
                ulps(out[2 * i], x) <= 1 && ulps(out[2 * i + 1], y) <= 1,
                "{filter:?} sample {i}: ({}, {}) vs ({x}, {y})",
                out[2 * i],
                out[2 * i + 1]
            );
        }
    }
}

/// Rays as the check kernels read them: origin and direction as float4s.
/// The arguments of `check_intersect` and `check_nearest` after the item
/// count: the rays and the scene's buffers.
fn ray_args<'a>(input: &'a [[f32; 4]], packed: &'a Packed) -> Vec<CheckArg<'a>> {
    vec![
        CheckArg::Buffer(bytemuck::cast_slice(input)),
        CheckArg::Buffer(bytemuck::cast_slice(&packed.objects)),
        CheckArg::Buffer(bytemuck::bytes_of::<KernelParams>(&packed.params)),
        CheckArg::Buffer(bytemuck::cast_slice(&packed.nodes)),
        CheckArg::Buffer(bytemuck::cast_slice(&packed.prims)),
        CheckArg::Buffer(bytemuck::cast_slice(&packed.big)),
    ]
}

/// 1e5 rays from inside the scene in every direction, against each object
/// and for the nearest hit.
fn intersections_agree(d: &OpenClBackend, scene: &str) {
    let job = job(scene);
    let packed = pack(&job);
    let world = &job.world;
    let count = world.objects.len();
    // Origins around the camera-relative scene centre, within its size.
    let centre = world.objects.iter().find_map(|o| match &o.geometry {
        Geometry::Quad(q) => Some(q.corner + 0.5 * (q.edge_u + q.edge_v)),
        _ => None,
    });
    let (centre, size) = match centre {
        Some(c) => (c, 40.0),
        None => (job.camera.forward * 120.0, 40.0),
    };
    let n = 100_000u64;
    let rays: Vec<Ray> = (0..n)
        .map(|i| {
            let jitter = Vec3A::new(
                uniform(i, 10) - 0.5,
                uniform(i, 11) - 0.5,
                uniform(i, 12) - 0.5,
            );
            Ray::new(centre + jitter * size, unit(i, 20))
        })
        .collect();
    let input = ray_input(&rays);
    let out: Vec<f32> = checks(d)
        .run(
            "check_intersect",
            n as usize,
            count + 2,
            &ray_args(&input, &packed),
        )
        .expect("run");
    let cpu_nearest = nearest_hits(
        world,
        &rays.iter().map(|r| (*r, Origin::NONE)).collect::<Vec<_>>(),
    );
    let (mut worst, mut hits, mut other_object) = (0u64, 0usize, 0usize);
    for (i, ray) in rays.iter().enumerate() {
        let r = &out[i * (count + 2)..(i + 1) * (count + 2)];
        let mut ts = Vec::with_capacity(count);
        for (j, o) in world.objects.iter().enumerate() {
            let t = match &o.geometry {
                Geometry::Sphere(s) => s.intersect(ray, Roots::Any),
                Geometry::Quad(q) => q.intersect(ray),
                Geometry::Instance(_) => unreachable!("no meshes here"),
            };
            let u = ulps(r[j], t);
            assert!(
                u <= 8,
                "{scene}: ray {i}, object {j}: device {} vs CPU {t} ({u} ulps)",
                r[j]
            );
            worst = worst.max(u);
            ts.push(t);
        }
        let device_hit = r[count + 1].to_bits();
        match cpu_nearest[i] {
            None => assert_eq!(
                device_hit,
                u32::MAX,
                "{scene}: ray {i}: the device hit {device_hit}, the CPU nothing"
            ),
            Some(h) => {
                hits += 1;
                assert!(
                    ulps(r[count], h.t) <= 8,
                    "{scene}: ray {i}: nearest t {} vs {}",
                    r[count],
                    h.t
                );
                if device_hit != h.object {
                    // Only a tie within rounding may pick another object.
                    other_object += 1;
                    let td = ts[device_hit as usize];
                    assert!(
                        ulps(td, h.t) <= 8,
                        "{scene}: ray {i}: object {device_hit} at {td} vs {} at {}",
                        h.object,
                        h.t
                    );
                }
            }
        }
    }
    eprintln!("{scene}: {hits} of {n} rays hit; worst {worst} ulps; {other_object} ties resolved differently");
    assert!(
        hits > n as usize / 2,
        "{scene}: the rays mostly hit the scene ({hits})"
    );
    assert!(
        other_object * 10_000 <= n as usize,
        "{scene}: {other_object} different nearest objects"
    );
}

#[test]
fn sphere_and_quad_intersection_and_the_nearest_hit_agree_on_1e5_rays() {
    let Some(d) = device() else { return };
    intersections_agree(&d, "cornell-quads");
    intersections_agree(&d, "smallpt");
}

/// `cornell` (or `cornell-quads`) with `extra` small random spheres (or
/// quads): enough to be searched through the BVH.
fn crowded(base: &str, extra: u64, quads: bool) -> RenderJob {
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene(base)
            .expect("built-in")
            .to_json(),
    )
    .expect("json");
    let objects = j["objects"].as_array_mut().expect("objects");
    for i in 0..extra {
        let c = [
            10.0 + 80.0 * uniform(i, 50),
            5.0 + 70.0 * uniform(i, 51),
            20.0 + 130.0 * uniform(i, 52),
        ];
        let size = if quads {
            2.0 + 10.0 * uniform(i, 53)
        } else {
            0.5 + 4.0 * uniform(i, 53)
        };
        objects.push(if quads {
            serde_json::json!({"type": "quad", "corner": c, "edge_u": [size, 0.0, 0.0], "edge_v": [0.0, size, size], "material": "white"})
        } else {
            serde_json::json!({"type": "sphere", "center": c, "radius": size, "material": "white"})
        });
    }
    let scene = Scene::from_json_value(j).expect("valid");
    RenderJob::new(&scene, 16, 16, &Quality::default())
}

/// The device's nearest hit through its BVH against the CPU's on 1e5 rays
/// from inside the box.
fn nearest_agrees(d: &OpenClBackend, label: &str, job: &RenderJob) {
    assert!(
        device_uses_bvh(&job.world),
        "{label}: searched through the BVH on the device"
    );
    let packed = pack(job);
    let n = 100_000u64;
    let centre = Vec3A::from((job.camera.forward * 140.0).to_array());
    let rays = rays_around(centre, 60.0, n);
    let input = ray_input(&rays);
    let out: Vec<f32> = checks(d)
        .run("check_nearest", n as usize, 2, &ray_args(&input, &packed))
        .expect("run");
    let cpu = nearest_hits(
        &job.world,
        &rays.iter().map(|r| (*r, Origin::NONE)).collect::<Vec<_>>(),
    );
    let mut small = 0;
    for i in 0..n as usize {
        let (t, hit) = (out[2 * i], out[2 * i + 1].to_bits());
        match cpu[i] {
            None => assert_eq!(
                hit,
                u32::MAX,
                "{label}: ray {i}: the device hit {hit} at {t}, the CPU nothing"
            ),
            Some(h) => {
                assert_eq!(
                    (hit, ulps(t, h.t)),
                    (h.object, 0),
                    "{label}: ray {i}: device {t} object {hit}, CPU {} object {}",
                    h.t,
                    h.object
                );
                small += usize::from(h.object >= 9);
            }
        }
    }
    eprintln!("{label}: {small} of {n} rays hit one of the added objects");
    assert!(
        small >= 500,
        "{label}: the rays meet the added objects ({small})"
    );
}

#[test]
fn the_bvh_nearest_hit_agrees_on_1e5_rays() {
    let Some(d) = device() else { return };
    // Six radius-1e5 walls tested before the BVH, 600 small spheres in it.
    nearest_agrees(&d, "cornell + 600 spheres", &crowded("cornell", 600, false));
    // 21 spheres: scanned on the CPU, a BVH built for the device.
    let few = crowded("cornell", 12, false);
    assert!(!few.world.uses_bvh());
    nearest_agrees(&d, "cornell + 12 spheres", &few);
    // Quad walls and 120 quads, all in the BVH.
    nearest_agrees(
        &d,
        "cornell-quads + 120 quads",
        &crowded("cornell-quads", 120, true),
    );
}

/// A scene of spheres, one per metallic-roughness corner the kernel must
/// match: metal, dielectric over a coloured base, a mix, a near-mirror,
/// rough glass, glass mixed with the coated base, a thin wall, index-
/// matched glass (a delta straight through), clear coats over a mix and
/// over rough glass, a weakened and tinted specular.
const PBR_SCENE: &str = r#"{
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "vfov_deg": 40},
  "materials": {
    "metal": {"type": "pbr", "base_color": [0.9, 0.6, 0.3], "metallic": 1, "roughness": 0.3},
    "plastic": {"type": "pbr", "base_color": [0.2, 0.5, 0.8], "metallic": 0, "roughness": 0.6},
    "mixed": {"type": "pbr", "base_color": [0.7, 0.7, 0.2], "metallic": 0.5, "roughness": 1.0, "ior": 1.33},
    "polished": {"type": "pbr", "metallic": 1, "roughness": 0.02},
    "frosted": {"type": "pbr", "base_color": [0.9, 0.8, 0.6], "metallic": 0, "roughness": 0.4, "transmission": 1},
    "half": {"type": "pbr", "base_color": [0.3, 0.5, 0.9], "metallic": 0.2, "roughness": 0.2, "transmission": 0.5, "ior": 1.33},
    "thin": {"type": "pbr", "metallic": 0, "roughness": 0.3, "transmission": 1, "thin": true},
    "matched": {"type": "pbr", "base_color": [0.5, 0.9, 0.7], "metallic": 0, "roughness": 0.5, "transmission": 0.7, "ior": 1.0},
    "coated": {"type": "pbr", "base_color": [0.6, 0.1, 0.1], "metallic": 0.3, "roughness": 0.6, "clearcoat": 0.8, "clearcoat_roughness": 0.1},
    "lacquer": {"type": "pbr", "metallic": 0, "roughness": 0.3, "transmission": 1, "clearcoat": 1, "clearcoat_roughness": 0.3},
    "tinted": {"type": "pbr", "base_color": [0.3, 0.6, 0.3], "metallic": 0.1, "roughness": 0.4, "specular": 0.6, "specular_color": [3, 1, 0.2]},
    "frosted": {"type": "pbr", "base_color": [0.8, 0.9, 1], "metallic": 0, "roughness": 0.35, "transmission": 1, "ior": 1.6, "specular": 0.7, "specular_color": [1.5, 0.8, 0.3]},
    "veil": {"type": "pbr", "metallic": 0, "roughness": 0.2, "transmission": 0.8, "thin": true, "specular": 0.4},
    "light": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [4, 4, 4]}
  },
  "objects": [
    {"type": "sphere", "center": [-1.5, 0, 0], "radius": 0.5, "material": "metal"},
    {"type": "sphere", "center": [-0.5, 0, 0], "radius": 0.5, "material": "plastic"},
    {"type": "sphere", "center": [0.5, 0, 0], "radius": 0.5, "material": "mixed"},
    {"type": "sphere", "center": [1.5, 0, 0], "radius": 0.5, "material": "polished"},
    {"type": "sphere", "center": [-1, 1, 0], "radius": 0.5, "material": "frosted"},
    {"type": "sphere", "center": [1, 1, 0], "radius": 0.5, "material": "half"},
    {"type": "sphere", "center": [0, 1, 0], "radius": 0.4, "material": "thin"},
    {"type": "sphere", "center": [0, -1, 0], "radius": 0.4, "material": "matched"},
    {"type": "sphere", "center": [-1, -1, 0], "radius": 0.4, "material": "coated"},
    {"type": "sphere", "center": [1, -1, 0], "radius": 0.4, "material": "lacquer"},
    {"type": "sphere", "center": [2, -1, 0], "radius": 0.4, "material": "tinted"},
    {"type": "sphere", "center": [-2, -1, 0], "radius": 0.4, "material": "frosted"},
    {"type": "sphere", "center": [-2, 1, 0], "radius": 0.4, "material": "veil"},
    {"type": "sphere", "center": [0, 3, 0], "radius": 0.5, "material": "light"}
  ]
}"#;

#[test]
fn scattering_agrees_for_every_material() {
    let Some(d) = device() else { return };
    let c = checks(&d);
    let mut seen = Vec::new();
    let pbr_scene = Scene::from_json_str(PBR_SCENE).expect("pbr scene");
    let jobs = [
        job("cornell-glass"),
        job("smallpt"),
        RenderJob::new(&pbr_scene, 16, 16, &Quality::default()),
    ];
    for job in &jobs {
        let packed = pack(job);
        let tables: &[f32] = &packed.ggx;
        for (index, m) in job.world.materials.iter().enumerate() {
            let kind = match m.bsdf {
                Bsdf::Diffuse => "diffuse".to_owned(),
                Bsdf::Mirror => "mirror".to_owned(),
                Bsdf::Glass { schlick: false, .. } => "glass (exact Fresnel)".to_owned(),
                Bsdf::Glass { schlick: true, .. } => "glass (Schlick)".to_owned(),
                Bsdf::Pbr(p) => format!("pbr {p:?}"),
            };
            if seen.contains(&kind) {
                continue;
            }
            seen.push(kind.clone());
            let pbr = matches!(m.bsdf, Bsdf::Pbr(_));
            let n = 10_000u64;
            let dirs: Vec<(Vec3A, Vec3A)> = (0..n).map(|i| (unit(i, 30), unit(i, 40))).collect();
            let input: Vec<[f32; 4]> = dirs
                .iter()
                .flat_map(|(d, n)| [d.extend(0.0).to_array(), n.extend(0.0).to_array()])
                .collect();
            let out: Vec<f32> = c
                .run(
                    "check_scatter",
                    n as usize,
                    8,
                    &[
                        CheckArg::Buffer(bytemuck::cast_slice(&input)),
                        CheckArg::Buffer(bytemuck::cast_slice(&packed.materials)),
                        CheckArg::U32(index as u32),
                        CheckArg::Buffer(bytemuck::cast_slice(tables)),
                    ],
                )
                .expect("run");
            let mut decisions = 0;
            let mut loose = 0;
            let mut loose_dirs = 0;
            for (i, (dir, normal)) in dirs.iter().enumerate() {
                let entering = dir.dot(*normal) < 0.0;
                let nl = if entering { *normal } else { -*normal };
                let mut s = Sampler::new(0, i as u64, 0);
                let cpu = scatter(m, *dir, entering, nl, &mut s);
                let r = &out[8 * i..8 * i + 8];
                let device_dir = Vec3A::new(r[0], r[1], r[2]);
                let device_weight = Vec3A::new(r[3], r[4], r[5]);
                if pbr {
                    // Table lookups, normalisations and dot products in
                    // another order: a few ulps, amplified where a
                    // direction grazes the surface (its cosine) or a narrow
                    // lobe's D is steep.
                    let gap = (device_weight - cpu.weight).abs().max_element()
                        / cpu.weight.max_element().max(1e-2);
                    assert!(
                        gap <= 1e-2,
                        "{kind}: item {i}: weight {device_weight} vs {}",
                        cpu.weight
                    );
                    // (Measured on PoCL: 5 of 40,000 above 1e-4, all
                    // leaving within 0.01 of the horizon.)
                    loose += usize::from(gap > 1e-4);
                } else {
                    assert_eq!(
                        device_weight.to_array(),
                        cpu.weight.to_array(),
                        "{kind}: item {i}: weight"
                    );
                }
                assert_eq!(r[6] != 0.0, cpu.specular, "{kind}: item {i}: specular");
                let gap = (device_dir - cpu.dir).abs().max_element();
                // A narrow lobe's visible normal near the edge of its cap
                // cancels digits (z + v.z): a few ulps in, 1e-5 out
                // (measured on PoCL: 1 of 10,000 under a coat of alpha 0.01).
                if pbr && gap > 1e-5 && gap <= 1e-4 {
                    loose_dirs += 1;
                    continue;
                }
                if gap > if pbr { 1e-4 } else { 1e-6 } {
                    // A reflect/refract choice on a Fresnel value within an
                    // ulp of the random number may go the other way.
                    decisions += 1;
                    assert!(
                        matches!(m.bsdf, Bsdf::Glass { .. })
                            || matches!(m.bsdf, Bsdf::Pbr(p) if p.transmission > 0.0),
                        "{kind}: item {i}: {device_dir} vs {}",
                        cpu.dir
                    );
                }
            }
            assert!(
                decisions <= 1,
                "{kind}: {decisions} of {n} directions differ"
            );
            assert!(
                loose <= 20,
                "{kind}: {loose} of {n} weights differ by more than 1e-4"
            );
            assert!(
                loose_dirs <= 3,
                "{kind}: {loose_dirs} of {n} directions differ by 1e-5 to 1e-4"
            );
        }
    }
    assert_eq!(seen.len(), 16, "every material kind was checked: {seen:?}");
}

#[test]
fn shared_constants_are_written_once_in_rust() {
    use pathstream::render::backend::opencl::{shared_defines, SHARED_CONSTANTS, SOURCES};
    let source = SOURCES.concat();
    for (name, value) in SHARED_CONSTANTS {
        assert!(
            !source.contains(&format!("#define {name}")),
            "kernels/ defines {name} again"
        );
        assert!(
            shared_defines().contains(&format!("-D {name}={value}u")),
            "{name} is not passed to the build"
        );
    }
}
