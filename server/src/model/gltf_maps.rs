//! glTF materials' texture maps: the base colour, metallic-roughness,
//! normal and emissive textures and the extensions' (transmission, clear
//! coat, specular), their samplers' wrap modes, their UV sets and
//! `KHR_texture_transform`; the images they read, decoded once each (PNG
//! or JPEG, from a buffer view, a `data:` URI or a file beside the
//! `.gltf`). Samplers' filters are not read: lookups are bilinear.

use super::common::Ctx;
use super::gltf_data::Buffers;
use super::uri::fetch_uri;
use super::{Image, Maps, ModelError, TextureRef, Wrap};
use ::gltf::image::Source;
use ::gltf::texture::{Texture, WrappingMode};
use ::gltf::Document;

/// The images the maps refer to, numbered in the order first used.
pub(super) struct Images {
    /// Model image of each glTF image, once used.
    of: Vec<Option<usize>>,
    /// glTF image of each model image.
    order: Vec<usize>,
    /// Each glTF texture's image and wrap modes (for texture infos that
    /// extensions give as JSON).
    textures: Vec<(usize, [Wrap; 2])>,
}

impl Images {
    pub fn new(doc: &Document) -> Self {
        Self {
            of: vec![None; doc.images().len()],
            order: Vec::new(),
            textures: doc
                .textures()
                .map(|t| (t.source().index(), wraps(&t)))
                .collect(),
        }
    }

    fn index(&mut self, image: usize) -> usize {
        if let Some(Some(k)) = self.of.get(image) {
            return *k;
        }
        let k = self.order.len();
        self.order.push(image);
        if let Some(slot) = self.of.get_mut(image) {
            *slot = Some(k);
        }
        k
    }

    /// Decodes every image used, in order.
    pub fn decode(
        &self,
        ctx: &mut Ctx,
        doc: &Document,
        bufs: &mut Buffers,
    ) -> Result<Vec<Image>, ModelError> {
        let mut out = Vec::with_capacity(self.order.len());
        for &i in &self.order {
            let path = format!("images[{i}]");
            let image = doc
                .images()
                .nth(i)
                .ok_or_else(|| ctx.err_at(&path, "no such image"))?;
            let name = match image.name() {
                Some(n) => format!("{n:?}"),
                None => path.clone(),
            };
            let bytes = match image.source() {
                Source::View { view, .. } => bufs.view(ctx, &view)?.to_vec(),
                Source::Uri { uri, .. } => fetch_uri(ctx, bufs.dir(), uri, &path, "image")?,
            };
            out.push(super::image::decode(ctx, &bytes, &name, &path)?);
        }
        Ok(out)
    }
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
    }
}

fn wraps(texture: &Texture) -> [Wrap; 2] {
    let sampler = texture.sampler();
    [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())]
}

/// A texture slot as a reference, or `None` (with a note) where it cannot
/// be read: a UV set other than 0 and 1, a texture index out of range.
fn reference(
    what: &str,
    texture: usize,
    tex_coord: u32,
    transform: Option<&serde_json::Value>,
    images: &mut Images,
    notes: &mut Vec<String>,
) -> Option<TextureRef> {
    let Some(&(image, wrap)) = images.textures.get(texture) else {
        notes.push(format!(
            "{what}: texture {texture} does not exist: not rendered"
        ));
        return None;
    };
    let mut r = TextureRef::plain(images.index(image));
    r.wrap = wrap;
    r.uv = tex_coord;
    if let Some(t) = transform {
        match read_transform(t) {
            Some((offset, rotation, scale, uv)) => {
                (r.offset, r.rotation, r.scale) = (offset, rotation, scale);
                r.uv = uv.unwrap_or(r.uv);
            }
            None => notes.push(format!(
                "{what}: KHR_texture_transform has values that are not finite numbers: not applied"
            )),
        }
    }
    if r.uv > 1 {
        notes.push(format!(
            "{what} reads TEXCOORD_{} (only TEXCOORD_0 and TEXCOORD_1 are read): not rendered",
            r.uv
        ));
        return None;
    }
    Some(r)
}

type Transform = ([f64; 2], f64, [f64; 2], Option<u32>);

