//! Open Image Denoise 2.x through its C API, loaded at run time (so the
//! binary starts where the library is absent): the few calls a denoiser
//! needs, each resolved by name when the library loads.
//!
//! `unsafe` is allowed statement by statement, each with a `SAFETY:`
//! comment. What the C API leaves to its caller: handles are used only
//! while alive (each is owned by one Rust value that releases it on drop),
//! names are NUL-terminated, and buffers are as large as the images set on
//! a filter (every size here is checked before a call).
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_void, CStr};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use crate::render::native::{open, symbols};

type Handle = *mut c_void;
/// A denoiser's guides: the albedo and the normal image.
pub type Guides<'a> = (&'a [[f32; 3]], &'a [[f32; 3]]);

/// `OIDN_FORMAT_FLOAT3`.
const FORMAT_FLOAT3: c_int = 3;
/// `OIDN_ERROR_NONE`.
const ERROR_NONE: c_int = 0;
/// `OIDN_DEVICE_TYPE_*`, in order from 1 (CPU).
const KINDS: [&str; 5] = ["cpu", "sycl", "cuda", "hip", "metal"];

/// The filter's quality mode (`OIDN_QUALITY_*`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FilterQuality {
    /// About 1.7x faster than `High` (measured on a 2-core CPU at 1080p):
    /// for frames that a newer one soon replaces.
    Fast,
    /// For a frame that stays.
    High,
}

impl FilterQuality {
    fn code(self) -> c_int {
        match self {
            FilterQuality::Fast => 4,
            FilterQuality::High => 6,
        }
    }
}

/// The library's entry points.
struct Api {
    num_physical_devices: unsafe extern "C" fn() -> c_int,
    physical_device_int: unsafe extern "C" fn(c_int, *const c_char) -> c_int,
    physical_device_string: unsafe extern "C" fn(c_int, *const c_char) -> *const c_char,
    new_device_by_id: unsafe extern "C" fn(c_int) -> Handle,
    commit_device: unsafe extern "C" fn(Handle),
    device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int,
    device_int: unsafe extern "C" fn(Handle, *const c_char) -> c_int,
    release_device: unsafe extern "C" fn(Handle),
    new_buffer: unsafe extern "C" fn(Handle, usize) -> Handle,
    write_buffer: unsafe extern "C" fn(Handle, usize, usize, *const c_void),
    read_buffer: unsafe extern "C" fn(Handle, usize, usize, *mut c_void),
    release_buffer: unsafe extern "C" fn(Handle),
    new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
    set_filter_image: unsafe extern "C" fn(
        Handle,
        *const c_char,
        Handle,
        c_int,
        usize,
        usize,
        usize,
        usize,
        usize,
    ),
    set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
    set_filter_int: unsafe extern "C" fn(Handle, *const c_char, c_int),
    commit_filter: unsafe extern "C" fn(Handle),
    execute_filter: unsafe extern "C" fn(Handle),
    release_filter: unsafe extern "C" fn(Handle),
}

/// The loaded library (kept loaded while its entry points may be called).
pub struct Library {
    api: Api,
    pub path: PathBuf,
    _lib: libloading::Library,
}

/// A device the library lists.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhysicalDevice {
    pub index: usize,
    pub kind: &'static str,
    pub name: String,
}

impl Library {
    /// Loads the library at `path` (a file name alone searches the
    /// system's library path).
    pub fn load(path: &Path) -> Result<Library, String> {
        let lib = open(path)?;
        let api = symbols!(
            Api,
            lib,
            path,
            "Open Image Denoise 2.x",
            num_physical_devices = "oidnGetNumPhysicalDevices",
            physical_device_int = "oidnGetPhysicalDeviceInt",
            physical_device_string = "oidnGetPhysicalDeviceString",
            new_device_by_id = "oidnNewDeviceByID",
            commit_device = "oidnCommitDevice",
            device_error = "oidnGetDeviceError",
            device_int = "oidnGetDeviceInt",
            release_device = "oidnReleaseDevice",
            new_buffer = "oidnNewBuffer",
            write_buffer = "oidnWriteBuffer",
            read_buffer = "oidnReadBuffer",
            release_buffer = "oidnReleaseBuffer",
            new_filter = "oidnNewFilter",
            set_filter_image = "oidnSetFilterImage",
            set_filter_bool = "oidnSetFilterBool",
            set_filter_int = "oidnSetFilterInt",
            commit_filter = "oidnCommitFilter",
            execute_filter = "oidnExecuteFilter",
            release_filter = "oidnReleaseFilter",
        );
        Ok(Library {
            api,
            path: path.to_path_buf(),
            _lib: lib,
        })
    }

