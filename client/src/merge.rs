//! One image from several independent renders of it (the same scene, size
//! and settings, different seeds), and the error of the result.
//!
//! Each render's pixel is the mean of its own samples; the merged pixel is
//! their mean weighted by samples per pixel,
//! `sum_i spp_i * mean_i / sum_i spp_i`, which for uniform sampling is
//! exactly the mean of all the samples together. With adaptive sampling a
//! render's `spp` is its mean over the pixels, so the weights are the mean
//! counts: the merged pixel is still a fixed-weight average of unbiased
//! estimates of the same value (so unbiased), and its error estimate below
//! stays right, but where the renders split a pixel's samples in other
//! proportions than their means it is a little noisier than pooling them.
//!
//! Error: a render's estimate is `e_i = sqrt(sum var) / S_i`, the
//! per-pixel variance of its mean summed over the image, over `S_i`, the
//! root of the sum of its squared pixel values. The renders are independent,
//! so the variance of the weighted mean is `sum_i w_i^2 var_i` with
//! `w_i = spp_i / sum spp`, and the merged relative error is
//! `sqrt(sum_i w_i^2 e_i^2 S_i^2) / S` ([`merge`]). While rendering, with
//! only each server's status at hand, `S_i = S` (the same image, up to
//! noise) gives `sqrt(sum_i w_i^2 e_i^2)` ([`combined_error`]); with equal
//! noise per sample it equals `1 / sqrt(sum_i 1 / e_i^2)`.

use crate::linear::{ImageError, LinearFrame, LinearImage};
use pathstream_wire::error_estimate::relative;

/// The merged image.
#[derive(Clone, Debug, PartialEq)]
pub struct Merged {
    pub image: LinearImage,
    /// Samples per pixel of all the renders together.
    pub spp: u64,
    /// Relative RMS error estimate of the merged image; None when a render
    /// (with samples) has none.
    pub error_estimate: Option<f64>,
}

/// Merges `frames` weighted by samples per pixel (renders without samples
/// add nothing). All must have the size of the first.
pub fn merge(frames: &[LinearFrame]) -> Result<Merged, ImageError> {
    let first = frames.first().ok_or(ImageError::NoSamples)?;
    let (width, height) = (first.image.width, first.image.height);
    let count = width as usize * height as usize;
    for (index, f) in frames.iter().enumerate() {
        let i = &f.image;
        if (i.width, i.height) != (width, height) || i.pixels.len() != count {
            return Err(ImageError::Size {
                index,
                width,
                height,
                got_width: i.width,
                got_height: i.height,
            });
        }
    }
    let spp: u64 = frames.iter().map(|f| f.spp).sum();
    if spp == 0 {
        return Err(ImageError::NoSamples);
    }
    let total = spp as f64;
    let mut sums = vec![[0.0f64; 3]; count];
    for f in frames.iter().filter(|f| f.spp > 0) {
        let weight = f.spp as f64;
        for (sum, p) in sums.iter_mut().zip(&f.image.pixels) {
            for c in 0..3 {
                sum[c] += weight * f64::from(p[c]);
            }
        }
    }
    let image = LinearImage {
        width,
        height,
        pixels: sums.iter().map(|s| s.map(|v| (v / total) as f32)).collect(),
    };
    let error_estimate = merged_error(frames, &image, total);
    Ok(Merged {
        image,
        spp,
        error_estimate,
    })
}

/// `sqrt(sum_i w_i^2 e_i^2 S_i^2) / S` (see the module's note).
fn merged_error(frames: &[LinearFrame], merged: &LinearImage, total: f64) -> Option<f64> {
    let mut err2 = 0.0;
    for f in frames.iter().filter(|f| f.spp > 0) {
        let e = f.error_estimate.filter(|e| e.is_finite())?;
        let w = f.spp as f64 / total;
        err2 += w * w * e * e * f.image.sum_of_squares();
    }
    Some(relative(err2, merged.sum_of_squares()))
}

