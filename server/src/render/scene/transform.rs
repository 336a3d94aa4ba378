//! Whole-scene similarity transforms: uniform scale and translation. The
//! invariance checks use them; a scene's image must not change under either.

use super::{Scene, Shape};
use crate::render::math::DVec3;

impl Scene {
    /// The scene with every length multiplied by `factor` (> 0). Radiance is
    /// unchanged, so the image must be too.
    pub fn scaled(&self, factor: f64) -> Scene {
        self.mapped(|p| p * factor, factor)
    }

    /// The scene moved by `offset`.
    pub fn translated(&self, offset: DVec3) -> Scene {
        self.mapped(|p| p + offset, 1.0)
    }

    fn mapped(&self, point: impl Fn(DVec3) -> DVec3, scale: f64) -> Scene {
        let mut s = self.clone();
        s.camera.position = point(s.camera.position);
        s.camera.look_at = point(s.camera.look_at);
        s.camera.near_clip *= scale;
        for o in &mut s.objects {
            o.shape = match o.shape {
                Shape::Sphere { center, radius } => Shape::Sphere {
                    center: point(center),
                    radius: radius * scale,
                },
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                } => Shape::Quad {
                    corner: point(corner),
                    edge_u: edge_u * scale,
                    edge_v: edge_v * scale,
                },
            };
        }
        s
    }
}
