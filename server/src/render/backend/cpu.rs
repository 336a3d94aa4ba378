//! The rayon backend: rows in parallel, each pixel's samples in index order.
//!
//! A row is rendered by one function with the whole path loop inlined into
//! it, compiled for every CPU, for AVX2 and FMA, and for AVX-512; the
//! widest the CPU has is chosen at run time (`wide`). All give the same
//! image, bit for bit. Paths are traced two at a time, side by side; where
//! Embree traces the world, 4, 8 or 16 at a time in lanes, their rays in
//! Embree's packets (`lanes`, [`PathLoop`]).

use crate::render::adaptive::{TileWork, TILE_SIZE};
use crate::render::features::{self, FeatureSums};
use crate::render::film::{Film, PixelSums};
use crate::render::integrator::{Path, PathSettings};
use crate::render::isa::Isa;
use crate::render::job::RenderJob;
use crate::render::math::Vec3A;
use crate::render::ray::Ray;
use crate::render::world::{Hit, Origin, World, EMBREE_MIN_TRIANGLES};
use rayon::prelude::*;
use std::ops::Range;
use std::sync::Arc;

#[derive(Debug, Default)]
pub struct CpuBackend {
    /// Why `auto` (or a failing device) left OpenCL, if it did.
    fallback_reason: Option<String>,
    /// A pool of its own (the server's, at low priority); None: rayon's global pool.
    pool: Option<Arc<rayon::ThreadPool>>,
    /// The widest kernels it may use (the widest the CPU has but in tests).
    cap: IsaCap,
    /// Where meshes are traced through Embree (where it is installed).
    embree: EmbreeUse,
    /// Which loop traces the paths.
    paths: PathLoop,
}

/// How the CPU advances its paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PathLoop {
    /// Where Embree traces the world (its packets serve lanes): in the
    /// wide loop where it serves the world (`wide_loop`), else in
    /// lanes; in pairs elsewhere.
    #[default]
    Auto,
    /// Always in lanes, shaded one by one (to test the lane loop against
    /// the pair loop and the wide loop).
    Lanes,
    /// Always in pairs.
    Pairs,
}

/// Where the CPU traces meshes through Embree rather than its own BVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EmbreeUse {
    /// In worlds of at least [`EMBREE_MIN_TRIANGLES`] triangles.
    #[default]
    LargeMeshes,
    /// In every world with meshes (to compare the two).
    AllMeshes,
    /// Never.
    Never,
}

impl CpuBackend {
    /// The rayon backend standing in for OpenCL, and why.
    pub fn fallback(reason: String) -> Self {
        Self {
            fallback_reason: Some(reason),
            ..Self::default()
        }
    }

    /// A backend whose render threads run at lower scheduling priority, so
    /// that on a busy machine the service's own threads (requests, frame
    /// encoding, WebSockets) still get the cores at once. Rendering takes
    /// whatever they leave, which is nearly everything. `threads`: how many
    /// render threads (None: one per core).
    pub fn low_priority(threads: Option<usize>) -> Self {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .thread_name(|i| format!("render-cpu-{i}"))
            .start_handler(|_| super::priority::lower_current_thread())
            .build()
            .map(Arc::new)
            .map_err(|e| tracing::warn!("no low-priority render pool ({e}); using the global one"))
            .ok();
        Self {
            pool,
            ..Self::default()
        }
    }

    /// This backend using at most the kernels `cap` names.
    pub fn isa_cap(self, cap: IsaCap) -> Self {
        Self { cap, ..self }
    }

    /// This backend tracing meshes through Embree where `embree` says.
    pub fn with_embree(self, embree: EmbreeUse) -> Self {
        Self { embree, ..self }
    }

    /// This backend advancing paths as `paths` says.
    pub fn with_paths(self, paths: PathLoop) -> Self {
        Self { paths, ..self }
    }

