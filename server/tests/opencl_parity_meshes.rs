//! Meshes, emitters and the sky on the device against the CPU: the
//! watertight triangle test and the nearest hit among mesh instances
//! routine by routine (check kernels in `kernels/checks.cl`), then whole
//! images rendered with the same seed on both backends.

mod common;
mod parity;

use common::opencl_device as device;
use parity::{checks, ray_input, rays_around, ulps, uniform, unit};
use pathstream::render::backend::nearest_hits;
use pathstream::render::backend::opencl::{pack, CheckArg, KernelParams, OpenClBackend, Packed};
use pathstream::render::math::Vec3A;
use pathstream::render::ray::Ray;
use pathstream::render::shape::TriRay;
use pathstream::render::world::{AccelChoice, Origin, World};
use pathstream::render::{Quality, RenderJob, Scene};

/// Next-event estimation picks one emitter in proportion to its power from
/// the same random bits on both backends: with the same seed, a scene of
/// 40 lights of different power renders the same image, pixel for pixel,
/// but for the rare path that a last-bit difference sends elsewhere. (A
/// device that aimed at every light, or picked another, would differ in
/// nearly every pixel.)
#[test]
fn the_device_picks_the_emitter_the_cpu_picks() {
    let Some(d) = device() else { return };
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene("cornell")
            .expect("scene")
            .to_json(),
    )
    .expect("json");
    for i in 0..40u64 {
        let c = [
            10.0 + 80.0 * uniform(i, 1),
            5.0 + 70.0 * uniform(i, 2),
            30.0 + 100.0 * uniform(i, 3),
        ];
        let name = format!("lamp{i}");
        let e = 1.0 + 20.0 * f64::from(uniform(i, 4));
        j["materials"][&name] = serde_json::json!({"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [e, e * 0.5, e * 0.25]});
        j["objects"].as_array_mut().expect("objects").push(
            serde_json::json!({"type": "sphere", "center": c, "radius": 0.5 + 2.0 * uniform(i, 5), "material": name}),
        );
    }
    let s = Scene::from_json_value(j).expect("valid");
    let q = Quality {
        seed: 3,
        max_depth: 2,
        ..Quality::default()
    };
    let job = RenderJob::new(&s, 24, 24, &q);
    assert!(
        job.world.lights.emitters.len() > 40,
        "the lamps and the ceiling light emit"
    );
    let (same, all) = same_pixels(d, &s, &q);
    assert!(
        same * 100 >= all * 95,
        "{same} of {all} pixels the same on both backends"
    );
}

/// Renders `s` with the same seed on rayon and on `d`; how many of the
/// pixels agree to 1e-4 (relative; 1e-7 absolute).
fn same_pixels(d: OpenClBackend, s: &Scene, q: &Quality) -> (usize, usize) {
    use pathstream::render::{Backend, BackendChoice, Film};
    let job = RenderJob::new(s, 24, 24, q);
    let mut cpu = Film::new(24, 24);
    Backend::choose(BackendChoice::Cpu)
        .expect("cpu")
        .render(&job, &mut cpu, 4)
        .expect("render");
    let mut gpu = Film::new(24, 24);
    let mut on_device = Backend::OpenCl {
        backend: Box::new(d),
        fallback: false,
    };
    on_device.render(&job, &mut gpu, 4).expect("render");
    let (a, b) = (cpu.mean(), gpu.mean());
    let same = a
        .iter()
        .zip(&b)
        .filter(|(x, y)| {
            x.iter()
                .zip(y.iter())
                .all(|(p, q)| (p - q).abs() <= 1e-4 * p.abs().max(q.abs()).max(1e-3))
        })
        .count();
    (same, a.len())
}

/// A mesh object with inline data: unit-sphere vertices, so that their
/// normals are their positions.
fn ball(levels: u32, material: &str, at: [f64; 3], scale: f64, smooth: bool) -> serde_json::Value {
    let m = pathstream::model::generate::icosphere(levels);
    let mut data = serde_json::json!({"positions": m.positions, "triangles": m.triangles});
    if smooth {
        data["normals"] = serde_json::json!(m.positions);
    }
    serde_json::json!({"type": "mesh", "material": material, "data": data,
                       "transform": {"translate": at, "scale": scale}})
}

/// Meshes on the device are the CPU's, operation for operation: with the
/// same seed, a room with a coarse smooth-shaded ball (shading normals
/// ~10 degrees off the faces'), a mirror ball of 81,920 triangles and an
/// emissive mesh as its light, and a smooth ball and a glowing mesh under
/// a sky, render the same images, pixel for pixel, but for the rare path
/// that a last-bit difference sends elsewhere.
#[test]
fn meshes_render_the_cpus_image_on_the_device() {
    let Some(_) = device() else { return };
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene("cornell")
            .expect("scene")
            .to_json(),
    )
    .expect("json");
    let objects = j["objects"].as_array_mut().expect("objects");
    let lamp = objects
        .iter()
        .position(|o| o["material"] == "lamp")
        .expect("lamp");
    let right = objects
        .iter()
        .position(|o| o["center"] == serde_json::json!([73.0, 16.5, 78.0]))
        .expect("ball");
    objects[right] = ball(2, "white", [73.0, 16.5, 78.0], 16.5, true);
    objects[lamp] = ball(2, "lamp", [50.0, 66.6, 81.6], 7.0, false);
    objects.push(ball(6, "mirror", [30.0, 50.0, 60.0], 10.0, false));
    let room = Scene::from_json_value(j).expect("valid");
    let sky = Scene::from_json_value(serde_json::json!({
        "camera": {"position": [0, 1, 6], "look_at": [0, 0, 0], "vfov_deg": 40},
        "materials": {"grey": {"type": "diffuse", "albedo": [0.6, 0.5, 0.4]},
                      "glow": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [4, 3, 2]}},
        "objects": [ball(2, "grey", [0.0, 0.0, 0.0], 1.0, true), ball(1, "glow", [1.5, 1.5, 0.0], 0.4, false),
                    {"type": "quad", "corner": [-5, -1, -5], "edge_u": [10, 0, 0], "edge_v": [0, 0, 10], "material": "grey"}],
        "environment": [0.3, 0.4, 0.5]
    }))
    .expect("valid");
    for (what, s) in [("room", &room), ("sky", &sky)] {
        let job = RenderJob::new(s, 24, 24, &Quality::default());
        assert!(
            job.world.instances[0].mesh.normals.is_some(),
            "{what}: {:?}",
            s.warnings
        );
        let q = Quality {
            seed: 9,
            max_depth: 3,
            ..Quality::default()
        };
        let (same, all) = same_pixels(device().expect("device"), s, &q);
        eprintln!("{what}: {same} of {all} pixels the same");
        assert!(
            same * 100 >= all * 95,
            "{what}: {same} of {all} pixels the same on both backends"
        );
    }
}