/// `KHR_texture_transform`'s fields (offset, rotation, scale, texCoord).
fn read_transform(v: &serde_json::Value) -> Option<Transform> {
    let pair = |key: &str, default: [f64; 2]| -> Option<[f64; 2]> {
        match v.get(key) {
            None => Some(default),
            Some(p) => {
                let a = p.as_array()?;
                let x = a.first()?.as_f64()?;
                let y = a.get(1)?.as_f64()?;
                (a.len() == 2 && x.is_finite() && y.is_finite()).then_some([x, y])
            }
        }
    };
    let rotation = match v.get("rotation") {
        None => 0.0,
        Some(r) => r.as_f64().filter(|r| r.is_finite())?,
    };
    let uv = match v.get("texCoord") {
        None => None,
        Some(t) => Some(u32::try_from(t.as_u64()?).ok()?),
    };
    Some((
        pair("offset", [0.0; 2])?,
        rotation,
        pair("scale", [1.0; 2])?,
        uv,
    ))
}

const TRANSFORM: &str = "KHR_texture_transform";

/// A texture slot's reference, if the material fills it.
pub(super) fn read(
    what: &str,
    info: Option<::gltf::texture::Info>,
    images: &mut Images,
    notes: &mut Vec<String>,
) -> Option<TextureRef> {
    let info = info?;
    let t = info.extension_value(TRANSFORM);
    reference(
        what,
        info.texture().index(),
        info.tex_coord(),
        t,
        images,
        notes,
    )
}

/// An extension's texture info `key` of `ext` (glTF `textureInfo` JSON:
/// `index`, `texCoord`, `KHR_texture_transform`), if it has one; a
/// malformed one is noted and not rendered.
pub(super) fn read_json(
    what: &str,
    ext: &serde_json::Value,
    key: &str,
    images: &mut Images,
    notes: &mut Vec<String>,
) -> Option<TextureRef> {
    let info = ext.get(key)?;
    let index = info.get("index").and_then(serde_json::Value::as_u64);
    let uv = match info.get("texCoord") {
        None => Some(0),
        Some(v) => v.as_u64().and_then(|v| u32::try_from(v).ok()),
    };
    let (Some(index), Some(uv)) = (index, uv) else {
        notes.push(format!(
            "{what}: not a texture reference ({{\"index\": n, \"texCoord\": n}}): not rendered"
        ));
        return None;
    };
    let t = info.get("extensions").and_then(|e| e.get(TRANSFORM));
    let index = usize::try_from(index).unwrap_or(usize::MAX);
    reference(what, index, uv, t, images, notes)
}

/// The maps of material `m` (notes for what cannot be read).
pub(super) fn maps(m: &::gltf::Material, images: &mut Images, notes: &mut Vec<String>) -> Maps {
    let pbr = m.pbr_metallic_roughness();
    let mut out = Maps {
        base_color: read(
            "base colour texture",
            pbr.base_color_texture(),
            images,
            notes,
        ),
        ..Maps::default()
    };
    // Metal in its blue channel, roughness in its green.
    let metallic_roughness = read(
        "metallic-roughness texture",
        pbr.metallic_roughness_texture(),
        images,
        notes,
    );
    (out.metallic, out.roughness) = (metallic_roughness, metallic_roughness);
    if let Some(n) = m.normal_texture() {
        let t = n.extension_value(TRANSFORM);
        let index = n.texture().index();
        out.normal = reference("normal map", index, n.tex_coord(), t, images, notes);
        let scale = f64::from(n.scale());
        out.normal_scale = if scale.is_finite() { scale } else { 1.0 };
    }
    out.emission = read("emissive texture", m.emissive_texture(), images, notes);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transforms_are_read_and_checked() {
        let v = serde_json::json!({"offset": [0.5, 1], "rotation": 0.25, "scale": [2, 3], "texCoord": 1});
        assert_eq!(
            read_transform(&v),
            Some(([0.5, 1.0], 0.25, [2.0, 3.0], Some(1)))
        );
        let v = serde_json::json!({});
        assert_eq!(read_transform(&v), Some(([0.0; 2], 0.0, [1.0; 2], None)));
        for bad in [
            serde_json::json!({"offset": [0.5]}),
            serde_json::json!({"scale": "big"}),
            serde_json::json!({"rotation": null}),
            serde_json::json!({"texCoord": -1}),
        ] {
            assert_eq!(read_transform(&bad), None, "{bad}");
        }
    }
}