    /// Which loop advances `job`'s paths.
    fn path_loop<'j>(&self, job: &'j RenderJob) -> Loop<'j> {
        match self.paths {
            PathLoop::Auto if job.world.traced_by_embree() => match wide_loop::serves(job) {
                Some(flat) => Loop::Wide(flat),
                None => Loop::Lanes,
            },
            PathLoop::Auto | PathLoop::Pairs => Loop::Pairs,
            PathLoop::Lanes => Loop::Lanes,
        }
    }

    pub fn device(&self) -> String {
        let threads = self
            .pool
            .as_ref()
            .map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
        // Only once a world has loaded it: asking must not start Embree.
        let embree = match (self.embree, crate::render::embree::loaded()) {
            (EmbreeUse::Never, _) | (_, None) => String::new(),
            (EmbreeUse::LargeMeshes, Some(e)) => {
                let k = EMBREE_MIN_TRIANGLES / 1000;
                format!(", meshes of {k}k+ triangles through Embree {}", e.version)
            }
            (EmbreeUse::AllMeshes, Some(e)) => format!(", meshes through Embree {}", e.version),
        };
        match &self.fallback_reason {
            Some(why) => format!("rayon, {threads} threads{embree}; {why}"),
            None => format!("rayon, {threads} threads{embree}"),
        }
    }

    /// Lets `job`'s world trace through Embree where this backend may and
    /// the world can (built once per world).
    fn prepare(&self, job: &RenderJob) {
        match self.embree {
            EmbreeUse::LargeMeshes => job.world.use_embree(EMBREE_MIN_TRIANGLES),
            EmbreeUse::AllMeshes => job.world.use_embree(0),
            EmbreeUse::Never => false,
        };
    }

    /// Runs `work` on this backend's pool (or rayon's global one).
    fn in_pool<T: Send>(&self, work: impl FnOnce() -> T + Send) -> T {
        match &self.pool {
            Some(pool) => pool.install(work),
            None => work(),
        }
    }

    /// Adds samples `film.next_sample() ..` `+ count` to every pixel.
    pub fn render(&mut self, job: &RenderJob, film: &mut Film, count: u64) {
        self.render_unless(job, film, count, &|| false);
    }

    /// As [`CpuBackend::render`], but gives up between rows once `cancelled`
    /// says so; returns false then, and the film is left half-updated (the
    /// caller throws it away).
    pub fn render_unless(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        count: u64,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> bool {
        self.prepare(job);
        let lanes = self.path_loop(job);
        let first = film.next_sample();
        let width = film.width() as usize;
        let wide = Wide::detect(self.cap);
        let work = |film: &mut Film| -> Option<u64> {
            let (pixels, feats) = film.parts_mut(job.settings.features);
            let n = pixels.len();
            (pixels.par_chunks_mut(width))
                .zip(features::chunks(feats, 0..n, width))
                .enumerate()
                .map(|(y, (row, f))| {
                    if cancelled() {
                        return None;
                    }
                    let span = Span::new(row, f);
                    let segments = [(0..width, first..first + count)];
                    Some(render_span(wide, job, y * width, span, &segments, lanes))
                })
                .sum()
        };
        let rejected = self.in_pool(|| work(film));
        rejected.map(|r| film.commit(count, r)).is_some()
    }

    /// Adds sample `film.next_sample()` to the pixels from `film.slice_start()` up
    /// to `end`, in chunks of [`SLICE_CHUNK`] pixels in parallel; gives up
    /// between chunks once `cancelled` says so (false then, and the film is
    /// thrown away). Every pixel gets the same number as from
    /// [`CpuBackend::render`].
    pub fn render_slice(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        end: usize,
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> bool {
        self.prepare(job);
        let lanes = self.path_loop(job);
        let (start, sample) = (film.slice_start(), film.next_sample());
        let wide = Wide::detect(self.cap);
        let work = |film: &mut Film| -> Option<u64> {
            let (pixels, feats) = film.parts_mut(job.settings.features);
            (pixels[start..end].par_chunks_mut(SLICE_CHUNK))
                .zip(features::chunks(feats, start..end, SLICE_CHUNK))
                .enumerate()
                .map(|(k, (chunk, f))| {
                    if cancelled() {
                        return None;
                    }
                    let first = start + k * SLICE_CHUNK;
                    let segments = [(0..chunk.len(), sample..sample + 1)];
                    let span = Span::new(chunk, f);
                    Some(render_span(wide, job, first, span, &segments, lanes))
                })
                .sum()
        };
        let rejected = self.in_pool(|| work(film));
        rejected.map(|r| film.commit_slice(end, r)).is_some()
    }
}

impl CpuBackend {
    /// Adds `work` (adaptive tiles, each from its own next sample on) to
    /// `film`, the touched rows in parallel; gives up between rows once
    /// `cancelled` says so (false then, and the film is thrown away).
    pub fn render_tiles(
        &mut self,
        job: &RenderJob,
        film: &mut Film,
        work: &[TileWork],
        cancelled: &(dyn Fn() -> bool + Sync),
    ) -> bool {
        let (Some(first), Some(last)) = (work.first(), work.last()) else {
            return true;
        };
        self.prepare(job);
        let lanes = self.path_loop(job);
        let tiles = *film.tiles();
        let width = film.width() as usize;
        // Each entry with the sample its tile is at; entries by tile row.
        let entries: Vec<(TileWork, u64)> = work
            .iter()
            .map(|w| (*w, film.tile_spp(w.tile as usize)))
            .collect();
        let row_of = |w: &TileWork| w.tile / tiles.cols;
        let (y0, y1) = (
            (row_of(first) * TILE_SIZE) as usize,
            ((row_of(last) + 1) * TILE_SIZE).min(tiles.height) as usize,
        );
        let wide = Wide::detect(self.cap);
        let rows = |film: &mut Film| -> Option<u64> {
            let (pixels, feats) = film.parts_mut(job.settings.features);
            let (from, to) = (y0 * width, y1 * width);
            (pixels[from..to].par_chunks_mut(width))
                .zip(features::chunks(feats, from..to, width))
                .enumerate()
                .map(|(k, (row, mut f))| {
                    if cancelled() {
                        return None;
                    }
                    let y = y0 + k;
                    let tile_row = y as u32 / TILE_SIZE;
                    let from = entries.partition_point(|(w, _)| row_of(w) < tile_row);
                    let to = entries.partition_point(|(w, _)| row_of(w) <= tile_row);
                    // The row's tiles as segments of one span, so that the
                    // lane loops fill their lanes across tiles.
                    let segments: Vec<Segment> = (entries[from..to].iter())
                        .map(|(w, at)| {
                            let (xs, _) = tiles.rect(w.tile as usize);
                            let pixels = xs.start as usize..xs.end as usize;
                            (pixels, *at..at + u64::from(w.count))
                        })
                        .collect();
                    let span = Span::new(row, f.as_deref_mut());
                    Some(render_span(wide, job, y * width, span, &segments, lanes))
                })
                .sum()
        };
        let rejected = self.in_pool(|| rows(film));
        rejected.map(|r| film.commit_tiles(work, r)).is_some()
    }
}

/// A run of pixels' radiance sums, and their feature sums where the film
/// keeps them (as long).
struct Span<'a> {
    sums: &'a mut [PixelSums],
    features: Option<&'a mut [FeatureSums]>,
}

