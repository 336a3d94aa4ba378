//! The scene JSON v1 wire format, as serde types. Nothing here is validated:
//! `super::validate` turns these into a [`super::Scene`].
//!
//! ```json
//! {
//!   "camera": {"position": [50, 52, 295.6], "look_at": [50, 51.957388, 294.6],
//!              "up": [0, 1, 0], "vfov_deg": 28.797, "near_clip": 140},
//!   "materials": {
//!     "white": {"type": "diffuse", "albedo": [0.75, 0.75, 0.75]},
//!     "glass": {"type": "glass", "ior": 1.5, "fresnel": "exact"},
//!     "lamp":  {"type": "diffuse", "albedo": [0, 0, 0], "emission": [12, 12, 12]}
//!   },
//!   "objects": [
//!     {"type": "sphere", "center": [73, 16.5, 78], "radius": 16.5, "material": "glass"},
//!     {"type": "quad", "corner": [1, 0, 0], "edge_u": [0, 0, 170],
//!      "edge_v": [0, 81.6, 0], "material": "white"},
//!     {"type": "sphere", "center": [50, 66.6, 81.6], "radius": 7, "material": "lamp"}
//!   ],
//!   "light": 2
//! }
//! ```
//!
//! Meshes and whole model files (see `super::import`), a background:
//!
//! ```json
//! {"objects": [
//!    {"type": "mesh", "file": "bunny.ply", "material": "white",
//!     "transform": {"translate": [0, 1, 0], "rotate": {"axis": [0, 1, 0], "deg": 30}, "scale": 10}},
//!    {"type": "mesh", "asset": "3f2a...", "transform": {"matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}},
//!    {"type": "mesh", "data": {"positions": [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0,1,2]]}, "material": "lamp"},
//!    {"type": "model", "file": "room.glb"}
//!  ],
//!  "environment": [0.2, 0.2, 0.25]}
//! ```
//! `camera` may be left out (the scene is then framed on its bounds, or a
//! model's own camera is used), and so may `materials`.

pub use super::map_json::{ColorInput, NormalJson, ScalarInput};
use super::SceneError;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;

/// A whole scene. Parse it with [`SceneJson::from_value`], which reports the
/// full JSON path of any error, also inside tagged materials and objects.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SceneJson {
    /// None: framed automatically (or a model file's own camera).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraJson>,
    pub materials: BTreeMap<String, MaterialJson>,
    pub objects: Vec<ObjectJson>,
    /// Index of the object that the `light` API verb moves and recolours.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<usize>,
    /// Radiance of rays that leave the scene (default black): a colour or
    /// an HDR map.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub environment: Option<EnvironmentJson>,
}

/// A clear sky's settings: the API's own type (`pathstream_wire::Sky`).
pub use pathstream_wire::Sky as SkyJson;

/// `environment`: `[r, g, b]`, `{"map": FILE|ASSET, ...}` or `{"sky": {...}, ...}`.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
#[allow(clippy::large_enum_variant)] // one per scene
pub enum EnvironmentJson {
    Color([f64; 3]),
    Map(EnvMapJson),
}

/// An equirectangular HDR environment map (`.hdr` or `.exr`), or a clear
/// sky computed as one (`sky`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvMapJson {
    /// A file (relative to the scene file) or an uploaded asset's id;
    /// empty with `sky`.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub map: String,
    /// A clear sky and sun (`render::envmap::sky_model`) in place of a map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sky: Option<SkyJson>,
    /// Scales the map's radiance.
    #[serde(default = "one")]
    pub intensity: f64,
    /// Turns the map about +y (right-handed); 0: its centre faces -z.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotation_deg: f64,
    /// Whether camera rays that leave the scene see the map.
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub visible: bool,
    /// What camera rays see instead when `visible` is false (default black).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub background: Option<[f64; 3]>,
}

fn yes() -> bool {
    true
}

fn is_true(v: &bool) -> bool {
    *v
}

