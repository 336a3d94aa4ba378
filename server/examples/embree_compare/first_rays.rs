//! `--first-rays`: the rays of `cornell-mesh` where Mitsuba's sixteen
//! lanes lead pathstream most (docs/BENCHMARKS.md, "The comparison made
//! even": its first two path rays and its first shadow rays cost 2.2x
//! less), traced as its lanes hold them: sixteen samples of one pixel,
//! one after another, so that each packet of sixteen is one pixel's.
//!
//! Three sets at 128x128, 16 samples a pixel: the camera rays (jittered in
//! the pixel), one cosine bounce from each camera hit, and one shadow ray
//! from each hit towards a point on the lamp. Bounce and shadow rays start
//! where the renderer spawns them, then moved off the surface as Mitsuba
//! moves its rays (`(1 + max|p|) 1500 eps` along the normal), so that
//! Embree, which is told nothing of the triangle a ray leaves, does not
//! meet it again; every tracer gets the same rays. Embree gets one flat
//! scene of every placed triangle (Mitsuba's layout; pathstream's world
//! keeps its instances), built with `RTC_BUILD_QUALITY_HIGH` as Mitsuba
//! builds it, in its default mode and robust (watertight, as pathstream's
//! test is). Each pass traces a whole set on rayon's threads; the tracers
//! take turns pass by pass; the table gives the median of the passes.

use crate::embree::{ffi, Device, EmbreeScene, Query};
use pathstream::bench::meshes::{rays_per_sec, rays_per_sec_with};
use pathstream::render::backend::{nearest_hits, nearest_hits_packets};
use pathstream::render::material::cosine_hemisphere;
use pathstream::render::math::{Affine3A, Vec3A};
use pathstream::render::ray::Ray;
use pathstream::render::sampler::Sampler;
use pathstream::render::world::{Geometry, Hit, Origin, World};
use pathstream::render::{Quality, RenderJob};

const SIZE: u32 = 128;
const SAMPLES: u32 = 16;

/// The three sets of rays, a pixel's sixteen samples after one another.
struct Sets {
    camera: Vec<(Ray, Origin)>,
    bounce: Vec<(Ray, Origin)>,
    shadow: Vec<(Ray, Origin)>,
}

fn sets(job: &RenderJob) -> Sets {
    let world = &job.world;
    // Each sample's own random numbers (the renderer's `random` sampler).
    let (mut camera, mut numbers) = (Vec::new(), Vec::new());
    for y in 0..SIZE {
        for x in 0..SIZE {
            for s in 0..u64::from(SAMPLES) {
                let mut rng = Sampler::new(7, u64::from(y * SIZE + x), s);
                let (dx, dy) = rng.next_2d();
                camera.push((job.camera.ray(x as f32 + dx, y as f32 + dy), Origin::NONE));
                numbers.push(rng);
            }
        }
    }
    let hits = nearest_hits(world, &camera);
    let (mut bounce, mut shadow) = (Vec::new(), Vec::new());
    let emitters = &world.lights.emitters;
    for (((ray, _), hit), rng) in camera.iter().zip(&hits).zip(&mut numbers) {
        let Some(hit) = hit else { continue };
        let s = world.surface(hit, ray);
        let nl = if ray.dir.dot(s.ng) < 0.0 { s.ng } else { -s.ng };
        let ns = if s.ns.dot(nl) < 0.0 { -s.ns } else { s.ns };
        // Leaving the surface along `dir`: the renderer's origin, moved
        // as Mitsuba moves its own.
        let leave = |dir: Vec3A| {
            let mut r = world.spawn(&s, dir);
            let side = if dir.dot(s.ng) > 0.0 { s.ng } else { -s.ng };
            let eps = 1500.0 * f32::EPSILON / 2.0;
            r.origin += side * (1.0 + s.p.abs().max_element()) * eps;
            let from = Origin {
                object: hit.object,
                prim: hit.prim,
                entering: dir.dot(s.ng) < 0.0,
            };
            (r, from)
        };
        let (u1, u2) = rng.next_2d();
        bounce.push(leave(cosine_hemisphere(ns, u1, u2)));
        let pick = (rng.next_f32() * emitters.len() as f32) as usize;
        let (u1, u2) = rng.next_2d();
        let e = &emitters[pick.min(emitters.len() - 1)];
        if let Some((dir, _)) = e.sample_direction(&s.receiver(nl, ns), u1, u2) {
            shadow.push(leave(dir));
        }
    }
    Sets {
        camera,
        bounce,
        shadow,
    }
}

