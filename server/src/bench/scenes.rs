//! The benchmark's own scenes, beside the built-in ones (by name, as
//! `--scenes` takes them):
//!
//! - `cornell-glass-mesh`: `cornell-glass` with its glass ball replaced by
//!   a glass bumpy sphere of 20,000 triangles (caustics through a mesh);
//! - `cornell-mesh`: a diffuse Cornell box made only of triangles, lit by
//!   an area light: the walls as two triangles each, two smooth diffuse
//!   icospheres of 20,480 triangles, and an emissive square of two
//!   triangles filling a hole in the ceiling (the scene renderers are
//!   compared on; emitters are two-sided, so a lamp under a closed ceiling
//!   would light the ceiling above it from a hair's breadth);
//! - `cornell-mesh-specular`: `cornell-mesh` with a mirror ball and a
//!   smooth glass ball (smallpt's pair, in triangles: the second scene the
//!   CPU is compared with Mitsuba on);
//! - `cornell-mesh-pbr`: `cornell-mesh` with glTF metallic-roughness balls,
//!   a rough gold metal and a coated blue plastic (what the GGX lobes
//!   cost against the diffuse ones);
//! - `cornell-mesh-frosted`: `cornell-mesh` with rough glass balls, one
//!   frosted (roughness 0.3, transmission 1), one tinted and half
//!   transmissive (what the rough dielectric costs);
//! - `cornell-mesh-coated`: `cornell-mesh` with a red paint under a clear
//!   coat and an amber rough glass ball that absorbs inside (what the coat
//!   and the volume's absorption cost);
//! - `cornell-mesh-textured` (`bench::textured`): `cornell-mesh` with
//!   textured balls (what the maps cost against `cornell-mesh-pbr`);
//! - `glossy-plane`: a rough metal plane (roughness 0.3) reflecting a
//!   small bright sphere light, a large dim quad light, an 80-triangle
//!   glowing ball and a dim sky (every emitter kind in a glossy
//!   reflection: where multiple importance sampling matters);
//! - `sunset-balls`: a diffuse ball and a rough metal ball (roughness 0.3)
//!   on a diffuse floor, lit only by a real HDR environment map (Poly
//!   Haven's CC0 "Venice Sunset" at 256 x 128, `assets/hdri/`, its sun a
//!   few texels): where the map's importance sampling matters;
//! - `sky-room`: a closed 2 x 2 x 2 room of grey quads lit by a small lamp
//!   under its ceiling, under a bright uniform sky (radiance 50) that the
//!   walls hide: power-proportional light selection would spend nearly
//!   every shadow ray on the sky (what the sky probe is for);
//! - `sky-window`: the same room with a 1 x 1 window in one wall, through
//!   which the sky brings ~15x the lamp's light.

use super::cornell_box::box_json;
use crate::model::generate::{bumpy_sphere, icosphere};
use crate::render::envmap::EnvMap;
use crate::render::scene::{LoadedModel, ModelSource, NoFiles, Resolver};
use crate::render::{Scene, SceneError};
use serde_json::{json, Value};
use std::sync::Arc;

/// `cornell-glass-mesh`.
pub const GLASS_MESH: &str = "cornell-glass-mesh";
/// `cornell-mesh`.
pub const CORNELL_MESH: &str = "cornell-mesh";
/// `cornell-mesh-specular`.
pub const CORNELL_MESH_SPECULAR: &str = "cornell-mesh-specular";
/// `cornell-mesh-pbr`.
pub const CORNELL_MESH_PBR: &str = "cornell-mesh-pbr";
/// `cornell-mesh-frosted`.
pub const CORNELL_MESH_FROSTED: &str = "cornell-mesh-frosted";
/// `cornell-mesh-coated`.
pub const CORNELL_MESH_COATED: &str = "cornell-mesh-coated";
/// `cornell-mesh-textured` (`bench::textured`).
pub const CORNELL_MESH_TEXTURED: &str = "cornell-mesh-textured";
/// `glossy-plane`.
pub const GLOSSY_PLANE: &str = "glossy-plane";
/// `sunset-balls`.
pub const SUNSET_BALLS: &str = "sunset-balls";

