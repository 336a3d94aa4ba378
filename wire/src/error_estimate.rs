//! The relative RMS error that a status's `error_estimate` reports, and
//! that a client merging several renders computes again:
//! `sqrt(sum of squared errors) / sqrt(sum of squared values)`, over all
//! pixels and channels. The server sums a film's estimated squared errors
//! (from the spread of its even and odd samples); a client merging renders
//! sums each render's, weighted. Both end in [`relative`], so the two agree
//! on the edge cases too.

/// The relative error of squared sums: `sqrt(err2 / sig2)`. No error is 0
/// whatever the signal (a black image rendered exactly); error on a black
/// image is infinite.
pub fn relative(err2: f64, sig2: f64) -> f64 {
    if err2 == 0.0 {
        0.0
    } else if sig2 == 0.0 {
        f64::INFINITY
    } else {
        (err2 / sig2).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_and_its_edge_cases() {
        assert_eq!(relative(1.0, 4.0), 0.5);
        assert_eq!(relative(0.0, 0.0), 0.0, "nothing rendered wrong");
        assert_eq!(relative(0.0, 9.0), 0.0);
        assert_eq!(relative(1e-30, 0.0), f64::INFINITY, "noise on black");
    }
}
