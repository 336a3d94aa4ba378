//! A material's texture maps: which slots a material textures ([`Map`]),
//! and how a hit's material and shading normal are made from them.
//!
//! - Base colour: the material's colour times the map's RGB (decoded from
//!   sRGB), for every kind (diffuse albedo, mirror and glass tint, `pbr`
//!   base colour).
//! - Metallic and roughness (`pbr` only): the factor times the map's blue
//!   and green channel (glTF's metallic-roughness texture); one lookup
//!   where both slots read the same texture the same way.
//! - Transmission, clear coat and its roughness, specular and specular
//!   colour (`pbr` only): the factor times the map's red, red, green, alpha
//!   channel and RGB (sRGB), as glTF's `KHR_materials_transmission`,
//!   `_clearcoat` and `_specular` textures.
//! - Emission (any kind): the material's emission times the map's RGB
//!   (decoded from sRGB), where a camera or BSDF ray meets the surface and
//!   where a shadow ray aimed at it does ([`emission`]).
//! - Normal (any kind): tangent-space, `(2 rgb - 1)` with x and y times
//!   `scale`, in the frame (T, B, N) of the surface's tangent, its sign's
//!   bitangent `B = sign (N x T)` and the interpolated shading normal N
//!   (glTF's convention: the map's green axis along B).
//! - Clear coat normal (`pbr` with a coat): the coat's own normal, the
//!   interpolated normal turned by its map as above; without that map the
//!   coat lies on the interpolated normal, not on the base's mapped one
//!   (glTF's `clearcoatNormalTexture`).
//!
//! `kernels/maps.h` mirrors [`shade`] operation for operation.

use crate::render::ggx::{Pbr, ALPHA_MIN};
use crate::render::material::{Bsdf, SurfaceMaterial};
use crate::render::math::Vec3A;
use crate::render::texture::{self, Map, Sampling, Texture, MAP_SLOTS};
use std::sync::Arc;

/// A slot's `texture` where the slot is unused.
pub const NO_TEXTURE: u32 = u32::MAX;

/// A slot in the hot path's form: the world's texture index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    pub texture: u32,
    pub sampling: Sampling,
}

impl Slot {
    pub const NONE: Slot = Slot {
        texture: NO_TEXTURE,
        sampling: Sampling {
            uv: 0,
            transform: texture::UvTransform::IDENTITY,
            wrap: [texture::Wrap::Repeat; 2],
        },
    };
}

/// A material's maps as the hot path reads them: a slot per [`Map`], and
/// the factors the textures multiply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorldMaps {
    pub slots: [Slot; MAP_SLOTS],
    /// The material's own metallic and roughness factors (`pbr`).
    pub metallic_factor: f32,
    pub roughness_factor: f32,
    pub normal_scale: f32,
    /// Metallic and roughness read the same texture the same way.
    pub shared_mr: bool,
    /// `pbr`'s transmission, clear coat weight and roughness, specular
    /// strength and colour, which their textures multiply.
    pub transmission_factor: f32,
    pub clearcoat_factor: f32,
    pub clearcoat_roughness_factor: f32,
    pub specular_factor: f32,
    pub specular_color_factor: Vec3A,
    /// The clear coat normal map's x and y scale.
    pub clearcoat_normal_scale: f32,
}

impl WorldMaps {
    /// No slot set, factors 1 (a material fills what it has).
    pub const NONE: WorldMaps = WorldMaps {
        slots: [Slot::NONE; MAP_SLOTS],
        metallic_factor: 1.0,
        roughness_factor: 1.0,
        normal_scale: 1.0,
        shared_mr: false,
        transmission_factor: 1.0,
        clearcoat_factor: 1.0,
        clearcoat_roughness_factor: 1.0,
        specular_factor: 1.0,
        specular_color_factor: Vec3A::ONE,
        clearcoat_normal_scale: 1.0,
    };

    #[inline(always)]
    pub fn slot(&self, m: Map) -> &Slot {
        &self.slots[m as usize]
    }

