//! The pair loop in groups whose camera rays go through the BVH as one
//! packet: the render loop of worlds of meshes (`World::packets_pay`).

use super::{Pair, Span};
use crate::render::bvh::PACKET;
use crate::render::integrator::Path;
use crate::render::isa::Isa;
use crate::render::job::RenderJob;
use crate::render::ray::Ray;
use std::ops::Range;

/// [`span_with`] in groups of up to [`PACKET`] pairs (a pixel's samples,
/// or with few samples per pixel neighbouring pixels'): the group's camera
/// rays go through the BVH as one packet ([`World::intersect_packet`]: the
/// same hits), then its paths two at a time. 5-6% faster on `cornell-mesh`
/// at depth 6; the sphere scenes, which have no BVH to share, lost 5% to
/// the groups' bookkeeping and keep the plain loop (docs/BENCHMARKS.md,
/// "A pixel's camera rays as one packet").
#[inline(always)]
pub(super) fn span_packets<I: Isa>(
    isa: I,
    job: &RenderJob,
    first: usize,
    mut span: Span<'_>,
    samples: Range<u64>,
) -> u64 {
    let settings = &job.settings;
    let n = span.sums.len();
    let mut rejected = 0u64;
    let mut at = Pair::first(&samples);
    while at.i < n && at.s < samples.end {
        // The group: up to PACKET pairs from `at` on.
        let (pairs, count, next) = at.group::<PACKET>(n, &samples);
        at = next;
        let mut paths: [Path; PACKET] =
            std::array::from_fn(|k| pairs[k.min(count - 1)].path(job, first));
        let rays: [Ray; PACKET] = std::array::from_fn(|k| paths[k].ray);
        let mut hits = [None; PACKET];
        job.world
            .intersect_packet(isa, &rays[..count], &mut hits[..count]);
        for k in (0..count).step_by(2) {
            let pair = k + 1 < count;
            let (head, tail) = paths.split_at_mut(k + 1);
            let (a, b) = (&mut head[k], &mut tail[0]);
            let hit_b = if pair { hits[k + 1] } else { None };
            trace_two!(isa, job, (a, hits[k]), (b, hit_b), pair);
            rejected += u64::from(!span.add(pairs[k].i, pairs[k].s, a, settings));
            if pair {
                rejected += u64::from(!span.add(pairs[k + 1].i, pairs[k + 1].s, b, settings));
            }
        }
    }
    rejected
}
