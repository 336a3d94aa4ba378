//! Paired sections (uniform vs adaptive sampling, random vs Sobol numbers):
//! two settings rendered on the same scenes with the same seeds, each
//! one's time to [`LEVELS`] of true error, and how much sooner the second
//! gets there, as median and range over the seeds.

use super::cells;
use super::fit::{self, Reach};
use super::TradeCurve;
use std::fmt::Write as _;

/// The error levels the sections compare at.
pub const LEVELS: [f64; 3] = [0.05, 0.02, 0.01];

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

/// How much sooner the second setting reaches a level than the first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Speedup {
    /// The first's time over the second's.
    Exact(f64),
    /// The first never got there in its run (nor by its fit): its run's
    /// length over the second's time.
    AtLeast(f64),
}

impl Speedup {
    fn value(self) -> f64 {
        match self {
            Speedup::Exact(x) | Speedup::AtLeast(x) => x,
        }
    }
}

/// The first curve's time / the second's to each level, where the second's
/// is known.
pub fn speedups(first: &TradeCurve, second: &TradeCurve) -> [Option<Speedup>; 3] {
    let (u, a) = (times(first), times(second));
    let run = first.points.last().map_or(0.0, |p| p.seconds);
    std::array::from_fn(|i| {
        let second = seconds(a[i])?;
        Some(match seconds(u[i]) {
            Some(t) => Speedup::Exact(t / second),
            None if run > 0.0 => Speedup::AtLeast(run / second),
            None => return None,
        })
    })
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
/// several; where the first setting did not get there in some seed's run,
/// the least the speed-up can be over all seeds ("> 12x").
fn speedup_cell(values: Vec<Option<Speedup>>) -> String {
    let Some(all) = values.iter().copied().collect::<Option<Vec<Speedup>>>() else {
        return "?".into();
    };
    if all.iter().any(|s| matches!(s, Speedup::AtLeast(_))) {
        let lo = all.iter().map(|s| s.value()).fold(f64::INFINITY, f64::min);
        // A bound under 1 says nothing.
        return match lo >= 1.0 {
            true => format!("> {lo:.1}x"),
            false => "?".into(),
        };
    }
    let known: Vec<f64> = all.iter().map(|s| s.value()).collect();
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

/// A curve of the first setting and the second's of the same seed.
type Pair<'a> = (&'a TradeCurve, &'a TradeCurve);

/// What a paired section's tables say.
pub struct Table<'a> {
    /// The heading, before `, WxH, backend`.
    pub title: &'a str,
    /// The paragraph under it, before the medians' note.
    pub about: &'a str,
    /// The two settings' short names, as the columns give them.
    pub names: [&'a str; 2],
}

/// A paired section's tables, one per backend: per scene, median times
/// over the seeds of each setting, and the median speed-up (first's time
/// over second's) with its range. `curves` holds, per scene, backend and
/// seed, the first setting's curve then the second's.
pub fn markdown(w: &mut String, curves: &[TradeCurve], trade_size: (u32, u32), t: &Table) {
    if curves.is_empty() {
        return;
    }
    let (tw, th) = trade_size;
    let [a, b] = t.names;
    // (backend, scene) in the order measured, each with its pairs, one per
    // seed.
    let mut groups: Vec<(&str, &str, Vec<Pair>)> = Vec::new();
    for pair in curves.chunks(2) {
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
        let _ = writeln!(w, "## {}, {tw}x{th}, {backend}\n", t.title);
        let _ = writeln!(w, "{} Rendering time to each true error (`~`: extrapolated from the fit), and {a} time / {b} time; medians over {seeds} seed(s), the speed-ups' range in brackets.\n", t.about);
        let _ = writeln!(
            w,
            "| scene | to 5% {a} | {b} | to 2% {a} | {b} | to 1% {a} | {b} | speed-up 5% / 2% / 1% |"
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
        let x = |v: f64| Some(Speedup::Exact(v));
        assert_eq!(speedup_cell(vec![x(1.5)]), "1.50x");
        assert_eq!(
            speedup_cell(vec![x(1.8), x(1.2), x(1.6)]),
            "1.60x (1.20-1.80)"
        );
        assert_eq!(speedup_cell(vec![x(1.8), None]), "?");
        assert_eq!(
            speedup_cell(vec![x(30.0), Some(Speedup::AtLeast(12.04)), x(9.5)]),
            "> 9.5x",
            "a bound: the least over the seeds"
        );
        assert_eq!(speedup_cell(vec![Some(Speedup::AtLeast(0.7))]), "?");
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

    fn curve(points: &[(f64, f64)]) -> TradeCurve {
        TradeCurve {
            backend: "cpu".into(),
            scene: "s".into(),
            setting: super::super::settings::Setting::new("x", Default::default()),
            seed: 1,
            points: (points.iter().enumerate())
                .map(
                    |(i, &(seconds, true_error))| super::super::fit::TracePoint {
                        seconds,
                        spp: 1 << i,
                        true_error,
                        estimate: None,
                    },
                )
                .collect(),
            fit: None,
        }
    }

    #[test]
    fn a_level_the_first_never_reached_bounds_the_speedup_by_its_run() {
        let slow = curve(&[(1.0, 0.2), (10.0, 0.06)]);
        let fast = curve(&[(0.25, 0.1), (0.5, 0.04), (4.0, 0.015)]);
        let s = speedups(&slow, &fast);
        // 5%: the slow run never got there in 10 s, the fast one at ~0.37 s.
        assert!(
            matches!(s[0], Some(Speedup::AtLeast(x)) if x > 20.0 && x < 40.0),
            "{s:?}"
        );
        // 1%: neither did: unknown.
        assert_eq!(s[2], None);
        let exact = speedups(&fast, &slow);
        assert_eq!(exact[0], None, "the second never got there");
    }
}
