//! Material JSON -> validated [`Material`] (with the textures its fields
//! name), and back; the error for a material name a scene does not define.

use super::json::{
    AlphaJson, AlphaModeJson, AttenuationJson, FresnelJson, GlassJson, MaterialJson, PbrJson,
    SurfaceJson,
};
use super::map_json::{ColorInput, MapSource, NormalJson, ScalarInput, TextureJson, WrapMode};
use super::maps::AlphaMode;
use super::resolve::{ModelSource, Resolver};
use super::values::{finite, vec3};
use super::{
    Attenuation, Fresnel, MapSlot, Maps, Material, MaterialKind, SceneError, MAX_EMISSION,
};
use crate::render::math::DVec3;
use crate::render::texture::{Sampling, UvTransform, Wrap};
use std::collections::BTreeMap;

type Result<T> = std::result::Result<T, SceneError>;

/// Highest index of refraction accepted.
const MAX_IOR: f64 = 10.0;

/// Material `name` checked: an index of refraction in [1, [`MAX_IOR`]],
/// albedo in [0, 1], emission in [0, [`MAX_EMISSION`]]; the textures its
/// fields name read by `resolver`.
pub(super) fn material(name: &str, m: &MaterialJson, resolver: &dyn Resolver) -> Result<Material> {
    let path = format!("materials.{name}");
    let white = ColorInput::Value([1.0; 3]);
    let mut maps = Maps::default();
    let mut attenuation = None;
    let (kind, albedo, emission, normal) = match m {
        MaterialJson::Diffuse(SurfaceJson {
            albedo,
            emission,
            normal,
            alpha: _,
        }) => (MaterialKind::Diffuse, albedo, emission, normal),
        MaterialJson::Mirror(SurfaceJson {
            albedo,
            emission,
            normal,
            alpha: _,
        }) => (MaterialKind::Mirror, albedo, emission, normal),
        MaterialJson::Glass(GlassJson {
            ior,
            albedo,
            fresnel,
            attenuation: absorbs,
            emission,
            normal,
        }) => {
            attenuation = absorbs
                .map(|a| checked_attenuation(&path, &a))
                .transpose()?;
            let ior = checked_ior(&path, *ior)?;
            let fresnel = match fresnel {
                FresnelJson::Exact => Fresnel::Exact,
                FresnelJson::Schlick => Fresnel::Schlick,
            };
            let albedo = albedo.as_ref().unwrap_or(&white);
            (
                MaterialKind::Glass { ior, fresnel },
                albedo,
                emission,
                normal,
            )
        }
        MaterialJson::Pbr(pbr) => {
            let PbrJson {
                base_color,
                metallic,
                roughness,
                ior,
                transmission,
                thin,
                attenuation: absorbs,
                clearcoat,
                clearcoat_roughness,
                specular,
                specular_color,
                emission,
                normal,
                clearcoat_normal,
                alpha: _,
            } = &**pbr;
            attenuation = absorbs
                .map(|a| checked_attenuation(&path, &a))
                .transpose()?;
            if *thin && attenuation.is_some() {
                return Err(SceneError::new(
                    format!("{path}.attenuation"),
                    "a thin wall has no inside to absorb in: drop `thin` or `attenuation`",
                ));
            }
            let number = |field: &str, v: &ScalarInput| {
                let textured = v.texture().is_some();
                let v = finite(&field_at(&path, field, textured), v.factor())?;
                match (0.0..=1.0).contains(&v) {
                    true => Ok(v),
                    false => Err(SceneError::new(
                        field_at(&path, field, textured),
                        format!("must be between 0 and 1 (got {v})"),
                    )),
                }
            };
            let kind = MaterialKind::Pbr {
                metallic: number("metallic", metallic)?,
                roughness: number("roughness", roughness)?,
                ior: checked_ior(&path, *ior)?,
                transmission: number("transmission", transmission)?,
                thin: *thin,
                clearcoat: number("clearcoat", clearcoat)?,
                clearcoat_roughness: number("clearcoat_roughness", clearcoat_roughness)?,
                specular: number("specular", specular)?,
                specular_color: checked_specular_color(
                    &field_at(&path, "specular_color", specular_color.texture().is_some()),
                    specular_color.factor(),
                )?,
            };
            let at = |field: &str| format!("{path}.{field}");
            let map = |field: &str, v: &ScalarInput| {
                texture(&at(field), v.texture().map(|t| t.source()), resolver)
            };
            maps.metallic = map("metallic", metallic)?;
            maps.roughness = map("roughness", roughness)?;
            maps.transmission = map("transmission", transmission)?;
            maps.clearcoat = map("clearcoat", clearcoat)?;
            maps.clearcoat_roughness = map("clearcoat_roughness", clearcoat_roughness)?;
            maps.specular = map("specular", specular)?;
            maps.specular_color = texture(
                &at("specular_color"),
                specular_color.texture().map(|t| t.source()),
                resolver,
            )?;
            if let Some(n) = clearcoat_normal {
                let at = at("clearcoat_normal");
                maps.clearcoat_normal_scale = finite(&format!("{at}.scale"), n.scale)?;
                maps.clearcoat_normal = texture(&at, Some(n.source()), resolver)?;
            }
            (kind, base_color, emission, normal)
        }
    };
    let field = match m {
        MaterialJson::Pbr(_) => "base_color",
        _ => "albedo",
    };
    let albedo_path = field_at(&path, field, albedo.texture().is_some());
    let albedo = vec3(&albedo_path, albedo.factor())?;
    if albedo.min_element() < 0.0 || albedo.max_element() > 1.0 {
        return Err(SceneError::new(
            albedo_path,
            "components must be between 0 and 1",
        ));
    }
    let textured_emission = emission.as_ref().is_some_and(|e| e.texture().is_some());
    let emission_path = field_at(&path, "emission", textured_emission);
    let emission = vec3(
        &emission_path,
        emission.as_ref().map_or([0.0; 3], ColorInput::factor),
    )?;
    if emission.min_element() < 0.0 || emission.max_element() > MAX_EMISSION {
        return Err(SceneError::new(
            emission_path,
            format!("components must be between 0 and {MAX_EMISSION:e}"),
        ));
    }
    let (base, glow) = match m {
        MaterialJson::Pbr(p) => (p.base_color.texture(), p.emission.as_ref()),
        MaterialJson::Diffuse(j) | MaterialJson::Mirror(j) => {
            (j.albedo.texture(), j.emission.as_ref())
        }
        MaterialJson::Glass(g) => (
            g.albedo.as_ref().and_then(|a| a.texture()),
            g.emission.as_ref(),
        ),
    };
    maps.base_color = texture(
        &format!("{path}.{field}"),
        base.map(|t| t.source()),
        resolver,
    )?;
    maps.emission = texture(
        &format!("{path}.emission"),
        glow.and_then(|e| e.texture()).map(|t| t.source()),
        resolver,
    )?;
    if let Some(n) = normal {
        let at = format!("{path}.normal");
        maps.normal_scale = finite(&format!("{at}.scale"), n.scale)?;
        maps.normal = texture(&at, Some(n.source()), resolver)?;
    }
    let alpha = match m {
        MaterialJson::Diffuse(j) | MaterialJson::Mirror(j) => j.alpha,
        MaterialJson::Pbr(p) => p.alpha,
        MaterialJson::Glass(_) => None,
    };
    if let Some(a) = &alpha {
        (maps.alpha_mode, maps.alpha) = alpha_test(&format!("{path}.alpha"), a)?;
    }
    Ok(Material {
        name: name.to_owned(),
        kind,
        albedo,
        emission,
        maps,
        attenuation,
        imported: false,
    })
}

