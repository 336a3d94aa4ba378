//! Quick mesh measurements: `cargo run --release --example mesh_rays -- 1000000`.
fn main() {
    let n: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(1_000_000);
    let row = pathstream::bench::meshes::measure(n, 2.0).expect("measure");
    println!("{row:?}");
}