/// `sky-room`.
pub const SKY_ROOM: &str = "sky-room";
/// `sky-window`.
pub const SKY_WINDOW: &str = "sky-window";

/// This module's scenes by name, with what each is for.
pub const NAMES: [(&str, &str); 11] = [
    (
        GLASS_MESH,
        "cornell-glass with a glass bumpy sphere of 20,000 triangles",
    ),
    (
        CORNELL_MESH,
        "a diffuse Cornell box of triangles, two 20,480-triangle balls, an area light",
    ),
    (
        CORNELL_MESH_SPECULAR,
        "cornell-mesh with a mirror ball and a smooth glass ball",
    ),
    (
        CORNELL_MESH_PBR,
        "cornell-mesh with a rough gold metal ball and a blue plastic one",
    ),
    (
        CORNELL_MESH_FROSTED,
        "cornell-mesh with a frosted glass ball and a tinted half-clear one",
    ),
    (
        CORNELL_MESH_COATED,
        "cornell-mesh with a clear-coated paint and an absorbing amber glass",
    ),
    (
        CORNELL_MESH_TEXTURED,
        "cornell-mesh with textured balls: a painted one (colour, roughness, normal and coat maps) and a brushed metal",
    ),
    (
        GLOSSY_PLANE,
        "a rough metal plane reflecting every emitter kind",
    ),
    (
        SUNSET_BALLS,
        "a diffuse and a rough metal ball lit by an HDR sunset",
    ),
    (
        SKY_ROOM,
        "a closed room lit by a small lamp under a bright sky the walls hide",
    ),
    (
        SKY_WINDOW,
        "sky-room with a 1x1 window the sky shines through",
    ),
];

/// The scene by name: a mesh scene of this module's, else a built-in one
/// or a file.
pub fn load(name: &str) -> Result<Scene, SceneError> {
    match name {
        GLASS_MESH => glass_mesh(),
        CORNELL_MESH => cornell_mesh(),
        CORNELL_MESH_SPECULAR => cornell_mesh_specular(),
        CORNELL_MESH_PBR => cornell_mesh_pbr(),
        CORNELL_MESH_FROSTED => cornell_mesh_frosted(),
        CORNELL_MESH_COATED => cornell_mesh_coated(),
        CORNELL_MESH_TEXTURED => super::textured::cornell_mesh_textured(),
        GLOSSY_PLANE => glossy_plane(0.3),
        SUNSET_BALLS => sunset_balls(),
        SKY_ROOM => sky_room(None, json!([50, 50, 50])),
        SKY_WINDOW => sky_room(Some(1.0), json!([50, 50, 50])),
        _ => crate::resolve::load_scene(name),
    }
}

fn json_of(scene: &Scene) -> Result<Value, SceneError> {
    serde_json::to_value(scene.to_json()).map_err(|e| SceneError::new(".", e.to_string()))
}

/// `cornell-glass-mesh`.
pub fn glass_mesh() -> Result<Scene, SceneError> {
    let mut j = json_of(&crate::resolve::load_scene("cornell-glass")?)?;
    let mesh = bumpy_sphere(20_000);
    let ball = json!({
        "type": "mesh",
        "data": {"positions": mesh.positions, "triangles": mesh.triangles},
        "material": "glass",
        "transform": {"translate": [73.0, 16.5, 78.0], "scale": 14.0},
    });
    if let Some(objects) = j["objects"].as_array_mut() {
        match objects
            .iter()
            .position(|o| o["center"] == json!([73.0, 16.5, 78.0]))
        {
            Some(i) => objects[i] = ball,
            None => objects.push(ball),
        }
    }
    Scene::from_json_value(j)
}

/// `cornell-mesh`: smallpt's box and camera, every surface triangles.
pub fn cornell_mesh() -> Result<Scene, SceneError> {
    let diffuse = json!({"type": "diffuse", "albedo": [0.75, 0.75, 0.75]});
    box_with_balls(diffuse.clone(), diffuse)
}

