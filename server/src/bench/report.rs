//! The benchmark's results as Markdown tables (stdout, docs) and CSV files.

use super::cells::{pct, reach, secs};
use super::fit::{self, Reach};
use super::{thesis, Results, TradeCurve};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The error levels the trade tables give times for.
pub const LEVELS: [f64; 4] = [0.10, 0.05, 0.02, 0.01];

fn reaches(curve: &TradeCurve) -> [Reach; 4] {
    LEVELS.map(|l| fit::time_to(&curve.points, curve.fit.as_ref(), l))
}

/// The whole report as Markdown.
pub fn markdown(r: &Results) -> String {
    let mut out = String::new();
    let w = &mut out;
    let _ = writeln!(w, "# pathstream bench\n");
    let _ = writeln!(w, "- Machine: {}", r.machine);
    for (name, device) in &r.backends {
        let _ = writeln!(w, "- Backend `{name}`: {device}");
    }
    let _ = writeln!(w, "- Date: {}; renderer {}\n", r.date, r.renderer_version);
    throughput(w, r);
    trade(w, r);
    super::adaptive::markdown(w, r);
    super::samplers::markdown(w, r);
    super::mis::markdown(w, r);
    super::sky::markdown(w, r);
    calibration(w, r);
    specialisation(w, r);
    meshes(w, r);
    devices(w, r);
    out
}

fn devices(w: &mut String, r: &Results) {
    if r.devices.is_empty() {
        return;
    }
    let _ = writeln!(w, "## Every device at once\n");
    let _ = writeln!(
        w,
        "Each backend alone, then all of them on one render (`--backend all`: blocks of samples sized to each \
         device's speed, merged in sample order). Alone: paths/s rendering by itself. Together: the paths/s it \
         added to the shared render. All: the shared render's paths/s against the sum of the rates alone. Fastest alone, split: \
         that device rendering alone through the same blocks and merges (what they cost). Devices that share processors (PoCL and rayon on the same cores) compete for them: the sum is not \
         reachable there.\n"
    );
    let _ = writeln!(
        w,
        "| scene | size | device | alone M paths/s | together M paths/s |"
    );
    let _ = writeln!(w, "| --- | --- | --- | ---: | ---: |");
    for row in &r.devices {
        for d in &row.devices {
            let _ = writeln!(
                w,
                "| {} | {}x{} | {} | {:.2} | {:.2} |",
                row.scene,
                row.size.0,
                row.size.1,
                d.backend,
                d.alone / 1e6,
                d.together / 1e6
            );
        }
        let _ = writeln!(
            w,
            "| {} | {}x{} | **all** | {:.2} (sum) | **{:.2}** ({:.0}% of the sum, {:.2}x the fastest alone) |",
            row.scene,
            row.size.0,
            row.size.1,
            row.ideal() / 1e6,
            row.combined / 1e6,
            100.0 * row.combined / row.ideal().max(1e-9),
            row.combined / row.fastest().max(1e-9)
        );
        let _ = writeln!(
            w,
            "| {} | {}x{} | fastest alone, split | {:.2} | {:.2} ({:.0}%) |",
            row.scene,
            row.size.0,
            row.size.1,
            row.fastest() / 1e6,
            row.split_fastest / 1e6,
            100.0 * row.split_fastest / row.fastest().max(1e-9)
        );
    }
    let _ = writeln!(w);
}

