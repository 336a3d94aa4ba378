//! `pathstream bench`: throughput, the speed/accuracy trade of every quality
//! setting, the error estimate's calibration and OpenCL specialisation, as
//! Markdown on stdout and, with `--out`, CSV files and PNG plots.

use super::render::BackendArg;
use super::CliError;
use indicatif::{ProgressBar, ProgressStyle};
use pathstream::bench::{self, plot, report, Config, Observer, Sections};
use pathstream::render::job::check_size;
use pathstream::render::BackendChoice;
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SectionArg {
    /// Camera paths and spp per second per scene at 512x512 and 1920x1080.
    Throughput,
    /// Time to 10/5/2/1% error, bias floor and variance constant per setting.
    Trade,
    /// The film's error estimate against the true error.
    Calibration,
    /// OpenCL: scene-specialised vs generic program.
    Specialisation,
    /// Meshes: BVH build time and memory, rays/s, paths/s (CPU and OpenCL), upload time.
    Meshes,
    /// Uniform vs adaptive sampling: time to 5/2/1% error on every built-in scene and a mesh scene.
    Adaptive,
    /// Random numbers vs Sobol points: time to 5/2/1% error on every built-in scene and two mesh scenes.
    Samplers,
    /// BSDF sampling alone vs MIS: time to 5/2/1% error on glossy-plane, cornell-mesh-pbr and sunset-balls.
    Mis,
    /// Emitters picked by power alone vs the sky probe: time to 5/2/1% error on sky-room and sky-window.
    Sky,
    /// Every backend alone, then all at once on one render (--backend all): paths/s of each and combined.
    Devices,
}

#[derive(clap::Args, Debug)]
#[command(
    allow_negative_numbers = true,
    after_help = "The first full run renders a reference per trade scene (minutes on a CPU) and \
caches it (see --cache); reruns reuse it. `--quick` takes seconds."
)]
pub struct BenchArgs {
    /// Backends to measure, comma-separated [default: cpu, and opencl when a
    /// device is found].
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    backend: Vec<BackendArg>,
    /// OpenCL device number (see `pathstream devices`). Default: the GPU
    /// with the most compute units, else device 0.
    #[arg(long, value_name = "N")]
    device: Option<usize>,
    /// Sections to run, comma-separated [default: all].
    #[arg(long, value_enum, value_delimiter = ',', value_name = "LIST")]
    sections: Vec<SectionArg>,
    /// Scenes for every section, comma-separated (built-in names, the bench
    /// scenes cornell-glass-mesh, cornell-mesh, cornell-mesh-pbr,
    /// cornell-mesh-frosted, cornell-mesh-coated, glossy-plane,
    /// sunset-balls, sky-room and sky-window, or JSON files) [default: throughput on cornell,
    /// cornell-glass, cornell-quads, smallpt, furnace, cornell-mesh,
    /// cornell-mesh-pbr, cornell-mesh-frosted, cornell-mesh-coated; trade on cornell, cornell-glass, smallpt; adaptive
    /// and samplers on the five built-in scenes and the first two mesh
    /// scenes; mis on glossy-plane, cornell-mesh-pbr and sunset-balls; sky
    /// on sky-room and sky-window].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    scenes: Vec<String>,
    /// A small version that runs in seconds (small images, short runs,
    /// noisy references).
    #[arg(long)]
    quick: bool,
    /// Write CSV files and PNG plots into this directory.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Where references are cached [default: $PATHSTREAM_CACHE_DIR, else
    /// $XDG_CACHE_HOME/pathstream, else ~/.cache/pathstream].
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Image size of the trade and calibration renders [default: 64x64; 16x16 with --quick].
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    trade_size: Option<(u32, u32)>,
    /// Rendering seconds per setting in the trade [default: 10; 0.15 with --quick].
    #[arg(long, value_name = "S")]
    trade_seconds: Option<f64>,
    /// Seconds per throughput measurement [default: 3; 0.1 with --quick].
    #[arg(long, value_name = "S")]
    throughput_seconds: Option<f64>,
    /// Seeds of the paired sections (adaptive, samplers, mis, sky): both settings are
    /// rendered with each, and the tables give the median speed-up and the
    /// range [default: 3; 1 with --quick].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..=100))]
    seeds: Option<u64>,
    /// Triangle counts of the mesh section, comma-separated [default:
    /// 10000,100000,1000000,4000000; 2000,20000 with --quick].
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    mesh_sizes: Vec<usize>,
    /// Render references until their estimated error is this low [default: 0.0025; 0.03 with --quick]...
    #[arg(long, value_name = "E")]
    reference_error: Option<f64>,
    /// ...or for at most this many seconds [default: 1800; 5 with --quick].
    #[arg(long, value_name = "S")]
    reference_seconds: Option<f64>,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("expected WxH, e.g. 64x64 (got {s:?})"))?;
    let num = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("expected WxH, e.g. 64x64 (got {s:?})"))
    };
    let size = (num(w)?, num(h)?);
    check_size(size.0, size.1)?;
    Ok(size)
}