/// The watertight test on 1e5 rays and triangles: random triangles of
/// every size and distance, rays aimed at their vertices and edges (where
/// edge functions come out zero and the f64 fallback decides), and rays
/// between two triangles sharing an edge. The same hits, distances and
/// barycentrics, bit for bit.
#[test]
fn the_watertight_triangle_test_agrees_bit_for_bit() {
    let Some(d) = device() else { return };
    let n = 100_000u64;
    let mut rays = Vec::new();
    let mut tris = Vec::new();
    for i in 0..n {
        let scale = 10f32.powf(-3.0 + 6.0 * uniform(i, 1));
        let at =
            (Vec3A::new(uniform(i, 2), uniform(i, 3), uniform(i, 4)) - 0.5) * 1e3 * uniform(i, 5);
        let v = [unit(i, 6), unit(i, 8), unit(i, 10)].map(|u| at + u * scale);
        // Aim at a vertex, the middle of an edge, or inside.
        let target = match i % 3 {
            0 => v[(i / 3 % 3) as usize],
            1 => (v[0] + v[1]) * 0.5,
            _ => (v[0] + v[1] + v[2]) / 3.0,
        };
        let origin = target - unit(i, 12) * (scale * 10.0 * uniform(i, 14));
        rays.push(Ray::new(origin, (target - origin).normalize()));
        tris.push(v);
    }
    let ray_in = ray_input(&rays);
    let tri_in: Vec<[f32; 4]> = tris
        .iter()
        .flat_map(|t| t.map(|v| v.extend(0.0).to_array()))
        .collect();
    let out: Vec<f32> = checks(&d)
        .run(
            "check_triangle",
            n as usize,
            4,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&ray_in)),
                CheckArg::Buffer(bytemuck::cast_slice(&tri_in)),
            ],
        )
        .expect("run");
    let mut hits = 0;
    for (i, (r, t)) in rays.iter().zip(&tris).enumerate() {
        let cpu = TriRay::new(r.origin, r.dir).intersect(*t, f32::INFINITY);
        let dev = &out[4 * i..4 * i + 4];
        match cpu {
            None => assert_eq!(dev[0], -1.0, "ray {i}: the device hit at {}", dev[0]),
            Some((t, b)) => {
                hits += 1;
                let got = [dev[0], dev[1], dev[2], dev[3]].map(f32::to_bits);
                let want = [t, b[0], b[1], b[2]].map(f32::to_bits);
                assert_eq!(got, want, "ray {i}: device {dev:?}, CPU {t} {b:?}");
            }
        }
    }
    eprintln!("{hits} of {n} rays hit their triangle");
    assert!(
        hits > n / 2,
        "most rays are aimed at their triangle ({hits})"
    );
}