impl<'a> Span<'a> {
    fn new(sums: &'a mut [PixelSums], features: Option<&'a mut [FeatureSums]>) -> Self {
        debug_assert!(features.as_ref().is_none_or(|f| f.len() == sums.len()));
        Self { sums, features }
    }

    /// The pixels `pixels` of this span, as a span of their own.
    #[inline(always)]
    fn sub(&mut self, pixels: Range<usize>) -> Span<'_> {
        Span {
            sums: &mut self.sums[pixels.clone()],
            features: self.features.as_deref_mut().map(|f| &mut f[pixels]),
        }
    }

    /// Adds sample `sample` of pixel `i` (the path `p` traced); false
    /// where its radiance was rejected.
    #[inline(always)]
    fn add(&mut self, i: usize, sample: u64, p: &Path, settings: &PathSettings) -> bool {
        if let Some(f) = &mut self.features {
            f[i].add(p.guide());
        }
        self.sums[i].add(sample, p.radiance(settings))
    }

    /// Adds sample `sample` of pixel `i`, radiance `l` (clamped already),
    /// where no features are gathered; false where it was rejected.
    #[inline(always)]
    fn add_radiance(&mut self, i: usize, sample: u64, l: Vec3A) -> bool {
        debug_assert!(self.features.is_none());
        self.sums[i].add(sample, l)
    }
}

/// Pixels one rayon task of a slice renders (small: a slice may be a few
/// hundred pixels of a very expensive scene, and every core should help).
pub const SLICE_CHUNK: usize = 16;

