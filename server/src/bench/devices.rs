//! Every device at once (`--backend all`): each of the benchmark's backends
//! alone, then all of them on one render ([`crate::render::split`]), per
//! scene and size: each device's paths/s alone and within the split, and the
//! combined rate against the sum of the rates alone (what splitting could
//! reach if the devices shared nothing); and the fastest device alone through
//! the split machinery, against its rate alone (what the machinery costs).

use super::measure;
use crate::render::split::render_split;
use crate::render::{Backend, BackendError, Film, Quality, RenderJob, Scene};
use std::time::Duration;

/// One device in one measurement.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DeviceRate {
    pub backend: String,
    pub device: String,
    /// Camera paths per second rendering alone.
    pub alone: f64,
    /// Camera paths per wall-clock second it added to the split render.
    pub together: f64,
    /// Camera paths it rendered in the split (the blocks it handed in).
    pub paths: u64,
}

/// One scene and size on every device.
#[derive(Clone, Debug, PartialEq)]
pub struct DevicesRow {
    pub scene: String,
    pub size: (u32, u32),
    pub devices: Vec<DeviceRate>,
    /// Camera paths per second of the split render.
    pub combined: f64,
    /// Camera paths the split render's film holds once merged: the
    /// devices' blocks, counted by the film, not by the devices.
    pub film_paths: u64,
    /// The fastest device alone through the split machinery (blocks,
    /// block films, merges): what the machinery itself costs.
    pub split_fastest: f64,
    /// Camera paths that render's film holds.
    pub split_fastest_paths: u64,
}

impl DevicesRow {
    /// The sum of the devices' rates alone.
    pub fn ideal(&self) -> f64 {
        self.devices.iter().map(|d| d.alone).sum()
    }

    /// The best rate alone.
    pub fn fastest(&self) -> f64 {
        self.devices.iter().map(|d| d.alone).fold(0.0, f64::max)
    }
}

/// A CSV line: one device, or `all` for the combined rate.
#[derive(serde::Serialize)]
pub struct DevicesCsv<'a> {
    pub scene: &'a str,
    pub width: u32,
    pub height: u32,
    pub backend: &'a str,
    pub device: &'a str,
    pub alone_paths_per_sec: f64,
    pub together_paths_per_sec: f64,
    /// Camera paths this device rendered in the split; for `all` and
    /// `split-fastest`, the paths the split render's film holds.
    pub split_paths: u64,
}

impl DevicesRow {
    pub fn csv(&self) -> Vec<DevicesCsv<'_>> {
        let line = |backend, device, alone, together, split_paths| DevicesCsv {
            scene: &self.scene,
            width: self.size.0,
            height: self.size.1,
            backend,
            device,
            alone_paths_per_sec: alone,
            together_paths_per_sec: together,
            split_paths,
        };
        let mut out: Vec<_> = (self.devices.iter())
            .map(|d| line(&d.backend, &d.device, d.alone, d.together, d.paths))
            .collect();
        out.push(line(
            "all",
            "every device",
            self.ideal(),
            self.combined,
            self.film_paths,
        ));
        out.push(line(
            "split-fastest",
            "the fastest device alone, through the split",
            self.fastest(),
            self.split_fastest,
            self.split_fastest_paths,
        ));
        out
    }
}

/// Measures `scene` at `size` on each backend alone for `seconds`, then on
/// all of them at once for as long.
pub fn measure(
    backends: &mut [Backend],
    name: &str,
    scene: &Scene,
    size: (u32, u32),
    seconds: f64,
) -> Result<DevicesRow, BackendError> {
    let quality = Quality::default();
    let mut devices = Vec::with_capacity(backends.len());
    for b in backends.iter_mut() {
        let alone = measure::throughput(b, scene, size, &quality, seconds)?;
        devices.push(DeviceRate {
            backend: b.name().to_owned(),
            device: b.device(),
            alone: alone.paths_per_sec,
            together: 0.0,
            paths: 0,
        });
    }
    let timed = Quality {
        time_ms: Some(Duration::from_secs_f64(seconds).as_millis().max(1) as u64),
        ..quality
    };
    let job = RenderJob::new(scene, size.0, size.1, &timed);
    let split = |backends: &mut [Backend]| {
        let mut film = Film::new(size.0, size.1);
        let (progress, shares) = render_split(&job, backends, &mut film, &timed, |_| {})?;
        Ok::<_, BackendError>((progress, shares, film.total_samples()))
    };
    let (progress, shares, film_paths) = split(backends)?;
    let wall = progress.elapsed.as_secs_f64().max(1e-9);
    for (d, s) in devices.iter_mut().zip(&shares) {
        d.together = s.samples as f64 / wall;
        d.paths = s.samples;
    }
    let fastest = (0..devices.len())
        .max_by(|&a, &b| devices[a].alone.total_cmp(&devices[b].alone))
        .unwrap_or(0);
    let (one, _, split_fastest_paths) = split(&mut backends[fastest..=fastest])?;
    Ok(DevicesRow {
        scene: name.to_owned(),
        size,
        devices,
        combined: progress.samples as f64 / wall,
        film_paths,
        split_fastest: one.samples as f64 / one.elapsed.as_secs_f64().max(1e-9),
        split_fastest_paths,
    })
}
