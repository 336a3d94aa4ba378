//! The samplers section: the unbiased setting with independent random
//! numbers and with Sobol points on every scene, and how much sooner Sobol
//! reaches 5%, 2% and 1% true error (a paired section, see `compare`).

use super::compare::{self, Table};
use super::settings::{self, Setting};
use super::Results;
use crate::render::sampler::SamplerKind;
use crate::render::Quality;

/// The two settings compared: the unbiased setting, random then Sobol.
pub fn pair() -> [Setting; 2] {
    let sobol = settings::unbiased();
    [
        Setting::new(
            "unbounded, random",
            Quality {
                sampler: SamplerKind::Random,
                ..sobol
            },
        ),
        Setting::new(
            "unbounded, sobol",
            Quality {
                sampler: SamplerKind::Sobol,
                ..sobol
            },
        ),
    ]
}

/// The section's tables.
pub fn markdown(w: &mut String, r: &Results) {
    let table = Table {
        title: "Samplers: random vs Sobol",
        about: "The unbiased setting (unbounded, NEE) with independent random numbers and with scrambled Sobol points.",
        names: ["random", "sobol"],
    };
    compare::markdown(w, &r.samplers, r.trade_size, &table);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_differs_only_in_the_sampler() {
        let [r, s] = pair();
        assert_eq!(r.quality.sampler, SamplerKind::Random);
        assert_eq!(s.quality, settings::unbiased(), "Sobol is the default");
        assert_eq!(
            Quality {
                sampler: SamplerKind::Sobol,
                ..r.quality
            },
            s.quality
        );
    }
}
