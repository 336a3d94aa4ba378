//! The validated scene model. Everything the renderer sees has been through
//! [`Scene::from_json_str`] or [`Scene::from_json`]: finite numbers, known
//! material names, positive radii, non-degenerate quads, a usable camera,
//! meshes whose files loaded (see `import`).
//! World coordinates stay in f64 here; the hot path gets camera-relative f32
//! (see `render::world`).
//!
//! ## Adding a material kind ([`MaterialKind`])
//! 1. Scene JSON: its `MaterialJson` variant and tag (`json.rs`), its checks
//!    and JSON form (`materials.rs`), its `MaterialKind` variant here.
//! 2. The hot path: its `Bsdf` and how `scatter` samples it
//!    (`render/material.rs`); whether next-event estimation applies to it
//!    (`render/integrator`).
//! 3. OpenCL: a `MAT_` constant in `SHARED_CONSTANTS` and its packing
//!    (`backend/opencl/layout.rs`), its `HAS_` feature
//!    (`backend/opencl/program.rs`), its case in `kernels/materials.h`.
//! 4. Model files that have it: `model::Material` and
//!    `resolve::material_json`.
//! 5. Tests: a CPU/OpenCL parity case (`tests/opencl_parity.rs`) and a
//!    closed-form check (furnace or analytic).
//!
//! ## Adding a shape kind ([`Shape`])
//! 1. Scene JSON: its `ObjectJson` variant and tag (`json.rs`), its checks
//!    and JSON form (`validate.rs`), its bounds and transform (`frame.rs`,
//!    `transform.rs`), its `Shape` variant here.
//! 2. The hot path: a file of its own in `render/shape/` (intersection,
//!    normal), its `world::Geometry` variant, box and accelerator choice
//!    (`world/build.rs`), hit and surface (`world/mod.rs`); if it can
//!    emit, an emitter kind (`render/light/emitter.rs`).
//! 3. OpenCL: a `KIND_` constant and its packing (`layout.rs`), its `HAS_`
//!    feature (`program.rs`), its test in `kernels/shapes.h` and
//!    `kernels/world.h`.
//! 4. Tests: intersection against a brute-force or analytic answer, a
//!    parity case, a furnace.

mod builtin;
mod edit;
mod environment;
mod frame;
mod import;
mod json;
mod map_json;
mod maps;
mod materials;
mod placement;
mod resolve;
pub mod sky;
mod transform;
mod validate;
mod values;

pub use builtin::{builtin, BUILTIN_NAMES};
pub use edit::{CameraEdit, EditError, LightEdit, LightInfo};
pub use environment::EnvironmentMap;
pub use import::{Import, ImportKind, MeshInstance};
pub use json::{
    AlphaJson, AlphaModeJson, AttenuationJson, CameraJson, EnvMapJson, EnvironmentJson,
    FresnelJson, GlassJson, ImportJson, MaterialJson, MeshDataJson, ObjectJson, PbrJson,
    ProjectionJson, QuadJson, RotateJson, ScaleJson, SceneJson, SkyJson, SphereJson, SurfaceJson,
    TransformJson,
};
pub use map_json::{
    ColorInput, MapSource, NormalJson, ScalarInput, TextureJson, UvTransformJson, WrapJson,
    WrapMode,
};
pub use maps::{MapSlot, Maps};
pub use resolve::{LoadedModel, ModelSource, NoFiles, Resolver};
pub use validate::{DEFAULT_ENVIRONMENT, MAX_PLACED};

use crate::render::math::DVec3;

/// Most objects a scene's JSON may list (a model file counts as one).
pub const MAX_OBJECTS: usize = 1 << 20;
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

/// Camera in world space: a pinhole, or a thin lens where `aperture` > 0;
/// orthographic, or a panorama.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: DVec3,
    pub look_at: DVec3,
    pub up: DVec3,
    pub vfov_deg: f64,
    pub near_clip: f64,
    /// The thin lens's radius (scene units); 0: a pinhole.
    pub aperture: f64,
    /// The f-number the aperture was given as, if it was.
    pub f_number: Option<f64>,
    pub projection: Projection,
    /// Distance along the view axis of the plane in focus; None: the
    /// `look_at` point's.
    pub focus_distance: Option<f64>,
}