    #[inline(always)]
    pub fn has(&self, m: Map) -> bool {
        self.slots[m as usize].texture != NO_TEXTURE
    }
}

/// Texture coordinates and the tangent frame at a hit, for its maps.
#[derive(Clone, Copy, Debug, Default)]
pub struct TexCoords {
    /// UV sets 0 and 1 (a set the geometry lacks reads as (0, 0)).
    pub uv: [[f32; 2]; 2],
    /// The tangent (along +u), not necessarily unit or orthogonal to the
    /// normal; zero where there is none.
    pub tangent: Vec3A,
    /// The bitangent's sign (glTF's `TANGENT.w`).
    pub sign: f32,
}

#[inline(always)]
fn read(textures: &[Arc<Texture>], slot: &Slot, tc: &TexCoords, srgb: bool) -> [f32; 4] {
    let uv = tc.uv[slot.sampling.uv as usize & 1];
    texture::lookup(&textures[slot.texture as usize], &slot.sampling, uv, srgb)
}

/// Emission `le` times the emission map of `maps` (which must have one) at
/// coordinates `tc`.
#[inline(always)]
pub fn emission(textures: &[Arc<Texture>], maps: &WorldMaps, le: Vec3A, tc: &TexCoords) -> Vec3A {
    le * texture::rgb(read(textures, maps.slot(Map::Emission), tc, true))
}

/// The material `m` (with maps `maps`) at a hit with coordinates `tc`, and
/// the unit shading normal `ns` (turned by the normal map, if any; `ns` is
/// the surface's interpolated shading normal, outward); `nc` becomes the
/// clear coat's own normal where the coat has one that can differ from
/// the new `ns` (else it is left as it is).
#[inline(always)]
pub fn shade(
    textures: &[Arc<Texture>],
    maps: &WorldMaps,
    m: &SurfaceMaterial,
    tc: &TexCoords,
    (ns, nc): (&mut Vec3A, &mut Vec3A),
) -> SurfaceMaterial {
    let mut out = *m;
    if maps.has(Map::Emission) {
        out.emission = emission(textures, maps, m.emission, tc);
    }
    if maps.has(Map::BaseColor) {
        let c = read(textures, maps.slot(Map::BaseColor), tc, true);
        out.albedo = m.albedo * texture::rgb(c);
    }
    if let Bsdf::Pbr(p) = m.bsdf {
        out.bsdf = Bsdf::Pbr(shade_pbr(textures, maps, p, tc));
    }
    let unmapped = *ns;
    if maps.has(Map::Normal) {
        *ns = turned(
            textures,
            maps.slot(Map::Normal),
            maps.normal_scale,
            tc,
            unmapped,
        );
    }
    if matches!(out.bsdf, Bsdf::Pbr(p) if p.coat > 0.0) {
        if maps.has(Map::ClearcoatNormal) {
            let (slot, scale) = (maps.slot(Map::ClearcoatNormal), maps.clearcoat_normal_scale);
            *nc = turned(textures, slot, scale, tc, unmapped);
        } else if maps.has(Map::Normal) {
            *nc = unmapped;
        }
    }
    out
}

/// Unit normal `n` turned by the tangent-space normal map in `slot` (x and
/// y times `scale`); `n` where the hit has no tangent.
#[inline(always)]
fn turned(textures: &[Arc<Texture>], slot: &Slot, scale: f32, tc: &TexCoords, n: Vec3A) -> Vec3A {
    let c = read(textures, slot, tc, false);
    let x = (c[0] * 2.0 - 1.0) * scale;
    let y = (c[1] * 2.0 - 1.0) * scale;
    let z = c[2] * 2.0 - 1.0;
    let t = (tc.tangent - n * n.dot(tc.tangent)).normalize_or_zero();
    if t == Vec3A::ZERO {
        return n;
    }
    let b = n.cross(t) * tc.sign;
    (t * x + b * y + n * z).try_normalize().unwrap_or(n)
}