/// Pinhole or thin-lens camera, orthographic, or a 360-degree panorama.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraJson {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    #[serde(default = "default_up")]
    pub up: [f64; 3],
    /// Full vertical field of view in degrees (perspective).
    pub vfov_deg: f64,
    /// Camera rays start this far from the camera along themselves (a
    /// sphere around it, as smallpt's camera: not a plane).
    #[serde(default)]
    pub near_clip: f64,
    /// Thin-lens radius in scene units (depth of field); 0: a pinhole.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub aperture: f64,
    /// The lens's f-number instead of `aperture`: radius = focal length /
    /// (2 N), the focal length that gives `vfov_deg` on a 24 mm tall
    /// (full-frame) sensor, scene units read as metres.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub f_number: Option<f64>,
    /// Distance along the view axis that is sharp [default: look_at's].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub focus_distance: Option<f64>,
    #[serde(default, skip_serializing_if = "ProjectionJson::is_perspective")]
    pub projection: ProjectionJson,
    /// An orthographic view's height in scene units [default: the
    /// perspective view's height at the look-at point].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ortho_height: Option<f64>,
}

/// How camera rays leave the camera.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum ProjectionJson {
    /// Through a pinhole or a thin lens, `vfov_deg` tall.
    #[default]
    Perspective,
    /// Parallel rays along the view axis from a rectangle `ortho_height`
    /// tall.
    Orthographic,
    /// Every direction: an equirectangular (latitude-longitude) image, its
    /// centre column looking at `look_at`, its top row straight `up` (the
    /// environment map's layout).
    Panorama,
}

impl ProjectionJson {
    pub fn is_perspective(&self) -> bool {
        *self == ProjectionJson::Perspective
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn default_up() -> [f64; 3] {
    [0.0, 1.0, 0.0]
}

/// Fresnel model of a glass material.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "lowercase")]
pub enum FresnelJson {
    #[default]
    Exact,
    Schlick,
}

/// A material, tagged by `type`; `emission` is allowed on every kind.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum MaterialJson {
    Diffuse(SurfaceJson),
    Mirror(SurfaceJson),
    Glass(GlassJson),
    /// Boxed: the largest kind by far (its fields may be textures).
    Pbr(Box<PbrJson>),
}

/// Fields of `pbr` materials: glTF 2.0's metallic-roughness model, with
/// glTF's defaults (white, metallic 1, roughness 1, ior 1.5). Colours and
/// numbers may be textures (`super::map_json`).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PbrJson {
    #[serde(default = "white")]
    pub base_color: ColorInput,
    #[serde(default = "one_input")]
    pub metallic: ScalarInput,
    #[serde(default = "one_input")]
    pub roughness: ScalarInput,
    #[serde(default = "default_ior")]
    pub ior: f64,
    /// The share of the dielectric that is rough glass.
    #[serde(default = "zero_input", skip_serializing_if = "is_zero_input")]
    pub transmission: ScalarInput,
    /// That glass is a thin wall (light passes unrefracted), not a solid.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub thin: bool,
    /// Absorption inside the solid (a thin wall has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attenuation: Option<AttenuationJson>,
    /// A clear coat over it all: its weight and roughness.
    #[serde(default = "zero_input", skip_serializing_if = "is_zero_input")]
    pub clearcoat: ScalarInput,
    #[serde(default = "zero_input", skip_serializing_if = "is_zero_input")]
    pub clearcoat_roughness: ScalarInput,
    /// The dielectric's reflection strength and F0 colour.
    #[serde(default = "one_input", skip_serializing_if = "is_one_input")]
    pub specular: ScalarInput,
    #[serde(default = "white", skip_serializing_if = "is_white")]
    pub specular_color: ColorInput,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<ColorInput>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<NormalJson>,
    /// The clear coat's own normal map (without one it follows the
    /// surface's unmapped normal).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clearcoat_normal: Option<NormalJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<AlphaJson>,
}

fn white() -> ColorInput {
    ColorInput::Value([1.0; 3])
}

