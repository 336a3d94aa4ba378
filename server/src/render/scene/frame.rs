//! A camera for a scene that gives none: looking at the centre of
//! everything's bounds from the front (+z), a little above and to the
//! right, far enough that the bounding sphere fills the view.

use super::{Camera, Import, Object, Shape};
use crate::render::math::DVec3;

/// Vertical field of view of a framed camera, in degrees.
pub const FRAMED_VFOV_DEG: f64 = 40.0;

/// World-space bounds (min, max) of the objects, or None if there are none.
pub(super) fn bounds(objects: &[Object], imports: &[Import]) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut grow = |p: DVec3| {
        lo = lo.min(p);
        hi = hi.max(p);
    };
    for o in objects {
        match o.shape {
            Shape::Sphere { center, radius } => {
                grow(center - DVec3::splat(radius));
                grow(center + DVec3::splat(radius));
            }
            Shape::Quad {
                corner,
                edge_u,
                edge_v,
            } => {
                for p in [
                    corner,
                    corner + edge_u,
                    corner + edge_v,
                    corner + edge_u + edge_v,
                ] {
                    grow(p);
                }
            }
            Shape::Import(k) => {
                if let Some((a, b)) = import_bounds(&imports[k]) {
                    grow(a);
                    grow(b);
                }
            }
        }
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// World-space bounds of every placement of an import.
pub(super) fn import_bounds(import: &Import) -> Option<(DVec3, DVec3)> {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for inst in &import.instances {
        let (a, b) = inst.mesh.bounds().transformed(&inst.world_from_object);
        (lo, hi) = (lo.min(a), hi.max(b));
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// The framing camera for bounds (lo, hi).
pub(super) fn framed(lo: DVec3, hi: DVec3) -> Camera {
    let center = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-9 * center.abs().max_element().max(1.0));
    let half = (FRAMED_VFOV_DEG * 0.5).to_radians();
    let distance = radius / half.sin() * 1.05;
    let from = DVec3::new(0.35, 0.3, 1.0).normalize();
    Camera::pinhole(center + from * distance, center, FRAMED_VFOV_DEG)
}
