//! The 2016 thesis's measured throughput (../shared/thesis.md, machine 2:
//! AMD FX-6300 CPU, NVIDIA GTX 970 GPU; max depth 6, NEE on), to print next
//! to ours. Figures are samples per pixel per second.

/// Thesis figures for one scene and size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThesisFigure {
    /// OpenMP build on the FX-6300.
    pub cpu_spp_per_sec: f64,
    /// OpenCL build on the GTX 970.
    pub gpu_spp_per_sec: f64,
}

/// The thesis's figure for `scene` at `width` x `height`, where it measured
/// one. Its 512x512 row names no scene; it stands for both Cornell scenes.
/// Its CPU 512x512 figure is printed as 13.82 samples/s, a typo for the
/// 1.39 that its 720 ms per pass gives.
pub fn figure(scene: &str, width: u32, height: u32) -> Option<ThesisFigure> {
    let f = |cpu, gpu| {
        Some(ThesisFigure {
            cpu_spp_per_sec: cpu,
            gpu_spp_per_sec: gpu,
        })
    };
    match (scene, width, height) {
        ("cornell" | "cornell-glass" | "cornell-quads", 512, 512) => f(1000.0 / 720.0, 60.84),
        ("cornell", 1920, 1080) => f(0.19, 12.91),
        ("cornell-glass" | "cornell-quads", 1920, 1080) => f(0.20, 12.69),
        _ => None,
    }
}
