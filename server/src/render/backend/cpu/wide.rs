//! Which copy of the render loop (and of the rays' loop the benchmarks
//! time) a CPU runs: one compiled for every CPU, one for AVX2 and FMA, and
//! one for AVX-512, each with the whole path loop inlined. All give the
//! same image, bit for bit (tested); the widest the CPU has is chosen at
//! run time, within the backend's cap.

use super::{span_lanes, span_packets, span_wide, span_with, Segment, Span};
use crate::render::bvh::PACKET;
#[cfg(target_arch = "x86_64")]
use crate::render::isa::{Avx2, Avx512};
use crate::render::isa::{Isa, Portable};
use crate::render::job::RenderJob;
use crate::render::ray::Ray;
use crate::render::world::flat::Flat;
use crate::render::world::{Hit, Origin, World};
use std::ops::Range;

/// The widest instruction set a [`super::CpuBackend`] may use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IsaCap {
    /// The widest this CPU has.
    #[default]
    Widest,
    /// AVX2 and FMA at most (to test that copy where the CPU has AVX-512).
    Avx2,
    /// The code every CPU runs.
    Portable,
}

/// The copy of the loops to run.
#[derive(Clone, Copy, Debug)]
pub(super) enum Wide {
    Portable,
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
    #[cfg(target_arch = "x86_64")]
    Avx512(Avx512),
}

impl Wide {
    /// The widest copy this CPU runs within `cap`.
    pub(super) fn detect(cap: IsaCap) -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if let (IsaCap::Widest, Some(isa)) = (cap, Avx512::detect()) {
                return Wide::Avx512(isa);
            }
            if let (IsaCap::Widest | IsaCap::Avx2, Some(isa)) = (cap, Avx2::detect()) {
                return Wide::Avx2(isa);
            }
        }
        let _ = cap;
        Wide::Portable
    }
}

/// The nearest hits of `rays` with `wide`'s kernels (the copy of the
/// traversal the render loop of the same width calls), in packets of
/// [`PACKET`] where `packets` says.
pub(super) fn hits_chunk(
    wide: Wide,
    world: &World,
    rays: &[(Ray, Origin)],
    packets: bool,
) -> Vec<Option<Hit>> {
    match wide {
        // SAFETY: an `Avx2` exists only where the CPU has AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx2(isa) => unsafe { hits_avx2(isa, world, rays, packets) },
        // SAFETY: an `Avx512` exists only where the CPU has AVX-512 F, VL,
        // BW and DQ, AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx512(isa) => unsafe { hits_avx512(isa, world, rays, packets) },
        Wide::Portable => hits_with(Portable, world, rays, packets),
    }
}

/// `hits_with` compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn hits_avx2(isa: Avx2, world: &World, rays: &[(Ray, Origin)], packets: bool) -> Vec<Option<Hit>> {
    hits_with(isa, world, rays, packets)
}

/// `hits_with` compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq")]
fn hits_avx512(
    isa: Avx512,
    world: &World,
    rays: &[(Ray, Origin)],
    packets: bool,
) -> Vec<Option<Hit>> {
    hits_with(isa, world, rays, packets)
}

#[inline(always)]
fn hits_with<I: Isa>(
    isa: I,
    world: &World,
    rays: &[(Ray, Origin)],
    packets: bool,
) -> Vec<Option<Hit>> {
    // A plain loop: an iterator's `collect` would put the traversal in a
    // function of its own, compiled without the caller's AVX2.
    let mut hits = Vec::with_capacity(rays.len());
    if packets {
        for group in rays.chunks(PACKET) {
            let n = group.len();
            let fresh = group.iter().all(|(_, from)| *from == Origin::NONE);
            let rays: [Ray; PACKET] = std::array::from_fn(|k| group[k.min(n - 1)].0);
            let mut found = [None; PACKET];
            if fresh {
                world.intersect_packet(isa, &rays[..n], &mut found[..n]);
            } else {
                for (k, (r, from)) in group.iter().enumerate() {
                    found[k] = world.intersect(isa, r, *from);
                }
            }
            hits.extend_from_slice(&found[..n]);
        }
        return hits;
    }
    for (r, from) in rays {
        hits.push(world.intersect(isa, r, *from));
    }
    hits
}

/// The loop that advances a render's paths.
#[derive(Clone, Copy, Debug)]
pub(super) enum Loop<'a> {
    /// Two at a time (`span_with`, or `span_packets` in a world of meshes).
    Pairs,
    /// In lanes, shaded one by one (`span_lanes`).
    Lanes,
    /// In lanes, shaded over lanes (`span_wide`), on these triangles.
    Wide(&'a Flat),
}

