//! `pathstream render`: one scene to one image file, with a progress bar and
//! a one-line summary.

use super::{outln, CliError, Switch};
use indicatif::{ProgressBar, ProgressStyle};
use pathstream::render::backend::{EmbreeUse, PathLoop};
use pathstream::render::denoise::{self, FilterQuality};
use pathstream::render::job::check_size;
use pathstream::render::output::{write_image, ImageFormat};
use pathstream::render::progressive::{self, DEFAULT_SPP};
use pathstream::render::quality::Denoise;
use pathstream::render::sampler::SamplerKind;
use pathstream::render::split::{render_split, DeviceShare};
use pathstream::render::tonemap::Tonemap;
use pathstream::render::{Backend, BackendChoice, Film, Filter, Preset, Quality, RenderJob};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FilterArg {
    Tent2x2,
    Box,
}

/// `--sampler`: which numbers paths draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SamplerArg {
    /// Owen-scrambled Sobol points: less error per sample.
    Sobol,
    /// Independent random numbers (the renderer's first sampler).
    Random,
}

/// `--backend`: where to render.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BackendArg {
    /// An OpenCL GPU if there is one, else rayon on the CPU.
    Auto,
    /// OpenCL (any device, CPU ones too; see --device).
    Opencl,
    /// rayon on the CPU.
    Cpu,
    /// Every OpenCL device and rayon at once, each taking blocks of samples
    /// sized to its speed, merged exactly into one image.
    All,
}

impl BackendArg {
    pub fn choice(self, device: Option<usize>) -> BackendChoice {
        match self {
            BackendArg::Auto => BackendChoice::Auto,
            BackendArg::Opencl => BackendChoice::OpenCl { device },
            BackendArg::Cpu => BackendChoice::Cpu,
            BackendArg::All => BackendChoice::All,
        }
    }
}

/// `--embree`: where the CPU traces meshes through Embree (if installed).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EmbreeArg {
    /// Scenes of at least 10,000 placed triangles.
    Large,
    /// Every scene with meshes.
    All,
    /// Never: the own BVH.
    Off,
}

/// `--cpu-paths`: how the CPU advances its paths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PathsArg {
    /// In lanes where Embree traces the scene (the wide loop, with diffuse
    /// surfaces shaded over the lanes, where no material has texture maps
    /// and every emitter is a triangle), else in pairs.
    Auto,
    /// 4-16 at a time in lanes, their rays traced together, each shaded
    /// on its own.
    Lanes,
    /// Two at a time, side by side.
    Pairs,
}

