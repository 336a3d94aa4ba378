//! The changes a client can make to a session, parsed from HTTP bodies and
//! WebSocket messages into validated values; [`super::session::Session::apply`]
//! applies them. Errors name the field.
//!
//! ```json
//! {"camera": {"position": [50, 52, 250], "look_at": [50, 40, 0], "vfov_deg": 40}}
//! {"light": {"position": [50, 70, 80], "color": [1, 0.8, 0.6], "intensity": 20}}
//! {"quality": {"max_depth": 4, "nee": false, "spp": null}}
//! {"quality": {"preset": "interactive", "seed": 3}}
//! {"scene": "cornell"}  or  {"scene": { ...scene JSON... }}
//! {"environment": {"map": ASSET_ID, "intensity": 2, "rotation_deg": 90}}  or  {"environment": [r, g, b]}
//! ```
//!
//! A WebSocket message may hold several keys. JSON objects have no order, so
//! they apply in a fixed one: `scene` first (a camera or light change in the
//! same message then applies to the new scene), then `environment`,
//! `camera`, `light` and `quality`.

use super::error::{parse_field, parse_json, ApiError};
use crate::render::envmap::EnvMap;
use crate::render::quality::Denoise;
use crate::render::scene::{
    builtin, CameraEdit, EnvironmentJson, LightEdit, LoadedModel, ModelSource, NoFiles, Resolver,
    SceneJson, BUILTIN_NAMES,
};
use crate::render::{Preset, Quality, Scene};
use serde_json::Value;
use std::sync::Arc;

/// One change to a session.
#[derive(Debug)]
pub enum Change {
    Camera(CameraEdit),
    Light(LightEdit),
    /// Quality fields to replace (a JSON object, merged at apply time onto
    /// the session's current quality by [`patch_quality`]).
    Quality(Value),
    /// A whole new scene: a built-in one by name, or `custom`.
    Scene {
        name: String,
        scene: Box<Scene>,
    },
    /// The scene's environment replaced; its map (an asset) already read.
    Environment {
        json: EnvironmentJson,
        map: Option<Arc<EnvMap>>,
    },
}

/// Serves the one map an environment change read (and nothing else).
struct Preloaded(Option<Arc<EnvMap>>);

impl Resolver for Preloaded {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        Err(NoFiles::refusal(source))
    }

    fn environment(&self, source: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        self.0.clone().ok_or_else(|| NoFiles::map_refusal(source))
    }
}

/// `scene` lit by the environment of a [`Change::Environment`].
pub fn with_environment(
    scene: &Scene,
    json: EnvironmentJson,
    map: Option<Arc<EnvMap>>,
) -> Result<Scene, ApiError> {
    scene
        .with_environment(json, &Preloaded(map))
        .map_err(|e| ApiError::BadRequest(e.to_string()))
}

/// What a scene sent to the server may use: meshes from `resolver` (the
/// server's assets; never files), at most `max_triangles` of them.
#[derive(Clone, Copy)]
pub struct SceneRules<'a> {
    pub resolver: &'a dyn Resolver,
    pub max_triangles: u64,
}

impl SceneRules<'static> {
    /// Built-in scenes and inline meshes only, no limit (tests).
    pub const INLINE_ONLY: SceneRules<'static> = SceneRules {
        resolver: &NoFiles,
        max_triangles: u64::MAX,
    };
}

impl Change {
    /// A scene by built-in name (a JSON string) or as scene JSON (an object)
    /// whose meshes `rules` allow. Names never reach the file system.
    pub fn scene(value: Value, rules: &SceneRules<'_>) -> Result<Change, ApiError> {
        let (name, scene) = match value {
            Value::String(name) => {
                let scene = builtin(&name).ok_or_else(|| {
                    ApiError::BadRequest(format!(
                        "scene: unknown scene '{name}' (known: {})",
                        BUILTIN_NAMES.join(", ")
                    ))
                })?;
                (name, scene)
            }
            value @ Value::Object(_) => {
                let bad =
                    |e: crate::render::SceneError| ApiError::BadRequest(format!("scene: {e}"));
                let scene = Scene::from_json_with(
                    &SceneJson::from_value(value).map_err(bad)?,
                    rules.resolver,
                )
                .map_err(bad)?;
                let triangles = scene.unique_triangles();
                if triangles > rules.max_triangles {
                    return Err(ApiError::BadRequest(format!(
                        "scene: {triangles} triangles is more than this server's limit of {} per session",
                        rules.max_triangles
                    )));
                }
                ("custom".to_owned(), scene)
            }
            _ => {
                return Err(ApiError::BadRequest(
                    "scene: must be a built-in scene name or a scene JSON object".into(),
                ))
            }
        };
        Ok(Change::Scene {
            name,
            scene: Box::new(scene),
        })
    }

