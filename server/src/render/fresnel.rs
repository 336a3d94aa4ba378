//! How much light a smooth dielectric boundary reflects.

/// The split at a boundary: reflectance and the cosine of the refracted
/// direction (0 under total internal reflection, where reflectance is 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    pub reflectance: f32,
    pub cos_t: f32,
}

/// Refraction geometry shared by both models: cos of the transmitted angle,
/// or None under total internal reflection. Light goes from index n1 to n2.
#[inline(always)]
fn cos_transmitted(cos_i: f32, n1: f32, n2: f32) -> Option<f32> {
    // cos_t^2 = 1 - (n1/n2)^2 (1 - cos_i^2), arranged so that nearly
    // matched indices at grazing angles do not cancel catastrophically.
    let cos2_t = ((n2 - n1) * (n2 + n1) + n1 * n1 * cos_i * cos_i) / (n2 * n2);
    (cos2_t > 0.0).then(|| cos2_t.sqrt())
}

/// Unpolarised Fresnel equations for light arriving at `cos_i` (> 0) in the
/// medium of index n1 and meeting a medium of index n2.
#[inline(always)]
pub fn exact(cos_i: f32, n1: f32, n2: f32) -> Split {
    let Some(cos_t) = cos_transmitted(cos_i, n1, n2) else {
        return Split {
            reflectance: 1.0,
            cos_t: 0.0,
        };
    };
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    let r = 0.5 * (rs * rs + rp * rp);
    Split {
        // At exact grazing incidence both ratios are -1/1: r = 1.
        reflectance: if r.is_finite() { r.min(1.0) } else { 1.0 },
        cos_t,
    }
}

/// Schlick's approximation, smallpt's convention: R0 = ((n1-n2)/(n1+n2))^2
/// and the cosine is taken on the lower-index side (the incident angle when
/// entering the denser medium, the transmitted angle when leaving it).
#[inline(always)]
pub fn schlick(cos_i: f32, n1: f32, n2: f32) -> Split {
    let Some(cos_t) = cos_transmitted(cos_i, n1, n2) else {
        return Split {
            reflectance: 1.0,
            cos_t: 0.0,
        };
    };
    let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
    let c = if n1 <= n2 { cos_i } else { cos_t };
    let m = 1.0 - c;
    Split {
        reflectance: r0 + (1.0 - r0) * m * m * m * m * m,
        cos_t,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Transmittance from the transmission amplitudes, independent of the
    /// reflectance formula: (n2 cos_t)/(n1 cos_i) (ts^2 + tp^2)/2.
    fn transmittance(cos_i: f64, n1: f64, n2: f64) -> f64 {
        let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return 0.0;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let ts = 2.0 * n1 * cos_i / (n1 * cos_i + n2 * cos_t);
        let tp = 2.0 * n1 * cos_i / (n2 * cos_i + n1 * cos_t);
        (n2 * cos_t) / (n1 * cos_i) * 0.5 * (ts * ts + tp * tp)
    }

    #[test]
    fn exact_reflectance_plus_transmittance_is_one_at_every_angle() {
        for (n1, n2) in [
            (1.0, 1.5),
            (1.5, 1.0),
            (1.0, 1.0001),
            (1.0, 4.0),
            (4.0, 1.0),
        ] {
            for i in 1..=1000 {
                let cos_i = i as f32 / 1000.0;
                let r = f64::from(exact(cos_i, n1, n2).reflectance);
                let t = transmittance(f64::from(cos_i), f64::from(n1), f64::from(n2));
                assert!(
                    (r + t - 1.0).abs() < 1e-5,
                    "n {n1}->{n2} cos {cos_i}: R {r} + T {t} != 1"
                );
            }
        }
    }

    #[test]
    fn known_values() {
        // Normal incidence glass: ((1.5-1)/(1.5+1))^2 = 0.04, both models.
        assert!((exact(1.0, 1.0, 1.5).reflectance - 0.04).abs() < 1e-6);
        assert!((schlick(1.0, 1.0, 1.5).reflectance - 0.04).abs() < 1e-6);
        // Matched indices reflect nothing.
        assert!(exact(0.3, 1.0, 1.0).reflectance.abs() < 1e-7);
        // Total internal reflection past the critical angle (41.8 deg).
        let past = (45f32).to_radians().cos();
        assert_eq!(exact(past, 1.5, 1.0).reflectance, 1.0);
        assert_eq!(schlick(past, 1.5, 1.0).reflectance, 1.0);
        // Grazing incidence reflects everything.
        assert!((exact(0.0, 1.0, 1.5).reflectance - 1.0).abs() < 1e-6);
    }

    #[test]
    fn schlick_is_a_probability_and_symmetric_across_the_boundary() {
        for i in 0..=1000 {
            let cos_i = i as f32 / 1000.0;
            for (n1, n2) in [(1.0, 1.5), (1.5, 1.0), (1.0, 4.0)] {
                let s = schlick(cos_i, n1, n2);
                assert!((0.0..=1.0).contains(&s.reflectance));
                // Reciprocity: leaving along the refracted ray sees the same R.
                // (Below cos 0.05 the way back sits at the critical angle,
                // where f32 cannot resolve the transmitted cosine.)
                if s.cos_t > 0.0 && n1 < n2 && cos_i > 0.05 {
                    let back = schlick(s.cos_t, n2, n1);
                    assert!(
                        (back.reflectance - s.reflectance).abs() < 1e-4,
                        "{n1}->{n2} cos {cos_i}: {} there, {} back",
                        s.reflectance,
                        back.reflectance
                    );
                }
            }
        }
    }
}