fn positive(name: &str, v: Option<f64>, default: f64) -> Result<f64, CliError> {
    match v {
        None => Ok(default),
        Some(x) if x.is_finite() && x > 0.0 => Ok(x),
        Some(x) => Err(CliError::Usage(format!(
            "--{name}: must be a number > 0 (got {x})"
        ))),
    }
}

impl BenchArgs {
    fn config(&self) -> Result<Config, CliError> {
        let mut c = if self.quick {
            Config::quick()
        } else {
            Config::full()
        };
        if !self.backend.is_empty() {
            c.optional_opencl = false;
            c.backends = Vec::new();
            for b in &self.backend {
                let choice = match b {
                    BackendArg::Auto => BackendChoice::Auto,
                    BackendArg::Cpu => BackendChoice::Cpu,
                    BackendArg::Opencl => BackendChoice::OpenCl {
                        device: self.device,
                    },
                    BackendArg::All => {
                        return Err(CliError::Usage(
                            "--backend all: the devices section measures every device at once (--sections devices)".into(),
                        ))
                    }
                };
                if !c.backends.contains(&choice) {
                    c.backends.push(choice);
                }
            }
        } else if self.device.is_some() {
            c.backends = vec![
                BackendChoice::Cpu,
                BackendChoice::OpenCl {
                    device: self.device,
                },
            ];
            c.optional_opencl = false;
        }
        if !self.sections.is_empty() {
            let has = |s| self.sections.contains(&s);
            c.sections = Sections {
                throughput: has(SectionArg::Throughput),
                trade: has(SectionArg::Trade),
                calibration: has(SectionArg::Calibration),
                specialisation: has(SectionArg::Specialisation),
                meshes: has(SectionArg::Meshes),
                adaptive: has(SectionArg::Adaptive),
                samplers: has(SectionArg::Samplers),
                mis: has(SectionArg::Mis),
                sky: has(SectionArg::Sky),
                devices: has(SectionArg::Devices),
            };
        }
        if !self.scenes.is_empty() {
            c.throughput_scenes = self.scenes.clone();
            c.trade_scenes = self.scenes.clone();
            c.adaptive_scenes = self.scenes.clone();
            c.sampler_scenes = self.scenes.clone();
            c.mis_scenes = self.scenes.clone();
            c.sky_scenes = self.scenes.clone();
        }
        if let Some(dir) = &self.cache {
            c.cache_dir = dir.clone();
        }
        if let Some(size) = self.trade_size {
            c.trade_size = size;
        }
        if let Some(n) = self.seeds {
            c.seeds = n;
        }
        if !self.mesh_sizes.is_empty() {
            if let Some(bad) = self
                .mesh_sizes
                .iter()
                .find(|&&n| !(100..=16_000_000).contains(&n))
            {
                return Err(CliError::Usage(format!(
                    "--mesh-sizes: {bad} is not between 100 and 16000000 triangles"
                )));
            }
            c.mesh_sizes = self.mesh_sizes.clone();
        }
        c.trade_seconds = positive("trade-seconds", self.trade_seconds, c.trade_seconds)?;
        c.throughput_seconds = positive(
            "throughput-seconds",
            self.throughput_seconds,
            c.throughput_seconds,
        )?;
        c.reference_error = positive("reference-error", self.reference_error, c.reference_error)?;
        c.reference_seconds = positive(
            "reference-seconds",
            self.reference_seconds,
            c.reference_seconds,
        )?;
        Ok(c)
    }
}

/// Progress bar over the benchmark's steps (drawn only on a terminal).
struct Bar {
    bar: ProgressBar,
    step: String,
}

impl Observer for Bar {
    fn begin(&mut self, steps: u64) {
        self.bar.set_length(steps);
    }
    fn step(&mut self, what: &str) {
        if !self.step.is_empty() {
            self.bar.inc(1);
        }
        self.step = what.to_owned();
        self.bar.set_message(what.to_owned());
        tracing::info!("{what}");
    }
    fn detail(&mut self, what: &str) {
        self.bar.set_message(format!("{}: {what}", self.step));
    }
    fn note(&mut self, what: &str) {
        self.bar.suspend(|| eprintln!("note: {what}"));
    }
}

pub fn run(args: BenchArgs) -> Result<(), CliError> {
    let config = args.config()?;
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Usage(format!("--out {}: {e}", dir.display())))?;
    }
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30.cyan/blue} {pos}/{len}  {wide_msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut observer = Bar {
        bar,
        step: String::new(),
    };
    let results = bench::run(&config, &mut observer).map_err(|e| match e {
        bench::BenchError::Usage(m) => CliError::Usage(m),
        other => CliError::Failed(other.to_string()),
    })?;
    observer.bar.finish_and_clear();
    super::write_out(format_args!("{}", report::markdown(&results)))?;
    if let Some(dir) = &args.out {
        let mut files = report::write_csv(&results, dir)
            .map_err(|e| CliError::Failed(format!("--out {}: {e}", dir.display())))?;
        files.extend(plot::write_all(&results, dir).map_err(|e| CliError::Failed(e.to_string()))?);
        let _ = std::fs::write(dir.join("bench.md"), report::markdown(&results));
        files.push(dir.join("bench.md"));
        for f in files {
            eprintln!("wrote {}", f.display());
        }
    }
    Ok(())
}