    /// The scene's environment: `[r, g, b]`, or a map (an uploaded asset
    /// of `rules`' resolver) with its settings. The map is read now; the
    /// settings are checked when the change applies.
    pub fn environment(value: Value, rules: &SceneRules<'_>) -> Result<Change, ApiError> {
        let json =
            EnvironmentJson::from_value(value).map_err(|e| ApiError::BadRequest(e.to_string()))?;
        let map = match &json {
            EnvironmentJson::Color(_) => None,
            // A computed sky: made now (and cached), not under the session's
            // lock when the change applies; its settings' errors named.
            EnvironmentJson::Map(m) if m.map.is_empty() && m.sky.is_some() => {
                let sky = m.sky.as_ref().map(crate::render::scene::sky::setup);
                if let Some(setup) = sky
                    .transpose()
                    .map_err(|e| ApiError::BadRequest(e.to_string()))?
                {
                    crate::render::scene::sky::sky_map(&setup);
                }
                None
            }
            EnvironmentJson::Map(m) => Some(
                (rules.resolver.environment(ModelSource::of_map(&m.map)))
                    .map_err(|e| ApiError::BadRequest(format!("environment.map: {e}")))?,
            ),
        };
        Ok(Change::Environment { json, map })
    }

    /// One WebSocket message: a JSON object with any of the keys `scene`,
    /// `camera`, `light` and `quality`; the changes in that order.
    pub fn parse_message(text: &str, rules: &SceneRules<'_>) -> Result<Vec<Change>, ApiError> {
        let value: Value = parse_json(text.as_bytes())?;
        let Value::Object(map) = value else {
            return Err(ApiError::BadRequest(
                "message: must be a JSON object".into(),
            ));
        };
        Self::from_fields(map, rules)
    }

    /// The changes of a message's fields (any of `scene`, `camera`, `light`
    /// and `quality`), in that order.
    pub fn from_fields(
        mut map: serde_json::Map<String, Value>,
        rules: &SceneRules<'_>,
    ) -> Result<Vec<Change>, ApiError> {
        const ORDER: [&str; 5] = ["scene", "environment", "camera", "light", "quality"];
        if let Some(other) = map.keys().find(|k| !ORDER.contains(&k.as_str())) {
            return Err(ApiError::BadRequest(format!(
                "message: unknown key '{other}' (expected camera, environment, light, quality or scene)"
            )));
        }
        ORDER
            .iter()
            .filter_map(|&key| map.remove(key).map(|v| (key, v)))
            .map(|(key, v)| match key {
                "scene" => Change::scene(v, rules),
                "environment" => Change::environment(v, rules),
                "camera" => Ok(Change::Camera(parse_field(key, v)?)),
                "light" => Ok(Change::Light(parse_field(key, v)?)),
                _ => Ok(Change::Quality(v)),
            })
            .collect()
    }
}

