//! Camera, light, scene and quality updates, as the API and the WebSocket
//! accept them. Each turns JSON into a new validated scene or quality, or an
//! error that names the field.
//!
//! ```json
//! {"camera": {"position": [50, 52, 250], "look_at": [50, 40, 0], "vfov_deg": 40}}
//! {"light": {"position": [50, 70, 80], "color": [1, 0.8, 0.6], "intensity": 20}}
//! {"quality": {"max_depth": 4, "nee": false, "spp": null}}
//! {"quality": {"preset": "interactive", "seed": 3}}
//! {"scene": "cornell"}  or  {"scene": { ...scene JSON... }}
//! ```

use super::error::{parse_json, ApiError};
use crate::render::math::DVec3;
use crate::render::scene::{builtin, ImportKind, Shape, BUILTIN_NAMES, MAX_COORDINATE, MAX_EMISSION};
use crate::render::{Preset, Quality, Scene};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// `PATCH /camera`: any subset of the camera's fields.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPatch {
    pub position: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub up: Option<[f64; 3]>,
    pub vfov_deg: Option<f64>,
    pub near_clip: Option<f64>,
}

/// `PATCH /light`: move, recolour or rescale the scene's light.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightPatch {
    pub position: Option<[f64; 3]>,
    /// Colour with components in [0, 1]; emission = colour x intensity.
    pub color: Option<[f64; 3]>,
    pub intensity: Option<f64>,
}

/// The scene's light as the API reports it.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct LightStatus {
    /// Index of the light object in the scene's `objects`.
    pub index: usize,
    /// Centre of the sphere or quad.
    pub position: [f64; 3],
    pub color: [f64; 3],
    pub intensity: f64,
}

pub fn light_status(scene: &Scene) -> Option<LightStatus> {
    let index = scene.light?;
    let object = scene.objects.get(index)?;
    let emission = scene.materials[object.material].emission;
    let intensity = emission.max_element();
    let color = if intensity > 0.0 { emission / intensity } else { DVec3::ZERO };
    Some(LightStatus {
        index,
        position: scene.object_center(index).to_array(),
        color: color.to_array(),
        intensity,
    })
}

pub fn apply_camera(scene: &Scene, patch: &CameraPatch) -> Result<Scene, ApiError> {
    let mut json = scene.to_json();
    let c = json.camera.get_or_insert_with(|| scene.camera.to_json());
    if let Some(v) = patch.position {
        c.position = v;
    }
    if let Some(v) = patch.look_at {
        c.look_at = v;
    }
    if let Some(v) = patch.up {
        c.up = v;
    }
    if let Some(v) = patch.vfov_deg {
        c.vfov_deg = v;
    }
    if let Some(v) = patch.near_clip {
        c.near_clip = v;
    }
    scene.revalidate(&json).map_err(|e| ApiError::BadRequest(e.to_string()))
}

fn finite3(field: &str, v: [f64; 3], max: f64) -> Result<DVec3, ApiError> {
    if v.iter().all(|x| x.is_finite() && x.abs() <= max) {
        Ok(DVec3::from_array(v))
    } else {
        Err(ApiError::BadRequest(format!("light.{field}: components must be finite and within +-{max:e}")))
    }
}

