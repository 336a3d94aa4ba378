//! `pathstream bench`: what each quality setting buys, in numbers.
//!
//! - `measure`: timed renders (throughput; error-against-time traces)
//! - `fit`: the error model `err^2 = b^2 + c^2/t`, time to an error level,
//!   calibration of the film's error estimate
//! - `settings`: the measured quality settings; `thesis`: the 2016 figures
//! - `cache`: reference images, rendered once
//! - `report`: Markdown tables and CSV; `plot`: PNG plots
//! - `run`: the order of work
//!
//! [`run`] measures what a [`Config`] asks for and returns [`Results`]; it
//! draws nothing itself and tells an [`Observer`] what it is doing.

pub mod adaptive;
pub mod cache;
pub mod cells;
pub mod compare;
pub mod cornell_box;
pub mod devices;
pub mod fit;
pub mod measure;
pub mod meshes;
pub mod mis;
pub mod plot;
pub mod report;
mod run;
pub mod samplers;
pub mod scenes;
pub mod settings;
pub mod sky;
pub mod textured;
pub mod thesis;

pub use run::run;

use crate::render::{BackendChoice, BackendError};
use cache::ReferenceInfo;
use fit::{Calibration, Fit, TracePoint};
use measure::Throughput;
use settings::Setting;
use std::path::PathBuf;

/// Which parts to measure.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sections {
    pub throughput: bool,
    pub trade: bool,
    pub calibration: bool,
    pub specialisation: bool,
    /// BVH build, rays/s and paths/s on generated meshes.
    pub meshes: bool,
    /// Uniform vs adaptive sampling: time to 5%, 2%, 1% on every scene.
    pub adaptive: bool,
    /// Random numbers vs Sobol points: time to 5%, 2%, 1% on every scene.
    pub samplers: bool,
    /// BSDF sampling alone vs MIS: time to 5%, 2%, 1% on glossy scenes.
    pub mis: bool,
    /// Power-proportional light selection vs the sky probe: time to 5%,
    /// 2%, 1% on rooms under a sky.
    pub sky: bool,
    /// Every backend alone, then all at once on one render.
    pub devices: bool,
}

impl Sections {
    pub const ALL: Sections = Sections {
        throughput: true,
        trade: true,
        calibration: true,
        specialisation: true,
        meshes: true,
        adaptive: true,
        samplers: true,
        mis: true,
        sky: true,
        devices: true,
    };
}

/// What to measure and for how long.
#[derive(Clone, Debug)]
pub struct Config {
    pub backends: Vec<BackendChoice>,
    /// Leave out the OpenCL backend (with a note) when it cannot start,
    /// instead of failing: for the default backend list.
    pub optional_opencl: bool,
    pub sections: Sections,
    pub throughput_scenes: Vec<String>,
    pub throughput_sizes: Vec<(u32, u32)>,
    pub throughput_seconds: f64,
    pub trade_scenes: Vec<String>,
    pub trade_size: (u32, u32),
    /// Rendering time per setting.
    pub trade_seconds: f64,
    /// Scenes of the adaptive section (at the trade size and time).
    pub adaptive_scenes: Vec<String>,
    /// Scenes of the samplers section (at the trade size and time).
    pub sampler_scenes: Vec<String>,
    /// Scenes of the MIS section (at the trade size and time).
    pub mis_scenes: Vec<String>,
    /// Scenes of the sky section (at the trade size and time).
    pub sky_scenes: Vec<String>,
    /// Seeds of the paired sections (adaptive, samplers, mis, sky): each pair of
    /// curves is rendered with every one (a single curve's time to 1%
    /// varies by 10-15%).
    pub seeds: u64,
    /// References are rendered until their error estimate is this low...
    pub reference_error: f64,
    /// ...or for this long.
    pub reference_seconds: f64,
    pub cache_dir: PathBuf,
    /// Triangle counts of the mesh section's meshes.
    pub mesh_sizes: Vec<usize>,
    /// Rendering seconds of each mesh's paths/s measurement.
    pub mesh_seconds: f64,
}

impl Config {
    /// The full benchmark: minutes on a GPU, the better part of an hour on
    /// two CPU cores the first time (references are cached).
    pub fn full() -> Self {
        Self {
            backends: vec![BackendChoice::Cpu, BackendChoice::OpenCl { device: None }],
            optional_opencl: true,
            sections: Sections::ALL,
            throughput_scenes: [
                "cornell",
                "cornell-glass",
                "cornell-quads",
                "smallpt",
                "furnace",
                scenes::CORNELL_MESH,
                scenes::CORNELL_MESH_PBR,
                scenes::CORNELL_MESH_FROSTED,
                scenes::CORNELL_MESH_COATED,
                scenes::CORNELL_MESH_TEXTURED,
            ]
            .map(String::from)
            .to_vec(),
            throughput_sizes: vec![(512, 512), (1920, 1080)],
            throughput_seconds: 3.0,
            trade_scenes: ["cornell", "cornell-glass", "smallpt"]
                .map(String::from)
                .to_vec(),
            adaptive_scenes: [
                "cornell",
                "cornell-glass",
                "cornell-quads",
                "smallpt",
                "furnace",
                scenes::GLASS_MESH,
            ]
            .map(String::from)
            .to_vec(),
            sampler_scenes: [
                "cornell",
                "cornell-glass",
                "cornell-quads",
                "smallpt",
                "furnace",
                scenes::GLASS_MESH,
                scenes::CORNELL_MESH,
            ]
            .map(String::from)
            .to_vec(),
            mis_scenes: [
                scenes::GLOSSY_PLANE,
                scenes::CORNELL_MESH_PBR,
                scenes::SUNSET_BALLS,
            ]
            .map(String::from)
            .to_vec(),
            sky_scenes: [scenes::SKY_ROOM, scenes::SKY_WINDOW]
                .map(String::from)
                .to_vec(),
            seeds: 3,
            trade_size: (64, 64),
            trade_seconds: 10.0,
            reference_error: 0.0025,
            reference_seconds: 1800.0,
            cache_dir: cache::default_dir(),
            mesh_sizes: vec![10_000, 100_000, 1_000_000, 4_000_000],
            mesh_seconds: 3.0,
        }
    }