/// The test `a` asks for and its factor, checked (`at`: the field's path).
fn alpha_test(at: &str, a: &AlphaJson) -> Result<(AlphaMode, f64)> {
    let unit = |field: &str, v: f64| -> Result<f64> {
        let path = format!("{at}.{field}");
        match finite(&path, v)? {
            v if (0.0..=1.0).contains(&v) => Ok(v),
            v => Err(SceneError::new(
                path,
                format!("must be between 0 and 1 (got {v})"),
            )),
        }
    };
    let factor = unit("factor", a.factor)?;
    let mode = match (a.mode, a.cutoff) {
        (AlphaModeJson::Mask, c) => AlphaMode::Mask(unit("cutoff", c.unwrap_or(0.5))? as f32),
        (AlphaModeJson::Blend, None) => AlphaMode::Blend,
        (AlphaModeJson::Blend, Some(_)) => {
            return Err(SceneError::new(
                format!("{at}.cutoff"),
                "only `mask` has a cutoff (`blend` keeps the surface with probability alpha)",
            ))
        }
    };
    Ok((mode, factor))
}

/// A material's alpha test as JSON (None: opaque).
fn alpha_json(maps: &Maps) -> Option<AlphaJson> {
    let (mode, cutoff) = match maps.alpha_mode {
        AlphaMode::Opaque => return None,
        // The f32 cutoff's shortest decimal (0.3, not 0.30000001192...).
        AlphaMode::Mask(c) => (AlphaModeJson::Mask, c.to_string().parse().ok()),
        AlphaMode::Blend => (AlphaModeJson::Blend, None),
    };
    Some(AlphaJson {
        mode,
        factor: maps.alpha,
        cutoff,
    })
}