    /// The devices the library can denoise on.
    pub fn physical_devices(&self) -> Vec<PhysicalDevice> {
        // SAFETY: no arguments; the library is loaded.
        let n = unsafe { (self.api.num_physical_devices)() }.max(0);
        (0..n)
            .map(|i| {
                // SAFETY: i is below the count the library gave; the names
                // are NUL-terminated literals.
                let kind = unsafe { (self.api.physical_device_int)(i, c"type".as_ptr()) };
                // SAFETY: as above; the string, if any, is the library's and
                // read at once.
                let name = unsafe { text((self.api.physical_device_string)(i, c"name".as_ptr())) };
                PhysicalDevice {
                    index: i as usize,
                    kind: KINDS
                        .get((kind - 1).max(0) as usize)
                        .copied()
                        .unwrap_or("other"),
                    name: name.unwrap_or_default(),
                }
            })
            .collect()
    }

    /// A committed device on physical device `index`.
    pub fn device(self: &Arc<Self>, index: usize) -> Result<Device, String> {
        // SAFETY: any index is accepted (a bad one gives a null handle and
        // an error).
        let handle = unsafe { (self.api.new_device_by_id)(index as c_int) };
        if handle.is_null() {
            return Err(self
                .error(std::ptr::null_mut())
                .unwrap_or("no device".into()));
        }
        let device = Device {
            lib: self.clone(),
            handle,
        };
        // SAFETY: a live device handle.
        unsafe { (self.api.commit_device)(handle) };
        device.check()?;
        Ok(device)
    }

    /// The first error stored for `device` (null: for device creation).
    fn error(&self, device: Handle) -> Option<String> {
        let mut message: *const c_char = std::ptr::null();
        // SAFETY: device is null or live; `message` is a valid out-pointer.
        let code = unsafe { (self.api.device_error)(device, &mut message) };
        // SAFETY: the message, if any, is the library's NUL-terminated string.
        let text = unsafe { text(message) };
        (code != ERROR_NONE).then(|| text.unwrap_or_else(|| format!("error {code}")))
    }
}

/// A C string the library owns, copied (None for null).
///
/// # Safety
/// `p` is null or a NUL-terminated string alive for the call.
unsafe fn text(p: *const c_char) -> Option<String> {
    // SAFETY: as the caller promises.
    (!p.is_null()).then(|| unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned())
}

/// A committed OIDN device.
pub struct Device {
    lib: Arc<Library>,
    handle: Handle,
}

// SAFETY: OIDN's API is thread-safe (calls on one device are serialised by
// the library); the handle is owned by this value alone.
unsafe impl Send for Device {}