fn meshes(w: &mut String, r: &Results) {
    if r.meshes.is_empty() {
        return;
    }
    let _ = writeln!(w, "## Meshes\n");
    let _ = writeln!(
        w,
        "A closed bumpy sphere of N triangles, framed; camera rays through the centres of 512x512 pixels, one \
         cosine-distributed bounce ray from each hit; paths: 256x256, max depth 4, NEE on, uniform sky. Build: \
         loading the mesh, checks and the BVH. Rays: on the CPU. OpenCL: the same paths on the first OpenCL \
         backend, the time to pack and upload the scene and film to it, and the device memory they take.\n"
    );
    let _ = writeln!(w, "| triangles | build | memory | BVH nodes | depth | camera M rays/s | bounce M rays/s | CPU M paths/s | OpenCL M paths/s | OpenCL upload | device memory |");
    let _ = writeln!(
        w,
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for m in &r.meshes {
        let _ = writeln!(
            w,
            "| {} | {} | {:.1} MiB | {} | {} | {:.2} | {:.2} | {:.2} | {} | {} | {} |",
            m.triangles,
            secs(m.build_seconds),
            m.memory_bytes as f64 / (1 << 20) as f64,
            m.bvh_nodes,
            m.bvh_depth,
            m.camera_rays_per_sec / 1e6,
            m.bounce_rays_per_sec / 1e6,
            m.paths_per_sec / 1e6,
            m.opencl_paths_per_sec
                .map_or("-".into(), |p| format!("{:.2}", p / 1e6)),
            m.opencl_upload_seconds.map_or("-".into(), secs),
            m.opencl_device_bytes.map_or("-".into(), |b| format!(
                "{:.1} MiB",
                b as f64 / (1 << 20) as f64
            ))
        );
    }
    let _ = writeln!(w);
}

fn throughput(w: &mut String, r: &Results) {
    if r.throughput.is_empty() {
        return;
    }
    let _ = writeln!(w, "## Throughput\n");
    let _ = writeln!(w, "Max depth 6, NEE on, tent filter (the thesis's settings). Thesis: 2016, AMD FX-6300 (OpenMP) and NVIDIA GTX 970 (OpenCL).\n");
    let _ = writeln!(
        w,
        "| backend | scene | size | spp/s | M paths/s | thesis CPU spp/s | thesis GPU spp/s |"
    );
    let _ = writeln!(w, "| --- | --- | --- | ---: | ---: | ---: | ---: |");
    for row in &r.throughput {
        let t = thesis::figure(&row.scene, row.size.0, row.size.1);
        let _ = writeln!(
            w,
            "| {} | {} | {}x{} | {:.2} | {:.2} | {} | {} |",
            row.backend,
            row.scene,
            row.size.0,
            row.size.1,
            row.result.spp_per_sec,
            row.result.paths_per_sec / 1e6,
            t.map_or("-".into(), |t| format!("{:.2}", t.cpu_spp_per_sec)),
            t.map_or("-".into(), |t| format!("{:.2}", t.gpu_spp_per_sec)),
        );
    }
    let _ = writeln!(w);
}

fn trade(w: &mut String, r: &Results) {
    let (tw, th) = r.trade_size;
    let mut groups: Vec<(&str, &str)> = r
        .trade
        .iter()
        .map(|c| (c.scene.as_str(), c.backend.as_str()))
        .collect();
    groups.dedup();
    for (scene, backend) in groups {
        let _ = writeln!(
            w,
            "## Speed/accuracy trade: `{scene}`, {tw}x{th}, {backend}\n"
        );
        let reference = r.references.iter().find(|(i, _)| i.scene == scene);
        let reference_error = reference.map_or(0.0, |(i, _)| i.error_estimate);
        if let Some((info, cached)) = reference {
            let _ = writeln!(
                w,
                "Reference: unbounded, NEE, no clamp; {} spp in {} on {}, error estimate {}{}. Times are rendering time at {tw}x{th}; they scale with the pixel count. `~` marks a time extrapolated from the fit (err^2 = bias^2 + c^2/t), `never` a bias floor above the level (`never?`: the fitted floor is above it but within the run's noise); a bias floor `< x` is too small for this run to tell from noise.\n",
                info.spp,
                secs(info.seconds),
                info.backend,
                pct(info.error_estimate),
                if *cached { " (cached)" } else { "" }
            );
        }
        let _ = writeln!(w, "| setting | M paths/s | to 10% | to 5% | to 2% | to 1% | bias floor | error x sqrt(s) |");
        let _ = writeln!(
            w,
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        );
        for c in r
            .trade
            .iter()
            .filter(|c| c.scene == scene && c.backend == backend)
        {
            let end = c.points.last().map_or(0.0, |p| p.seconds);
            // "never" stands only where the run resolves the bias floor.
            let resolved = c
                .fit
                .is_some_and(|f| fit::resolved_bias(&f, end, reference_error).is_ok());
            let [a, b, cc, d] = reaches(c).map(|r| match r {
                Reach::Never if !resolved => "never?".to_owned(),
                r => reach(r),
            });
            let (bias, var) = c.fit.map_or(("?".into(), "?".into()), |f| {
                let bias = match fit::resolved_bias(&f, end, reference_error) {
                    Ok(b) => pct(b),
                    Err(bound) => format!("< {}", pct(bound)),
                };
                (bias, pct(f.variance_constant))
            });
            let _ = writeln!(
                w,
                "| {} | {:.2} | {a} | {b} | {cc} | {d} | {bias} | {var} |",
                c.setting.label,
                c.paths_per_sec(r.trade_size) / 1e6
            );
        }
        let _ = writeln!(w);
    }
}

fn calibration(w: &mut String, r: &Results) {
    if r.calibration.is_empty() {
        return;
    }
    let _ = writeln!(w, "## Calibration of the error estimate\n");
    let _ = writeln!(w, "Estimated / true relative RMS error of the unbiased setting, at every checkpoint with at least 8 spp and an error above twice the reference's.\n");
    let _ = writeln!(w, "| backend | scene | checkpoints | median | min | max |");
    let _ = writeln!(w, "| --- | --- | ---: | ---: | ---: | ---: |");
    for row in &r.calibration {
        match row.calibration {
            Some(c) => {
                let _ = writeln!(
                    w,
                    "| {} | {} | {} | {:.3} | {:.3} | {:.3} |",
                    row.backend, row.scene, c.points, c.median, c.min, c.max
                );
            }
            None => {
                let _ = writeln!(w, "| {} | {} | 0 | - | - | - |", row.backend, row.scene);
            }
        }
    }
    let _ = writeln!(w);
}

fn specialisation(w: &mut String, r: &Results) {
    if r.specialisation.is_empty() {
        return;
    }
    let _ = writeln!(w, "## OpenCL: scene-specialised vs generic program\n");
    let _ = writeln!(
        w,
        "| device | scene | size | specialised M paths/s | generic M paths/s | ratio |"
    );
    let _ = writeln!(w, "| --- | --- | --- | ---: | ---: | ---: |");
    for row in &r.specialisation {
        let (s, g) = (row.specialised.paths_per_sec, row.generic.paths_per_sec);
        let _ = writeln!(
            w,
            "| {} | {} | {}x{} | {:.2} | {:.2} | {:.2} |",
            row.device.split(" (").next().unwrap_or(&row.device),
            row.scene,
            row.size.0,
            row.size.1,
            s / 1e6,
            g / 1e6,
            if g > 0.0 { s / g } else { f64::NAN }
        );
    }
    let _ = writeln!(w);
}

#[derive(Serialize)]
struct ThroughputCsv<'a> {
    backend: &'a str,
    device: &'a str,
    scene: &'a str,
    width: u32,
    height: u32,
    spp: u64,
    seconds: f64,
    paths_per_sec: f64,
    spp_per_sec: f64,
    thesis_cpu_spp_per_sec: Option<f64>,
    thesis_gpu_spp_per_sec: Option<f64>,
}