/// The arguments of `check_nearest_meshes` after the item count.
fn mesh_args<'a>(input: &'a [[f32; 4]], p: &'a Packed) -> Vec<CheckArg<'a>> {
    let m = &p.meshes;
    vec![
        CheckArg::Buffer(bytemuck::cast_slice(input)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.objects)),
        CheckArg::Buffer(bytemuck::bytes_of::<KernelParams>(&p.params)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.nodes)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.prims)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.big)),
        CheckArg::Buffer(bytemuck::cast_slice(&m.instances)),
        CheckArg::Buffer(bytemuck::cast_slice(&m.arrays().nodes)),
        CheckArg::Buffer(bytemuck::cast_slice(&m.arrays().tris)),
        CheckArg::Buffer(bytemuck::cast_slice(&m.arrays().normals)),
        CheckArg::Buffer(bytemuck::cast_slice(&m.slots)),
    ]
}

/// The arguments of the emitter checks (`check_light_sample`,
/// `check_emitter_pdf`) after the item count: each item's input, its
/// emitter, and the scene's objects and lights.
fn emitter_args<'a>(input: &'a [[f32; 4]], which: &'a [u32], p: &'a Packed) -> Vec<CheckArg<'a>> {
    vec![
        CheckArg::Buffer(bytemuck::cast_slice(input)),
        CheckArg::Buffer(bytemuck::cast_slice(which)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.objects)),
        CheckArg::Buffer(bytemuck::cast_slice(&p.lights)),
    ]
}

