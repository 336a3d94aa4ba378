//! A scene material's texture maps, as validation and model files give
//! them (`render::maps` has the hot path's form and how a hit reads them).

pub use super::map_json::MapSource;
pub use crate::material_maps::AlphaMode;
use crate::render::texture::{Map, Sampling, Texture};
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
pub type Maps = crate::material_maps::Maps<MapSlot>;

impl Maps {
    /// The slots that are set, by their field's name.
    pub fn slots(&self) -> impl Iterator<Item = (&'static str, &MapSlot)> {
        (Map::ALL.into_iter().zip(self.by_slot())).filter_map(|(m, s)| s.map(|s| (m.name(), s)))
    }
}