fn one_input() -> ScalarInput {
    ScalarInput::Value(1.0)
}

fn one() -> f64 {
    1.0
}

fn zero_input() -> ScalarInput {
    ScalarInput::Value(0.0)
}

fn is_zero_input(v: &ScalarInput) -> bool {
    *v == ScalarInput::Value(0.0)
}

fn is_one_input(v: &ScalarInput) -> bool {
    *v == ScalarInput::Value(1.0)
}

fn is_white(v: &ColorInput) -> bool {
    *v == ColorInput::Value([1.0; 3])
}

fn default_ior() -> f64 {
    1.5
}

/// Beer-Lambert absorption inside a transmitting solid
/// (`KHR_materials_volume`): light that travels `distance` scene units
/// through it keeps `color` of itself.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AttenuationJson {
    pub color: [f64; 3],
    pub distance: f64,
}

/// Fields of `diffuse` and `mirror` materials.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SurfaceJson {
    pub albedo: ColorInput,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<ColorInput>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<NormalJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha: Option<AlphaJson>,
}

/// A cut-out or see-through surface (glTF's `alphaMode`, `alphaCutoff` and
/// the base colour's alpha): the surface is there where its alpha (`factor`
/// times the base colour or albedo texture's alpha channel) reaches
/// `cutoff` (`mask`), or with probability alpha (`blend`); elsewhere every
/// ray passes through it. Quads and meshes only.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AlphaJson {
    pub mode: AlphaModeJson,
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub factor: f64,
    /// `mask` only [default: 0.5, as glTF's].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff: Option<f64>,
}

/// [`AlphaJson`]'s test.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum AlphaModeJson {
    Mask,
    Blend,
}

fn is_one(v: &f64) -> bool {
    *v == 1.0
}

/// Fields of `glass` materials.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GlassJson {
    pub ior: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<ColorInput>,
    #[serde(default)]
    pub fresnel: FresnelJson,
    /// Absorption inside the solid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attenuation: Option<AttenuationJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<ColorInput>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal: Option<NormalJson>,
}

/// A shape with its material's name, tagged by `type`.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum ObjectJson {
    Sphere(SphereJson),
    Quad(QuadJson),
    /// A triangle mesh from a file, an uploaded asset or inline data.
    Mesh(ImportJson),
    /// A whole model file: its meshes, materials, node hierarchy and camera.
    Model(ImportJson),
}

/// A mesh or model: exactly one of `file`, `asset` and (meshes only) `data`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImportJson {
    /// A path (relative to the scene file); read by `pathstream render`, never by the server.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// The id of an asset uploaded with `POST /api/assets`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub asset: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub data: Option<MeshDataJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<TransformJson>,
    /// Meshes: one material for every triangle instead of the file's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
}

/// An inline indexed triangle mesh.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDataJson {
    pub positions: Vec<[f64; 3]>,
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex shading normals.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normals: Option<Vec<[f64; 3]>>,
}

/// world_from_object: `matrix` (row-major 4x4, last row 0 0 0 1), or
/// translate * rotate * scale, each optional.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransformJson {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translate: Option<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<RotateJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ScaleJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<[[f64; 4]; 4]>,
}

/// A rotation by `deg` degrees about `axis` (right-handed).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RotateJson {
    pub axis: [f64; 3],
    pub deg: f64,
}

/// A uniform scale factor or one per axis.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum ScaleJson {
    Uniform(f64),
    PerAxis([f64; 3]),
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SphereJson {
    pub center: [f64; 3],
    pub radius: f64,
    pub material: String,
}

/// A parallelogram corner + s*edge_u + t*edge_v, s and t in [0, 1]; two-sided.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct QuadJson {
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    pub material: String,
}

