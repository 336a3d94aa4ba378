//! Packets of 4, 8 or 16 rays through the placed meshes at once
//! (`rtcIntersectN`, `rtcOccludedN`): the lane loop's queries, one call
//! for a batch of paths' rays instead of one a ray. Each ray is answered
//! as a query of its own would be (Embree's packet kernels walk the tree
//! for the live lanes together; a hit's distance may differ from the
//! single ray's in its last bits, `tests/embree.rs` measures it).

use super::{ffi, hit_id, run_filter, Filtered, HitFilter, RawHit, WorldScene};
use std::ffi::c_void;

/// A packet of `W` rays as Embree reads them, lane by lane, and after a
/// query its answers. A ray's `id` is its lane, for the filter.
pub struct Packet<const W: usize> {
    valid: Valid<W>,
    rays: ffi::RayHitN<W>,
}

impl<const W: usize> Packet<W> {
    /// A packet of no live lane.
    #[inline(always)]
    pub fn new() -> Self {
        const { assert!(W == 4 || W == 8 || W == 16) };
        Self {
            valid: Valid([0; W]),
            rays: ffi::RayHitN {
                org: [[0.0; W]; 3],
                tnear: [0.0; W],
                // A dead lane's direction is read too: zero made the
                // queries 4% slower (its reciprocals infinite).
                dir: [[1.0; W]; 3],
                time: [0.0; W],
                tfar: [0.0; W],
                mask: [u32::MAX; W],
                id: std::array::from_fn(|k| k as u32),
                flags: [0; W],
                ng: [[0.0; W]; 3],
                u: [0.0; W],
                v: [0.0; W],
                prim_id: [ffi::INVALID_ID; W],
                geom_id: [ffi::INVALID_ID; W],
                inst_id: [ffi::INVALID_ID; W],
            },
        }
    }

    /// Makes lane `k` live with the ray `org + t dir`, 0 <= t <= `tfar`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, org: [f32; 3], dir: [f32; 3], tfar: f32) {
        for a in 0..3 {
            self.rays.org[a][k] = org[a];
            self.rays.dir[a][k] = dir[a];
        }
        self.rays.tfar[k] = tfar;
        self.valid.0[k] = -1;
    }

    /// Every lane's ray at once (`org[a]`, `dir[a]`: axis `a` of each
    /// lane's origin and direction), 0 <= t <= `tfar[k]`, the lanes `live`
    /// names made live: whole arrays copied, not a lane at a time. A dead
    /// lane is not traced; its direction is set to ones (Embree reads its
    /// reciprocal).
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane `k` of several arrays
    pub fn set_lanes(
        &mut self,
        (org, dir): ([[f32; W]; 3], [[f32; W]; 3]),
        tfar: [f32; W],
        live: &[bool; W],
    ) {
        (self.rays.org, self.rays.tfar) = (org, tfar);
        for a in 0..3 {
            for k in 0..W {
                self.rays.dir[a][k] = if live[k] { dir[a][k] } else { 1.0 };
            }
        }
        for (v, &l) in self.valid.0.iter_mut().zip(live) {
            *v = -i32::from(l);
        }
    }

    /// After an intersection query, every lane's answer as arrays: the
    /// distance (infinite where a lane is dead or hit nothing), the
    /// object, the triangle and the barycentrics u, v.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lane `k` of several arrays
    pub fn answers(&self) -> Answers<W> {
        let p = &self.rays;
        let mut t = [f32::INFINITY; W];
        for k in 0..W {
            let hit = (self.valid.0[k] != 0) & (p.geom_id[k] != ffi::INVALID_ID);
            t[k] = if hit { p.tfar[k] } else { f32::INFINITY };
        }
        let mut id = [0; W];
        for k in 0..W {
            id[k] = hit_id(p.inst_id[k], p.geom_id[k]);
        }
        Answers {
            t,
            id,
            prim: p.prim_id,
            u: p.u,
            v: p.v,
        }
    }

    /// Whether lane `k` is live.
    #[inline(always)]
    pub fn live(&self, k: usize) -> bool {
        self.valid.0[k] != 0
    }

    /// After an intersection query: whether live lane `k` hit, and what
    /// Embree wrote there (meaningless where it did not), without a
    /// branch on either.
    #[inline(always)]
    pub fn answer(&self, k: usize) -> (bool, RawHit) {
        let p = &self.rays;
        (
            self.live(k) & (p.geom_id[k] != ffi::INVALID_ID),
            RawHit {
                t: p.tfar[k],
                id: hit_id(p.inst_id[k], p.geom_id[k]),
                prim: p.prim_id[k],
                u: p.u[k],
                v: p.v[k],
            },
        )
    }

    /// After an occlusion query: whether live lane `k`'s ray is blocked.
    #[inline(always)]
    pub fn blocked(&self, k: usize) -> bool {
        // `&`, not `&&`: no branch on whether the lane is live.
        self.live(k) & (self.rays.tfar[k] == f32::NEG_INFINITY)
    }
}

