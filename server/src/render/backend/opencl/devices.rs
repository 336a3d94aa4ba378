//! OpenCL platforms and devices: what is there, and which one `auto` takes.

use opencl3::device::{
    Device, CL_DEVICE_TYPE_ACCELERATOR, CL_DEVICE_TYPE_ALL, CL_DEVICE_TYPE_CPU, CL_DEVICE_TYPE_GPU,
    CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT,
};
use opencl3::platform::get_platforms;
use serde::Serialize;
use std::sync::OnceLock;

/// One OpenCL device, numbered across all platforms (`--device N`).
#[derive(Clone, Debug, Serialize)]
pub struct DeviceInfo {
    pub index: usize,
    pub platform: String,
    pub name: String,
    pub vendor: String,
    /// `gpu`, `cpu`, `accelerator` or `other`.
    pub kind: &'static str,
    pub compute_units: u32,
    pub global_mem_bytes: u64,
    /// Largest single buffer the device allocates.
    pub max_alloc_bytes: u64,
    pub fp64: bool,
    pub opencl_c_version: String,
    /// Single-precision division and sqrt can be built correctly rounded
    /// (`-cl-fp32-correctly-rounded-divide-sqrt`), as on the CPU.
    #[serde(skip)]
    pub correctly_rounded_divide_sqrt: bool,
    #[serde(skip)]
    pub device: Device,
}

impl DeviceInfo {
    /// One line for listings and logs.
    pub fn describe(&self) -> String {
        format!(
            "{} ({}, {}, {} compute units, {:.1} GiB, fp64 {}, {}, platform {})",
            self.name.trim(),
            self.vendor.trim(),
            self.kind,
            self.compute_units,
            self.global_mem_bytes as f64 / (1u64 << 30) as f64,
            if self.fp64 { "yes" } else { "no" },
            self.opencl_c_version.trim(),
            self.platform.trim()
        )
    }
}

/// Every OpenCL device, or why there are none (no loader, no platform).
/// Enumerated once per process: some drivers (PoCL 5) crash when two threads
/// initialise the platform at once, and devices do not come and go.
pub fn list() -> Result<Vec<DeviceInfo>, String> {
    static DEVICES: OnceLock<Result<Vec<DeviceInfo>, String>> = OnceLock::new();
    DEVICES.get_or_init(enumerate).clone()
}

fn enumerate() -> Result<Vec<DeviceInfo>, String> {
    let platforms = get_platforms().map_err(|e| {
        if e.0 == -2000 {
            "no OpenCL loader (libOpenCL.so.1) found".to_owned()
        } else if e.0 == -1001 {
            "no OpenCL platform found (CL_PLATFORM_NOT_FOUND_KHR)".to_owned()
        } else {
            format!("cannot list OpenCL platforms: {e}")
        }
    })?;
    let mut out = Vec::new();
    for platform in platforms {
        let platform_name = platform
            .name()
            .unwrap_or_else(|_| "unknown platform".into());
        let Ok(ids) = platform.get_devices(CL_DEVICE_TYPE_ALL) else {
            continue;
        };
        for id in ids {
            let d = Device::new(id);
            let ty = d.dev_type().unwrap_or(0);
            let kind = if ty & CL_DEVICE_TYPE_GPU != 0 {
                "gpu"
            } else if ty & CL_DEVICE_TYPE_CPU != 0 {
                "cpu"
            } else if ty & CL_DEVICE_TYPE_ACCELERATOR != 0 {
                "accelerator"
            } else {
                "other"
            };
            out.push(DeviceInfo {
                index: out.len(),
                platform: platform_name.clone(),
                name: d.name().unwrap_or_default(),
                vendor: d.vendor().unwrap_or_default(),
                kind,
                compute_units: d.max_compute_units().unwrap_or(0),
                global_mem_bytes: d.global_mem_size().unwrap_or(0),
                max_alloc_bytes: d.max_mem_alloc_size().unwrap_or(0),
                correctly_rounded_divide_sqrt: d
                    .single_fp_config()
                    .map(|c| c & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT != 0)
                    .unwrap_or(false),
                fp64: d.double_fp_config().map(|c| c != 0).unwrap_or(false)
                    || d.extensions()
                        .map(|e| e.contains("cl_khr_fp64"))
                        .unwrap_or(false),
                opencl_c_version: d.opencl_c_version().unwrap_or_default(),
                device: d,
            });
        }
    }
    if out.is_empty() {
        return Err("OpenCL platforms were found but they have no devices".into());
    }
    Ok(out)
}

/// What `auto` takes: the GPU with the most compute units, if any.
pub fn auto_pick(devices: &[DeviceInfo]) -> Option<&DeviceInfo> {
    devices
        .iter()
        .filter(|d| d.kind == "gpu")
        .max_by_key(|d| d.compute_units)
}
