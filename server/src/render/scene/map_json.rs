//! Texture maps in scene JSON: a material field that takes a value
//! (`"base_color": [0.8, 0.6, 0.4]`, `"roughness": 0.5`) may instead name an
//! image, times an optional factor:
//!
//! ```json
//! "base_color": {"texture": "wood.png", "factor": [1, 0.9, 0.8],
//!                "uv": 0, "wrap": "repeat",
//!                "transform": {"offset": [0, 0], "rotation_deg": 0, "scale": [4, 4]}},
//! "roughness": {"texture": "rough.png"},
//! "normal": {"texture": "normal.png", "scale": 1}
//! ```
//!
//! `texture` is a PNG or JPEG file (relative to the scene file, on the
//! command line) or an uploaded image's asset id. Colours (base colour,
//! albedo, emission, specular colour) are decoded from sRGB; numbers read
//! the channel glTF gives them (`texture::Map`): `metallic` blue,
//! `roughness` and `clearcoat_roughness` green, `transmission` and
//! `clearcoat` red, `specular` alpha (a grey image reads the same in the
//! colour channels). `wrap` is one
//! mode for both axes or `[u, v]`; `transform` is `KHR_texture_transform`
//! (translation x rotation x scale, the rotation counter-clockwise in UV
//! space). Spheres and quads carry coordinates of their own
//! (`render::world::textures`); `uv` picks a mesh's set 0 or 1.

use serde::de::{DeserializeOwned, Deserializer, Error as _};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// A colour field: `[r, g, b]` or a texture times a colour factor.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum ColorInput {
    Value([f64; 3]),
    Texture(TextureJson<[f64; 3]>),
}

/// A number field: a value or a texture times a factor.
#[derive(Clone, Debug, Serialize, PartialEq)]
#[serde(untagged)]
pub enum ScalarInput {
    Value(f64),
    Texture(TextureJson<f64>),
}

/// A texture read by a material field, times `factor` (default: 1).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TextureJson<F> {
    /// A PNG or JPEG file (relative to the scene file) or an image asset's id.
    pub texture: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub factor: Option<F>,
    /// A mesh's UV set (0 or 1).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub uv: u32,
    #[serde(default, skip_serializing_if = "WrapJson::is_default")]
    pub wrap: WrapJson,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<UvTransformJson>,
}

/// A tangent-space normal map (any material), its x and y scaled by `scale`.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct NormalJson {
    pub texture: String,
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub scale: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub uv: u32,
    #[serde(default, skip_serializing_if = "WrapJson::is_default")]
    pub wrap: WrapJson,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<UvTransformJson>,
}

/// A `texture` and how a field reads it (what a scene material keeps of
/// its JSON, to write it back).
#[derive(Clone, Debug, PartialEq)]
pub struct MapSource {
    pub texture: String,
    pub uv: u32,
    pub wrap: WrapJson,
    pub transform: Option<UvTransformJson>,
}

impl MapSource {
    fn new(texture: &str, uv: u32, wrap: WrapJson, transform: Option<UvTransformJson>) -> Self {
        MapSource {
            texture: texture.to_owned(),
            uv,
            wrap,
            transform,
        }
    }
}

impl<F> TextureJson<F> {
    pub fn source(&self) -> MapSource {
        MapSource::new(&self.texture, self.uv, self.wrap, self.transform)
    }

    /// `source` read with factor `factor`.
    pub fn of(source: &MapSource, factor: Option<F>) -> Self {
        TextureJson {
            texture: source.texture.clone(),
            factor,
            uv: source.uv,
            wrap: source.wrap,
            transform: source.transform,
        }
    }
}

impl NormalJson {
    pub fn source(&self) -> MapSource {
        MapSource::new(&self.texture, self.uv, self.wrap, self.transform)
    }

    pub fn of(source: &MapSource, scale: f64) -> Self {
        NormalJson {
            texture: source.texture.clone(),
            scale,
            uv: source.uv,
            wrap: source.wrap,
            transform: source.transform,
        }
    }
}

/// Wrap modes: one for both axes, or `[u, v]`.
#[derive(Clone, Copy, Debug, Serialize, PartialEq, Eq)]
#[serde(untagged)]
pub enum WrapJson {
    Both(WrapMode),
    PerAxis([WrapMode; 2]),
}

impl Default for WrapJson {
    fn default() -> Self {
        WrapJson::Both(WrapMode::Repeat)
    }
}

impl WrapJson {
    fn is_default(&self) -> bool {
        *self == WrapJson::default()
    }

    /// Along u, along v.
    pub fn axes(&self) -> [WrapMode; 2] {
        match *self {
            WrapJson::Both(m) => [m; 2],
            WrapJson::PerAxis(a) => a,
        }
    }
}

#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum WrapMode {
    Repeat,
    Clamp,
    Mirror,
}

/// `KHR_texture_transform`'s fields, the rotation in degrees.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UvTransformJson {
    #[serde(default)]
    pub offset: [f64; 2],
    #[serde(default)]
    pub rotation_deg: f64,
    #[serde(default = "ones")]
    pub scale: [f64; 2],
}

