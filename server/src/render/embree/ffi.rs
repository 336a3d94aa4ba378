//! The part of Embree 3's C API (rtcore.h, 3.13) that the CPU's rays need,
//! resolved by name when the library loads: the structures copy the
//! header's layout (as Debian and Intel build it: one instance level, no
//! minimum width), the function types its signatures.
#![allow(unsafe_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};
use std::path::{Path, PathBuf};

use crate::render::native::{open, symbols};

pub type Handle = *mut c_void;

pub const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
pub const GEOMETRY_TYPE_INSTANCE: c_uint = 121;
pub const BUFFER_TYPE_INDEX: c_uint = 0;
pub const BUFFER_TYPE_VERTEX: c_uint = 1;
pub const FORMAT_UINT3: c_uint = 0x5003;
pub const FORMAT_FLOAT3: c_uint = 0x9003;
pub const FORMAT_FLOAT3X4_COLUMN_MAJOR: c_uint = 0x9234;
pub const SCENE_FLAG_ROBUST: c_uint = 1 << 2;
pub const SCENE_FLAG_CONTEXT_FILTER_FUNCTION: c_uint = 1 << 3;
pub const BUILD_QUALITY_MEDIUM: c_uint = 1;
pub const BUILD_QUALITY_HIGH: c_uint = 2;
pub const CONTEXT_FLAG_INCOHERENT: c_uint = 0;
pub const CONTEXT_FLAG_COHERENT: c_uint = 1;
pub const INVALID_ID: c_uint = c_uint::MAX;
pub const DEVICE_PROPERTY_VERSION: c_uint = 0;
pub const ERROR_NONE: c_uint = 0;

/// `struct RTCRay` (16-byte aligned, 48 bytes).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub org: [f32; 3],
    pub tnear: f32,
    pub dir: [f32; 3],
    pub time: f32,
    pub tfar: f32,
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

/// `struct RTCHit` with one instance level.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub ng: [f32; 3],
    pub u: f32,
    pub v: f32,
    pub prim_id: c_uint,
    pub geom_id: c_uint,
    pub inst_id: [c_uint; 1],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RayHit {
    pub ray: Ray,
    pub hit: Hit,
}

/// `struct RTCFilterFunctionNArguments`.
#[repr(C)]
pub struct FilterArgs {
    pub valid: *mut c_int,
    pub geometry_user_ptr: *mut c_void,
    pub context: *mut Context,
    pub ray: *mut c_void,
    /// `RTCHitN`: N hits as structure of arrays (u at 3N, prim at 5N,
    /// instance at 7N).
    pub hit: *mut c_void,
    pub n: c_uint,
}

pub type FilterFn = unsafe extern "C" fn(*const FilterArgs);

/// `struct RTCIntersectContext` with one instance level.
#[repr(C)]
pub struct Context {
    pub flags: c_uint,
    pub filter: Option<FilterFn>,
    pub inst_id: [c_uint; 1],
}

const _: () = assert!(std::mem::size_of::<Ray>() == 48);
const _: () = assert!(std::mem::size_of::<Hit>() == 32);
const _: () = assert!(std::mem::size_of::<RayHit>() == 80);
const _: () = assert!(std::mem::size_of::<Context>() == 24);
const _: () = assert!(std::mem::size_of::<FilterArgs>() == 48);

impl Context {
    /// What the header's inline `rtcInitIntersectContext` does, with a
    /// filter.
    pub fn new(filter: Option<FilterFn>) -> Self {
        Self {
            flags: CONTEXT_FLAG_INCOHERENT,
            filter,
            inst_id: [INVALID_ID],
        }
    }
}

