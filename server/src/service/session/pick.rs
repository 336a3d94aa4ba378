//! `GET /api/sessions/{id}/pick?x=&y=`: the surface under a point of the
//! session's image (for focusing on it).

use super::{lock, Session};
use crate::render::pick::{pick, Pick};
use crate::service::error::ApiError;

impl Session {
    /// The surface under image point (`x`, `y`) (pixels of the session's
    /// image, from its top left), or None where the ray leaves the scene;
    /// a point outside the image is refused by name.
    pub fn pick(&self, x: f64, y: f64) -> Result<Option<Pick>, ApiError> {
        let (job, position) = {
            let st = lock(&self.state);
            (st.job.clone(), st.scene.camera.position)
        };
        for (name, v, size) in [("x", x, job.width()), ("y", y, job.height())] {
            if !(v >= 0.0 && v <= f64::from(size)) {
                return Err(ApiError::BadRequest(format!(
                    "{name}: must be within the image, 0 to {size} pixels (got {v})"
                )));
            }
        }
        Ok(pick(&job, position, x as f32, y as f32))
    }
}