fn one() -> f64 {
    1.0
}

fn ones() -> [f64; 2] {
    [1.0; 2]
}

fn is_one(v: &f64) -> bool {
    *v == 1.0
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

/// A value, or (a JSON object) a texture: told apart by the JSON's kind,
/// so that an error names what was wrong with the form that was meant.
fn value_or_texture<V: DeserializeOwned, T: DeserializeOwned, E: serde::de::Error>(
    v: Value,
    what: &str,
) -> Result<Result<V, T>, E> {
    match v {
        Value::Object(_) => serde_json::from_value(v).map(Err).map_err(E::custom),
        other => serde_json::from_value(other)
            .map(Ok)
            .map_err(|e| E::custom(format!("{e} (expected {what} or {{\"texture\": ...}})"))),
    }
}

impl<'de> Deserialize<'de> for WrapJson {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let read = match v {
            Value::Array(_) => serde_json::from_value(v).map(WrapJson::PerAxis),
            other => serde_json::from_value(other).map(WrapJson::Both),
        };
        read.map_err(|_| {
            D::Error::custom(
                "wrap: expected \"repeat\", \"clamp\" or \"mirror\", or [u, v] of those",
            )
        })
    }
}

impl<'de> Deserialize<'de> for ColorInput {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        Ok(match value_or_texture(v, "a colour [r, g, b]")? {
            Ok(c) => ColorInput::Value(c),
            Err(t) => ColorInput::Texture(t),
        })
    }
}

impl<'de> Deserialize<'de> for ScalarInput {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Value::deserialize(d)?;
        let r: Result<Result<f64, TextureJson<f64>>, D::Error> = value_or_texture(v, "a number");
        Ok(match r? {
            Ok(x) => ScalarInput::Value(x),
            Err(t) => ScalarInput::Texture(t),
        })
    }
}

impl ColorInput {
    /// The colour (a texture's factor, white by default).
    pub fn factor(&self) -> [f64; 3] {
        match self {
            ColorInput::Value(c) => *c,
            ColorInput::Texture(t) => t.factor.unwrap_or([1.0; 3]),
        }
    }

    pub fn texture(&self) -> Option<&TextureJson<[f64; 3]>> {
        match self {
            ColorInput::Value(_) => None,
            ColorInput::Texture(t) => Some(t),
        }
    }
}

impl ScalarInput {
    /// The value (a texture's factor, 1 by default).
    pub fn factor(&self) -> f64 {
        match self {
            ScalarInput::Value(x) => *x,
            ScalarInput::Texture(t) => t.factor.unwrap_or(1.0),
        }
    }

    pub fn texture(&self) -> Option<&TextureJson<f64>> {
        match self {
            ScalarInput::Value(_) => None,
            ScalarInput::Texture(t) => Some(t),
        }
    }
}

impl From<[f64; 3]> for ColorInput {
    fn from(c: [f64; 3]) -> Self {
        ColorInput::Value(c)
    }
}

impl From<f64> for ScalarInput {
    fn from(x: f64) -> Self {
        ScalarInput::Value(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn values_and_textures_are_told_apart_and_errors_say_which() {
        let c: ColorInput = serde_json::from_value(json!([0.5, 0.5, 0.5])).expect("colour");
        assert_eq!(c, ColorInput::Value([0.5; 3]));
        let t: ColorInput =
            serde_json::from_value(json!({"texture": "a.png", "wrap": ["clamp", "mirror"],
            "transform": {"scale": [2, 2]}, "uv": 1}))
            .expect("texture");
        let t = t.texture().expect("a texture");
        assert_eq!(t.wrap.axes(), [WrapMode::Clamp, WrapMode::Mirror]);
        assert_eq!(t.uv, 1);
        assert_eq!(
            t.transform.map(|x| (x.offset, x.scale)),
            Some(([0.0; 2], [2.0; 2]))
        );
        let e = serde_json::from_value::<ColorInput>(json!("red")).expect_err("a string");
        assert!(
            e.to_string()
                .contains("expected a colour [r, g, b] or {\"texture\": ...}"),
            "{e}"
        );
        let e = serde_json::from_value::<ScalarInput>(json!({"texture": "a.png", "scael": 1}))
            .expect_err("unknown field");
        assert!(e.to_string().contains("scael"), "{e}");
        let e = serde_json::from_value::<ScalarInput>(json!({"texture": "a.png", "wrap": "wavy"}))
            .expect_err("unknown wrap");
        assert!(
            e.to_string().contains("wrap") || e.to_string().contains("variant"),
            "{e}"
        );
        // Written back as read.
        let s: ScalarInput =
            serde_json::from_value(json!({"texture": "r.png", "factor": 0.5})).expect("scalar");
        assert_eq!(
            serde_json::to_value(&s).expect("json"),
            json!({"texture": "r.png", "factor": 0.5})
        );
    }
}
