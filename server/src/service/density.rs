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
    pub spp: Vec<u64>,
    pub done: Vec<bool>,
}

impl Density {
    /// The film's tiles (a uniform film: every tile at its spp).
    pub fn of(film: &Film) -> Self {
        let tiles = film.tiles();
        let done = film.tiles_done();
        Self {
            cols: tiles.cols,
            rows: tiles.rows,
            spp: (0..tiles.count()).map(|t| film.tile_spp(t)).collect(),
            done: (0..tiles.count())
                .map(|t| done.get(t).copied().unwrap_or(false))
                .collect(),
        }
    }

    /// The fewest and the most samples of a tile.
    fn range(&self) -> (u64, u64) {
        let lo = self.spp.iter().copied().min().unwrap_or(0);
        (lo, self.spp.iter().copied().max().unwrap_or(0))
    }

    /// A film's tiles before any sample.
    pub fn empty(width: u32, height: u32) -> Self {
        let tiles = crate::render::adaptive::Tiles::new(width, height);
        Self {
            cols: tiles.cols,
            rows: tiles.rows,
            spp: vec![0; tiles.count()],
            done: vec![false; tiles.count()],
        }
    }

    /// Colour of a tile: samples on a log scale from the fewest (dark
    /// blue) to the most (yellow); done tiles in green.
    fn colour(&self, t: usize, (lo, hi): (u64, u64)) -> [u8; 4] {
        if self.done[t] {
            return [40, 200, 90, 255];
        }
        let span = ((hi.max(1) as f64).ln() - (lo.max(1) as f64).ln()).max(1e-9);
        let x = (((self.spp[t].max(1) as f64).ln() - (lo.max(1) as f64).ln()) / span) as f32;
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
        let bytes: Vec<u8> = (0..self.spp.len())
            .flat_map(|t| self.colour(t, range))
            .collect();
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
    }
}
