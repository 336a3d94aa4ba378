//! Texture images (PNG and JPEG) decoded to 8-bit RGBA. The size in the
//! image's header is checked against the model's texel budget before any
//! texel is decoded, so a 100000 x 100000 header costs nothing.

use super::common::Ctx;
use super::Image;
use std::io::Cursor;

/// Decodes `bytes` (named `name` in messages, `location` where in the
/// file the image is referred to), charging its texels to `ctx`'s budget.
pub(super) fn decode(
    ctx: &mut Ctx,
    bytes: &[u8],
    name: &str,
    location: &str,
) -> Result<Image, super::ModelError> {
    let fail = |ctx: &Ctx, reason: String| match name == location {
        true => ctx.err_at(location, reason),
        false => ctx.err_at(location, format!("{name}: {reason}")),
    };
    let reader = || {
        image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| e.to_string())
    };
    let format = reader().map_err(|e| fail(ctx, e))?.format();
    match format {
        Some(image::ImageFormat::Png | image::ImageFormat::Jpeg) => {}
        Some(other) => {
            return Err(fail(
                ctx,
                format!("{other:?} images are not read (PNG and JPEG are)"),
            ))
        }
        None => return Err(fail(ctx, "not a PNG or JPEG image".to_owned())),
    }
    let (width, height) = reader()
        .and_then(|r| r.into_dimensions().map_err(|e| e.to_string()))
        .map_err(|e| fail(ctx, format!("cannot read the header: {e}")))?;
    let texels = u64::from(width) * u64::from(height);
    let side = crate::model::MAX_IMAGE_SIDE;
    if width == 0 || height == 0 || width > side || height > side {
        return Err(fail(
            ctx,
            format!("{width}x{height} texels: each side must be between 1 and {side}"),
        ));
    }
    ctx.charge_texels(texels, location)?;
    let mut r = reader().map_err(|e| fail(ctx, e))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(width);
    limits.max_image_height = Some(height);
    limits.max_alloc = Some(texels.saturating_mul(8).max(1 << 20));
    r.limits(limits);
    let decoded = r
        .decode()
        .map_err(|e| fail(ctx, format!("cannot decode: {e}")))?;
    Ok(Image {
        name: name.to_owned(),
        width,
        height,
        rgba: decoded.into_rgba8().into_raw(),
    })
}

/// An image file on its own (a scene material's texture), PNG or JPEG,
/// named `name`; its texels within `limits.max_texels`.
pub fn load_image(
    bytes: &[u8],
    name: &str,
    limits: &super::Limits,
) -> Result<Image, super::ModelError> {
    let mut ctx = Ctx::new(name, limits);
    decode(&mut ctx, bytes, name, name).map_err(|e| super::ModelError {
        location: None,
        ..e
    })
}

/// "png" or "jpeg" where `bytes` start as those files do.
pub fn image_format(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("png")
    } else if bytes.starts_with(b"\xFF\xD8\xFF") {
        Some("jpeg")
    } else {
        None
    }
}
