//! The adaptive section: uniform and adaptive sampling of the unbiased
//! setting on every scene, and how much sooner adaptive reaches 5%, 2% and
//! 1% true error (a paired section, see `compare`).

use super::compare::{self, Table};
use super::settings::{self, Setting};
use super::Results;
use crate::render::Quality;

/// The two settings compared: the unbiased setting, uniform and adaptive.
pub fn pair() -> [Setting; 2] {
    let uniform = settings::unbiased();
    [
        Setting::new("unbounded, uniform", uniform),
        Setting::new(
            "unbounded, adaptive",
            Quality {
                adaptive: true,
                ..uniform
            },
        ),
    ]
}

/// The section's tables.
pub fn markdown(w: &mut String, r: &Results) {
    let table = Table {
        title: "Adaptive sampling: uniform vs adaptive",
        about: "The unbiased setting (unbounded, NEE) with uniform and with adaptive sampling.",
        names: ["uniform", "adaptive"],
    };
    compare::markdown(w, &r.adaptive, r.trade_size, &table);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_differs_only_in_adaptive_sampling() {
        let [u, a] = pair();
        assert!(!u.quality.adaptive && a.quality.adaptive);
        assert_eq!(
            Quality {
                adaptive: false,
                ..a.quality
            },
            u.quality
        );
    }
}
