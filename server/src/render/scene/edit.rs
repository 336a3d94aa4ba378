//! Edits to a validated scene: move the camera, move, recolour or rescale the
//! scene's light. Each edit takes a scene and returns a new validated one, or
//! an error that names the field; the scene given is never changed. The
//! service's `PATCH /camera` and `PATCH /light` bodies are these types:
//!
//! ```json
//! {"position": [50, 52, 250], "look_at": [50, 40, 0], "vfov_deg": 40}
//! {"position": [50, 70, 80], "color": [1, 0.8, 0.6], "intensity": 20}
//! ```
//!
//! An edit sets the light's emission to colour x intensity; read back, the
//! intensity is the emission's largest component and the colour the emission
//! over it (largest component 1). When the
//! light shares its material with other objects, a recolour gives the light
//! a copy of its own (named `<material>-light`), so the other objects keep
//! theirs. A light that is a `mesh` gets one material of the scene's for all
//! its triangles (its file's own come back from the file on every
//! validation); a whole `model` cannot be recoloured (its position moves).
//! Edits re-validate through [`Scene::revalidate`]: meshes are not read or
//! rebuilt.

use super::{ImportKind, ProjectionJson, Scene, SceneError, Shape, MAX_COORDINATE, MAX_EMISSION};
use crate::render::math::DVec3;
use serde::{Deserialize, Serialize};

/// Any subset of the camera's fields.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraEdit {
    pub position: Option<[f64; 3]>,
    pub look_at: Option<[f64; 3]>,
    pub up: Option<[f64; 3]>,
    pub vfov_deg: Option<f64>,
    pub near_clip: Option<f64>,
    pub aperture: Option<f64>,
    pub f_number: Option<f64>,
    pub focus_distance: Option<f64>,
    pub projection: Option<ProjectionJson>,
    pub ortho_height: Option<f64>,
}

/// Move, recolour or rescale the scene's light.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightEdit {
    /// New centre of the light's sphere or quad.
    pub position: Option<[f64; 3]>,
    /// Components in [0, 1]; emission = colour x intensity.
    pub color: Option<[f64; 3]>,
    /// Largest emission component, in [0, `MAX_EMISSION`].
    pub intensity: Option<f64>,
}

/// The scene's light as edits see it (and the service reports it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightInfo {
    /// Index of the light object in the scene's `objects`.
    pub index: usize,
    /// Centre of the sphere or quad, or of the mesh's bounds.
    pub position: [f64; 3],
    /// Emission over intensity: largest component 1 (all 0 when dark).
    pub color: [f64; 3],
    pub intensity: f64,
}