/// `pbr` parameters `p` with their textures at `tc`: each factor times
/// its texture's channel ([`Map`]), the derived values (alpha, the
/// dielectric's F0 and F90, the coat's alpha) made again from them.
#[inline(always)]
fn shade_pbr(textures: &[Arc<Texture>], maps: &WorldMaps, p: Pbr, tc: &TexCoords) -> Pbr {
    let mut metallic = maps.metallic_factor;
    let mut roughness = maps.roughness_factor;
    let mut mr = [0.0f32; 4];
    if maps.has(Map::Metallic) {
        mr = read(textures, maps.slot(Map::Metallic), tc, false);
        metallic *= mr[2];
    }
    if maps.has(Map::Roughness) {
        if !maps.shared_mr {
            mr = read(textures, maps.slot(Map::Roughness), tc, false);
        }
        roughness *= mr[1];
    }
    let mut out = Pbr {
        metallic,
        alpha: (roughness * roughness).max(ALPHA_MIN),
        roughness,
        ..p
    };
    if maps.has(Map::Transmission) {
        let t = read(textures, maps.slot(Map::Transmission), tc, false);
        out.transmission = maps.transmission_factor * t[0];
    }
    if maps.has(Map::Clearcoat) || maps.has(Map::ClearcoatRoughness) {
        let (mut weight, mut rough) = (maps.clearcoat_factor, maps.clearcoat_roughness_factor);
        if maps.has(Map::Clearcoat) {
            weight *= read(textures, maps.slot(Map::Clearcoat), tc, false)[0];
        }
        if maps.has(Map::ClearcoatRoughness) {
            rough *= read(textures, maps.slot(Map::ClearcoatRoughness), tc, false)[1];
        }
        out = out.coated(weight, rough);
    }
    if maps.has(Map::Specular) || maps.has(Map::SpecularColor) {
        let mut factor = maps.specular_factor;
        let mut color = maps.specular_color_factor;
        if maps.has(Map::Specular) {
            factor *= read(textures, maps.slot(Map::Specular), tc, false)[3];
        }
        if maps.has(Map::SpecularColor) {
            color *= texture::rgb(read(textures, maps.slot(Map::SpecularColor), tc, true));
        }
        out = out.specular(factor, color);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::texture::Texture;

    fn one(rgba: [u8; 4]) -> Arc<Texture> {
        Arc::new(Texture::new("t", 1, 1, &rgba).expect("valid"))
    }

    fn slot(texture: u32) -> Slot {
        Slot {
            texture,
            ..Slot::NONE
        }
    }

    fn maps(set: &[(Map, u32)]) -> WorldMaps {
        let mut m = WorldMaps::NONE;
        for &(map, texture) in set {
            m.slots[map as usize] = slot(texture);
        }
        m
    }

    fn pbr() -> SurfaceMaterial {
        SurfaceMaterial {
            bsdf: Bsdf::Pbr(Pbr::new(0.5, 0.5, 1.5)),
            albedo: Vec3A::new(0.5, 1.0, 1.0),
            emission: Vec3A::ZERO,
            emissive: false,
            maps: 0,
            absorb: Vec3A::ZERO,
        }
    }

    #[test]
    fn base_colour_multiplies_and_mr_reads_blue_and_green() {
        let textures = [one([255, 128, 0, 255]), one([0, 51, 204, 255])];
        let m = WorldMaps {
            metallic_factor: 0.5,
            roughness_factor: 1.0,
            shared_mr: true,
            ..maps(&[(Map::BaseColor, 0), (Map::Metallic, 1), (Map::Roughness, 1)])
        };
        let tc = TexCoords::default();
        let (mut ns, mut nc) = (Vec3A::Z, Vec3A::ZERO);
        let out = shade(&textures, &m, &pbr(), &tc, (&mut ns, &mut nc));
        let t = texture::srgb_table();
        assert_eq!(out.albedo, Vec3A::new(0.5, t[128], 0.0));
        let Bsdf::Pbr(p) = out.bsdf else {
            panic!("not pbr")
        };
        assert!((p.metallic - 0.5 * 0.8).abs() < 1e-6, "{p:?}");
        assert!((p.roughness - 0.2).abs() < 1e-6, "{p:?}");
        assert!((p.alpha - 0.04).abs() < 1e-6, "{p:?}");
        assert_eq!(ns, Vec3A::Z);
    }

    /// The shading normal (z before) that `maps` give a `pbr` hit at `tc`.
    fn shaded_normal(textures: &[Arc<Texture>], maps: &WorldMaps, tc: &TexCoords) -> Vec3A {
        let (mut ns, mut nc) = (Vec3A::Z, Vec3A::ZERO);
        shade(textures, maps, &pbr(), tc, (&mut ns, &mut nc));
        ns
    }

    #[test]
    fn a_flat_normal_map_changes_nothing_and_a_tilted_one_tilts() {
        // (128, 128, 255) is (0.0039, 0.0039, 1): flat to within a byte.
        let textures = [one([128, 128, 255, 255]), one([255, 128, 128, 255])];
        let tc = TexCoords {
            uv: [[0.5; 2]; 2],
            tangent: Vec3A::new(2.0, 0.0, 0.5),
            sign: 1.0,
        };
        let ns = shaded_normal(&textures, &maps(&[(Map::Normal, 0)]), &tc);
        assert!((ns - Vec3A::Z).length() < 0.01, "{ns}");
        // Red full: tilted all the way towards the tangent.
        let m = maps(&[(Map::Normal, 1)]);
        let ns = shaded_normal(&textures, &m, &tc);
        assert!(ns.x > 0.99 && (ns.length() - 1.0).abs() < 1e-6, "{ns}");
        // No tangent: the normal stays.
        let flat = TexCoords {
            tangent: Vec3A::ZERO,
            ..tc
        };
        assert_eq!(shaded_normal(&textures, &m, &flat), Vec3A::Z);
    }

    #[test]
    fn a_coat_keeps_the_unmapped_normal_or_follows_its_own_map() {
        let textures = [one([255, 128, 128, 255]), one([128, 255, 128, 255])];
        let tc = TexCoords {
            uv: [[0.5; 2]; 2],
            tangent: Vec3A::X,
            sign: 1.0,
        };
        let coated = SurfaceMaterial {
            bsdf: Bsdf::Pbr(Pbr::new(0.0, 0.5, 1.5).coated(1.0, 0.1)),
            ..pbr()
        };
        let run = |m: &WorldMaps, mat: &SurfaceMaterial| {
            let (mut ns, mut nc) = (Vec3A::Z, Vec3A::ZERO);
            shade(&textures, m, mat, &tc, (&mut ns, &mut nc));
            (ns, nc)
        };
        // The base's map tilts the base towards x; the coat stays on z.
        let (ns, nc) = run(&maps(&[(Map::Normal, 0)]), &coated);
        assert!(ns.x > 0.99 && nc == Vec3A::Z, "{ns} {nc}");
        // The coat's own map tilts it towards the bitangent (y); the base
        // stays on z.
        let m = WorldMaps {
            clearcoat_normal_scale: 1.0,
            ..maps(&[(Map::ClearcoatNormal, 1)])
        };
        let (ns, nc) = run(&m, &coated);
        assert!(ns == Vec3A::Z && nc.y > 0.99, "{ns} {nc}");
        // Its scale scales its x and y, as the base map's does.
        let m = WorldMaps {
            clearcoat_normal_scale: 0.0,
            ..m
        };
        let (_, nc) = run(&m, &coated);
        assert!((nc - Vec3A::Z).length() < 1e-6, "{nc}");
        // No coat: no coat normal.
        let (ns, nc) = run(&maps(&[(Map::Normal, 0)]), &pbr());
        assert!(ns.x > 0.99 && nc == Vec3A::ZERO, "{ns} {nc}");
    }
}
