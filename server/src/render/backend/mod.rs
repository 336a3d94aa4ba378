//! Where rendering runs. One enum, one place that chooses (`Backend::choose`).

mod cpu;

pub use cpu::CpuBackend;

use crate::render::film::Film;
use crate::render::job::RenderJob;

/// What the user asked for (`--backend`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BackendChoice {
    /// The best available: an OpenCL GPU once that backend exists, else rayon.
    #[default]
    Auto,
    Cpu,
}

impl BackendChoice {
    pub const NAMES: [&'static str; 2] = ["auto", "cpu"];

    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "auto" => Some(Self::Auto),
            "cpu" => Some(Self::Cpu),
            _ => None,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("{0}")]
    Unavailable(String),
}

/// A backend ready to render.
#[derive(Debug)]
pub enum Backend {
    Cpu(CpuBackend),
}

impl Backend {
    /// The one place that decides where rendering runs.
    pub fn choose(choice: BackendChoice) -> Result<Backend, BackendError> {
        match choice {
            BackendChoice::Auto | BackendChoice::Cpu => Ok(Backend::Cpu(CpuBackend)),
        }
    }

    /// Short name: `cpu` or `opencl`.
    pub fn name(&self) -> &'static str {
        match self {
            Backend::Cpu(_) => "cpu",
        }
    }

    /// Human-readable device description.
    pub fn device(&self) -> String {
        match self {
            Backend::Cpu(b) => b.device(),
        }
    }

    /// Adds `count` samples per pixel to `film`.
    pub fn render(&mut self, job: &RenderJob, film: &mut Film, count: u64) -> Result<(), BackendError> {
        match self {
            Backend::Cpu(b) => {
                b.render(job, film, count);
                Ok(())
            }
        }
    }
}