/// The merged relative error from each render's samples per pixel and
/// error estimate alone, assuming the renders show the same image:
/// `sqrt(sum_i w_i^2 e_i^2)`. None when a render with samples has no
/// estimate, or no render has samples.
pub fn combined_error(parts: &[(u64, Option<f64>)]) -> Option<f64> {
    let total: u64 = parts.iter().map(|p| p.0).sum();
    if total == 0 {
        return None;
    }
    let mut err2 = 0.0;
    for &(spp, e) in parts.iter().filter(|p| p.0 > 0) {
        let w = spp as f64 / total as f64;
        let e = e?;
        err2 += w * w * e * e;
    }
    Some(err2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(width: u32, pixels: Vec<[f32; 3]>, spp: u64, e: Option<f64>) -> LinearFrame {
        let height = pixels.len() as u32 / width;
        LinearFrame {
            image: LinearImage {
                width,
                height,
                pixels,
            },
            spp,
            error_estimate: e,
            generation: 0,
        }
    }

    #[test]
    fn constant_images_merge_to_their_spp_weighted_mean_exactly() {
        let a = frame(2, vec![[1.0, 0.0, 8.0]; 4], 1, Some(0.1));
        let b = frame(2, vec![[3.0, 2.0, 0.0]; 4], 3, Some(0.1));
        let m = merge(&[a, b]).expect("merges");
        assert_eq!(m.spp, 4);
        assert_eq!((m.image.width, m.image.height), (2, 2));
        // (1*1 + 3*3)/4, (1*0 + 3*2)/4, (1*8 + 3*0)/4: exact in binary.
        assert!(m.image.pixels.iter().all(|p| *p == [2.5, 1.5, 2.0]));
    }

    #[test]
    fn one_render_merges_to_itself_bit_for_bit() {
        let pixels: Vec<[f32; 3]> = (0..12).map(|i| [0.1 * i as f32, 1.0 / 3.0, 7e-5]).collect();
        let a = frame(4, pixels.clone(), 37, Some(0.02));
        let m = merge(&[a]).expect("merges");
        assert_eq!(m.image.pixels, pixels);
        let e = m.error_estimate.expect("an estimate");
        assert!((e - 0.02).abs() < 1e-12, "{e}");
    }

    #[test]
    fn mismatched_sizes_and_no_samples_are_refused() {
        let a = frame(2, vec![[1.0; 3]; 4], 1, None);
        let b = frame(4, vec![[1.0; 3]; 4], 1, None);
        assert!(matches!(
            merge(&[a.clone(), b]),
            Err(ImageError::Size { index: 1, .. })
        ));
        let empty = frame(2, vec![[1.0; 3]; 4], 0, None);
        assert!(matches!(merge(&[empty]), Err(ImageError::NoSamples)));
        assert!(matches!(merge(&[]), Err(ImageError::NoSamples)));
        // A render without an error estimate leaves the merge without one.
        assert_eq!(merge(&[a]).expect("merges").error_estimate, None);
    }

    #[test]
    fn combined_error_is_that_of_the_pooled_samples() {
        // Equal noise per sample: e_i = c / sqrt(spp_i), and the pooled
        // samples have c / sqrt(sum spp) = 1 / sqrt(sum 1 / e_i^2).
        let c = 0.8;
        let spp = [16u64, 48, 8];
        let parts: Vec<(u64, Option<f64>)> = spp
            .iter()
            .map(|&n| (n, Some(c / (n as f64).sqrt())))
            .collect();
        let e = combined_error(&parts).expect("estimate");
        assert!((e - c / 72f64.sqrt()).abs() < 1e-12, "{e}");
        let inverse: f64 = parts.iter().map(|p| 1.0 / p.1.map_or(1.0, |e| e * e)).sum();
        assert!((e - 1.0 / inverse.sqrt()).abs() < 1e-12);
        assert_eq!(combined_error(&[(4, Some(0.1)), (4, None)]), None);
        assert_eq!(combined_error(&[(0, None)]), None);
        assert_eq!(combined_error(&[(4, Some(0.1)), (0, None)]), Some(0.1));
    }

    /// SplitMix64: a fixed stream of test noise.
    struct Noise(u64);

    impl Noise {
        /// Uniform in [-1, 1): variance 1/3.
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
    }

    #[test]
    fn merged_error_estimate_matches_the_measured_error() {
        // Two noisy renders of a gradient: render i has per-pixel noise of
        // standard deviation s_i (its mean of spp_i samples of deviation
        // sigma) and says so in its estimate, as the server would:
        // sqrt(pixels * 3 * s_i^2) / S_i.
        let (width, height, sigma) = (64u32, 64u32, 0.5f64);
        let truth: Vec<[f32; 3]> = (0..width * height)
            .map(|i| {
                let v = 0.2 + f64::from(i % width) / f64::from(width);
                [v as f32, (0.5 * v) as f32, 1.0]
            })
            .collect();
        let mut noise = Noise(7);
        let render = |spp: u64, noise: &mut Noise| {
            let s = sigma / (spp as f64).sqrt();
            let amplitude = s * 3f64.sqrt(); // uniform [-a, a) has deviation a / sqrt(3)
            let pixels: Vec<[f32; 3]> = truth
                .iter()
                .map(|t| t.map(|v| (f64::from(v) + amplitude * noise.next()) as f32))
                .collect();
            let image = LinearImage {
                width,
                height,
                pixels,
            };
            let e = (truth.len() as f64 * 3.0 * s * s / image.sum_of_squares()).sqrt();
            LinearFrame {
                image,
                spp,
                error_estimate: Some(e),
                generation: 0,
            }
        };
        let a = render(16, &mut noise);
        let b = render(48, &mut noise);
        let m = merge(&[a.clone(), b.clone()]).expect("merges");
        let truth_image = LinearImage {
            width,
            height,
            pixels: truth.clone(),
        };
        let measured = (m
            .image
            .pixels
            .iter()
            .flatten()
            .zip(truth.iter().flatten())
            .map(|(&x, &t)| (f64::from(x) - f64::from(t)).powi(2))
            .sum::<f64>()
            / truth_image.sum_of_squares())
        .sqrt();
        let estimate = m.error_estimate.expect("an estimate");
        // 12,288 values: the measured RMS is within about 1% of its mean.
        assert!(
            (estimate / measured - 1.0).abs() < 0.05,
            "estimate {estimate}, measured {measured}"
        );
        // The merge has the error of 64 samples: half that of 16.
        let alone = a.error_estimate.expect("estimate");
        assert!((estimate / alone - 0.5).abs() < 0.02, "{estimate} {alone}");
        // And the status-only approximation agrees with the exact form.
        let approx = combined_error(&[(a.spp, a.error_estimate), (b.spp, b.error_estimate)])
            .expect("estimate");
        assert!(
            (approx / estimate - 1.0).abs() < 0.01,
            "{approx} {estimate}"
        );
    }
}