/// `cornell-mesh-specular`: the same box, a mirror ball and a glass one.
pub fn cornell_mesh_specular() -> Result<Scene, SceneError> {
    box_with_balls(
        json!({"type": "mirror", "albedo": [0.95, 0.95, 0.95]}),
        json!({"type": "glass", "ior": 1.5, "albedo": [1.0, 1.0, 1.0]}),
    )
}

/// `cornell-mesh-pbr`: the same box, metallic-roughness balls.
pub fn cornell_mesh_pbr() -> Result<Scene, SceneError> {
    box_with_balls(
        json!({"type": "pbr", "base_color": [1.0, 0.78, 0.34], "metallic": 1.0, "roughness": 0.35}),
        json!({"type": "pbr", "base_color": [0.2, 0.35, 0.8], "metallic": 0.0, "roughness": 0.5}),
    )
}

/// `cornell-mesh-frosted`: the same box, rough glass balls.
pub fn cornell_mesh_frosted() -> Result<Scene, SceneError> {
    box_with_balls(
        json!({"type": "pbr", "metallic": 0.0, "roughness": 0.3, "transmission": 1.0}),
        json!({"type": "pbr", "base_color": [0.9, 0.6, 0.3], "metallic": 0.0, "roughness": 0.5,
            "transmission": 0.5}),
    )
}

/// `cornell-mesh-coated`: the same box, a clear-coated paint and an
/// absorbing rough glass.
pub fn cornell_mesh_coated() -> Result<Scene, SceneError> {
    box_with_balls(
        json!({"type": "pbr", "base_color": [0.7, 0.05, 0.05], "metallic": 0.0, "roughness": 0.6,
            "clearcoat": 1.0, "clearcoat_roughness": 0.05}),
        json!({"type": "pbr", "metallic": 0.0, "roughness": 0.1, "transmission": 1.0,
            "attenuation": {"color": [0.9, 0.6, 0.2], "distance": 20.0}}),
    )
}

/// The triangle Cornell box with two balls of materials `left` and `right`.
fn box_with_balls(left: Value, right: Value) -> Result<Scene, SceneError> {
    Scene::from_json_value(box_json(left, right))
}

/// `glossy-plane`, its metal of `roughness`.
pub fn glossy_plane(roughness: f64) -> Result<Scene, SceneError> {
    let ball = icosphere(1);
    Scene::from_json_value(json!({
        "camera": {"position": [0, 1.2, 4], "look_at": [0, 0, 0], "vfov_deg": 50},
        "environment": [0.05, 0.06, 0.08],
        "materials": {
            "metal": {"type": "pbr", "base_color": [0.9, 0.8, 0.7], "metallic": 1, "roughness": roughness},
            "small": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [100, 80, 60]},
            "large": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [0.6, 0.7, 0.9]},
            "glow": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [4, 1, 1]}
        },
        "objects": [
            {"type": "quad", "corner": [-3, 0, -3], "edge_u": [0, 0, 6], "edge_v": [6, 0, 0], "material": "metal"},
            {"type": "sphere", "center": [-0.8, 1.0, -1.5], "radius": 0.15, "material": "small"},
            {"type": "quad", "corner": [0.2, 0.8, -3], "edge_u": [3, 0, 0], "edge_v": [0, 2.5, 0], "material": "large"},
            {"type": "mesh", "material": "glow",
             "data": {"positions": ball.positions, "triangles": ball.triangles},
             "transform": {"translate": [-1.6, 0.5, -0.6], "scale": 0.25}}
        ]
    }))
}

