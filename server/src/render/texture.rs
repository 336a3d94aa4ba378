//! Image textures as materials read them: 8-bit RGBA texels, looked up by
//! bilinear filtering with glTF's samplers (wrap modes per axis, repeat,
//! clamp to edge, mirrored repeat), texture coordinates from a chosen UV set
//! through `KHR_texture_transform`'s affine map, colour channels decoded from
//! sRGB where the slot is a colour (base colour) and read as they are where
//! it is data (metallic-roughness, normals).
//!
//! Conventions (glTF's): UV (0, 0) is the image's top-left corner, u grows
//! to the right and v downwards; texel (i, j)'s centre is at
//! ((i + 0.5) / width, (j + 0.5) / height). Texels are decoded before they
//! are filtered (filtering in linear light), and the four are weighed as
//! `(t00 (1 - fx) + t10 fx) (1 - fy) + (t01 (1 - fx) + t11 fx) fy`: the
//! kernel (`kernels/textures.h`) reads the same sRGB table
//! ([`srgb_table`]) and does the same operations in the same order, so both
//! backends see the same floats.

use crate::render::math::Vec3A;
use std::sync::OnceLock;

/// Largest width or height accepted (a 16k map is 1 GiB at 4 bytes a texel).
pub const MAX_SIDE: u32 = 16384;

/// A decoded image: RGBA8 texels, row by row from the top, each packed into
/// a `u32` with red in the low byte (the kernel reads the same words).
#[derive(Debug, PartialEq)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub texels: Vec<u32>,
    /// The mean of the texels' RGB decoded from sRGB: how bright an
    /// emission map is on average (light selection weighs by it).
    pub mean_srgb: [f32; 3],
}

impl Texture {
    /// `rgba`: 4 bytes per texel, rows from the top.
    pub fn new(name: &str, width: u32, height: u32, rgba: &[u8]) -> Result<Texture, String> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(format!(
                "{name}: {width}x{height} texels: each side must be between 1 and {MAX_SIDE}"
            ));
        }
        let count = width as usize * height as usize;
        if rgba.len() != count * 4 {
            return Err(format!(
                "{name}: {} bytes for {width}x{height} RGBA texels",
                rgba.len()
            ));
        }
        let texels: Vec<u32> = rgba
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        let table = srgb_table();
        let mut sum = [0.0f64; 3];
        for c in rgba.chunks_exact(4) {
            for (s, &b) in sum.iter_mut().zip(&c[..3]) {
                *s += f64::from(table[b as usize]);
            }
        }
        Ok(Texture {
            name: name.to_owned(),
            width,
            height,
            texels,
            mean_srgb: sum.map(|s| (s / count as f64) as f32),
        })
    }

    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * 4
    }
}

/// How coordinates outside [0, 1] find a texel (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat = 0,
    Clamp = 1,
    Mirror = 2,
}

impl Wrap {
    /// Texel index `i` of a row or column `n` long, wrapped.
    #[inline(always)]
    pub fn index(self, i: i32, n: i32) -> i32 {
        match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k >= n {
                    2 * n - 1 - k
                } else {
                    k
                }
            }
        }
    }
}

/// `KHR_texture_transform` as a 2x3 matrix applied to (u, v, 1):
/// translation * rotation * scale, the extension's order.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// u' = m[0] u + m[1] v + m[2]; v' = m[3] u + m[4] v + m[5].
    pub m: [f32; 6],
}

impl UvTransform {
    pub const IDENTITY: UvTransform = UvTransform {
        m: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
    };

    /// From the extension's fields (`rotation` in radians, counter-
    /// clockwise in UV space as the extension defines it).
    pub fn new(offset: [f64; 2], rotation: f64, scale: [f64; 2]) -> UvTransform {
        let (s, c) = rotation.sin_cos();
        let m = [
            c * scale[0],
            s * scale[1],
            offset[0],
            -s * scale[0],
            c * scale[1],
            offset[1],
        ];
        UvTransform {
            m: m.map(|x| x as f32),
        }
    }

    #[inline(always)]
    pub fn apply(&self, uv: [f32; 2]) -> [f32; 2] {
        let m = &self.m;
        [
            m[0] * uv[0] + m[1] * uv[1] + m[2],
            m[3] * uv[0] + m[4] * uv[1] + m[5],
        ]
    }
}

/// What a material's texture slot feeds, in the order of the hot path's
/// slot arrays (`render::maps::WorldMaps::slots`, the kernel's
/// `MaterialMaps.slot`, indexed by the shared constants `MAP_*`). Which
/// channel each reads is glTF's: base colour, emission and specular colour
/// RGB (sRGB), metallic blue, roughness green, normal and clear coat
/// normal RGB, transmission and clear coat red, clear coat roughness green,
/// specular alpha.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Map {
    BaseColor = 0,
    Metallic,
    Roughness,
    Normal,
    Emission,
    Transmission,
    Clearcoat,
    ClearcoatRoughness,
    Specular,
    SpecularColor,
    ClearcoatNormal,
}

