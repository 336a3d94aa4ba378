//! `pathstream bench`: the quick version runs every section, writes tables,
//! CSV and plots, caches its references, and its error estimate calibration
//! holds; bad arguments exit with code 2.

use std::path::Path;
use std::process::{Command, Output};

fn pathstream(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pathstream"))
        .args(args)
        .output()
        .expect("runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// CSV rows (header first), split naively: the bench writes no quoted commas
/// except in the `quality` column, which is read by name only in `trade.csv`.
fn csv_rows(file: &Path) -> Vec<Vec<String>> {
    let mut reader = csv::Reader::from_path(file).expect("csv");
    let header: Vec<String> = reader
        .headers()
        .expect("header")
        .iter()
        .map(str::to_owned)
        .collect();
    let mut rows = vec![header];
    for r in reader.records() {
        rows.push(r.expect("record").iter().map(str::to_owned).collect());
    }
    rows
}

#[test]
fn quick_bench_writes_tables_csv_and_plots_and_caches_references() {
    let out_dir = tempfile::tempdir().expect("tempdir");
    let cache = tempfile::tempdir().expect("tempdir");
    let args = [
        "bench",
        "--quick",
        "--backend",
        "cpu",
        "--out",
        path(out_dir.path()),
        "--cache",
        path(cache.path()),
    ];
    let first = pathstream(&args);
    assert!(first.status.success(), "{}", text(&first.stderr));
    let md = text(&first.stdout);
    for heading in [
        "## Throughput",
        "## Speed/accuracy trade: `cornell`, 16x16, cpu",
        "## Calibration of the error estimate",
        "## A sky behind walls: power picks vs the sky probe, 16x16, cpu",
        "| sky-room (power picks) |",
    ] {
        assert!(md.contains(heading), "{heading} missing:\n{md}");
    }
    // Every trade setting has a row with a time or a verdict for each level.
    for s in pathstream::bench::settings::trade_settings() {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| {} |", s.label)))
            .unwrap_or_else(|| panic!("{} missing", s.label));
        assert_eq!(row.matches('|').count(), 9, "{row}");
    }
    assert!(!md.contains("(cached)"), "first run renders its reference");

    let trade = csv_rows(&out_dir.path().join("trade.csv"));
    assert_eq!(
        trade.len() - 1,
        pathstream::bench::settings::trade_settings().len()
    );
    let points = csv_rows(&out_dir.path().join("trade_points.csv"));
    assert_eq!(
        points[0],
        [
            "backend",
            "scene",
            "setting",
            "seconds",
            "spp",
            "true_error",
            "estimate"
        ]
    );
    // Within one setting, time and samples only grow.
    for pair in points[1..].windows(2).filter(|w| w[0][2] == w[1][2]) {
        let f = |r: &Vec<String>, i: usize| r[i].parse::<f64>().expect("number");
        assert!(
            f(&pair[1], 3) >= f(&pair[0], 3) && f(&pair[1], 4) > f(&pair[0], 4),
            "{pair:?}"
        );
    }
    let throughput = csv_rows(&out_dir.path().join("throughput.csv"));
    assert_eq!(throughput.len() - 1, 4, "2 scenes x 2 sizes");
    for name in ["trade-cornell-cpu.png", "calibration.png"] {
        let img = image::open(out_dir.path().join(name)).expect("a PNG");
        assert_eq!(
            (img.width(), img.height()),
            pathstream::bench::plot::SIZE,
            "{name}"
        );
        let rgb = img.to_rgb8();
        assert!(
            rgb.pixels().any(|p| p.0 != [255, 255, 255]),
            "{name} is blank"
        );
    }
    assert!(out_dir.path().join("bench.md").is_file());

    // The rerun finds the reference in the cache.
    let second = pathstream(&[
        "bench",
        "--quick",
        "--backend",
        "cpu",
        "--sections",
        "trade",
        "--cache",
        path(cache.path()),
    ]);
    assert!(second.status.success(), "{}", text(&second.stderr));
    let md = text(&second.stdout);
    assert!(md.contains("(cached)"), "{md}");
    assert!(
        !md.contains("## Throughput"),
        "only the trade section was asked for"
    );
}

#[test]
fn error_estimate_calibration_is_near_one() {
    // 24x24, not 16x16: at 16x16 a few fireflies around cornell's small
    // lamp decide the median, and on a loaded machine (the checkpoints'
    // sample counts follow the time) it strayed to 0.69 one run in six;
    // 24x24 reads 0.92 in every run measured under the same load.
    let cache = tempfile::tempdir().expect("tempdir");
    let out_dir = tempfile::tempdir().expect("tempdir");
    let out = pathstream(&[
        "bench",
        "--backend",
        "cpu",
        "--sections",
        "calibration,adaptive",
        "--scenes",
        "cornell",
        "--trade-size",
        "24x24",
        "--trade-seconds",
        "0.5",
        "--reference-error",
        "0.008",
        "--reference-seconds",
        "20",
        "--cache",
        path(cache.path()),
        "--out",
        path(out_dir.path()),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let md = text(&out.stdout);
    // Uniform and adaptive sampling alike.
    for scene in ["cornell", "cornell (adaptive)"] {
        let row = md
            .lines()
            .find(|l| l.starts_with(&format!("| cpu | {scene} |")))
            .unwrap_or_else(|| panic!("row {scene} missing:\n{md}"));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let points: usize = cells[3].parse().expect("count");
        let median: f64 = cells[4].parse().expect("median");
        assert!(points >= 5, "{row}");
        assert!(
            (0.7..1.4).contains(&median),
            "estimate/true median {median}: {row}"
        );
    }
    assert!(
        md.contains("## Adaptive sampling: uniform vs adaptive"),
        "{md}"
    );
}

#[test]
fn bad_arguments_exit_2_naming_the_problem() {
    let cases: [(&[&str], &str); 4] = [
        (&["bench", "--quick", "--trade-size", "0x5"], "--trade-size"),
        (&["bench", "--quick", "--scenes", "nope"], "--scenes nope"),
        (
            &["bench", "--quick", "--trade-seconds", "-1"],
            "--trade-seconds",
        ),
        (&["bench", "--quick", "--sections", "speed"], "--sections"),
    ];
    for (args, needle) in cases {
        let out = pathstream(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = text(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn opencl_throughput_and_specialisation() {
    let cache = tempfile::tempdir().expect("tempdir");
    let out_dir = tempfile::tempdir().expect("tempdir");
    let out = pathstream(&[
        "bench",
        "--quick",
        "--backend",
        "opencl",
        "--sections",
        "throughput,specialisation",
        "--scenes",
        "cornell",
        "--cache",
        path(cache.path()),
        "--out",
        path(out_dir.path()),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let md = text(&out.stdout);
    assert!(
        md.contains("## OpenCL: scene-specialised vs generic program"),
        "{md}"
    );
    let rows: Vec<&str> = md
        .lines()
        .filter(|l| l.starts_with("| opencl | cornell |"))
        .collect();
    assert_eq!(rows.len(), 2, "{md}");
    // | device | scene | size | specialised M paths/s | generic M paths/s | ratio |
    let spec = md
        .lines()
        .find(|l| l.contains("| cornell | 64x64 |") && !l.starts_with("| opencl"))
        .expect("row");
    let cells: Vec<f64> = spec
        .split('|')
        .map(str::trim)
        .skip(4)
        .take(3)
        .map(|c| c.parse().expect("number"))
        .collect();
    let [specialised, generic, ratio] = cells[..] else {
        panic!("three numbers: {spec}")
    };
    // The ratio is specialised / generic, to the table's rounding (each
    // figure to 0.005).
    let exact = specialised / generic;
    let rounding = 0.005 + exact * (0.005 / specialised + 0.005 / generic);
    assert!(
        (ratio - exact).abs() <= rounding,
        "ratio {ratio} vs {specialised} / {generic} = {exact:.4}: {spec}"
    );
    // Both programs trace the same paths (the same image: tests/opencl.rs),
    // so neither can be several times the other on any device.
    assert!((0.25..4.0).contains(&ratio), "{spec}");
    // The CSV holds the unrounded rates behind the table.
    let csv = csv_rows(&out_dir.path().join("specialisation.csv"));
    let col = |name: &str| {
        csv[0]
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name} in {:?}", csv[0]))
    };
    let rate = |name: &str| csv[1][col(name)].parse::<f64>().expect("number") / 1e6;
    let (s, g) = (
        rate("specialised_paths_per_sec"),
        rate("generic_paths_per_sec"),
    );
    assert!(
        (s - specialised).abs() <= 0.005 + 1e-9 && (g - generic).abs() <= 0.005 + 1e-9,
        "CSV {s} {g} vs table {spec}"
    );
    assert!(
        (s / g - ratio).abs() <= 0.005 + 1e-9,
        "CSV ratio {} vs table {ratio}",
        s / g
    );
}

#[test]
fn the_devices_section_measures_each_backend_alone_and_all_at_once() {
    if pathstream::render::backend::opencl::OpenClBackend::new(None).is_err()
        && std::env::var_os("CI").is_none()
    {
        return; // no second device to split with
    }
    let out_dir = tempfile::tempdir().expect("tempdir");
    let out = pathstream(&[
        "bench",
        "--quick",
        "--backend",
        "cpu",
        "--backend",
        "opencl",
        "--sections",
        "devices",
        "--scenes",
        "cornell",
        "--out",
        path(out_dir.path()),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let md = text(&out.stdout);
    assert!(md.contains("## Every device at once"), "{md}");
    let rows = csv_rows(&out_dir.path().join("devices.csv"));
    assert_eq!(
        rows[0][3..],
        [
            "backend",
            "device",
            "alone_paths_per_sec",
            "together_paths_per_sec",
            "split_paths"
        ]
    );
    let kinds: Vec<&str> = rows[1..].iter().map(|r| r[3].as_str()).collect();
    assert_eq!(
        kinds,
        [
            "cpu",
            "opencl",
            "all",
            "split-fastest",
            "cpu",
            "opencl",
            "all",
            "split-fastest"
        ],
        "2 sizes"
    );
    let num = |r: &Vec<String>, i: usize| r[i].parse::<f64>().expect("number");
    let count = |r: &Vec<String>| r[7].parse::<u64>().expect("path count");
    for size in rows[1..].chunks(4) {
        assert!(
            size.iter().all(|r| num(r, 5) > 0.0 && num(r, 6) > 0.0),
            "{size:?}"
        );
        // Measured, not defined: each device took blocks of the split, and
        // the paths the devices say they rendered are the paths the film
        // holds once merged (a block lost, merged twice or miscounted
        // breaks the equality), in whole samples per pixel.
        let side = |i: usize| size[0][i].parse::<u64>().expect("image size");
        let pixels = side(1) * side(2);
        let (cpu, opencl, film) = (count(&size[0]), count(&size[1]), count(&size[2]));
        assert!(cpu > 0 && opencl > 0, "every device took part: {size:?}");
        assert_eq!(
            cpu + opencl,
            film,
            "the devices' paths are the film's: {size:?}"
        );
        assert_eq!(film % pixels, 0, "whole samples: {size:?}");
        let one = count(&size[3]);
        assert!(one > 0 && one % pixels == 0, "{size:?}");
    }
}
