//! PNG plots of the benchmark with `plotters`: error against time per
//! setting (log-log), and the error estimate's calibration over time. Text
//! is drawn with an embedded DejaVu Sans (assets/, Bitstream Vera licence),
//! so plotting needs no system fonts.

use super::fit::calibration_points;
use super::meshes::MeshRow;
use super::report::LEVELS;
use super::{CalibrationRow, Results, TradeCurve};
use crate::render::progressive::MIN_SPP_FOR_TARGET_ERROR;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");
/// Size of every plot, in pixels.
pub const SIZE: (u32, u32) = (1200, 720);
/// Width of the legend panel right of the chart.
const LEGEND_WIDTH: u32 = 340;
/// Line colours (Tableau 10, then darker ones); later lines reuse them.
const COLOURS: [RGBColor; 18] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
    RGBColor(0, 0, 0),
    RGBColor(255, 200, 0),
    RGBColor(0, 0, 128),
    RGBColor(128, 0, 0),
    RGBColor(0, 110, 110),
    RGBColor(90, 0, 140),
    RGBColor(90, 130, 0),
    RGBColor(200, 80, 140),
];

/// A percentage axis label with as many decimals as it needs.
fn percent_label(v: &f64) -> String {
    let p = v * 100.0;
    match p {
        p if p >= 1.0 => format!("{p:.0}%"),
        p if p >= 0.1 => format!("{p:.1}%"),
        p => format!("{p:.2}%"),
    }
}

/// Lines' labels and colours in a panel of their own, so no line is hidden.
fn legend(
    area: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    entries: &[(String, RGBColor)],
) -> Result<(), String> {
    let font = ("sans-serif", 15).into_font().color(&BLACK);
    for (i, (label, colour)) in entries.iter().enumerate() {
        let y = 70 + 24 * i as i32;
        area.draw(&PathElement::new([(6, y), (34, y)], colour.stroke_width(3)))
            .map_err(|e| e.to_string())?;
        area.draw(&Text::new(label.clone(), (42, y - 8), font.clone()))
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// A plot that could not be drawn or written.
#[derive(Debug, thiserror::Error)]
#[error("plot {path}: {reason}")]
pub struct PlotError {
    pub path: PathBuf,
    pub reason: String,
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is part of the binary; it parses or the build is broken.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Draws with `draw` into an RGB buffer and writes it as PNG at `path`.
fn png(
    path: &Path,
    draw: impl FnOnce(DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<(), PlotError> {
    register_font();
    let fail = |reason: String| PlotError {
        path: path.to_owned(),
        reason,
    };
    let mut buf = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut buf, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
        draw(root.clone()).map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    image::save_buffer_with_format(
        path,
        &buf,
        SIZE.0,
        SIZE.1,
        image::ExtendedColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| fail(e.to_string()))
}

/// Smallest and largest of `values` (positive, finite), widened a little.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo < hi) {
        return 1e-3..1.0;
    }
    lo / 1.2..hi * 1.2
}

/// Tick values 1, 2 and 5 times the powers of ten inside `range`.
fn log_ticks(range: &std::ops::Range<f64>) -> Vec<f64> {
    let first = range.start.log10().floor() as i32;
    let last = range.end.log10().ceil() as i32;
    (first..=last)
        .flat_map(|p| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(p)))
        .filter(|v| range.contains(v))
        .collect()
}

/// 1500 -> "1.5k", 2e6 -> "2M".
fn si_label(v: f64) -> String {
    let (scaled, unit) = match v {
        v if v >= 1e9 => (v / 1e9, "G"),
        v if v >= 1e6 => (v / 1e6, "M"),
        v if v >= 1e3 => (v / 1e3, "k"),
        v => (v, ""),
    };
    let digits = if scaled.fract().abs() < 1e-9 { 0 } else { 1 };
    format!("{scaled:.digits$}{unit}")
}

/// Relative error against rendering time, one line per setting, with the
/// 10/5/2/1% levels dashed.
pub fn trade(path: &Path, title: &str, curves: &[&TradeCurve]) -> Result<(), PlotError> {
    let points = || curves.iter().flat_map(|c| c.points.iter());
    let x = log_range(points().map(|p| p.seconds));
    let y = log_range(points().map(|p| p.true_error).chain(LEVELS));
    png(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let (root, side) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
        let entries: Vec<(String, RGBColor)> = curves
            .iter()
            .enumerate()
            .map(|(i, c)| (c.setting.label.clone(), COLOURS[i % COLOURS.len()]))
            .collect();
        legend(&side, &entries)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x.clone().log_scale(), y.clone().log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("rendering time (s)")
            .y_desc("relative RMS error vs reference")
            .y_label_formatter(&percent_label)
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(e)?;
        for level in LEVELS {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x.start, level), (x.end, level)],
                    6,
                    6,
                    BLACK.mix(0.35).stroke_width(1),
                ))
                .map_err(e)?;
        }
        for (i, c) in curves.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let line = c
                .points
                .iter()
                .filter(|p| p.true_error > 0.0)
                .map(|p| (p.seconds, p.true_error));
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .map_err(e)?;
        }
        Ok(())
    })
}

