//! The scene's environment as validated: a uniform colour, or an HDR map
//! (`render::envmap::EnvMap`, read by the scene's resolver once per file or asset
//! and shared by every scene and world that uses it).

use super::json::{EnvMapJson, EnvironmentJson};
use super::resolve::{ModelSource, Resolver};
use super::values::vec3;
use super::{SceneError, MAX_EMISSION};
use crate::render::envmap::EnvMap;
use crate::render::math::DVec3;
use std::sync::Arc;

/// An environment map with the scene's settings for it.
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    pub json: EnvMapJson,
    pub map: Arc<EnvMap>,
}

impl PartialEq for EnvironmentMap {
    /// The same settings and the same image (by identity: comparing a
    /// 4k map texel by texel would be a scan of 100 MB).
    fn eq(&self, other: &Self) -> bool {
        self.json == other.json && Arc::ptr_eq(&self.map, &other.map)
    }
}

fn radiance(path: &str, v: [f64; 3]) -> Result<DVec3, SceneError> {
    let e = vec3(path, v)?;
    if e.min_element() < 0.0 || e.max_element() > MAX_EMISSION {
        return Err(SceneError::new(
            path,
            format!("components must be between 0 and {MAX_EMISSION:e}"),
        ));
    }
    Ok(e)
}

/// The uniform radiance and the map of a scene's `environment`.
pub(super) fn environment(
    raw: Option<&EnvironmentJson>,
    resolver: &dyn Resolver,
) -> Result<(DVec3, Option<EnvironmentMap>), SceneError> {
    let j = match raw {
        None => return Ok((DVec3::ZERO, None)),
        Some(EnvironmentJson::Color(c)) => return Ok((radiance("environment", *c)?, None)),
        Some(EnvironmentJson::Map(j)) => j,
    };
    if !(j.intensity.is_finite() && (0.0..=MAX_EMISSION).contains(&j.intensity)) {
        return Err(SceneError::new(
            "environment.intensity",
            format!("must be between 0 and {MAX_EMISSION:e}"),
        ));
    }
    if !(j.rotation_deg.is_finite() && j.rotation_deg.abs() <= 1e6) {
        return Err(SceneError::new(
            "environment.rotation_deg",
            "must be a finite angle in degrees",
        ));
    }
    if let Some(b) = j.background {
        radiance("environment.background", b)?;
    }
    if j.map.is_empty() {
        return Err(SceneError::new(
            "environment.map",
            "must name an .hdr or .exr file or an uploaded asset",
        ));
    }
    let map = resolver
        .environment(ModelSource::of_map(&j.map))
        .map_err(|e| SceneError::new("environment.map", e))?;
    Ok((
        DVec3::ZERO,
        Some(EnvironmentMap {
            json: j.clone(),
            map,
        }),
    ))
}
