//! Raw JSON -> validated [`Scene`], and back. Every rule reports the JSON path
//! of the field it rejects.

use super::json::{
    CameraJson, FresnelJson, GlassJson, MaterialJson, ObjectJson, QuadJson, SceneJson, SphereJson, SurfaceJson,
};
use super::{
    Camera, Fresnel, Material, MaterialKind, Object, Scene, SceneError, Shape, MAX_COORDINATE,
    MAX_EMISSION, MAX_OBJECTS,
};
use crate::render::math::DVec3;
use std::collections::BTreeMap;

type Result<T> = std::result::Result<T, SceneError>;

/// Highest index of refraction accepted.
const MAX_IOR: f64 = 10.0;

pub(super) fn scene(raw: &SceneJson) -> Result<Scene> {
    let camera = camera(&raw.camera)?;

    let mut materials = Vec::with_capacity(raw.materials.len());
    let mut index_of = BTreeMap::new();
    for (name, m) in &raw.materials {
        index_of.insert(name.as_str(), materials.len());
        materials.push(material(name, m)?);
    }

    if raw.objects.is_empty() {
        return Err(SceneError::new("objects", "must hold at least one object"));
    }
    if raw.objects.len() > MAX_OBJECTS {
        return Err(SceneError::new(
            "objects",
            format!("{} objects is more than the limit of {MAX_OBJECTS}", raw.objects.len()),
        ));
    }
    let objects = raw
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| object(&format!("objects[{i}]"), o, &index_of))
        .collect::<Result<Vec<_>>>()?;

    let light = match raw.light {
        Some(i) if i >= objects.len() => {
            return Err(SceneError::new(
                "light",
                format!("object index {i} is out of range (the scene has {} objects)", objects.len()),
            ))
        }
        Some(i) => Some(i),
        None => objects
            .iter()
            .position(|o| materials[o.material].is_emissive()),
    };

    Ok(Scene {
        camera,
        materials,
        objects,
        light,
    })
}

fn camera(c: &CameraJson) -> Result<Camera> {
    let position = point("camera.position", c.position)?;
    let look_at = point("camera.look_at", c.look_at)?;
    let up = point("camera.up", c.up)?;
    let vfov_deg = finite("camera.vfov_deg", c.vfov_deg)?;
    if !(vfov_deg > 0.0 && vfov_deg < 180.0) {
        return Err(SceneError::new(
            "camera.vfov_deg",
            format!("must be between 0 and 180 degrees, exclusive (got {vfov_deg})"),
        ));
    }
    let near_clip = finite("camera.near_clip", c.near_clip)?;
    if !(0.0..=MAX_COORDINATE).contains(&near_clip) {
        return Err(SceneError::new(
            "camera.near_clip",
            format!("must be >= 0 (got {near_clip})"),
        ));
    }
    let view = look_at - position;
    if view.length() <= 1e-12 * position.abs().max_element().max(1.0) {
        return Err(SceneError::new("camera.look_at", "must differ from camera.position"));
    }
    if up.length() == 0.0 {
        return Err(SceneError::new("camera.up", "must not be the zero vector"));
    }
    let sin = view.normalize().cross(up.normalize()).length();
    if sin < 1e-6 {
        return Err(SceneError::new(
            "camera.up",
            "is parallel to the view direction (look_at - position)",
        ));
    }
    Ok(Camera {
        position,
        look_at,
        up,
        vfov_deg,
        near_clip,
    })
}

