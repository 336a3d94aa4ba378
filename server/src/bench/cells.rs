//! How figures are written in the benchmark's tables: relative errors as
//! percentages, durations, the time a curve reaches an error level.

use super::fit::Reach;

/// A relative error as a percentage, with as many decimals as it needs.
pub fn pct(e: f64) -> String {
    match e {
        e if !e.is_finite() => "n/a".into(),
        e if e < 1e-4 => "< 0.01%".into(),
        e if e < 0.1 => format!("{:.2}%", e * 100.0),
        e => format!("{:.1}%", e * 100.0),
    }
}

/// A duration in seconds, in the unit that reads best.
pub fn secs(s: f64) -> String {
    match s {
        s if s < 0.01 => format!("{:.1} ms", s * 1000.0),
        s if s < 10.0 => format!("{s:.2} s"),
        s if s < 1000.0 => format!("{s:.0} s"),
        s => format!("{:.1} h", s / 3600.0),
    }
}

/// When a curve reaches an error level: measured, extrapolated (`~`),
/// never, or unknown.
pub fn reach(r: Reach) -> String {
    match r {
        Reach::Measured(s) => secs(s),
        Reach::Extrapolated(s) => format!("~{}", secs(s)),
        Reach::Never => "never".into(),
        Reach::Unknown => "?".into(),
    }
}
