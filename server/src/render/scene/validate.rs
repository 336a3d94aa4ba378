//! Raw JSON -> validated [`Scene`], and back. Every rule reports the JSON path
//! of the field it rejects.

use super::import::{ImportKind, Importer};
use super::json::{
    CameraJson, EnvironmentJson, ObjectJson, ProjectionJson, QuadJson, SceneJson, SphereJson,
};
use super::maps::AlphaMode;
use super::materials::{self, unknown_material};
use super::resolve::Resolver;
use super::values::{finite, point};
use super::{
    aperture_of_f_number, frame, Camera, Object, Projection, Scene, SceneError, Shape,
    MAX_COORDINATE, MAX_OBJECTS,
};
use crate::render::math::DVec3;
use std::collections::{BTreeMap, HashMap};

type Result<T> = std::result::Result<T, SceneError>;

/// Most objects a scene may place, counting every placement of a mesh.
pub const MAX_PLACED: usize = 1 << 22;

/// The environment a scene of meshes without emitters gets, so that a bare
/// model shows up lit.
pub const DEFAULT_ENVIRONMENT: [f64; 3] = [1.0, 1.0, 1.0];

pub(super) fn scene(raw: &SceneJson, resolver: &dyn Resolver) -> Result<Scene> {
    let mut materials = Vec::with_capacity(raw.materials.len());
    let mut index_of = BTreeMap::new();
    for (name, m) in &raw.materials {
        index_of.insert(name.clone(), materials.len());
        materials.push(materials::material(name, m, resolver)?);
    }

    if raw.objects.is_empty() {
        return Err(SceneError::new("objects", "must hold at least one object"));
    }
    if raw.objects.len() > MAX_OBJECTS {
        return Err(SceneError::new(
            "objects",
            format!(
                "{} objects is more than the limit of {MAX_OBJECTS}",
                raw.objects.len()
            ),
        ));
    }
    let mut imports = Vec::new();
    let mut objects = Vec::with_capacity(raw.objects.len());
    let mut importer = Importer {
        resolver,
        materials: &mut materials,
        index_of: &mut index_of,
        added: HashMap::new(),
    };
    let mut placed = 0usize;
    for (i, o) in raw.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        let object = match o {
            ObjectJson::Mesh(json) | ObjectJson::Model(json) => {
                let kind = if matches!(o, ObjectJson::Mesh(_)) {
                    ImportKind::Mesh
                } else {
                    ImportKind::Model
                };
                let (import, material) = importer.import(&path, kind, json)?;
                placed += import.instances.len();
                imports.push(import);
                Object {
                    shape: Shape::Import(imports.len() - 1),
                    material,
                }
            }
            _ => {
                placed += 1;
                let object = object(&path, o, importer.index_of)?;
                let alpha = importer.materials[object.material].maps.alpha_mode;
                if matches!(object.shape, Shape::Sphere { .. }) && alpha != AlphaMode::Opaque {
                    return Err(SceneError::new(
                        format!("{path}.material"),
                        "an alpha-tested material (its `alpha`) needs a quad or a mesh: spheres are opaque",
                    ));
                }
                object
            }
        };
        objects.push(object);
    }
    if placed > MAX_PLACED {
        return Err(SceneError::new(
            "objects",
            format!("the scene places {placed} objects (mesh placements included), more than the limit of {MAX_PLACED}"),
        ));
    }

    let mut warnings = Vec::new();
    for import in &imports {
        for w in &import.model.warnings {
            let line = format!("{}: {w}", import.model.name);
            if !warnings.contains(&line) {
                warnings.push(line);
            }
        }
    }

    let camera = match &raw.camera {
        Some(c) => camera(c)?,
        None => {
            let from_model = imports
                .iter()
                .filter(|i| i.kind == ImportKind::Model)
                .find_map(|i| {
                    let c = i.model.camera.as_ref()?;
                    let t = i.world_from_json;
                    Some(CameraJson {
                        position: t.transform_point3(DVec3::from_array(c.position)).to_array(),
                        look_at: t.transform_point3(DVec3::from_array(c.look_at)).to_array(),
                        up: t.transform_vector3(DVec3::from_array(c.up)).to_array(),
                        vfov_deg: c.vfov_deg,
                        projection: match c.ortho_height {
                            Some(_) => ProjectionJson::Orthographic,
                            None => ProjectionJson::Perspective,
                        },
                        // The placement's scale along the camera's up.
                        ortho_height: c.ortho_height.map(|h| {
                            h * t
                                .transform_vector3(DVec3::from_array(c.up).normalize())
                                .length()
                        }),
                        ..CameraJson::default()
                    })
                });
            match from_model {
                Some(c) => camera(&c).map_err(|e| {
                    SceneError::new("camera", format!("the model's camera: {}", e.reason))
                })?,
                None => {
                    let (lo, hi) = frame::bounds(&objects, &imports).ok_or_else(|| {
                        SceneError::new("camera", "the scene has no bounds to frame; give a camera")
                    })?;
                    warnings.push("no camera given: framed the scene's bounds".to_owned());
                    camera(&frame::framed(lo, hi).to_json())?
                }
            }
        }
    };

    let (environment, environment_map) =
        super::environment::environment(raw.environment.as_ref(), resolver)?;
    warnings.extend(environment_map.as_ref().and_then(|m| m.map.warning.clone()));

    let mut scene = Scene {
        camera,
        materials,
        objects,
        light: None,
        environment,
        environment_map,
        imports,
        warnings,
    };
    scene.light = match raw.light {
        Some(i) if i >= scene.objects.len() => {
            return Err(SceneError::new(
                "light",
                format!(
                    "object index {i} is out of range (the scene has {} objects)",
                    scene.objects.len()
                ),
            ))
        }
        Some(i) => Some(i),
        None => scene.emitters().next(),
    };
    if raw.environment.is_none() && !scene.imports.is_empty() && scene.light.is_none() {
        scene.environment = DVec3::from_array(DEFAULT_ENVIRONMENT);
        scene.warnings.push(format!(
            "the scene has no emitters: lit by a uniform environment {DEFAULT_ENVIRONMENT:?} (set \"environment\" to change it)"
        ));
    }
    Ok(scene)
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
    let aperture = finite("camera.aperture", c.aperture)?;
    if !(0.0..=MAX_COORDINATE).contains(&aperture) {
        return Err(SceneError::new(
            "camera.aperture",
            format!("must be >= 0 (the lens radius; 0 is a pinhole) (got {aperture})"),
        ));
    }
    let f_number = match c.f_number {
        None => None,
        Some(n) => {
            let n = finite("camera.f_number", n)?;
            if !(n > 0.0 && n <= 1e6) {
                return Err(SceneError::new(
                    "camera.f_number",
                    format!("must be > 0 (got {n})"),
                ));
            }
            if aperture > 0.0 {
                return Err(SceneError::new(
                    "camera.f_number",
                    "give the lens as camera.aperture or as camera.f_number, not both",
                ));
            }
            Some(n)
        }
    };
    let focus_distance = match c.focus_distance {
        None => None,
        Some(f) => {
            let f = finite("camera.focus_distance", f)?;
            if !(f > 0.0 && f <= MAX_COORDINATE) {
                return Err(SceneError::new(
                    "camera.focus_distance",
                    format!("must be > 0 (got {f})"),
                ));
            }
            Some(f)
        }
    };
    let projection = projection(c, position, look_at, vfov_deg)?;
    if projection != Projection::Perspective {
        let (field, given) = match f_number {
            Some(_) => ("camera.f_number", true),
            None => ("camera.aperture", aperture > 0.0),
        };
        if given {
            return Err(SceneError::new(
                field,
                "only a perspective camera has a lens (set camera.projection to \"perspective\")",
            ));
        }
    }
    let view = look_at - position;
    if view.length() <= 1e-12 * position.abs().max_element().max(1.0) {
        return Err(SceneError::new(
            "camera.look_at",
            "must differ from camera.position",
        ));
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
        aperture: f_number.map_or(aperture, |n| aperture_of_f_number(n, vfov_deg)),
        f_number,
        focus_distance,
        projection,
    })
}