/// A 2 x 2 x 2 room of grey quads about the origin with a 0.4 x 0.4 lamp
/// (radiance 20) under its ceiling, the camera inside; `window`: a hole of
/// that side in the wall at x = +1 (the wall then made of four quads
/// around it); `sky`: the environment (`sky-room`, `sky-window`).
pub fn sky_room(window: Option<f64>, sky: Value) -> Result<Scene, SceneError> {
    let quad = |corner: [f64; 3], u: [f64; 3], v: [f64; 3]| json!({"type": "quad", "corner": corner, "edge_u": u, "edge_v": v, "material": "grey"});
    let mut objects = vec![
        quad([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]), // floor
        quad([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),  // ceiling
        quad([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]), // x = -1
        quad([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]), // z = -1
        quad([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),  // z = +1
        json!({"type": "quad", "corner": [-0.2, 0.95, -0.2], "edge_u": [0.4, 0, 0], "edge_v": [0, 0, 0.4], "material": "lamp"}),
    ];
    match window {
        None => objects.push(quad([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0])),
        Some(a) => {
            // The x = +1 wall around a hole a x a at its centre.
            let (lo, hi) = (-a / 2.0, a / 2.0);
            objects.push(quad(
                [1.0, -1.0, -1.0],
                [0.0, 1.0 + lo, 0.0],
                [0.0, 0.0, 2.0],
            ));
            objects.push(quad([1.0, hi, -1.0], [0.0, 1.0 - hi, 0.0], [0.0, 0.0, 2.0]));
            objects.push(quad([1.0, lo, -1.0], [0.0, a, 0.0], [0.0, 0.0, 1.0 + lo]));
            objects.push(quad([1.0, lo, hi], [0.0, a, 0.0], [0.0, 0.0, 1.0 - hi]));
        }
    }
    Scene::from_json_value(json!({
        "camera": {"position": [-0.9, 0, 0.9], "look_at": [0.5, -0.2, -0.5], "vfov_deg": 80},
        "materials": {
            "grey": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
            "lamp": {"type": "diffuse", "albedo": [0, 0, 0], "emission": [20, 20, 20]}
        },
        "objects": objects,
        "environment": sky,
    }))
}

/// The map built into the binary for `sunset-balls`.
struct Sunset;

impl Resolver for Sunset {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        NoFiles.resolve(source)
    }

    fn environment(&self, _: ModelSource<'_>) -> Result<Arc<EnvMap>, String> {
        crate::resolve::builtin_map("sunset")
            .ok_or("no built-in map 'sunset'")?
            .map()
    }
}

/// `sunset-balls`.
pub fn sunset_balls() -> Result<Scene, SceneError> {
    let json = json!({
        "camera": {"position": [0, 1.0, 3.5], "look_at": [0, 0.5, 0], "vfov_deg": 45},
        "environment": {"map": "sunset-256.hdr", "rotation_deg": 200},
        "materials": {
            "white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
            "metal": {"type": "pbr", "base_color": [0.9, 0.8, 0.6], "metallic": 1, "roughness": 0.3}
        },
        "objects": [
            {"type": "quad", "corner": [-4, 0, -4], "edge_u": [0, 0, 8], "edge_v": [8, 0, 0], "material": "white"},
            {"type": "sphere", "center": [-0.6, 0.5, 0], "radius": 0.5, "material": "metal"},
            {"type": "sphere", "center": [0.6, 0.5, 0], "radius": 0.5, "material": "white"}
        ]
    });
    Scene::from_json_str_with(&json.to_string(), &Sunset)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mesh_scenes_are_what_they_say() {
        let s = glass_mesh().expect("valid");
        assert_eq!(s.imports.len(), 1, "one mesh");
        assert!(s.unique_triangles() >= 19_000);
        let c = cornell_mesh().expect("valid");
        assert_eq!(c.imports.len(), 11, "every object is a mesh");
        assert_eq!(
            c.unique_triangles(),
            20_480 + 9 * 2,
            "the balls share theirs"
        );
        assert_eq!(c.emitters().count(), 1, "one area light");
        assert!(c.warnings.is_empty(), "{:?}", c.warnings);
        let p = cornell_mesh_pbr().expect("valid");
        assert_eq!(p.unique_triangles(), c.unique_triangles());
        assert!(p
            .materials
            .iter()
            .any(|m| matches!(m.kind, crate::render::scene::MaterialKind::Pbr { .. })));
        let g = load(GLOSSY_PLANE).expect("valid");
        assert_eq!(g.emitters().count(), 3, "sphere, quad and ball glow");
        assert!(g.warnings.is_empty(), "{:?}", g.warnings);
    }
}