/// Ok, or the first error stored for `device`.
fn check(lib: &Library, device: Handle) -> Result<(), String> {
    match lib.error(device) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

impl Device {
    fn check(&self) -> Result<(), String> {
        check(&self.lib, self.handle)
    }

    /// The library's version as `major.minor.patch`.
    pub fn version(&self) -> String {
        // SAFETY: a live device; a NUL-terminated literal.
        let v = unsafe { (self.lib.api.device_int)(self.handle, c"version".as_ptr()) };
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    /// A filter for `width` x `height` images, with or without the
    /// albedo and normal guides, at `quality`.
    pub fn filter(
        &self,
        width: usize,
        height: usize,
        guided: bool,
        quality: FilterQuality,
    ) -> Result<Filter, String> {
        let api = &self.lib.api;
        let bytes = width
            .checked_mul(height)
            .and_then(|n| n.checked_mul(12))
            .filter(|&b| b > 0)
            .ok_or("an empty or oversized image")?;
        let count = if guided { 4 } else { 2 };
        let mut buffers = Vec::with_capacity(count);
        for _ in 0..count {
            // SAFETY: a live device; the size is checked above.
            let b = unsafe { (api.new_buffer)(self.handle, bytes) };
            if b.is_null() {
                self.check()?;
                return Err("no buffer".into());
            }
            buffers.push(Buffer {
                lib: self.lib.clone(),
                handle: b,
            });
        }
        // SAFETY: a live device; a NUL-terminated literal.
        let handle = unsafe { (api.new_filter)(self.handle, c"RT".as_ptr()) };
        if handle.is_null() {
            self.check()?;
            return Err("no filter".into());
        }
        let filter = Filter {
            lib: self.lib.clone(),
            device: self.handle,
            handle,
            buffers,
            bytes,
        };
        let names = [c"color", c"output", c"albedo", c"normal"];
        for (name, b) in names.iter().zip(&filter.buffers) {
            // SAFETY: live filter and buffer; the buffer holds
            // width x height FLOAT3 pixels, densely packed (strides 0).
            unsafe {
                (api.set_filter_image)(
                    handle,
                    name.as_ptr(),
                    b.handle,
                    FORMAT_FLOAT3,
                    width,
                    height,
                    0,
                    0,
                    0,
                )
            };
        }
        // SAFETY: a live filter; NUL-terminated literals.
        unsafe {
            (api.set_filter_bool)(handle, c"hdr".as_ptr(), true);
            (api.set_filter_int)(handle, c"quality".as_ptr(), quality.code());
            (api.commit_filter)(handle);
        }
        self.check()?;
        Ok(filter)
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once.
        unsafe { (self.lib.api.release_device)(self.handle) };
    }
}

struct Buffer {
    lib: Arc<Library>,
    handle: Handle,
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once.
        unsafe { (self.lib.api.release_buffer)(self.handle) };
    }
}

/// An "RT" filter and its buffers: colour, output, then albedo and normal
/// where it is guided. It keeps its device alive (OIDN counts references),
/// and is used only while the [`Device`] it came from is (the caller keeps
/// both).
pub struct Filter {
    lib: Arc<Library>,
    device: Handle,
    handle: Handle,
    buffers: Vec<Buffer>,
    bytes: usize,
}

// SAFETY: as for `Device`; the filter's handles are owned by it alone.
unsafe impl Send for Filter {}

impl Filter {
    /// Denoises `color` (guided by `guides`, albedo then normal, where the
    /// filter was made guided) into `out`; every slice holds the filter's
    /// width x height pixels.
    pub fn run(
        &self,
        color: &[[f32; 3]],
        guides: Option<Guides<'_>>,
        out: &mut [[f32; 3]],
    ) -> Result<(), String> {
        let api = &self.lib.api;
        let fits = |s: &[[f32; 3]]| std::mem::size_of_val(s) == self.bytes;
        let mut inputs = vec![(0, color)];
        if let Some((albedo, normal)) = guides.filter(|_| self.buffers.len() == 4) {
            inputs.extend([(2, albedo), (3, normal)]);
        }
        if !inputs.iter().all(|(_, s)| fits(s)) || !fits(out) {
            return Err("an image of another size than the filter's".into());
        }
        for (i, data) in inputs {
            // SAFETY: a live buffer of `bytes` bytes; `data` is as long.
            unsafe {
                (api.write_buffer)(self.buffers[i].handle, 0, self.bytes, data.as_ptr().cast())
            };
        }
        // SAFETY: a live, committed filter whose images are all set.
        unsafe { (api.execute_filter)(self.handle) };
        check(&self.lib, self.device)?;
        // SAFETY: a live buffer of `bytes` bytes; `out` is as long.
        unsafe {
            (api.read_buffer)(
                self.buffers[1].handle,
                0,
                self.bytes,
                out.as_mut_ptr().cast(),
            )
        };
        check(&self.lib, self.device)
    }
}

impl Drop for Filter {
    fn drop(&mut self) {
        // SAFETY: the handle is live and released once (before its buffers).
        unsafe { (self.lib.api.release_filter)(self.handle) };
    }
}