/// Why an edit was refused. The message starts with the field's path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EditError {
    #[error("light: the scene has no light to change")]
    NoLight,
    #[error("{field}: {reason}")]
    Field { field: &'static str, reason: String },
    /// The edited scene failed validation (e.g. `camera.up` parallel to the view).
    #[error(transparent)]
    Scene(#[from] SceneError),
}

impl Scene {
    /// The light that [`Scene::edit_light`] changes, if the scene has one.
    pub fn light_info(&self) -> Option<LightInfo> {
        let index = self.light?;
        let object = self.objects.get(index)?;
        let emission = self.materials.get(object.material)?.emission;
        let intensity = emission.max_element();
        let color = if intensity > 0.0 {
            emission / intensity
        } else {
            DVec3::ZERO
        };
        Some(LightInfo {
            index,
            position: self.object_center(index).to_array(),
            color: color.to_array(),
            intensity,
        })
    }

    /// This scene with the camera fields that `edit` names replaced.
    pub fn edit_camera(&self, edit: &CameraEdit) -> Result<Scene, EditError> {
        let mut json = self.to_json();
        let c = json.camera.get_or_insert_with(|| self.camera.to_json());
        let CameraEdit {
            position,
            look_at,
            up,
            vfov_deg,
            near_clip,
            aperture,
            f_number,
            focus_distance,
            projection,
            ortho_height,
        } = *edit;
        c.position = position.unwrap_or(c.position);
        c.look_at = look_at.unwrap_or(c.look_at);
        c.up = up.unwrap_or(c.up);
        c.vfov_deg = vfov_deg.unwrap_or(c.vfov_deg);
        c.near_clip = near_clip.unwrap_or(c.near_clip);
        c.focus_distance = focus_distance.or(c.focus_distance);
        if let Some(p) = projection {
            // Another projection drops what belonged to the old one: the
            // lens (only a perspective camera has one) and the height.
            if p != c.projection {
                c.ortho_height = None;
            }
            if p != ProjectionJson::Perspective {
                (c.aperture, c.f_number) = (0.0, None);
            }
            c.projection = p;
        }
        c.ortho_height = ortho_height.or(c.ortho_height);
        // The lens is given one way or the other: the newer replaces it
        // (an aperture of 0 beside an f-number, as a status carries it, is
        // the f-number's).
        if aperture.is_some_and(|a| a != 0.0) && f_number.is_some() {
            return Err(EditError::Field {
                field: "camera.f_number",
                reason: "give the lens as camera.aperture or as camera.f_number, not both".into(),
            });
        }
        if let Some(a) = aperture {
            (c.aperture, c.f_number) = (a, None);
        }
        if let Some(n) = f_number {
            (c.aperture, c.f_number) = (0.0, Some(n));
        }
        Ok(self.revalidate(&json)?)
    }

    /// This scene with its light moved (the shape keeps its size and
    /// orientation), recoloured or rescaled as `edit` says.
    pub fn edit_light(&self, edit: &LightEdit) -> Result<Scene, EditError> {
        let now = self.light_info().ok_or(EditError::NoLight)?;
        let index = now.index;
        let mut s = self.clone();
        if let Some(p) = edit.position {
            let to = finite3("light.position", p, MAX_COORDINATE)?;
            s.move_object(index, to - DVec3::from_array(now.position));
        }
        if edit.color.is_some() || edit.intensity.is_some() {
            let color = match edit.color {
                Some(c) => unit_color(c)?,
                None if now.intensity > 0.0 => DVec3::from_array(now.color),
                // A dark light brightened without a colour: white.
                None => DVec3::ONE,
            };
            let intensity = edit.intensity.unwrap_or(now.intensity);
            if !(intensity.is_finite() && (0.0..=MAX_EMISSION).contains(&intensity)) {
                return Err(EditError::Field {
                    field: "light.intensity",
                    reason: format!("must be between 0 and {MAX_EMISSION:e} (got {intensity})"),
                });
            }
            let m = own_material(&mut s, index)?;
            s.materials[m].emission = color * intensity;
        }
        Ok(s.revalidate(&s.to_json())?)
    }
}

fn finite3(field: &'static str, v: [f64; 3], max: f64) -> Result<DVec3, EditError> {
    if v.iter().all(|x| x.is_finite() && x.abs() <= max) {
        Ok(DVec3::from_array(v))
    } else {
        Err(EditError::Field {
            field,
            reason: format!("components must be finite and within +-{max:e}"),
        })
    }
}

/// A colour with components in [0, 1].
fn unit_color(c: [f64; 3]) -> Result<DVec3, EditError> {
    let field = "light.color";
    let c = finite3(field, c, 1.0)?;
    if c.min_element() < 0.0 {
        return Err(EditError::Field {
            field,
            reason: "components must be between 0 and 1".into(),
        });
    }
    Ok(c)
}

/// The index of a material used by object `index` alone: its own, or a copy
/// made for it when other objects share it (or, for a mesh, when it is one
/// of its file's).
fn own_material(s: &mut Scene, index: usize) -> Result<usize, EditError> {
    let m = s.objects[index].material;
    let import = match s.objects[index].shape {
        Shape::Import(k) if s.imports[k].kind == ImportKind::Model => {
            return Err(EditError::Field {
                field: "light.color",
                reason: "the light is a whole model file: recolour it in the file, or place it as a mesh".into(),
            })
        }
        Shape::Import(k) => Some(k),
        _ => None,
    };
    let shared = s
        .objects
        .iter()
        .enumerate()
        .any(|(i, o)| i != index && o.material == m);
    if !shared && !s.materials[m].imported {
        return Ok(m);
    }
    let mut own = s.materials[m].clone();
    own.name = unique_name(s, &format!("{}-light", own.name.replace('/', "-")));
    own.imported = false;
    if let Some(k) = import {
        s.imports[k].json.material = Some(own.name.clone());
    }
    s.materials.push(own);
    s.objects[index].material = s.materials.len() - 1;
    Ok(s.materials.len() - 1)
}

fn unique_name(s: &Scene, base: &str) -> String {
    let taken = |name: &str| s.materials.iter().any(|m| m.name == name);
    if !taken(base) {
        return base.to_owned();
    }
    (2..)
        .map(|n| format!("{base}-{n}"))
        .find(|name| !taken(name))
        .unwrap_or_else(|| base.to_owned())
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn cornell() -> Scene {
        super::super::builtin("cornell").unwrap()
    }

    /// Cornell's light on a quad that shares its material with a second quad.
    fn shared_quad_light() -> Scene {
        Scene::from_json_str(
            r#"{"camera": {"position": [0, 1, 5], "look_at": [0, 1, 0], "vfov_deg": 40},
                "materials": {"lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [4, 2, 1]},
                              "lamp-light": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
                "objects": [{"type": "quad", "corner": [-1, 2, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "lamp"},
                            {"type": "quad", "corner": [-1, 0, -1], "edge_u": [2, 0, 0], "edge_v": [0, 0, 2], "material": "lamp"},
                            {"type": "sphere", "center": [0, 1, 0], "radius": 0.5, "material": "lamp-light"}],
                "light": 0}"#,
        )
        .unwrap()
    }

    #[test]
    fn light_info_reads_centre_colour_and_intensity() {
        let info = cornell().light_info().unwrap();
        assert_eq!(info.position, [50.0, 66.6, 81.6]);
        assert_eq!((info.color, info.intensity), ([1.0, 1.0, 1.0], 12.0));
        let quad = shared_quad_light().light_info().unwrap();
        assert_eq!(quad.index, 0);
        assert_eq!(quad.position, [0.0, 2.0, 0.0], "the quad's centre");
        assert_eq!((quad.color, quad.intensity), ([1.0, 0.5, 0.25], 4.0));
    }

    #[test]
    fn moving_a_light_keeps_its_shape_and_everything_else() {
        let s = cornell();
        let moved = s
            .edit_light(&LightEdit {
                position: Some([20.0, 60.0, 100.0]),
                ..LightEdit::default()
            })
            .unwrap();
        let i = s.light.unwrap();
        assert_eq!(
            moved.objects[i].shape,
            Shape::Sphere {
                center: DVec3::new(20.0, 60.0, 100.0),
                radius: 7.0
            }
        );
        assert_eq!(moved.light_info().unwrap().intensity, 12.0);
        assert_eq!(moved.camera, s.camera);
        assert_eq!(moved.objects.len(), s.objects.len());
        // A quad moves by its centre; its edges stay.
        let q = shared_quad_light()
            .edit_light(&LightEdit {
                position: Some([1.0, 3.0, 0.5]),
                ..LightEdit::default()
            })
            .unwrap();
        let Shape::Quad {
            corner,
            edge_u,
            edge_v,
        } = q.objects[0].shape
        else {
            panic!("a quad")
        };
        assert_eq!(
            (corner, edge_u, edge_v),
            (
                DVec3::new(0.0, 3.0, -0.5),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, 2.0)
            )
        );
        assert_eq!(q.light_info().unwrap().position, [1.0, 3.0, 0.5]);
    }

    #[test]
    fn recolouring_a_shared_material_splits_it_with_a_fresh_name() {
        let s = shared_quad_light();
        let e = s
            .edit_light(&LightEdit {
                color: Some([0.0, 1.0, 0.5]),
                intensity: Some(8.0),
                ..LightEdit::default()
            })
            .unwrap();
        let light = &e.materials[e.objects[0].material];
        // "lamp-light" is taken by the sphere's material: the copy is "lamp-light-2".
        assert_eq!(light.name, "lamp-light-2");
        assert_eq!(
            light.emission,
            DVec3::new(0.0, 8.0, 4.0),
            "colour times intensity"
        );
        let other = &e.materials[e.objects[1].material];
        assert_eq!(
            (other.name.as_str(), other.emission),
            ("lamp", DVec3::new(4.0, 2.0, 1.0)),
            "the other quad keeps its lamp"
        );
        assert_eq!(e.materials[e.objects[2].material].name, "lamp-light");
        // An intensity alone keeps the colour; a light of its own is not copied again.
        let again = e
            .edit_light(&LightEdit {
                intensity: Some(2.0),
                ..LightEdit::default()
            })
            .unwrap();
        assert_eq!(again.materials.len(), e.materials.len());
        assert_eq!(again.light_info().unwrap().color, [0.0, 1.0, 0.5]);
        assert_eq!(again.light_info().unwrap().intensity, 2.0);
    }

    #[test]
    fn a_dark_light_brightened_without_a_colour_is_white() {
        let dark = cornell()
            .edit_light(&LightEdit {
                intensity: Some(0.0),
                ..LightEdit::default()
            })
            .unwrap();
        assert_eq!(dark.light_info().unwrap().color, [0.0; 3]);
        let lit = dark
            .edit_light(&LightEdit {
                intensity: Some(3.0),
                ..LightEdit::default()
            })
            .unwrap();
        assert_eq!(lit.light_info().unwrap().color, [1.0; 3]);
    }

    #[test]
    fn bad_light_edits_name_the_field_and_change_nothing() {
        let s = cornell();
        let cases = [
            (
                LightEdit {
                    position: Some([f64::NAN, 0.0, 0.0]),
                    ..LightEdit::default()
                },
                "light.position: components must be finite",
            ),
            (
                LightEdit {
                    position: Some([2e15, 0.0, 0.0]),
                    ..LightEdit::default()
                },
                "light.position",
            ),
            (
                LightEdit {
                    color: Some([2.0, 0.0, 0.0]),
                    ..LightEdit::default()
                },
                "light.color: components must be finite and within",
            ),
            (
                LightEdit {
                    color: Some([-0.5, 1.0, 0.0]),
                    ..LightEdit::default()
                },
                "light.color: components must be between 0 and 1",
            ),
            (
                LightEdit {
                    intensity: Some(-1.0),
                    ..LightEdit::default()
                },
                "light.intensity: must be between 0",
            ),
            (
                LightEdit {
                    intensity: Some(f64::INFINITY),
                    ..LightEdit::default()
                },
                "light.intensity",
            ),
        ];
        for (edit, needle) in cases {
            let e = s.edit_light(&edit).expect_err(needle).to_string();
            assert!(
                e.starts_with(needle),
                "{e:?} does not start with {needle:?}"
            );
        }
        let mut none = s.clone();
        none.light = None;
        assert_eq!(
            none.edit_light(&LightEdit::default()),
            Err(EditError::NoLight)
        );
    }

    #[test]
    fn camera_edits_replace_only_the_fields_given_and_are_validated() {
        let s = cornell();
        let e = s
            .edit_camera(&CameraEdit {
                vfov_deg: Some(50.0),
                ..CameraEdit::default()
            })
            .unwrap();
        assert_eq!(e.camera.vfov_deg, 50.0);
        assert_eq!(
            (e.camera.position, e.camera.look_at, e.camera.near_clip),
            (s.camera.position, s.camera.look_at, s.camera.near_clip)
        );
        let err = s
            .edit_camera(&CameraEdit {
                up: Some([0.0, 0.0, 0.0]),
                ..CameraEdit::default()
            })
            .unwrap_err();
        assert!(err.to_string().starts_with("camera.up"), "{err}");
        let err = s
            .edit_camera(&CameraEdit {
                vfov_deg: Some(200.0),
                ..CameraEdit::default()
            })
            .unwrap_err();
        assert!(err.to_string().starts_with("camera.vfov_deg"), "{err}");
    }
}
