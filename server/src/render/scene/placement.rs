//! `transform` of a mesh or model: JSON to world_from_object and back.

use super::json::{RotateJson, ScaleJson, TransformJson};
use super::SceneError;
use crate::render::math::{DAffine3, DMat3, DVec3};

type Result<T> = std::result::Result<T, SceneError>;

/// Largest |scale| (and smallest) accepted.
const MAX_SCALE: f64 = 1e9;

/// The transform a JSON `transform` (at `path`) describes; the identity
/// if there is none.
pub(super) fn world_from_object(path: &str, t: Option<&TransformJson>) -> Result<DAffine3> {
    let Some(t) = t else {
        return Ok(DAffine3::IDENTITY);
    };
    let err = |field: &str, why: String| SceneError::new(format!("{path}.{field}"), why);
    let finite = |field: &str, v: &[f64]| -> Result<()> {
        match v.iter().position(|x| !x.is_finite()) {
            Some(i) => Err(err(
                &format!("{field}[{i}]"),
                "must be a finite number".into(),
            )),
            None => Ok(()),
        }
    };
    if let Some(m) = &t.matrix {
        if t.translate.is_some() || t.rotate.is_some() || t.scale.is_some() {
            return Err(err(
                "matrix",
                "give either matrix or translate/rotate/scale, not both".into(),
            ));
        }
        for (r, row) in m.iter().enumerate() {
            finite(&format!("matrix[{r}]"), row)?;
        }
        if m[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(err(
                "matrix[3]",
                "the last row must be [0, 0, 0, 1] (no projection)".into(),
            ));
        }
        let matrix3 = DMat3::from_cols(
            DVec3::new(m[0][0], m[1][0], m[2][0]),
            DVec3::new(m[0][1], m[1][1], m[2][1]),
            DVec3::new(m[0][2], m[1][2], m[2][2]),
        );
        let a = DAffine3 {
            matrix3,
            translation: DVec3::new(m[0][3], m[1][3], m[2][3]),
        };
        return check_invertible(path, "matrix", a);
    }
    let translate = match t.translate {
        Some(v) => {
            finite("translate", &v)?;
            DVec3::from_array(v)
        }
        None => DVec3::ZERO,
    };
    let rotation = match &t.rotate {
        Some(RotateJson { axis, deg }) => {
            finite("rotate.axis", axis)?;
            finite("rotate.deg", &[*deg])?;
            let axis = DVec3::from_array(*axis);
            if !(axis.length() > 0.0) {
                return Err(err("rotate.axis", "must not be the zero vector".into()));
            }
            DMat3::from_axis_angle(axis.normalize(), deg.to_radians())
        }
        None => DMat3::IDENTITY,
    };
    let scale = match &t.scale {
        Some(ScaleJson::Uniform(s)) => {
            finite("scale", &[*s])?;
            DVec3::splat(*s)
        }
        Some(ScaleJson::PerAxis(v)) => {
            finite("scale", v)?;
            DVec3::from_array(*v)
        }
        None => DVec3::ONE,
    };
    if scale.abs().min_element() < 1.0 / MAX_SCALE || scale.abs().max_element() > MAX_SCALE {
        return Err(err(
            "scale",
            format!(
                "every factor must be non-zero, between 1e-9 and 1e9 in size (got {:?})",
                scale.to_array()
            ),
        ));
    }
    let a = DAffine3 {
        matrix3: rotation * DMat3::from_diagonal(scale),
        translation: translate,
    };
    check_invertible(path, "scale", a)
}

fn check_invertible(path: &str, field: &str, a: DAffine3) -> Result<DAffine3> {
    let det = a.matrix3.determinant();
    let size = a.matrix3.x_axis.length() * a.matrix3.y_axis.length() * a.matrix3.z_axis.length();
    if !(det.abs() > 1e-12 * size) || !(size > 0.0) {
        return Err(SceneError::new(
            format!("{path}.{field}"),
            "the transform is singular (it flattens the mesh)",
        ));
    }
    Ok(a)
}

/// A transform as JSON: the identity as none, else the matrix.
pub(super) fn to_json(a: &DAffine3) -> Option<TransformJson> {
    if *a == DAffine3::IDENTITY {
        return None;
    }
    let m = a.matrix3;
    let t = a.translation;
    Some(TransformJson {
        matrix: Some([
            [m.x_axis.x, m.y_axis.x, m.z_axis.x, t.x],
            [m.x_axis.y, m.y_axis.y, m.z_axis.y, t.y],
            [m.x_axis.z, m.y_axis.z, m.z_axis.z, t.z],
            [0.0, 0.0, 0.0, 1.0],
        ]),
        ..TransformJson::default()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn translate_rotate_scale_compose_in_that_order() {
        let t = TransformJson {
            translate: Some([1.0, 2.0, 3.0]),
            rotate: Some(RotateJson {
                axis: [0.0, 0.0, 1.0],
                deg: 90.0,
            }),
            scale: Some(ScaleJson::Uniform(2.0)),
            matrix: None,
        };
        let a = world_from_object("objects[0].transform", Some(&t)).expect("valid");
        // x -> scaled 2 -> rotated to +y -> moved.
        let p = a.transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 4.0, 3.0)).length() < 1e-12, "{p:?}");
        let back = world_from_object("t", to_json(&a).as_ref()).expect("matrix form");
        assert!(
            (back.transform_point3(DVec3::new(0.3, -2.0, 5.0))
                - a.transform_point3(DVec3::new(0.3, -2.0, 5.0)))
            .length()
                < 1e-12
        );
    }

    #[test]
    fn bad_transforms_name_the_field() {
        let cases = [
            (
                TransformJson {
                    scale: Some(ScaleJson::PerAxis([1.0, 0.0, 1.0])),
                    ..Default::default()
                },
                "t.scale",
            ),
            (
                TransformJson {
                    rotate: Some(RotateJson {
                        axis: [0.0; 3],
                        deg: 5.0,
                    }),
                    ..Default::default()
                },
                "t.rotate.axis",
            ),
            (
                TransformJson {
                    translate: Some([0.0, f64::NAN, 0.0]),
                    ..Default::default()
                },
                "t.translate[1]",
            ),
            (
                TransformJson {
                    matrix: Some([
                        [1.0, 0.0, 0.0, 0.0],
                        [0.0, 1.0, 0.0, 0.0],
                        [0.0, 0.0, 1.0, 0.0],
                        [0.0, 0.0, 1.0, 1.0],
                    ]),
                    ..Default::default()
                },
                "t.matrix[3]",
            ),
            (
                TransformJson {
                    matrix: Some([
                        [1.0, 0.0, 0.0, 0.0],
                        [1.0, 0.0, 0.0, 0.0],
                        [0.0, 0.0, 1.0, 0.0],
                        [0.0, 0.0, 0.0, 1.0],
                    ]),
                    ..Default::default()
                },
                "t.matrix",
            ),
        ];
        for (t, path) in cases {
            let e = world_from_object("t", Some(&t)).expect_err("invalid");
            assert_eq!(e.path, path, "{e}");
        }
    }
}
