//! The (pixel, sample) pairs a render's loops trace, in the order their
//! samples reach the film: pixel by pixel, each pixel's samples in index
//! order.

use crate::render::integrator::Path;
use crate::render::job::RenderJob;
use crate::render::math::Vec3A;
use std::collections::VecDeque;
use std::ops::Range;

/// A (pixel, sample) pair of a run of pixels: pixel `i` of the run,
/// sample `s`. Pairs go pixel by pixel, each pixel's samples in index
/// order: the order they reach the film.
#[derive(Clone, Copy)]
pub(super) struct Pair {
    pub i: usize,
    pub s: u64,
}

impl Pair {
    /// The pair after this one, with samples `samples` per pixel.
    #[inline(always)]
    pub fn next(self, samples: &Range<u64>) -> Pair {
        match self.s + 1 < samples.end {
            true => Pair {
                s: self.s + 1,
                ..self
            },
            false => Pair {
                i: self.i + 1,
                s: samples.start,
            },
        }
    }

    /// Up to `N` pairs from this one on, in a run of `n` pixels with
    /// samples `samples` each: the pairs (the rest copies of this one), how
    /// many, and the pair after them.
    #[inline(always)]
    pub fn group<const N: usize>(self, n: usize, samples: &Range<u64>) -> ([Pair; N], usize, Pair) {
        let (mut pairs, mut count, mut at) = ([self; N], 0, self);
        while count < N && at.i < n {
            pairs[count] = at;
            count += 1;
            at = at.next(samples);
        }
        (pairs, count, at)
    }

    /// The first pair of a run with samples `samples`.
    #[inline(always)]
    pub fn first(samples: &Range<u64>) -> Pair {
        Pair {
            i: 0,
            s: samples.start,
        }
    }

    /// The pair's camera path, its run starting at pixel `first`.
    #[inline(always)]
    pub fn path(self, job: &RenderJob, first: usize) -> Path {
        let (p, width) = (first + self.i, job.width() as usize);
        job.camera_path((p % width) as u32, (p / width) as u32, self.s)
    }
}

/// Pixels of a span (indices into it) and the samples each of them gets.
pub(super) type Segment = (Range<usize>, Range<u64>);

/// The (pixel, sample) pairs of a span's segments in order: each
/// segment's pixels one by one, each pixel's samples in index order (the
/// order they reach the film). The lane loops fill their lanes from it
/// across segments: an adaptive round gives a two-pixel tile a few
/// samples, and a group of sixteen lanes per tile would run part empty.
pub(super) struct Pairs<'a> {
    segs: &'a [Segment],
    /// The segment `at` is in (`segs.len()`: done).
    seg: usize,
    at: Pair,
}

impl<'a> Pairs<'a> {
    #[inline(always)]
    pub fn new(segs: &'a [Segment]) -> Self {
        let mut pairs = Pairs {
            segs,
            seg: 0,
            at: Pair { i: 0, s: 0 },
        };
        pairs.enter(0);
        pairs
    }

    /// Moves to the first pair of the first non-empty segment from `seg`.
    #[inline(always)]
    fn enter(&mut self, mut seg: usize) {
        while let Some((pixels, samples)) = self.segs.get(seg) {
            if !pixels.is_empty() && !samples.is_empty() {
                break;
            }
            seg += 1;
        }
        self.seg = seg;
        if let Some((pixels, samples)) = self.segs.get(seg) {
            self.at = Pair {
                i: pixels.start,
                s: samples.start,
            };
        }
    }

    /// The next pair; None once every segment is done.
    #[inline(always)]
    pub fn next(&mut self) -> Option<Pair> {
        let (pixels, samples) = self.segs.get(self.seg)?;
        let pair = self.at;
        self.at = pair.next(samples);
        if self.at.i >= pixels.end {
            self.enter(self.seg + 1);
        }
        Some(pair)
    }

    /// Up to `N` pairs from here on (the rest copies of the first) and how
    /// many; None once every segment is done.
    #[inline(always)]
    pub fn group<const N: usize>(&mut self) -> Option<([Pair; N], usize)> {
        let first = self.next()?;
        let (mut pairs, mut count) = ([first; N], 1);
        while count < N {
            let Some(pair) = self.next() else { break };
            pairs[count] = pair;
            count += 1;
        }
        Some((pairs, count))
    }
}

