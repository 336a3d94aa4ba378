//! A scene material's texture maps, as validation and model files give
//! them (`render::maps` has the hot path's form and how a hit reads them).

pub use super::map_json::MapSource;
pub use crate::render::alpha::AlphaMode;
use crate::render::texture::{Map, Sampling, Texture, MAP_SLOTS};
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
    /// `pbr`'s transmission (red), clear coat weight (red) and roughness
    /// (green), specular strength (alpha) and colour (sRGB RGB), as glTF's
    /// extensions' textures.
    pub transmission: Option<MapSlot>,
    pub clearcoat: Option<MapSlot>,
    pub clearcoat_roughness: Option<MapSlot>,
    pub specular: Option<MapSlot>,
    pub specular_color: Option<MapSlot>,
    /// The clear coat's own normal map (glTF's `clearcoatNormalTexture`;
    /// without one the coat follows the surface's unmapped normal).
    pub clearcoat_normal: Option<MapSlot>,
    /// The normal maps' x and y scale (glTF `normalTexture.scale`,
    /// `clearcoatNormalTexture.scale`).
    pub normal_scale: f64,
    pub clearcoat_normal_scale: f64,
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
            transmission: None,
            clearcoat: None,
            clearcoat_roughness: None,
            specular: None,
            specular_color: None,
            clearcoat_normal: None,
            normal_scale: 1.0,
            clearcoat_normal_scale: 1.0,
            alpha_mode: AlphaMode::Opaque,
            alpha: 1.0,
        }
    }
}

impl Maps {
    pub fn is_empty(&self) -> bool {
        self.by_map().iter().all(Option::is_none)
    }

    /// The slots in [`Map`]'s order.
    pub fn by_map(&self) -> [Option<&MapSlot>; MAP_SLOTS] {
        [
            self.base_color.as_ref(),
            self.metallic.as_ref(),
            self.roughness.as_ref(),
            self.normal.as_ref(),
            self.emission.as_ref(),
            self.transmission.as_ref(),
            self.clearcoat.as_ref(),
            self.clearcoat_roughness.as_ref(),
            self.specular.as_ref(),
            self.specular_color.as_ref(),
            self.clearcoat_normal.as_ref(),
        ]
    }

    /// The slots that are set, by their field's name.
    pub fn slots(&self) -> impl Iterator<Item = (&'static str, &MapSlot)> {
        (Map::ALL.into_iter().zip(self.by_map())).filter_map(|(m, s)| s.map(|s| (m.name(), s)))
    }
}