/// The library's entry points.
pub struct Api {
    pub new_device: unsafe extern "C" fn(*const c_char) -> Handle,
    pub device_error: unsafe extern "C" fn(Handle) -> c_uint,
    pub device_property: unsafe extern "C" fn(Handle, c_uint) -> isize,
    pub new_scene: unsafe extern "C" fn(Handle) -> Handle,
    pub set_scene_flags: unsafe extern "C" fn(Handle, c_uint),
    pub set_scene_build_quality: unsafe extern "C" fn(Handle, c_uint),
    pub new_geometry: unsafe extern "C" fn(Handle, c_uint) -> Handle,
    pub set_geometry_build_quality: unsafe extern "C" fn(Handle, c_uint),
    pub set_new_geometry_buffer:
        unsafe extern "C" fn(Handle, c_uint, c_uint, c_uint, usize, usize) -> *mut c_void,
    pub set_geometry_instanced_scene: unsafe extern "C" fn(Handle, Handle),
    pub set_geometry_transform: unsafe extern "C" fn(Handle, c_uint, c_uint, *const c_void),
    pub commit_geometry: unsafe extern "C" fn(Handle),
    pub attach_geometry_by_id: unsafe extern "C" fn(Handle, Handle, c_uint),
    pub release_geometry: unsafe extern "C" fn(Handle),
    pub commit_scene: unsafe extern "C" fn(Handle),
    pub release_scene: unsafe extern "C" fn(Handle),
    pub intersect1: unsafe extern "C" fn(Handle, *mut Context, *mut RayHit),
    /// `rtcIntersect4`, `8` and `16`: a packet's valid mask (-1 or 0 a
    /// lane), the scene, the context and an `RTCRayHitN` ([`RayHitN`]).
    pub intersect4: PacketFn,
    pub intersect8: PacketFn,
    pub intersect16: PacketFn,
    /// `rtcOccluded4`, `8` and `16`: the same, reading and writing only
    /// the packet's rays (tfar becomes -inf where something blocks).
    pub occluded4: PacketFn,
    pub occluded8: PacketFn,
    pub occluded16: PacketFn,
}

impl Api {
    /// The nearest-hit and the occlusion query for packets of `w` rays.
    pub fn packet_queries(&self, w: usize) -> (PacketFn, PacketFn) {
        match w {
            4 => (self.intersect4, self.occluded4),
            8 => (self.intersect8, self.occluded8),
            16 => (self.intersect16, self.occluded16),
            _ => unreachable!("Embree's packets are 4, 8 or 16 rays, not {w}"),
        }
    }
}

/// A packet query's entry point.
pub type PacketFn = unsafe extern "C" fn(*const c_int, Handle, *mut Context, *mut c_void);

/// `RTCRayHitN` for N = `W` (4, 8 or 16): `RTCRayN` then `RTCHitN` with
/// one instance level, a field at a time, each `W` lanes (the headers
/// align them to the packet's width; 64 bytes serves every width).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RayHitN<const W: usize> {
    pub org: [[f32; W]; 3],
    pub tnear: [f32; W],
    pub dir: [[f32; W]; 3],
    pub time: [f32; W],
    pub tfar: [f32; W],
    pub mask: [c_uint; W],
    pub id: [c_uint; W],
    pub flags: [c_uint; W],
    pub ng: [[f32; W]; 3],
    pub u: [f32; W],
    pub v: [f32; W],
    pub prim_id: [c_uint; W],
    pub geom_id: [c_uint; W],
    pub inst_id: [c_uint; W],
}

/// Where `RTCRayN`'s `id` field of lane `i` lies, in 32-bit words from
/// the packet's start (rtcore_ray.h's `RTCRayN_id`).
pub const fn ray_id_word(n: usize, i: usize) -> usize {
    10 * n + i
}

const _: () = assert!(std::mem::size_of::<RayHitN<16>>() == 20 * 64);
const _: () = assert!(std::mem::offset_of!(RayHitN<8>, id) == ray_id_word(8, 0) * 4);
const _: () = assert!(std::mem::offset_of!(RayHitN<4>, ng) == 12 * 4 * 4);

/// The loaded library (kept loaded while its entry points may be called).
pub struct Library {
    pub api: Api,
    pub path: PathBuf,
    _lib: libloading::Library,
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
            "Embree 3",
            new_device = "rtcNewDevice",
            device_error = "rtcGetDeviceError",
            device_property = "rtcGetDeviceProperty",
            new_scene = "rtcNewScene",
            set_scene_flags = "rtcSetSceneFlags",
            set_scene_build_quality = "rtcSetSceneBuildQuality",
            new_geometry = "rtcNewGeometry",
            set_geometry_build_quality = "rtcSetGeometryBuildQuality",
            set_new_geometry_buffer = "rtcSetNewGeometryBuffer",
            set_geometry_instanced_scene = "rtcSetGeometryInstancedScene",
            set_geometry_transform = "rtcSetGeometryTransform",
            commit_geometry = "rtcCommitGeometry",
            attach_geometry_by_id = "rtcAttachGeometryByID",
            release_geometry = "rtcReleaseGeometry",
            commit_scene = "rtcCommitScene",
            release_scene = "rtcReleaseScene",
            intersect1 = "rtcIntersect1",
            intersect4 = "rtcIntersect4",
            intersect8 = "rtcIntersect8",
            intersect16 = "rtcIntersect16",
            occluded4 = "rtcOccluded4",
            occluded8 = "rtcOccluded8",
            occluded16 = "rtcOccluded16",
        );
        Ok(Library {
            api,
            path: path.to_path_buf(),
            _lib: lib,
        })
    }
}
