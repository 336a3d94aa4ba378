//! The validated scene model. Everything the renderer sees has been through
//! [`Scene::from_json_str`] or [`Scene::from_json`]: finite numbers, known
//! material names, positive radii, non-degenerate quads, a usable camera.
//! World coordinates stay in f64 here; the hot path gets camera-relative f32
//! (see `render::world`).

mod builtin;
mod edit;
mod json;
mod transform;
mod validate;

pub use builtin::{builtin, BUILTIN_NAMES};
pub use edit::{CameraEdit, EditError, LightEdit, LightInfo};
pub use json::{
    CameraJson, FresnelJson, GlassJson, MaterialJson, ObjectJson, QuadJson, SceneJson, SphereJson, SurfaceJson,
};

use crate::render::math::DVec3;

/// Most objects a scene may hold (intersection is a linear scan).
pub const MAX_OBJECTS: usize = 4096;
/// Largest coordinate or radius magnitude accepted (f32 keeps |c|^2 finite).
pub const MAX_COORDINATE: f64 = 1e15;
/// Largest emission component accepted.
pub const MAX_EMISSION: f64 = 1e20;

/// A scene input error: the JSON path of the offending field and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{path}: {reason}")]
pub struct SceneError {
    /// JSON path such as `objects[3].radius` (`.` for the whole document).
    pub path: String,
    pub reason: String,
}

impl SceneError {
    pub(crate) fn new(path: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            reason: reason.into(),
        }
    }
}

/// Pinhole camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    pub vfov_deg: f64,
    pub near_clip: f64,
}

/// Fresnel model of glass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fresnel {
    /// Unpolarised dielectric Fresnel equations.
    Exact,
    /// Schlick's approximation with smallpt's convention (cosine on the
    /// lower-index side).
    Schlick,
}

/// How a surface scatters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaterialKind {
    Diffuse,
    Mirror,
    Glass { ior: f64, fresnel: Fresnel },
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    /// Diffuse reflectance, mirror reflectance, or glass tint.
    pub albedo: DVec3,
    /// Emitted radiance, from both sides of the surface.
    pub emission: DVec3,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// Geometry of an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: DVec3,
        radius: f64,
    },
    /// Parallelogram corner + s*edge_u + t*edge_v; two-sided.
    Quad {
        corner: DVec3,
        edge_u: DVec3,
        edge_v: DVec3,
    },
}

/// A shape and the index of its material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Object {
    pub shape: Shape,
    pub material: usize,
}

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub camera: Camera,
    pub materials: Vec<Material>,
    pub objects: Vec<Object>,
    /// The object the `light` verb acts on, if the scene has one.
    pub light: Option<usize>,
}

impl Scene {
    /// Parses and validates scene JSON. Errors name the JSON path.
    pub fn from_json_str(text: &str) -> Result<Scene, SceneError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let value: serde_json::Value = serde_path_to_error::deserialize(de)
            .map_err(|e| SceneError::new(e.path().to_string(), e.into_inner().to_string()))?;
        Self::from_json_value(value)
    }

    /// Validates already parsed JSON (e.g. the `scene` field of a request).
    pub fn from_json_value(value: serde_json::Value) -> Result<Scene, SceneError> {
        Self::from_json(&SceneJson::from_value(value)?)
    }

    /// Validates an already parsed scene.
    pub fn from_json(raw: &SceneJson) -> Result<Scene, SceneError> {
        validate::scene(raw)
    }

    /// A scene given by built-in name or as a path to a JSON file.
    pub fn load(name_or_path: &str) -> Result<Scene, SceneError> {
        if let Some(scene) = builtin(name_or_path) {
            return Ok(scene);
        }
        let path = std::path::Path::new(name_or_path);
        if !path.exists() {
            return Err(SceneError::new(
                ".",
                format!(
                    "'{name_or_path}' is neither a built-in scene ({}) nor a file",
                    BUILTIN_NAMES.join(", ")
                ),
            ));
        }
        let text = std::fs::read_to_string(path)
            .map_err(|e| SceneError::new(".", format!("cannot read {name_or_path}: {e}")))?;
        Self::from_json_str(&text)
    }

    /// The scene back in its JSON form (round-trips through `from_json`).
    pub fn to_json(&self) -> SceneJson {
        validate::to_json(self)
    }

    /// Indices of objects whose material emits.
    pub fn emitters(&self) -> impl Iterator<Item = usize> + '_ {
        self.objects
            .iter()
            .enumerate()
            .filter(|(_, o)| self.materials[o.material].is_emissive())
            .map(|(i, _)| i)
    }
}