/// Slots per material.
pub const MAP_SLOTS: usize = crate::material_maps::SLOTS;

impl Map {
    pub const ALL: [Map; MAP_SLOTS] = [
        Map::BaseColor,
        Map::Metallic,
        Map::Roughness,
        Map::Normal,
        Map::Emission,
        Map::Transmission,
        Map::Clearcoat,
        Map::ClearcoatRoughness,
        Map::Specular,
        Map::SpecularColor,
        Map::ClearcoatNormal,
    ];

    /// The scene JSON field it textures (`pbr`'s names; `albedo` is
    /// `base_color` there).
    pub fn name(self) -> &'static str {
        match self {
            Map::BaseColor => "base_color",
            Map::Metallic => "metallic",
            Map::Roughness => "roughness",
            Map::Normal => "normal",
            Map::Emission => "emission",
            Map::Transmission => "transmission",
            Map::Clearcoat => "clearcoat",
            Map::ClearcoatRoughness => "clearcoat_roughness",
            Map::Specular => "specular",
            Map::SpecularColor => "specular_color",
            Map::ClearcoatNormal => "clearcoat_normal",
        }
    }
}

/// How a material slot reads its texture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// The UV set (0: TEXCOORD_0, 1: TEXCOORD_1).
    pub uv: u32,
    pub transform: UvTransform,
    /// Along u, along v.
    pub wrap: [Wrap; 2],
}

impl Default for Sampling {
    fn default() -> Self {
        Sampling {
            uv: 0,
            transform: UvTransform::IDENTITY,
            wrap: [Wrap::Repeat; 2],
        }
    }
}

/// sRGB-encoded byte -> linear value, for all 256 bytes (IEC 61966-2-1,
/// computed in f64 and rounded once).
pub fn srgb_table() -> &'static [f32; 256] {
    static T: OnceLock<[f32; 256]> = OnceLock::new();
    T.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let l = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            l as f32
        })
    })
}

/// Largest |texel coordinate| kept before the integer conversion (f32 has
/// no fraction beyond it anyway).
const COORD_LIMIT: f32 = 16_777_216.0;

/// The texel coordinate `x` (in texels, centres at i + 0.5) split into the
/// lower texel and the weight of the upper one.
#[inline(always)]
fn split(x: f32) -> (i32, f32) {
    let x = if x.is_nan() { 0.0 } else { x - 0.5 };
    let lo = x.floor();
    let lo = lo.clamp(-COORD_LIMIT, COORD_LIMIT);
    (lo as i32, (x - lo).clamp(0.0, 1.0))
}

#[inline(always)]
fn decode(texel: u32, srgb: bool) -> [f32; 4] {
    let table = srgb_table();
    let b = texel.to_le_bytes();
    let lin = |c: u8| f32::from(c) * (1.0 / 255.0);
    if srgb {
        [
            table[b[0] as usize],
            table[b[1] as usize],
            table[b[2] as usize],
            lin(b[3]),
        ]
    } else {
        [lin(b[0]), lin(b[1]), lin(b[2]), lin(b[3])]
    }
}

/// The bilinearly filtered RGBA of `tex` at texture coordinates `uv` (after
/// the slot's transform), colour channels decoded from sRGB if `srgb`
/// (alpha is always linear).
#[inline(always)]
pub fn lookup(tex: &Texture, s: &Sampling, uv: [f32; 2], srgb: bool) -> [f32; 4] {
    let [u, v] = s.transform.apply(uv);
    let (w, h) = (tex.width as i32, tex.height as i32);
    let (x0, fx) = split(u * w as f32);
    let (y0, fy) = split(v * h as f32);
    let xa = s.wrap[0].index(x0, w) as usize;
    let xb = s.wrap[0].index(x0.saturating_add(1), w) as usize;
    let ya = s.wrap[1].index(y0, h) as usize * w as usize;
    let yb = s.wrap[1].index(y0.saturating_add(1), h) as usize * w as usize;
    let t = |i: usize| decode(tex.texels[i], srgb);
    let (t00, t10, t01, t11) = (t(ya + xa), t(ya + xb), t(yb + xa), t(yb + xb));
    let (gx, gy) = (1.0 - fx, 1.0 - fy);
    std::array::from_fn(|c| (t00[c] * gx + t10[c] * fx) * gy + (t01[c] * gx + t11[c] * fx) * fy)
}

