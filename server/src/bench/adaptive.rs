//! The adaptive section: uniform and adaptive sampling of the unbiased
//! setting on every scene, and how much sooner adaptive reaches 5%, 2% and
//! 1% true error.

use super::fit::{self, Reach};
use super::settings::{self, Setting};
use super::{report, Results, TradeCurve};
use crate::model::generate::bumpy_sphere;
use crate::render::{Quality, Scene, SceneError};
use serde_json::json;
use std::fmt::Write as _;

/// A scene with a mesh for the section: cornell-glass with its glass ball
/// replaced by a glass bumpy sphere of 20,000 triangles (caustics through a
/// mesh).
pub const MESH_SCENE: &str = "cornell-glass-mesh";

/// The error levels the section compares at.
pub const LEVELS: [f64; 3] = [0.05, 0.02, 0.01];

/// [`MESH_SCENE`], built.
pub fn mesh_scene() -> Result<Scene, SceneError> {
    let mut j = serde_json::to_value(Scene::load("cornell-glass")?.to_json())
        .map_err(|e| SceneError::new(".", e.to_string()))?;
    let mesh = bumpy_sphere(20_000);
    let ball = json!({
        "type": "mesh",
        "data": {"positions": mesh.positions, "triangles": mesh.triangles},
        "material": "glass",
        "transform": {"translate": [73.0, 16.5, 78.0], "scale": 14.0},
    });
    if let Some(objects) = j["objects"].as_array_mut() {
        match objects
            .iter()
            .position(|o| o["center"] == json!([73.0, 16.5, 78.0]))
        {
            Some(i) => objects[i] = ball,
            None => objects.push(ball),
        }
    }
    Scene::from_json_value(j)
}

/// The two settings compared: the unbiased setting, uniform and adaptive.
pub fn pair() -> [Setting; 2] {
    let uniform = settings::unbiased();
    [
        Setting {
            label: "unbounded, uniform".into(),
            quality: uniform,
        },
        Setting {
            label: "unbounded, adaptive".into(),
            quality: Quality {
                adaptive: true,
                ..uniform
            },
        },
    ]
}

/// Seconds to `level` as a number, where measured or extrapolated.
fn seconds(r: Reach) -> Option<f64> {
    match r {
        Reach::Measured(s) | Reach::Extrapolated(s) => Some(s),
        Reach::Never | Reach::Unknown => None,
    }
}

/// Times to [`LEVELS`] of `curve`.
fn times(curve: &TradeCurve) -> [Reach; 3] {
    LEVELS.map(|l| fit::time_to(&curve.points, curve.fit.as_ref(), l))
}

/// Uniform time / adaptive time to each level, where both are known.
pub fn speedups(uniform: &TradeCurve, adaptive: &TradeCurve) -> [Option<f64>; 3] {
    let (u, a) = (times(uniform), times(adaptive));
    std::array::from_fn(|i| Some(seconds(u[i])? / seconds(a[i])?))
}

/// The section's table, one per backend.
pub fn markdown(w: &mut String, r: &Results) {
    if r.adaptive.is_empty() {
        return;
    }
    let (tw, th) = r.trade_size;
    let mut backends: Vec<&str> = Vec::new();
    for c in &r.adaptive {
        if !backends.contains(&c.backend.as_str()) {
            backends.push(&c.backend);
        }
    }
    for backend in backends {
        let _ = writeln!(
            w,
            "## Adaptive sampling: uniform vs adaptive, {tw}x{th}, {backend}\n"
        );
        let _ = writeln!(w, "The unbiased setting (unbounded, NEE) with uniform and with adaptive sampling: rendering time to each true error (`~`: extrapolated from the fit), and uniform time / adaptive time.\n");
        let _ = writeln!(
            w,
            "| scene | to 5% uniform | adaptive | to 2% uniform | adaptive | to 1% uniform | adaptive | speed-up 5% / 2% / 1% |"
        );
        let _ = writeln!(
            w,
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        );
        let curves: Vec<&TradeCurve> = r.adaptive.iter().filter(|c| c.backend == backend).collect();
        for pair in curves.chunks(2) {
            let [u, a] = pair else { continue };
            let (tu, ta) = (times(u), times(a));
            let x = speedups(u, a).map(|s| s.map_or("?".into(), |s| format!("{s:.2}x")));
            let _ = writeln!(
                w,
                "| {} | {} | {} | {} | {} | {} | {} | {} / {} / {} |",
                u.scene,
                report::reach(tu[0]),
                report::reach(ta[0]),
                report::reach(tu[1]),
                report::reach(ta[1]),
                report::reach(tu[2]),
                report::reach(ta[2]),
                x[0],
                x[1],
                x[2]
            );
        }
        let _ = writeln!(w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mesh_scene_has_its_glass_mesh() {
        let s = mesh_scene().expect("valid");
        assert!(s.unique_triangles() >= 19_000, "{}", s.unique_triangles());
        let [u, a] = pair();
        assert!(!u.quality.adaptive && a.quality.adaptive);
        assert_eq!(
            Quality {
                adaptive: false,
                ..a.quality
            },
            u.quality
        );
    }
}