fn material(name: &str, m: &MaterialJson) -> Result<Material> {
    let path = format!("materials.{name}");
    let (kind, albedo, emission) = match m {
        MaterialJson::Diffuse(SurfaceJson { albedo, emission }) => (MaterialKind::Diffuse, *albedo, *emission),
        MaterialJson::Mirror(SurfaceJson { albedo, emission }) => (MaterialKind::Mirror, *albedo, *emission),
        MaterialJson::Glass(GlassJson {
            ior,
            albedo,
            fresnel,
            emission,
        }) => {
            let ior = finite(&format!("{path}.ior"), *ior)?;
            if !(1.0..=MAX_IOR).contains(&ior) {
                return Err(SceneError::new(
                    format!("{path}.ior"),
                    format!("must be between 1 and {MAX_IOR} (got {ior})"),
                ));
            }
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
    };
    let albedo = vec3(&format!("{path}.albedo"), albedo)?;
    if albedo.min_element() < 0.0 || albedo.max_element() > 1.0 {
        return Err(SceneError::new(
            format!("{path}.albedo"),
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
    })
}

fn object(path: &str, o: &ObjectJson, index_of: &BTreeMap<&str, usize>) -> Result<Object> {
    let (shape, material) = match o {
        ObjectJson::Sphere(SphereJson {
            center,
            radius,
            material,
        }) => {
            let center = point(&format!("{path}.center"), *center)?;
            let radius = finite(&format!("{path}.radius"), *radius)?;
            if radius <= 0.0 {
                return Err(SceneError::new(
                    format!("{path}.radius"),
                    format!("must be > 0 (got {radius})"),
                ));
            }
            if radius > MAX_COORDINATE {
                return Err(SceneError::new(
                    format!("{path}.radius"),
                    format!("must be at most {MAX_COORDINATE:e} (got {radius})"),
                ));
            }
            (Shape::Sphere { center, radius }, material)
        }
        ObjectJson::Quad(QuadJson {
            corner,
            edge_u,
            edge_v,
            material,
        }) => {
            let corner = point(&format!("{path}.corner"), *corner)?;
            let edge_u = point(&format!("{path}.edge_u"), *edge_u)?;
            let edge_v = point(&format!("{path}.edge_v"), *edge_v)?;
            let area = edge_u.cross(edge_v).length();
            if !(area > 1e-9 * edge_u.length() * edge_v.length()) || area == 0.0 {
                return Err(SceneError::new(
                    format!("{path}.edge_v"),
                    "the quad is degenerate: edge_u and edge_v are zero or parallel",
                ));
            }
            (
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                },
                material,
            )
        }
    };
    let Some(&material) = index_of.get(material.as_str()) else {
        let known: Vec<&str> = index_of.keys().copied().collect();
        return Err(SceneError::new(
            format!("{path}.material"),
            format!("unknown material '{material}' (known: {})", known.join(", ")),
        ));
    };
    Ok(Object { shape, material })
}

fn finite(path: &str, x: f64) -> Result<f64> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(SceneError::new(path, format!("must be a finite number (got {x})")))
    }
}

fn vec3(path: &str, v: [f64; 3]) -> Result<DVec3> {
    for (i, x) in v.iter().enumerate() {
        finite(&format!("{path}[{i}]"), *x)?;
    }
    Ok(DVec3::from_array(v))
}

/// A position or direction: finite and within [`MAX_COORDINATE`].
fn point(path: &str, v: [f64; 3]) -> Result<DVec3> {
    let p = vec3(path, v)?;
    if p.abs().max_element() > MAX_COORDINATE {
        return Err(SceneError::new(
            path,
            format!("coordinates must be within +-{MAX_COORDINATE:e}"),
        ));
    }
    Ok(p)
}

pub(super) fn to_json(s: &Scene) -> SceneJson {
    let camera = s.camera.to_json();
    let emission = |m: &Material| m.is_emissive().then(|| m.emission.to_array());
    let materials = s
        .materials
        .iter()
        .map(|m| {
            let json = match m.kind {
                MaterialKind::Diffuse => MaterialJson::Diffuse(SurfaceJson {
                    albedo: m.albedo.to_array(),
                    emission: emission(m),
                }),
                MaterialKind::Mirror => MaterialJson::Mirror(SurfaceJson {
                    albedo: m.albedo.to_array(),
                    emission: emission(m),
                }),
                MaterialKind::Glass { ior, fresnel } => MaterialJson::Glass(GlassJson {
                    ior,
                    albedo: Some(m.albedo.to_array()),
                    fresnel: match fresnel {
                        Fresnel::Exact => FresnelJson::Exact,
                        Fresnel::Schlick => FresnelJson::Schlick,
                    },
                    emission: emission(m),
                }),
            };
            (m.name.clone(), json)
        })
        .collect();
    let objects = s
        .objects
        .iter()
        .map(|o| {
            let material = s.materials[o.material].name.clone();
            match o.shape {
                Shape::Sphere { center, radius } => ObjectJson::Sphere(SphereJson {
                    center: center.to_array(),
                    radius,
                    material,
                }),
                Shape::Quad {
                    corner,
                    edge_u,
                    edge_v,
                } => ObjectJson::Quad(QuadJson {
                    corner: corner.to_array(),
                    edge_u: edge_u.to_array(),
                    edge_v: edge_v.to_array(),
                    material,
                }),
            }
        })
        .collect();
    SceneJson {
        camera,
        materials,
        objects,
        light: s.light,
    }
}

impl Camera {
    /// The camera in its JSON form.
    pub fn to_json(&self) -> CameraJson {
        CameraJson {
            position: self.position.to_array(),
            look_at: self.look_at.to_array(),
            up: self.up.to_array(),
            vfov_deg: self.vfov_deg,
            near_clip: self.near_clip,
        }
    }
}
