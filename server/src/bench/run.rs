//! The benchmark's order of work: open the backends, then throughput,
//! references and traces, specialisation.

use super::cache::{self, Reference, ReferenceInfo, RENDERER_VERSION};
use super::measure::TRACE_SEED;
use super::settings::{self, Setting};
use super::{
    adaptive, cells, fit, measure, mis, samplers, scenes, sky, BenchError, CalibrationRow, Config,
    Observer, Results, SpecialisationRow, ThroughputRow, TradeCurve,
};
use crate::render::progressive::MIN_SPP_FOR_TARGET_ERROR;
use crate::render::{Backend, BackendChoice, Quality, RenderJob, Scene};

fn load_scene(name: &str) -> Result<Scene, BenchError> {
    scenes::load(name).map_err(|e| BenchError::Usage(format!("--scenes {name}: {e}")))
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
        return Err(BenchError::Usage(
            "--backend: no backend could start".into(),
        ));
    }
    Ok(out)
}

/// Runs the benchmark.
pub fn run(config: &Config, observer: &mut dyn Observer) -> Result<Results, BenchError> {
    let load = |names: &[String]| -> Result<Scenes, BenchError> {
        names
            .iter()
            .map(|n| Ok((n.clone(), load_scene(n)?)))
            .collect()
    };
    let throughput_scenes = load(&config.throughput_scenes)?;
    let trade_scenes = load(&config.trade_scenes)?;
    let adaptive_scenes = match config.sections.adaptive {
        true => load(&config.adaptive_scenes)?,
        false => Vec::new(),
    };
    let sampler_scenes = match config.sections.samplers {
        true => load(&config.sampler_scenes)?,
        false => Vec::new(),
    };
    let mis_scenes = match config.sections.mis {
        true => load(&config.mis_scenes)?,
        false => Vec::new(),
    };
    let sky_scenes = match config.sections.sky {
        true => load(&config.sky_scenes)?,
        false => Vec::new(),
    };
    let backends = open_backends(config, observer)?;
    let s = config.sections;
    let settings: Vec<Setting> = if s.trade {
        settings::trade_settings()
    } else {
        vec![Setting::new("unbounded", settings::unbiased())]
    };
    let opencl_count = backends
        .iter()
        .filter(|b| matches!(b, Backend::OpenCl { .. }))
        .count() as u64;
    let na =
        (adaptive_scenes.len() + sampler_scenes.len() + mis_scenes.len() + sky_scenes.len()) as u64;
    let (nb, nt, nr) = (
        backends.len() as u64,
        throughput_scenes.len() as u64,
        trade_scenes.len() as u64,
    );
    let traced = s.trade || s.calibration;
    observer.begin(
        u64::from(s.throughput) * nb * nt * config.throughput_sizes.len() as u64
            + u64::from(traced) * nr * (1 + nb * settings.len() as u64)
            + u64::from(s.specialisation) * opencl_count * nt * 2
            + u64::from(s.meshes) * config.mesh_sizes.len() as u64
            + u64::from(s.devices) * nt * config.throughput_sizes.len() as u64
            + na * (1 + nb * 2 * config.seeds),
    );

    let results = Results {
        machine: machine(),
        date: humantime::format_rfc3339_seconds(std::time::SystemTime::now()).to_string(),
        renderer_version: RENDERER_VERSION.into(),
        backends: backends
            .iter()
            .map(|b| (b.name().to_owned(), b.device()))
            .collect(),
        trade_size: config.trade_size,
        ..Results::default()
    };
    let mut work = Work {
        config,
        backends,
        observer,
        results,
    };
    if s.throughput {
        work.throughput(&throughput_scenes)?;
    }
    if traced {
        work.trade(&trade_scenes, &settings)?;
        if !s.trade {
            work.results.trade.clear();
        }
        if !s.calibration {
            work.results.calibration.clear();
        }
    }
    if s.adaptive {
        work.results.adaptive = work.pairs(&adaptive_scenes, adaptive::pair())?;
    }
    if s.samplers {
        work.results.samplers = work.pairs(&sampler_scenes, samplers::pair())?;
    }
    if s.mis {
        work.results.mis = work.pairs(&mis_scenes, mis::pair())?;
    }
    if s.sky {
        work.results.sky = work.pairs(&sky_scenes, sky::pair())?;
    }
    if s.specialisation {
        work.specialisation(&throughput_scenes)?;
    }
    if s.meshes {
        work.meshes()?;
    }
    if s.devices {
        work.devices(&throughput_scenes)?;
    }
    Ok(work.results)
}

/// Scenes by name.
type Scenes = Vec<(String, Scene)>;

/// The open backends, and what has been measured on them so far.
struct Work<'a> {
    config: &'a Config,
    backends: Vec<Backend>,
    observer: &'a mut dyn Observer,
    results: Results,
}

