//! `cornell-mesh-textured`: `cornell-mesh` with its balls textured as a
//! product model's are: a clear-coated paint with base colour, metallic-
//! roughness, normal and clear coat maps, and a brushed metal with
//! metallic-roughness and normal maps (1024 x 1024 RGBA8 each, made in
//! code, on a UV sphere of 20,000 triangles with its own tangents). What
//! the maps cost beside `cornell-mesh-pbr`'s factors-only balls.

use super::cornell_box::box_json;
use crate::model::generate::uv_sphere;
use crate::render::math::DAffine3;
use crate::render::scene::{
    LoadedModel, MapSlot, Maps, MaterialJson, ModelSource, NoFiles, PbrJson, Resolver,
};
use crate::render::texture::{Sampling, Texture};
use crate::render::{Scene, SceneError};
use serde_json::{json, Value};
use std::f32::consts::PI;
use std::sync::Arc;

/// Texels per side of each map.
pub const MAP_SIDE: u32 = 1024;

/// The balls' model files, by name.
struct Balls([(&'static str, Arc<LoadedModel>); 2]);

impl Resolver for Balls {
    fn resolve(&self, source: ModelSource<'_>) -> Result<Arc<LoadedModel>, String> {
        match (self.0.iter()).find(|(name, _)| source == ModelSource::File(name)) {
            Some((_, model)) => Ok(model.clone()),
            None => NoFiles.resolve(source),
        }
    }
}

/// A map `MAP_SIDE` square whose texel (u, v) is `f(u, v)`.
fn map(name: &str, f: impl Fn(f32, f32) -> [u8; 4]) -> Result<MapSlot, SceneError> {
    let n = MAP_SIDE;
    let mut rgba = Vec::with_capacity((n * n * 4) as usize);
    for y in 0..n {
        for x in 0..n {
            rgba.extend(f(x as f32 / n as f32, y as f32 / n as f32));
        }
    }
    let texture = Texture::new(name, n, n, &rgba).map_err(|e| SceneError::new(".", e))?;
    Ok(MapSlot {
        texture: Arc::new(texture),
        sampling: Sampling::default(),
        source: None,
    })
}

/// A tangent-space normal map of bumps `freq` across u and v.
fn bumps(name: &str, freq: f32) -> Result<MapSlot, SceneError> {
    map(name, |u, v| {
        let (sx, sy) = ((u * freq * PI).sin() * 0.3, (v * freq * PI).cos() * 0.3);
        let l = (sx * sx + sy * sy + 1.0).sqrt();
        let byte = |c: f32| ((c / l * 0.5 + 0.5) * 255.0).round() as u8;
        [byte(sx), byte(sy), byte(1.0), 255]
    })
}

/// One ball's model: the UV sphere with `material` and its `maps`.
fn ball(name: &str, material: Value, maps: Maps) -> Result<Arc<LoadedModel>, SceneError> {
    let pbr: PbrJson =
        serde_json::from_value(material).map_err(|e| SceneError::new(name, e.to_string()))?;
    let model = LoadedModel::new(
        name,
        vec![uv_sphere(100, 100)],
        vec![(name.to_owned(), MaterialJson::Pbr(Box::new(pbr)), maps)],
        vec![(0, DAffine3::IDENTITY)],
        None,
        Vec::new(),
    )
    .map_err(|e| SceneError::new(name, e))?;
    Ok(Arc::new(model))
}

/// `cornell-mesh-textured`.
pub fn cornell_mesh_textured() -> Result<Scene, SceneError> {
    // Red and cream stripes; rough bands under a coat that comes and goes.
    let stripes = |u: f32, v: f32| ((u * 24.0).floor() as u32 + (v * 12.0).floor() as u32) % 2;
    let paint = Maps {
        base_color: Some(map("paint-color", |u, v| match stripes(u, v) {
            0 => [200, 60, 40, 255],
            _ => [230, 220, 200, 255],
        })?),
        roughness: Some(map("paint-mr", |u, _| {
            [0, (64.0 + 128.0 * (u * 40.0).sin().abs()) as u8, 0, 255]
        })?),
        normal: Some(bumps("paint-normal", 60.0)?),
        clearcoat: Some(map("paint-coat", |_, v| {
            let c = if (v * 6.0).fract() < 0.5 { 255 } else { 64 };
            [c, c, c, 255]
        })?),
        ..Maps::default()
    };
    let metal = Maps {
        metallic: Some(map("metal-mr", |u, v| {
            let brushed = (128.0 + 100.0 * (v * 300.0 + u * 7.0).sin()) as u8;
            [
                0,
                brushed / 2,
                if stripes(u, v) == 0 { 255 } else { 200 },
                255,
            ]
        })?),
        normal: Some(bumps("metal-normal", 200.0)?),
        ..Maps::default()
    };
    let metal = Maps {
        roughness: metal.metallic.clone(),
        ..metal
    };
    let balls = Balls([
        (
            "painted-ball",
            ball(
                "painted-ball",
                json!({"metallic": 0, "roughness": 1, "clearcoat": 1, "clearcoat_roughness": 0.05}),
                paint,
            )?,
        ),
        (
            "metal-ball",
            ball(
                "metal-ball",
                json!({"base_color": [1.0, 0.78, 0.34], "metallic": 1, "roughness": 1}),
                metal,
            )?,
        ),
    ]);
    let grey = json!({"type": "diffuse", "albedo": [0.5, 0.5, 0.5]});
    let mut j = box_json(grey.clone(), grey);
    // The balls (the last two objects) become the textured models.
    if let Some(objects) = j["objects"].as_array_mut() {
        for (object, file) in objects.iter_mut().rev().zip(["metal-ball", "painted-ball"]) {
            let transform = object["transform"].clone();
            *object = json!({"type": "model", "file": file, "transform": transform});
        }
        if let Some(m) = j["materials"].as_object_mut() {
            m.remove("left");
            m.remove("right");
        }
    }
    Scene::from_json_str_with(&j.to_string(), &balls)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_textured_box_has_its_maps_and_the_pbr_box_its_triangles() {
        let s = cornell_mesh_textured().expect("valid");
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        let textured: Vec<_> = (s.materials.iter())
            .filter(|m| !m.maps.is_empty())
            .collect();
        assert_eq!(textured.len(), 2, "two textured materials");
        assert_eq!(
            textured[0].maps.slots().count() + textured[1].maps.slots().count(),
            7
        );
        assert_eq!(s.emitters().count(), 1, "one area light");
        let balls: u64 = (s.imports.iter().rev().take(2))
            .map(|i| i.model.triangles())
            .sum();
        assert_eq!(balls, 2 * 2 * 100 * 99);
    }
}
