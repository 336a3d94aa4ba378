//! Quick mesh measurements: `cargo run --release --example mesh_rays -- 1000000 [trace]`.
//! With `trace`, only traces the camera and bounce rays (for profiling).
use pathstream::bench::meshes;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    if std::env::args().nth(2).as_deref() == Some("trace") {
        let set = meshes::ray_set(n);
        for _ in 0..3 {
            let c = meshes::rays_per_sec(&set.world, &set.camera, 3);
            let b = meshes::rays_per_sec(&set.world, &set.bounce, 3);
            println!("camera {:.2} M/s, bounce {:.2} M/s", c / 1e6, b / 1e6);
        }
        return;
    }
    let row = meshes::measure(n, 2.0, None).expect("measure");
    println!("{row:?}");
}
