//! Images at another resolution than the film's: a preview (a view
//! rendered at 1/k of the resolution, shown scaled up) and any image
//! averaged down to a stream's width.

use crate::render::Film;
use std::sync::Arc;

/// A view rendered at 1/`factor` of the film's resolution, one sample.
#[derive(Debug)]
pub struct Preview {
    pub factor: u32,
    pub width: u32,
    pub height: u32,
    /// Mean radiance, row-major.
    pub pixels: Vec<[f32; 3]>,
}

impl Preview {
    /// The preview a one-sample `film` of the preview job holds.
    pub fn of(film: &Film, factor: u32) -> Arc<Self> {
        Arc::new(Self {
            factor,
            width: film.width(),
            height: film.height(),
            pixels: film.mean(),
        })
    }

    /// The pixel covering image pixel (x, y).
    #[inline]
    fn at(&self, x: u32, y: u32) -> [f32; 3] {
        let (px, py) = (
            (x / self.factor).min(self.width - 1),
            (y / self.factor).min(self.height - 1),
        );
        self.pixels[(py * self.width + px) as usize]
    }

    /// The image (`width` x `height`) the preview shows, scaled up.
    pub fn scaled_up(&self, width: u32, height: u32) -> Vec<[f32; 3]> {
        let mut out = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            out.extend((0..width).map(|x| self.at(x, y)));
        }
        out
    }

    /// The preview as an image `width` pixels wide (the aspect kept):
    /// averaged down, or each pixel repeated (nearest) up.
    pub fn resized(&self, width: u32) -> (u32, u32, Vec<[f32; 3]>) {
        if width <= self.width {
            return downscale(&self.pixels, self.width, self.height, width);
        }
        let height =
            (u64::from(self.height) * u64::from(width)).div_ceil(u64::from(self.width)) as u32;
        let mut out = Vec::with_capacity(width as usize * height as usize);
        for y in 0..height {
            let py = (u64::from(y) * u64::from(self.height) / u64::from(height)) as u32;
            out.extend((0..width).map(|x| {
                let px = (u64::from(x) * u64::from(self.width) / u64::from(width)) as u32;
                self.pixels[(py * self.width + px) as usize]
            }));
        }
        (width, height, out)
    }

    /// Puts the preview into `mean` (the film's, row-major) wherever the
    /// film has no sample yet: from pixel `from` on (the first sample's
    /// slice in progress).
    pub fn fill(&self, mean: &mut [[f32; 3]], width: u32, from: usize) {
        for (i, p) in mean.iter_mut().enumerate().skip(from) {
            *p = self.at(i as u32 % width, i as u32 / width);
        }
    }
}

/// `pixels` (w x h, row-major) averaged down to `width` columns and the
/// rows that keep the aspect ratio: each output pixel is the mean of the
/// input pixels whose indices fall in its footprint (in linear radiance,
/// before tone mapping).
pub fn downscale(pixels: &[[f32; 3]], w: u32, h: u32, width: u32) -> (u32, u32, Vec<[f32; 3]>) {
    let width = width.clamp(1, w);
    let height = ((u64::from(h) * u64::from(width)).div_ceil(u64::from(w)) as u32).clamp(1, h);
    let span = |o: u32, out: u32, n: u32| {
        let a = (u64::from(o) * u64::from(n) / u64::from(out)) as usize;
        let b = (u64::from(o + 1) * u64::from(n)).div_ceil(u64::from(out)) as usize;
        a..b.max(a + 1)
    };
    let mut out = Vec::with_capacity(width as usize * height as usize);
    for oy in 0..height {
        let ys = span(oy, height, h);
        for ox in 0..width {
            let xs = span(ox, width, w);
            let mut sum = [0f64; 3];
            for y in ys.clone() {
                for x in xs.clone() {
                    let p = pixels[y * w as usize + x];
                    for c in 0..3 {
                        sum[c] += f64::from(p[c]);
                    }
                }
            }
            let n = (ys.len() * xs.len()) as f64;
            out.push(sum.map(|v| (v / n) as f32));
        }
    }
    (width, height, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscaling_keeps_the_mean_and_the_aspect() {
        let (w, h) = (10u32, 6u32);
        let pixels: Vec<[f32; 3]> = (0..w * h)
            .map(|i| [i as f32, 1.0, (i % 3) as f32])
            .collect();
        let (dw, dh, small) = downscale(&pixels, w, h, 5);
        assert_eq!((dw, dh), (5, 3));
        // 2x2 blocks: the first is pixels 0, 1, 10, 11.
        assert_eq!(small[0], [5.5, 1.0, (0.0 + 1.0 + 1.0 + 2.0) / 4.0]);
        let mean = |p: &[[f32; 3]]| p.iter().map(|v| f64::from(v[0])).sum::<f64>() / p.len() as f64;
        assert!((mean(&small) - mean(&pixels)).abs() < 1e-9);
        let (_, _, same) = downscale(&pixels, w, h, 10);
        assert_eq!(same, pixels);
        assert_eq!(downscale(&pixels, w, h, 1).0, 1);
    }
}
