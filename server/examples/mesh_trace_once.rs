//! One pass of camera and bounce rays over a mesh, single-threaded, for
//! instruction counts: `valgrind --tool=callgrind target/release/examples/mesh_trace_once 100000`.
use pathstream::bench::meshes;
fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100_000);
    let set = meshes::ray_set(n);
    let c = meshes::rays_per_sec(&set.world, &set.camera, 1);
    let b = meshes::rays_per_sec(&set.world, &set.bounce, 1);
    println!(
        "{} camera rays {:.2} M/s, {} bounce rays {:.2} M/s",
        set.camera.len(),
        c / 1e6,
        set.bounce.len(),
        b / 1e6
    );
}