/// `current` with the fields of `patch` (a JSON object) replaced; a
/// `"preset"` field applies that preset first, the other fields over it.
pub fn patch_quality(current: &Quality, patch: &Value) -> Result<Quality, ApiError> {
    let Value::Object(fields) = patch else {
        return Err(ApiError::BadRequest(
            "quality: must be a JSON object".into(),
        ));
    };
    let base = match fields.get("preset") {
        None => *current,
        Some(Value::String(name)) => Preset::from_name(name)
            .map(|p| p.apply(*current))
            .ok_or_else(|| {
                ApiError::BadRequest(format!(
                    "quality.preset: unknown preset {name:?} (one of {})",
                    Preset::names()
                ))
            })?,
        Some(_) => {
            return Err(ApiError::BadRequest(format!(
                "quality.preset: must be one of {}",
                Preset::names()
            )))
        }
    };
    let mut merged = serde_json::to_value(base).map_err(|e| ApiError::Internal(e.to_string()))?;
    if let Value::Object(m) = &mut merged {
        for (k, v) in fields.iter().filter(|(k, _)| *k != "preset") {
            m.insert(k.clone(), v.clone());
        }
    }
    let q: Quality = parse_field("quality", merged)?;
    q.validate()
        .map_err(|e| ApiError::BadRequest(e.to_string()))?;
    if q.denoise != Denoise::Off {
        crate::render::denoise::available()
            .map_err(|e| ApiError::BadRequest(format!("quality.denoise: {e}")))?;
    }
    Ok(q)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use serde_json::json;

    fn message(text: &str) -> Result<Vec<Change>, String> {
        Change::parse_message(text, &SceneRules::INLINE_ONLY).map_err(|e| e.to_string())
    }

    #[test]
    fn a_message_parses_into_changes_scene_first() {
        let changes = message(r#"{"quality": {"spp": 8}, "light": {"intensity": 3}, "camera": {"vfov_deg": 40}, "scene": "furnace"}"#).unwrap();
        assert_eq!(changes.len(), 4);
        assert!(matches!(&changes[0], Change::Scene { name, .. } if name == "furnace"));
        assert!(
            matches!(&changes[1], Change::Camera(c) if c.vfov_deg == Some(40.0) && c.position.is_none())
        );
        assert!(
            matches!(&changes[2], Change::Light(l) if l.intensity == Some(3.0) && l.color.is_none())
        );
        assert!(matches!(&changes[3], Change::Quality(q) if q == &json!({"spp": 8})));
        assert!(message("{}").unwrap().is_empty());
    }

    #[test]
    fn bad_messages_name_what_is_wrong() {
        let cases = [
            ("not json", "invalid JSON"),
            ("[1]", "message: must be a JSON object"),
            (
                r#"{"zoom": 1}"#,
                "message: unknown key 'zoom' (expected camera, environment, light, quality or scene)",
            ),
            (
                r#"{"camera": {"zoom": 2}}"#,
                "camera.zoom: unknown field `zoom`",
            ),
            (
                r#"{"camera": {"position": [1, 2]}}"#,
                "camera.position: invalid length 2",
            ),
            (
                r#"{"light": {"intensity": "bright"}}"#,
                "light.intensity: invalid type: string",
            ),
            (r#"{"light": 3}"#, "light: invalid type: integer `3`"),
            (
                r#"{"scene": "nope"}"#,
                "scene: unknown scene 'nope' (known: cornell",
            ),
            (
                r#"{"scene": 3}"#,
                "scene: must be a built-in scene name or a scene JSON object",
            ),
            (r#"{"scene": {"camera": {}}}"#, "scene: camera"),
        ];
        for (text, needle) in cases {
            let e = message(text).expect_err(text);
            assert!(
                e.starts_with(needle),
                "{text}: {e:?} does not start with {needle:?}"
            );
        }
    }

    #[test]
    fn a_scene_object_is_custom_and_validated() {
        let furnace = builtin("furnace").unwrap();
        let json = serde_json::to_value(furnace.to_json()).unwrap();
        let Change::Scene { name, scene } = Change::scene(json, &SceneRules::INLINE_ONLY).unwrap()
        else {
            panic!("a scene")
        };
        assert_eq!((name.as_str(), *scene), ("custom", furnace));
    }

    #[test]
    fn quality_patches_keep_the_fields_not_named() {
        let current = Quality {
            seed: 7,
            spp: Some(64),
            ..Quality::default()
        };
        let q = patch_quality(&current, &json!({"max_depth": 3, "spp": null})).unwrap();
        assert_eq!(
            (q.max_depth, q.spp, q.seed, q.nee),
            (3, None, 7, current.nee)
        );
        // A preset sets its knobs; a field beside it wins; seed and halts stay.
        let q = patch_quality(&current, &json!({"preset": "reference", "rr_depth": 2})).unwrap();
        let reference = Preset::Reference.apply(current);
        assert_eq!(
            (q.max_depth, q.nee, q.rr_depth, q.seed, q.spp),
            (reference.max_depth, reference.nee, 2, 7, Some(64))
        );
    }

    #[test]
    fn bad_quality_patches_name_the_field() {
        let q = Quality::default();
        let cases = [
            (json!([1, 2]), "quality: must be a JSON object"),
            (json!({"preset": "fast"}), "quality.preset: unknown preset \"fast\" (one of preview, interactive, final, reference)"),
            (json!({"preset": 3}), "quality.preset: must be one of"),
            (json!({"filter": "gauss"}), "quality.filter: unknown variant `gauss`"),
            (json!({"max_depth": -1}), "quality.max_depth: invalid value"),
            (json!({"colour": 1}), "quality.colour: unknown field `colour`"),
            (json!({"clamp": -1}), "quality.clamp"),
        ];
        for (patch, needle) in cases {
            let e = patch_quality(&q, &patch).expect_err(needle).to_string();
            assert!(
                e.starts_with(needle),
                "{patch}: {e:?} does not start with {needle:?}"
            );
        }
    }
}