pub fn apply_light(scene: &Scene, patch: &LightPatch) -> Result<Scene, ApiError> {
    let Some(index) = scene.light else {
        return Err(ApiError::BadRequest("light: the scene has no light to change".into()));
    };
    let mut s = scene.clone();
    if let Some(p) = patch.position {
        let to = finite3("position", p, MAX_COORDINATE)?;
        let by = to - s.object_center(index);
        s.move_object(index, by);
    }
    if patch.color.is_some() || patch.intensity.is_some() {
        let now = light_status(scene).ok_or_else(|| ApiError::Internal("light vanished".into()))?;
        let color = match patch.color {
            Some(c) => {
                let c = finite3("color", c, 1.0)?;
                if c.min_element() < 0.0 {
                    return Err(ApiError::BadRequest("light.color: components must be between 0 and 1".into()));
                }
                c
            }
            None if now.intensity > 0.0 => DVec3::from_array(now.color),
            None => DVec3::ONE,
        };
        let intensity = patch.intensity.unwrap_or(now.intensity);
        if !(intensity.is_finite() && (0.0..=MAX_EMISSION).contains(&intensity)) {
            return Err(ApiError::BadRequest(format!(
                "light.intensity: must be between 0 and {MAX_EMISSION:e} (got {intensity})"
            )));
        }
        // Give the light a material of its own if it shares one (a mesh's
        // come from its file: it gets one of the scene's instead).
        let m = s.objects[index].material;
        if let Shape::Import(k) = s.objects[index].shape {
            if s.imports[k].kind == ImportKind::Model {
                return Err(ApiError::BadRequest(
                    "light: the light is a whole model file; recolour it in the file, or place it as a mesh".into(),
                ));
            }
            let mut own = s.materials[m].clone();
            own.name = unique_name(&s, "light");
            own.imported = false;
            s.imports[k].json.material = Some(own.name.clone());
            s.materials.push(own);
            s.objects[index].material = s.materials.len() - 1;
        } else if s.objects.iter().enumerate().any(|(i, o)| i != index && o.material == m) {
            let mut own = s.materials[m].clone();
            own.name = unique_name(&s, &format!("{}-light", own.name));
            s.materials.push(own);
            s.objects[index].material = s.materials.len() - 1;
        }
        let m = s.objects[index].material;
        s.materials[m].emission = color * intensity;
    }
    s.revalidate(&s.to_json()).map_err(|e| ApiError::BadRequest(e.to_string()))
}

fn unique_name(s: &Scene, base: &str) -> String {
    let mut name = base.to_owned();
    let mut n = 2;
    while s.materials.iter().any(|m| m.name == name) {
        name = format!("{base}-{n}");
        n += 1;
    }
    name
}

/// A scene by built-in name (a JSON string) or as scene JSON (an object).
/// Names never reach the file system.
pub fn parse_scene(value: Value) -> Result<(String, Scene), ApiError> {
    match value {
        Value::String(name) => builtin(&name).map(|s| (name.clone(), s)).ok_or_else(|| {
            ApiError::BadRequest(format!("scene: unknown scene '{name}' (known: {})", BUILTIN_NAMES.join(", ")))
        }),
        value @ Value::Object(_) => Scene::from_json_value(value)
            .map(|s| ("custom".to_owned(), s))
            .map_err(|e| ApiError::BadRequest(format!("scene: {e}"))),
        _ => Err(ApiError::BadRequest("scene: must be a built-in scene name or a scene JSON object".into())),
    }
}

/// `current` with the fields of `patch` (a JSON object) replaced; a
/// `"preset"` field applies that preset first, the other fields over it.
pub fn apply_quality(current: &Quality, patch: &Value) -> Result<Quality, ApiError> {
    let Value::Object(fields) = patch else {
        return Err(ApiError::BadRequest("quality: must be a JSON object".into()));
    };
    let base = match fields.get("preset") {
        None => *current,
        Some(Value::String(name)) => Preset::from_name(name).map(|p| p.apply(*current)).ok_or_else(|| {
            ApiError::BadRequest(format!("quality.preset: unknown preset {name:?} (one of {})", Preset::names()))
        })?,
        Some(_) => return Err(ApiError::BadRequest(format!("quality.preset: must be one of {}", Preset::names()))),
    };
    let mut merged = serde_json::to_value(base).map_err(|e| ApiError::Internal(e.to_string()))?;
    if let Value::Object(m) = &mut merged {
        for (k, v) in fields.iter().filter(|(k, _)| *k != "preset") {
            m.insert(k.clone(), v.clone());
        }
    }
    let text = merged.to_string();
    // Positions in the merged text mean nothing to the client: drop them.
    let q: Quality = parse_json(text.as_bytes()).map_err(|e| match e {
        ApiError::BadRequest(m) => {
            let m = m.trim_start_matches("invalid JSON: ");
            let m = m.split(" at line ").next().unwrap_or(m);
            ApiError::BadRequest(format!("quality.{m}"))
        }
        other => other,
    })?;
    q.validate().map_err(|e| ApiError::BadRequest(e.to_string()))?;
    Ok(q)
}