/// The nearest hit among mesh instances (a rotated and scaled 81,920-
/// triangle ball, a 20,480- and an 80-triangle ball, spheres and walls) on 1e5
/// rays from inside the room: the same object, triangle and distance as
/// the CPU's, bit for bit; with every mesh on its own instance, and with
/// the small ones merged (`render::world::merge`: the flat balls become
/// one mesh placed by a translation).
#[test]
fn the_nearest_hit_among_meshes_agrees_on_1e5_rays() {
    let Some(d) = device() else { return };
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene("cornell")
            .expect("scene")
            .to_json(),
    )
    .expect("json");
    let objects = j["objects"].as_array_mut().expect("objects");
    let mut fine = ball(6, "white", [30.0, 40.0, 60.0], 12.0, true);
    fine["transform"]["rotate"] = serde_json::json!({"axis": [1, 2, 3], "deg": 37});
    objects.push(fine);
    objects.push(ball(5, "mirror", [70.0, 50.0, 100.0], 9.0, false));
    objects.push(ball(1, "glass", [50.0, 20.0, 90.0], 8.0, false));
    let s = Scene::from_json_value(j).expect("valid");
    let merged = RenderJob::new(&s, 16, 16, &Quality::default());
    assert_eq!(merged.world.instances.len(), 2);
    let mut unmerged = merged.with_new_id();
    unmerged.world = World::unmerged(&s, s.camera.position, AccelChoice::Auto);
    assert_eq!(unmerged.world.instances.len(), 3);
    nearest_hits_agree(&d, &merged);
    nearest_hits_agree(&d, &unmerged);
}

fn nearest_hits_agree(d: &OpenClBackend, job: &RenderJob) {
    let packed = pack(job);
    let n = 100_000u64;
    let centre = Vec3A::from((job.camera.forward * 200.0).to_array());
    let rays = rays_around(centre, 60.0, n);
    let input = ray_input(&rays);
    let out: Vec<f32> = checks(d)
        .run(
            "check_nearest_meshes",
            n as usize,
            3,
            &mesh_args(&input, &packed),
        )
        .expect("run");
    let cpu = nearest_hits(
        &job.world,
        &rays.iter().map(|r| (*r, Origin::NONE)).collect::<Vec<_>>(),
    );
    let mut on_meshes = 0;
    for (i, h) in cpu.iter().enumerate() {
        let (t, object, prim) = (
            out[3 * i],
            out[3 * i + 1].to_bits(),
            out[3 * i + 2].to_bits(),
        );
        match h {
            None => assert_eq!(
                object,
                u32::MAX,
                "ray {i}: the device hit {object} at {t}, the CPU nothing"
            ),
            Some(h) => {
                assert_eq!(
                    (object, prim, ulps(t, h.t)),
                    (h.object, h.prim, 0),
                    "ray {i}: device {t} object {object} triangle {prim}, CPU {} {} {}",
                    h.t,
                    h.object,
                    h.prim
                );
                on_meshes += usize::from(h.prim != u32::MAX);
            }
        }
    }
    eprintln!("{on_meshes} of {n} rays hit a mesh");
    assert!(on_meshes >= 2000, "the rays meet the meshes ({on_meshes})");
}

