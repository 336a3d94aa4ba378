//! A scene material's texture maps, as validation and model files give
//! them (`render::maps` has the hot path's form and how a hit reads them).

pub use super::map_json::MapSource;
pub use crate::render::alpha::AlphaMode;
use crate::render::texture::{Sampling, Texture};
use std::sync::Arc;

/// A texture as a material slot reads it.
#[derive(Clone, Debug)]
pub struct MapSlot {
    pub texture: Arc<Texture>,
    pub sampling: Sampling,
    /// How scene JSON named it (None: a model file's own).
    pub source: Option<MapSource>,
}

impl PartialEq for MapSlot {
    fn eq(&self, o: &Self) -> bool {
        (Arc::ptr_eq(&self.texture, &o.texture) || self.texture == o.texture)
            && self.sampling == o.sampling
            && self.source == o.source
    }
}

/// The maps of a scene material (all `None`: an untextured material).
#[derive(Clone, Debug, PartialEq)]
pub struct Maps {
    pub base_color: Option<MapSlot>,
    pub metallic: Option<MapSlot>,
    pub roughness: Option<MapSlot>,
    pub normal: Option<MapSlot>,
    /// Multiplies the emission (sRGB RGB, glTF `emissiveTexture`).
    pub emission: Option<MapSlot>,
    /// The normal map's x and y scale (glTF `normalTexture.scale`).
    pub normal_scale: f64,
    /// glTF's `alphaMode` (meshes only: `render::alpha`), and the base
    /// colour factor's alpha, which the base colour texture's alpha channel
    /// multiplies.
    pub alpha_mode: AlphaMode,
    pub alpha: f64,
}

impl Default for Maps {
    fn default() -> Self {
        Self {
            base_color: None,
            metallic: None,
            roughness: None,
            normal: None,
            emission: None,
            normal_scale: 1.0,
            alpha_mode: AlphaMode::Opaque,
            alpha: 1.0,
        }
    }
}

impl Maps {
    pub fn is_empty(&self) -> bool {
        self.base_color.is_none()
            && self.metallic.is_none()
            && self.roughness.is_none()
            && self.normal.is_none()
            && self.emission.is_none()
    }

    /// The slots that are set, by name.
    pub fn slots(&self) -> impl Iterator<Item = (&'static str, &MapSlot)> {
        [
            ("base_color", &self.base_color),
            ("metallic", &self.metallic),
            ("roughness", &self.roughness),
            ("normal", &self.normal),
            ("emission", &self.emission),
        ]
        .into_iter()
        .filter_map(|(n, s)| s.as_ref().map(|s| (n, s)))
    }
}
