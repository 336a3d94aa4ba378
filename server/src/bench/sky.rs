//! The sky section: light selection by power alone against selection with
//! the sky probe (`render::sky_probe`, the renderer's default) on rooms
//! under a sky, and how much sooner the probe reaches 5%, 2% and 1% true
//! error (a paired section, see `compare`).

use super::compare::{self, Table};
use super::settings::{self, Setting};
use super::Results;

/// The two settings compared: the unbiased setting with emitters picked
/// by power alone, then with the sky weighed by what the probe sees.
pub fn pair() -> [Setting; 2] {
    let q = settings::unbiased();
    [
        Setting {
            sky_probe: false,
            ..Setting::new("unbounded, power picks", q)
        },
        Setting::new("unbounded, sky probe", q),
    ]
}

/// The section's tables.
pub fn markdown(w: &mut String, r: &Results) {
    let table = Table {
        title: "A sky behind walls: power picks vs the sky probe",
        about: "The unbiased setting with emitters picked for shadow rays in proportion to their power (a sky counts as lighting everything) and with the sky's share scaled by the fraction of the probe's shadow rays that reach it (`render/sky_probe.rs`).",
        names: ["power picks", "sky probe"],
    };
    compare::markdown(w, &r.sky, r.trade_size, &table);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_differs_only_in_the_probe() {
        let [p, s] = pair();
        assert!(!p.sky_probe && s.sky_probe);
        assert_eq!(p.quality, s.quality);
        assert_eq!(s.quality, settings::unbiased());
    }
}
