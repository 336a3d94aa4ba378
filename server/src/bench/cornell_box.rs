//! The triangle Cornell box the mesh scenes share (`bench::scenes`,
//! `bench::textured`): smallpt's box and camera, every wall two
//! triangles, an emissive square in a hole of the ceiling, and two balls.

use crate::model::generate::icosphere;
use crate::model::MeshData;
use serde_json::{json, Value};

/// Two triangles spanning the parallelogram corner + s u + t v.
fn square(corner: [f64; 3], u: [f64; 3], v: [f64; 3], material: &str) -> Value {
    let at = |s: f64, t: f64| [0, 1, 2].map(|k| corner[k] + s * u[k] + t * v[k]);
    json!({
        "type": "mesh",
        "data": {
            "positions": [at(0.0, 0.0), at(1.0, 0.0), at(1.0, 1.0), at(0.0, 1.0)],
            "triangles": [[0, 1, 2], [0, 2, 3]],
        },
        "material": material,
    })
}

/// A smooth icosphere of radius `r` at `center`.
fn ball(mesh: &MeshData, center: [f64; 3], r: f64, material: &str) -> Value {
    json!({
        "type": "mesh",
        "data": {"positions": mesh.positions, "triangles": mesh.triangles, "normals": mesh.normals},
        "material": material,
        "transform": {"translate": center, "scale": r},
    })
}

/// The box's scene JSON with balls of materials `left` and `right`, the balls its last two objects (left,
/// right), each a unit mesh placed by its `transform`.
pub fn box_json(left: Value, right: Value) -> Value {
    let sphere = icosphere(5);
    let (x0, x1, y1, z1) = (1.0, 99.0, 81.6, 170.0);
    let (lx0, lx1, lz0, lz1) = (34.0, 66.0, 66.0, 98.0);
    let objects = vec![
        square([x0, 0.0, 0.0], [0.0, 0.0, z1], [0.0, y1, 0.0], "red"),
        square([x1, 0.0, 0.0], [0.0, y1, 0.0], [0.0, 0.0, z1], "blue"),
        square([x0, 0.0, 0.0], [x1 - x0, 0.0, 0.0], [0.0, y1, 0.0], "white"),
        square([x0, 0.0, 0.0], [0.0, 0.0, z1], [x1 - x0, 0.0, 0.0], "white"),
        // The ceiling around the lamp's hole, [lx0, lx1] x [lz0, lz1].
        square([x0, y1, 0.0], [lx0 - x0, 0.0, 0.0], [0.0, 0.0, z1], "white"),
        square(
            [lx1, y1, 0.0],
            [x1 - lx1, 0.0, 0.0],
            [0.0, 0.0, z1],
            "white",
        ),
        square(
            [lx0, y1, 0.0],
            [lx1 - lx0, 0.0, 0.0],
            [0.0, 0.0, lz0],
            "white",
        ),
        square(
            [lx0, y1, lz1],
            [lx1 - lx0, 0.0, 0.0],
            [0.0, 0.0, z1 - lz1],
            "white",
        ),
        square(
            [lx0, y1, lz0],
            [lx1 - lx0, 0.0, 0.0],
            [0.0, 0.0, lz1 - lz0],
            "lamp",
        ),
        ball(&sphere, [27.0, 16.5, 47.0], 16.5, "left"),
        ball(&sphere, [73.0, 16.5, 78.0], 16.5, "right"),
    ];
    let diffuse = |c: [f64; 3]| json!({"type": "diffuse", "albedo": c});
    json!({
        "camera": {"position": [50.0, 52.0, 295.6], "look_at": [50.0, 51.957388, 294.6],
                   "vfov_deg": 28.799316231093748, "near_clip": 140.0},
        "materials": {
            "red": diffuse([0.75, 0.25, 0.25]),
            "blue": diffuse([0.25, 0.25, 0.75]),
            "white": diffuse([0.75, 0.75, 0.75]),
            "left": left,
            "right": right,
            "lamp": {"type": "diffuse", "albedo": [0.0, 0.0, 0.0], "emission": [8.0, 8.0, 8.0]},
        },
        "objects": objects,
    })
}
