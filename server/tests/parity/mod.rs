//! Helpers of the routine-parity tests: counters turned into uniform
//! numbers and directions, rays as check-kernel input, distances in ulps,
//! the check program.
#![allow(dead_code)]

use pathstream::render::backend::opencl::{pack, CheckArg, Checks, KernelParams, OpenClBackend};
use pathstream::render::math::{sincos_turns, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::{mix64, Sampler, SamplerKind};
use pathstream::render::RenderJob;

/// Distance in units in the last place (0 for equal values, infinities
/// included; u64::MAX when only one is NaN or infinite).
pub fn ulps(a: f32, b: f32) -> u64 {
    if a == b {
        return 0;
    }
    if !(a.is_finite() && b.is_finite()) {
        return u64::MAX;
    }
    let key = |x: f32| {
        let i = i64::from(x.to_bits() as i32);
        if i < 0 {
            i64::from(i32::MIN) - i
        } else {
            i
        }
    };
    key(a).abs_diff(key(b))
}

/// Uniform numbers in [0, 1) from a counter.
pub fn uniform(i: u64, salt: u64) -> f32 {
    (mix64(i ^ mix64(salt)) >> 40) as f32 / 16_777_216.0
}

pub fn unit(i: u64, salt: u64) -> Vec3A {
    let z = 1.0 - 2.0 * uniform(i, salt);
    let (s, c) = sincos_turns(uniform(i, salt + 1));
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3A::new(r * c, r * s, z)
}

/// The check program; `PARITY_OPTIONS` adds compiler options, to measure
/// what each floating-point choice changes (docs/OPENCL.md).
pub fn checks(d: &OpenClBackend) -> Checks<'_> {
    let extra = std::env::var("PARITY_OPTIONS").unwrap_or_default();
    d.checks(&extra).expect("the check program builds")
}

/// Rays as check kernels read them: origin, then direction, as float4s.
pub fn ray_input(rays: &[Ray]) -> Vec<[f32; 4]> {
    rays.iter()
        .flat_map(|r| {
            [
                r.origin.extend(0.0).to_array(),
                r.dir.extend(0.0).to_array(),
            ]
        })
        .collect()
}

/// `n` rays from points within a cube of side `size` about `centre`, in
/// every direction.
pub fn rays_around(centre: Vec3A, size: f32, n: u64) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let jitter = Vec3A::new(
                uniform(i, 60) - 0.5,
                uniform(i, 61) - 0.5,
                uniform(i, 62) - 0.5,
            );
            Ray::new(centre + jitter * size, unit(i, 63))
        })
        .collect()
}

/// Asserts that the kernel's `camera_ray` gives `job`'s camera rays (lens
/// numbers drawn by either sampler) within 4 ulps, or 1e-6 where a
/// component is a difference near 0, at 20,000 raster points of a 64 x 48
/// image. The pinhole's direction already differs by an ulp now and then
/// (PoCL; the image tests are statistical), so ulps, not bits.
pub fn assert_camera_rays_agree(d: &OpenClBackend, job: &RenderJob, what: &str) {
    let packed = pack(job);
    let n = 20_000u64;
    let xy: Vec<f32> = (0..n)
        .flat_map(|i| [uniform(i, 1) * 64.0, uniform(i, 2) * 48.0])
        .collect();
    let input: Vec<u64> = (0..n)
        .flat_map(|i| [i % 2, mix64(i) % 7, mix64(i + n) % 3072, i / 2])
        .collect();
    let out: Vec<f32> = checks(d)
        .run(
            "check_camera_ray",
            n as usize,
            6,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&xy)),
                CheckArg::Buffer(bytemuck::cast_slice(&input)),
                CheckArg::Buffer(bytemuck::bytes_of::<KernelParams>(&packed.params)),
            ],
        )
        .expect("run");
    for i in 0..n as usize {
        let kind = [SamplerKind::Random, SamplerKind::Sobol][input[4 * i] as usize];
        let mut s = Sampler::of_kind(kind, input[4 * i + 1], input[4 * i + 2], input[4 * i + 3]);
        let _ = s.camera_2d();
        let r = job.camera.lens_ray(xy[2 * i], xy[2 * i + 1], s.lens_2d());
        let cpu = [
            r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z,
        ];
        let dev = &out[6 * i..6 * i + 6];
        // An origin's component near 0 is a difference (lens point plus
        // near_clip along the ray): compared to the operands' scale.
        let close = cpu
            .iter()
            .zip(dev)
            .all(|(a, b)| ulps(*a, *b) <= 4 || (a - b).abs() <= 1e-6);
        assert!(
            close,
            "{what}: ray {i} ({kind:?}): device {dev:?}, CPU {cpu:?}"
        );
    }
}