impl SceneJson {
    /// Reads a scene from parsed JSON. Tagged materials and objects are
    /// dispatched here by hand (serde's internally tagged enums buffer their
    /// content and lose the path of errors inside it).
    pub fn from_value(value: Value) -> Result<SceneJson, SceneError> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Shell {
            #[serde(default)]
            camera: Option<CameraJson>,
            #[serde(default)]
            materials: BTreeMap<String, Value>,
            objects: Vec<Value>,
            #[serde(default)]
            light: Option<usize>,
            #[serde(default)]
            environment: Option<Value>,
        }
        let shell: Shell = at("", value)?;
        let materials = shell
            .materials
            .into_iter()
            .map(|(name, v)| {
                let path = format!("materials.{name}");
                let m = match tagged(&path, v, &["diffuse", "mirror", "glass", "pbr"])? {
                    ("diffuse", rest) => MaterialJson::Diffuse(at(&path, rest)?),
                    ("mirror", rest) => MaterialJson::Mirror(at(&path, rest)?),
                    ("glass", rest) => MaterialJson::Glass(at(&path, rest)?),
                    (_, rest) => MaterialJson::Pbr(Box::new(at(&path, rest)?)),
                };
                Ok((name, m))
            })
            .collect::<Result<_, SceneError>>()?;
        let objects = shell
            .objects
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                let path = format!("objects[{i}]");
                Ok(
                    match tagged(&path, v, &["sphere", "quad", "mesh", "model"])? {
                        ("sphere", rest) => ObjectJson::Sphere(at(&path, rest)?),
                        ("quad", rest) => ObjectJson::Quad(at(&path, rest)?),
                        ("mesh", rest) => ObjectJson::Mesh(at(&path, rest)?),
                        (_, rest) => ObjectJson::Model(at(&path, rest)?),
                    },
                )
            })
            .collect::<Result<_, SceneError>>()?;
        Ok(SceneJson {
            camera: shell.camera,
            materials,
            objects,
            light: shell.light,
            environment: shell.environment.map(environment).transpose()?,
        })
    }
}

impl EnvironmentJson {
    /// `environment` as scene JSON gives it; errors name the field.
    pub fn from_value(value: Value) -> Result<EnvironmentJson, SceneError> {
        environment(value)
    }
}

/// `environment`: a colour or a map, told apart by their JSON kinds.
fn environment(value: Value) -> Result<EnvironmentJson, SceneError> {
    match value {
        Value::Object(_) => Ok(EnvironmentJson::Map(at("environment", value)?)),
        Value::Array(_) => Ok(EnvironmentJson::Color(at("environment", value)?)),
        _ => Err(SceneError::new(
            "environment",
            "expected a colour [r, g, b], a map {\"map\": \"studio.hdr\", ...} or a sky {\"sky\": {...}}",
        )),
    }
}

/// Deserializes `value`, prefixing error paths with `prefix`.
fn at<T: DeserializeOwned>(prefix: &str, value: Value) -> Result<T, SceneError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let inner = e.path().to_string();
        let path = match (prefix, inner.as_str()) {
            ("", inner) => inner.to_owned(),
            (prefix, ".") => prefix.to_owned(),
            (prefix, inner) if inner.starts_with('[') => format!("{prefix}{inner}"),
            (prefix, inner) => format!("{prefix}.{inner}"),
        };
        SceneError::new(path, e.into_inner().to_string())
    })
}

/// Splits the `type` tag off an object; it must be one of `kinds`.
fn tagged(
    path: &str,
    value: Value,
    kinds: &[&'static str],
) -> Result<(&'static str, Value), SceneError> {
    let Value::Object(mut map) = value else {
        return Err(SceneError::new(path, "expected an object"));
    };
    let kind = match map.remove("type") {
        Some(Value::String(kind)) => kind,
        Some(_) => return Err(SceneError::new(format!("{path}.type"), "must be a string")),
        None => return Err(SceneError::new(path, "missing field `type`")),
    };
    let Some(&kind) = kinds.iter().find(|k| **k == kind) else {
        return Err(SceneError::new(
            format!("{path}.type"),
            format!(
                "unknown type '{kind}' (expected one of: {})",
                kinds.join(", ")
            ),
        ));
    };
    Ok((kind, Value::Object(map)))
}
