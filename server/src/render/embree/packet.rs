//! Packets of 4, 8 or 16 rays through the placed meshes at once
//! (`rtcIntersectN`, `rtcOccludedN`): the lane loop's queries, one call
//! for a batch of paths' rays instead of one a ray. Each ray is answered
//! as a query of its own would be (Embree's packet kernels walk the tree
//! for the live lanes together; a hit's distance may differ from the
//! single ray's in its last bits, `tests/embree.rs` measures it).

use super::{ffi, hit_id, run_filter, Filtered, HitFilter, RawHit, WorldScene};
use std::ffi::c_void;

/// A packet of `W` rays (origins `org`, directions `dir`, each from 0 to
/// its `tfar`), lane `k` live where `live[k]`, and its valid mask. A
/// ray's `id` is its lane, for the filter.
#[inline(always)]
fn packet<const W: usize>(
    org: &[[f32; 3]; W],
    dir: &[[f32; 3]; W],
    tfar: &[f32; W],
    live: &[bool; W],
) -> (Valid<W>, ffi::RayHitN<W>) {
    let mut p = ffi::RayHitN {
        org: [[0.0; W]; 3],
        tnear: [0.0; W],
        dir: [[0.0; W]; 3],
        time: [0.0; W],
        tfar: *tfar,
        mask: [u32::MAX; W],
        id: std::array::from_fn(|k| k as u32),
        flags: [0; W],
        ng: [[0.0; W]; 3],
        u: [0.0; W],
        v: [0.0; W],
        prim_id: [ffi::INVALID_ID; W],
        geom_id: [ffi::INVALID_ID; W],
        inst_id: [ffi::INVALID_ID; W],
    };
    for k in 0..W {
        for a in 0..3 {
            p.org[a][k] = org[k][a];
            p.dir[a][k] = dir[k][a];
        }
    }
    (Valid(live.map(|l| if l { -1 } else { 0 })), p)
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

    /// The nearest hit of each live lane's ray `org[k] + t dir[k]`, 0 <= t
    /// <= `tfar[k]`, that `filter` (if any) accepts; `W` is 4, 8 or 16.
    /// `coherent`: the rays start together and go alike (a pixel's camera
    /// rays), which Embree's packet walk serves better told.
    #[inline(always)]
    pub fn intersect_lanes<F: HitFilter, const W: usize>(
        &self,
        (org, dir, tfar): (&[[f32; 3]; W], &[[f32; 3]; W], &[f32; W]),
        live: &[bool; W],
        (filter, coherent): (Option<&F>, bool),
    ) -> [Option<RawHit>; W] {
        const { assert!(W == 4 || W == 8 || W == 16) };
        let (valid, mut p) = packet(org, dir, tfar, live);
        let (query, _) = self.embree.lib.api.packet_queries(W);
        self.run_packet(query, &valid, &mut p, (filter, coherent));
        std::array::from_fn(|k| {
            (live[k] && p.geom_id[k] != ffi::INVALID_ID).then_some(RawHit {
                t: p.tfar[k],
                id: hit_id(p.inst_id[k], p.geom_id[k]),
                prim: p.prim_id[k],
                u: p.u[k],
                v: p.v[k],
            })
        })
    }

    /// Whether something `filter` (if any) accepts blocks each live
    /// lane's ray before its `tfar`; `W` is 4, 8 or 16.
    #[inline(always)]
    pub fn occluded_lanes<F: HitFilter, const W: usize>(
        &self,
        (org, dir, tfar): (&[[f32; 3]; W], &[[f32; 3]; W], &[f32; W]),
        live: &[bool; W],
        filter: Option<&F>,
    ) -> [bool; W] {
        const { assert!(W == 4 || W == 8 || W == 16) };
        let (valid, mut p) = packet(org, dir, tfar, live);
        let (_, query) = self.embree.lib.api.packet_queries(W);
        self.run_packet(query, &valid, &mut p, (filter, false));
        std::array::from_fn(|k| live[k] && p.tfar[k] == f32::NEG_INFINITY)
    }
}
