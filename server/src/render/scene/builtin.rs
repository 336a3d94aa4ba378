//! Built-in scenes by name. They are written as scene JSON and go through the
//! same validation as user scenes.

use super::Scene;
use serde_json::{json, Value};

/// Names accepted by [`builtin`], in the order `pathstream scenes` lists them.
pub const BUILTIN_NAMES: [&str; 5] = [
    "cornell",
    "cornell-glass",
    "cornell-quads",
    "smallpt",
    "furnace",
];

/// A built-in scene by name.
pub fn builtin(name: &str) -> Option<Scene> {
    let json = match name {
        "cornell" => cornell(false),
        "cornell-glass" => cornell(true),
        "cornell-quads" => cornell_quads(),
        "smallpt" => smallpt(),
        "furnace" => furnace(),
        _ => return None,
    };
    Scene::from_json_value(json).ok()
}

/// smallpt's camera, exactly: position (50, 52, 295.6), direction
/// (0, -0.042612, -1), vertical half-extent 0.25675 at unit distance, rays
/// starting 140 units out (past the black front wall).
fn smallpt_camera() -> Value {
    json!({
        "position": [50.0, 52.0, 295.6],
        "look_at": [50.0, 52.0 - 0.042612, 295.6 - 1.0],
        "up": [0.0, 1.0, 0.0],
        "vfov_deg": 2.0 * 0.25675f64.atan().to_degrees(),
        "near_clip": 140.0
    })
}

fn sphere(center: [f64; 3], radius: f64, material: &str) -> Value {
    json!({"type": "sphere", "center": center, "radius": radius, "material": material})
}

fn quad(corner: [f64; 3], edge_u: [f64; 3], edge_v: [f64; 3], material: &str) -> Value {
    json!({"type": "quad", "corner": corner, "edge_u": edge_u, "edge_v": edge_v, "material": material})
}

/// smallpt's six radius-1e5 walls: left, right, back, front, floor, ceiling.
fn sphere_walls(back: &str) -> Vec<Value> {
    vec![
        sphere([1e5 + 1.0, 40.8, 81.6], 1e5, "red"),
        sphere([-1e5 + 99.0, 40.8, 81.6], 1e5, "blue"),
        sphere([50.0, 40.8, 1e5], 1e5, back),
        sphere([50.0, 40.8, -1e5 + 170.0], 1e5, "black"),
        sphere([50.0, 1e5, 81.6], 1e5, "white"),
        sphere([50.0, -1e5 + 81.6, 81.6], 1e5, "white"),
    ]
}

/// The same box as quads on the planes x=1, x=99, z=0, z=170, y=0, y=81.6.
fn quad_walls(back: &str) -> Vec<Value> {
    vec![
        quad([1.0, 0.0, 0.0], [0.0, 0.0, 170.0], [0.0, 81.6, 0.0], "red"),
        quad(
            [99.0, 0.0, 0.0],
            [0.0, 0.0, 170.0],
            [0.0, 81.6, 0.0],
            "blue",
        ),
        quad([1.0, 0.0, 0.0], [98.0, 0.0, 0.0], [0.0, 81.6, 0.0], back),
        quad(
            [1.0, 0.0, 170.0],
            [98.0, 0.0, 0.0],
            [0.0, 81.6, 0.0],
            "black",
        ),
        quad(
            [1.0, 0.0, 0.0],
            [98.0, 0.0, 0.0],
            [0.0, 0.0, 170.0],
            "white",
        ),
        quad(
            [1.0, 81.6, 0.0],
            [98.0, 0.0, 0.0],
            [0.0, 0.0, 170.0],
            "white",
        ),
    ]
}

