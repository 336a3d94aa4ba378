//! Environment maps built into the binary: 256 x 128 box-filtered
//! reductions of four CC0 Poly Haven HDRIs (server/assets/hdri/LICENSE.txt),
//! for the page's menu and for scenes that want a sky without an upload.
//! Each is named by the SHA-256 of its bytes, like an uploaded asset, so a
//! scene refers to one as `"environment": {"map": ID}` whether it was
//! uploaded or built in; each is read the first time a scene uses it.

use crate::render::envmap::EnvMap;
use std::sync::{Arc, OnceLock};

/// (name, the `.hdr` file's bytes).
const FILES: [(&str, &[u8]); 4] = [
    (
        "courtyard",
        include_bytes!("../../assets/hdri/courtyard-256.hdr"),
    ),
    (
        "interior",
        include_bytes!("../../assets/hdri/interior-256.hdr"),
    ),
    ("studio", include_bytes!("../../assets/hdri/studio-256.hdr")),
    ("sunset", include_bytes!("../../assets/hdri/sunset-256.hdr")),
];

/// A built-in map: its id and name; its image once read.
pub struct BuiltinMap {
    pub id: String,
    pub name: &'static str,
    bytes: &'static [u8],
    map: OnceLock<Result<Arc<EnvMap>, String>>,
}

impl BuiltinMap {
    /// The map, read and its tables built on first use.
    pub fn map(&self) -> Result<Arc<EnvMap>, String> {
        self.map
            .get_or_init(|| super::env_map_bytes(self.bytes, self.name).map(Arc::new))
            .clone()
    }
}

/// Every built-in map, by name.
pub fn builtin_maps() -> &'static [BuiltinMap] {
    static ALL: OnceLock<Vec<BuiltinMap>> = OnceLock::new();
    ALL.get_or_init(|| {
        FILES
            .iter()
            .map(|&(name, bytes)| BuiltinMap {
                id: super::asset_id(bytes),
                name,
                bytes,
                map: OnceLock::new(),
            })
            .collect()
    })
}

/// The built-in map with id (or name) `key`.
pub fn builtin_map(key: &str) -> Option<&'static BuiltinMap> {
    builtin_maps().iter().find(|m| m.id == key || m.name == key)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_map_reads_and_is_found_by_id_and_name() {
        for m in builtin_maps() {
            let map = m.map().expect("reads");
            assert_eq!((map.width, map.height), (256, 128), "{}", m.name);
            assert!(map.mean.iter().all(|&c| c > 0.0), "{}", m.name);
            assert!(std::ptr::eq(builtin_map(&m.id).expect("by id"), m));
            assert!(std::ptr::eq(builtin_map(m.name).expect("by name"), m));
        }
        assert!(builtin_map("nowhere").is_none());
    }
}
