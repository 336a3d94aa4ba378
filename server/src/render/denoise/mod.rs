//! Denoising with Intel Open Image Denoise (OIDN 2.x), loaded at run time
//! as OpenCL is: `PATHSTREAM_OIDN` names the library file or a folder
//! holding it; else `libOpenImageDenoise.so.2` is looked up on the
//! system's library path. Without it everything else works, and
//! [`status`] says why denoising does not.
//!
//! The library is loaded and a device started once, on first use; one
//! image is denoised at a time (OIDN spreads one image over every core of
//! its device). A filter is kept per image size and quality, as making one
//! costs more than running it on a small image.
//!
//! The device: `PATHSTREAM_OIDN_DEVICE` names one by kind (`cpu`, `cuda`)
//! or by its number in the library's list; otherwise a CUDA GPU where the
//! library lists one, else the CPU.

mod oidn;

pub use oidn::FilterQuality;

use crate::render::envmap::spectrum::luminance;
use crate::render::features::Features;
use pathstream_wire::{Denoiser as DenoiserInfo, DenoiserDevice};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// The share of the time that streamed frames' denoising may take (see
/// [`next_turn`]): on a CPU denoiser, what it takes the renderer loses.
pub const STREAM_SHARE: f64 = 0.25;

/// The library's file name on Linux (OIDN 2.x).
pub const LIBRARY: &str = "libOpenImageDenoise.so.2";
/// Filters kept (each holds its buffers: 48 bytes per pixel).
const FILTERS_KEPT: usize = 3;

/// What to do where there is no denoiser: the start of every refusal.
pub const INSTALL_HINT: &str = "install Open Image Denoise 2.x (its \
    libOpenImageDenoise.so.2 on the library path, or PATHSTREAM_OIDN naming the \
    file or its folder; `pip download pyoidn` has it in pyoidn/oidn/lib)";

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DenoiseError {
    /// No usable library or device: what is wrong and what to install.
    #[error("denoising is unavailable: {0}")]
    Unavailable(String),
    /// The library failed on this image.
    #[error("denoising failed: {0}")]
    Failed(String),
}

type FilterKey = (u32, u32, bool, FilterQuality);

/// A started device and its filters (dropped before the device).
struct Denoiser {
    filters: Vec<(FilterKey, oidn::Filter)>,
    device: oidn::Device,
}

struct State {
    info: DenoiserInfo,
    denoiser: Option<Mutex<Denoiser>>,
}

fn state() -> &'static State {
    static STATE: OnceLock<State> = OnceLock::new();
    STATE.get_or_init(|| {
        let state = start();
        match &state.info.reason {
            Some(why) => tracing::info!("denoising unavailable: {why}"),
            None => tracing::info!(
                library = state.info.library.as_deref().unwrap_or(""),
                version = state.info.version.as_deref().unwrap_or(""),
                device = ?state.info.device.and_then(|i| state.info.devices.get(i)).map(|d| &d.name),
                "denoising with Open Image Denoise"
            ),
        }
        state
    })
}

/// Where to look for the library, in order.
fn candidates() -> Vec<PathBuf> {
    match std::env::var_os("PATHSTREAM_OIDN").filter(|v| !v.is_empty()) {
        Some(p) => {
            let p = PathBuf::from(p);
            if p.is_dir() {
                vec![p.join(LIBRARY), p.join("lib").join(LIBRARY)]
            } else {
                vec![p]
            }
        }
        None => vec![PathBuf::from(LIBRARY)],
    }
}

/// Loads the library and starts its device, or says why not.
fn start() -> State {
    let unavailable = |reason: String| State {
        info: DenoiserInfo {
            reason: Some(reason),
            ..DenoiserInfo::default()
        },
        denoiser: None,
    };
    let mut tried = Vec::new();
    let mut loaded = None;
    for path in candidates() {
        match oidn::Library::load(&path) {
            Ok(lib) => {
                loaded = Some(lib);
                break;
            }
            Err(e) => tried.push(e),
        }
    }
    let Some(lib) = loaded.map(Arc::new) else {
        return unavailable(format!("{}; {INSTALL_HINT}", tried.join("; ")));
    };
    let listed = lib.physical_devices();
    let devices: Vec<DenoiserDevice> = listed
        .iter()
        .map(|d| DenoiserDevice {
            index: d.index,
            kind: d.kind.to_owned(),
            name: d.name.clone(),
        })
        .collect();
    let library = Some(lib.path.display().to_string());
    let with = |reason: String| State {
        info: DenoiserInfo {
            reason: Some(reason),
            library: library.clone(),
            devices: devices.clone(),
            ..DenoiserInfo::default()
        },
        denoiser: None,
    };
    let wanted = std::env::var("PATHSTREAM_OIDN_DEVICE").ok();
    let Some(index) = pick(&devices, wanted.as_deref()) else {
        return with(match wanted {
            Some(w) => format!("PATHSTREAM_OIDN_DEVICE={w} names no device the library lists"),
            None => "the library lists no device".into(),
        });
    };
    match lib.device(index) {
        Ok(device) => State {
            info: DenoiserInfo {
                available: true,
                reason: None,
                library,
                version: Some(device.version()),
                device: Some(index),
                devices,
            },
            denoiser: Some(Mutex::new(Denoiser {
                filters: Vec::new(),
                device,
            })),
        },
        Err(e) => with(format!("device {index} did not start: {e}")),
    }
}

