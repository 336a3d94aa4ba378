//! Checks of numbers every validator applies: finite, and for positions
//! within [`MAX_COORDINATE`]. Errors name the JSON path.

use super::{SceneError, MAX_COORDINATE};
use crate::render::math::DVec3;

type Result<T> = std::result::Result<T, SceneError>;

pub(super) fn finite(path: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(SceneError::new(
            path,
            format!("must be a finite number (got {x})"),
        ))
    }
}

pub(super) fn vec3(path: &str, v: [f64; 3]) -> Result<DVec3> {
    for (i, x) in v.iter().enumerate() {
        finite(&format!("{path}[{i}]"), *x)?;
    }
    Ok(DVec3::from_array(v))
}

/// A position or direction: finite and within [`MAX_COORDINATE`].
pub(super) fn point(path: &str, v: [f64; 3]) -> Result<DVec3> {
    let p = vec3(path, v)?;
    if p.abs().max_element() > MAX_COORDINATE {
        return Err(SceneError::new(
            path,
            format!("coordinates must be within +-{MAX_COORDINATE:e}"),
        ));
    }
    Ok(p)
}
