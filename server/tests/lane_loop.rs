//! The CPU's lane loop (`backend/cpu/lanes.rs`: paths advanced 4, 8 or 16
//! at a time, their rays traced together) against the pair loop. Where the
//! own BVH traces, the lanes send the same rays and shade them the same
//! way: the image is the pair loop's bit for bit, at every width. Through
//! Embree's packets, a shadow ray to a flat or distant emitter becomes an
//! occlusion test (a thousandth short of the emitter's point), and hits
//! differ from the own BVH's by rounding: the image is the same but in a
//! few samples, which are bounded here.

mod common;

use common::films::apart;

use pathstream::bench::scenes::load;
use pathstream::render::backend::{CpuBackend, EmbreeUse, IsaCap, PathLoop};
use pathstream::render::{Film, Quality, RenderJob, Scene};

/// Scenes that cover every material, emitter kind and accelerator: the
/// scan (spheres), meshes (one BVH, textures), an environment map, a sky
/// with a sun, emissive triangles.
const SCENES: [&str; 9] = [
    "cornell",
    "cornell-glass",
    "smallpt",
    "cornell-mesh",
    "cornell-mesh-pbr",
    "cornell-mesh-textured",
    "glossy-plane",
    "sunset-balls",
    "sky-window",
];

fn render(backend: CpuBackend, scene: &Scene, (w, h): (u32, u32), spp: u64) -> Film {
    let job = RenderJob::new(scene, w, h, &Quality::default());
    let mut film = Film::new(w, h);
    let mut backend = backend;
    backend.render(&job, &mut film, spp);
    film
}

#[test]
fn with_the_own_bvh_the_lanes_give_the_pair_loops_image_bit_for_bit() {
    for name in SCENES {
        let scene = load(name).expect("scene");
        let cpu = || CpuBackend::default().with_embree(EmbreeUse::Never);
        let pairs = render(cpu().with_paths(PathLoop::Pairs), &scene, (24, 16), 8);
        // Sixteen lanes (AVX-512 here), eight (AVX2) and four (every CPU).
        for cap in [IsaCap::Widest, IsaCap::Avx2, IsaCap::Portable] {
            let backend = cpu().with_paths(PathLoop::Lanes).isa_cap(cap);
            let lanes = render(backend, &scene, (24, 16), 8);
            assert!(
                lanes.pixels() == pairs.pixels(),
                "{name}: the lane loop ({cap:?}) differs from the pair loop"
            );
        }
    }
}

#[test]
fn through_embree_the_lanes_agree_with_the_pair_loop() {
    if !common::embree() {
        return;
    }
    for name in [
        "cornell-mesh",
        "cornell-mesh-pbr",
        "cornell-mesh-textured",
        "glossy-plane",
    ] {
        let scene = load(name).expect("scene");
        let job = RenderJob::new(&scene, 8, 8, &Quality::default());
        assert!(job.world.use_embree(0), "{name}: Embree traces its meshes");
        let size = (48, 36);
        let pixels = (size.0 * size.1) as usize;
        let pairs = CpuBackend::default()
            .with_embree(EmbreeUse::Never)
            .with_paths(PathLoop::Pairs);
        let reference = render(pairs, &scene, size, 16);
        let embree = || CpuBackend::default().with_embree(EmbreeUse::AllMeshes);
        let lanes = render(embree().with_paths(PathLoop::Lanes), &scene, size, 16);
        let (differ, rel) = apart(&lanes, &reference);
        eprintln!("{name}: {differ} of {pixels} pixels differ, sums {rel:.2e} apart");
        // The same random numbers meet the same surfaces: but for the
        // few samples that rounding sends elsewhere, the same image.
        assert!(
            differ * 10 < pixels && rel < 2e-3,
            "{name}: {differ} of {pixels} pixels differ, sums {rel:.2e} apart"
        );
        // Embree's packets of every width answer alike, bit for bit.
        for cap in [IsaCap::Avx2, IsaCap::Portable] {
            let narrow = render(
                embree().with_paths(PathLoop::Lanes).isa_cap(cap),
                &scene,
                size,
                16,
            );
            assert!(
                narrow.pixels() == lanes.pixels(),
                "{name}: {cap:?} lanes through Embree differ from sixteen"
            );
        }
    }
}

/// The lanes' Embree queries call no filter (no alpha here): a ray spawned
/// off a triangle, grazing it both ways (the directions most likely to
/// meet it again), gets the answers of the single-ray query, which
/// refuses that triangle: the same nearest surface (a self-hit asked
/// again alone), and from the occlusion test "blocked" exactly where that
/// surface lies before the test's distance.
#[test]
fn embrees_packets_answer_as_the_filtered_single_rays() {
    use common::meshes::{grazing, leaving, mixed_scene};
    use pathstream::render::isa::Portable;
    use pathstream::render::ray::Ray;
    use pathstream::render::world::{Hit, Origin, World};
    if !common::embree() {
        return;
    }
    let scene = mixed_scene();
    let world = World::new(&scene, scene.camera.position);
    assert!(world.use_embree(0));
    let mut rays = Vec::new();
    for (hit, surface, dirs) in grazing(&world, 11, 100_000) {
        for dir in dirs {
            rays.push((world.spawn(&surface, dir), leaving(&hit, surface.ng, dir)));
        }
    }
    let (mut differ, mut wrong, mut blocked) = (0, 0, 0);
    for group in rays.chunks_exact(16) {
        let r: [Ray; 16] = std::array::from_fn(|k| group[k].0);
        let from: [Origin; 16] = std::array::from_fn(|k| group[k].1);
        let single: [_; 16] = std::array::from_fn(|k| world.intersect(Portable, &r[k], from[k]));
        let lanes = world
            .intersect_lanes(Portable, &r, &from, &[true; 16])
            .map(Hit::some);
        for (a, b) in single.iter().zip(&lanes) {
            let same = match (a, b) {
                (Some(a), Some(b)) => {
                    (a.object, a.prim) == (b.object, b.prim) && (a.t - b.t).abs() <= 1e-5 * a.t
                }
                (None, None) => true,
                _ => false,
            };
            differ += usize::from(!same);
        }
        // Each lane's test just short of and just beyond its surface.
        for factor in [0.999f32, 1.001] {
            let tmax = single.map(|h| h.map_or(1e30, |h| h.t * factor));
            let lanes = world.occluded_lanes(Portable, (&r, &from, &tmax), &[true; 16]);
            let lanes = lanes.expect("Embree traces the world");
            for k in 0..16 {
                let expect = single[k].is_some_and(|h| h.t < tmax[k]);
                wrong += usize::from(lanes[k] != expect);
                blocked += usize::from(expect);
            }
        }
    }
    eprintln!(
        "{} rays: {differ} nearest hits differ, {wrong} occlusion answers ({blocked} blocked)",
        rays.len()
    );
    assert!(rays.len() > 30_000 && blocked > rays.len() / 2);
    assert_eq!(differ, 0, "packet hits that are not the single rays'");
    assert_eq!(wrong, 0, "occlusion answers that are not the single rays'");
}
