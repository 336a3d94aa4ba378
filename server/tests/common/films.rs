//! Comparisons of two films of the same scene.

use pathstream::render::film::PixelSums;
use pathstream::render::Film;

/// How far two films are apart: pixels whose green sums differ by more
/// than 1% (a sample that went elsewhere: rounding alone moves a sum in
/// its last bits), and the relative difference of the images' sums.
pub fn apart(a: &Film, b: &Film) -> (usize, f64) {
    let green = |p: &PixelSums| p.even[1] + p.odd[1];
    let sum = |f: &Film| -> f64 { f.pixels().iter().map(green).sum() };
    let differ = (a.pixels().iter().zip(b.pixels()))
        .filter(|(x, y)| (green(x) - green(y)).abs() > 0.01 * green(y).abs().max(1e-3))
        .count();
    (differ, (sum(a) - sum(b)).abs() / sum(b))
}
