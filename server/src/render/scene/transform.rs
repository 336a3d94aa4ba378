//! Whole-scene similarity transforms: uniform scale and translation. The
//! invariance checks use them; a scene's image must not change under either.

use super::{placement, Projection, Scene, Shape};
use crate::render::math::{DAffine3, DVec3};

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
        let map = DAffine3::from_scale_rotation_translation(
            DVec3::splat(scale),
            Default::default(),
            point(DVec3::ZERO),
        );
        for import in &mut s.imports {
            import.world_from_json = map * import.world_from_json;
            import.json.transform = placement::to_json(&import.world_from_json);
            for inst in &mut import.instances {
                inst.world_from_object = map * inst.world_from_object;
            }
        }
        s.camera.position = point(s.camera.position);
        s.camera.look_at = point(s.camera.look_at);
        s.camera.near_clip *= scale;
        s.camera.aperture *= scale;
        // An f-number's aperture is in metres: the scaled one is not.
        s.camera.f_number = None;
        if let Projection::Orthographic { height } = &mut s.camera.projection {
            *height *= scale;
        }
        s.camera.focus_distance = s.camera.focus_distance.map(|f| f * scale);
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
                Shape::Import(k) => Shape::Import(k),
            };
        }
        s
    }
}

impl Scene {
    /// The centre of object `i`: a sphere's centre, a quad's middle, the
    /// middle of a mesh's bounds.
    pub fn object_center(&self, i: usize) -> DVec3 {
        match self.objects[i].shape {
            Shape::Sphere { center, .. } => center,
            Shape::Quad {
                corner,
                edge_u,
                edge_v,
            } => corner + (edge_u + edge_v) * 0.5,
            Shape::Import(k) => super::frame::import_bounds(&self.imports[k])
                .map_or(DVec3::ZERO, |(lo, hi)| (lo + hi) * 0.5),
        }
    }

    /// Object `i` moved by `by`.
    pub fn move_object(&mut self, i: usize, by: DVec3) {
        let shape = &mut self.objects[i].shape;
        *shape = match *shape {
            Shape::Sphere { center, radius } => Shape::Sphere {
                center: center + by,
                radius,
            },
            Shape::Quad {
                corner,
                edge_u,
                edge_v,
            } => Shape::Quad {
                corner: corner + by,
                edge_u,
                edge_v,
            },
            Shape::Import(k) => {
                let import = &mut self.imports[k];
                import.world_from_json.translation += by;
                import.json.transform = placement::to_json(&import.world_from_json);
                for inst in &mut import.instances {
                    inst.world_from_object.translation += by;
                }
                Shape::Import(k)
            }
        };
    }
}
