//! What a glTF `uri` names: a `data:` URI's bytes (base64 or
//! percent-encoded), or a file beside the `.gltf` (never an absolute path or
//! a URL; an upload has no directory, so a file is an error saying what to
//! upload instead).

use super::common::Ctx;
use super::ModelError;
use std::path::Path;

/// The bytes a `uri` names: a `data:` URI's, or a file's relative to
/// `dir` (an upload has none: `what` says what to upload instead).
pub(super) fn fetch_uri(
    ctx: &Ctx,
    dir: Option<&Path>,
    uri: &str,
    path: &str,
    what: &str,
) -> Result<Vec<u8>, ModelError> {
    if uri.starts_with("data:") {
        return data_uri(uri).map_err(|r| ctx.err_at(path, r));
    }
    let Some(dir) = dir else {
        return Err(ctx.err_at(
            path,
            format!("refers to the external file {uri:?}, which an upload cannot include: upload a .glb instead (or embed the {what} as a data: URI)"),
        ));
    };
    let name = String::from_utf8_lossy(&percent_decode(uri)).into_owned();
    if name.contains("://") || Path::new(&name).is_absolute() {
        return Err(ctx.err_at(
            path,
            format!("{uri:?}: only files relative to the glTF file are read"),
        ));
    }
    std::fs::read(dir.join(&name))
        .map_err(|e| ctx.err_at(path, format!("cannot read {name:?}: {e}")))
}

fn percent_decode(s: &str) -> Vec<u8> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = b
            .get(i + 1..i + 3)
            .and_then(|h| std::str::from_utf8(h).ok())
            .and_then(|h| u8::from_str_radix(h, 16).ok());
        match (b[i], hex) {
            (b'%', Some(v)) => {
                out.push(v);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

/// The bytes of a `data:[<type>][;base64],<data>` URI.
fn data_uri(uri: &str) -> Result<Vec<u8>, String> {
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    use base64::Engine;
    let (meta, payload) = uri["data:".len()..]
        .split_once(',')
        .ok_or("a data: URI without a comma")?;
    if meta.ends_with(";base64") {
        let engine = GeneralPurpose::new(
            &base64::alphabet::STANDARD,
            GeneralPurposeConfig::new().with_decode_padding_mode(DecodePaddingMode::Indifferent),
        );
        engine
            .decode(payload.trim())
            .map_err(|e| format!("the data: URI is not valid base64 ({e})"))
    } else {
        Ok(percent_decode(payload))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uris_and_percent_encoding() {
        assert_eq!(
            data_uri("data:application/octet-stream;base64,AAEC/w=="),
            Ok(vec![0, 1, 2, 255])
        );
        assert_eq!(
            data_uri("data:application/gltf-buffer;base64,AAEC/w"),
            Ok(vec![0, 1, 2, 255])
        );
        assert_eq!(data_uri("data:,a%20b"), Ok(b"a b".to_vec()));
        assert!(data_uri("data:;base64,@@@")
            .is_err_and(|e| e.starts_with("the data: URI is not valid base64")));
        assert_eq!(
            data_uri("data:nothing"),
            Err("a data: URI without a comma".to_owned())
        );
        assert_eq!(percent_decode("a%2"), b"a%2".to_vec());
    }
}
