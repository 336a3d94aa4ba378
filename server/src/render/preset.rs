//! Named quality presets: the path settings `pathstream bench` measured as
//! the best trade for a purpose (docs/BENCHMARKS.md has the figures).
//!
//! A preset sets the path knobs (`max_depth`, `rr_depth`, `nee`, `filter`,
//! `clamp`) and `adaptive` (on for the finished images of `final` and
//! `reference`, whose error is uneven over the image; off for the quick
//! looks, which are restarted long before a warm-up ends); it leaves the
//! seed and the halt conditions alone. Settings given
//! next to a preset override it: `--preset preview --max-depth 4`, or
//! `{"preset": "preview", "max_depth": 4}` in the API.

use crate::render::filter::Filter;
use crate::render::quality::Quality;
use crate::render::sampler::SamplerKind;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Preset {
    /// Framing a shot: two bounces, Russian roulette from the first. Fastest;
    /// biased dark where light needs more bounces (glass, caustics).
    Preview,
    /// Moving the camera or the light: four bounces, Russian roulette from
    /// the first. A few per cent of bias on glass scenes.
    Interactive,
    /// A finished image: unbounded paths (unbiased), Russian roulette from the
    /// first bounce; the first unbiased setting to reach 1% error on the
    /// small-light scenes.
    Final,
    /// The benchmark's references: unbounded, Russian roulette from the
    /// fifth bounce (the most conservative; unbiased).
    Reference,
}

impl Preset {
    pub const ALL: [Preset; 4] = [
        Preset::Preview,
        Preset::Interactive,
        Preset::Final,
        Preset::Reference,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Preset::Preview => "preview",
            Preset::Interactive => "interactive",
            Preset::Final => "final",
            Preset::Reference => "reference",
        }
    }

    pub fn from_name(name: &str) -> Option<Preset> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// One line on what the preset is for.
    pub fn description(self) -> &'static str {
        match self {
            Preset::Preview => "framing a shot: 2 bounces, RR from bounce 1, NEE (fastest; glass and caustics dark)",
            Preset::Interactive => "moving camera or light: 4 bounces, RR from bounce 1, NEE (a few % bias on glass)",
            Preset::Final => "a finished image: unbounded, RR from bounce 1, NEE, adaptive (unbiased; soonest to 1%)",
            Preset::Reference => "ground truth: unbounded, RR from bounce 5, NEE, adaptive (unbiased, most conservative)",
        }
    }

    /// `quality` with this preset's path knobs.
    pub fn apply(self, quality: Quality) -> Quality {
        let (max_depth, rr_depth, adaptive) = match self {
            Preset::Preview => (2, 1, false),
            Preset::Interactive => (4, 1, false),
            Preset::Final => (0, 1, true),
            Preset::Reference => (0, 5, true),
        };
        Quality {
            max_depth,
            rr_depth,
            nee: true,
            filter: Filter::Tent2x2,
            sampler: SamplerKind::Sobol,
            clamp: 0.0,
            adaptive,
            ..quality
        }
    }

    /// Comma-separated names, for error messages.
    pub fn names() -> String {
        Self::ALL.map(Preset::name).join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_presets_are_valid() {
        for p in Preset::ALL {
            assert_eq!(Preset::from_name(p.name()), Some(p));
            let json = serde_json::to_string(&p).expect("serialises");
            assert_eq!(json, format!("\"{}\"", p.name()));
            p.apply(Quality::default()).validate().expect("valid");
        }
        assert_eq!(Preset::from_name("fast"), None);
    }

    #[test]
    fn a_preset_keeps_seed_and_halts() {
        let q = Quality {
            seed: 7,
            spp: Some(3),
            target_error: Some(0.1),
            ..Quality::default()
        };
        let p = Preset::Reference.apply(q);
        assert_eq!((p.seed, p.spp, p.target_error), (7, Some(3), Some(0.1)));
        assert_eq!((p.max_depth, p.clamp, p.nee), (0, 0.0, true));
    }
}
