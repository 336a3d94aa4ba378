//! Quality flags (`--spp`, `--preset`, `--nee on|off`, `--adaptive on|off`,
//! ...) as a quality patch, and samples per pixel as `render` reports them.

use clap::{Args, ValueEnum};
use pathstream_client::{Denoise, QualityPatch, SessionStatus};

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum Switch {
    On,
    Off,
}

#[derive(Args, Debug, Default)]
pub struct QualityArgs {
    /// Halt at this many samples per pixel.
    #[arg(long)]
    spp: Option<u64>,
    /// Halt after this many milliseconds.
    #[arg(long)]
    time_ms: Option<u64>,
    /// Halt when the estimated relative error falls below this.
    #[arg(long)]
    target_error: Option<f64>,
    /// Quality preset: preview, interactive, final or reference (the other
    /// settings given override it).
    #[arg(long, value_name = "NAME")]
    preset: Option<String>,
    /// Most bounces per path; 0 = unbounded.
    #[arg(long)]
    max_depth: Option<u32>,
    /// Bounces after which Russian roulette may end paths.
    #[arg(long)]
    rr_depth: Option<u32>,
    /// Next-event estimation.
    #[arg(long, value_enum)]
    nee: Option<Switch>,
    /// Adaptive sampling: after a uniform warm-up, samples go to the 8x8
    /// tiles with the most error (--spp is then the mean).
    #[arg(long, value_enum)]
    adaptive: Option<Switch>,
    /// Pixel filter: tent2x2 or box.
    #[arg(long)]
    filter: Option<String>,
    /// Random numbers: sobol (low-discrepancy, the default) or random.
    #[arg(long)]
    sampler: Option<String>,
    /// Largest sample radiance; 0 = off.
    #[arg(long)]
    clamp: Option<f32>,
    #[arg(long)]
    seed: Option<u64>,
    /// Denoise frames with Open Image Denoise on the server: `stream` (the
    /// frames while rendering), `final` (those and the last; the default
    /// for a bare --denoise) or `off`. The error estimate stays the raw
    /// image's.
    #[arg(long, value_enum, value_name = "WHEN", num_args = 0..=1, default_missing_value = "final")]
    denoise: Option<DenoiseArg>,
}

/// `--denoise`.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum DenoiseArg {
    Off,
    Stream,
    Final,
}

impl QualityArgs {
    pub fn patch(&self) -> QualityPatch {
        QualityPatch {
            preset: self.preset.clone(),
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            nee: self.nee.map(|n| matches!(n, Switch::On)),
            filter: self.filter.clone(),
            sampler: self.sampler.clone(),
            clamp: self.clamp,
            seed: self.seed,
            adaptive: self.adaptive.map(|a| matches!(a, Switch::On)),
            spp: self.spp.map(Some),
            time_ms: self.time_ms.map(Some),
            target_error: self.target_error.map(Some),
            denoise: self.denoise.map(|d| match d {
                DenoiseArg::Off => Denoise::Off,
                DenoiseArg::Stream => Denoise::Stream,
                DenoiseArg::Final => Denoise::Final,
            }),
        }
    }

    pub fn halts(&self) -> bool {
        self.spp.is_some() || self.time_ms.is_some() || self.target_error.is_some()
    }
}

/// Samples per pixel as `render` reports them; with adaptive sampling, the
/// mean and how the pixels' counts spread about it (and, with an error
/// target, the tiles that reached their share of it).
pub fn spp_summary(s: &SessionStatus) -> String {
    if !s.quality.adaptive {
        return format!("{} spp", s.spp);
    }
    let p = s.spp_spread;
    let mut text = format!(
        "{} spp (mean; min {}, median {}, max {})",
        s.spp, p.min, p.median, p.max
    );
    if s.quality.target_error.is_some() {
        text.push_str(&format!(", {}/{} tiles done", s.tiles_done, s.tiles));
    }
    text
}