/// The device to denoise on: the one `wanted` names (a kind or a number),
/// else the first CUDA device, else the first CPU, else the first.
fn pick(devices: &[DenoiserDevice], wanted: Option<&str>) -> Option<usize> {
    let of_kind = |k: &str| devices.iter().find(|d| d.kind == k).map(|d| d.index);
    match wanted.map(str::trim).filter(|w| !w.is_empty()) {
        Some(w) => match w.parse::<usize>() {
            Ok(i) => devices.iter().find(|d| d.index == i).map(|d| d.index),
            Err(_) => of_kind(&w.to_ascii_lowercase()),
        },
        None => of_kind("cuda")
            .or_else(|| of_kind("cpu"))
            .or_else(|| devices.first().map(|d| d.index)),
    }
}

/// What `/api/devices` says of the denoiser (loads it on first call).
pub fn status() -> DenoiserInfo {
    state().info.clone()
}

/// Ok where images can be denoised; else why not, naming what to install.
pub fn available() -> Result<(), DenoiseError> {
    match &state().info.reason {
        None => Ok(()),
        Some(why) => Err(DenoiseError::Unavailable(why.clone())),
    }
}

/// `color` (width x height, row-major) denoised, guided by `features`
/// where given (of the same size).
pub fn denoise(
    width: u32,
    height: u32,
    color: &[[f32; 3]],
    features: Option<&Features>,
    quality: FilterQuality,
) -> Result<Vec<[f32; 3]>, DenoiseError> {
    let pixels = width as usize * height as usize;
    if color.len() != pixels {
        return Err(DenoiseError::Failed(format!(
            "{} pixels for a {width}x{height} image",
            color.len()
        )));
    }
    let features = features.filter(|f| (f.width, f.height) == (width, height));
    let Some(denoiser) = &state().denoiser else {
        available()?;
        return Err(DenoiseError::Unavailable(INSTALL_HINT.into()));
    };
    let mut d = denoiser.lock().unwrap_or_else(|e| e.into_inner());
    let key = (width, height, features.is_some(), quality);
    let at = match d.filters.iter().position(|(k, _)| *k == key) {
        Some(i) => i,
        None => {
            let f = (d.device)
                .filter(width as usize, height as usize, key.2, quality)
                .map_err(DenoiseError::Failed)?;
            if d.filters.len() >= FILTERS_KEPT {
                d.filters.remove(0);
            }
            d.filters.push((key, f));
            d.filters.len() - 1
        }
    };
    // The most recently used last: the oldest goes first.
    let entry = d.filters.remove(at);
    d.filters.push(entry);
    let filter = &d.filters[d.filters.len() - 1].1;
    let mut out = vec![[0f32; 3]; pixels];
    let guides = features.map(|f| (&f.albedo[..], &f.normal[..]));
    let started = Instant::now();
    let ran = filter.run(color, guides, &mut out);
    *last_run().lock().unwrap_or_else(|e| e.into_inner()) = Some((started, Instant::now()));
    ran.map_err(DenoiseError::Failed)?;
    match check(color, &out) {
        Check::Fine => {}
        Check::NonFinite(i) => {
            return Err(DenoiseError::Failed(format!(
                "the denoiser returned a non-finite pixel ({i} of {pixels})"
            )))
        }
        // Kept (the denoiser spreads fireflies' energy, which can move a
        // mean), but said: a black or washed-out denoised frame should
        // leave a trace of what went in.
        Check::Far { input, output } if now_and_then() => {
            let (albedo, normal) = features.map_or((None, None), |f| {
                (Some(mean_of(&f.albedo)), Some(mean_of(&f.normal)))
            });
            tracing::warn!(
                width,
                height,
                ?quality,
                input,
                output,
                ?albedo,
                ?normal,
                "a denoised image's mean luminance is far from its input's"
            );
        }
        Check::Far { .. } => {}
    }
    Ok(out)
}