/// The RGB of a lookup.
#[inline(always)]
pub fn rgb(c: [f32; 4]) -> Vec3A {
    Vec3A::new(c[0], c[1], c[2])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2x2: red, green / blue, white (sRGB 255 and 0 only).
        let rgba = [
            255, 0, 0, 255, 0, 255, 0, 255, //
            0, 0, 255, 255, 255, 255, 255, 128,
        ];
        Texture::new("checker", 2, 2, &rgba).expect("valid")
    }

    #[test]
    fn texel_centres_read_their_texel() {
        let t = checker();
        let s = Sampling::default();
        assert_eq!(lookup(&t, &s, [0.25, 0.25], true), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(lookup(&t, &s, [0.75, 0.25], true), [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(lookup(&t, &s, [0.25, 0.75], true), [0.0, 0.0, 1.0, 1.0]);
        let w = lookup(&t, &s, [0.75, 0.75], true);
        assert_eq!(&w[..3], &[1.0; 3]);
        assert_eq!(t.mean_srgb, [0.5; 3]);
        assert!((w[3] - 128.0 / 255.0).abs() < 1e-7);
    }

    #[test]
    fn bilinear_between_centres() {
        let t = checker();
        let s = Sampling::default();
        // Halfway between red and green: both at half weight.
        let c = lookup(&t, &s, [0.5, 0.25], true);
        assert!(
            (c[0] - 0.5).abs() < 1e-6 && (c[1] - 0.5).abs() < 1e-6,
            "{c:?}"
        );
        // A quarter texel from the red centre towards green.
        let c = lookup(&t, &s, [0.25 + 0.125, 0.25], true);
        assert!(
            (c[0] - 0.75).abs() < 1e-6 && (c[1] - 0.25).abs() < 1e-6,
            "{c:?}"
        );
    }

    #[test]
    fn wrap_modes() {
        assert_eq!(
            (-3..7)
                .map(|i| Wrap::Repeat.index(i, 3))
                .collect::<Vec<_>>(),
            [0, 1, 2, 0, 1, 2, 0, 1, 2, 0]
        );
        assert_eq!(
            (-3..7).map(|i| Wrap::Clamp.index(i, 3)).collect::<Vec<_>>(),
            [0, 0, 0, 0, 1, 2, 2, 2, 2, 2]
        );
        assert_eq!(
            (-3..7)
                .map(|i| Wrap::Mirror.index(i, 3))
                .collect::<Vec<_>>(),
            [2, 1, 0, 0, 1, 2, 2, 1, 0, 0]
        );
        let t = checker();
        let at = |wrap, u: f32| {
            let s = Sampling {
                wrap: [wrap, Wrap::Clamp],
                ..Sampling::default()
            };
            lookup(&t, &s, [u, 0.25], true)
        };
        // u = 1.25 is texel 2: repeat -> red, clamp -> green, mirror -> green.
        assert_eq!(at(Wrap::Repeat, 1.25)[0], 1.0);
        assert_eq!(at(Wrap::Clamp, 1.25)[1], 1.0);
        assert_eq!(at(Wrap::Mirror, 1.25)[1], 1.0);
        // u = 1.75 is texel 3: repeat -> green, mirror -> red.
        assert_eq!(at(Wrap::Repeat, 1.75)[1], 1.0);
        assert_eq!(at(Wrap::Mirror, 1.75)[0], 1.0);
        // Far away and not a number: still a texel.
        assert!(at(Wrap::Repeat, 1e30)[3] > 0.0);
        assert!(at(Wrap::Mirror, f32::NAN)[3] > 0.0);
        assert!(at(Wrap::Clamp, -f32::INFINITY)[3] > 0.0);
    }

    #[test]
    fn transform_is_translation_rotation_scale() {
        // The extension's example order: scale, then rotate, then offset.
        let x = UvTransform::new([0.5, 0.25], std::f64::consts::FRAC_PI_2, [2.0, 3.0]);
        let [u, v] = x.apply([1.0, 0.0]);
        // (1, 0) scaled (2, 0), rotated by +90 degrees in UV (to (0, -2)),
        // offset.
        assert!(
            (u - 0.5).abs() < 1e-6 && (v - (0.25 - 2.0)).abs() < 1e-6,
            "{u} {v}"
        );
        assert_eq!(UvTransform::IDENTITY.apply([0.3, 0.7]), [0.3, 0.7]);
    }

    #[test]
    fn srgb_decoding() {
        let t = srgb_table();
        assert_eq!(t[0], 0.0);
        assert_eq!(t[255], 1.0);
        assert!((t[128] - 0.21586).abs() < 1e-4, "{}", t[128]);
        assert!(t.windows(2).all(|w| w[0] < w[1]));
        let gray = Texture::new("g", 1, 1, &[128, 128, 128, 255]).expect("valid");
        let s = Sampling::default();
        assert_eq!(lookup(&gray, &s, [0.5, 0.5], false)[0], 128.0 / 255.0);
        assert_eq!(lookup(&gray, &s, [0.5, 0.5], true)[0], t[128]);
    }

    #[test]
    fn bad_sizes_are_refused() {
        assert!(Texture::new("a", 0, 1, &[]).is_err());
        assert!(Texture::new("a", 2, 1, &[0; 4]).is_err());
        assert!(Texture::new("a", MAX_SIDE + 1, 1, &[]).is_err());
    }
}
