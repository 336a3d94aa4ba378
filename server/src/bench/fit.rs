//! Error against time: the model a progressive render follows, fitted to
//! measured points, and what it predicts.
//!
//! A render's squared relative error against the truth is its squared bias
//! plus a variance that falls as 1/time: `err^2 = b^2 + c^2 / t`. `b` is the
//! bias floor (error left at convergence), `c` the variance constant (error
//! x sqrt(seconds) while noise dominates). Measured against a reference that
//! has noise of its own (`r`, its error estimate), the squared error gains
//! `r^2`, which [`corrected`] takes out of every point before the fit.

/// One measurement of a render in progress.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TracePoint {
    /// Rendering time so far (excludes measuring).
    pub seconds: f64,
    pub spp: u64,
    /// Relative RMS error against the reference, the reference's own noise
    /// taken out in quadrature.
    pub true_error: f64,
    /// The film's own error estimate.
    pub estimate: Option<f64>,
}

/// Takes the reference's noise `reference_error` out of a measured error.
pub fn corrected(measured: f64, reference_error: f64) -> f64 {
    (measured * measured - reference_error * reference_error)
        .max(0.0)
        .sqrt()
}

/// `err^2 = bias^2 + variance_constant^2 / seconds`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub bias: f64,
    pub variance_constant: f64,
}

impl Fit {
    /// Error the model predicts after `seconds`.
    pub fn error_at(&self, seconds: f64) -> f64 {
        (self.bias * self.bias + self.variance_constant * self.variance_constant / seconds).sqrt()
    }

    /// Seconds until the error falls to `target`; None when the bias floor
    /// is at or above it.
    pub fn time_to(&self, target: f64) -> Option<f64> {
        let room = target * target - self.bias * self.bias;
        (room > 0.0).then(|| self.variance_constant * self.variance_constant / room)
    }
}

/// The bias floor where a run resolves it: `Ok(bias)` when it stands out of
/// the noise left at the end of the run (`c / sqrt(t_end)`) and the
/// reference's, combined in quadrature, by a factor of two; else
/// `Err(bound)`: the bias is below what the run can tell from noise.
pub fn resolved_bias(fit: &Fit, end_seconds: f64, reference_error: f64) -> Result<f64, f64> {
    let noise = (fit.variance_constant * fit.variance_constant / end_seconds.max(1e-12)
        + reference_error * reference_error)
        .sqrt();
    if fit.bias > 2.0 * noise {
        Ok(fit.bias)
    } else {
        Err(2.0 * noise)
    }
}

/// Points with fewer samples per pixel than this are left out of fits: the
/// first passes carry start-up costs and too few samples for the model.
pub const MIN_FIT_SPP: u64 = 4;

/// Weighted least squares of `err^2 = a + c^2 x` (x = 1/t) over `points`,
/// each weighted by 1/err^4 so that every point counts by its relative
/// error. The errors are already corrected for the reference's noise.
pub fn fit(points: &[TracePoint]) -> Option<Fit> {
    let usable: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.spp >= MIN_FIT_SPP && p.seconds > 0.0 && p.true_error.is_finite())
        .map(|p| (1.0 / p.seconds, p.true_error * p.true_error))
        .collect();
    if usable.len() < 2 {
        return None;
    }
    // Weight by the relative size of each point; a zero error (the render
    // matched the reference within its noise) gets the largest weight seen.
    let floor = usable
        .iter()
        .map(|&(_, y)| y)
        .filter(|&y| y > 0.0)
        .fold(f64::INFINITY, f64::min);
    let floor = if floor.is_finite() { floor } else { 1e-12 };
    let w = |y: f64| 1.0 / (y.max(floor) * y.max(floor));
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y) in &usable {
        let wi = w(y);
        sw += wi;
        sx += wi * x;
        sy += wi * y;
        sxx += wi * x * x;
        sxy += wi * x * y;
    }
    let det = sw * sxx - sx * sx;
    let (mut a, mut c2) = if det.abs() > 0.0 {
        ((sxx * sy - sx * sxy) / det, (sw * sxy - sx * sy) / det)
    } else {
        (sy / sw, 0.0)
    };
    if a < 0.0 {
        // No measurable bias: fit the variance alone.
        a = 0.0;
        c2 = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    }
    if c2 < 0.0 {
        // Error does not fall with time: all bias.
        c2 = 0.0;
        a = sy / sw;
    }
    Some(Fit {
        bias: a.sqrt(),
        variance_constant: c2.max(0.0).sqrt(),
    })
}

/// When a render reaches an error level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// Seen in the measurements (interpolated between two points).
    Measured(f64),
    /// Beyond the measured time, from the fit.
    Extrapolated(f64),
    /// The bias floor is at or above the level.
    Never,
    /// Not enough points to say.
    Unknown,
}

impl Reach {
    pub fn seconds(&self) -> Option<f64> {
        match *self {
            Reach::Measured(s) | Reach::Extrapolated(s) => Some(s),
            Reach::Never | Reach::Unknown => None,
        }
    }
}