/// A scene with every kind of emitter: quads (cornell-quads' light), a
/// sphere, the triangles of a glowing mesh, and the sky.
fn every_emitter() -> Scene {
    let mut j = serde_json::to_value(
        pathstream::resolve::load_scene("cornell-quads")
            .expect("scene")
            .to_json(),
    )
    .expect("json");
    j["materials"]["glow"] =
        serde_json::json!({"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [3, 2, 1]});
    let objects = j["objects"].as_array_mut().expect("objects");
    objects.push(serde_json::json!({"type": "sphere", "center": [30, 60, 70], "radius": 4, "material": "glow"}));
    objects.push(ball(1, "glow", [70.0, 30.0, 90.0], 6.0, false));
    j["environment"] = serde_json::json!([0.1, 0.2, 0.3]);
    Scene::from_json_value(j).expect("valid")
}

/// Light selection and light sampling, routine by routine: the emitter the
/// power table picks from 1e5 random 32-bit numbers (and what each leaves
/// for the point), and the direction and 1/pdf towards every kind of
/// emitter from 1e5 random points, normals and numbers (a quarter of them
/// on the emitter's own object), bit for bit.
#[test]
fn light_picks_and_light_samples_agree_bit_for_bit() {
    use pathstream::render::sampler::mix64;
    use pathstream::render::world::{Surface, NO_OBJECT, NO_PRIM};
    let Some(d) = device() else { return };
    let job = RenderJob::new(&every_emitter(), 16, 16, &Quality::default());
    let lights = &job.world.lights;
    let table = lights.table.as_ref().expect("an alias table");
    assert!(
        lights.emitters.len() > 80,
        "quads, sphere, 80 triangles, the sky"
    );
    let packed = pack(&job);
    let n = 100_000usize;
    let bits: Vec<u32> = (0..n as u64)
        .map(|i| (mix64(i ^ 0xABCD) >> 32) as u32)
        .collect();
    let picks: Vec<u32> = checks(&d)
        .run(
            "check_light_pick",
            n,
            3,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&bits)),
                CheckArg::Buffer(bytemuck::bytes_of::<KernelParams>(&packed.params)),
                CheckArg::Buffer(bytemuck::cast_slice(&packed.lights)),
            ],
        )
        .expect("run");
    for (i, &x) in bits.iter().enumerate() {
        let (j, pmf, u) = table.pick_point(x);
        assert_eq!(
            &picks[3 * i..3 * i + 3],
            &[j as u32, pmf.to_bits(), u.to_bits()],
            "pick {i}"
        );
    }
    let count = lights.emitters.len() as u64;
    let mut input = Vec::new();
    let mut which = Vec::new();
    let mut surfaces = Vec::new();
    for i in 0..n as u64 {
        let k = (i % count) as usize;
        let e = &lights.emitters[k];
        let p = Vec3A::new(uniform(i, 20), uniform(i, 21), uniform(i, 22)) * 120.0 - 60.0;
        let normal = unit(i, 23);
        let on = if i % 4 == 0 { e.object } else { NO_OBJECT };
        let s = Surface {
            p,
            ng: normal,
            ns: normal,
            nc: Vec3A::ZERO,
            smooth: false,
            material: 0,
            object: on,
            prim: if on == NO_OBJECT { NO_PRIM } else { e.prim },
            offset: None,
        };
        input.extend([
            p.extend(f32::from_bits(on)).to_array(),
            normal.extend(0.0).to_array(),
            [uniform(i, 24), uniform(i, 25), 0.0, 0.0],
        ]);
        which.push(k as u32);
        surfaces.push(s);
    }
    let out: Vec<f32> = checks(&d)
        .run(
            "check_light_sample",
            n,
            4,
            &emitter_args(&input, &which, &packed),
        )
        .expect("run");
    let mut sampled = 0;
    for (i, s) in surfaces.iter().enumerate() {
        let e = &lights.emitters[which[i] as usize];
        let (u1, u2) = (input[3 * i + 2][0], input[3 * i + 2][1]);
        let dev = &out[4 * i..4 * i + 4];
        match e.sample_direction(&s.receiver(s.ng, s.ns), u1, u2) {
            None => assert_eq!(dev[3], -1.0, "sample {i}: the device sampled {dev:?}"),
            Some((dir, w)) => {
                sampled += 1;
                let want = [dir.x, dir.y, dir.z, w].map(f32::to_bits);
                let got = [dev[0], dev[1], dev[2], dev[3]].map(f32::to_bits);
                assert_eq!(
                    got, want,
                    "sample {i} ({:?}): device {dev:?}, CPU {dir} {w}",
                    e.shape
                );
            }
        }
    }
    eprintln!("{sampled} of {n} samples gave a direction");
    assert!(sampled > n / 2, "most samples give a direction ({sampled})");
}

