//! The adaptive section: uniform and adaptive sampling of the unbiased
//! setting on every scene, and how much sooner adaptive reaches 5%, 2% and
//! 1% true error.

use super::cells;
use super::fit::{self, Reach};
use super::settings::{self, Setting};
use super::{Results, TradeCurve};
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
    let mut j = serde_json::to_value(crate::resolve::load_scene("cornell-glass")?.to_json())
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

/// The middle of `values` (the lower middle of an even count), sorted by
/// `key`; None when empty.
fn median_by<T: Copy>(mut values: Vec<T>, key: impl Fn(&T) -> f64) -> Option<T> {
    values.sort_by(|a, b| key(a).total_cmp(&key(b)));
    values.get(values.len().saturating_sub(1) / 2).copied()
}

/// A time cell: the median over seeds.
fn time_cell(reaches: Vec<Reach>) -> String {
    median_by(reaches, |r| seconds(*r).unwrap_or(f64::INFINITY)).map_or("?".into(), cells::reach)
}

/// A speed-up cell: the median over seeds, and their range when there are
/// several.
fn speedup_cell(values: Vec<Option<f64>>) -> String {
    let known: Vec<f64> = values.iter().flatten().copied().collect();
    if known.len() < values.len() {
        return "?".into();
    }
    let Some(mid) = median_by(known.clone(), |x| *x) else {
        return "?".into();
    };
    match known.len() {
        1 => format!("{mid:.2}x"),
        _ => {
            let lo = known.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = known.iter().copied().fold(0.0, f64::max);
            format!("{mid:.2}x ({lo:.2}-{hi:.2})")
        }
    }
}

/// A uniform curve and the adaptive one of the same seed.
type Pair<'a> = (&'a TradeCurve, &'a TradeCurve);

/// The section's table, one per backend: per scene, median times over the
/// seeds and the median speed-up with its range.
pub fn markdown(w: &mut String, r: &Results) {
    if r.adaptive.is_empty() {
        return;
    }
    let (tw, th) = r.trade_size;
    // (backend, scene) in the order measured, each with its (uniform,
    // adaptive) pairs, one per seed.
    let mut groups: Vec<(&str, &str, Vec<Pair>)> = Vec::new();
    for pair in r.adaptive.chunks(2) {
        let [u, a] = pair else { continue };
        match groups
            .iter_mut()
            .find(|g| g.0 == u.backend && g.1 == u.scene)
        {
            Some(g) => g.2.push((u, a)),
            None => groups.push((&u.backend, &u.scene, vec![(u, a)])),
        }
    }
    let mut backends: Vec<&str> = Vec::new();
    for g in &groups {
        if !backends.contains(&g.0) {
            backends.push(g.0);
        }
    }
    for backend in backends {
        let seeds = groups
            .iter()
            .find(|g| g.0 == backend)
            .map_or(0, |g| g.2.len());
        let _ = writeln!(
            w,
            "## Adaptive sampling: uniform vs adaptive, {tw}x{th}, {backend}\n"
        );
        let _ = writeln!(w, "The unbiased setting (unbounded, NEE) with uniform and with adaptive sampling: rendering time to each true error (`~`: extrapolated from the fit), and uniform time / adaptive time; medians over {seeds} seed(s), the speed-ups' range in brackets.\n");
        let _ = writeln!(
            w,
            "| scene | to 5% uniform | adaptive | to 2% uniform | adaptive | to 1% uniform | adaptive | speed-up 5% / 2% / 1% |"
        );
        let _ = writeln!(
            w,
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        );
        for (_, scene, pairs) in groups.iter().filter(|g| g.0 == backend) {
            let level = |i: usize| {
                let u = time_cell(pairs.iter().map(|(u, _)| times(u)[i]).collect());
                let a = time_cell(pairs.iter().map(|(_, a)| times(a)[i]).collect());
                let x = speedup_cell(pairs.iter().map(|(u, a)| speedups(u, a)[i]).collect());
                (u, a, x)
            };
            let [l0, l1, l2] = [level(0), level(1), level(2)];
            let _ = writeln!(
                w,
                "| {scene} | {} | {} | {} | {} | {} | {} | {} / {} / {} |",
                l0.0, l0.1, l1.0, l1.1, l2.0, l2.1, l0.2, l1.2, l2.2
            );
        }
        let _ = writeln!(w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_give_the_median_and_the_range() {
        assert_eq!(speedup_cell(vec![Some(1.5)]), "1.50x");
        assert_eq!(
            speedup_cell(vec![Some(1.8), Some(1.2), Some(1.6)]),
            "1.60x (1.20-1.80)"
        );
        assert_eq!(speedup_cell(vec![Some(1.8), None]), "?");
        assert_eq!(
            time_cell(vec![
                Reach::Measured(2.0),
                Reach::Extrapolated(9.0),
                Reach::Measured(1.0)
            ]),
            "2.00 s"
        );
        assert_eq!(time_cell(vec![Reach::Never, Reach::Unknown]), "never");
    }

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
