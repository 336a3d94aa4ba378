//! The scan accelerator: every sphere, eight at a time with `isa`'s
//! kernel, then every quad. For a handful of objects (the thesis's scenes)
//! nothing is faster.

use super::{Hit, Origin, NO_PRIM};
use crate::render::isa::Isa;
use crate::render::ray::Ray;
use crate::render::scene::MAX_PLACED;
use crate::render::shape::{Leaving, Quad, SphereBatch};

#[inline(always)]
pub(super) fn nearest<I: Isa>(
    isa: I,
    batches: &[SphereBatch],
    quads: &[(u32, Quad)],
    ray: &Ray,
    from: Origin,
) -> Hit {
    let leaving = Leaving {
        id: from.object as f32,
        entering: from.entering,
    };
    let (t, id) = isa.nearest_sphere(batches, ray, leaving);
    // id + 2^23 has the integer id in its low mantissa bits: no
    // saturating float-to-int conversion on the way to the material
    // (no world holds 2^23 objects).
    const _: () = assert!(MAX_PLACED < 1 << 23);
    let object = (id + 8_388_608.0).to_bits() & 0x7F_FFFF;
    let mut best = Hit {
        t,
        object,
        prim: NO_PRIM,
        bary: [0.0; 3],
    };
    for &(id, ref quad) in quads {
        if id == from.object {
            continue;
        }
        let t = quad.intersect_before(ray, best.t);
        if t < best.t {
            best.t = t;
            best.object = id;
        }
    }
    best
}
