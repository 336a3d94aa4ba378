//! Texture maps in the kernel's layout (`kernels/types.h`, `MapSlot`,
//! `MaterialMaps`, `TexImage`; `kernels/maps.h` reads them): every
//! material's maps, each texture's place in one texel buffer, and the sRGB
//! table the CPU decodes with (`texture::srgb_table`), so that both
//! backends decode the same bytes to the same floats. Bound only when a
//! scene has maps (`HAS_TEXTURES`).

use crate::render::maps::{Slot, WorldMaps};
use crate::render::texture::{Texture, MAP_SLOTS};
use crate::render::world::World;
use bytemuck::{Pod, Zeroable};
use std::sync::{Arc, OnceLock};

/// A material slot: its UV transform's two rows, then (texture, UV set,
/// wrap along u, wrap along v); texture `NO_TEXTURE` when unused.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MapSlot {
    pub xf_u: [f32; 4],
    pub xf_v: [f32; 4],
    pub info: [u32; 4],
}

/// A material's maps and factors (`maps::WorldMaps`): a slot per
/// `texture::Map`, in its order.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MaterialMaps {
    pub slot: [MapSlot; MAP_SLOTS],
    /// metallic factor, roughness factor, normal scale, 1 where metallic
    /// and roughness share a lookup.
    pub factors: [f32; 4],
    /// transmission, clear coat weight, clear coat roughness, specular.
    pub layers: [f32; 4],
    /// The specular colour factor, the clear coat normal map's scale.
    pub spec_color: [f32; 4],
}

/// Where a texture's texels start in `texels`, and its size.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TexImage {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub pad0: u32,
}

const _: () = assert!(std::mem::size_of::<MapSlot>() == 48);
const _: () = assert!(std::mem::size_of::<MaterialMaps>() == 576);
const _: () = assert!(std::mem::size_of::<TexImage>() == 16);

/// A world's maps and textures as the kernel reads them (all empty when
/// no material has maps).
#[derive(Debug, Default)]
pub struct PackedTextures {
    pub maps: Vec<MaterialMaps>,
    pub images: Vec<TexImage>,
    /// The textures, in `images`' order: their texels one after another
    /// are the kernel's `texels` ([`PackedTextures::texels`]).
    pub textures: Vec<Arc<Texture>>,
    texels: OnceLock<Vec<u32>>,
    pub srgb: Vec<f32>,
}

impl PackedTextures {
    /// Every texture's texels, one after another: copied on first use
    /// only, so that a device already holding these textures (the jobs of
    /// one scene: every camera move) never has them copied.
    pub fn texels(&self) -> &[u32] {
        self.texels.get_or_init(|| {
            (self.textures.iter())
                .flat_map(|t| t.texels.iter().copied())
                .collect()
        })
    }

    /// The bytes [`PackedTextures::texels`] holds, without making it.
    pub fn texel_bytes(&self) -> usize {
        self.textures.iter().map(|t| t.texels.len() * 4).sum()
    }
}

pub(super) fn slot(s: &Slot) -> MapSlot {
    let m = &s.sampling.transform.m;
    MapSlot {
        xf_u: [m[0], m[1], m[2], 0.0],
        xf_v: [m[3], m[4], m[5], 0.0],
        info: [
            s.texture,
            s.sampling.uv,
            s.sampling.wrap[0] as u32,
            s.sampling.wrap[1] as u32,
        ],
    }
}

fn maps(m: &WorldMaps) -> MaterialMaps {
    let c = m.specular_color_factor;
    MaterialMaps {
        slot: m.slots.map(|s| slot(&s)),
        factors: [
            m.metallic_factor,
            m.roughness_factor,
            m.normal_scale,
            if m.shared_mr { 1.0 } else { 0.0 },
        ],
        layers: [
            m.transmission_factor,
            m.clearcoat_factor,
            m.clearcoat_roughness_factor,
            m.specular_factor,
        ],
        spec_color: [c.x, c.y, c.z, m.clearcoat_normal_scale],
    }
}

pub fn pack(w: &World) -> PackedTextures {
    if w.maps.is_empty() {
        return PackedTextures::default();
    }
    let mut out = PackedTextures {
        maps: w.maps.iter().map(maps).collect(),
        srgb: crate::render::texture::srgb_table().to_vec(),
        ..PackedTextures::default()
    };
    let mut offset = 0;
    for t in &w.textures {
        out.images.push(TexImage {
            offset: offset as u32,
            width: t.width,
            height: t.height,
            pad0: 0,
        });
        offset += t.texels.len();
    }
    out.textures = w.textures.clone();
    out
}
