//! Material JSON -> validated [`Material`], and back; the error for a
//! material name a scene does not define.

use super::json::{FresnelJson, GlassJson, MaterialJson, PbrJson, SurfaceJson};
use super::values::{finite, vec3};
use super::{Fresnel, Material, MaterialKind, SceneError, MAX_EMISSION};
use std::collections::BTreeMap;

type Result<T> = std::result::Result<T, SceneError>;

/// Highest index of refraction accepted.
const MAX_IOR: f64 = 10.0;

/// Material `name` checked: an index of refraction in [1, [`MAX_IOR`]],
/// albedo in [0, 1], emission in [0, [`MAX_EMISSION`]].
pub(super) fn material(name: &str, m: &MaterialJson) -> Result<Material> {
    let path = format!("materials.{name}");
    let (kind, albedo, emission) = match m {
        MaterialJson::Diffuse(SurfaceJson { albedo, emission }) => {
            (MaterialKind::Diffuse, *albedo, *emission)
        }
        MaterialJson::Mirror(SurfaceJson { albedo, emission }) => {
            (MaterialKind::Mirror, *albedo, *emission)
        }
        MaterialJson::Glass(GlassJson {
            ior,
            albedo,
            fresnel,
            emission,
        }) => {
            let ior = checked_ior(&path, *ior)?;
            let fresnel = match fresnel {
                FresnelJson::Exact => Fresnel::Exact,
                FresnelJson::Schlick => Fresnel::Schlick,
            };
            (
                MaterialKind::Glass { ior, fresnel },
                albedo.unwrap_or([1.0; 3]),
                *emission,
            )
        }
        MaterialJson::Pbr(PbrJson {
            base_color,
            metallic,
            roughness,
            ior,
            emission,
        }) => {
            let unit = |field: &str, v: f64| {
                let v = finite(&format!("{path}.{field}"), v)?;
                if (0.0..=1.0).contains(&v) {
                    Ok(v)
                } else {
                    Err(SceneError::new(
                        format!("{path}.{field}"),
                        format!("must be between 0 and 1 (got {v})"),
                    ))
                }
            };
            let kind = MaterialKind::Pbr {
                metallic: unit("metallic", *metallic)?,
                roughness: unit("roughness", *roughness)?,
                ior: checked_ior(&path, *ior)?,
            };
            (kind, *base_color, *emission)
        }
    };
    let field = match m {
        MaterialJson::Pbr(_) => "base_color",
        _ => "albedo",
    };
    let albedo = vec3(&format!("{path}.{field}"), albedo)?;
    if albedo.min_element() < 0.0 || albedo.max_element() > 1.0 {
        return Err(SceneError::new(
            format!("{path}.{field}"),
            "components must be between 0 and 1",
        ));
    }
    let emission = vec3(&format!("{path}.emission"), emission.unwrap_or([0.0; 3]))?;
    if emission.min_element() < 0.0 || emission.max_element() > MAX_EMISSION {
        return Err(SceneError::new(
            format!("{path}.emission"),
            format!("components must be between 0 and {MAX_EMISSION:e}"),
        ));
    }
    Ok(Material {
        name: name.to_owned(),
        kind,
        albedo,
        emission,
        maps: Default::default(),
        imported: false,
    })
}

/// An index of refraction in [1, [`MAX_IOR`]].
fn checked_ior(path: &str, ior: f64) -> Result<f64> {
    let ior = finite(&format!("{path}.ior"), ior)?;
    if !(1.0..=MAX_IOR).contains(&ior) {
        return Err(SceneError::new(
            format!("{path}.ior"),
            format!("must be between 1 and {MAX_IOR} (got {ior})"),
        ));
    }
    Ok(ior)
}

/// The material's JSON form.
pub(super) fn to_json(m: &Material) -> MaterialJson {
    let emission = m.is_emissive().then(|| m.emission.to_array());
    match m.kind {
        MaterialKind::Diffuse => MaterialJson::Diffuse(SurfaceJson {
            albedo: m.albedo.to_array(),
            emission,
        }),
        MaterialKind::Mirror => MaterialJson::Mirror(SurfaceJson {
            albedo: m.albedo.to_array(),
            emission,
        }),
        MaterialKind::Glass { ior, fresnel } => MaterialJson::Glass(GlassJson {
            ior,
            albedo: Some(m.albedo.to_array()),
            fresnel: match fresnel {
                Fresnel::Exact => FresnelJson::Exact,
                Fresnel::Schlick => FresnelJson::Schlick,
            },
            emission,
        }),
        MaterialKind::Pbr {
            metallic,
            roughness,
            ior,
        } => MaterialJson::Pbr(PbrJson {
            base_color: m.albedo.to_array(),
            metallic,
            roughness,
            ior,
            emission,
        }),
    }
}

/// The error for a material name that the scene does not define.
pub(super) fn unknown_material(
    path: &str,
    name: &str,
    index_of: &BTreeMap<String, usize>,
) -> SceneError {
    let known: Vec<&str> = index_of.keys().map(String::as_str).collect();
    SceneError::new(
        path,
        format!("unknown material '{name}' (known: {})", known.join(", ")),
    )
}