/// The nearest hit of every ray (leaving the surface it names), in
/// parallel on rayon's threads with the widest kernels this CPU has: what
/// the benchmarks time as rays per second.
pub fn nearest_hits(world: &World, rays: &[(Ray, Origin)]) -> Vec<Option<Hit>> {
    let wide = Wide::detect(IsaCap::Widest);
    rays.par_chunks(4096)
        .flat_map_iter(|chunk| hits_chunk(wide, world, chunk, false))
        .collect()
}

/// [`nearest_hits`] with the rays in packets of [`crate::render::bvh::PACKET`] after one
/// another ([`World::intersect_packet`]), as the render loop traces its
/// camera rays: the same hits. Rays that leave a surface go one by one.
pub fn nearest_hits_packets(world: &World, rays: &[(Ray, Origin)]) -> Vec<Option<Hit>> {
    let wide = Wide::detect(IsaCap::Widest);
    rays.par_chunks(4096)
        .flat_map_iter(|chunk| hits_chunk(wide, world, chunk, true))
        .collect()
}

/// Traces paths `$a` and, if `$pair`, `$b` to their ends, bounce by
/// bounce, starting from their cameras rays' hits `$hit_a` and `$hit_b`:
/// each bounce traces both paths' rays before shading either, so that the
/// processor overlaps the two (independent) intersection tests, and the
/// second path's surface is prefetched while the first shades.
/// A macro, not a function: the loop stays in its caller's body, compiled
/// and inlined as before (as a function it cost smallpt 15%, measured).
macro_rules! trace_two {
    ($isa:expr, $job:expr, ($a:ident, $hit_a:expr), ($b:ident, $hit_b:expr), $pair:expr) => {{
        let (world, settings) = (&$job.world, &$job.settings);
        let (mut live_a, mut live_b) = (true, $pair);
        let meshes = !world.instances.is_empty();
        let (mut hit_a, mut hit_b) = ($hit_a, $hit_b);
        loop {
            // The second path's surface loads (a mesh's vertices, which
            // miss the cache) start while the first shades.
            if let (true, Some(h)) = (meshes, &hit_b) {
                world.prefetch_surface(h);
            }
            live_a = live_a && $a.advance($isa, world, settings, hit_a);
            live_b = live_b && $b.advance($isa, world, settings, hit_b);
            if !(live_a || live_b) {
                break;
            }
            hit_a = if live_a {
                world.intersect($isa, &$a.ray, $a.from)
            } else {
                None
            };
            hit_b = if live_b {
                world.intersect($isa, &$b.ray, $b.from)
            } else {
                None
            };
        }
    }};
}

/// The samples of a run of pixels, with the whole path loop inlined here
/// so that it is compiled for the caller's instruction set. Pairs go two
/// at a time, side by side ([`trace_two`]): two samples of a pixel, or
/// with one sample per pixel (a slice, or a 512x512 pass on two cores)
/// two neighbouring pixels (20% faster than one path at a time,
/// measured). Each pixel gets its samples in index order. In a world of
/// meshes [`span_packets`] runs instead.
#[inline(always)]
fn span_with<I: Isa>(
    isa: I,
    job: &RenderJob,
    first: usize,
    mut span: Span<'_>,
    samples: Range<u64>,
) -> u64 {
    let (world, settings) = (&job.world, &job.settings);
    let n = span.sums.len();
    let mut rejected = 0u64;
    let mut at = Pair::first(&samples);
    while at.i < n && at.s < samples.end {
        let then = at.next(&samples);
        let pair = then.i < n;
        let mut a = at.path(job, first);
        let mut b = if pair { then.path(job, first) } else { a };
        let hit_a = world.intersect(isa, &a.ray, a.from);
        let hit_b = if pair {
            world.intersect(isa, &b.ray, b.from)
        } else {
            None
        };
        trace_two!(isa, job, (a, hit_a), (b, hit_b), pair);
        rejected += u64::from(!span.add(at.i, at.s, &a, settings));
        if pair {
            rejected += u64::from(!span.add(then.i, then.s, &b, settings));
        }
        at = then.next(&samples);
    }
    rejected
}

mod lanes;
mod packets;
mod pairs;
mod wide;
mod wide_loop;
mod wide_surfaces;
use lanes::span_lanes;
use packets::span_packets;
use pairs::{Pair, Pairs, Segment};
pub use wide::IsaCap;
use wide::{hits_chunk, render_span, Loop, Wide};
use wide_loop::span_wide;
