//! Spectra to linear sRGB, for the sky model (`sky_model`), which
//! scatters light wavelength by wavelength.
//!
//! - Wavelengths: 380-780 nm in 10 nm bins (41 samples), each the bin's
//!   centre; a spectrum is an array of values per bin.
//! - Colour matching: the CIE 1931 2-degree observer as the multi-lobe
//!   Gaussian fit of Wyman, Sloan and Shirley ("Simple Analytic
//!   Approximations to the CIE XYZ Color Matching Functions", JCGT 2013),
//!   within ~1% of the tabulated functions where they matter.
//! - XYZ to linear sRGB (Rec. 709 primaries, D65 white): IEC 61966-2-1.
//! - The sun outside the atmosphere: the ASTM G-173 extraterrestrial
//!   spectrum, averaged per 10 nm bin (W m^-2 nm^-1).

/// The first bin's wavelength (nm).
pub const LAMBDA_MIN: f64 = 380.0;
/// Bin width (nm).
pub const LAMBDA_STEP: f64 = 10.0;
/// Bins from 380 to 780 nm.
pub const BINS: usize = 41;

/// A value per wavelength bin.
pub type Spectrum = [f64; BINS];

/// Wavelength of bin `i` in nm.
#[inline]
pub fn lambda(i: usize) -> f64 {
    LAMBDA_MIN + LAMBDA_STEP * i as f64
}

/// ASTM G-173 extraterrestrial solar spectral irradiance, W m^-2 nm^-1,
/// bins 380-780 nm (each the mean over [lambda, lambda + 10)).
const SOLAR: Spectrum = [
    1.01249, 1.14716, 1.72765, 1.73054, 1.6887, 1.61253, 1.91198, 2.03474, 2.02042, 2.02212,
    1.93377, 1.95809, 1.91686, 1.8298, 1.8685, 1.8931, 1.85149, 1.8504, 1.8341, 1.8345, 1.8147,
    1.78158, 1.7533, 1.6965, 1.68194, 1.64654, 1.6048, 1.52143, 1.55622, 1.5113, 1.474, 1.4482,
    1.41018, 1.36775, 1.34188, 1.31429, 1.28303, 1.26758, 1.2367, 1.2082, 1.18737,
];

/// The extraterrestrial solar spectral irradiance (W m^-2 nm^-1).
pub fn solar_irradiance() -> Spectrum {
    SOLAR
}

/// One lobe of the fit: a Gaussian with different widths either side.
fn lobe(l: f64, mu: f64, s1: f64, s2: f64) -> f64 {
    let t = (l - mu) / if l < mu { s1 } else { s2 };
    (-0.5 * t * t).exp()
}

/// CIE 1931 x-bar, y-bar, z-bar at wavelength `l` (nm).
pub fn cmf(l: f64) -> [f64; 3] {
    let x = 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7)
        - 0.065 * lobe(l, 501.1, 20.4, 26.2);
    let y = 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1);
    let z = 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8);
    [x, y, z]
}

/// CIE XYZ of a spectrum (per nm), integrated over the bins.
pub fn to_xyz(s: &Spectrum) -> [f64; 3] {
    let mut xyz = [0.0; 3];
    for (i, v) in s.iter().enumerate() {
        let c = cmf(lambda(i));
        for k in 0..3 {
            xyz[k] += v * c[k] * LAMBDA_STEP;
        }
    }
    xyz
}

/// Linear sRGB of CIE XYZ.
pub fn xyz_to_rgb([x, y, z]: [f64; 3]) -> [f64; 3] {
    [
        3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
        -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
        0.0556434 * x - 0.2040259 * y + 1.0572252 * z,
    ]
}

/// Luminance (Y) of linear sRGB.
pub fn luminance([r, g, b]: [f64; 3]) -> f64 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fit_integrates_and_peaks_where_the_cie_tables_do() {
        // The three functions have equal integrals, 106.86 over 360-830 nm
        // (illuminant E has x = y = z).
        let xyz = to_xyz(&[1.0; BINS]);
        for c in xyz {
            assert!((c / 106.86 - 1.0).abs() < 0.02, "{xyz:?}");
        }
        // y-bar peaks at 555 nm at 1.0 (CIE 1931 table: 1.0000 at 555).
        assert!((cmf(555.0)[1] - 1.0).abs() < 0.01, "{}", cmf(555.0)[1]);
        // x-bar's two peaks (1.0622 at 600 nm, 0.3483 at 445 nm) and z-bar's
        // (1.7721 at 450 nm), within 3%.
        assert!((cmf(600.0)[0] / 1.0622 - 1.0).abs() < 0.03);
        assert!((cmf(445.0)[0] / 0.3483 - 1.0).abs() < 0.03);
        assert!((cmf(450.0)[2] / 1.7721 - 1.0).abs() < 0.03);
        // D65's white point maps to equal RGB: XYZ (0.9505, 1, 1.089).
        let w = xyz_to_rgb([0.95047, 1.0, 1.08883]);
        for c in w {
            assert!((c - 1.0).abs() < 1e-3, "{w:?}");
        }
    }

    #[test]
    fn the_sun_outside_the_atmosphere_is_near_white_and_its_visible_irradiance_is_the_tables() {
        let s = solar_irradiance();
        // 380-790 nm carries ~660 W/m^2 of the 1361 W/m^2 solar constant.
        let total: f64 = s.iter().sum::<f64>() * LAMBDA_STEP;
        assert!((600.0..720.0).contains(&total), "{total}");
        let rgb = xyz_to_rgb(to_xyz(&s));
        let mean = rgb.iter().sum::<f64>() / 3.0;
        for c in rgb {
            assert!((c / mean - 1.0).abs() < 0.1, "{rgb:?}");
        }
    }
}