impl Camera {
    /// A pinhole at `position` looking at `look_at`, +y up.
    pub fn pinhole(position: DVec3, look_at: DVec3, vfov_deg: f64) -> Camera {
        Camera {
            position,
            look_at,
            up: DVec3::Y,
            vfov_deg,
            near_clip: 0.0,
            aperture: 0.0,
            f_number: None,
            focus_distance: None,
            projection: Projection::Perspective,
        }
    }

    /// The distance along the view axis that is in focus.
    pub fn focus(&self) -> f64 {
        self.focus_distance
            .unwrap_or_else(|| (self.look_at - self.position).length())
    }
}

/// How camera rays leave the camera (`ProjectionJson`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Perspective,
    /// Parallel rays from a rectangle this tall (scene units).
    Orthographic {
        height: f64,
    },
    Panorama,
}

/// A full-frame (35 mm) sensor's height: the f-number's focal length.
pub const SENSOR_HEIGHT_M: f64 = 0.024;

/// The lens radius of f-number `n` at vertical field of view `vfov_deg`:
/// focal length / (2 n), the focal length giving that field of view on a
/// sensor [`SENSOR_HEIGHT_M`] tall.
pub fn aperture_of_f_number(n: f64, vfov_deg: f64) -> f64 {
    let focal = 0.5 * SENSOR_HEIGHT_M / (0.5 * vfov_deg.to_radians()).tan();
    focal / (2.0 * n)
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
    Glass {
        ior: f64,
        fresnel: Fresnel,
    },
    /// glTF 2.0's metallic-roughness model (`render::ggx`); the albedo is
    /// its base colour.
    Pbr {
        metallic: f64,
        roughness: f64,
        ior: f64,
        /// The share of the dielectric that is rough glass
        /// (`KHR_materials_transmission`), in [0, 1].
        transmission: f64,
        /// The glass is a thin wall (unrefracted), not a solid.
        thin: bool,
        /// A clear coat's weight (`KHR_materials_clearcoat`, 0: none) and
        /// roughness, both in [0, 1].
        clearcoat: f64,
        clearcoat_roughness: f64,
        /// `KHR_materials_specular`: the dielectric's reflection strength
        /// in [0, 1] and F0 colour (components >= 0), 1 and white without.
        specular: f64,
        specular_color: [f64; 3],
    },
}

/// A named material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    /// Diffuse reflectance, mirror reflectance, glass tint, or base colour.
    pub albedo: DVec3,
    /// Emitted radiance, from both sides of the surface.
    pub emission: DVec3,
    /// Texture maps (`render::maps`): none for most materials.
    pub maps: Maps,
    /// Absorption inside a transmitting solid (`glass`, `pbr`), or none.
    pub attenuation: Option<Attenuation>,
    /// Came from a model file (named `file/material`); not written back
    /// to scene JSON, where the file brings it again.
    pub imported: bool,
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// Beer-Lambert absorption inside a transmitting solid
/// (`KHR_materials_volume`): light that travels `distance` scene units
/// through it keeps `color` of itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Attenuation {
    pub color: DVec3,
    pub distance: f64,
}

impl Attenuation {
    /// Least share of light kept over `distance`: a colour component of 0
    /// keeps this much (a finite coefficient).
    pub const MIN_KEPT: f64 = 1e-6;