    /// A version that runs in seconds: small images, short runs, noisy
    /// references. For tests and for trying the command out.
    pub fn quick() -> Self {
        Self {
            throughput_scenes: vec!["cornell".into(), "smallpt".into()],
            throughput_sizes: vec![(64, 64), (192, 108)],
            throughput_seconds: 0.1,
            trade_scenes: vec!["cornell".into()],
            adaptive_scenes: vec!["cornell".into()],
            sampler_scenes: vec!["cornell".into()],
            mis_scenes: vec![scenes::GLOSSY_PLANE.into()],
            sky_scenes: vec![scenes::SKY_ROOM.into()],
            seeds: 1,
            trade_size: (16, 16),
            trade_seconds: 0.15,
            reference_error: 0.03,
            reference_seconds: 5.0,
            mesh_sizes: vec![2_000, 20_000],
            mesh_seconds: 0.1,
            ..Self::full()
        }
    }
}

/// Told what the benchmark is doing (progress bars live in the CLI).
pub trait Observer {
    /// The number of steps to come.
    fn begin(&mut self, steps: u64);
    /// A step starts.
    fn step(&mut self, what: &str);
    /// News within a long step (a reference's error so far).
    fn detail(&mut self, what: &str);
    /// Something the reader should know (a backend left out).
    fn note(&mut self, what: &str);
}

/// One throughput measurement.
#[derive(Clone, Debug, PartialEq)]
pub struct ThroughputRow {
    pub backend: String,
    pub device: String,
    pub scene: String,
    pub size: (u32, u32),
    pub result: Throughput,
}

/// One setting's error against time on one scene and backend.
#[derive(Clone, Debug, PartialEq)]
pub struct TradeCurve {
    pub backend: String,
    pub scene: String,
    pub setting: Setting,
    /// The renders' seed.
    pub seed: u64,
    pub points: Vec<TracePoint>,
    pub fit: Option<Fit>,
}

impl TradeCurve {
    pub fn paths_per_sec(&self, size: (u32, u32)) -> f64 {
        self.points.last().map_or(0.0, |p| {
            p.spp as f64 * f64::from(size.0) * f64::from(size.1) / p.seconds.max(1e-12)
        })
    }
}

/// How well the film's error estimate tracks the true error.
#[derive(Clone, Debug, PartialEq)]
pub struct CalibrationRow {
    pub backend: String,
    pub scene: String,
    pub calibration: Option<Calibration>,
    /// The unbiased render's points (estimate and true error over time).
    pub points: Vec<TracePoint>,
    /// The reference's own error estimate.
    pub reference_error: f64,
}

/// Specialised vs generic OpenCL program on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecialisationRow {
    pub device: String,
    pub scene: String,
    pub size: (u32, u32),
    pub specialised: Throughput,
    pub generic: Throughput,
}

/// Everything measured.
#[derive(Clone, Debug, Default)]
pub struct Results {
    /// Where and when: CPU model, cores, date.
    pub machine: String,
    pub date: String,
    pub renderer_version: String,
    /// Backend name and device, in the order measured.
    pub backends: Vec<(String, String)>,
    pub throughput: Vec<ThroughputRow>,
    pub trade_size: (u32, u32),
    pub references: Vec<(ReferenceInfo, bool)>,
    pub trade: Vec<TradeCurve>,
    pub calibration: Vec<CalibrationRow>,
    /// The adaptive section: per scene, backend and seed, the uniform curve
    /// then the adaptive one.
    pub adaptive: Vec<TradeCurve>,
    /// The samplers section: per scene, backend and seed, the random curve
    /// then the Sobol one.
    pub samplers: Vec<TradeCurve>,
    /// The MIS section: per scene, backend and seed, the BSDF-only curve
    /// then the MIS one.
    pub mis: Vec<TradeCurve>,
    /// The sky section: per scene, backend and seed, the power-picks curve
    /// then the sky probe's.
    pub sky: Vec<TradeCurve>,
    pub specialisation: Vec<SpecialisationRow>,
    pub meshes: Vec<meshes::MeshRow>,
    pub devices: Vec<devices::DevicesRow>,
}

/// A benchmark that could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("{0}")]
    Usage(String),
    #[error(transparent)]
    Backend(#[from] BackendError),
    #[error("reference cache {path}: {source}")]
    Cache {
        path: PathBuf,
        source: std::io::Error,
    },
}