/// The kernel's `shade_maps` (check_maps) against `maps::shade` on the
/// first material of `job` that has maps, at `n` random coordinates,
/// normals and tangents: every output bit for bit (albedo, metallic,
/// alpha, roughness, f0, the turned normal, emission, transmission, the
/// coat's weight, alpha and roughness, the dielectric's F0 and F90).
pub fn assert_maps_agree(d: &OpenClBackend, job: &RenderJob, n: u64) {
    use pathstream::render::maps::{shade, TexCoords};
    use pathstream::render::material::Bsdf;
    const OUT: usize = 24;
    let w = &job.world;
    let which = (w.materials.iter())
        .position(|m| m.maps != pathstream::render::material::NO_MAPS)
        .expect("a material with maps") as u32;
    let packed = pack(job);
    let mut input = Vec::new();
    let mut cpu = Vec::new();
    for i in 0..n {
        let uv = [0, 1, 2, 3].map(|k| uniform(i, 10 + k) * 5.0 - 2.0);
        let ns = unit(i, 20);
        let t = unit(i, 30) * 2.0;
        let sign = if i % 3 == 0 { -1.0 } else { 1.0 };
        input.extend([uv, ns.extend(0.0).to_array(), t.extend(sign).to_array()]);
        let tc = TexCoords {
            uv: [[uv[0], uv[1]], [uv[2], uv[3]]],
            tangent: t,
            sign,
        };
        let m = &w.materials[which as usize];
        let (mut n_out, mut nc) = (ns, Vec3A::ZERO);
        let out = shade(
            &w.textures,
            &w.maps[m.maps as usize],
            m,
            &tc,
            (&mut n_out, &mut nc),
        );
        let Bsdf::Pbr(p) = out.bsdf else {
            panic!("a pbr material")
        };
        let (a, e, s) = (out.albedo, out.emission, p.spec_f0);
        let values: [f32; OUT] = [
            a.x,
            a.y,
            a.z,
            p.metallic,
            p.alpha,
            p.roughness,
            p.f0,
            n_out.x,
            n_out.y,
            n_out.z,
            e.x,
            e.y,
            e.z,
            p.transmission,
            p.coat,
            p.coat_alpha,
            p.coat_roughness,
            s.x,
            s.y,
            s.z,
            p.spec_f90,
            nc.x,
            nc.y,
            nc.z,
        ];
        cpu.push(values);
    }
    let t = &packed.textures;
    let out: Vec<f32> = checks(d)
        .run(
            "check_maps",
            n as usize,
            OUT,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&input)),
                CheckArg::Buffer(bytemuck::cast_slice(&vec![which; n as usize])),
                CheckArg::Buffer(bytemuck::cast_slice(&packed.materials)),
                CheckArg::Buffer(bytemuck::cast_slice(&t.maps)),
                CheckArg::Buffer(bytemuck::cast_slice(&t.images)),
                CheckArg::Buffer(bytemuck::cast_slice(t.texels())),
                CheckArg::Buffer(bytemuck::cast_slice(&t.srgb)),
            ],
        )
        .expect("run");
    for (i, want) in cpu.iter().enumerate() {
        let got = &out[OUT * i..OUT * i + OUT];
        for (k, (g, c)) in got.iter().zip(want).enumerate() {
            assert_eq!(
                g.to_bits(),
                c.to_bits(),
                "item {i} value {k}: device {g}, CPU {c}"
            );
        }
    }
}