/// Error against samples per pixel (log-log), one line per `(label,
/// points)`; `y_desc` names the error.
pub fn error_vs_spp(
    path: &Path,
    title: &str,
    y_desc: &str,
    lines: &[(String, Vec<(f64, f64)>)],
) -> Result<(), PlotError> {
    let points = || lines.iter().flat_map(|(_, p)| p.iter());
    let x = log_range(points().map(|p| p.0));
    let y = log_range(points().map(|p| p.1));
    png(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let (root, side) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
        let entries: Vec<(String, RGBColor)> = (lines.iter().enumerate())
            .map(|(i, (label, _))| (label.clone(), COLOURS[i % COLOURS.len()]))
            .collect();
        legend(&side, &entries)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 24))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(x.clone().log_scale(), y.clone().log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("samples per pixel")
            .y_desc(y_desc)
            .y_label_formatter(&percent_label)
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(e)?;
        for (i, (_, p)) in lines.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let line = p.iter().copied().filter(|p| p.1 > 0.0);
            chart
                .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))
                .map_err(e)?;
            chart
                .draw_series(line.map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(e)?;
        }
        Ok(())
    })
}

/// Estimated / true error against rendering time, one line per scene and
/// backend (the points the calibration table uses), with the ideal ratio 1
/// marked.
pub fn calibration(path: &Path, rows: &[CalibrationRow]) -> Result<(), PlotError> {
    let shown = |r: &CalibrationRow| {
        calibration_points(&r.points, r.reference_error, MIN_SPP_FOR_TARGET_ERROR)
            .collect::<Vec<_>>()
    };
    let x = log_range(
        rows.iter()
            .flat_map(|r| shown(r).into_iter().map(|(t, _)| t)),
    );
    png(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Error estimate / true error (unbiased setting)",
                ("sans-serif", 24),
            )
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(x.clone().log_scale(), 0.0..2.5f64)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("rendering time (s)")
            .y_desc("estimate / true")
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(e)?;
        chart
            .draw_series(DashedLineSeries::new(
                [(x.start, 1.0), (x.end, 1.0)],
                6,
                6,
                BLACK.mix(0.5).stroke_width(1),
            ))
            .map_err(e)?;
        for (i, row) in rows.iter().enumerate() {
            let colour = COLOURS[i % COLOURS.len()];
            let line = shown(row).into_iter().map(|(t, r)| (t, r.min(2.5)));
            chart
                .draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .map_err(e)?
                .label(format!("{} ({})", row.scene, row.backend))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 24, y)], colour.stroke_width(3))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font(("sans-serif", 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.5))
            .draw()
            .map_err(e)?;
        Ok(())
    })
}

/// Rays and paths per second against the mesh's triangle count (log-log).
pub fn meshes(path: &Path, rows: &[MeshRow]) -> Result<(), PlotError> {
    type Series = (&'static str, fn(&MeshRow) -> f64);
    let series: [Series; 3] = [
        ("camera rays/s", |m| m.camera_rays_per_sec),
        ("bounce rays/s", |m| m.bounce_rays_per_sec),
        ("paths/s", |m| m.paths_per_sec),
    ];
    let x = log_range(rows.iter().map(|m| m.triangles as f64));
    let y = log_range(
        rows.iter()
            .flat_map(|m| series.iter().map(move |(_, f)| f(m))),
    );
    png(path, |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        let (root, side) = root.split_horizontally(SIZE.0 - LEGEND_WIDTH);
        let entries: Vec<(String, RGBColor)> = series
            .iter()
            .enumerate()
            .map(|(i, (l, _))| ((*l).to_owned(), COLOURS[i]))
            .collect();
        legend(&side, &entries)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Meshes on the CPU: rays and paths per second",
                ("sans-serif", 24),
            )
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(
                x.clone().log_scale().with_key_points(log_ticks(&x)),
                y.clone().log_scale().with_key_points(log_ticks(&y)),
            )
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc("triangles")
            .y_desc("per second (all cores)")
            .x_label_formatter(&|v| si_label(*v))
            .y_label_formatter(&|v| si_label(*v))
            .label_style(("sans-serif", 15))
            .draw()
            .map_err(e)?;
        for (i, (_, f)) in series.iter().enumerate() {
            let colour = COLOURS[i];
            let points: Vec<(f64, f64)> = rows.iter().map(|m| (m.triangles as f64, f(m))).collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(3)))
                .map_err(e)?;
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 5, colour.filled())))
                .map_err(e)?;
        }
        Ok(())
    })
}

/// Writes every plot of `results` into `dir`; returns their paths.
pub fn write_all(results: &Results, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let mut files = Vec::new();
    let mut groups: Vec<(&str, &str)> = results
        .trade
        .iter()
        .map(|c| (c.scene.as_str(), c.backend.as_str()))
        .collect();
    groups.dedup();
    let (w, h) = results.trade_size;
    for (scene, backend) in groups {
        let curves: Vec<&TradeCurve> = results
            .trade
            .iter()
            .filter(|c| c.scene == scene && c.backend == backend)
            .collect();
        let path = dir.join(format!("trade-{scene}-{backend}.png"));
        trade(
            &path,
            &format!("{scene}, {w}x{h}, {backend}: error against time"),
            &curves,
        )?;
        files.push(path);
    }
    if !results.calibration.is_empty() {
        let path = dir.join("calibration.png");
        calibration(&path, &results.calibration)?;
        files.push(path);
    }
    if results.meshes.len() > 1 {
        let path = dir.join("meshes.png");
        meshes(&path, &results.meshes)?;
        files.push(path);
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_1_2_5_per_decade_inside_the_range() {
        assert_eq!(log_ticks(&(1.5e6..2.1e7)), vec![2e6, 5e6, 1e7, 2e7]);
        assert_eq!(
            log_ticks(&(9e3..4.8e6)),
            vec![1e4, 2e4, 5e4, 1e5, 2e5, 5e5, 1e6, 2e6]
        );
    }

    #[test]
    fn si_labels() {
        assert_eq!(si_label(2e6), "2M");
        assert_eq!(si_label(1500.0), "1.5k");
        assert_eq!(si_label(10_000.0), "10k");
        assert_eq!(si_label(5.0), "5");
    }
}
