//! A material's texture maps, slot by slot: written once for the loaders
//! (`model`, whose slots refer to a model's images) and the renderer's
//! scene (`render::scene`, whose slots hold textures), below both.

/// Map slots per material, in [`Maps::by_slot`]'s order (the renderer's
/// `texture::Map`).
pub const SLOTS: usize = 11;

/// The maps of one material (all `None`: an untextured material), each
/// slot a `T`. glTF's metallic-roughness texture fills both the metallic
/// (its blue channel) and the roughness (green) slot.
#[derive(Clone, Debug, PartialEq)]
pub struct Maps<T> {
    /// Multiplies the base colour (sRGB RGB).
    pub base_color: Option<T>,
    pub metallic: Option<T>,
    pub roughness: Option<T>,
    /// A tangent-space normal map.
    pub normal: Option<T>,
    /// Multiplies the emission (sRGB RGB, glTF `emissiveTexture`).
    pub emission: Option<T>,
    /// `pbr`'s transmission (red), clear coat weight (red) and roughness
    /// (green), specular strength (alpha) and colour (sRGB RGB), as glTF's
    /// extensions' textures (specular colour: also OBJ's `map_Ks`).
    pub transmission: Option<T>,
    pub clearcoat: Option<T>,
    pub clearcoat_roughness: Option<T>,
    pub specular: Option<T>,
    pub specular_color: Option<T>,
    /// The clear coat's own normal map (glTF's `clearcoatNormalTexture`;
    /// without one the coat follows the surface's unmapped normal).
    pub clearcoat_normal: Option<T>,
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

/// Which surfaces a ray stops at.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum AlphaMode {
    #[default]
    Opaque,
    /// Where alpha >= the cutoff.
    Mask(f32),
    /// With probability alpha.
    Blend,
}

impl<T> Default for Maps<T> {
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

impl<T> Maps<T> {
    /// The slots in order.
    pub fn by_slot(&self) -> [Option<&T>; SLOTS] {
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

    /// Whether no slot is set.
    pub fn is_empty(&self) -> bool {
        self.by_slot().iter().all(Option::is_none)
    }

    /// The same maps with every set slot passed through `f`.
    pub fn map<U>(&self, mut f: impl FnMut(&T) -> U) -> Maps<U> {
        let mut slot = |s: &Option<T>| s.as_ref().map(&mut f);
        Maps {
            base_color: slot(&self.base_color),
            metallic: slot(&self.metallic),
            roughness: slot(&self.roughness),
            normal: slot(&self.normal),
            emission: slot(&self.emission),
            transmission: slot(&self.transmission),
            clearcoat: slot(&self.clearcoat),
            clearcoat_roughness: slot(&self.clearcoat_roughness),
            specular: slot(&self.specular),
            specular_color: slot(&self.specular_color),
            clearcoat_normal: slot(&self.clearcoat_normal),
            normal_scale: self.normal_scale,
            clearcoat_normal_scale: self.clearcoat_normal_scale,
            alpha_mode: self.alpha_mode,
            alpha: self.alpha,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_keeps_every_slot_in_place() {
        let mut m = Maps::<usize>::default();
        let slots = [
            &mut m.base_color,
            &mut m.metallic,
            &mut m.roughness,
            &mut m.normal,
            &mut m.emission,
            &mut m.transmission,
            &mut m.clearcoat,
            &mut m.clearcoat_roughness,
            &mut m.specular,
            &mut m.specular_color,
            &mut m.clearcoat_normal,
        ];
        for (i, s) in slots.into_iter().enumerate() {
            *s = Some(i);
        }
        (m.normal_scale, m.clearcoat_normal_scale) = (0.5, 2.0);
        (m.alpha_mode, m.alpha) = (AlphaMode::Mask(0.25), 0.75);
        let doubled = m.map(|&i| 2 * i);
        let want: Vec<Option<usize>> = (0..SLOTS).map(|i| Some(2 * i)).collect();
        assert_eq!(doubled.by_slot().map(|s| s.copied()).to_vec(), want);
        assert_eq!(
            (doubled.normal_scale, doubled.clearcoat_normal_scale),
            (0.5, 2.0)
        );
        assert_eq!(
            (doubled.alpha_mode, doubled.alpha),
            (AlphaMode::Mask(0.25), 0.75)
        );
        assert!(!doubled.is_empty());
        assert!(Maps::<usize>::default().is_empty());
    }
}