/// When the measured error first falls to `target` (log-log interpolation
/// between the points either side), else what the fit predicts.
pub fn time_to(points: &[TracePoint], fit: Option<&Fit>, target: f64) -> Reach {
    for (i, p) in points.iter().enumerate() {
        if p.true_error <= target {
            let Some(prev) = i.checked_sub(1).map(|j| points[j]) else {
                return Reach::Measured(p.seconds);
            };
            let (e0, e1) = (
                prev.true_error.max(1e-300).ln(),
                p.true_error.max(1e-300).ln(),
            );
            let (t0, t1) = (prev.seconds.ln(), p.seconds.ln());
            let f = if e0 > e1 {
                ((e0 - target.ln()) / (e0 - e1)).clamp(0.0, 1.0)
            } else {
                1.0
            };
            return Reach::Measured((t0 + f * (t1 - t0)).exp());
        }
    }
    match fit {
        None => Reach::Unknown,
        Some(f) => f.time_to(target).map_or(Reach::Never, Reach::Extrapolated),
    }
}

/// (seconds, estimate / true error) of the points [`calibration`] uses.
pub fn calibration_points(
    points: &[TracePoint],
    reference_error: f64,
    min_spp: u64,
) -> impl Iterator<Item = (f64, f64)> + '_ {
    points
        .iter()
        .filter(move |p| {
            p.spp >= min_spp && p.true_error > 2.0 * reference_error && p.true_error > 0.0
        })
        .filter_map(|p| {
            p.estimate
                .filter(|e| e.is_finite())
                .map(|e| (p.seconds, e / p.true_error))
        })
}

/// How the film's error estimate compares with the true error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration {
    /// Points compared.
    pub points: usize,
    /// Median of estimate / true error.
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

/// Estimate / true error over the points of an unbiased render that have
/// enough samples for the estimate and an error well above the reference's
/// noise (`reference_error`), where the true error is known well.
pub fn calibration(
    points: &[TracePoint],
    reference_error: f64,
    min_spp: u64,
) -> Option<Calibration> {
    let mut ratios: Vec<f64> = calibration_points(points, reference_error, min_spp)
        .map(|(_, ratio)| ratio)
        .collect();
    if ratios.is_empty() {
        return None;
    }
    ratios.sort_by(f64::total_cmp);
    let n = ratios.len();
    let median = if n % 2 == 1 {
        ratios[n / 2]
    } else {
        0.5 * (ratios[n / 2 - 1] + ratios[n / 2])
    };
    Some(Calibration {
        points: n,
        median,
        min: ratios[0],
        max: ratios[n - 1],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn synthetic(bias: f64, c: f64) -> Vec<TracePoint> {
        (0..20)
            .map(|i| {
                let seconds = 0.01 * 1.5f64.powi(i);
                TracePoint {
                    seconds,
                    spp: 4 << i,
                    true_error: (bias * bias + c * c / seconds).sqrt(),
                    estimate: Some(c / seconds.sqrt()),
                }
            })
            .collect()
    }

    #[test]
    fn fit_recovers_bias_and_variance_constant() {
        for (bias, c) in [(0.0, 0.05), (0.02, 0.05), (0.1, 0.001)] {
            let f = fit(&synthetic(bias, c)).expect("fits");
            assert!((f.bias - bias).abs() < 1e-6, "bias {} vs {bias}", f.bias);
            assert!(
                (f.variance_constant - c).abs() < 1e-6 * c.max(1e-3),
                "c {} vs {c}",
                f.variance_constant
            );
        }
    }

    #[test]
    fn time_to_interpolates_extrapolates_and_says_never() {
        let points = synthetic(0.02, 0.05);
        let f = fit(&points).expect("fits");
        // 5% is reached inside the measured range, close to the model's time.
        let Reach::Measured(t) = time_to(&points, Some(&f), 0.05) else {
            panic!("measured")
        };
        let exact = f.time_to(0.05).expect("reachable");
        assert!((t / exact - 1.0).abs() < 0.05, "{t} vs {exact}");
        // 1% is below the 2% bias floor.
        assert_eq!(time_to(&points, Some(&f), 0.01), Reach::Never);
        // Without bias, a level past the last point is extrapolated.
        let points = synthetic(0.0, 0.05);
        let f = fit(&points).expect("fits");
        let Reach::Extrapolated(t) = time_to(&points, Some(&f), 1e-4) else {
            panic!("extrapolated")
        };
        assert!((t / (0.05f64 / 1e-4).powi(2) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn calibration_of_a_perfect_estimate_is_one() {
        let c = calibration(&synthetic(0.0, 0.05), 0.0, 8).expect("points");
        assert!((c.median - 1.0).abs() < 1e-12 && (c.min - 1.0).abs() < 1e-12);
        assert_eq!(c.points, 19);
        assert_eq!(calibration(&synthetic(0.0, 0.05), 1.0, 8), None);
    }

    #[test]
    fn bias_is_reported_only_where_the_run_resolves_it() {
        let f = Fit {
            bias: 0.05,
            variance_constant: 0.03,
        };
        assert_eq!(resolved_bias(&f, 9.0, 0.0), Ok(0.05));
        let f = Fit {
            bias: 0.005,
            variance_constant: 0.03,
        };
        let bound = resolved_bias(&f, 9.0, 0.0).expect_err("unresolved");
        assert!((bound - 0.02).abs() < 1e-12);
    }

    #[test]
    fn reference_noise_comes_out_in_quadrature() {
        assert!((corrected(0.05, 0.03) - 0.04).abs() < 1e-12);
        assert_eq!(corrected(0.01, 0.02), 0.0);
    }
}