/// The projection and, for an orthographic one, its height (by default the
/// perspective view's at the look-at point, so that switching keeps the
/// framing there).
fn projection(
    c: &CameraJson,
    position: DVec3,
    look_at: DVec3,
    vfov_deg: f64,
) -> Result<Projection> {
    let height = match c.ortho_height {
        None => None,
        Some(h) => {
            let h = finite("camera.ortho_height", h)?;
            if !(h > 0.0 && h <= MAX_COORDINATE) {
                return Err(SceneError::new(
                    "camera.ortho_height",
                    format!("must be > 0 (got {h})"),
                ));
            }
            Some(h)
        }
    };
    match c.projection {
        ProjectionJson::Orthographic => Ok(Projection::Orthographic {
            height: height.unwrap_or_else(|| {
                2.0 * (look_at - position).length() * (0.5 * vfov_deg.to_radians()).tan()
            }),
        }),
        _ if height.is_some() => Err(SceneError::new(
            "camera.ortho_height",
            "only an orthographic camera has one (set camera.projection to \"orthographic\")",
        )),
        ProjectionJson::Perspective => Ok(Projection::Perspective),
        ProjectionJson::Panorama => Ok(Projection::Panorama),
    }
}

fn object(path: &str, o: &ObjectJson, index_of: &BTreeMap<String, usize>) -> Result<Object> {
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
        ObjectJson::Mesh(_) | ObjectJson::Model(_) => {
            unreachable!("imports are validated by the importer")
        }
    };
    let Some(&material) = index_of.get(material.as_str()) else {
        return Err(unknown_material(
            &format!("{path}.material"),
            material,
            index_of,
        ));
    };
    Ok(Object { shape, material })
}

pub(super) fn to_json(s: &Scene) -> SceneJson {
    let camera = s.camera.to_json();
    let materials = s
        .materials
        .iter()
        .filter(|m| !m.imported)
        .map(|m| (m.name.clone(), materials::to_json(m)))
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
                Shape::Import(k) => {
                    let import = &s.imports[k];
                    let json = import.json.clone();
                    match import.kind {
                        ImportKind::Mesh => ObjectJson::Mesh(json),
                        ImportKind::Model => ObjectJson::Model(json),
                    }
                }
            }
        })
        .collect();
    SceneJson {
        camera: Some(camera),
        materials,
        objects,
        light: s.light,
        environment: match &s.environment_map {
            Some(m) => Some(EnvironmentJson::Map(m.json.clone())),
            None => (s.environment != DVec3::ZERO)
                .then(|| EnvironmentJson::Color(s.environment.to_array())),
        },
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
            aperture: if self.f_number.is_some() {
                0.0
            } else {
                self.aperture
            },
            f_number: self.f_number,
            focus_distance: self.focus_distance,
            projection: match self.projection {
                Projection::Perspective => ProjectionJson::Perspective,
                Projection::Orthographic { .. } => ProjectionJson::Orthographic,
                Projection::Panorama => ProjectionJson::Panorama,
            },
            ortho_height: match self.projection {
                Projection::Orthographic { height } => Some(height),
                _ => None,
            },
        }
    }
}