/// Largest component of a `specular_color` (F0 is clamped to 1 anyway).
const MAX_SPECULAR_COLOR: f64 = 100.0;

/// A specular colour with finite components in [0, [`MAX_SPECULAR_COLOR`]]
/// (`at` names the field).
fn checked_specular_color(at: &str, c: [f64; 3]) -> Result<[f64; 3]> {
    let at = at.to_owned();
    let v = vec3(&at, c)?;
    if v.min_element() < 0.0 || v.max_element() > MAX_SPECULAR_COLOR {
        return Err(SceneError::new(
            at,
            format!("components must be between 0 and {MAX_SPECULAR_COLOR}"),
        ));
    }
    Ok(c)
}

/// Absorption with each colour component in [0, 1] and a distance > 0.
fn checked_attenuation(path: &str, a: &AttenuationJson) -> Result<Attenuation> {
    let at = |f: &str| format!("{path}.attenuation.{f}");
    let color = vec3(&at("color"), a.color)?;
    if color.min_element() < 0.0 || color.max_element() > 1.0 {
        return Err(SceneError::new(
            at("color"),
            "components must be between 0 and 1 (the share of light kept over `distance`)",
        ));
    }
    let distance = finite(&at("distance"), a.distance)?;
    if !(distance > 0.0) {
        return Err(SceneError::new(
            at("distance"),
            format!("must be > 0 (got {distance})"),
        ));
    }
    Ok(Attenuation { color, distance })
}

/// Where material `path`'s field value is: the field, or (`textured`) its
/// texture's factor.
fn field_at(path: &str, field: &str, textured: bool) -> String {
    match textured {
        false => format!("{path}.{field}"),
        true => format!("{path}.{field}.factor"),
    }
}

/// The slot a field's texture fills, `path` naming the field: its UV set,
/// transform and wrap checked, its image read by `resolver`.
fn texture(
    path: &str,
    source: Option<MapSource>,
    resolver: &dyn Resolver,
) -> Result<Option<MapSlot>> {
    let Some(source) = source else {
        return Ok(None);
    };
    if source.uv > 1 {
        return Err(SceneError::new(
            format!("{path}.uv"),
            format!("must be 0 or 1 (got {})", source.uv),
        ));
    }
    let transform = match &source.transform {
        None => UvTransform::IDENTITY,
        Some(t) => {
            let at = |f: &str| format!("{path}.transform.{f}");
            for (i, x) in t.offset.iter().enumerate() {
                finite(&format!("{}[{i}]", at("offset")), *x)?;
            }
            for (i, x) in t.scale.iter().enumerate() {
                finite(&format!("{}[{i}]", at("scale")), *x)?;
            }
            let deg = finite(&at("rotation_deg"), t.rotation_deg)?;
            UvTransform::new(t.offset, deg.to_radians(), t.scale)
        }
    };
    let name = source.texture.trim();
    if name.is_empty() {
        return Err(SceneError::new(
            format!("{path}.texture"),
            "must name a PNG or JPEG file or an uploaded image's asset id",
        ));
    }
    let image = resolver
        .texture(ModelSource::of_map(name))
        .map_err(|e| SceneError::new(format!("{path}.texture"), e))?;
    let wrap = source.wrap.axes().map(|w| match w {
        WrapMode::Repeat => Wrap::Repeat,
        WrapMode::Clamp => Wrap::Clamp,
        WrapMode::Mirror => Wrap::Mirror,
    });
    Ok(Some(MapSlot {
        texture: image,
        sampling: Sampling {
            uv: source.uv,
            transform,
            wrap,
        },
        source: Some(source),
    }))
}

/// An index of refraction in [1, [`MAX_IOR`]].
fn checked_ior(path: &str, ior: f64) -> Result<f64> {
    let ior = finite(&format!("{path}.ior"), ior)?;
    if !(1.0..=MAX_IOR).contains(&ior) {
        return Err(SceneError::new(
            format!("{path}.ior"),
            format!("must be between 1 and {MAX_IOR} (got {ior})"),
        ));
    }
    Ok(ior)
}

