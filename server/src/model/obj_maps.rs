//! MTL texture maps (`map_Kd`, `map_Ke`, `map_Ks` and `norm`/`map_Bump`/`bump`) read for an
//! OBJ: each image file once, relative to the OBJ's directory. A file that
//! cannot be found (or an upload, which has no directory) is a warning and
//! the material renders without that map; a file that is found but is not a
//! PNG or JPEG is an error naming it. A bump map whose image is grey is a
//! height map, which is not rendered (noted); one in colour is a normal map.
//! A material whose emission is its `map_Ke` alone (no `Ke`) does not glow
//! where that map cannot be read.

use super::common::{Ctx, Mat};
use super::mtl::ColorMap;
use super::mtl::MtlMaterial;
use super::{Image, Material, ModelError, TextureRef, Wrap};
use std::collections::HashMap;
use std::path::Path;

/// Reads the maps of the `used` materials of `libs` into `materials` (the
/// same order); the images.
pub(super) fn read(
    ctx: &mut Ctx,
    libs: &[MtlMaterial],
    materials: &mut [Mat],
    dir: Option<&Path>,
    used: &[bool],
) -> Result<Vec<Image>, ModelError> {
    let mut images: Vec<Image> = Vec::new();
    let mut by_name: HashMap<String, Option<usize>> = HashMap::new();
    let mut image = |ctx: &mut Ctx, key: &str, file: &str| -> Result<Option<usize>, ModelError> {
        if let Some(&known) = by_name.get(file) {
            return Ok(known);
        }
        let found = match dir {
            None => {
                ctx.warn(format!(
                    "{key} {file:?}: an upload cannot include other files: not rendered (upload a .glb to keep textures)"
                ));
                None
            }
            Some(_) if Path::new(file).is_absolute() || file.contains("://") => {
                ctx.warn(format!(
                    "{key} {file:?}: only paths relative to the OBJ file are followed: not rendered"
                ));
                None
            }
            Some(dir) => match std::fs::read(dir.join(file)) {
                Err(e) => {
                    ctx.warn(format!(
                        "{key} {file:?}: cannot be read ({e}): not rendered"
                    ));
                    None
                }
                Ok(bytes) => {
                    images.push(super::image::decode(
                        ctx,
                        &bytes,
                        file,
                        &format!("{key} {file:?}"),
                    )?);
                    Some(images.len() - 1)
                }
            },
        };
        by_name.insert(file.to_owned(), found);
        Ok(found)
    };
    let mut maps = Vec::with_capacity(libs.len());
    for (k, lib) in libs.iter().enumerate() {
        let used = |_: &_| used.get(k).copied().unwrap_or(false);
        let mut color = |key: &str, map: &Option<ColorMap>| match map.as_ref().filter(|_| used(lib))
        {
            None => Ok(None),
            Some((file, clamp, offset, scale)) => Ok(image(ctx, key, file)?.map(|i| TextureRef {
                wrap: [if *clamp { Wrap::Clamp } else { Wrap::Repeat }; 2],
                offset: *offset,
                scale: *scale,
                ..TextureRef::plain(i)
            })),
        };
        let base = color("map_Kd", &lib.map_kd)?;
        let specular = match materials[k].json {
            Material::Pbr { .. } => color("map_Ks", &lib.map_ks)?,
            _ => None,
        };
        let emissive = color("map_Ke", &lib.map_ke)?;
        if emissive.is_none() && lib.map_ke.is_some() && lib.ke.is_none() {
            dark(&mut materials[k].json);
        }
        let mut bump = None;
        if let Some((file, scale)) = lib.bump.as_ref().filter(|_| used(lib)) {
            bump = image(ctx, "bump map", file)?.map(|i| (i, *scale));
        }
        maps.push((base, emissive, specular, bump));
    }
    for ((base, emissive, specular, bump), m) in maps.into_iter().zip(materials.iter_mut()) {
        m.maps.base_color = base;
        m.maps.emission = emissive;
        m.maps.specular_color = specular;
        if let Some((i, scale)) = bump {
            let grey = images[i]
                .rgba
                .chunks_exact(4)
                .all(|p| p[0] == p[1] && p[1] == p[2]);
            if grey {
                m.notes.push(format!(
                    "bump map {:?} is a height map (grey): not rendered (normal maps are)",
                    images[i].name
                ));
            } else {
                m.maps.normal = Some(TextureRef::plain(i));
                m.maps.normal_scale = scale;
            }
        }
    }
    Ok(images)
}

/// Takes the emission off `m` (its emission map could not be read).
fn dark(m: &mut Material) {
    let (Material::Diffuse { emission, .. }
    | Material::Mirror { emission, .. }
    | Material::Glass { emission, .. }
    | Material::Pbr { emission, .. }) = m;
    *emission = None;
}