#[derive(clap::Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    /// Built-in or bench scene name (see `pathstream scenes`), a scene JSON
    /// file, or a model file (.obj, .gltf, .glb, .ply) framed and lit by
    /// default.
    #[arg(long, value_name = "NAME|FILE")]
    scene: String,
    /// Image width in pixels.
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Halt at this many samples per pixel (default 64 when no halt is given).
    #[arg(long, value_name = "N")]
    spp: Option<u64>,
    /// Halt after this many milliseconds of rendering.
    #[arg(long, value_name = "T")]
    time_ms: Option<u64>,
    /// Halt when the estimated relative RMS error falls below E (e.g. 0.02).
    #[arg(long, value_name = "E")]
    target_error: Option<f64>,
    /// Named quality preset (path knobs; the flags below override it):
    /// preview, interactive, final, reference. See `pathstream bench`.
    #[arg(long, value_enum, value_name = "NAME")]
    preset: Option<Preset>,
    /// Most bounces per path; 0 = unbounded (Russian roulette only) [default: 6].
    #[arg(long, value_name = "D")]
    max_depth: Option<u32>,
    /// Bounces after which Russian roulette may end paths [default: 5].
    #[arg(long, value_name = "D")]
    rr_depth: Option<u32>,
    /// Next-event estimation (shadow rays to the lights) [default: on].
    #[arg(long, value_enum)]
    nee: Option<Switch>,
    /// Pixel filter [default: tent2x2].
    #[arg(long, value_enum)]
    filter: Option<FilterArg>,
    /// Random numbers: low-discrepancy Sobol points or independent ones
    /// [default: sobol].
    #[arg(long, value_enum)]
    sampler: Option<SamplerArg>,
    /// Largest radiance of one sample; 0 = off (biased; removes fireflies) [default: 0].
    #[arg(long, value_name = "C")]
    clamp: Option<f32>,
    /// Adaptive sampling: after 16 uniform samples, samples go to the tiles
    /// with the most error; --spp is then the mean [default: on with the
    /// final and reference presets, else off].
    #[arg(long, value_enum)]
    adaptive: Option<Switch>,
    /// Random seed; the same seed and sample count give the same image.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// Where to render.
    #[arg(long, value_enum, default_value_t = BackendArg::Auto)]
    backend: BackendArg,
    /// OpenCL device number (see `pathstream devices`); implies --backend opencl.
    /// Default: the GPU with the most compute units, else device 0.
    #[arg(long, value_name = "N")]
    device: Option<usize>,
    /// Use the one generic OpenCL program (every feature compiled in) instead
    /// of one specialised to the scene: for measuring what specialisation buys.
    #[arg(long)]
    generic_kernel: bool,
    /// CPU backend: where meshes are traced through Embree, where the
    /// library is installed (else always the own BVH).
    #[arg(long, value_enum, default_value_t = EmbreeArg::Large)]
    embree: EmbreeArg,
    /// CPU backend: how paths are advanced (the image is the same but for
    /// rounding; for measuring the loops).
    #[arg(long, value_enum, default_value_t = PathsArg::Auto)]
    cpu_paths: PathsArg,
    /// Thin-lens radius in scene units (depth of field) [default: the
    /// scene's camera's; 0 = pinhole].
    #[arg(long, value_name = "R", conflicts_with = "f_number")]
    aperture: Option<f64>,
    /// The lens as an f-number instead of --aperture: radius = focal length
    /// / (2 N), the focal length that gives the field of view on a 24 mm
    /// (full-frame) sensor, scene units read as metres.
    #[arg(long, value_name = "N")]
    f_number: Option<f64>,
    /// Distance along the view axis that stays sharp [default: the scene's
    /// camera's, else the distance to its look_at point].
    #[arg(long, value_name = "D")]
    focus_distance: Option<f64>,
    /// How rays leave the camera [default: the scene camera's]; panorama is
    /// an equirectangular 360-degree image (make it twice as wide as tall).
    #[arg(long, value_enum)]
    projection: Option<ProjectionArg>,
    /// An orthographic view's height in scene units [default: the
    /// perspective view's height at the look_at point].
    #[arg(long, value_name = "H")]
    ortho_height: Option<f64>,
    /// An equirectangular HDR environment map (.hdr or .exr; its top row
    /// is up, its centre faces -z) lighting the scene in place of the
    /// scene's own environment.
    #[arg(long, value_name = "FILE", group = "env_source")]
    environment: Option<PathBuf>,
    /// A clear sky and sun computed in place of the scene's environment
    /// (the sun 45 degrees up in the south-east unless --sun-elevation and
    /// --sun-azimuth say otherwise).
    #[arg(long, group = "env_source")]
    sky: bool,
    /// The --sky's sun height above the horizon, degrees.
    #[arg(
        long,
        value_name = "DEG",
        requires = "sky",
        allow_negative_numbers = true
    )]
    sun_elevation: Option<f64>,
    /// The --sky's sun compass direction, degrees clockwise from north
    /// (-z); 90 is east (+x).
    #[arg(
        long,
        value_name = "DEG",
        requires = "sky",
        allow_negative_numbers = true
    )]
    sun_azimuth: Option<f64>,
    /// Scales the --environment map's (or --sky's) radiance.
    #[arg(long, value_name = "S", default_value_t = 1.0, requires = "env_source")]
    env_intensity: f64,
    /// Turns the --environment map (or --sky) about +y, in degrees (right-handed).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        requires = "env_source",
        allow_negative_numbers = true
    )]
    env_rotation: f64,
    /// Exposure in stops applied before tone mapping (PNG only).
    #[arg(long, value_name = "EV", default_value_t = 0.0)]
    exposure: f32,
    /// Denoise the image with Open Image Denoise, guided by the first hit's
    /// albedo and normal (needs libOpenImageDenoise.so.2: see the README).
    /// The error estimate printed is the raw image's.
    #[arg(long)]
    denoise: bool,
    /// With --denoise: also write the raw (not denoised) image here.
    #[arg(long, value_name = "FILE", requires = "denoise")]
    raw_out: Option<PathBuf>,
    /// Output file: .png (tone-mapped sRGB) or .pfm (linear float).
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