/// The material's JSON form (textured fields name their texture again).
pub(super) fn to_json(m: &Material) -> MaterialJson {
    let color = |c: DVec3, slot: &Option<MapSlot>| match source(slot) {
        Some(src) => {
            let factor = (c != DVec3::ONE).then(|| c.to_array());
            ColorInput::Texture(TextureJson::of(src, factor))
        }
        None => ColorInput::Value(c.to_array()),
    };
    let scalar = |x: f64, slot: &Option<MapSlot>| match source(slot) {
        Some(src) => ScalarInput::Texture(TextureJson::of(src, (x != 1.0).then_some(x))),
        None => ScalarInput::Value(x),
    };
    let emission = m.is_emissive().then(|| color(m.emission, &m.maps.emission));
    let normal = source(&m.maps.normal).map(|src| NormalJson::of(src, m.maps.normal_scale));
    let albedo = color(m.albedo, &m.maps.base_color);
    let alpha = alpha_json(&m.maps);
    let attenuation = m.attenuation.map(|a| AttenuationJson {
        color: a.color.to_array(),
        distance: a.distance,
    });
    match m.kind {
        MaterialKind::Diffuse => MaterialJson::Diffuse(SurfaceJson {
            albedo,
            emission,
            normal,
            alpha,
        }),
        MaterialKind::Mirror => MaterialJson::Mirror(SurfaceJson {
            albedo,
            emission,
            normal,
            alpha,
        }),
        MaterialKind::Glass { ior, fresnel } => MaterialJson::Glass(GlassJson {
            ior,
            albedo: Some(albedo),
            fresnel: match fresnel {
                Fresnel::Exact => FresnelJson::Exact,
                Fresnel::Schlick => FresnelJson::Schlick,
            },
            attenuation,
            emission,
            normal,
        }),
        MaterialKind::Pbr {
            metallic,
            roughness,
            ior,
            transmission,
            thin,
            clearcoat,
            clearcoat_roughness,
            specular,
            specular_color,
        } => MaterialJson::Pbr(Box::new(PbrJson {
            base_color: albedo,
            metallic: scalar(metallic, &m.maps.metallic),
            roughness: scalar(roughness, &m.maps.roughness),
            ior,
            transmission: scalar(transmission, &m.maps.transmission),
            thin,
            attenuation,
            clearcoat: scalar(clearcoat, &m.maps.clearcoat),
            clearcoat_roughness: scalar(clearcoat_roughness, &m.maps.clearcoat_roughness),
            specular: scalar(specular, &m.maps.specular),
            specular_color: color(DVec3::from_array(specular_color), &m.maps.specular_color),
            emission,
            normal,
            clearcoat_normal: source(&m.maps.clearcoat_normal)
                .map(|src| NormalJson::of(src, m.maps.clearcoat_normal_scale)),
            alpha,
        })),
    }
}

/// How scene JSON named a slot's texture, if it did.
fn source(slot: &Option<MapSlot>) -> Option<&MapSource> {
    slot.as_ref().and_then(|s| s.source.as_ref())
}