/// Multiple importance sampling's routines, bit for bit: each emitter's
/// density of a direction (1e5 random points, normals, directions and
/// points on the emitter, a quarter of them on the emitter's own object),
/// finding an emitter by object and triangle, and the power heuristic.
#[test]
fn mis_densities_and_emitter_lookups_agree_bit_for_bit() {
    use pathstream::render::integrator::mis::power_heuristic;
    use pathstream::render::light::Receiver;
    use pathstream::render::world::{NO_OBJECT, NO_PRIM};
    let Some(d) = device() else { return };
    let job = RenderJob::new(&every_emitter(), 16, 16, &Quality::default());
    let lights = &job.world.lights;
    let packed = pack(&job);
    let n = 100_000usize;
    let count = lights.emitters.len() as u64;
    let (mut input, mut which, mut want) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..n as u64 {
        let k = (i % count) as usize;
        let e = &lights.emitters[k];
        let p = Vec3A::new(uniform(i, 30), uniform(i, 31), uniform(i, 32)) * 120.0 - 60.0;
        let normal = unit(i, 33);
        let on = if i % 4 == 0 { e.object } else { NO_OBJECT };
        let r = Receiver {
            p,
            object: on,
            prim: if on == NO_OBJECT { NO_PRIM } else { e.prim },
            nl: normal,
            ns: normal,
        };
        // Sampled directions where sampling gives one, else any.
        let dir = e
            .sample_direction(&r, uniform(i, 34), uniform(i, 35))
            .map_or(unit(i, 36), |(dir, _)| dir);
        let q = p + dir * (1.0 + 90.0 * uniform(i, 37));
        input.extend([
            p.extend(f32::from_bits(on)).to_array(),
            normal.extend(0.0).to_array(),
            dir.extend(0.0).to_array(),
            q.extend(0.0).to_array(),
        ]);
        which.push(k as u32);
        want.push(e.pdf_direction(&r, dir, q));
    }
    let out: Vec<f32> = checks(&d)
        .run(
            "check_emitter_pdf",
            n,
            1,
            &emitter_args(&input, &which, &packed),
        )
        .expect("run");
    let positive = want.iter().filter(|p| **p > 0.0).count();
    for (i, (&got, &cpu)) in out.iter().zip(&want).enumerate() {
        let e = &lights.emitters[which[i] as usize];
        assert_eq!(
            got.to_bits(),
            cpu.to_bits(),
            "density {i} ({:?}): device {got}, CPU {cpu}",
            e.shape
        );
    }
    assert!(
        positive > n / 2,
        "most directions have a density ({positive})"
    );

    // Every emitter's key, and keys next to them that are none.
    let mut keys = Vec::new();
    for e in &lights.emitters {
        keys.extend([e.object, e.prim, e.object, e.prim.wrapping_add(1)]);
        keys.extend([e.object.wrapping_add(1), e.prim, e.object, 0]);
    }
    let values = [0.0, 1e-30, 0.5, 1.0, 3.0, 1e20, f32::INFINITY];
    let ab: Vec<f32> = (0..keys.len() / 2)
        .flat_map(|i| [values[i % 7], values[(i / 7) % 7]])
        .collect();
    let m = keys.len() / 2;
    let out: Vec<u32> = checks(&d)
        .run(
            "check_mis_routines",
            m,
            3,
            &[
                CheckArg::Buffer(bytemuck::cast_slice(&keys)),
                CheckArg::Buffer(bytemuck::cast_slice(&ab)),
                CheckArg::Buffer(bytemuck::bytes_of::<KernelParams>(&packed.params)),
                CheckArg::Buffer(bytemuck::cast_slice(&packed.lights)),
            ],
        )
        .expect("run");
    let env = lights.environment().map_or(u32::MAX, |i| i as u32);
    for i in 0..m {
        let index = lights
            .index_of(keys[2 * i], keys[2 * i + 1])
            .map_or(u32::MAX, |j| j as u32);
        let w = power_heuristic(ab[2 * i], ab[2 * i + 1]);
        assert_eq!(
            (out[3 * i], out[3 * i + 1], out[3 * i + 2]),
            (index, env, w.to_bits()),
            "key ({}, {}), heuristic of {} and {}",
            keys[2 * i],
            keys[2 * i + 1],
            ab[2 * i],
            ab[2 * i + 1]
        );
    }
    assert_ne!(env, u32::MAX, "the sky is an emitter");
}