fn box_materials() -> Value {
    json!({
        "red": {"type": "diffuse", "albedo": [0.75, 0.25, 0.25]},
        "blue": {"type": "diffuse", "albedo": [0.25, 0.25, 0.75]},
        "white": {"type": "diffuse", "albedo": [0.75, 0.75, 0.75]},
        "black": {"type": "diffuse", "albedo": [0.0, 0.0, 0.0]},
        "mirror": {"type": "mirror", "albedo": [0.999, 0.999, 0.999]},
        "glass": {"type": "glass", "ior": 1.5, "fresnel": "exact"},
        "lamp": {"type": "diffuse", "albedo": [0.0, 0.0, 0.0], "emission": [12.0, 12.0, 12.0]}
    })
}

/// Thesis scene 1 (`glass == false`: two white diffuse balls) and scene 2
/// (mirror ball, glass ball, mirror back wall), with the small light.
fn cornell(glass: bool) -> Value {
    let (left, right, back) = if glass {
        ("mirror", "glass", "mirror")
    } else {
        ("white", "white", "white")
    };
    let mut objects = sphere_walls(back);
    objects.push(sphere([27.0, 16.5, 47.0], 16.5, left));
    objects.push(sphere([73.0, 16.5, 78.0], 16.5, right));
    objects.push(sphere([50.0, 66.6, 81.6], 7.0, "lamp"));
    json!({"camera": smallpt_camera(), "materials": box_materials(), "objects": objects, "light": 8})
}

fn cornell_quads() -> Value {
    let mut objects = quad_walls("mirror");
    objects.push(sphere([27.0, 16.5, 47.0], 16.5, "mirror"));
    objects.push(sphere([73.0, 16.5, 78.0], 16.5, "glass"));
    objects.push(sphere([50.0, 66.6, 81.6], 7.0, "lamp"));
    json!({"camera": smallpt_camera(), "materials": box_materials(), "objects": objects, "light": 8})
}

/// smallpt's scene exactly: its big light (radius 600) pokes 0.27 units
/// through the ceiling; its glass is Schlick with albedo 0.999.
fn smallpt() -> Value {
    let mut materials = box_materials();
    materials["glass"] =
        json!({"type": "glass", "ior": 1.5, "albedo": [0.999, 0.999, 0.999], "fresnel": "schlick"});
    let mut objects = sphere_walls("white");
    objects.push(sphere([27.0, 16.5, 47.0], 16.5, "mirror"));
    objects.push(sphere([73.0, 16.5, 78.0], 16.5, "glass"));
    objects.push(sphere([50.0, 681.6 - 0.27, 81.6], 600.0, "lamp"));
    json!({"camera": smallpt_camera(), "materials": materials, "objects": objects, "light": 8})
}

/// The white furnace: inside a closed sphere of albedo 0.5 and emission 0.5
/// the radiance is exactly 0.5 / (1 - 0.5) = 1 everywhere.
fn furnace() -> Value {
    json!({
        "camera": {"position": [0.0, 0.0, 0.0], "look_at": [0.0, 0.0, -1.0], "up": [0.0, 1.0, 0.0], "vfov_deg": 60.0},
        "materials": {"shell": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5], "emission": [0.5, 0.5, 0.5]}},
        "objects": [sphere([0.0, 0.0, 0.0], 1.0, "shell")],
        "light": 0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_validates_and_round_trips() {
        for name in BUILTIN_NAMES {
            let scene = builtin(name).unwrap_or_else(|| panic!("{name} does not validate"));
            let again = Scene::from_json(&scene.to_json()).expect("round trip");
            assert_eq!(scene, again, "{name}");
            assert!(scene.emitters().count() > 0, "{name} has no light");
        }
        assert!(builtin("nope").is_none());
    }

    #[test]
    fn smallpt_camera_is_exact() {
        let c = builtin("smallpt").expect("smallpt").camera;
        let vfov = 2.0 * 0.25675f64.atan().to_degrees();
        assert!((c.vfov_deg - vfov).abs() < 1e-12);
        assert!((c.vfov_deg - 28.7993).abs() < 1e-3);
        assert_eq!(c.near_clip, 140.0);
    }
}
