//! glTF materials as the renderer's (the rules are in `gltf`'s module doc),
//! each converted when a primitive first uses it, with its texture maps
//! (`gltf_maps`).

use super::common::{self, widen, Ctx, Mat};
use super::gltf_maps::{self, Images};
use super::{Maps, Material};
use ::gltf::material::AlphaMode;

/// glTF materials converted when first used, in that order.
pub(super) struct Materials {
    pub of: Vec<Option<u32>>,
    pub default: Option<u32>,
    pub list: Vec<Mat>,
    pub images: Images,
}

impl Materials {
    pub fn index(&mut self, ctx: &mut Ctx, m: &::gltf::Material) -> u32 {
        let next = self.list.len() as u32;
        match m.index() {
            Some(i) => match self.of.get(i).copied().flatten() {
                Some(k) => k,
                None => {
                    if m.occlusion_texture().is_some() {
                        ctx.warn("occlusion maps are not used: a path tracer finds the occlusion itself");
                    }
                    self.list.push(material(m, i, &mut self.images));
                    if let Some(slot) = self.of.get_mut(i) {
                        *slot = Some(next);
                    }
                    next
                }
            },
            None => *self.default.get_or_insert_with(|| {
                ctx.warn("primitives without a material use the glTF default material: white diffuse (albedo 1)");
                self.list.push(Mat {
                    name: "default".to_owned(),
                    json: Material::Diffuse {
                        albedo: [1.0; 3],
                        emission: None,
                    },
                    maps: Maps::default(),
                    notes: Vec::new(),
                });
                next
            }),
        }
    }
}

/// The scene material for a glTF material (rules in the module doc).
fn material(m: &::gltf::Material, index: usize, images: &mut Images) -> Mat {
    let name = m
        .name()
        .map(str::to_owned)
        .unwrap_or_else(|| format!("material{index}"));
    let (mut notes, mut ignored) = (Vec::new(), Vec::new());
    let pbr = m.pbr_metallic_roughness();
    let base = pbr.base_color_factor();
    let rgb = [base[0], base[1], base[2]].map(widen);
    let strength = m.emissive_strength().map_or(1.0, widen);
    let emission = common::emission(
        "emission",
        m.emissive_factor().map(|e| widen(e) * strength),
        &mut notes,
    );
    let (metallic, roughness) = (widen(pbr.metallic_factor()), widen(pbr.roughness_factor()));
    let transmission = m.transmission();
    let t = transmission
        .as_ref()
        .map_or(0.0, |t| widen(t.transmission_factor()));
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    // KHR_materials_volume: a thickness makes the transmitting surface a
    // solid's boundary (light refracts in and out); without one it is a
    // thin wall, as glTF defines.
    let volume = m.volume();
    let solid = volume
        .as_ref()
        .is_some_and(|v| widen(v.thickness_factor()) > 0.0);
    let mut attenuation = None;
    if let Some(v) = volume.as_ref().filter(|_| t > 0.0) {
        let color = v.attenuation_color().map(|c| widen(c).clamp(0.0, 1.0));
        let distance = widen(v.attenuation_distance());
        // The default distance is infinite: no absorption.
        if solid && distance.is_finite() && distance > 0.0 && color.iter().any(|&c| c < 1.0) {
            attenuation = Some(super::Attenuation { color, distance });
        }
        if v.thickness_texture().is_some() {
            ignored.push("thickness texture".to_owned());
        }
    }

    let mut maps = gltf_maps::maps(m, images, &mut notes);
    if let Some(tr) = transmission.as_ref().filter(|_| t > 0.0) {
        let what = "transmission texture";
        maps.transmission = gltf_maps::read(what, tr.transmission_texture(), images, &mut notes);
    }
    let (clearcoat, clearcoat_roughness) = clearcoat(m, &mut maps, images, &mut notes);
    let (specular, specular_color) = specular(m, &mut maps, images, &mut notes);
    let plain = clearcoat == 0.0
        && specular == 1.0
        && specular_color == [1.0; 3]
        && maps.specular.is_none()
        && maps.specular_color.is_none();
    let alpha = widen(base[3]);
    maps.alpha = if alpha.is_finite() {
        alpha.clamp(0.0, 1.0)
    } else {
        1.0
    };
    // A surface whose alpha is 1 everywhere stays opaque (no test to pay).
    let translucent = maps.alpha < 1.0 || maps.base_color.is_some();
    maps.alpha_mode = match m.alpha_mode() {
        AlphaMode::Opaque => super::AlphaMode::Opaque,
        AlphaMode::Mask => {
            // glTF's f32, as the renderer's alpha test compares it.
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            let cutoff = if cutoff.is_finite() { cutoff } else { 0.5 };
            match translucent || cutoff > 1.0 {
                true => super::AlphaMode::Mask(cutoff),
                false => super::AlphaMode::Opaque,
            }
        }
        AlphaMode::Blend if translucent => super::AlphaMode::Blend,
        AlphaMode::Blend => super::AlphaMode::Opaque,
    };

    // Smooth, clear, whole transmission is the `glass` corner of the model
    // (and the other corners likewise only without a coat).
    let smooth_glass = plain
        && solid
        && t == 1.0
        && maps.transmission.is_none()
        && roughness == 0.0
        && metallic == 0.0
        && maps.metallic.is_none();
    let json = if smooth_glass {
        let ior = match m.ior() {
            None => common::DEFAULT_IOR,
            Some(v) => common::ior("ior", Some(widen(v)), &mut notes),
        };
        Material::Glass {
            ior,
            albedo: Some(common::albedo("base colour", rgb, &mut notes)),
            attenuation,
            emission,
        }
    } else if metallic == 1.0 && roughness == 0.0 && clearcoat == 0.0 && maps.metallic.is_none() {
        Material::Mirror {
            albedo: common::albedo("base colour", rgb, &mut notes),
            emission,
        }
    } else if metallic == 0.0 && roughness == 1.0 && t == 0.0 && plain && maps.metallic.is_none() {
        Material::Diffuse {
            albedo: common::albedo("base colour", rgb, &mut notes),
            emission,
        }
    } else {
        Material::Pbr {
            base_color: common::albedo("base colour", rgb, &mut notes),
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            ior: match m.ior() {
                None => common::DEFAULT_IOR,
                Some(v) => common::ior("ior", Some(widen(v)), &mut notes),
            },
            transmission: t,
            thin: t > 0.0 && !solid,
            attenuation,
            clearcoat,
            clearcoat_roughness,
            specular,
            specular_color,
            emission,
        }
    };
    if !ignored.is_empty() {
        notes.push(format!("not modelled, ignored: {}", ignored.join(", ")));
    }
    Mat {
        name,
        json,
        maps,
        notes,
    }
}

