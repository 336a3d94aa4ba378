//! The CPU backend with and without Embree (loaded at run time, as the
//! service loads it), on the same worlds: rays per second through
//! `World::intersect` and paths per second of whole renders. What
//! `world::EMBREE_MIN_TRIANGLES` is chosen from (docs/BENCHMARKS.md,
//! "Embree as the CPU's tracer").
//!
//! ```text
//! apt-get install -y libembree3-3        # Debian 12: Embree 3.13.5
//! cargo run --release -p pathstream --example embree_rays -- \
//!     [TRIANGLES...] [--rounds N] [--seconds S]
//! ```
//!
//! For each size (default 10k, 100k, 1M triangles) `bench::meshes` makes
//! the bumpy sphere under a sky, 512x512 camera rays and one diffuse bounce
//! per camera hit; then `cornell-mesh` (41k triangles, merged).
//! Each round measures own BVH and Embree one after the other (rays: one
//! pass each; paths: `--seconds` of rendering each, 256x256, depth 4), so
//! that load from elsewhere hits both alike; the table gives the median
//! and the range over `--rounds` (default 5). Paths through Embree go in
//! lanes, their rays in Embree's packets (`PathLoop::Auto`), and for
//! comparison in pairs, each ray alone; the own BVH's in pairs.

use pathstream::bench::meshes::{ray_set, rays_per_sec};
use pathstream::render::backend::{CpuBackend, EmbreeUse, PathLoop};
use pathstream::render::{progressive, Backend, Film, Quality, RenderJob, Scene};

fn median_range(v: &mut [f64]) -> String {
    v.sort_by(f64::total_cmp);
    format!("{:.2} ({:.2}-{:.2})", v[v.len() / 2], v[0], v[v.len() - 1])
}

/// Paths per second of `seconds` of rendering `scene` with `embree`,
/// advanced as `loop_` says.
fn paths(scene: &Scene, (embree, loop_): (EmbreeUse, PathLoop), seconds: f64) -> f64 {
    let quality = Quality {
        max_depth: 4,
        rr_depth: 5,
        time_ms: Some((seconds * 1000.0) as u64),
        ..Quality::default()
    };
    let job = RenderJob::new(scene, 256, 256, &quality);
    let cpu = CpuBackend::default().with_embree(embree).with_paths(loop_);
    let mut backend = Backend::Cpu(cpu);
    let mut film = Film::new(256, 256);
    let done = progressive::render(&job, &mut backend, &mut film, &quality, |_| {})
        .expect("the CPU renders");
    assert_eq!(
        job.world.traced_by_embree(),
        embree == EmbreeUse::AllMeshes,
        "Embree as asked"
    );
    done.samples_per_sec / 1e6
}

fn main() {
    let mut sizes = Vec::new();
    let (mut rounds, mut seconds) = (5usize, 2.0f64);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().and_then(|v| v.parse::<f64>().ok());
        match a.as_str() {
            "--rounds" => rounds = value().expect("--rounds N") as usize,
            "--seconds" => seconds = value().expect("--seconds S"),
            n => sizes.push(n.parse().expect("a triangle count")),
        }
    }
    if sizes.is_empty() {
        sizes = vec![10_000, 100_000, 1_000_000];
    }
    if let Err(e) = pathstream::render::embree::embree() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
    println!("| scene | camera M rays/s: own | Embree | bounce M rays/s: own | Embree | M paths/s: own | Embree, lanes | Embree, pairs |");
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    let own_paths = (EmbreeUse::Never, PathLoop::Pairs);
    let lanes = (EmbreeUse::AllMeshes, PathLoop::Auto);
    let pairs = (EmbreeUse::AllMeshes, PathLoop::Pairs);
    for n in sizes {
        let set = ray_set(n);
        let own = set.world.clone();
        let embree = set.world.clone();
        assert!(embree.use_embree(0), "Embree takes the mesh");
        let mut m: [Vec<f64>; 7] = Default::default();
        for _ in 0..rounds {
            m[0].push(rays_per_sec(&own, &set.camera, 1) / 1e6);
            m[1].push(rays_per_sec(&embree, &set.camera, 1) / 1e6);
            m[2].push(rays_per_sec(&own, &set.bounce, 1) / 1e6);
            m[3].push(rays_per_sec(&embree, &set.bounce, 1) / 1e6);
            m[4].push(paths(&set.scene, own_paths, seconds));
            m[5].push(paths(&set.scene, lanes, seconds));
            m[6].push(paths(&set.scene, pairs, seconds));
        }
        let cells: Vec<String> = m.iter_mut().map(|v| median_range(v)).collect();
        let triangles = set.scene.imports[0].instances[0].mesh.triangles.len();
        println!(
            "| bumpy sphere, {triangles} triangles | {} |",
            cells.join(" | ")
        );
    }
    let scene = pathstream::bench::scenes::cornell_mesh().expect("cornell-mesh");
    let mut m: [Vec<f64>; 3] = Default::default();
    for _ in 0..rounds {
        m[0].push(paths(&scene, own_paths, seconds));
        m[1].push(paths(&scene, lanes, seconds));
        m[2].push(paths(&scene, pairs, seconds));
    }
    let cells: Vec<String> = m.iter_mut().map(|v| median_range(v)).collect();
    println!("| cornell-mesh | | | | | {} |", cells.join(" | "));
}
