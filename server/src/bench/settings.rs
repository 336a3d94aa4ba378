//! The quality settings the trade section measures: every knob the renderer
//! offers, one at a time from the default, plus the named presets.

use crate::render::{Filter, Preset, Quality};

/// One measured setting.
#[derive(Clone, Debug, PartialEq)]
pub struct Setting {
    /// Short label for tables and plot legends, e.g. "depth 4" or
    /// "depth 8 = final".
    pub label: String,
    pub quality: Quality,
    /// Whether jobs weigh a hidden sky by the probe (`render::sky_probe`,
    /// as the renderer always does) or pick emitters by power alone.
    pub sky_probe: bool,
}

impl Setting {
    /// A setting as the renderer runs it (with the sky probe).
    pub fn new(label: impl Into<String>, quality: Quality) -> Self {
        Self {
            label: label.into(),
            quality,
            sky_probe: true,
        }
    }
}

/// The unbiased setting the references and the calibration use.
pub fn unbiased() -> Quality {
    Quality {
        adaptive: false,
        ..Preset::Reference.apply(Quality::default())
    }
}

/// Every setting, each quality once (a preset equal to a knob setting
/// shares its row: "depth 8 = final").
pub fn trade_settings() -> Vec<Setting> {
    let d = Quality::default();
    let mut raw: Vec<(String, Quality)> = Vec::new();
    for depth in [1u32, 2, 4, 6, 8] {
        let label = if depth == d.max_depth {
            format!("depth {depth} (default)")
        } else {
            format!("depth {depth}")
        };
        raw.push((
            label,
            Quality {
                max_depth: depth,
                ..d
            },
        ));
    }
    raw.push(("unbounded".into(), Quality { max_depth: 0, ..d }));
    raw.push(("NEE off".into(), Quality { nee: false, ..d }));
    raw.push((
        "NEE off, unbounded".into(),
        Quality {
            nee: false,
            max_depth: 0,
            ..d
        },
    ));
    raw.push(("clamp 10".into(), Quality { clamp: 10.0, ..d }));
    raw.push(("clamp 1".into(), Quality { clamp: 1.0, ..d }));
    raw.push((
        "box filter".into(),
        Quality {
            filter: Filter::Box,
            ..d
        },
    ));
    raw.push(("RR from bounce 1".into(), Quality { rr_depth: 1, ..d }));
    raw.push((
        "RR from bounce 1, unbounded".into(),
        Quality {
            rr_depth: 1,
            max_depth: 0,
            ..d
        },
    ));
    for p in Preset::ALL {
        raw.push((p.name().into(), p.apply(d)));
    }
    let mut out: Vec<Setting> = Vec::new();
    for (label, quality) in raw {
        match out.iter_mut().find(|s| s.quality == quality) {
            Some(s) => s.label = format!("{} = {label}", s.label),
            None => out.push(Setting::new(label, quality)),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_distinct_valid_and_name_every_preset() {
        let s = trade_settings();
        for (i, a) in s.iter().enumerate() {
            a.quality.validate().expect("valid");
            assert!(
                s[i + 1..].iter().all(|b| b.quality != a.quality),
                "{} twice",
                a.label
            );
        }
        for p in Preset::ALL {
            assert!(
                s.iter()
                    .any(|x| x.label.split(" = ").any(|l| l == p.name())),
                "{}",
                p.name()
            );
        }
        assert!(s.iter().any(|x| x.quality == unbiased()));
    }
}