/// The error for a material name that the scene does not define.
pub(super) fn unknown_material(
    path: &str,
    name: &str,
    index_of: &BTreeMap<String, usize>,
) -> SceneError {
    let known: Vec<&str> = index_of.keys().map(String::as_str).collect();
    SceneError::new(
        path,
        format!("unknown material '{name}' (known: {})", known.join(", ")),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::texture::Texture;
    use serde_json::{json, Value};
    use std::sync::Arc;

    /// Knows one image, `a.png`.
    struct OneImage(Arc<Texture>);

    impl Resolver for OneImage {
        fn resolve(
            &self,
            s: ModelSource<'_>,
        ) -> std::result::Result<Arc<super::super::LoadedModel>, String> {
            Err(super::super::NoFiles::refusal(s))
        }

        fn texture(&self, s: ModelSource<'_>) -> std::result::Result<Arc<Texture>, String> {
            match s {
                ModelSource::File("a.png") => Ok(self.0.clone()),
                _ => Err("no such image".to_owned()),
            }
        }
    }

    fn resolver() -> OneImage {
        OneImage(Arc::new(
            Texture::new("a.png", 1, 1, &[1, 2, 3, 255]).expect("valid"),
        ))
    }

    fn check(m: Value) -> Result<Material> {
        let json = crate::render::scene::SceneJson::from_value(json!({
            "materials": {"m": m},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
        }))?;
        material("m", &json.materials["m"], &resolver())
    }

    #[test]
    fn bad_texture_fields_are_named() {
        let cases = [
            (
                json!({"type": "diffuse", "albedo": {"texture": "a.png", "uv": 2}}),
                "materials.m.albedo.uv",
                "must be 0 or 1",
            ),
            (
                json!({"type": "pbr", "base_color": {"texture": "a.png", "factor": [2, 0, 0]}}),
                "materials.m.base_color.factor",
                "between 0 and 1",
            ),
            (
                json!({"type": "pbr", "metallic": {"texture": "a.png", "factor": 1.5}}),
                "materials.m.metallic.factor",
                "between 0 and 1",
            ),
            (
                json!({"type": "pbr", "roughness": -0.5}),
                "materials.m.roughness",
                "between 0 and 1",
            ),
            (
                json!({"type": "glass", "ior": 1.5, "emission": {"texture": "b.png"}}),
                "materials.m.emission.texture",
                "no such image",
            ),
            (
                json!({"type": "mirror", "albedo": [1, 1, 1], "normal": {"texture": " "}}),
                "materials.m.normal.texture",
                "must name a PNG or JPEG",
            ),
            (
                json!({"type": "diffuse", "albedo": {"texture": "a.png", "wrap": "wavy"}}),
                "materials.m.albedo",
                "wrap",
            ),
            (
                json!({"type": "diffuse", "albedo": "white"}),
                "materials.m.albedo",
                "expected a colour",
            ),
        ];
        for (m, path, words) in cases {
            let e = check(m.clone()).expect_err("refused");
            assert!(
                e.path == path && e.reason.contains(words),
                "{m}: {e} (wanted {path}: ...{words}...)"
            );
        }
        // Without a resolver that reads files, the error says how to upload.
        let json = crate::render::scene::SceneJson::from_value(json!({
            "materials": {"m": {"type": "diffuse", "albedo": {"texture": "a.png"}}},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "m"}],
        }))
        .expect("parses");
        let e = crate::render::scene::Scene::from_json(&json).expect_err("no files");
        assert_eq!(e.path, "materials.m.albedo.texture");
        assert!(e.reason.contains("POST /api/assets"), "{e}");
    }

    #[test]
    fn textured_fields_fill_their_slots_and_write_back_as_given() {
        for m in [
            json!({"type": "diffuse", "albedo": {"texture": "a.png", "factor": [0.5, 0.5, 0.5], "uv": 1,
                "wrap": ["clamp", "mirror"], "transform": {"offset": [0.5, 0.0], "rotation_deg": 90.0, "scale": [2.0, 2.0]}}}),
            json!({"type": "pbr", "base_color": [0.2, 0.3, 0.4], "metallic": {"texture": "a.png"},
                "roughness": {"texture": "a.png", "factor": 0.5}, "ior": 1.5,
                "emission": {"texture": "a.png", "factor": [4.0, 4.0, 4.0]}, "normal": {"texture": "a.png", "scale": 0.5}}),
            json!({"type": "glass", "ior": 1.4, "albedo": {"texture": "a.png"}, "fresnel": "exact"}),
        ] {
            let got = check(m.clone()).expect("valid");
            assert_eq!(
                serde_json::to_value(to_json(&got)).expect("json"),
                m,
                "written back"
            );
        }
        let m = check(
            json!({"type": "diffuse", "albedo": {"texture": "a.png", "uv": 1, "wrap": "clamp",
            "transform": {"rotation_deg": 90}}}),
        )
        .expect("valid");
        let slot = m.maps.base_color.expect("base colour");
        assert_eq!(
            (slot.sampling.uv, slot.sampling.wrap),
            (1, [Wrap::Clamp; 2])
        );
        let t = slot.sampling.transform.apply([1.0, 0.0]);
        assert!(t[0].abs() < 1e-6 && (t[1] + 1.0).abs() < 1e-6, "{t:?}");
        let m = check(json!({"type": "pbr", "metallic": {"texture": "a.png"}, "emission": {"texture": "a.png"}}))
            .expect("valid");
        assert!(m.maps.metallic.is_some() && m.maps.roughness.is_none());
        assert_eq!(m.emission, DVec3::ONE, "an emission texture's factor is 1");
    }
}