impl<const W: usize> Default for Packet<W> {
    fn default() -> Self {
        Self::new()
    }
}

/// A packet's answers, lane by lane ([`Packet::answers`]).
#[derive(Clone, Copy, Debug)]
pub struct Answers<const W: usize> {
    pub t: [f32; W],
    pub id: [u32; W],
    pub prim: [u32; W],
    pub u: [f32; W],
    pub v: [f32; W],
}

impl<const W: usize> Answers<W> {
    /// `self`'s answer in the lanes where `take`, else `other`'s.
    #[inline(always)]
    pub fn select(self, take: &[bool; W], other: &Answers<W>) -> Answers<W> {
        let pick = |k: usize| take[k];
        Answers {
            t: std::array::from_fn(|k| if pick(k) { self.t[k] } else { other.t[k] }),
            id: std::array::from_fn(|k| if pick(k) { self.id[k] } else { other.id[k] }),
            prim: std::array::from_fn(|k| if pick(k) { self.prim[k] } else { other.prim[k] }),
            u: std::array::from_fn(|k| if pick(k) { self.u[k] } else { other.u[k] }),
            v: std::array::from_fn(|k| if pick(k) { self.v[k] } else { other.v[k] }),
        }
    }
}

/// A packet's valid mask, aligned as Embree's vector loads want it.
#[repr(C, align(64))]
struct Valid<const W: usize>([i32; W]);

impl WorldScene {
    /// Runs `query` (one of the packet entry points for `W` rays) on
    /// `packet` with `filter`, if any.
    #[inline(always)]
    fn run_packet<F: HitFilter, const W: usize>(
        &self,
        query: ffi::PacketFn,
        valid: &Valid<W>,
        packet: &mut ffi::RayHitN<W>,
        (filter, coherent): (Option<&F>, bool),
    ) {
        let p = (packet as *mut ffi::RayHitN<W>).cast::<c_void>();
        let flags = match coherent {
            true => ffi::CONTEXT_FLAG_COHERENT,
            false => ffi::CONTEXT_FLAG_INCOHERENT,
        };
        match filter {
            None => {
                let mut context = ffi::Context::new(None);
                context.flags = flags;
                // SAFETY: a committed, live scene; the mask, context and
                // packet are valid, aligned as the header wants (64
                // bytes serves every width), and ours for the call; the
                // entry point is the one for packets of `W` rays.
                unsafe { query(valid.0.as_ptr(), self.scene, &mut context, p) };
            }
            Some(filter) => {
                let mut context = Filtered {
                    context: ffi::Context::new(Some(run_filter::<F>)),
                    filter,
                };
                context.context.flags = flags;
                let c = (&mut context as *mut Filtered<'_, F>).cast::<ffi::Context>();
                // SAFETY: as above; `context` starts with Embree's context
                // and lives through the call, in which `run_filter::<F>`
                // reads it back as a `Filtered<F>`.
                unsafe { query(valid.0.as_ptr(), self.scene, c, p) };
            }
        }
    }

    /// Answers each live lane of `packet` with its nearest hit that
    /// `filter` (if any) accepts ([`Packet::answer`]). `coherent`: the rays
    /// start together and go alike (a pixel's camera rays), which
    /// Embree's packet walk serves better told.
    #[inline(always)]
    pub fn intersect_lanes<F: HitFilter, const W: usize>(
        &self,
        packet: &mut Packet<W>,
        (filter, coherent): (Option<&F>, bool),
    ) {
        let (query, _) = self.embree.lib.api.packet_queries(W);
        self.run_packet(query, &packet.valid, &mut packet.rays, (filter, coherent));
    }

    /// Answers whether something `filter` (if any) accepts blocks each
    /// live lane's ray of `packet` ([`Packet::blocked`]).
    #[inline(always)]
    pub fn occluded_lanes<F: HitFilter, const W: usize>(
        &self,
        packet: &mut Packet<W>,
        filter: Option<&F>,
    ) {
        let (_, query) = self.embree.lib.api.packet_queries(W);
        self.run_packet(query, &packet.valid, &mut packet.rays, (filter, false));
    }
}
