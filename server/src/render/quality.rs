//! Quality settings: the speed/accuracy trade every render takes.
//!
//! ```json
//! {"max_depth": 6, "rr_depth": 5, "nee": true, "filter": "tent2x2",
//!  "sampler": "sobol", "clamp": 0, "seed": 0, "adaptive": false,
//!  "spp": 256, "time_ms": null, "target_error": 0.02, "denoise": "off"}
//! ```
//! Every field is optional (defaults below); unknown fields are refused.

use crate::render::filter::Filter;
use crate::render::integrator::PathSettings;
use crate::render::sampler::SamplerKind;
pub use pathstream_wire::Denoise;
use serde::{Deserialize, Serialize};

/// Highest explicit `max_depth` / `rr_depth`.
pub const MAX_DEPTH_LIMIT: u32 = 100_000;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Quality {
    /// Most scattering events per path; 0 = unbounded (Russian roulette only).
    pub max_depth: u32,
    /// Scattering events after which Russian roulette may end a path.
    pub rr_depth: u32,
    /// Next-event estimation (shadow rays to emitters).
    pub nee: bool,
    pub filter: Filter,
    /// Which numbers paths draw: `sobol` (low-discrepancy) or `random`.
    pub sampler: SamplerKind,
    /// Largest sample radiance (max component); 0 = off. Biased.
    pub clamp: f32,
    pub seed: u64,
    /// Adaptive sampling: after a uniform warm-up, samples go to the tiles
    /// with the most error (see [`crate::render::adaptive`]).
    pub adaptive: bool,
    /// Halt at this many samples per pixel (adaptive: on average).
    pub spp: Option<u64>,
    /// Halt after this much rendering time.
    pub time_ms: Option<u64>,
    /// Halt when the estimated relative RMS error falls below this.
    pub target_error: Option<f64>,
    /// Which frames show a denoised image (`off`, `stream`, `final`); the
    /// film keeps the denoiser's feature buffers only when not `off`.
    pub denoise: Denoise,
}

impl Default for Quality {
    fn default() -> Self {
        Self {
            max_depth: 6,
            rr_depth: 5,
            nee: true,
            filter: Filter::Tent2x2,
            sampler: SamplerKind::Sobol,
            clamp: 0.0,
            seed: 0,
            adaptive: false,
            spp: None,
            time_ms: None,
            target_error: None,
            denoise: Denoise::Off,
        }
    }
}

/// A quality setting out of range: the field and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("quality.{field}: {reason}")]
pub struct QualityError {
    pub field: &'static str,
    pub reason: String,
}

impl Quality {
    /// Checks ranges; every message names the field.
    pub fn validate(&self) -> Result<(), QualityError> {
        let err = |field, reason: String| Err(QualityError { field, reason });
        if self.max_depth > MAX_DEPTH_LIMIT {
            return err(
                "max_depth",
                format!("must be at most {MAX_DEPTH_LIMIT} (0 = unbounded)"),
            );
        }
        if self.rr_depth > MAX_DEPTH_LIMIT {
            return err("rr_depth", format!("must be at most {MAX_DEPTH_LIMIT}"));
        }
        if !(self.clamp.is_finite() && self.clamp >= 0.0) {
            return err(
                "clamp",
                format!("must be a finite number >= 0 (got {})", self.clamp),
            );
        }
        if self.spp == Some(0) {
            return err("spp", "must be at least 1".into());
        }
        if self.time_ms == Some(0) {
            return err("time_ms", "must be at least 1".into());
        }
        if let Some(e) = self.target_error {
            if !(e.is_finite() && e > 0.0) {
                return err(
                    "target_error",
                    format!("must be a finite number > 0 (got {e})"),
                );
            }
        }
        Ok(())
    }

    /// Whether any halt condition is set.
    pub fn halts(&self) -> bool {
        self.spp.is_some() || self.time_ms.is_some() || self.target_error.is_some()
    }

    /// When an adaptive render stops, as its rounds see it.
    pub fn goal(&self) -> crate::render::adaptive::Goal {
        crate::render::adaptive::Goal {
            target_error: self.target_error,
            spp: self.spp,
        }
    }

    pub fn path_settings(&self) -> PathSettings {
        PathSettings {
            max_depth: self.max_depth,
            rr_depth: self.rr_depth,
            nee: self.nee,
            clamp: self.clamp,
            light_sampling: crate::render::integrator::LightSampling::Power,
            combine: crate::render::integrator::Combine::Mis,
            features: self.denoise != Denoise::Off,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_defaults_and_unknown_fields() {
        let q: Quality =
            serde_json::from_str(r#"{"max_depth": 0, "filter": "box"}"#).expect("parses");
        assert_eq!(q.max_depth, 0);
        assert_eq!(q.filter, Filter::Box);
        assert_eq!(q.rr_depth, Quality::default().rr_depth);
        let e = serde_json::from_str::<Quality>(r#"{"max_dept": 3}"#).expect_err("unknown field");
        assert!(e.to_string().contains("max_dept"), "{e}");
        let e = serde_json::from_str::<Quality>(r#"{"filter": "gauss"}"#).expect_err("bad filter");
        assert!(e.to_string().contains("gauss"), "{e}");
    }

    #[test]
    fn out_of_range_values_name_their_field() {
        let cases = [
            (
                Quality {
                    max_depth: MAX_DEPTH_LIMIT + 1,
                    ..Quality::default()
                },
                "max_depth",
            ),
            (
                Quality {
                    rr_depth: u32::MAX,
                    ..Quality::default()
                },
                "rr_depth",
            ),
            (
                Quality {
                    clamp: -1.0,
                    ..Quality::default()
                },
                "clamp",
            ),
            (
                Quality {
                    clamp: f32::NAN,
                    ..Quality::default()
                },
                "clamp",
            ),
            (
                Quality {
                    spp: Some(0),
                    ..Quality::default()
                },
                "spp",
            ),
            (
                Quality {
                    time_ms: Some(0),
                    ..Quality::default()
                },
                "time_ms",
            ),
            (
                Quality {
                    target_error: Some(0.0),
                    ..Quality::default()
                },
                "target_error",
            ),
            (
                Quality {
                    target_error: Some(f64::INFINITY),
                    ..Quality::default()
                },
                "target_error",
            ),
        ];
        for (q, field) in cases {
            let e = q.validate().expect_err(field);
            assert_eq!(e.field, field);
            assert!(
                e.to_string().starts_with(&format!("quality.{field}: ")),
                "{e}"
            );
        }
        assert!(Quality::default().validate().is_ok());
    }
}
