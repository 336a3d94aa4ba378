//! The scene's environment as validated: a uniform colour, or an HDR map
//! (`render::envmap::EnvMap`, read by the scene's resolver once per file or asset
//! and shared by every scene and world that uses it).

use super::json::{EnvMapJson, EnvironmentJson};
use super::resolve::{ModelSource, Resolver};
use super::values::vec3;
use super::{Scene, SceneError, MAX_EMISSION};
use crate::render::envmap::sky_model::SunDisc;
use crate::render::envmap::EnvMap;
use crate::render::math::DVec3;
use std::sync::Arc;

/// An environment map with the scene's settings for it.
#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    pub json: EnvMapJson,
    pub map: Arc<EnvMap>,
    /// A computed sky's sun (map frame, before `intensity` and rotation).
    pub sun: Option<SunDisc>,
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
    let (map, sun) = match (&j.sky, j.map.is_empty()) {
        (Some(_), false) => {
            return Err(SceneError::new(
                "environment",
                "give a map or a sky, not both",
            ))
        }
        (Some(sky), true) => super::sky::sky_map(&super::sky::setup(sky)?),
        (None, true) => {
            return Err(SceneError::new(
                "environment.map",
                "must name an .hdr or .exr file or an uploaded asset (or give a sky)",
            ))
        }
        (None, false) => {
            let map = resolver
                .environment(ModelSource::of_map(&j.map))
                .map_err(|e| SceneError::new("environment.map", e))?;
            (map, None)
        }
    };
    Ok((
        DVec3::ZERO,
        Some(EnvironmentMap {
            json: j.clone(),
            map,
            sun,
        }),
    ))
}

impl Scene {
    /// This scene lit by `environment` instead: its map, where it names
    /// one, is this scene's own if it is the same, else read by `resolver`.
    pub fn with_environment(
        &self,
        environment: EnvironmentJson,
        resolver: &dyn Resolver,
    ) -> Result<Scene, SceneError> {
        let mut json = self.to_json();
        json.environment = Some(environment);
        self.revalidate_with(&json, resolver)
    }

    /// The environment as scene JSON gives it (a colour, black included).
    pub fn environment_json(&self) -> EnvironmentJson {
        match &self.environment_map {
            Some(m) => EnvironmentJson::Map(m.json.clone()),
            None => EnvironmentJson::Color(self.environment.to_array()),
        }
    }
}