/// True at most once a minute: a stream denoises several frames a second,
/// and one warning says what each would.
fn now_and_then() -> bool {
    static LAST: Mutex<Option<Instant>> = Mutex::new(None);
    let mut last = LAST.lock().unwrap_or_else(|e| e.into_inner());
    let due = last.is_none_or(|t| t.elapsed() >= Duration::from_secs(60));
    if due {
        *last = Some(Instant::now());
    }
    due
}

/// What a denoised image says of the denoiser's run.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Check {
    Fine,
    /// Pixel `.0` is NaN or infinite (the frame goes out as rendered).
    NonFinite(usize),
    /// The mean luminance moved by more than a factor of [`FAR`].
    Far {
        input: f64,
        output: f64,
    },
}

/// How far a denoised image's mean luminance may move from its input's
/// before it is reported: the denoiser keeps a mean within a percent or
/// two, unless fireflies dominate the image.
const FAR: f64 = 2.0;

/// Checks `out`, the denoised `color`.
fn check(color: &[[f32; 3]], out: &[[f32; 3]]) -> Check {
    if let Some(i) = out.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Check::NonFinite(i);
    }
    // Luminance is linear: the mean's is the mean luminance.
    let (input, output) = (luminance(mean_of(color)), luminance(mean_of(out)));
    let finite_input = input.is_finite() && input > 0.0;
    if finite_input && !(output <= input * FAR && output >= input / FAR) {
        return Check::Far { input, output };
    }
    Check::Fine
}

/// Mean of each channel of an image (in f64: a sum of millions).
fn mean_of(image: &[[f32; 3]]) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for p in image {
        for (s, &c) in sum.iter_mut().zip(p) {
            *s += f64::from(c);
        }
    }
    sum.map(|s| s / image.len().max(1) as f64)
}

/// When the last image was denoised (start, end).
fn last_run() -> &'static Mutex<Option<(Instant, Instant)>> {
    static LAST: Mutex<Option<(Instant, Instant)>> = Mutex::new(None);
    &LAST
}

/// The earliest time the next streamed frame should be denoised, so that
/// denoising takes at most [`STREAM_SHARE`] of the time: the last run's
/// end plus its duration times (1 - share) / share (None: now). Streams
/// wait for it rather than denoise every frame back to back, which on a
/// 2-core machine left rendering a seventh of its rate (measured); the
/// frame endpoints, asked, denoise at once.
pub fn next_turn() -> Option<Instant> {
    let last = *last_run().lock().unwrap_or_else(|e| e.into_inner());
    let (start, end) = last?;
    let rest = (end - start).mul_f64((1.0 - STREAM_SHARE) / STREAM_SHARE);
    Some(end + rest).filter(|&t| t > Instant::now())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dev(index: usize, kind: &str) -> DenoiserDevice {
        DenoiserDevice {
            index,
            kind: kind.into(),
            name: format!("{kind} {index}"),
        }
    }

    #[test]
    fn a_denoised_image_is_checked_for_non_finite_pixels_and_a_moved_mean() {
        let color = vec![[0.5f32, 0.4, 0.3]; 64];
        let mut out = color.clone();
        out[3][1] *= 1.5;
        assert_eq!(check(&color, &out), Check::Fine);
        out[7][2] = f32::NAN;
        assert_eq!(check(&color, &out), Check::NonFinite(7));
        out[7][2] = f32::INFINITY;
        assert_eq!(check(&color, &out), Check::NonFinite(7));
        let black = vec![[0.0f32; 3]; 64];
        assert!(matches!(check(&color, &black), Check::Far { output, .. } if output == 0.0));
        let bright = vec![[2.0f32; 3]; 64];
        assert!(matches!(check(&color, &bright), Check::Far { .. }));
        // A black input has no mean to keep.
        assert_eq!(check(&black, &black), Check::Fine);
        assert_eq!(check(&black, &color), Check::Fine);
    }

    #[test]
    fn the_device_is_cuda_where_listed_else_the_cpu_unless_named() {
        let cpu_only = [dev(0, "cpu")];
        let both = [dev(0, "cpu"), dev(1, "cuda")];
        assert_eq!(pick(&cpu_only, None), Some(0));
        assert_eq!(pick(&both, None), Some(1));
        assert_eq!(pick(&both, Some("cpu")), Some(0));
        assert_eq!(pick(&both, Some("CUDA")), Some(1));
        assert_eq!(pick(&both, Some("1")), Some(1));
        assert_eq!(pick(&both, Some("7")), None);
        assert_eq!(pick(&cpu_only, Some("hip")), None);
        assert_eq!(pick(&[], None), None);
    }
}