#[derive(Serialize)]
struct PointCsv<'a> {
    backend: &'a str,
    scene: &'a str,
    setting: &'a str,
    seconds: f64,
    spp: u64,
    true_error: f64,
    estimate: Option<f64>,
}

#[derive(Serialize)]
struct TradeCsv<'a> {
    backend: &'a str,
    scene: &'a str,
    setting: &'a str,
    quality: String,
    paths_per_sec: f64,
    seconds_to_10pct: Option<f64>,
    seconds_to_5pct: Option<f64>,
    seconds_to_2pct: Option<f64>,
    seconds_to_1pct: Option<f64>,
    bias_floor: Option<f64>,
    variance_constant: Option<f64>,
}

#[derive(Serialize)]
struct SpecialisationCsv<'a> {
    device: &'a str,
    scene: &'a str,
    width: u32,
    height: u32,
    specialised_paths_per_sec: f64,
    generic_paths_per_sec: f64,
}

fn write_rows<T: Serialize>(
    path: PathBuf,
    rows: impl IntoIterator<Item = T>,
) -> std::io::Result<PathBuf> {
    let mut w = csv::Writer::from_path(&path)?;
    for row in rows {
        w.serialize(row)?;
    }
    w.flush()?;
    Ok(path)
}

/// Writes the CSV files into `dir`; returns their paths.
pub fn write_csv(r: &Results, dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    if !r.meshes.is_empty() {
        files.push(write_rows(dir.join("meshes.csv"), &r.meshes)?);
    }
    if !r.devices.is_empty() {
        files.push(write_rows(
            dir.join("devices.csv"),
            r.devices.iter().flat_map(|d| d.csv()),
        )?);
    }
    if !r.throughput.is_empty() {
        files.push(write_rows(
            dir.join("throughput.csv"),
            r.throughput.iter().map(|t| {
                let th = thesis::figure(&t.scene, t.size.0, t.size.1);
                ThroughputCsv {
                    backend: &t.backend,
                    device: &t.device,
                    scene: &t.scene,
                    width: t.size.0,
                    height: t.size.1,
                    spp: t.result.spp,
                    seconds: t.result.seconds,
                    paths_per_sec: t.result.paths_per_sec,
                    spp_per_sec: t.result.spp_per_sec,
                    thesis_cpu_spp_per_sec: th.map(|f| f.cpu_spp_per_sec),
                    thesis_gpu_spp_per_sec: th.map(|f| f.gpu_spp_per_sec),
                }
            }),
        )?);
    }
    let curves = r.trade.iter();
    let points = curves.clone().flat_map(|c| {
        c.points.iter().map(move |p| PointCsv {
            backend: &c.backend,
            scene: &c.scene,
            setting: &c.setting.label,
            seconds: p.seconds,
            spp: p.spp,
            true_error: p.true_error,
            estimate: p.estimate,
        })
    });
    let calib_points = r.calibration.iter().flat_map(|c| {
        c.points.iter().map(move |p| PointCsv {
            backend: &c.backend,
            scene: &c.scene,
            setting: "unbiased (calibration)",
            seconds: p.seconds,
            spp: p.spp,
            true_error: p.true_error,
            estimate: p.estimate,
        })
    });
    if !r.trade.is_empty() {
        files.push(write_rows(dir.join("trade_points.csv"), points)?);
        files.push(write_rows(
            dir.join("trade.csv"),
            curves.map(|c| {
                let [a, b, cc, d] = reaches(c).map(|x| x.seconds());
                TradeCsv {
                    backend: &c.backend,
                    scene: &c.scene,
                    setting: &c.setting.label,
                    quality: serde_json::to_string(&c.setting.quality).unwrap_or_default(),
                    paths_per_sec: c.paths_per_sec(r.trade_size),
                    seconds_to_10pct: a,
                    seconds_to_5pct: b,
                    seconds_to_2pct: cc,
                    seconds_to_1pct: d,
                    bias_floor: c.fit.map(|f| f.bias),
                    variance_constant: c.fit.map(|f| f.variance_constant),
                }
            }),
        )?);
    }
    if !r.calibration.is_empty() {
        files.push(write_rows(
            dir.join("calibration_points.csv"),
            calib_points,
        )?);
    }
    if !r.specialisation.is_empty() {
        files.push(write_rows(
            dir.join("specialisation.csv"),
            r.specialisation.iter().map(|s| SpecialisationCsv {
                device: &s.device,
                scene: &s.scene,
                width: s.size.0,
                height: s.size.1,
                specialised_paths_per_sec: s.specialised.paths_per_sec,
                generic_paths_per_sec: s.generic.paths_per_sec,
            }),
        )?);
    }
    Ok(files)
}