impl Work<'_> {
    /// Build, memory, rays/s and paths/s of each mesh size (on the CPU,
    /// and paths/s and upload time on the first OpenCL backend).
    fn meshes(&mut self) -> Result<(), BenchError> {
        for &n in &self.config.mesh_sizes {
            self.observer.step(&format!("mesh of {n} triangles"));
            let opencl = self
                .backends
                .iter_mut()
                .find(|b| matches!(b, Backend::OpenCl { .. }));
            let row = super::meshes::measure(n, self.config.mesh_seconds, opencl)?;
            self.results.meshes.push(row);
        }
        Ok(())
    }

    /// Each backend alone, then all of them on one render, per throughput
    /// scene and size (nothing to split with one backend).
    fn devices(&mut self, scenes: &Scenes) -> Result<(), BenchError> {
        if self.backends.len() < 2 {
            self.observer
                .note("devices: one backend only, nothing to split across");
            return Ok(());
        }
        for (name, scene) in scenes {
            for &size in &self.config.throughput_sizes {
                self.observer
                    .step(&format!("every device: {name} {}x{}", size.0, size.1));
                let row = super::devices::measure(
                    &mut self.backends,
                    name,
                    scene,
                    size,
                    self.config.throughput_seconds,
                )?;
                self.results.devices.push(row);
            }
        }
        Ok(())
    }

    fn throughput(&mut self, scenes: &Scenes) -> Result<(), BenchError> {
        let (config, observer, results) = (self.config, &mut *self.observer, &mut self.results);
        for backend in &mut self.backends {
            for (name, scene) in scenes {
                for &size in &config.throughput_sizes {
                    observer.step(&format!(
                        "throughput {name} {}x{} on {}",
                        size.0,
                        size.1,
                        backend.name()
                    ));
                    let result = measure::throughput(
                        backend,
                        scene,
                        size,
                        &Quality::default(),
                        config.throughput_seconds,
                    )?;
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
        Ok(())
    }

    /// Every setting's trace on every backend, against each scene's reference;
    /// the unbiased setting's traces also go to the calibration.
    fn trade(&mut self, scenes: &Scenes, settings: &[Setting]) -> Result<(), BenchError> {
        for (name, scene) in scenes {
            let reference = self.reference(name, scene)?;
            for b in 0..self.backends.len() {
                for setting in settings {
                    let curve = self.curve(b, name, scene, setting, &reference, TRACE_SEED)?;
                    self.results.trade.push(curve);
                }
            }
        }
        Ok(())
    }

    /// A paired section: the two settings of `pair` on every scene,
    /// backend and seed, in that order; unbiased settings' traces also go
    /// to the calibration (see [`Work::curve`]).
    fn pairs(
        &mut self,
        scenes: &Scenes,
        pair: [Setting; 2],
    ) -> Result<Vec<TradeCurve>, BenchError> {
        let mut curves = Vec::new();
        for (name, scene) in scenes {
            let reference = self.reference(name, scene)?;
            for b in 0..self.backends.len() {
                for seed in (0..self.config.seeds).map(|k| TRACE_SEED + k) {
                    for setting in &pair {
                        curves.push(self.curve(b, name, scene, setting, &reference, seed)?);
                    }
                }
            }
        }
        Ok(curves)
    }

    /// `name`'s reference (cached or rendered), recorded once in the results.
    fn reference(&mut self, name: &str, scene: &Scene) -> Result<Reference, BenchError> {
        let (w, h) = self.config.trade_size;
        self.observer.step(&format!("reference {name} {w}x{h}"));
        let r = reference(self.config, &mut self.backends, name, scene, self.observer)?;
        if !self.results.references.iter().any(|(i, _)| i.scene == name) {
            self.results.references.push((r.info.clone(), r.cached));
        }
        Ok(r)
    }

    /// `setting`'s error against time on backend `b`; the unbiased
    /// setting's (uniform or adaptive, Sobol or random, with the sky probe
    /// or without) also goes to the calibration, as "scene", "scene
    /// (adaptive)", "scene (random)", "scene (power picks)".
    fn curve(
        &mut self,
        b: usize,
        name: &str,
        scene: &Scene,
        setting: &Setting,
        reference: &Reference,
        seed: u64,
    ) -> Result<TradeCurve, BenchError> {
        let config = self.config;
        let backend = &mut self.backends[b];
        self.observer.step(&format!(
            "trade {name}: {} on {} (seed {seed})",
            setting.label,
            backend.name()
        ));
        let reference_error = reference.info.error_estimate;
        let points = measure::trace(
            backend,
            scene,
            config.trade_size,
            setting,
            (&reference.pixels, reference_error),
            config.trade_seconds,
            seed,
        )?;
        let q = setting.quality;
        let plain = Quality {
            adaptive: false,
            sampler: settings::unbiased().sampler,
            ..q
        };
        if plain == settings::unbiased() {
            let mut calibrated = name.to_owned();
            if q.adaptive {
                calibrated.push_str(" (adaptive)");
            }
            if q.sampler != plain.sampler {
                calibrated.push_str(&format!(" ({})", q.sampler.name()));
            }
            if !setting.sky_probe {
                calibrated.push_str(" (power picks)");
            }
            let row = CalibrationRow {
                backend: backend.name().into(),
                scene: calibrated,
                calibration: fit::calibration(&points, reference_error, MIN_SPP_FOR_TARGET_ERROR),
                points: points.clone(),
                reference_error,
            };
            let known = |r: &CalibrationRow| r.backend == row.backend && r.scene == row.scene;
            if !self.results.calibration.iter().any(known) {
                self.results.calibration.push(row);
            }
        }
        Ok(TradeCurve {
            backend: backend.name().into(),
            scene: name.to_owned(),
            setting: setting.clone(),
            seed,
            fit: fit::fit(&points),
            points,
        })
    }

    /// Each OpenCL backend's throughput with the scene-specialised program and
    /// with the generic one, at the first throughput size.
    fn specialisation(&mut self, scenes: &Scenes) -> Result<(), BenchError> {
        let (config, observer, results) = (self.config, &mut *self.observer, &mut self.results);
        let size = config.throughput_sizes[0];
        for backend in &mut self.backends {
            if !matches!(backend, Backend::OpenCl { .. }) {
                continue;
            }
            for (name, scene) in scenes {
                let mut rates = Vec::with_capacity(2);
                for generic in [false, true] {
                    let program = if generic { "generic" } else { "specialised" };
                    observer.step(&format!("specialisation {name}: {program} program"));
                    set_generic(backend, generic);
                    let rate = measure::throughput(
                        backend,
                        scene,
                        size,
                        &Quality::default(),
                        config.throughput_seconds,
                    );
                    set_generic(backend, false);
                    rates.push(rate?);
                }
                results.specialisation.push(SpecialisationRow {
                    device: backend.device(),
                    scene: name.clone(),
                    size,
                    specialised: rates[0],
                    generic: rates[1],
                });
            }
        }
        Ok(())
    }
}

fn set_generic(backend: &mut Backend, generic: bool) {
    if let Backend::OpenCl { backend, .. } = backend {
        backend.generic = generic;
    }
}

/// The reference for `scene` at the trade size: from the cache, or rendered
/// with the unbiased setting on the fastest of `backends` and cached.
fn reference(
    config: &Config,
    backends: &mut [Backend],
    name: &str,
    scene: &Scene,
    observer: &mut dyn Observer,
) -> Result<Reference, BenchError> {
    /// Seed of the references (the measured renders use another).
    const REFERENCE_SEED: u64 = 0x0005_EED0_F2EF;
    let quality = Quality {
        seed: REFERENCE_SEED,
        ..settings::unbiased()
    };
    let stem = cache::stem(name, scene, config.trade_size, &quality);
    if let Some(r) = cache::load(
        &config.cache_dir,
        &stem,
        config.reference_error,
        config.reference_seconds,
    ) {
        observer.detail(&format!("cached: {stem}"));
        return Ok(r);
    }
    let backend = fastest(backends, scene, config.trade_size, &quality, observer)?;
    let job = RenderJob::new(scene, config.trade_size.0, config.trade_size.1, &quality);
    let (film, done) = measure::render_reference(
        backend,
        &job,
        config.reference_error,
        config.reference_seconds,
        |p| {
            let e = p.error_estimate.map_or_else(|| "n/a".into(), cells::pct);
            observer.detail(&format!("{} spp, error {e}", p.spp));
        },
    )?;
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

/// The backend that renders `quality` fastest (a short timed render on each
/// when there are several): references take minutes on a CPU, seconds on a
/// GPU, whatever order the backends were listed in.
fn fastest<'a>(
    backends: &'a mut [Backend],
    scene: &Scene,
    size: (u32, u32),
    quality: &Quality,
    observer: &mut dyn Observer,
) -> Result<&'a mut Backend, BenchError> {
    /// Seconds of each backend's trial render.
    const TRIAL_SECONDS: f64 = 0.3;
    let mut best = (0, 0.0);
    if backends.len() > 1 {
        for (i, backend) in backends.iter_mut().enumerate() {
            observer.detail(&format!("timing {} for the reference", backend.name()));
            let rate =
                measure::throughput(backend, scene, size, quality, TRIAL_SECONDS)?.paths_per_sec;
            if rate > best.1 {
                best = (i, rate);
            }
        }
    }
    Ok(&mut backends[best.0])
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