/// The radiance of paths that end out of order (the wide loop refills its
/// lanes as their paths end), handed on in the order the paths started:
/// the film's order, so that each pixel's sums are added as the other
/// loops add them. (The sums are f64, which add f32 radiance exactly
/// unless a pixel's samples span some nine orders of magnitude; in this
/// order they are the same bits always.)
#[derive(Default)]
pub(super) struct InOrder {
    /// The number of the oldest path not handed on.
    next: u64,
    /// The paths from `next` on: each pair, and its radiance once ended.
    waiting: VecDeque<(Pair, Option<Vec3A>)>,
}

impl InOrder {
    /// Takes a path about to start on `pair`; its number.
    #[inline(always)]
    pub fn push(&mut self, pair: Pair) -> u64 {
        self.waiting.push_back((pair, None));
        self.next + self.waiting.len() as u64 - 1
    }

    /// Path `number` ended with radiance `l`.
    #[inline(always)]
    pub fn finish(&mut self, number: u64, l: Vec3A) {
        self.waiting[(number - self.next) as usize].1 = Some(l);
    }

    /// Hands `add` every ended path older than the oldest one running, in
    /// the order they started.
    #[inline(always)]
    pub fn flush(&mut self, mut add: impl FnMut(Pair, Vec3A)) {
        while let Some(&(pair, Some(l))) = self.waiting.front() {
            self.waiting.pop_front();
            self.next += 1;
            add(pair, l);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair of `segments` one at a time, as the pair loops visit them.
    fn one_by_one(segments: &[Segment]) -> Vec<(usize, u64)> {
        let mut all = Vec::new();
        for (pixels, samples) in segments {
            for i in pixels.clone() {
                all.extend(samples.clone().map(|s| (i, s)));
            }
        }
        all
    }

    fn grouped<const N: usize>(segments: &[Segment]) -> Vec<(usize, u64)> {
        let (mut pairs, mut all) = (Pairs::new(segments), Vec::new());
        while let Some((group, count)) = pairs.group::<N>() {
            assert!((1..=N).contains(&count));
            all.extend(group[..count].iter().map(|p| (p.i, p.s)));
        }
        all
    }

    #[test]
    fn groups_fill_across_segments_in_the_film_order() {
        let cases: [Vec<Segment>; 5] = [
            vec![(0..5, 3..10)],
            vec![
                (0..2, 16..19),
                (2..4, 16..21),
                (4..6, 16..16),
                (6..8, 20..21),
            ],
            vec![(0..0, 0..4), (3..5, 0..0), (5..7, 8..9)],
            vec![],
            vec![(2..3, 5..6)],
        ];
        for segments in &cases {
            let want = one_by_one(segments);
            assert_eq!(grouped::<4>(segments), want, "{segments:?}");
            assert_eq!(grouped::<16>(segments), want, "{segments:?}");
        }
    }

    #[test]
    fn paths_that_end_out_of_order_are_handed_on_in_order() {
        let segments = [(0..6, 0..3)];
        let mut pairs = Pairs::new(&segments);
        let mut order = InOrder::default();
        let mut handed = Vec::new();
        let mut running: Vec<(u64, Pair)> = Vec::new();
        // Start four, end them in a shuffled order, refill as they end.
        for _ in 0..4 {
            let pair = pairs.next().expect("a pair");
            running.push((order.push(pair), pair));
        }
        let mut turn = 0usize;
        while !running.is_empty() {
            turn = (turn * 7 + 3) % running.len().max(1);
            let (number, _) = running.swap_remove(turn);
            order.finish(number, Vec3A::splat(number as f32));
            order.flush(|p, l| handed.push((p.i, p.s, l.x as u64)));
            if let Some(pair) = pairs.next() {
                running.push((order.push(pair), pair));
            }
        }
        let want: Vec<(usize, u64, u64)> = (one_by_one(&segments).into_iter())
            .enumerate()
            .map(|(n, (i, s))| (i, s, n as u64))
            .collect();
        assert_eq!(handed, want);
    }
}
