//! glTF containers and data: GLB chunks, the JSON document (parsed and
//! validated by the `gltf` crate), buffers (the GLB BIN chunk, `data:` URIs,
//! external files, each loaded when first needed) and accessors. Accessors
//! are read here, not by the crate's readers, so that every byte range is
//! checked (the crate slices and unwraps) and integer attributes
//! (KHR_mesh_quantization) and sparse accessors work.

use super::common::Ctx;
use super::uri::fetch_uri;
use super::ModelError;
use ::gltf::accessor::{sparse::IndexType, Accessor, DataType, Dimensions};
use ::gltf::buffer::{Source, View};
use ::gltf::json::validation::{Checked, Error as Invalid, Validate};
use ::gltf::Document;
use std::path::Path;

/// A GLB's chunks.
pub(super) struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a GLB (`glTF` magic, version 2) into its JSON and BIN chunks;
/// chunks of other types are skipped, as the spec asks.
pub(super) fn split_glb<'a>(ctx: &Ctx, bytes: &'a [u8]) -> Result<Glb<'a>, ModelError> {
    let (Some(version), Some(length)) = (u32_at(bytes, 4), u32_at(bytes, 8)) else {
        return Err(ctx.err_at("byte 0", "truncated: a GLB header has 12 bytes"));
    };
    if version != 2 {
        return Err(ctx.err_at(
            "byte 4",
            format!("GLB version {version} (only version 2 is read)"),
        ));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(ctx.err_at(
            "byte 8",
            format!(
                "truncated: the GLB header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let bytes = &bytes[..length];
    let (mut at, mut index) = (12usize, 0usize);
    let (mut json, mut bin) = (None, None);
    while at < length {
        let (Some(len), Some(kind)) = (u32_at(bytes, at), bytes.get(at + 4..at + 8)) else {
            return Err(ctx.err_at(
                format!("byte {at}"),
                format!("truncated: chunk {index} has no complete header"),
            ));
        };
        let start = at + 8;
        let Some(end) = start.checked_add(len as usize).filter(|&e| e <= length) else {
            return Err(ctx.err_at(
                format!("byte {at}"),
                format!(
                    "truncated: chunk {index} says {len} bytes, {} remain",
                    length - start
                ),
            ));
        };
        match (index, kind) {
            (0, b"JSON") => json = Some(&bytes[start..end]),
            (0, _) => return Err(ctx.err_at("byte 12", "the first GLB chunk is not JSON")),
            (1, b"BIN\0") => bin = Some(&bytes[start..end]),
            _ => {}
        }
        at = end;
        index += 1;
    }
    let json = json.ok_or_else(|| ctx.err_at("byte 12", "truncated: the GLB has no JSON chunk"))?;
    Ok(Glb { json, bin })
}

/// Parses and validates the JSON. Unsupported `extensionsRequired` are left
/// to the caller (which refuses only those that hide the geometry).
pub(super) fn parse_document(ctx: &Ctx, json: &[u8]) -> Result<Document, ModelError> {
    let root: ::gltf::json::Root = serde_json::from_slice(json).map_err(|e| {
        let text = e.to_string();
        let reason = text.split(" at line ").next().unwrap_or(&text).to_owned();
        ctx.err_at(
            format!("JSON line {}, column {}", e.line(), e.column()),
            reason,
        )
    })?;
    // gltf-json's validation indexes `accessors` by each POSITION without a
    // check (and panics): check those first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim
                .attributes
                .get(&Checked::Valid(::gltf::Semantic::Positions));
            if position.is_some_and(|i| i.value() >= root.accessors.len()) {
                return Err(ctx.err_at(
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    "index out of range",
                ));
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(
        &root,
        ::gltf::json::Path::new,
        &mut |path: &dyn Fn() -> ::gltf::json::Path, e| {
            let path = path().to_string();
            // Accessor bounds are not used (the spec's required POSITION min/max
            // are missing from some exporters' files).
            let unused = path.ends_with(".min") || path.ends_with(".max");
            let extension = e == Invalid::Unsupported && path.starts_with("extensionsRequired");
            if !(unused || extension) {
                problems.push((path, e));
            }
        },
    );
    if let Some((path, e)) = problems.first() {
        let what = match e {
            Invalid::IndexOutOfBounds => "index out of range",
            Invalid::Invalid => "invalid value",
            Invalid::Missing => "missing",
            Invalid::Oversize => "too large",
            Invalid::Unsupported => "not supported",
        };
        let more = match problems.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        return Err(ctx.err_at(path.clone(), format!("{what}{more}")));
    }
    Ok(Document::from_json_without_validation(root))
}

/// The document's buffers, each read when an accessor first needs it.
pub(super) struct Buffers<'a> {
    bin: Option<&'a [u8]>,
    dir: Option<&'a Path>,
    /// Per buffer: (source, byteLength), then its bytes once loaded.
    sources: Vec<(Option<String>, usize)>,
    loaded: Vec<Option<Vec<u8>>>,
}

impl<'a> Buffers<'a> {
    pub fn new(doc: &Document, bin: Option<&'a [u8]>, dir: Option<&'a Path>) -> Self {
        let sources: Vec<_> = doc
            .buffers()
            .map(|b| {
                let uri = match b.source() {
                    Source::Bin => None,
                    Source::Uri(u) => Some(u.to_owned()),
                };
                (uri, b.length())
            })
            .collect();
        let loaded = vec![None; sources.len()];
        Self {
            bin,
            dir,
            sources,
            loaded,
        }
    }

    /// Reads buffer `index` if not yet read; checks it holds its byteLength.
    fn load(&mut self, ctx: &Ctx, index: usize) -> Result<(), ModelError> {
        if self.loaded.get(index).is_some_and(Option::is_some) {
            return Ok(());
        }
        let path = format!("buffers[{index}]");
        let (uri, length) = self
            .sources
            .get(index)
            .ok_or_else(|| ctx.err_at(&path, "no such buffer"))?;
        let data = match uri.as_deref() {
            None if index == 0 => self
                .bin
                .ok_or_else(|| ctx.err_at(&path, "has no uri, and the file has no GLB BIN chunk"))?
                .to_vec(),
            None => {
                return Err(ctx.err_at(
                    &path,
                    "has no uri (only buffer 0 of a GLB may use the BIN chunk)",
                ))
            }
            Some(uri) => fetch_uri(ctx, self.dir, uri, &path, "buffer")?,
        };
        if data.len() < *length {
            return Err(ctx.err_at(
                &path,
                format!(
                    "holds {} bytes, but its byteLength is {length} (truncated)",
                    data.len()
                ),
            ));
        }
        self.loaded[index] = Some(data);
        Ok(())
    }

    /// The bytes of buffer view `view` (an image's).
    pub fn view(&mut self, ctx: &Ctx, view: &View) -> Result<&[u8], ModelError> {
        let (buffer, start, _) = place(
            ctx,
            self,
            view,
            0,
            view.length(),
            1,
            true,
            &format!("bufferViews[{}]", view.index()),
        )?;
        Ok(&self.bytes(buffer)[start..start + view.length()])
    }

    /// The directory external files are read from (none for an upload).
    pub fn dir(&self) -> Option<&'a Path> {
        self.dir
    }

    fn bytes(&self, index: usize) -> &[u8] {
        self.loaded
            .get(index)
            .and_then(Option::as_deref)
            .unwrap_or_default()
    }
}

/// Where `count` elements of `elem` bytes, `stride` apart, start `offset`
/// bytes into `view`: (buffer, first byte, stride), every byte checked to lie
/// in the view and the view in its buffer. `packed` (sparse data) ignores
/// the view's byteStride.
#[allow(clippy::too_many_arguments)]
fn place(
    ctx: &Ctx,
    bufs: &mut Buffers,
    view: &View,
    offset: usize,
    count: usize,
    elem: usize,
    packed: bool,
    path: &str,
) -> Result<(usize, usize, usize), ModelError> {
    let stride = if packed {
        elem
    } else {
        view.stride().unwrap_or(elem)
    };
    if stride < elem {
        return Err(ctx.err_at(
            path,
            format!("byteStride {stride} is less than the element size {elem}"),
        ));
    }
    let needed = match count {
        0 => Some(0),
        n => (n - 1)
            .checked_mul(stride)
            .and_then(|x| x.checked_add(elem)),
    }
    .and_then(|x| x.checked_add(offset));
    if needed.is_none_or(|n| n > view.length()) {
        return Err(ctx.err_at(
            path,
            format!(
                "{count} elements of {elem} bytes from byte {offset} do not fit in bufferViews[{}] ({} bytes)",
                view.index(),
                view.length()
            ),
        ));
    }
    let buffer = view.buffer().index();
    bufs.load(ctx, buffer)?;
    let have = bufs.bytes(buffer).len();
    if view
        .offset()
        .checked_add(view.length())
        .is_none_or(|end| end > have)
    {
        return Err(ctx.err_at(
            format!("bufferViews[{}]", view.index()),
            format!(
                "bytes {}..+{} lie outside buffers[{buffer}] ({have} bytes)",
                view.offset(),
                view.length()
            ),
        ));
    }
    Ok((buffer, view.offset() + offset, stride))
}

/// Reads an accessor's elements with `decode` (given exactly one element's
/// bytes): the dense data (zeros without a bufferView), then the sparse
/// substitutions. The caller has checked `count` against the limits.
fn read<T: Copy + Default>(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &Accessor,
    path: &str,
    decode: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, ModelError> {
    let (count, elem) = (acc.count(), acc.size());
    let short = || ctx.err_at(path, "data cut short (a loader bug)");
    let mut out = match acc.view() {
        Some(view) => {
            let (buffer, start, stride) =
                place(ctx, bufs, &view, acc.offset(), count, elem, false, path)?;
            let data = bufs.bytes(buffer);
            let mut out = Vec::with_capacity(count);
            for i in 0..count {
                let at = start + i * stride;
                out.push(decode(data.get(at..at + elem).ok_or_else(short)?));
            }
            out
        }
        None => vec![T::default(); count],
    };
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        let (indices, values) = (sparse.indices(), sparse.values());
        let width = match indices.index_type() {
            IndexType::U8 => 1,
            IndexType::U16 => 2,
            IndexType::U32 => 4,
        };
        let ipath = format!("{path}.sparse.indices");
        let (ib, istart, _) = place(
            ctx,
            bufs,
            &indices.view(),
            indices.offset(),
            n,
            width,
            true,
            &ipath,
        )?;
        let vpath = format!("{path}.sparse.values");
        let (vb, vstart, _) = place(
            ctx,
            bufs,
            &values.view(),
            values.offset(),
            n,
            elem,
            true,
            &vpath,
        )?;
        for k in 0..n {
            let ib = bufs
                .bytes(ib)
                .get(istart + k * width..istart + (k + 1) * width)
                .ok_or_else(short)?;
            let i = match ib {
                [a] => u32::from(*a),
                [a, b] => u32::from(u16::from_le_bytes([*a, *b])),
                [a, b, c, d] => u32::from_le_bytes([*a, *b, *c, *d]),
                _ => return Err(short()),
            } as usize;
            let value = bufs
                .bytes(vb)
                .get(vstart + k * elem..vstart + (k + 1) * elem)
                .ok_or_else(short)?;
            let slot = out.get_mut(i).ok_or_else(|| {
                ctx.err_at(&ipath, format!("index {i} out of range (count {count})"))
            })?;
            *slot = decode(value);
        }
    }
    Ok(out)
}

/// One component as f32: floats as they are, integers normalised when the
/// accessor says so (KHR_mesh_quantization), else converted.
fn component(ty: DataType, normalized: bool) -> Option<fn(&[u8]) -> f32> {
    fn b<const N: usize>(x: &[u8]) -> [u8; N] {
        let mut a = [0u8; N];
        a.copy_from_slice(&x[..N]);
        a
    }
    Some(match (ty, normalized) {
        (DataType::F32, _) => |x| f32::from_le_bytes(b(x)),
        (DataType::I8, true) => |x| (f32::from(i8::from_le_bytes(b(x))) / 127.0).max(-1.0),
        (DataType::U8, true) => |x| f32::from(x[0]) / 255.0,
        (DataType::I16, true) => |x| (f32::from(i16::from_le_bytes(b(x))) / 32767.0).max(-1.0),
        (DataType::U16, true) => |x| f32::from(u16::from_le_bytes(b(x))) / 65535.0,
        (DataType::I8, false) => |x| f32::from(i8::from_le_bytes(b(x))),
        (DataType::U8, false) => |x| f32::from(x[0]),
        (DataType::I16, false) => |x| f32::from(i16::from_le_bytes(b(x))),
        (DataType::U16, false) => |x| f32::from(u16::from_le_bytes(b(x))),
        (DataType::U32, _) => return None,
    })
}

/// A VEC3 attribute (POSITION, NORMAL).
pub(super) fn read_vec3(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &Accessor,
    path: &str,
) -> Result<Vec<[f32; 3]>, ModelError> {
    let ty = acc.data_type();
    let (Dimensions::Vec3, Some(c)) = (acc.dimensions(), component(ty, acc.normalized())) else {
        return Err(ctx.err_at(
            path,
            format!(
                "accessors[{}] is {:?} of {ty:?}, not a VEC3 of floats or small integers",
                acc.index(),
                acc.dimensions()
            ),
        ));
    };
    let s = ty.size();
    read(ctx, bufs, acc, path, |x| [c(x), c(&x[s..]), c(&x[2 * s..])])
}

/// A VEC2 attribute (TEXCOORD_n).
pub(super) fn read_vec2(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &Accessor,
    path: &str,
) -> Result<Vec<[f32; 2]>, ModelError> {
    let (c, s) = float_components(ctx, acc, Dimensions::Vec2, path)?;
    read(ctx, bufs, acc, path, |x| [c(x), c(&x[s..])])
}

/// A VEC4 attribute (TANGENT).
pub(super) fn read_vec4(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &Accessor,
    path: &str,
) -> Result<Vec<[f32; 4]>, ModelError> {
    let (c, s) = float_components(ctx, acc, Dimensions::Vec4, path)?;
    read(ctx, bufs, acc, path, |x| {
        [c(x), c(&x[s..]), c(&x[2 * s..]), c(&x[3 * s..])]
    })
}

/// Reads one component of an element as f32.
type Decode = fn(&[u8]) -> f32;

/// The component decoder and size of an accessor that must have `dims`.
fn float_components(
    ctx: &Ctx,
    acc: &Accessor,
    dims: Dimensions,
    path: &str,
) -> Result<(Decode, usize), ModelError> {
    let ty = acc.data_type();
    match (acc.dimensions() == dims, component(ty, acc.normalized())) {
        (true, Some(c)) => Ok((c, ty.size())),
        _ => Err(ctx.err_at(
            path,
            format!(
                "accessors[{}] is {:?} of {ty:?}, not a {dims:?} of floats or small integers",
                acc.index(),
                acc.dimensions()
            ),
        )),
    }
}

/// Triangle indices: SCALAR unsigned bytes, shorts or ints.
pub(super) fn read_indices(
    ctx: &Ctx,
    bufs: &mut Buffers,
    acc: &Accessor,
    path: &str,
) -> Result<Vec<u32>, ModelError> {
    let ty = acc.data_type();
    let decode: fn(&[u8]) -> u32 = match (acc.dimensions(), ty) {
        (Dimensions::Scalar, DataType::U8) => |x| u32::from(x[0]),
        (Dimensions::Scalar, DataType::U16) => |x| u32::from(u16::from_le_bytes([x[0], x[1]])),
        (Dimensions::Scalar, DataType::U32) => |x| u32::from_le_bytes([x[0], x[1], x[2], x[3]]),
        (dims, _) => {
            return Err(ctx.err_at(
                path,
                format!(
                    "accessors[{}] is {dims:?} of {ty:?}, not unsigned integer indices",
                    acc.index()
                ),
            ))
        }
    };
    read(ctx, bufs, acc, path, decode)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_chunks_are_checked() {
        let ctx = Ctx::new("m.glb", &crate::model::Limits::default());
        let mut glb = b"glTF".to_vec();
        glb.extend(2u32.to_le_bytes());
        glb.extend(28u32.to_le_bytes());
        glb.extend(4u32.to_le_bytes());
        glb.extend(b"JSON{}  ");
        glb.extend(0u32.to_le_bytes());
        let e = split_glb(&ctx, &glb).err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("m.glb: byte 24: truncated: chunk 1 has no complete header")
        );
        glb.truncate(24);
        glb[8] = 24;
        let g = split_glb(&ctx, &glb).expect("a JSON chunk alone");
        assert_eq!((g.json, g.bin), (&b"{}  "[..], None));
        glb[12] = 40;
        let e = split_glb(&ctx, &glb).err().map(|e| e.to_string());
        assert_eq!(
            e.as_deref(),
            Some("m.glb: byte 12: truncated: chunk 0 says 40 bytes, 4 remain")
        );
    }
}