impl RenderArgs {
    fn quality(&self) -> Quality {
        let base = Quality {
            seed: self.seed,
            spp: self.spp,
            time_ms: self.time_ms,
            target_error: self.target_error,
            ..Quality::default()
        };
        let q = self.preset.map_or(base, |p| p.apply(base));
        Quality {
            max_depth: self.max_depth.unwrap_or(q.max_depth),
            rr_depth: self.rr_depth.unwrap_or(q.rr_depth),
            nee: self.nee.map_or(q.nee, |n| n == Switch::On),
            filter: self.filter.map_or(q.filter, |f| match f {
                FilterArg::Tent2x2 => Filter::Tent2x2,
                FilterArg::Box => Filter::Box,
            }),
            sampler: self.sampler.map_or(q.sampler, |s| match s {
                SamplerArg::Sobol => SamplerKind::Sobol,
                SamplerArg::Random => SamplerKind::Random,
            }),
            clamp: self.clamp.unwrap_or(q.clamp),
            adaptive: self.adaptive.map_or(q.adaptive, |a| a == Switch::On),
            denoise: match self.denoise {
                true => Denoise::Final,
                false => Denoise::Off,
            },
            ..q
        }
    }
}

pub fn run(args: RenderArgs) -> Result<(), CliError> {
    let usage = |e: String| CliError::Usage(e);
    ImageFormat::from_path(&args.out).map_err(|e| usage(format!("--out: {e}")))?;
    if let Some(raw) = &args.raw_out {
        ImageFormat::from_path(raw).map_err(|e| usage(format!("--raw-out: {e}")))?;
    }
    if args.denoise {
        // Before rendering: a missing library is a usage error, found now.
        denoise::available().map_err(|e| usage(format!("--denoise: {e}")))?;
    }
    check_size(args.width, args.height).map_err(|e| usage(format!("--{e}")))?;
    if !args.exposure.is_finite() {
        return Err(usage("--exposure: must be a finite number".into()));
    }
    let quality = args.quality();
    quality
        .validate()
        .map_err(|e| usage(format!("--{}: {}", e.field.replace('_', "-"), e.reason)))?;
    let mut scene = pathstream::bench::scenes::load(&args.scene)
        .map_err(|e| usage(format!("--scene {}: {e}", args.scene)))?;
    let lens = pathstream::render::scene::CameraEdit {
        aperture: args.aperture,
        f_number: args.f_number,
        focus_distance: args.focus_distance,
        projection: args.projection.map(ProjectionArg::json),
        ortho_height: args.ortho_height,
        ..Default::default()
    };
    if lens != Default::default() {
        // The message names the camera's field (camera.aperture, ...).
        scene = scene
            .edit_camera(&lens)
            .map_err(|e| usage(format!("camera options: {e}")))?;
    }
    if let Some(map) = &args.environment {
        // The message names environment.map, .intensity or .rotation_deg.
        scene = pathstream::resolve::with_environment(
            &scene,
            map,
            args.env_intensity,
            args.env_rotation,
        )
        .map_err(|e| usage(format!("--environment: {e}")))?;
    }
    if args.sky {
        let sky = pathstream::render::scene::SkyJson {
            sun_elevation_deg: args.sun_elevation,
            sun_azimuth_deg: args.sun_azimuth,
            ..Default::default()
        };
        scene = pathstream::resolve::with_sky(&scene, sky, args.env_intensity, args.env_rotation)
            .map_err(|e| usage(format!("--sky: {e}")))?;
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }

    let backend_arg = match (args.backend, args.device) {
        (BackendArg::Cpu | BackendArg::All, Some(_)) => {
            return Err(usage("--device: only with --backend opencl or auto".into()))
        }
        (BackendArg::Auto, Some(_)) => BackendArg::Opencl,
        (b, _) => b,
    };
    let mut backends = match backend_arg {
        BackendArg::All => Backend::all(),
        arg => vec![Backend::choose(arg.choice(args.device))
            .map_err(|e| CliError::Failed(e.to_string()))?],
    };
    let job = RenderJob::new(&scene, args.width, args.height, &quality);
    for backend in &mut backends {
        match backend {
            Backend::OpenCl { backend, .. } => backend.generic = args.generic_kernel,
            Backend::Cpu(cpu) => {
                let embree = match args.embree {
                    EmbreeArg::Large => EmbreeUse::LargeMeshes,
                    EmbreeArg::All => EmbreeUse::AllMeshes,
                    EmbreeArg::Off => EmbreeUse::Never,
                };
                let paths = match args.cpu_paths {
                    PathsArg::Auto => PathLoop::Auto,
                    PathsArg::Lanes => PathLoop::Lanes,
                    PathsArg::Pairs => PathLoop::Pairs,
                };
                *cpu = std::mem::take(cpu).with_embree(embree).with_paths(paths);
            }
        }
        tracing::info!(backend = backend.name(), device = %backend.device(), "rendering");
        backend
            .prepare(&job)
            .map_err(|e| CliError::Failed(e.to_string()))?;
    }
    let mut film = Film::new(args.width, args.height);
    let bar = progress_bar(&quality);
    let show = |p: &progressive::Progress| {
        bar.set_position(p.spp);
        bar.set_message(format!(
            "error {}  {:.2} M paths/s",
            percent(p.error_estimate),
            p.samples_per_sec / 1e6
        ));
    };
    let failed = |e: pathstream::render::BackendError| CliError::Failed(e.to_string());
    let (done, shares) = match &mut backends[..] {
        [one] => (
            progressive::render(&job, one, &mut film, &quality, show).map_err(failed)?,
            vec![DeviceShare::of(one)],
        ),
        all => render_split(&job, all, &mut film, &quality, show).map_err(failed)?,
    };
    bar.finish_and_clear();

    let tonemap = Tonemap {
        exposure: args.exposure,
    };
    let write = |path: &PathBuf, pixels: &[[f32; 3]]| {
        write_image(path, film.width(), film.height(), pixels, &tonemap)
            .map_err(|e| CliError::Failed(e.to_string()))
    };
    let raw = film.mean();
    if args.denoise {
        let started = std::time::Instant::now();
        let features = film.feature_means();
        let clean = denoise::denoise(
            film.width(),
            film.height(),
            &raw,
            features.as_ref(),
            FilterQuality::High,
        )
        .map_err(|e| CliError::Failed(e.to_string()))?;
        tracing::info!(ms = started.elapsed().as_secs_f64() * 1e3, "denoised");
        write(&args.out, &clean)?;
        if let Some(path) = &args.raw_out {
            write(path, &raw)?;
        }
    } else {
        write(&args.out, &raw)?;
    }

    let rejected = if done.rejected > 0 {
        format!(", {} samples rejected (NaN/Inf)", done.rejected)
    } else {
        String::new()
    };
    let spp = match quality.adaptive {
        true => format!(
            "{} spp (adaptive: min {}, median {}, max {}; {} rounds)",
            done.spp,
            done.spread.min,
            done.spread.median,
            done.spread.max,
            film.rounds()
        ),
        false => format!("{} spp", done.spp),
    };
    let backend = match &shares[..] {
        [one] => format!("backend {} ({})", one.backend, one.device),
        all => format!("backend all ({} devices)", all.len()),
    };
    outln!(
        "{} {}x{}: {spp} in {:.2} s, {:.2} M paths/s, error estimate {}, {backend}{} -> {}{}",
        args.scene,
        args.width,
        args.height,
        done.elapsed.as_secs_f64(),
        done.samples_per_sec / 1e6,
        percent(done.error_estimate),
        rejected,
        args.out.display(),
        if args.denoise { " (denoised)" } else { "" }
    )?;
    if shares.len() > 1 {
        for s in &shares {
            let failure = s
                .failure
                .as_ref()
                .map_or_else(String::new, |f| format!("; dropped out: {f}"));
            outln!(
                "  {} ({}): {:.2} M paths/s, {:.1}% of the samples{failure}",
                s.backend,
                s.device,
                s.samples_per_sec / 1e6,
                100.0 * s.samples as f64 / done.samples.max(1) as f64
            )?;
        }
    }
    Ok(())
}

fn percent(e: Option<f64>) -> String {
    e.map_or_else(|| "n/a".to_owned(), |e| format!("{:.2}%", e * 100.0))
}

/// A bar over samples when the spp halt is known, else a spinner; drawn only
/// on a terminal.
fn progress_bar(quality: &Quality) -> ProgressBar {
    let target = if quality.halts() {
        quality.spp
    } else {
        Some(DEFAULT_SPP)
    };
    match target {
        Some(n) => ProgressBar::new(n).with_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30.cyan/blue} {pos}/{len} spp  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        ),
        None => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {pos} spp  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        ),
    }
}

/// `--projection`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ProjectionArg {
    Perspective,
    Orthographic,
    Panorama,
}

impl ProjectionArg {
    fn json(self) -> pathstream::render::scene::ProjectionJson {
        use pathstream::render::scene::ProjectionJson as P;
        match self {
            Self::Perspective => P::Perspective,
            Self::Orthographic => P::Orthographic,
            Self::Panorama => P::Panorama,
        }
    }
}
