//! Where an adaptive render put its samples: samples per pixel of every
//! tile, as a frame carries it and as `GET /api/sessions/{id}/samples.png`
//! draws it (one image pixel per tile, for the page's overlay).

use crate::render::film::Film;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};

/// Samples per pixel of each tile, and which tiles are done.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Density {
    pub cols: u32,
    pub rows: u32,
    /// Every tile's count while the film is uniform (no vectors then: a
    /// frame of a large uniform film is published many times a second).
    uniform: u64,
    /// Per tile once adaptive rounds begin (else empty).
    spp: Vec<u64>,
    done: Vec<bool>,
}

impl Density {
    /// The film's tiles.
    pub fn of(film: &Film) -> Self {
        let tiles = film.tiles();
        let mut d = Self {
            cols: tiles.cols,
            rows: tiles.rows,
            uniform: film.spp(),
            spp: Vec::new(),
            done: Vec::new(),
        };
        if film.adaptive_started() {
            d.spp = (0..tiles.count()).map(|t| film.tile_spp(t)).collect();
            d.done = film.tiles_done().to_vec();
        }
        d
    }

    /// A film's tiles before any sample.
    pub fn empty(width: u32, height: u32) -> Self {
        let tiles = crate::render::adaptive::Tiles::new(width, height);
        Self {
            cols: tiles.cols,
            rows: tiles.rows,
            uniform: 0,
            spp: Vec::new(),
            done: Vec::new(),
        }
    }

    /// Tile `t`'s samples per pixel.
    fn spp(&self, t: usize) -> u64 {
        self.spp.get(t).copied().unwrap_or(self.uniform)
    }

    /// Tiles at their share of the target error.
    pub fn done_count(&self) -> usize {
        self.done.iter().filter(|&&d| d).count()
    }

    /// The fewest and the most samples of a tile.
    fn range(&self) -> (u64, u64) {
        match self.spp.is_empty() {
            true => (self.uniform, self.uniform),
            false => (
                self.spp.iter().copied().min().unwrap_or(0),
                self.spp.iter().copied().max().unwrap_or(0),
            ),
        }
    }

    /// Colour of a tile: samples on a log scale from the fewest (dark
    /// blue) to the most (yellow); done tiles in green.
    fn colour(&self, t: usize, (lo, hi): (u64, u64)) -> [u8; 4] {
        if self.done.get(t) == Some(&true) {
            return [40, 200, 90, 255];
        }
        let span = ((hi.max(1) as f64).ln() - (lo.max(1) as f64).ln()).max(1e-9);
        let x = (((self.spp(t).max(1) as f64).ln() - (lo.max(1) as f64).ln()) / span) as f32;
        let stops = [
            [20.0, 20.0, 120.0],
            [200.0, 40.0, 120.0],
            [250.0, 230.0, 60.0],
        ];
        let (a, b, f) = if x < 0.5 {
            (stops[0], stops[1], x * 2.0)
        } else {
            (stops[1], stops[2], (x - 0.5) * 2.0)
        };
        let c = |i: usize| (a[i] + (b[i] - a[i]) * f).round().clamp(0.0, 255.0) as u8;
        [c(0), c(1), c(2), 255]
    }

    /// The map as an RGBA PNG, one pixel per tile.
    pub fn png(&self) -> Result<Vec<u8>, image::ImageError> {
        let range = self.range();
        let count = self.cols as usize * self.rows as usize;
        let bytes: Vec<u8> = (0..count).flat_map(|t| self.colour(t, range)).collect();
        let mut out = Vec::new();
        PngEncoder::new(&mut out).write_image(
            &bytes,
            self.cols,
            self.rows,
            ExtendedColorType::Rgba8,
        )?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_spans_the_fewest_to_the_most_samples() {
        let d = Density {
            cols: 3,
            rows: 1,
            uniform: 16,
            spp: vec![16, 64, 256],
            done: vec![false, false, true],
        };
        let r = d.range();
        assert_eq!(r, (16, 256));
        assert_eq!(d.colour(0, r), [20, 20, 120, 255]);
        assert_eq!(d.colour(1, r), [200, 40, 120, 255]);
        assert_eq!(d.colour(2, r), [40, 200, 90, 255]);
        let png = d.png().expect("png");
        let img = image::load_from_memory(&png).expect("decodes");
        assert_eq!((img.width(), img.height()), (3, 1));
        assert_eq!(d.done_count(), 1);
        // A uniform film: every tile at its count, none done.
        let u = Density {
            spp: Vec::new(),
            done: Vec::new(),
            ..d
        };
        assert_eq!((u.range(), u.done_count()), ((16, 16), 0));
        let img = image::load_from_memory(&u.png().expect("png")).expect("decodes");
        assert_eq!((img.width(), img.height()), (3, 1));
    }
}
