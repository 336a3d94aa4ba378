//! `pathstream bench`: what each quality setting buys, in numbers.
//!
//! - `measure`: timed renders (throughput; error-against-time traces)
//! - `fit`: the error model `err^2 = b^2 + c^2/t`, time to an error level,
//!   calibration of the film's error estimate
//! - `settings`: the measured quality settings; `thesis`: the 2016 figures
//! - `cache`: reference images, rendered once
//! - `report`: Markdown tables and CSV; `plot`: PNG plots
//!
//! [`run`] measures what a [`Config`] asks for and returns [`Results`]; it
//! draws nothing itself and tells an [`Observer`] what it is doing.

pub mod cache;
pub mod fit;
pub mod measure;
pub mod plot;
pub mod report;
pub mod settings;
pub mod thesis;

use crate::render::progressive::MIN_SPP_FOR_TARGET_ERROR;
use crate::render::{Backend, BackendChoice, BackendError, Quality, RenderJob, Scene};
use cache::{Reference, ReferenceInfo, RENDERER_VERSION};
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
}

impl Sections {
    pub const ALL: Sections = Sections {
        throughput: true,
        trade: true,
        calibration: true,
        specialisation: true,
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
    /// References are rendered until their error estimate is this low...
    pub reference_error: f64,
    /// ...or for this long.
    pub reference_seconds: f64,
    pub cache_dir: PathBuf,
}

impl Config {
    /// The full benchmark: minutes on a GPU, the better part of an hour on
    /// two CPU cores the first time (references are cached).
    pub fn full() -> Self {
        Self {
            backends: vec![BackendChoice::Cpu, BackendChoice::OpenCl { device: None }],
            optional_opencl: true,
            sections: Sections::ALL,
            throughput_scenes: ["cornell", "cornell-glass", "cornell-quads", "smallpt"].map(String::from).to_vec(),
            throughput_sizes: vec![(512, 512), (1920, 1080)],
            throughput_seconds: 3.0,
            trade_scenes: ["cornell", "cornell-glass", "smallpt"].map(String::from).to_vec(),
            trade_size: (64, 64),
            trade_seconds: 10.0,
            reference_error: 0.0025,
            reference_seconds: 1800.0,
            cache_dir: cache::default_dir(),
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
            trade_size: (16, 16),
            trade_seconds: 0.15,
            reference_error: 0.03,
            reference_seconds: 5.0,
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
    pub specialisation: Vec<SpecialisationRow>,
}

/// A benchmark that could not run.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("{0}")]
    Usage(String),
    #[error(transparent)]
    Backend(#[from] BackendError),
    #[error("reference cache {path}: {source}")]
    Cache { path: PathBuf, source: std::io::Error },
}

fn load_scene(name: &str) -> Result<Scene, BenchError> {
    Scene::load(name).map_err(|e| BenchError::Usage(format!("--scenes {name}: {e}")))
}

/// Opens the configured backends; an OpenCL one that cannot start is left
/// out with a note when `optional_opencl`.
fn open_backends(config: &Config, observer: &mut dyn Observer) -> Result<Vec<Backend>, BenchError> {
    let mut out = Vec::new();
    for &choice in &config.backends {
        match Backend::choose(choice) {
            Ok(b) => out.push(b),
            Err(e) if config.optional_opencl && matches!(choice, BackendChoice::OpenCl { .. }) => {
                observer.note(&format!("opencl left out: {e}"));
            }
            Err(e) => return Err(e.into()),
        }
    }
    if out.is_empty() {
        return Err(BenchError::Usage("--backend: no backend could start".into()));
    }
    Ok(out)
}

/// Runs the benchmark.
pub fn run(config: &Config, observer: &mut dyn Observer) -> Result<Results, BenchError> {
    let throughput_scenes: Vec<(String, Scene)> =
        config.throughput_scenes.iter().map(|n| Ok((n.clone(), load_scene(n)?))).collect::<Result<_, BenchError>>()?;
    let trade_scenes: Vec<(String, Scene)> =
        config.trade_scenes.iter().map(|n| Ok((n.clone(), load_scene(n)?))).collect::<Result<_, BenchError>>()?;
    let mut backends = open_backends(config, observer)?;
    let s = config.sections;
    let settings: Vec<Setting> = if s.trade {
        settings::trade_settings()
    } else {
        vec![Setting { label: "unbounded".into(), quality: settings::unbiased() }]
    };
    let opencl_count = backends.iter().filter(|b| matches!(b, Backend::OpenCl { .. })).count() as u64;
    let (nb, nt, nr) = (backends.len() as u64, throughput_scenes.len() as u64, trade_scenes.len() as u64);
    let traced = s.trade || s.calibration;
    observer.begin(
        u64::from(s.throughput) * nb * nt * config.throughput_sizes.len() as u64
            + u64::from(traced) * nr * (1 + nb * settings.len() as u64)
            + u64::from(s.specialisation) * opencl_count * nt * 2,
    );

    let mut results = Results {
        machine: machine(),
        date: humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
        renderer_version: RENDERER_VERSION.into(),
        backends: backends.iter().map(|b| (b.name().to_owned(), b.device())).collect(),
        trade_size: config.trade_size,
        ..Results::default()
    };
    let default_quality = Quality::default();

    if s.throughput {
        for backend in &mut backends {
            for (name, scene) in &throughput_scenes {
                for &size in &config.throughput_sizes {
                    observer.step(&format!("throughput {name} {}x{} on {}", size.0, size.1, backend.name()));
                    let result = measure::throughput(backend, scene, size, &default_quality, config.throughput_seconds)?;
                    results.throughput.push(ThroughputRow {
                        backend: backend.name().into(),
                        device: backend.device(),
                        scene: name.clone(),
                        size,
                        result,
                    });
                }
            }
        }
    }

    if traced {
        for (name, scene) in &trade_scenes {
            observer.step(&format!("reference {name} {}x{}", config.trade_size.0, config.trade_size.1));
            let reference = reference(config, &mut backends[0], name, scene, observer)?;
            results.references.push((reference.info.clone(), reference.cached));
            for backend in &mut backends {
                for setting in &settings {
                    observer.step(&format!("trade {name}: {} on {}", setting.label, backend.name()));
                    let points = measure::trace(
                        backend,
                        scene,
                        config.trade_size,
                        &setting.quality,
                        (&reference.pixels, reference.info.error_estimate),
                        config.trade_seconds,
                    )?;
                    if setting.quality == settings::unbiased() {
                        results.calibration.push(CalibrationRow {
                            backend: backend.name().into(),
                            scene: name.clone(),
                            calibration: fit::calibration(&points, reference.info.error_estimate, MIN_SPP_FOR_TARGET_ERROR),
                            points: points.clone(),
                        });
                    }
                    results.trade.push(TradeCurve {
                        backend: backend.name().into(),
                        scene: name.clone(),
                        setting: setting.clone(),
                        fit: fit::fit(&points),
                        points,
                    });
                }
            }
        }
        if !s.trade {
            results.trade.clear();
        }
        if !s.calibration {
            results.calibration.clear();
        }
    }

    if s.specialisation {
        for backend in &mut backends {
            let Backend::OpenCl { .. } = backend else { continue };
            let size = config.throughput_sizes[0];
            for (name, scene) in &throughput_scenes {
                let mut pair = [None, None];
                for (generic, slot) in [false, true].into_iter().zip(&mut pair) {
                    observer.step(&format!(
                        "specialisation {name}: {} program",
                        if generic { "generic" } else { "specialised" }
                    ));
                    if let Backend::OpenCl { backend, .. } = backend {
                        backend.generic = generic;
                    }
                    *slot = Some(measure::throughput(backend, scene, size, &default_quality, config.throughput_seconds)?);
                }
                if let Backend::OpenCl { backend, .. } = backend {
                    backend.generic = false;
                }
                if let [Some(specialised), Some(generic)] = pair {
                    results.specialisation.push(SpecialisationRow {
                        device: backend.device(),
                        scene: name.clone(),
                        size,
                        specialised,
                        generic,
                    });
                }
            }
        }
    }
    Ok(results)
}

/// The reference for `scene` at the trade size: from the cache, or rendered
/// with the unbiased setting on `backend` and cached.
fn reference(
    config: &Config,
    backend: &mut Backend,
    name: &str,
    scene: &Scene,
    observer: &mut dyn Observer,
) -> Result<Reference, BenchError> {
    /// Seed of the references (the measured renders use another).
    const REFERENCE_SEED: u64 = 0x0005_EED0_F2EF;
    let quality = Quality { seed: REFERENCE_SEED, ..settings::unbiased() };
    let stem = cache::stem(name, scene, config.trade_size, &quality);
    if let Some(r) = cache::load(&config.cache_dir, &stem, config.reference_error, config.reference_seconds) {
        observer.detail(&format!("cached: {stem}"));
        return Ok(r);
    }
    let job = RenderJob::new(scene, config.trade_size.0, config.trade_size.1, &quality);
    let (film, done) = measure::render_reference(backend, &job, config.reference_error, config.reference_seconds, |p| {
        let e = p.error_estimate.map_or("n/a".into(), |e| format!("{:.2}%", e * 100.0));
        observer.detail(&format!("{} spp, error {e}", p.spp));
    })?;
    let reference = Reference {
        info: ReferenceInfo {
            scene: name.into(),
            width: config.trade_size.0,
            height: config.trade_size.1,
            spp: done.spp,
            seconds: done.elapsed.as_secs_f64(),
            error_estimate: done.error_estimate.unwrap_or(f64::INFINITY),
            backend: format!("{} ({})", backend.name(), backend.device()),
            renderer_version: RENDERER_VERSION.into(),
        },
        pixels: film.mean(),
        cached: false,
    };
    if reference.info.error_estimate > config.reference_error {
        observer.note(&format!(
            "reference {name}: error {:.2}% after {:.0} s, above the {:.2}% asked for (raise --reference-seconds)",
            reference.info.error_estimate * 100.0,
            reference.info.seconds,
            config.reference_error * 100.0
        ));
    }
    cache::store(&config.cache_dir, &stem, &reference).map_err(|source| BenchError::Cache {
        path: config.cache_dir.clone(),
        source,
    })?;
    Ok(reference)
}

/// CPU model and logical cores, from /proc/cpuinfo where there is one.
fn machine() -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_owned())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
    format!("{model}, {cores} logical cores")
}