/// `KHR_materials_clearcoat`'s factors (0 where absent), each in [0, 1]
/// (clamped with a note), and its textures into `maps` where it coats.
fn clearcoat(
    m: &::gltf::Material,
    maps: &mut Maps,
    images: &mut Images,
    notes: &mut Vec<String>,
) -> (f64, f64) {
    let Some(ext) = m.extension_value("KHR_materials_clearcoat") else {
        return (0.0, 0.0);
    };
    let mut factor = |key: &str| {
        let v = ext
            .get(key)
            .and_then(serde_json::Value::as_f64)
            .unwrap_or(0.0);
        common::unit(&format!("KHR_materials_clearcoat.{key}"), v, notes)
    };
    let weight = factor("clearcoatFactor");
    let roughness = factor("clearcoatRoughnessFactor");
    if weight > 0.0 {
        let key = "clearcoatTexture";
        maps.clearcoat = gltf_maps::read_json("clearcoat texture", ext, key, images, notes);
        let (key, what) = ("clearcoatRoughnessTexture", "clearcoat roughness texture");
        maps.clearcoat_roughness = gltf_maps::read_json(what, ext, key, images, notes);
        let (key, what) = ("clearcoatNormalTexture", "clearcoat normal map");
        maps.clearcoat_normal = gltf_maps::read_json(what, ext, key, images, notes);
        if maps.clearcoat_normal.is_some() {
            let scale = ext[key].get("scale").and_then(serde_json::Value::as_f64);
            maps.clearcoat_normal_scale = scale.filter(|s| s.is_finite()).unwrap_or(1.0);
        }
    }
    (weight, roughness)
}

/// `KHR_materials_specular`'s factor (in [0, 1]) and colour (components
/// >= 0), 1 and white where absent, and its textures into `maps`.
fn specular(
    m: &::gltf::Material,
    maps: &mut Maps,
    images: &mut Images,
    notes: &mut Vec<String>,
) -> (f64, [f64; 3]) {
    let Some(ext) = m.extension_value("KHR_materials_specular") else {
        return (1.0, [1.0; 3]);
    };
    let raw = ext
        .get("specularFactor")
        .and_then(serde_json::Value::as_f64)
        .unwrap_or(1.0);
    let factor = common::unit("KHR_materials_specular.specularFactor", raw, notes);
    let mut color = [1.0; 3];
    if let Some(c) = ext
        .get("specularColorFactor")
        .and_then(serde_json::Value::as_array)
    {
        for (k, v) in c.iter().take(3).enumerate() {
            let x = v.as_f64().unwrap_or(1.0);
            color[k] = if x.is_finite() {
                x.clamp(0.0, 100.0)
            } else {
                1.0
            };
        }
    }
    maps.specular = gltf_maps::read_json("specular texture", ext, "specularTexture", images, notes);
    let (key, what) = ("specularColorTexture", "specular colour texture");
    maps.specular_color = gltf_maps::read_json(what, ext, key, images, notes);
    (factor, color)
}
