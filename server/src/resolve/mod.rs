//! Scenes from names, files and model files: the layer between the model
//! loaders (`crate::model`, which know nothing of rendering) and the
//! renderer (`crate::render`, which reads no files). It resolves a scene's
//! `file` references ([`FileResolver`]), turns a loader's [`Model`] into the
//! renderer's [`LoadedModel`] ([`loaded_model`]: the server's asset store
//! uses it for uploads), and loads a scene by built-in name, scene JSON file
//! or model file ([`load_scene`]).

mod builtin_maps;
mod files;

pub use files::FileResolver;

use crate::model::{self, Model};
use crate::render::envmap::EnvMap;
use crate::render::math::{DAffine3, DMat3, DVec3};
use crate::render::scene::{
    builtin, CameraJson, EnvMapJson, EnvironmentJson, GlassJson, ImportJson, LoadedModel,
    MaterialJson, ObjectJson, PbrJson, ProjectionJson, SceneJson, SurfaceJson, BUILTIN_NAMES,
};
use crate::render::scene::{AttenuationJson, FresnelJson, MapSlot, Maps, Scene, SceneError};
use crate::render::texture::{Sampling, Texture, UvTransform, Wrap};
use std::path::Path;
use std::sync::Arc;

pub use builtin_maps::{builtin_map, builtin_maps, BuiltinMap};

