//! Reference images, rendered once and kept: a PFM and a JSON note beside
//! it, named by scene, resolution and a key over the scene's JSON, the
//! renderer's version and the reference settings. A cached reference noisier
//! than asked for is rendered again, unless it had all the time allowed.

use crate::render::output::{decode_pfm, encode_pfm};
use crate::render::{Quality, Scene};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Changes whenever the estimator does (what a reference converges to):
/// bump the suffix with any change to the integrator's answer.
pub const RENDERER_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "+estimator.1");

/// What the JSON note beside a cached reference records.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u64,
    pub seconds: f64,
    /// The film's error estimate at the end.
    pub error_estimate: f64,
    pub backend: String,
    pub renderer_version: String,
}

/// A reference image and its note.
#[derive(Clone, Debug)]
pub struct Reference {
    pub info: ReferenceInfo,
    pub pixels: Vec<[f32; 3]>,
    /// Read from the cache rather than rendered in this run.
    pub cached: bool,
}

/// 64-bit FNV-1a: stable across Rust versions, unlike `DefaultHasher`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// File stem of a reference: `ref-<scene>-<w>x<h>-<key>`.
pub fn stem(name: &str, scene: &Scene, (width, height): (u32, u32), quality: &Quality) -> String {
    let scene_json = serde_json::to_string(&scene.to_json()).unwrap_or_default();
    let quality_json = serde_json::to_string(quality).unwrap_or_default();
    let key = fnv1a(format!("{scene_json}\n{RENDERER_VERSION}\n{quality_json}").as_bytes());
    let safe: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect();
    format!("ref-{safe}-{width}x{height}-{key:016x}")
}

/// The cached reference at `dir/stem`, if it is there, readable, and no
/// noisier than `max_error` or rendered for at least `max_seconds`.
pub fn load(dir: &Path, stem: &str, max_error: f64, max_seconds: f64) -> Option<Reference> {
    let note = std::fs::read(dir.join(format!("{stem}.json"))).ok()?;
    let info: ReferenceInfo = serde_json::from_slice(&note).ok()?;
    if !(info.error_estimate <= max_error || info.seconds >= max_seconds)
        || info.renderer_version != RENDERER_VERSION
    {
        return None;
    }
    let (w, h, pixels) = decode_pfm(&std::fs::read(dir.join(format!("{stem}.pfm"))).ok()?).ok()?;
    ((w, h) == (info.width, info.height)).then_some(Reference {
        info,
        pixels,
        cached: true,
    })
}

/// Writes `reference` to `dir/stem.{pfm,json}`; returns the PFM's path.
pub fn store(dir: &Path, stem: &str, reference: &Reference) -> std::io::Result<PathBuf> {
    std::fs::create_dir_all(dir)?;
    let pfm = dir.join(format!("{stem}.pfm"));
    std::fs::write(
        &pfm,
        encode_pfm(
            reference.info.width,
            reference.info.height,
            &reference.pixels,
        ),
    )?;
    let note = serde_json::to_vec_pretty(&reference.info).map_err(std::io::Error::other)?;
    std::fs::write(dir.join(format!("{stem}.json")), note)?;
    Ok(pfm)
}

/// Where references go by default: `$PATHSTREAM_CACHE_DIR`, else
/// `$XDG_CACHE_HOME/pathstream`, else `~/.cache/pathstream`, else
/// `.pathstream-cache` here.
pub fn default_dir() -> PathBuf {
    let env = |k: &str| {
        std::env::var_os(k)
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
    };
    env("PATHSTREAM_CACHE_DIR")
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("pathstream")))
        .or_else(|| env("HOME").map(|d| d.join(".cache").join("pathstream")))
        .unwrap_or_else(|| PathBuf::from(".pathstream-cache"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::builtin;

    #[test]
    fn key_follows_scene_size_and_settings() {
        let s = builtin("cornell").expect("scene");
        let q = Quality::default();
        let a = stem("cornell", &s, (64, 64), &q);
        assert_eq!(a, stem("cornell", &s, (64, 64), &q));
        assert!(a.starts_with("ref-cornell-64x64-"));
        assert_ne!(a, stem("cornell", &s, (64, 32), &q));
        assert_ne!(
            a,
            stem("cornell", &s, (64, 64), &Quality { max_depth: 3, ..q })
        );
        let glass = builtin("cornell-glass").expect("scene");
        assert_ne!(
            a.rsplit('-').next(),
            stem("cornell", &glass, (64, 64), &q).rsplit('-').next()
        );
    }

    #[test]
    fn store_then_load_and_refuse_a_noisier_one() {
        let dir = tempfile::tempdir().expect("tempdir");
        let r = Reference {
            info: ReferenceInfo {
                scene: "x".into(),
                width: 2,
                height: 1,
                spp: 10,
                seconds: 1.0,
                error_estimate: 0.01,
                backend: "cpu".into(),
                renderer_version: RENDERER_VERSION.into(),
            },
            pixels: vec![[1.0, 2.0, 3.0], [0.5, 0.25, 0.0]],
            cached: false,
        };
        store(dir.path(), "s", &r).expect("stores");
        let back = load(dir.path(), "s", 0.02, 1e9).expect("loads");
        assert_eq!(
            (back.info, back.pixels, back.cached),
            (r.info.clone(), r.pixels.clone(), true)
        );
        assert!(
            load(dir.path(), "s", 0.005, 1e9).is_none(),
            "noisier than asked"
        );
        assert!(
            load(dir.path(), "s", 0.005, 1.0).is_some(),
            "as long as allowed"
        );
        assert!(load(dir.path(), "other", 1.0, 1e9).is_none());
    }
}
