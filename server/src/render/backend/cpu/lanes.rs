//! The lane loop: `W` paths (4, 8 or 16, the instruction set's float
//! lanes) advanced bounce by bounce in step, so that their rays go to the
//! tracer together: each bounce's path rays as one packet, then the
//! shadow rays of the vertices just shaded as another (Embree's
//! `rtcIntersectN` and `rtcOccludedN` where it traces the world). Every
//! path is shaded as the pair loop shades it ([`Path::step`]), each lane
//! on its own; only where the rays go changes.
//!
//! In a world the own BVH traces, the rays go one at a time and a shadow
//! ray asks for its nearest hit, as in the pair loop: the image is the
//! pair loop's, bit for bit (tested). Through Embree, a shadow ray to a
//! flat emitter or a distant one is an occlusion test up to a thousandth
//! short of its point ([`Shadow::unblocked`]), which stops at the first
//! blocker; the image then differs from the pair loop's only where a
//! surface lies within that thousandth or Embree breaks a tie the other
//! way (measured in `tests/lane_loop.rs`).

use super::{Pairs, Segment, Span};
use crate::render::integrator::{Path, PathSettings, Shadow};
use crate::render::isa::Isa;
use crate::render::job::RenderJob;
use crate::render::lanes::lanes_where;
use crate::render::math::Vec3A;
use crate::render::world::{Hit, Origin, World};

/// Adds the samples `segments` name to the pixels of `span` (from pixel
/// `first`), `W` (pixel, sample) pairs at a time, in the pair loop's
/// order; returns how many were rejected.
#[inline(always)]
pub(super) fn span_lanes<I: Isa, const W: usize>(
    isa: I,
    job: &RenderJob,
    first: usize,
    mut span: Span<'_>,
    segments: &[Segment],
) -> u64 {
    let settings = &job.settings;
    let mut rejected = 0u64;
    let mut all = Pairs::new(segments);
    while let Some((pairs, count)) = all.group::<W>() {
        let mut paths: [Path; W] =
            std::array::from_fn(|k| pairs[k.min(count - 1)].path(job, first));
        trace_lanes(isa, &job.world, settings, &mut paths, count);
        for (pair, path) in pairs.iter().zip(&paths).take(count) {
            rejected += u64::from(!span.add(pair.i, pair.s, path, settings));
        }
    }
    rejected
}

/// Traces the first `count` of `paths` to their ends, bounce by bounce.
#[inline(always)]
fn trace_lanes<I: Isa, const W: usize>(
    isa: I,
    world: &World,
    settings: &PathSettings,
    paths: &mut [Path; W],
    count: usize,
) {
    let mut live: [bool; W] = std::array::from_fn(|k| k < count);
    loop {
        let rays = std::array::from_fn(|k| paths[k].ray);
        let from = std::array::from_fn(|k| paths[k].from);
        let hits = world.intersect_lanes(isa, &rays, &from, &live);
        // Every lane's surface loads (a mesh's vertices, which miss the
        // cache) start before the first lane shades.
        for k in lanes_where(&hits.each_ref().map(Hit::found)) {
            world.prefetch_surface(&hits[k]);
        }
        let mut shadows = [None; W];
        for k in lanes_where(&live) {
            let hit = hits[k].some();
            live[k] = paths[k].step::<true, I>(isa, world, settings, hit, &mut shadows[k]);
        }
        trace_shadows(isa, world, paths, &shadows);
        if !live.contains(&true) {
            break;
        }
    }
}

/// Traces the shadow rays the paths' last steps sent and adds what each
/// brings to its path.
#[inline(always)]
fn trace_shadows<I: Isa, const W: usize>(
    isa: I,
    world: &World,
    paths: &mut [Path; W],
    shadows: &[Option<Shadow>; W],
) {
    if !world.traced_by_embree() {
        for (path, shadow) in paths.iter_mut().zip(shadows) {
            if let Some(light) = shadow.and_then(|s| s.trace(isa, world)) {
                path.add_light(light);
            }
        }
        return;
    }
    // Lanes an occlusion test answers, and lanes whose emitter only the
    // nearest hit names.
    let (mut tested, mut named) = ([false; W], [false; W]);
    let (mut tmax, mut le) = ([0.0; W], [Vec3A::ZERO; W]);
    let (mut rays, mut from) = ([paths[0].ray; W], [Origin::NONE; W]);
    for k in lanes_where(&shadows.each_ref().map(Option::is_some)) {
        let Some(s) = &shadows[k] else {
            continue;
        };
        (rays[k], from[k]) = (s.ray, s.from);
        match s.unblocked(world) {
            Some((t, l)) => (tested[k], tmax[k], le[k]) = (true, t, l),
            None => named[k] = true,
        }
    }
    if tested.contains(&true) {
        if let Some(blocked) = world.occluded_lanes(isa, (&rays, &from, &tmax), &tested) {
            for k in lanes_where::<W>(&std::array::from_fn(|k| tested[k] & !blocked[k])) {
                if let Some(s) = &shadows[k] {
                    paths[k].add_light(s.light(le[k]));
                }
            }
        }
    }
    if named.contains(&true) {
        let hits = world.intersect_lanes(isa, &rays, &from, &named);
        for k in lanes_where(&named) {
            if let Some(s) = &shadows[k] {
                if let Some(l) = s.arriving(world, hits[k].some()) {
                    paths[k].add_light(s.light(l));
                }
            }
        }
    }
}