/// The id of some bytes (an asset's, a built-in map's): their SHA-256, in
/// hex.
pub fn asset_id(bytes: &[u8]) -> String {
    use sha2::{Digest, Sha256};
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A scene given by built-in name, as a scene JSON file, or as a model file
/// (`.obj`, `.gltf`, `.glb`, `.ply`) framed and lit by default. Files that a
/// scene refers to are read relative to its directory.
pub fn load_scene(name_or_path: &str) -> Result<Scene, SceneError> {
    if let Some(scene) = builtin(name_or_path) {
        return Ok(scene);
    }
    let path = Path::new(name_or_path);
    if !path.exists() {
        return Err(SceneError::new(
            ".",
            format!(
                "'{name_or_path}' is neither a built-in scene ({}) nor a file",
                BUILTIN_NAMES.join(", ")
            ),
        ));
    }
    let resolver = FileResolver::new(path.parent().unwrap_or(Path::new(".")));
    if model::is_model_name(name_or_path) {
        let file = path.file_name().map_or_else(
            || name_or_path.to_owned(),
            |f| f.to_string_lossy().into_owned(),
        );
        let raw = SceneJson {
            camera: None,
            materials: Default::default(),
            objects: vec![ObjectJson::Model(ImportJson {
                file: Some(file),
                asset: None,
                data: None,
                transform: None,
                material: None,
            })],
            light: None,
            environment: None,
        };
        return Scene::from_json_with(&raw, &resolver);
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| SceneError::new(".", format!("cannot read {name_or_path}: {e}")))?;
    Scene::from_json_str_with(&text, &resolver)
}

/// `scene` lit by the environment map in file `map` (read relative to the
/// working directory), `intensity` times as bright and turned by
/// `rotation_deg` about +y: the command line's `--environment`.
pub fn with_environment(
    scene: &Scene,
    map: &Path,
    intensity: f64,
    rotation_deg: f64,
) -> Result<Scene, SceneError> {
    let environment = EnvironmentJson::Map(EnvMapJson {
        map: map.to_string_lossy().into_owned(),
        sky: None,
        intensity,
        rotation_deg,
        visible: true,
        background: None,
    });
    scene.with_environment(environment, &FileResolver::new(Path::new(".")))
}

/// `scene` under the clear sky `sky`, `intensity` times as bright and
/// turned by `rotation_deg` about +y: the command line's `--sky`.
pub fn with_sky(
    scene: &Scene,
    sky: crate::render::scene::SkyJson,
    intensity: f64,
    rotation_deg: f64,
) -> Result<Scene, SceneError> {
    let environment = EnvironmentJson::Map(EnvMapJson {
        map: String::new(),
        sky: Some(sky),
        intensity,
        rotation_deg,
        visible: true,
        background: None,
    });
    scene.with_environment(environment, &FileResolver::new(Path::new(".")))
}

/// An environment map read from an `.hdr` or `.exr` file and its sampling
/// tables built; errors name the file.
pub fn env_map_file(path: &Path) -> Result<EnvMap, String> {
    let name = path.file_name().map_or_else(
        || path.display().to_string(),
        |f| f.to_string_lossy().into_owned(),
    );
    if !model::hdr::is_hdr_name(&name) {
        return Err(format!(
            "'{name}': an environment map must be an .hdr or .exr file"
        ));
    }
    let bytes =
        std::fs::read(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    env_map_bytes(&bytes, &name)
}

/// An environment map from an image file's bytes (`name` for messages).
pub fn env_map_bytes(bytes: &[u8], name: &str) -> Result<EnvMap, String> {
    let image = model::hdr::read_hdr(bytes, name)?;
    let mut map = EnvMap::new(name, image.width, image.height, image.texels);
    if image.clamped > 0 {
        map.warning = Some(format!(
            "{name}: {} slightly negative texel values (rounding of the file's compression) read as 0",
            image.clamped
        ));
    }
    Ok(map)
}

/// A texture from a PNG or JPEG file's bytes (`name` for messages), its
/// texels within `limits.max_texels`.
pub fn texture_bytes(bytes: &[u8], name: &str, limits: &model::Limits) -> Result<Texture, String> {
    let image = model::load_image(bytes, name, limits).map_err(|e| e.to_string())?;
    Texture::new(name, image.width, image.height, &image.rgba)
}

/// A model as the renderer takes it: its meshes built (BVHs in parallel),
/// its materials as scene materials, its placements and camera in the
/// renderer's types. `name` is the file's (or the upload's) name, for
/// material names and messages.
pub fn loaded_model(name: &str, model: Model) -> Result<LoadedModel, String> {
    let textures = (model.images.into_iter())
        .map(|i| Texture::new(&i.name, i.width, i.height, &i.rgba).map(Arc::new))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("{name}: {e}"))?;
    let materials = (model.materials.into_iter())
        .map(|(name, m, maps)| (name, material_json(m), render_maps(&maps, &textures)))
        .collect();
    let instances = (model.instances.iter())
        .map(|i| (i.mesh, world_from_object(i.transform)))
        .collect();
    let camera = model.camera.map(|c| CameraJson {
        position: c.position,
        look_at: c.look_at,
        up: c.up,
        vfov_deg: c.vfov_deg,
        projection: match c.ortho_height {
            Some(_) => ProjectionJson::Orthographic,
            None => ProjectionJson::Perspective,
        },
        ortho_height: c.ortho_height,
        ..CameraJson::default()
    });
    LoadedModel::new(
        name,
        model.meshes,
        materials,
        instances,
        camera,
        model.warnings,
    )
}

/// A loader's texture maps on the renderer's textures (`textures[i]` is
/// the model's image `i`).
fn render_maps(maps: &model::Maps, textures: &[Arc<Texture>]) -> Maps {
    let slot = |r: &model::TextureRef| MapSlot {
        source: None,
        texture: textures[r.image].clone(),
        sampling: Sampling {
            uv: r.uv,
            transform: UvTransform::new(r.offset, r.rotation, r.scale),
            wrap: r.wrap.map(|w| match w {
                model::Wrap::Repeat => Wrap::Repeat,
                model::Wrap::Clamp => Wrap::Clamp,
                model::Wrap::Mirror => Wrap::Mirror,
            }),
        },
    };
    maps.map(slot)
}

/// A loader's material as scene JSON (glass from files is always exact
/// Fresnel).
fn material_json(m: model::Material) -> MaterialJson {
    match m {
        model::Material::Diffuse { albedo, emission } => MaterialJson::Diffuse(SurfaceJson {
            albedo: albedo.into(),
            emission: emission.map(Into::into),
            normal: None,
            alpha: None,
        }),
        model::Material::Mirror { albedo, emission } => MaterialJson::Mirror(SurfaceJson {
            albedo: albedo.into(),
            emission: emission.map(Into::into),
            normal: None,
            alpha: None,
        }),
        model::Material::Glass {
            ior,
            albedo,
            attenuation,
            emission,
        } => MaterialJson::Glass(GlassJson {
            ior,
            albedo: albedo.map(Into::into),
            fresnel: FresnelJson::Exact,
            attenuation: attenuation.map(attenuation_json),
            emission: emission.map(Into::into),
            normal: None,
        }),
        model::Material::Pbr {
            base_color,
            metallic,
            roughness,
            ior,
            transmission,
            thin,
            attenuation,
            clearcoat,
            clearcoat_roughness,
            specular,
            specular_color,
            emission,
        } => MaterialJson::Pbr(Box::new(PbrJson {
            base_color: base_color.into(),
            metallic: metallic.into(),
            roughness: roughness.into(),
            ior,
            transmission: transmission.into(),
            thin,
            attenuation: attenuation.map(attenuation_json),
            clearcoat: clearcoat.into(),
            clearcoat_roughness: clearcoat_roughness.into(),
            specular: specular.into(),
            specular_color: specular_color.into(),
            emission: emission.map(Into::into),
            normal: None,
            clearcoat_normal: None,
            alpha: None,
        })),
    }
}

fn attenuation_json(a: model::Attenuation) -> AttenuationJson {
    AttenuationJson {
        color: a.color,
        distance: a.distance,
    }
}

/// A row-major 3x4 world_from_object matrix as an affine map.
fn world_from_object(m: [[f64; 4]; 3]) -> DAffine3 {
    let [r0, r1, r2] = m;
    DAffine3 {
        matrix3: DMat3::from_cols(
            DVec3::new(r0[0], r1[0], r2[0]),
            DVec3::new(r0[1], r1[1], r2[1]),
            DVec3::new(r0[2], r1[2], r2[2]),
        ),
        translation: DVec3::new(r0[3], r1[3], r2[3]),
    }
}
