//! What the image shows at a point: the first surface along the camera's
//! ray through it (through the pinhole or the lens's centre, whatever the
//! aperture), for "focus on the point under the cursor".

use crate::render::isa::Portable;
use crate::render::job::RenderJob;
use crate::render::math::DVec3;
use crate::render::world::Origin;
use serde::Serialize;

/// The surface under raster point (x, y).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pick {
    /// Where the ray meets it, in world space.
    pub point: [f64; 3],
    /// How far from the camera's position, along the ray.
    pub distance: f64,
    /// Its depth along the view axis: the `focus_distance` that makes it
    /// sharp (None where it lies behind the camera's plane, as a panorama
    /// can see).
    pub focus_distance: Option<f64>,
}

/// The first surface along the ray through raster (`x`, `y`) of `job`
/// (pixels, from the top left), for a camera at `position`; None where the
/// ray leaves the scene.
pub fn pick(job: &RenderJob, position: DVec3, x: f32, y: f32) -> Option<Pick> {
    let ray = job.camera.ray(x, y);
    let hit = job.world.intersect(Portable, &ray, Origin::NONE)?;
    // Camera space: the world is centred on the camera (`render::world`).
    let at = ray.origin + ray.dir * hit.t;
    let depth = f64::from(at.dot(job.camera.forward));
    Some(Pick {
        point: (position + at.as_dvec3()).to_array(),
        distance: f64::from(at.length()),
        focus_distance: (depth > 0.0).then_some(depth),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Quality, Scene};

    fn scene(camera: &str) -> Scene {
        let s = format!(
            r#"{{"camera": {camera},
               "materials": {{"m": {{"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}}}},
               "objects": [{{"type": "quad", "corner": [-10, -10, -7], "edge_u": [20, 0, 0], "edge_v": [0, 20, 0], "material": "m"}}]}}"#
        );
        Scene::from_json_str(&s).expect("valid")
    }

    #[test]
    fn the_pick_gives_the_depth_that_brings_the_point_into_focus() {
        // A wall at z = -7 seen from (0, 0, 1): 8 away along the axis.
        let s = scene(r#"{"position": [0, 0, 1], "look_at": [0, 0, 0], "vfov_deg": 60}"#);
        let job = RenderJob::new(&s, 64, 32, &Quality::default());
        let centre = pick(&job, s.camera.position, 32.0, 16.0).expect("the wall");
        assert!((centre.focus_distance.expect("in front") - 8.0).abs() < 1e-5);
        assert!((centre.distance - 8.0).abs() < 1e-5);
        assert!(centre
            .point
            .iter()
            .zip([0.0, 0.0, -7.0])
            .all(|(a, b)| (a - b).abs() < 1e-5));
        // Off-centre the ray is longer, its depth the same: the plane.
        let corner = pick(&job, s.camera.position, 1.0, 1.0).expect("the wall");
        assert!((corner.focus_distance.expect("in front") - 8.0).abs() < 1e-4);
        assert!(corner.distance > 9.0);
        // Looking away: nothing.
        let away = scene(r#"{"position": [0, 0, 1], "look_at": [0, 0, 2], "vfov_deg": 60}"#);
        let job = RenderJob::new(&away, 64, 32, &Quality::default());
        assert_eq!(pick(&job, away.camera.position, 32.0, 16.0), None);
    }
}