    /// The absorption coefficient per scene unit, -ln(color) / distance.
    pub fn coefficient(&self) -> DVec3 {
        -self.color.max(DVec3::splat(Self::MIN_KEPT)).map(f64::ln) / self.distance
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
    /// A mesh or model placed in the scene: `Scene::imports[i]`.
    Import(usize),
}

/// A shape and the index of its material (for an import: its `material`
/// override, else the material of its first triangle).
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
    /// Radiance of rays that leave the scene (black where a map is given).
    pub environment: DVec3,
    /// An HDR environment map, in place of the uniform colour.
    pub environment_map: Option<EnvironmentMap>,
    /// The meshes and models that `Shape::Import` objects place.
    pub imports: Vec<Import>,
    /// What the scene's files hold that is not rendered, and what was
    /// chosen for the user (a framed camera, a default environment).
    pub warnings: Vec<String>,
}

impl Scene {
    /// Parses and validates scene JSON. Errors name the JSON path. Meshes
    /// may only be inline data (see [`Scene::from_json_with`]).
    pub fn from_json_str(text: &str) -> Result<Scene, SceneError> {
        Self::from_json_value(Self::parse_value(text)?)
    }

    fn parse_value(text: &str) -> Result<serde_json::Value, SceneError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(de)
            .map_err(|e| SceneError::new(e.path().to_string(), e.into_inner().to_string()))
    }

    /// Parses and validates scene JSON whose meshes and models `resolver`
    /// reads.
    pub fn from_json_str_with(text: &str, resolver: &dyn Resolver) -> Result<Scene, SceneError> {
        Self::from_json_with(&SceneJson::from_value(Self::parse_value(text)?)?, resolver)
    }

    /// Validates already parsed JSON (e.g. the `scene` field of a request).
    pub fn from_json_value(value: serde_json::Value) -> Result<Scene, SceneError> {
        Self::from_json(&SceneJson::from_value(value)?)
    }

    /// Validates an already parsed scene; mesh files and assets are not
    /// read ([`NoFiles`]).
    pub fn from_json(raw: &SceneJson) -> Result<Scene, SceneError> {
        Self::from_json_with(raw, &NoFiles)
    }

    /// Validates a scene whose meshes and models `resolver` reads.
    pub fn from_json_with(raw: &SceneJson, resolver: &dyn Resolver) -> Result<Scene, SceneError> {
        validate::scene(raw, resolver)
    }

    /// Validates an edited form of this scene: its meshes and models are
    /// taken from this scene where the edit still refers to them (nothing
    /// is read or rebuilt), else as `from_json` would.
    pub fn revalidate(&self, raw: &SceneJson) -> Result<Scene, SceneError> {
        self.revalidate_with(raw, &NoFiles)
    }

    /// As [`Scene::revalidate`], with what this scene does not hold read by
    /// `fallback` (an environment map given on the command line).
    pub fn revalidate_with(
        &self,
        raw: &SceneJson,
        fallback: &dyn Resolver,
    ) -> Result<Scene, SceneError> {
        Self::from_json_with(raw, &resolve::Reuse::new(self, fallback))
    }

    /// The scene back in its JSON form (round-trips through `from_json`
    /// with the same resolver, or through `revalidate`).
    pub fn to_json(&self) -> SceneJson {
        validate::to_json(self)
    }

    /// Whether object `i` emits light (an import: any of its triangles).
    pub fn object_emits(&self, i: usize) -> bool {
        match self.objects[i].shape {
            Shape::Import(k) => self.imports[k].instances.iter().any(|inst| {
                inst.materials
                    .iter()
                    .any(|&m| self.materials[m as usize].is_emissive())
            }),
            _ => self.materials[self.objects[i].material].is_emissive(),
        }
    }

    /// Indices of objects that emit.
    pub fn emitters(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.objects.len()).filter(|&i| self.object_emits(i))
    }

    /// Triangles held in memory (each mesh once, however often placed).
    pub fn unique_triangles(&self) -> u64 {
        let mut seen = std::collections::HashSet::new();
        self.imports
            .iter()
            .flat_map(|i| &i.instances)
            .filter(|inst| seen.insert(std::sync::Arc::as_ptr(&inst.mesh)))
            .map(|inst| inst.mesh.triangles.len() as u64)
            .sum()
    }
}
