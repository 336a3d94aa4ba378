//! The MIS section: BSDF sampling alone (next-event estimation off) against
//! next-event estimation and BSDF sampling joined by multiple importance
//! sampling (the default) on glossy scenes, and how much sooner MIS
//! reaches 5%, 2% and 1% true error (a paired section, see `compare`).

use super::compare::{self, Table};
use super::settings::{self, Setting};
use super::Results;
use crate::render::Quality;

/// The two settings compared: the unbiased setting without, then with,
/// next-event estimation (which `pbr` surfaces weigh by MIS).
pub fn pair() -> [Setting; 2] {
    let mis = settings::unbiased();
    [
        Setting::new("unbounded, BSDF only", Quality { nee: false, ..mis }),
        Setting::new("unbounded, MIS", mis),
    ]
}

/// The section's tables.
pub fn markdown(w: &mut String, r: &Results) {
    let table = Table {
        title: "MIS: BSDF sampling alone vs multiple importance sampling",
        about: "The unbiased setting with next-event estimation off (emitters found by BSDF samples only) and on (at `pbr` surfaces, and at every surface under an environment map, the shadow ray and the BSDF sample weighted by the power heuristic).",
        names: ["BSDF only", "MIS"],
    };
    compare::markdown(w, &r.mis, r.trade_size, &table);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pair_differs_only_in_next_event_estimation() {
        let [b, m] = pair();
        assert!(!b.quality.nee);
        assert_eq!(m.quality, settings::unbiased(), "MIS is the default");
        assert_eq!(
            Quality {
                nee: true,
                ..b.quality
            },
            m.quality
        );
    }
}
