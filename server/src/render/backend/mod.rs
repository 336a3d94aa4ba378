//! Where rendering runs. One enum, one place that chooses ([`Backend::choose`]).
//!
//! `auto` takes an OpenCL GPU if there is one, else rayon on the CPU (and
//! says why). An OpenCL backend chosen by `auto` falls back to rayon, with a
//! logged warning, if the device fails mid-render; one asked for by name
//! reports the error instead.

mod cpu;
pub mod opencl;
mod priority;

pub use cpu::{nearest_hits, nearest_hits_packets, CpuBackend, EmbreeUse, IsaCap, PathLoop};
pub use opencl::{OpenClBackend, OpenClError};

use crate::render::adaptive::TileWork;
use crate::render::film::Film;
use crate::render::job::RenderJob;

/// What the user asked for (`--backend`, `--device`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BackendChoice {
    /// An OpenCL GPU if there is one, else rayon.
    #[default]
    Auto,
    Cpu,
    /// OpenCL device N as `pathstream devices` numbers them (None: the first).
    OpenCl {
        device: Option<usize>,
    },
    /// Every OpenCL device and rayon at once (see [`crate::render::split`]).
    All,
}

impl BackendChoice {
    pub const NAMES: [&'static str; 4] = ["auto", "opencl", "cpu", "all"];

    pub fn parse(s: &str, device: Option<usize>) -> Option<Self> {
        match s {
            "auto" => Some(Self::Auto),
            "cpu" => Some(Self::Cpu),
            "opencl" => Some(Self::OpenCl { device }),
            "all" => Some(Self::All),
            _ => None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("{0}")]
    Unavailable(String),
    #[error(transparent)]
    OpenCl(#[from] OpenClError),
}

/// Says once per job that `auto` renders it with rayon, and why.
fn log_scene_fallback(job: &RenderJob, why: &str) {
    static LAST: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    if LAST.swap(job.id, std::sync::atomic::Ordering::Relaxed) != job.id {
        tracing::info!(
            job = job.id,
            "OpenCL cannot render this scene ({why}); rendering it with rayon on the CPU"
        );
    }
}

/// A backend ready to render.
#[derive(Debug)]
pub enum Backend {
    Cpu(CpuBackend),
    OpenCl {
        backend: Box<OpenClBackend>,
        /// Chosen by `auto`: fall back to rayon on failure.
        fallback: bool,
    },
}

impl Backend {
    /// Every OpenCL device that starts, each asked for by number (a device
    /// that fails drops out of a split render rather than fall back: rayon
    /// is there already). Devices that do not start are logged and left out.
    pub fn opencl_devices() -> Vec<Backend> {
        let count = opencl::list_devices().map_or(0, |d| d.len());
        (0..count)
            .filter_map(|i| match OpenClBackend::new(Some(i)) {
                Ok(b) => Some(Backend::OpenCl {
                    backend: Box::new(b),
                    fallback: false,
                }),
                Err(e) => {
                    tracing::warn!(device = i, error = %e, "an OpenCL device did not start; leaving it out");
                    None
                }
            })
            .collect()
    }

    /// Every backend `all` renders on: each OpenCL device, then rayon.
    pub fn all() -> Vec<Backend> {
        let mut all = Self::opencl_devices();
        all.push(Backend::Cpu(CpuBackend::default()));
        all
    }

    /// The one place that decides where rendering runs (`all` is several
    /// backends: [`Backend::all`]).
    pub fn choose(choice: BackendChoice) -> Result<Backend, BackendError> {
        match choice {
            BackendChoice::All => Err(BackendError::Unavailable(
                "'all' is every device at once, not one backend".into(),
            )),
            BackendChoice::Cpu => Ok(Backend::Cpu(CpuBackend::default())),
            BackendChoice::OpenCl { device } => Ok(Backend::OpenCl {
                backend: Box::new(OpenClBackend::new(device)?),
                fallback: false,
            }),
            BackendChoice::Auto => match OpenClBackend::auto() {
                Ok(b) => {
                    tracing::info!(device = %b.device(), "auto: rendering on the OpenCL GPU");
                    Ok(Backend::OpenCl {
                        backend: Box::new(b),
                        fallback: true,
                    })
                }
                Err(e) => {
                    let why = e.to_string();
                    tracing::info!(reason = %why, "auto: no OpenCL GPU, rendering with rayon on the CPU");
                    Ok(Backend::Cpu(CpuBackend::fallback(why)))
                }
            },
        }
    }

    /// Short name: `cpu` or `opencl`.
    pub fn name(&self) -> &'static str {
        match self {
            Backend::Cpu(_) => "cpu",
            Backend::OpenCl { .. } => "opencl",
        }
    }

    /// Human-readable device description.
    pub fn device(&self) -> String {
        match self {
            Backend::Cpu(b) => b.device(),
            Backend::OpenCl { backend, .. } => backend.device(),
        }
    }

    /// Gets ready to render `job` (builds the OpenCL program for its
    /// features), so that timing the first pass does not time the compiler.
    pub fn prepare(&mut self, job: &RenderJob) -> Result<(), BackendError> {
        match self {
            Backend::Cpu(_) => Ok(()),
            Backend::OpenCl { backend, fallback } => match backend.prepare_program(job) {
                Ok(()) => Ok(()),
                Err(OpenClError::Unsupported(_)) if *fallback => Ok(()),
                Err(e) if *fallback => {
                    let why = format!("OpenCL failed on {}: {e}", backend.info().name.trim());
                    tracing::warn!("{why}; falling back to rayon on the CPU");
                    *self = Backend::Cpu(CpuBackend::fallback(why));
                    Ok(())
                }
                Err(e) => Err(e.into()),
            },
        }
    }

    /// As [`Backend::render`], but a pass gives up early once `cancelled`
    /// says so (a CPU pass between rows, a device's between launches);
    /// Ok(false) then, and the film must be thrown away.
    pub fn render_unless(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        count: u64,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, BackendError> {
        self.run(
            job,
            film,
            |b, film| b.render_unless(job, film, count, cancelled),
            |c, film| c.render_unless(job, film, count, cancelled),
        )
    }

    /// Adds sample `film.spp()` to pixels `film.slice_start()..end` (a pass
    /// shorter than one sample of the whole image). Ok(false) when a CPU
    /// slice gave up for `cancelled`; the film must then be thrown away. On
    /// failure the film is as it was before the call.
    pub fn render_slice(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        end: usize,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, BackendError> {
        self.run(
            job,
            film,
            |b, film| b.render_slice(job, film, end).map(|()| true),
            |c, film| c.render_slice(job, film, end, cancelled),
        )
    }

    /// Adds adaptive `work` to `film` (see [`Film::adaptive_work`]).
    /// Ok(false) when a CPU pass gave up for `cancelled`; the film must then
    /// be thrown away. On failure the film is as it was before the call.
    pub fn render_tiles(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        work: &[TileWork],
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> Result<bool, BackendError> {
        self.run(
            job,
            film,
            |b, film| b.render_tiles(job, film, work).map(|()| true),
            |c, film| c.render_tiles(job, film, work, cancelled),
        )
    }

    /// Adds `count` samples per pixel to `film`. On failure the film is as
    /// it was before the call.
    pub fn render(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        count: u64,
    ) -> Result<(), BackendError> {
        self.run(
            job,
            film,
            |b, film| b.render(job, film, count),
            |c, film| c.render(job, film, count),
        )
    }

    /// Runs `on_device` on OpenCL, or `on_cpu` with rayon: for this scene
    /// only when `auto` chose OpenCL and the kernel does not model it, from
    /// now on when the device fails.
    fn run<T>(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        on_device: impl FnOnce(&mut OpenClBackend, &mut Film) -> Result<T, OpenClError>,
        on_cpu: impl FnOnce(&mut CpuBackend, &mut Film) -> T,
    ) -> Result<T, BackendError> {
        match self {
            Backend::Cpu(b) => Ok(on_cpu(b, film)),
            Backend::OpenCl { backend, fallback } => match on_device(backend, film) {
                Ok(t) => Ok(t),
                Err(OpenClError::Unsupported(why)) if *fallback => {
                    // This scene only: the device keeps serving the others.
                    log_scene_fallback(job, &why);
                    Ok(on_cpu(&mut CpuBackend::fallback(why), film))
                }
                Err(e) if *fallback => {
                    let why = format!("OpenCL failed on {}: {e}", backend.info().name.trim());
                    tracing::warn!("{why}; falling back to rayon on the CPU");
                    let mut cpu = CpuBackend::fallback(why);
                    let t = on_cpu(&mut cpu, film);
                    *self = Backend::Cpu(cpu);
                    Ok(t)
                }
                Err(e) => Err(e.into()),
            },
        }
    }
}