/// Every placed triangle in camera space, as one mesh.
fn flat(world: &World) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    assert!(
        world
            .objects
            .iter()
            .all(|o| matches!(o.geometry, Geometry::Instance(_))),
        "cornell-mesh is meshes only"
    );
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    for inst in &world.instances {
        let base = positions.len() as u32;
        for p in inst.mesh.positions.iter() {
            let q = inst.cam_from_obj.transform_point3a(Vec3A::from(*p));
            positions.push(q.to_array());
        }
        triangles.extend(inst.mesh.triangles.iter().map(|t| t.map(|v| v + base)));
    }
    (positions, triangles)
}

/// Rays both tracers hit at distances more than 1e-4 apart (relative), and
/// rays one hits and the other misses (the table gives the larger of the
/// two packet queries' counts).
fn disagree(ours: &[Option<Hit>], theirs: &[Option<Hit>]) -> (usize, usize) {
    let mut far = 0;
    let mut one = 0;
    for (a, b) in ours.iter().zip(theirs) {
        match (a, b) {
            (Some(a), Some(b)) if (a.t - b.t).abs() > 1e-4 * a.t.max(1.0) => far += 1,
            (Some(_), None) | (None, Some(_)) => one += 1,
            _ => {}
        }
    }
    (far, one)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

pub fn run(device: &Device, repeats: u32) {
    let scene = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    let job = RenderJob::new(&scene, SIZE, SIZE, &Quality::default());
    let world = &job.world;
    let sets = sets(&job);
    let (positions, triangles) = flat(world);
    let id = Affine3A::IDENTITY;
    let build = |flags| {
        EmbreeScene::build(
            device,
            &positions,
            &triangles,
            flags,
            ffi::RTC_BUILD_QUALITY_HIGH,
        )
    };
    let (fast, robust) = (
        build(ffi::RTC_SCENE_FLAG_NONE),
        build(ffi::RTC_SCENE_FLAG_ROBUST),
    );
    println!(
        "cornell-mesh, {} placed triangles; {SIZE}x{SIZE}, {SAMPLES} samples a pixel, median of {repeats} passes, M rays/s\n",
        triangles.len()
    );
    println!("| rays | count | own BVH | own packets of 16 | Embree, single | packets of 16 | coherent packets | robust Embree, single | robust packets | best Embree / own | distance differs / hit by one only |");
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    for (name, rays) in [
        ("camera", &sets.camera),
        ("first bounce", &sets.bounce),
        ("first shadow", &sets.shadow),
    ] {
        // Hits as the own BVH finds them, against each packet query's.
        let ours = nearest_hits(world, rays);
        // The own packets (camera rays; the others leave a surface and go
        // one by one) give the own single rays' hits, bit for bit.
        assert!(
            nearest_hits_packets(world, rays) == ours,
            "{name}: own packets differ"
        );
        let (far, one) = [false, true]
            .map(|coherent| disagree(&ours, &fast.hits16(&id, rays, coherent)))
            .into_iter()
            .fold((0, 0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
        let mut m: [Vec<f64>; 7] = Default::default();
        for _ in 0..repeats.max(1) {
            m[0].push(rays_per_sec(world, rays, 1));
            m[1].push(rays_per_sec_with(world, rays, 1, nearest_hits_packets));
            m[2].push(fast.rays_per_sec(&id, rays, Query::Single));
            m[3].push(fast.rays_per_sec(&id, rays, Query::Packets));
            m[4].push(fast.rays_per_sec(&id, rays, Query::Coherent));
            m[5].push(robust.rays_per_sec(&id, rays, Query::Single));
            m[6].push(robust.rays_per_sec(&id, rays, Query::Packets));
        }
        let v: Vec<f64> = m.iter_mut().map(|x| median(x) / 1e6).collect();
        println!(
            "| {name} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {far} / {one} |",
            rays.len(),
            v[0],
            v[1],
            v[2],
            v[3],
            v[4],
            v[5],
            v[6],
            v[2..].iter().fold(0.0f64, |a, &b| a.max(b)) / v[0],
        );
    }
}