/// Adds the samples `segments` name to the pixels of `span`, which start
/// at pixel number `first` (row-major); returns how many were rejected.
/// Runs the copy of the loop `wide` names: `lanes` says which loop; the
/// lane loops as wide as the instruction set's float lanes (16, 8, or 4
/// for every CPU), filled across segments; the pair loops a segment at a
/// time.
pub(super) fn render_span(
    wide: Wide,
    job: &RenderJob,
    first: usize,
    mut span: Span<'_>,
    segments: &[Segment],
    lanes: Loop<'_>,
) -> u64 {
    if let Loop::Pairs = lanes {
        return (segments.iter())
            .map(|(pixels, samples)| {
                let sub = span.sub(pixels.clone());
                pairs_span(wide, job, first + pixels.start, sub, samples.clone())
            })
            .sum();
    }
    match wide {
        // SAFETY: an `Avx512` exists only where the CPU has AVX-512 F, VL,
        // BW and DQ, AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx512(isa) => unsafe {
            match lanes {
                Loop::Wide(flat) => wide_avx512(job, flat, first, span, segments),
                _ => lanes_avx512(isa, job, first, span, segments),
            }
        },
        // SAFETY: an `Avx2` exists only where the CPU has AVX2 and FMA.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx2(isa) => unsafe {
            match lanes {
                Loop::Wide(flat) => wide_avx2(job, flat, first, span, segments),
                _ => lanes_avx2(isa, job, first, span, segments),
            }
        },
        Wide::Portable => match lanes {
            Loop::Wide(flat) => span_wide::<4>(job, flat, first, span, segments),
            _ => span_lanes::<_, 4>(Portable, job, first, span, segments),
        },
    }
}

/// [`render_span`]'s pair loops, for one segment: samples `samples` of
/// every pixel of `span`.
fn pairs_span(
    wide: Wide,
    job: &RenderJob,
    first: usize,
    span: Span<'_>,
    samples: Range<u64>,
) -> u64 {
    // Two functions per instruction set, not one with both loops: inlined
    // into one, the mesh scenes' loop lost its gain (code placement).
    let packets = job.world.packets_pay();
    match wide {
        // SAFETY: as in `render_span`.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx512(isa) => unsafe {
            match packets {
                true => packets_avx512(isa, job, first, span, samples),
                false => span_avx512(isa, job, first, span, samples),
            }
        },
        // SAFETY: as in `render_span`.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        Wide::Avx2(isa) => unsafe {
            match packets {
                true => packets_avx2(isa, job, first, span, samples),
                false => span_avx2(isa, job, first, span, samples),
            }
        },
        Wide::Portable => match packets {
            true => span_packets(Portable, job, first, span, samples),
            false => span_with(Portable, job, first, span, samples),
        },
    }
}

/// `$name`: the loop `$body` compiled with the target features `$features`
/// for the token `$isa` (an unsafe call: the token is the caller's proof),
/// its samples given as `$samples`.
macro_rules! compiled_for {
    ($(#[$doc:meta])* $name:ident, $body:expr, $isa:ty, $samples:ty, $features:literal) => {
        $(#[$doc])*
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $features)]
        fn $name(isa: $isa, job: &RenderJob, first: usize, span: Span<'_>, samples: $samples) -> u64 {
            $body(isa, job, first, span, samples)
        }
    };
}

compiled_for!(
    /// `span_with` compiled for AVX2 and FMA.
    span_avx2, span_with, Avx2, Range<u64>, "avx2,fma"
);
compiled_for!(
    /// `span_packets` compiled for AVX2 and FMA.
    packets_avx2, span_packets, Avx2, Range<u64>, "avx2,fma"
);
compiled_for!(
    /// The lane loop, eight paths wide, compiled for AVX2 and FMA.
    lanes_avx2, span_lanes::<Avx2, 8>, Avx2, &[Segment], "avx2,fma"
);
compiled_for!(
    /// The lane loop, sixteen paths wide, compiled for AVX-512.
    lanes_avx512, span_lanes::<Avx512, 16>, Avx512, &[Segment],
    "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq"
);
compiled_for!(
    /// `span_with` compiled for AVX-512 (32 vector registers; the
    /// arithmetic is the AVX2 copy's, and so is the image).
    span_avx512, span_with, Avx512, Range<u64>, "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq"
);
compiled_for!(
    /// `span_packets` compiled for AVX-512: 4-6% faster than the AVX2 copy
    /// on `cornell-mesh` (docs/BENCHMARKS.md, "The traversal out of line").
    packets_avx512, span_packets, Avx512, Range<u64>,
    "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq"
);

/// The wide loop, eight paths wide, compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn wide_avx2(job: &RenderJob, flat: &Flat, first: usize, span: Span<'_>, s: &[Segment]) -> u64 {
    span_wide::<8>(job, flat, first, span, s)
}

/// The wide loop, sixteen paths wide, compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq")]
fn wide_avx512(job: &RenderJob, flat: &Flat, first: usize, span: Span<'_>, s: &[Segment]) -> u64 {
    span_wide::<16>(job, flat, first, span, s)
}
